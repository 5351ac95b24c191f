//! Stable-toolchain equivalent of the `fuzz/` target: bounded random streams (raw bytes,
//! `55`-heavy bytes, fragments and bit-flipped copies of valid frames) fed in random chunks;
//! nothing panics and the parser's invariants hold.

use nav440_proto::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

#[path = "common/fuzz_check.rs"]
mod fuzz_check;
use fuzz_check::check;

/// Seeded generator (rand's xoshiro256++) with the two draws the test needs.
struct Rng(Xoshiro256PlusPlus);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0.random()
    }
    fn below(&mut self, n: u64) -> u64 {
        self.0.random_range(0..n)
    }
}

#[test]
fn random_streams_never_panic_and_keep_invariants() {
    let mut r = Rng(Xoshiro256PlusPlus::seed_from_u64(0x0123_4567_89AB_CDEF));
    let mut buf = [0u8; MAX_FRAME];
    for _ in 0..3000 {
        let mut stream = Vec::new();
        let target = r.below(2048) as usize;
        while stream.len() < target {
            match r.below(5) {
                0 => stream.extend((0..r.below(64)).map(|_| r.next() as u8)),
                1 => stream.extend((0..r.below(16)).map(|_| {
                    if r.below(2) == 0 {
                        0x55
                    } else {
                        r.next() as u8
                    }
                })),
                k => {
                    let t = PacketType::KNOWN[r.below(PacketType::KNOWN.len() as u64) as usize];
                    let t = if r.below(4) == 0 {
                        PacketType(*b"z1")
                    } else {
                        t
                    };
                    let len = if r.below(2) == 0 {
                        30
                    } else {
                        r.below(256) as usize
                    };
                    let payload: Vec<u8> = (0..len).map(|_| r.next() as u8).collect();
                    let n = encode_frame(t, &payload, &mut buf).unwrap();
                    let mut f = buf[..n].to_vec();
                    if k == 3 {
                        let bit = r.below(n as u64 * 8) as usize;
                        f[bit / 8] ^= 1 << (bit % 8);
                    }
                    if k == 4 {
                        f.truncate(r.below(n as u64) as usize);
                    }
                    stream.extend(f);
                }
            }
        }
        let chunk = match r.below(3) {
            0 => 1,
            1 => 1 + r.below(64) as usize,
            _ => stream.len(),
        };
        check(&stream, chunk);
    }
}
