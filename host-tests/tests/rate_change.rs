//! Captures whose packet rate changes, through `nav440 estimate`'s streaming path
//! (`replay::estimate_stream`, the pipeline the firmware runs): every estimate of every bank
//! (paper and product, f32 and fixed point) stays bounded, and a new epoch at another rate
//! re-measures the nominal period.
//!
//! Bounds, from the captures' motion: every velocity within 10x the largest reference rate
//! (the packets' `yaw_rate`); every acceleration within 10x 2000 deg/s^2, the bound of the
//! paper's Fig. 5 motion that `fig5` scales to (90 % of it) and above the spin's 126 deg/s^2.
//! The captures are generated here (`nav440_cli::synth`, what `nav440 synth` writes), except
//! the first, which concatenates two bundled ones.

use nav440_cli::motion::ProfileKind;
use nav440_cli::replay::{self, BankKind, EstimateOptions};
use nav440_cli::synth::{self, SynthConfig};

/// The largest acceleration of the paper's Fig. 5 motion, deg/s^2.
const ACC_BOUND: f64 = 2000.0;

fn data(name: &str) -> Vec<u8> {
    let p = host_tests::data(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn capture(
    profile: ProfileKind,
    rate_hz: u32,
    duration_s: f64,
    start_itow_ms: u64,
) -> Vec<Vec<u8>> {
    synth::frames(&SynthConfig {
        profile,
        rate_hz,
        duration_s,
        start_itow_ms,
        ..SynthConfig::default()
    })
    .unwrap()
}

/// What one run gave: largest |velocity| and |acceleration| estimate, largest |reference
/// rate|, rows, period changes.
#[derive(Debug)]
struct Run {
    v: f64,
    a: f64,
    rate: f64,
    rows: usize,
    period_changes: u32,
}

/// Runs `bytes` through the bank and returns the extremes of the CSV.
fn run(bytes: &[u8], bank: BankKind, fixed: bool) -> Run {
    let opts = EstimateOptions {
        bank,
        fixed,
        ..EstimateOptions::default()
    };
    let mut out = Vec::new();
    let report = replay::estimate_stream(bytes, &opts, &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut r = Run {
        v: 0.0,
        a: 0.0,
        rate: 0.0,
        rows: 0,
        period_changes: report.summary.period_changes,
    };
    for line in lines {
        r.rows += 1;
        for (name, field) in header.iter().zip(line.split(',')) {
            let x: f64 = field.parse::<f64>().unwrap().abs();
            assert!(x.is_finite(), "{name} = {field}");
            let m = if name.ends_with("_v") {
                &mut r.v
            } else if name.ends_with("_a") {
                &mut r.a
            } else if *name == "yaw_rate" {
                &mut r.rate
            } else {
                continue;
            };
            *m = m.max(x);
        }
    }
    r
}

/// Every bank and number type over `bytes`: bounded, with `period_changes` changes.
fn check_all(what: &str, bytes: &[u8], rows: usize, period_changes: u32) {
    for bank in [BankKind::Paper, BankKind::Product] {
        for fixed in [false, true] {
            let r = run(bytes, bank, fixed);
            println!("{what}, {} bank, fixed {fixed}: {r:?}", bank.name());
            assert_eq!(r.rows, rows, "{what}");
            assert_eq!(r.period_changes, period_changes, "{what}");
            assert!(r.rate > 100.0, "{what}: the capture moves");
            assert!(r.v < 10.0 * r.rate, "{what}: {r:?}");
            assert!(r.a < 10.0 * ACC_BOUND, "{what}: {r:?}");
        }
    }
}

/// The bundled 100 Hz fig5 capture, then the bundled 20 Hz spin capture
/// (its time of week starts again: a new epoch). The second epoch runs at 50 ms.
#[test]
fn fig5_100hz_then_spin_20hz() {
    let mut bytes = data("fig5_a2_100hz.bin");
    bytes.extend(data("spin_n1_20hz.bin"));
    check_all("fig5 100 Hz + spin 20 Hz", &bytes, 3501 + 401, 1);
}

/// A link that delivers one packet in five after the warm-up: the nominal period stays
/// 10 ms (no new epoch), every later interval is 50 ms (the tracker sub-steps it). Before,
/// `kf_v` reached 4e24 deg/s here.
#[test]
fn one_packet_in_five_after_warmup() {
    let frames = capture(ProfileKind::Fig5, 100, 35.0, 208_800_000);
    let kept: Vec<u8> = frames
        .iter()
        .enumerate()
        .filter(|(k, _)| *k < 100 || k % 5 == 0)
        .flat_map(|(_, f)| f.iter().copied())
        .collect();
    check_all("one packet in five", &kept, 100 + 681, 0);
}

/// What CI runs on a firmware image (docs/RELIABILITY.md): 10 s at 100 Hz, 10 s at 50 Hz in
/// the same epoch (the rate halves: the tracker sub-steps the 20 ms intervals), then a reset:
/// 10 s at 20 Hz from the first time of week again (a new epoch at 50 ms: the banks are
/// rebuilt, one period change).
#[test]
fn rate_halves_then_a_fifth_after_a_reset() {
    let bytes = rate_change_capture();
    check_all("100 Hz, 50 Hz, reset, 20 Hz", &bytes, 1001 + 501 + 201, 1);
}

/// The capture of [`rate_halves_then_a_fifth_after_a_reset`]: `nav440 synth --profile fig5
/// --rate 100 --duration 10`, `--rate 50 --duration 10 --start-itow 208810020` (20 ms after the last 100 Hz packet), `--rate 20
/// --duration 10` (default start 208800000), concatenated.
fn rate_change_capture() -> Vec<u8> {
    let mut bytes = Vec::new();
    for (rate, start) in [(100, 208_800_000), (50, 208_810_020), (20, 208_800_000)] {
        for f in capture(ProfileKind::Fig5, rate, 10.0, start) {
            bytes.extend(f);
        }
    }
    bytes
}
