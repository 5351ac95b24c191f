//! Parser throughput against a bare CRC-16 pass over the same bytes, in one process.
//!
//! Run: `cargo bench -p nav440-proto --bench throughput`
//!
//! The stream is ~4 MiB of A2, N1 and S1 frames with random field values; after ~5 % of the
//! frames comes a run of 1-16 garbage bytes (some starting with `55` or `55 55`). Two orders:
//! frame types drawn at random per frame (worst case for branch prediction), and runs of 200
//! frames of one type (what a unit sends: one continuous packet type). Both passes use the same `crc` crate table variant;
//! the result is reported for the default host variant (`Table<16>`) and for `Table<1>` (the
//! bare-metal default). Best of N runs each, interleaved.

use std::hint::black_box;
use std::time::{Duration, Instant};

use crc::Table;
use nav440_proto::{A2Fields, Crc16Table, N1Fields, Parser, S1Fields, MAX_FRAME};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Seeded generator (rand's xoshiro256++) with the draws the stream builder needs.
struct Rng(Xoshiro256PlusPlus);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0.random()
    }
    fn i16(&mut self) -> i16 {
        self.0.random()
    }
}

fn stream(target: usize, run: u64) -> Vec<u8> {
    let mut r = Rng(Xoshiro256PlusPlus::seed_from_u64(0x9E37_79B9_7F4A_7C15));
    let mut out = Vec::with_capacity(target + MAX_FRAME);
    let mut buf = [0u8; MAX_FRAME];
    let mut t = 0u32;
    let mut kind = 0;
    let mut frame = 0u64;
    while out.len() < target {
        t = t.wrapping_add(10);
        if frame % run == 0 {
            kind = r.next() % 3;
        }
        frame += 1;
        let n = match kind {
            0 => A2Fields {
                roll: r.i16(),
                pitch: r.i16(),
                yaw_true: r.i16(),
                rate_z: r.i16(),
                accel_z: r.i16(),
                time_itow: t,
                ..Default::default()
            }
            .encode(&mut buf),
            1 => N1Fields {
                roll: r.i16(),
                yaw_true: r.i16(),
                rate_z: r.i16(),
                vel_n: r.i16(),
                longitude: r.next() as i32,
                latitude: r.next() as i32,
                time_itow: t,
                ..Default::default()
            }
            .encode(&mut buf),
            _ => S1Fields {
                accel_x: r.i16(),
                rate_x: r.i16(),
                counter: t as u16,
                ..Default::default()
            }
            .encode(&mut buf),
        }
        .expect("buffer fits");
        out.extend_from_slice(&buf[..n]);
        if r.next() % 100 < 5 {
            // garbage run of 1..=16 bytes, sometimes with a fake preamble
            let len = 1 + (r.next() % 16) as usize;
            for i in 0..len {
                let b = r.next() as u8;
                out.push(if i < 2 && r.next() % 4 == 0 { 0x55 } else { b });
            }
        }
    }
    out
}

fn best_of(runs: usize, mut f: impl FnMut()) -> Duration {
    let mut best = Duration::MAX;
    for _ in 0..runs {
        let t0 = Instant::now();
        f();
        best = best.min(t0.elapsed());
    }
    best
}

fn mbs(bytes: usize, d: Duration) -> f64 {
    bytes as f64 / d.as_secs_f64() / 1e6
}

fn measure<C: Crc16Table>(name: &str, data: &[u8], chunk: usize, runs: usize) -> f64 {
    let mut frames = 0u64;
    let mut bare = Duration::MAX;
    let mut parse = Duration::MAX;
    // Interleave so frequency drift hits both equally.
    for _ in 0..runs {
        bare = bare.min(best_of(1, || {
            black_box(C::checksum(black_box(data)));
        }));
        parse = parse.min(best_of(1, || {
            let mut p = Parser::<C>::with_crc_table();
            let mut n = 0u64;
            for c in black_box(data).chunks(chunk) {
                p.feed(c, |f| {
                    n += 1;
                    black_box(f.payload.len());
                });
            }
            frames = black_box(n);
        }));
    }
    // Lower bound for any CRC-checking parser: only the per-frame CRC calls, at known offsets.
    let mut spans = Vec::new();
    let mut q = Parser::<C>::with_crc_table();
    let base = data.as_ptr() as usize;
    q.feed(data, |f| {
        spans.push((f.payload.as_ptr() as usize - base - 3, f.payload.len() + 3))
    });
    let mut per_frame = Duration::MAX;
    for _ in 0..runs {
        per_frame = per_frame.min(best_of(1, || {
            let mut acc = 0u16;
            for &(s, l) in black_box(&spans) {
                acc ^= C::message_crc(&data[s..s + l]);
            }
            black_box(acc);
        }));
    }
    println!(
        "{name:<10} per-frame CRC calls only: {:8.1} MB/s (time ratio to bare {:.3})",
        mbs(data.len(), per_frame),
        per_frame.as_secs_f64() / bare.as_secs_f64()
    );
    let (b, p) = (mbs(data.len(), bare), mbs(data.len(), parse));
    println!(
        "{name:<10} chunk {chunk:>5} B: bare CRC {b:8.1} MB/s, parser {p:8.1} MB/s, \
         parser/CRC time ratio {:.3} ({frames} frames)",
        b / p
    );
    b / p
}

fn main() {
    // `cargo bench` passes `--bench`; under `cargo test --all-targets` only a quick smoke run
    // (figures of an unoptimized build would mean nothing).
    if !std::env::args().any(|a| a == "--bench") {
        let data = stream(64 << 10, 1);
        measure::<Table<16>>("smoke", &data, 4096, 1);
        println!("smoke run only; measure with `cargo bench -p nav440-proto --bench throughput`");
        return;
    }
    let runs = 15;
    let mut headline = (0.0, 0.0);
    for (label, run) in [
        ("random type order", 1),
        ("runs of 200 frames per type", 200),
    ] {
        let data = stream(4 << 20, run);
        println!(
            "stream ({label}): {} bytes, ~5 % of frames followed by garbage, best of {runs}",
            data.len()
        );
        let r16 = measure::<Table<16>>("Table<16>", &data, 4096, runs);
        measure::<Table<16>>("Table<16>", &data, 64, runs);
        let r1 = measure::<Table<1>>("Table<1>", &data, 4096, runs);
        measure::<Table<1>>("Table<1>", &data, 64, runs);
        if run == 1 {
            headline = (r16, r1);
        }
    }
    println!(
        "RESULT (random type order, 4 KiB chunks): parser time / bare CRC time = {:.2} with \
         Table<16> (host default), {:.2} with Table<1> (bare-metal default); goal <= 1.5",
        headline.0, headline.1
    );
}
