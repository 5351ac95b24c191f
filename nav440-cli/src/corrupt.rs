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
        for _ in 0..c.bit_flips {
            let (k, pos) = random_byte(&mut rng, &kept);
            let bit = rng.random_range(0..8u32);
            if let Some(b) = kept[k].1.get_mut(pos) {
                *b ^= 1 << bit;
                report.damaged.insert(kept[k].0);
            }
        }
        for _ in 0..c.dropped_bytes {
            let (k, pos) = random_byte(&mut rng, &kept);
            if pos < kept[k].1.len() {
                kept[k].1.remove(pos);
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

/// A uniformly random byte position over all bytes of `kept`: (frame index in kept, offset).
fn random_byte(rng: &mut Xoshiro256PlusPlus, kept: &[(usize, Vec<u8>)]) -> (usize, usize) {
    let total: usize = kept.iter().map(|(_, f)| f.len()).sum();
    let mut pos = rng.random_range(0..total.max(1));
    for (k, (_, f)) in kept.iter().enumerate() {
        if pos < f.len() {
            return (k, pos);
        }
        pos -= f.len();
    }
    (0, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(n: usize) -> Vec<Vec<u8>> {
        (0..n).map(|i| vec![i as u8; 10]).collect()
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
