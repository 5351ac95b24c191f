//! Near gimbal lock (|pitch| >= 80 deg) the roll and yaw banks are not fed and restart when
//! the pitch returns, while the pitch bank runs on. Checked on a hand-made stream whose
//! values follow from the rule itself: 100 Hz, roll 10 deg, yaw turning at 20 deg/s, pitch
//! 30 deg except 20 samples at 85 deg (t = 1.00 .. 1.19 s).

use estimators::{BankConfig, Channel, ConfigError, EstimatorOutput, PaperBank, PaperOutput};
use nav440_pipeline::euler::{near_lock, PITCH_LIMIT_DEG};
use nav440_pipeline::{axis_bank, Axes, Axis, Counters, Estimation, Row, Sample};

const N: u64 = 400;
const LOCK: std::ops::Range<u64> = 100..120;
const YAW_RATE: f32 = 20.0;

fn sample(k: u64) -> Sample {
    let t = k as f32 * 0.01;
    let pitch = if LOCK.contains(&k) { 85.0 } else { 30.0 };
    let yaw = (YAW_RATE * t + 180.0).rem_euclid(360.0) - 180.0;
    Sample::new(k * 10_000, [10.0, pitch, yaw], [0.0, 0.0, YAW_RATE], false)
}

fn run(axes: Axes) -> (Vec<Row<PaperOutput>>, Counters) {
    let build = |axis: Axis, cfg: &BankConfig| -> Result<PaperBank<f32>, ConfigError> {
        axis_bank(axis, cfg)
    };
    let mut est = Estimation::new(axes, BankConfig::PAPER, build);
    let mut rows = Vec::new();
    for k in 0..N {
        est.push(sample(k), &mut |r| rows.push(*r)).unwrap();
    }
    est.finish(&mut |r| rows.push(*r)).unwrap();
    (rows, *est.counters())
}

#[test]
fn the_limit_is_the_reference_rate_limit() {
    assert!(near_lock(PITCH_LIMIT_DEG) && near_lock(-PITCH_LIMIT_DEG));
    assert!(!near_lock(79.99) && !near_lock(-79.99) && !near_lock(f32::NAN));
    assert!(Axis::Roll.singular_near_lock() && Axis::Yaw.singular_near_lock());
    assert!(!Axis::Pitch.singular_near_lock());
}

#[test]
fn roll_and_yaw_skip_the_lock_and_restart_after_it() {
    let (rows, c) = run(Axes::ALL);
    // Every sample gives a row; the lock costs roll and yaw fields only.
    assert_eq!(rows.len(), N as usize);
    assert_eq!((c.rows, c.rejected.total()), (N, 0));
    assert_eq!((c.near_lock, c.lock_passes, c.gaps), (20, 1, 0));
    for (k, r) in rows.iter().enumerate() {
        let k = k as u64;
        assert_eq!(r.t_us, k * 10_000);
        let locked = LOCK.contains(&k);
        assert_eq!(r.axis(Axis::Roll).is_none(), locked, "roll at {k}");
        assert_eq!(r.axis(Axis::Yaw).is_none(), locked, "yaw at {k}");
        assert!(r.axis(Axis::Pitch).is_some(), "pitch at {k}");
    }
    // The first sample after the lock re-initialises the yaw bank: every channel reports 0
    // and the angle is the sample's own (no turn was made).
    let first = rows[LOCK.end as usize].axis(Axis::Yaw).unwrap();
    assert!(first.out.values().all(|v| v == 0.0), "{first:?}");
    assert_eq!(
        first.out.unwrapped_deg(),
        sample(LOCK.end).angles_deg()[2],
        "restart angle"
    );
    // Just before the lock the AD velocity follows the 20 deg/s turn, and it does again 1 s
    // after the restart (a bank fed through the lock would see pitch-pole swings instead).
    let ad = |k: u64| rows[k as usize].axis(Axis::Yaw).unwrap().out[Channel::AdV];
    for k in [LOCK.start - 1, LOCK.end + 100, N - 1] {
        assert!(
            (ad(k) - YAW_RATE).abs() < 0.5,
            "AD velocity {} at {k}",
            ad(k)
        );
    }
}

#[test]
fn a_pitch_only_pipeline_is_untouched() {
    let (rows, c) = run(Axes::only(Axis::Pitch));
    assert_eq!(rows.len(), N as usize);
    assert_eq!((c.near_lock, c.lock_passes), (0, 0));
    assert!(rows.iter().all(|r| r.axis(Axis::Pitch).is_some()));
}

#[test]
fn every_pass_is_counted_and_a_lock_at_the_end_is_not() {
    // Two locks: two passes; a stream ending inside a lock does not count a pass.
    let build = |axis: Axis, cfg: &BankConfig| -> Result<PaperBank<f32>, ConfigError> {
        axis_bank(axis, cfg)
    };
    let mut est = Estimation::new(Axes::only(Axis::Yaw), BankConfig::PAPER, build);
    let mut rows = 0usize;
    for k in 0..300u64 {
        let mut s = sample(k);
        let locked = (50..60).contains(&k) || (150..160).contains(&k) || k >= 290;
        s.set_angle_deg(Axis::Pitch, if locked { -88.0 } else { 0.0 });
        est.push(s, &mut |_| rows += 1).unwrap();
    }
    est.finish(&mut |_| rows += 1).unwrap();
    let c = est.counters();
    assert_eq!(rows, 300);
    assert_eq!((c.near_lock, c.lock_passes), (30, 2));
}
