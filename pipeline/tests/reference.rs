//! The rows' rate column chosen by type (`nav440_pipeline::Reference`): the Euler reference
//! rate (`EulerReference`, the default) or the unit's body rate (`BodyRates`). Checked against
//! values known independently of the code under test:
//!
//! * a level unit turning at r: the body-rate yaw column is r as the packet encodes it (LSB x
//!   1260 / 2^16 deg/s), which is also the Euler yaw rate of a level unit;
//! * a tilted unit: the body-rate columns are p, q, r as given, whatever the angles;
//! * near gimbal lock: the same rows (time, angles, every channel) and the same counters with
//!   either reference; only the rate column differs;
//! * the header names `<axis>_body_rate`.

use estimators::{
    BankConfig, ConfigError, EstimatorOutput, PaperBank, PaperOutput, ProductBank, ProductOutput,
};
use nav440_pipeline::{
    axis_bank, csv, Axes, Axis, BodyRates, Counters, Estimation, EulerReference, Pipeline,
    RateColumn, Reference, Row, Sample,
};
use nav440_proto::{encode_frame, A2Fields, PacketType};

/// Body rate of a rate field, deg/s (the A2 rate scaling: 7 pi rad/s = 1260 deg/s per 2^16).
fn rate_deg_s(lsb: i16) -> f32 {
    (f64::from(lsb) * 1260.0 / 65536.0) as f32
}

/// `n` A2 packets at 100 Hz, level, yaw turning with the rate field `rate_z` (LSB), p and q
/// fields `rate_x`, `rate_y`.
fn level_turn(n: u32, rate_x: i16, rate_y: i16, rate_z: i16) -> Vec<u8> {
    let r = f64::from(rate_deg_s(rate_z));
    let mut bytes = Vec::new();
    for k in 0..n {
        let yaw = (r * 0.01 * f64::from(k) + 180.0).rem_euclid(360.0) - 180.0;
        let p = A2Fields {
            yaw_true: (yaw * 65536.0 / 360.0).round() as i16,
            rate_x,
            rate_y,
            rate_z,
            time_itow: 1000 + 10 * k,
            ..Default::default()
        };
        let mut frame = [0u8; 64];
        let len = encode_frame(PacketType::A2, &p.payload(), &mut frame).unwrap();
        bytes.extend_from_slice(&frame[..len]);
    }
    bytes
}

type Build = fn(Axis, &BankConfig) -> Result<ProductBank<f32>, ConfigError>;

fn build(axis: Axis, cfg: &BankConfig) -> Result<ProductBank<f32>, ConfigError> {
    axis_bank(axis, cfg)
}

/// Rows and CSV lines of `bytes` through a three-axis product pipeline with the rate column
/// `R`.
fn run<R: Reference>(bytes: &[u8]) -> (Vec<Row<ProductOutput>>, Vec<String>) {
    let mut rows = Vec::new();
    let mut pipe: Pipeline<_, _, Build, 3, R> =
        Pipeline::with_slots(Axes::ALL, BankConfig::NAV440, build);
    pipe.feed(bytes, &mut |r| rows.push(*r)).unwrap();
    pipe.finish(&mut |r| rows.push(*r)).unwrap();
    let mut lines = Vec::new();
    let mut pipe: Pipeline<_, _, Build, 3, R> =
        Pipeline::with_slots(Axes::ALL, BankConfig::NAV440, build);
    pipe.feed_csv(bytes, |l| lines.push(l.to_owned())).unwrap();
    pipe.finish_csv(|l| lines.push(l.to_owned())).unwrap();
    assert_eq!(pipe.rate_column(), R::COLUMN);
    (rows, lines)
}

/// Level, r = 1560 LSB (29.99 deg/s), p = 100, q = -50 LSB: the body-rate columns are the
/// packet's rates, and equal the Euler reference of a level unit; the estimates are the same.
#[test]
fn a_level_sample_gives_the_body_rates_which_are_the_euler_rates() {
    let (rx, ry, rz) = (100, -50, 1560);
    let bytes = level_turn(200, rx, ry, rz);
    let (body, body_csv) = run::<BodyRates>(&bytes);
    let (euler, euler_csv) = run::<EulerReference>(&bytes);
    assert_eq!(body.len(), 200);
    let r = rate_deg_s(rz);
    assert!((r - 29.992_676).abs() < 1e-5, "{r}");
    for (b, e) in body.iter().zip(&euler) {
        for (axis, want) in Axis::ALL.iter().zip([rate_deg_s(rx), rate_deg_s(ry), r]) {
            let (ba, ea) = (b.axis(*axis).unwrap(), e.axis(*axis).unwrap());
            assert_eq!(ba.reference_deg_s, Some(want), "{axis:?} at {}", b.t_us);
            // Level: the Euler rates are exactly p, q, r.
            assert_eq!(ea.reference_deg_s, Some(want), "{axis:?} at {}", b.t_us);
            assert_eq!(ba.out, ea.out);
        }
    }
    // Level, so the CSV rows are the same text; the headers differ in the rate columns only.
    assert_eq!(body_csv, euler_csv);
    let yaw_rate = body_csv[150].trim().split(',').nth(10).unwrap();
    assert_eq!(yaw_rate.parse::<f32>().unwrap(), r);
}

/// Tilted (roll 30, pitch 45 deg): the body-rate column is p, q, r whatever the angles; the
/// Euler yaw rate is (q sin 30 + r cos 30) / cos 45.
#[test]
fn a_tilted_sample_gives_the_body_rates_as_sent() {
    let (angles, pqr) = ([30.0, 45.0, -120.0], [1.0, 2.0, 3.0]);
    assert_eq!(
        BodyRates::rates_deg_s(angles, pqr),
        [Some(1.0), Some(2.0), Some(3.0)]
    );
    let euler = EulerReference::rates_deg_s(angles, pqr)[2].unwrap();
    let want = (2.0 * 0.5 + 3.0 * 3f64.sqrt() / 2.0) * 2f64.sqrt();
    assert!((f64::from(euler) - want).abs() < 1e-5, "{euler}");
}

/// The header: `<axis>_body_rate`, prefixed for one axis as for all.
#[test]
fn header_names() {
    let header = |axes, rate| {
        let mut s = String::new();
        csv::write_header_for::<ProductOutput>(&mut s, axes, rate).unwrap();
        s
    };
    assert_eq!(
        header(Axes::only(Axis::Yaw), RateColumn::Body),
        "t,yaw,yaw_body_rate,ilo1_v,kf_a"
    );
    assert_eq!(
        header(Axes::only(Axis::Yaw), RateColumn::Euler),
        "t,yaw,yaw_rate,ilo1_v,kf_a"
    );
    assert_eq!(
        header(Axes::ALL, BodyRates::COLUMN),
        "t,roll,roll_body_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_body_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_body_rate,yaw_ilo1_v,yaw_kf_a"
    );
    let mut paper = String::new();
    csv::write_header_for::<PaperOutput>(&mut paper, Axes::only(Axis::Yaw), RateColumn::Body)
        .unwrap();
    assert_eq!(paper, csv::HEADER.replace("yaw_rate", "yaw_body_rate"));
    assert_eq!(EulerReference::COLUMN, RateColumn::Euler);
}

/// The stream of `pipeline/tests/gimbal_lock.rs`: 100 Hz, roll 10 deg, yaw turning at
/// 20 deg/s, pitch 30 deg except 20 samples at 85 deg (k = 100 .. 119); p, q, r = 0, 0, 20.
fn lock_sample(k: u64) -> Sample {
    let t = k as f32 * 0.01;
    let pitch = if (100..120).contains(&k) { 85.0 } else { 30.0 };
    let yaw = (20.0 * t + 180.0).rem_euclid(360.0) - 180.0;
    Sample::new(k * 10_000, [10.0, pitch, yaw], [0.0, 0.0, 20.0], false)
}

fn lock_run<R: Reference>() -> (Vec<Row<PaperOutput>>, Counters) {
    let build = |axis: Axis, cfg: &BankConfig| -> Result<PaperBank<f32>, ConfigError> {
        axis_bank(axis, cfg)
    };
    let mut est: Estimation<_, _, _, 3, R> =
        Estimation::with_slots(Axes::ALL, BankConfig::PAPER, build);
    let mut rows = Vec::new();
    for k in 0..400 {
        est.push(lock_sample(k), &mut |r| rows.push(*r)).unwrap();
    }
    est.finish(&mut |r| rows.push(*r)).unwrap();
    (rows, *est.counters())
}

/// The pause near gimbal lock does not depend on the rate column: the same rows without roll
/// and yaw in the lock, the same restart, the same counters (20 samples, one pass).
#[test]
fn the_gimbal_lock_pause_is_the_same_with_body_rates() {
    let (body, cb) = lock_run::<BodyRates>();
    let (euler, ce) = lock_run::<EulerReference>();
    assert_eq!(cb, ce);
    assert_eq!((cb.rows, cb.near_lock, cb.lock_passes), (400, 20, 1));
    assert_eq!(body.len(), euler.len());
    for (k, (b, e)) in body.iter().zip(&euler).enumerate() {
        let locked = (100..120).contains(&k);
        assert_eq!(b.t_us, e.t_us);
        for axis in Axis::ALL {
            let (ba, ea) = (b.axis(axis), e.axis(axis));
            assert_eq!(
                ba.is_none(),
                locked && axis != Axis::Pitch,
                "{axis:?} at {k}"
            );
            assert_eq!(ba.is_none(), ea.is_none());
            if let (Some(ba), Some(ea)) = (ba, ea) {
                assert_eq!(ba.out, ea.out, "{axis:?} at {k}");
            }
        }
        // The pitch axis runs through the lock: its body rate is q = 0 there too.
        assert_eq!(b.axis(Axis::Pitch).unwrap().reference_deg_s, Some(0.0));
        if !locked {
            assert_eq!(b.axis(Axis::Yaw).unwrap().reference_deg_s, Some(20.0));
            // Tilted: the Euler yaw rate is r cos 10 / cos 30, not r.
            let want = 20.0 * 10f64.to_radians().cos() / 30f64.to_radians().cos();
            let got = e.axis(Axis::Yaw).unwrap().reference_deg_s.unwrap();
            assert!((f64::from(got) - want).abs() < 1e-4, "{got} at {k}");
        }
    }
    // The first sample after the lock restarts the yaw bank: every channel 0.
    let first = body[120].axis(Axis::Yaw).unwrap();
    assert!(first.out.values().all(|v| v == 0.0));
}
