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

/// One random stream (up to 2 KiB: raw bytes, `55`-heavy bytes, valid frames, bit-flipped
/// and truncated frames) and the chunk size to feed it in.
fn random_stream(r: &mut Rng, stream: &mut Vec<u8>) -> usize {
    let mut buf = [0u8; MAX_FRAME];
    stream.clear();
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
                let f = &mut buf[..n];
                if k == 3 {
                    let bit = r.below(n as u64 * 8) as usize;
                    f[bit / 8] ^= 1 << (bit % 8);
                }
                let keep = if k == 4 {
                    r.below(n as u64) as usize
                } else {
                    n
                };
                stream.extend_from_slice(&f[..keep]);
            }
        }
    }
    match r.below(3) {
        0 => 1,
        1 => 1 + r.below(64) as usize,
        _ => stream.len(),
    }
}

/// Runs `n` random streams from `seed` through [`check`]; returns the bytes fed.
fn run_streams(seed: u64, n: u64) -> u64 {
    let mut r = Rng(Xoshiro256PlusPlus::seed_from_u64(seed));
    let mut stream = Vec::with_capacity(4096);
    let mut bytes = 0;
    for _ in 0..n {
        let chunk = random_stream(&mut r, &mut stream);
        check(&stream, chunk);
        bytes += stream.len() as u64;
    }
    bytes
}

#[test]
fn random_streams_never_panic_and_keep_invariants() {
    run_streams(0x0123_4567_89AB_CDEF, 3000);
}

/// Number of streams of the release-mode run (what the README states).
const RELEASE_STREAMS: u64 = 1_000_000;

/// The same checks on 10^6 streams (about 1 GB), the stable stand-in for a cargo-fuzz run in
/// CI (no nightly toolchain there). Release only: `cargo test --release -p nav440-proto --test
/// fuzz_equivalent` (part of `cargo xtask ci`).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p nav440-proto --test fuzz_equivalent"
)]
fn a_million_random_streams_in_release() {
    let bytes = run_streams(0x00C0_FFEE_1234_5678, RELEASE_STREAMS);
    // Streams average about 1 KiB: the run really went through ~10^9 bytes.
    assert!(bytes > RELEASE_STREAMS * 512, "{bytes} bytes");
}
