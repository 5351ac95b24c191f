//! Time faults, mixed time-stamp kinds and low packet rates through the host pipeline
//! (`replay::samples_and_faults` -> `replay::estimate_report`), the same code path as
//! `nav440 estimate` and, through `nav440_proto::TimeBase`, the firmware. Expected values come
//! from the stamps written into the capture and the closed-form motion.

mod common;

use nav440_cli::replay::{self, Axis, EstimateOptions};
use nav440_proto::{A0Fields, A2Fields};

const YAW_LSB: f64 = 360.0 / 65536.0;
const RATE_LSB: f64 = 1260.0 / 65536.0;

fn wrap_counts(yaw_deg: f64) -> i16 {
    ((yaw_deg / YAW_LSB).round() as i64).rem_euclid(65536) as u16 as i16
}

fn a2(itow: u32, yaw_deg: f64, rate: f64) -> Vec<u8> {
    let mut buf = [0u8; 64];
    let n = A2Fields {
        yaw_true: wrap_counts(yaw_deg),
        rate_z: (rate / RATE_LSB).round() as i16,
        time_itow: itow,
        ..Default::default()
    }
    .encode(&mut buf)
    .unwrap();
    buf[..n].to_vec()
}

fn a0(gps_itow: u16, yaw_deg: f64) -> Vec<u8> {
    let mut buf = [0u8; 64];
    let n = A0Fields {
        yaw_mag: wrap_counts(yaw_deg),
        gps_itow,
        ..Default::default()
    }
    .encode(&mut buf)
    .unwrap();
    buf[..n].to_vec()
}

/// A 100 Hz A2 recording of a spin at `rate` deg/s from `yaw0`, `n` packets from `itow0`.
fn spin(itow0: u32, n: u32, yaw0: f64, rate: f64) -> Vec<Vec<u8>> {
    (0..n)
        .map(|k| a2(itow0 + 10 * k, yaw0 + rate * f64::from(k) * 0.01, rate))
        .collect()
}

fn for_both(f: impl Fn(&EstimateOptions)) {
    for fixed in [false, true] {
        f(&EstimateOptions {
            fixed,
            ..Default::default()
        });
    }
}

/// The case: two recordings stitched, the second starting 300 s earlier in time of
/// week with the yaw 137 deg away and turning the other way. Old code: velocity estimates of
/// 3,000-10,000 deg/s. Now: one backward jump counted, no sample lost, time keeps increasing
/// by the packet period, and every velocity estimate stays within a bound from the true motion
/// (|rate| <= 240 deg/s): 2 x 240 (the overshoot of a second-order loop started from rest on a
/// motion already at full rate, as at the start of each recording) + 49 deg/s (the ED's Euler
/// chatter lambda^2 h).
#[test]
fn stitched_recordings_do_not_spike() {
    let mut frames = spin(400_000, 1000, 0.0, 240.0);
    frames.extend(spin(100_000, 1000, 137.0, -200.0));
    let bytes = frames.concat();
    let (samples, faults) = replay::samples_and_faults(&bytes).unwrap();
    assert_eq!(samples.len(), 2000);
    assert_eq!(faults.backward_jumps, 1);
    assert_eq!(faults.discarded(), 0);
    for (k, s) in samples.iter().enumerate() {
        assert_eq!((s.t_us, s.new_epoch), (k as u64 * 10_000, k == 1000));
    }
    for_both(|opts| {
        let est = replay::estimate_report(&samples, opts).unwrap();
        assert_eq!(est.rows.len(), 2000);
        let bound = 2.0 * 240.0 + 49.0;
        for r in &est.rows {
            for v in r.axis(Axis::Yaw).unwrap().out.velocities() {
                assert!(v.abs() <= bound, "t {} s: {v} deg/s", r.t_us as f64 * 1e-6);
            }
        }
        // The new epoch re-initialised the bank: its first row reports 0.
        assert_eq!(
            est.rows[1000].axis(Axis::Yaw).unwrap().out.velocities(),
            [0.0; estimators::FAMILY_COUNT]
        );
    });
    let w = replay::fault_warning(&faults, 0).unwrap();
    assert!(w.contains("backward_jumps=1"), "{w}");
}

/// A single CRC-valid packet with timeITOW 0xFFFFFFFF: exactly one sample lost and every later
/// time unchanged (old code: two samples lost and every later t shifted by 10 ms).
#[test]
fn one_impossible_stamp_costs_one_sample() {
    let clean = spin(123_000, 300, 10.0, 50.0);
    let mut bad = clean.clone();
    bad[100] = a2(0xFFFF_FFFF, 0.0, 0.0);
    let s_clean = replay::samples(&clean.concat()).unwrap();
    let (s_bad, faults) = replay::samples_and_faults(&bad.concat()).unwrap();
    let mut expected = s_clean.clone();
    expected.remove(100);
    assert_eq!(s_bad, expected);
    assert_eq!((faults.impossible, faults.discarded()), (1, 1));
    // The same for a single backward and a single forward stamp.
    for itow in [123_000 + 990 - 7_000, 123_000 + 990 + 3_600_000] {
        let mut bad = clean.clone();
        bad[100] = a2(itow, 0.0, 0.0);
        let (s_bad, faults) = replay::samples_and_faults(&bad.concat()).unwrap();
        assert_eq!(s_bad, expected, "stamp {itow}");
        assert_eq!(faults.discarded(), 1);
    }
}

fn n_a0(every: u32) -> u32 {
    2000 / every
}

/// A0 packets (GPSITOW = low 16 bits of the same ms counter, magnetic yaw) polled between A2
/// packets: every A2 sample is kept at its own time; the A0s are ignored and counted. Old
/// code: 1,801 rows from 2,000 A2 + 200 A0; 1 row when they alternate.
#[test]
fn polled_a0_between_a2_loses_no_a2_sample() {
    for (every, a0_first) in [(10u32, false), (1, false), (1, true)] {
        let mut bytes = Vec::new();
        for k in 0..2000u32 {
            let itow = 300_000_000 + 10 * k;
            let a0_here = k % every == 0;
            if a0_here && a0_first {
                bytes.extend(a0((itow - 3) as u16, 77.0));
            }
            bytes.extend(a2(itow, f64::from(k) * 0.5, 50.0));
            if a0_here && !a0_first {
                bytes.extend(a0((itow + 3) as u16, 77.0));
            }
        }
        let (samples, faults) = replay::samples_and_faults(&bytes).unwrap();
        // Every yaw packet is accounted for: released, discarded or a duplicate.
        let mut reader = replay::SampleReader::new();
        reader.feed(&bytes, |_| {});
        reader.finish(|_| {});
        assert_eq!(reader.yaw_packets(), u64::from(2000 + n_a0(every)));
        assert_eq!(
            reader.yaw_packets(),
            reader.samples() + u64::from(faults.discarded() + faults.duplicates)
        );
        let a2_samples: Vec<_> = samples.iter().filter(|s| s.rates_deg_s[2] != 0.0).collect();
        assert_eq!(a2_samples.len(), 2000, "every {every}, A0 first {a0_first}");
        let n_a0 = n_a0(every);
        if a0_first {
            // The first A0 starts the stream; the first A2 switches the base to timeITOW.
            assert_eq!(samples.len(), 2001);
            assert_eq!((faults.kind_switches, faults.other_kind), (1, n_a0 - 1));
        } else {
            assert_eq!(samples.len(), 2000);
            assert_eq!((faults.kind_switches, faults.other_kind), (0, n_a0));
        }
        for w in a2_samples.windows(2) {
            assert_eq!(w[1].t_us - w[0].t_us, 10_000);
        }
        let est = replay::estimate_report(&samples, &EstimateOptions::default()).unwrap();
        assert_eq!(est.rows.len(), samples.len());
    }
}

/// 2 Hz (the unit's slowest rate): the gap rule is 25 nominal periods (12.5 s), so the bank
/// integrates and reports the rate (old code: every 0.5 s interval exceeded the fixed 0.25 s,
/// every sample re-initialised the bank and every estimate was 0).
#[test]
fn two_hertz_capture_gives_estimates() {
    let rate = 30.0; // deg/s, 15 deg per packet
    let frames: Vec<_> = (0..120u32)
        .map(|k| a2(50_000 + 500 * k, rate * f64::from(k) * 0.5, rate))
        .collect();
    let samples = replay::samples(&frames.concat()).unwrap();
    for_both(|opts| {
        let est = replay::estimate_report(&samples, opts).unwrap();
        assert_eq!(est.gaps, 0);
        let last = est
            .rows
            .last()
            .unwrap()
            .axis(Axis::Yaw)
            .unwrap()
            .out
            .velocities();
        // AVE, AD, KF within 2 %; ILOs within their leaky DC gain c / (L + c),
        // c = K2 / (1 - K1) (the paper's ILO2/ILO3: 0.952, 0.985) and 2 %; ED within its
        // chatter.
        let ilo = opts.bank_config().velocity.ilo;
        let dc = |i: usize| common::ilo_dc_gain(&ilo[i]);
        for (i, v) in last.iter().enumerate() {
            let (gain, tol) = match i {
                1..=3 => (dc(i - 1) as f32, 0.02),
                5 => (1.0, 49.0 / rate),
                _ => (1.0, 0.02),
            };
            assert!(
                (v / (gain * rate as f32) - 1.0).abs() <= tol as f32,
                "column {i}: {v}"
            );
        }
    });
}

/// The committed capture `host-tests/data/time_faults_a2_100hz.bin` (so `cargo xtask
/// ci-firmware`, which runs every capture there through the firmware, checks the firmware's
/// time-fault handling against `nav440 estimate` byte for byte): 400 A2 packets of a
/// 240 deg/s spin at 100 Hz with one A0 polled per ten A2, one 0xFFFFFFFF stamp (packet 50),
/// one stamp 7 s back (120) and one an hour ahead (200); then a second recording starting
/// 402 s earlier, turning the other way at 200 deg/s, with a 2 s dropout after 300 packets.
/// Regenerate with `NAV440_WRITE_CAPTURE=1 cargo test -p host-tests --test time_faults`.
fn time_fault_capture() -> Vec<u8> {
    let mut out = Vec::new();
    for k in 0..400u32 {
        let itow = match k {
            50 => 0xFFFF_FFFF,
            120 => 500_000 + 10 * k - 7_000,
            200 => 500_000 + 10 * k + 3_600_000,
            _ => 500_000 + 10 * k,
        };
        out.extend(a2(itow, 2.4 * f64::from(k), 240.0));
        if k % 10 == 3 {
            out.extend(a0((itow.wrapping_add(3)) as u16, 77.0));
        }
    }
    for k in 0..300u32 {
        out.extend(a2(100_000 + 10 * k, 137.0 - 2.0 * f64::from(k), -200.0));
    }
    for k in 0..300u32 {
        out.extend(a2(105_000 + 10 * k, -463.0 - 2.0 * f64::from(k), -200.0));
    }
    out
}

#[test]
fn committed_time_fault_capture() {
    let bytes = time_fault_capture();
    let path = host_tests::data("time_faults_a2_100hz.bin");
    if std::env::var_os("NAV440_WRITE_CAPTURE").is_some() {
        std::fs::write(&path, &bytes).unwrap();
    }
    assert_eq!(
        std::fs::read(&path).unwrap(),
        bytes,
        "regenerate: see the doc comment"
    );
    let (samples, f) = replay::samples_and_faults(&bytes).unwrap();
    // 1,000 A2 packets less the three bad stamps; 40 A0 ignored.
    assert_eq!(samples.len(), 997);
    assert_eq!(
        (
            f.impossible,
            f.bad_backward,
            f.bad_forward,
            f.backward_jumps,
            f.other_kind
        ),
        (1, 1, 1, 1, 40)
    );
    for_both(|opts| {
        let est = replay::estimate_report(&samples, opts).unwrap();
        assert_eq!((est.rows.len(), est.gaps), (997, 1));
        for r in &est.rows {
            for v in r.axis(Axis::Yaw).unwrap().out.velocities() {
                assert!(v.abs() <= 2.0 * 240.0 + 49.0, "{v}");
            }
        }
    });
}
