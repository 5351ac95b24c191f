//! Seeded corruption of a stream of frames: bit flips, dropped bytes, dropped packets and
//! garbage bursts, with a report of exactly which frames were hit (so tests can compute the
//! number of frames a parser must still recover).

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use std::collections::BTreeSet;

/// What to do to a stream. Every count is an exact number of events, placed at random
/// (deterministic from `seed`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Corruption {
    /// Number of single-bit flips, at uniformly random bit positions of the surviving frames.
    pub bit_flips: usize,
    /// Number of bytes deleted from the surviving frames.
    pub dropped_bytes: usize,
    /// Number of whole frames left out (distinct frames).
    pub dropped_packets: usize,
    /// Number of bursts of random bytes inserted between frames.
    pub garbage_bursts: usize,
    /// Largest length of one garbage burst, bytes (each burst is 1..=this long).
    pub garbage_max_len: usize,
    /// Seed of the corruption's random choices.
    pub seed: u64,
}

impl Corruption {
    /// True when the corruption changes nothing.
    pub fn is_none(&self) -> bool {
        self.bit_flips == 0
            && self.dropped_bytes == 0
            && self.dropped_packets == 0
            && self.garbage_bursts == 0
    }
}

/// Which frames a corruption removed or damaged.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CorruptionReport {
    /// Frames given to `apply`.
    pub frames_in: usize,
    /// Indices of frames left out entirely.
    pub dropped: BTreeSet<usize>,
    /// Indices of frames present but with at least one flipped or deleted byte.
    pub damaged: BTreeSet<usize>,
    /// Garbage bytes inserted.
    pub garbage_bytes: usize,
}

impl CorruptionReport {
    /// Frames that are still intact in the output (a parser must recover exactly these).
    pub fn intact(&self) -> usize {
        self.frames_in - self.dropped.len() - self.damaged.len()
    }
}

/// Applies `c` to `frames` (each a whole encoded frame) and returns the byte stream.
pub fn apply(frames: &[Vec<u8>], c: &Corruption) -> (Vec<u8>, CorruptionReport) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(c.seed);
    let mut report = CorruptionReport {
        frames_in: frames.len(),
        ..Default::default()
    };
    let n_drop = c.dropped_packets.min(frames.len());
    while report.dropped.len() < n_drop {
        report.dropped.insert(rng.random_range(0..frames.len()));
    }
    let mut kept: Vec<(usize, Vec<u8>)> = frames
        .iter()
        .enumerate()
        .filter(|(i, _)| !report.dropped.contains(i))
        .map(|(i, f)| (i, f.clone()))
        .collect();
    if !kept.is_empty() {
        let mut lens = Lengths::new(kept.iter().map(|(_, f)| f.len()));
        for _ in 0..c.bit_flips {
            let (k, pos) = lens.random_byte(&mut rng);
            let bit = rng.random_range(0..8u32);
            if let Some(b) = kept[k].1.get_mut(pos) {
                *b ^= 1 << bit;
                report.damaged.insert(kept[k].0);
            }
        }
        for _ in 0..c.dropped_bytes {
            let (k, pos) = lens.random_byte(&mut rng);
            if pos < kept[k].1.len() {
                kept[k].1.remove(pos);
                lens.remove_one(k);
                report.damaged.insert(kept[k].0);
            }
        }
    }
    // Garbage bursts go into gaps: gap g is before kept frame g (gap kept.len() = the end).
    let mut bursts: Vec<Vec<Vec<u8>>> = vec![Vec::new(); kept.len() + 1];
    for _ in 0..c.garbage_bursts {
        let gap = rng.random_range(0..=kept.len());
        let len = rng.random_range(1..=c.garbage_max_len.max(1));
        let burst: Vec<u8> = (0..len).map(|_| rng.random::<u8>()).collect();
        report.garbage_bytes += len;
        bursts[gap].push(burst);
    }
    let mut out = Vec::new();
    for (g, (_, f)) in kept.iter().enumerate() {
        for b in &bursts[g] {
            out.extend_from_slice(b);
        }
        out.extend_from_slice(f);
    }
    for b in &bursts[kept.len()] {
        out.extend_from_slice(b);
    }
    (out, report)
}

/// The lengths of the kept frames as a Fenwick tree (binary indexed tree): a random byte
/// position and a deleted byte cost O(log frames) each, so the corruption's time grows with
/// its counts times the logarithm of the capture, not with their product.
struct Lengths {
    /// `tree[i]` (1-based) sums the lengths of frames `i - (i & -i) .. i`.
    tree: Vec<usize>,
    total: usize,
}

impl Lengths {
    fn new(lens: impl Iterator<Item = usize>) -> Self {
        let mut tree = vec![0];
        tree.extend(lens);
        let n = tree.len() - 1;
        for i in 1..=n {
            let parent = i + (i & i.wrapping_neg());
            if parent <= n {
                tree[parent] += tree[i];
            }
        }
        let mut t = Lengths { tree, total: 0 };
        t.total = t.prefix(n);
        t
    }

    /// The sum of the lengths of frames `0..i`.
    fn prefix(&self, mut i: usize) -> usize {
        let mut s = 0;
        while i > 0 {
            s += self.tree[i];
            i &= i - 1;
        }
        s
    }

    /// Frame `k` lost one byte.
    fn remove_one(&mut self, k: usize) {
        let mut i = k + 1;
        while i < self.tree.len() {
            self.tree[i] -= 1;
            i += i & i.wrapping_neg();
        }
        self.total -= 1;
    }

    /// A uniformly random byte position over all bytes: (frame index, offset in the frame),
    /// the first frame whose bytes reach past the drawn position; (0, 0) when no byte is left.
    fn random_byte(&self, rng: &mut Xoshiro256PlusPlus) -> (usize, usize) {
        let mut pos = rng.random_range(0..self.total.max(1));
        if self.total == 0 {
            return (0, 0);
        }
        // Descend: the largest `idx` with prefix(idx) <= pos; frame `idx` (0-based) holds pos.
        let n = self.tree.len() - 1;
        let mut idx = 0;
        let mut bit = n.checked_next_power_of_two().unwrap_or(0);
        while bit > 0 {
            let next = idx + bit;
            if next <= n && self.tree[next] <= pos {
                idx = next;
                pos -= self.tree[next];
            }
            bit >>= 1;
        }
        (idx, pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(n: usize) -> Vec<Vec<u8>> {
        (0..n).map(|i| vec![i as u8; 10]).collect()
    }

    /// The linear scan the Fenwick tree replaces: the same draws give the same positions.
    #[test]
    fn lengths_pick_the_byte_a_linear_scan_picks() {
        let lens = [3usize, 0, 5, 1, 0, 0, 7, 2];
        let mut t = Lengths::new(lens.iter().copied());
        let mut now = lens.to_vec();
        let mut a = Xoshiro256PlusPlus::seed_from_u64(5);
        let mut b = Xoshiro256PlusPlus::seed_from_u64(5);
        for _ in 0..18 {
            let total: usize = now.iter().sum();
            let mut pos = a.random_range(0..total.max(1));
            let mut want = (0, 0);
            for (k, &l) in now.iter().enumerate() {
                if pos < l {
                    want = (k, pos);
                    break;
                }
                pos -= l;
            }
            let got = t.random_byte(&mut b);
            assert_eq!(got, want);
            if now[got.0] > 0 {
                now[got.0] -= 1;
                t.remove_one(got.0);
            }
        }
        assert_eq!(t.random_byte(&mut b), (0, 0));
    }

    #[test]
    fn no_corruption_is_identity() {
        let f = frames(5);
        let (out, rep) = apply(&f, &Corruption::default());
        assert_eq!(out, f.concat());
        assert_eq!(rep.intact(), 5);
    }

    #[test]
    fn counts_are_exact_and_reproducible() {
        let f = frames(100);
        let c = Corruption {
            bit_flips: 3,
            dropped_bytes: 2,
            dropped_packets: 4,
            garbage_bursts: 5,
            garbage_max_len: 8,
            seed: 9,
        };
        let (out, rep) = apply(&f, &c);
        assert_eq!(rep.dropped.len(), 4);
        assert!(rep.damaged.len() <= 5 && !rep.damaged.is_empty());
        assert!(rep.dropped.is_disjoint(&rep.damaged));
        assert_eq!(out.len(), 1000 - 40 - 2 + rep.garbage_bytes);
        assert!((5..=40).contains(&rep.garbage_bytes));
        assert_eq!(apply(&f, &c), (out, rep));
    }
}
