//! The nominal sample period rule (`nav440_pipeline::period`), against intervals sorted by hand.

use estimators::BankConfig;
use nav440_pipeline::period::{PeriodEstimator, WARMUP_SAMPLES};

/// The period the rule must give for an upper-median interval of `us` microseconds, s.
fn secs(us: u32) -> f32 {
    us as f32 * 1e-6
}

/// Times (us) from a first time of 0 and the given intervals (us).
fn times(intervals_us: &[u64]) -> Vec<u64> {
    let mut t = vec![0u64];
    for d in intervals_us {
        t.push(t.last().unwrap() + d);
    }
    t
}

fn assert_period(est: &PeriodEstimator, want_s: f64, us: u32) {
    let p = est.period_s().expect("a period");
    assert!((f64::from(p) - want_s).abs() < 1e-9, "{p} vs {want_s}");
    assert_eq!(p, secs(us));
}

#[test]
fn warm_up_is_sixteen_samples() {
    assert_eq!(WARMUP_SAMPLES, 16);
}

#[test]
fn steady_100_hz() {
    let est = PeriodEstimator::from_times((0..16u64).map(|k| 1_000_000 + k * 10_000));
    assert!(est.is_complete());
    assert_period(&est, 0.01, 10_000);
    assert!((est.apply(BankConfig::default()).sample_period_s - 0.01).abs() < 1e-9);
}

#[test]
fn steady_20_hz_replaces_the_default() {
    let est = PeriodEstimator::from_times((0..16u64).map(|k| k * 50_000));
    let cfg = est.apply(BankConfig::default());
    assert!((cfg.sample_period_s - 0.05).abs() < 1e-9);
    // Nothing else changes.
    assert_eq!(
        BankConfig {
            sample_period_s: 0.01,
            ..cfg
        },
        BankConfig::default()
    );
}

#[test]
fn one_dropped_packet_among_the_first_16() {
    // k = 0..=16 without k = 5: 16 samples, intervals 14 x 10 ms and one 20 ms.
    let t: Vec<u64> = (0..=16u64)
        .filter(|&k| k != 5)
        .map(|k| k * 10_000)
        .collect();
    assert_eq!(t.len(), 16);
    let est = PeriodEstimator::from_times(t);
    assert!(est.is_complete());
    // Sorted: 10000 x 14, 20000; d[7] = 10000.
    assert_period(&est, 0.01, 10_000);
}

#[test]
fn jitter() {
    let d = [
        10_010, 9_990, 10_020, 10_030, 9_980, 10_040, 10_010, 10_050, 9_970, 10_020, 10_060,
        10_000, 10_030, 9_960, 10_040,
    ];
    // Sorted by hand: 9960 9970 9980 9990 10000 10010 10010 [10020] 10020 10030 10030 10040
    // 10040 10050 10060; the 8th of 15 (d[7]) is 10020 us.
    let est = PeriodEstimator::from_times(times(&d));
    assert_eq!(est.samples(), 16);
    assert_period(&est, 0.010_02, 10_020);
}

#[test]
fn samples_after_the_warm_up_are_ignored() {
    // 16 samples at 100 Hz, then 50 Hz.
    let mut est = PeriodEstimator::new();
    for k in 0..16u64 {
        assert!(est.push(k * 10_000));
    }
    assert!(est.is_complete());
    for k in 1..30u64 {
        assert!(!est.push(150_000 + k * 20_000));
    }
    assert_eq!(est.samples(), WARMUP_SAMPLES);
    assert_period(&est, 0.01, 10_000);
    // Same as reading the whole stream at once.
    let all = (0..16u64)
        .map(|k| k * 10_000)
        .chain((1..30u64).map(|k| 150_000 + k * 20_000));
    assert_eq!(PeriodEstimator::from_times(all), est);
}

#[test]
fn fewer_than_16_samples_use_the_intervals_they_have() {
    // Intervals 20 ms, 10 ms: sorted [10000, 20000], upper median d[1] = 20000 us.
    let est = PeriodEstimator::from_times([0, 20_000, 30_000]);
    assert!(!est.is_complete());
    assert_eq!(est.samples(), 3);
    assert_period(&est, 0.02, 20_000);
    // Intervals 10, 20, 10 ms: sorted [10000, 10000, 20000], d[1] = 10000 us.
    assert_period(
        &PeriodEstimator::from_times([0, 10_000, 30_000, 40_000]),
        0.01,
        10_000,
    );
    // Two samples: their one interval.
    assert_period(&PeriodEstimator::from_times([5, 40_005]), 0.04, 40_000);
    // Ten samples at 50 Hz (a capture shorter than the warm-up).
    assert_period(
        &PeriodEstimator::from_times((0..10u64).map(|k| k * 20_000)),
        0.02,
        20_000,
    );
}

#[test]
fn non_increasing_time_is_a_zero_interval() {
    // Intervals 10000, 0 (5000 < 10000), 10000: sorted [0, 10000, 10000], d[1] = 10000 us.
    assert_period(
        &PeriodEstimator::from_times([0, 10_000, 5_000, 15_000]),
        0.01,
        10_000,
    );
    // Intervals 10000, 0: sorted [0, 10000], d[1] = 10000 us.
    assert_period(
        &PeriodEstimator::from_times([0, 10_000, 10_000]),
        0.01,
        10_000,
    );
}

#[test]
fn single_sample_or_none_keeps_the_configured_period() {
    for est in [
        PeriodEstimator::from_times([123_456]),
        PeriodEstimator::new(),
    ] {
        assert_eq!(est.period_s(), None);
        assert!(!est.is_complete());
        assert_eq!(est.apply(BankConfig::default()), BankConfig::default());
        let cfg = BankConfig {
            sample_period_s: 0.05,
            ..BankConfig::default()
        };
        assert_eq!(est.apply(cfg).sample_period_s, 0.05);
    }
    assert_eq!(PeriodEstimator::new().samples(), 0);
    assert_eq!(PeriodEstimator::from_times([7]).samples(), 1);
}
