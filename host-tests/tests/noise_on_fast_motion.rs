//! Does the adaptive bank's online noise estimate (`estimators::NoiseEstimator`, third
//! differences) read fast motion as noise? Measured on the synthetic motions at 100 Hz,
//! noise-free (the quantisation alone, 2.6e-6 deg^2) and with N(0, V) added per packet, against
//! the variance actually added. The motion's own term in a third difference is
//! `(jerk dt^3)^2 / 20`: negligible at 100 Hz unless the jerk reaches about 1e5 deg/s^3.
//!
//! Printed with `cargo test -p host-tests --test noise_on_fast_motion -- --nocapture`; the
//! assertions are the finding (docs/ADAPTIVE-RESULTS.md, "Fast motion and the noise estimate").

use estimators::NoiseEstimator;
use nav440_cli::motion::ProfileKind;
use nav440_cli::replay::{noisy_angle, Axis, Noise};
use nav440_cli::synth::a2_samples;

/// The estimate after each sample past the first 2 s (one time constant of 0.5 s is 50
/// samples): (median, 99th percentile, maximum), deg^2.
fn estimate(profile: ProfileKind, seed: u64, axis: Axis, var: f64) -> (f32, f32, f32) {
    let samples = a2_samples(profile, seed, 100, 35.0).unwrap();
    let noise = (var > 0.0).then_some(Noise { var, seed: 1 });
    let y = noisy_angle(&samples, axis, noise).unwrap();
    let mut est = NoiseEstimator::new(0.5, 0.01).unwrap();
    let mut seen = Vec::new();
    for (s, &a) in samples.iter().zip(&y) {
        est.update(s.t_us, a);
        if s.t_us >= 2_000_000 {
            seen.extend(est.variance());
        }
    }
    seen.sort_by(f32::total_cmp);
    let at = |q: f64| seen[((seen.len() - 1) as f64 * q) as usize];
    (at(0.5), at(0.99), at(1.0))
}

#[test]
fn fast_motion_is_not_read_as_noise_at_100_hz() {
    let cases = [
        (
            ProfileKind::Fig5,
            1,
            Axis::Yaw,
            "fig5 seed 1 (the bundled motion)",
        ),
        (ProfileKind::Fig5, 7, Axis::Yaw, "fig5 seed 7"),
        (ProfileKind::Spin, 1, Axis::Yaw, "spin 100-300 deg/s"),
        (ProfileKind::Tumble, 1, Axis::Pitch, "tumble pitch"),
        (
            ProfileKind::Tumble,
            1,
            Axis::Yaw,
            "tumble yaw (through gimbal lock)",
        ),
    ];
    for (profile, seed, axis, name) in cases {
        for var in [0.0, 0.01, 0.5] {
            let (median, p99, max) = estimate(profile, seed, axis, var);
            eprintln!("{name:34} added {var:5}: median {median:.3e} p99 {p99:.3e} max {max:.3e}");
            let tumble_yaw = profile == ProfileKind::Tumble && axis == Axis::Yaw;
            if var == 0.0 && !tumble_yaw {
                // Noise-free: the estimate stays at the paper's lowest level's tenth or below.
                assert!(p99 < 1e-3, "{name}: {p99} deg^2 read without noise");
            } else if var > 0.0 && !tumble_yaw {
                // With noise: the median within 20 % of the added variance, the 99th
                // percentile within a factor 2 (the estimate's own jitter, 50 terms).
                assert!(
                    (f64::from(median) / var - 1.0).abs() < 0.2,
                    "{name}: median {median} for {var}"
                );
                assert!(f64::from(p99) < 2.0 * var, "{name}: p99 {p99} for {var}");
            } else if var == 0.01 {
                // Fed through gimbal lock, the Euler yaw's swings at the pole read as noise
                // (the pipeline does not feed them to the yaw bank, nor its noise estimate).
                assert!(f64::from(p99) > 2.0 * var, "{name}: p99 {p99}");
            }
        }
    }
}

/// The motions beyond the paper's bounds (`nav440 synth --profile hand|fast-sine|violent`):
/// at 100 Hz they are not read as noise either. Noise-free, the 99th percentile stays below
/// 2e-3 deg^2, a fifth of the lowest level (the violent strokes' jerk, up to
/// `2 pi^2 A / T^2` = 1.2e6 deg/s^3 at their ends, lasts a sample or two: measured 1.4e-3);
/// with noise, the median is within 20 % of the added variance and the 99th percentile within
/// a factor 2, as for the paper's motions.
#[test]
fn motion_beyond_the_papers_bounds() {
    let cases = [
        (ProfileKind::Hand, 1, "hand strokes with pauses"),
        (ProfileKind::FastSine, 1, "fast sine 2 Hz, 400 deg/s"),
        (ProfileKind::Violent, 1, "violent, 600 deg/s"),
    ];
    for (profile, seed, name) in cases {
        for var in [0.0, 0.01, 0.1, 0.5] {
            let (median, p99, max) = estimate(profile, seed, Axis::Yaw, var);
            eprintln!("{name:34} added {var:5}: median {median:.3e} p99 {p99:.3e} max {max:.3e}");
            if var == 0.0 {
                assert!(p99 < 2e-3, "{name}: {p99} deg^2 read without noise");
            } else {
                assert!(
                    (f64::from(median) / var - 1.0).abs() < 0.2,
                    "{name}: median {median} for {var}"
                );
                assert!(f64::from(p99) < 2.0 * var, "{name}: p99 {p99} for {var}");
            }
        }
    }
}

/// How fast the estimate (time constant 0.5 s, `AdaptiveConfig::DEFAULT`) follows a switch of
/// the noise at 15 s, on every yaw motion: up from 0.01 to 0.5 deg^2 (first time it reaches
/// 0.4) and down from 0.5 to 0.01 (first time it falls to 0.012). The clip (a term counts at
/// most 9 times the estimate) bounds the rise to a factor `1 + 8 dt / tau` = 1.16 per sample,
/// 25 samples for 40x; the terms that stay below the clip make it 0.69 s. The fall is the
/// exponential decay of the excess. Measured: up 0.69 s and down 2.29 to 2.35 s on every
/// motion; asserted: up within 1 s and down within 3 s, so the motion does not slow it.
#[test]
fn lag_after_a_noise_switch() {
    let cases = [
        (ProfileKind::Fig5, 1, "fig5"),
        (ProfileKind::Spin, 1, "spin"),
        (ProfileKind::Hand, 1, "hand"),
        (ProfileKind::FastSine, 1, "fast sine"),
        (ProfileKind::Violent, 1, "violent"),
    ];
    const SWITCH_US: u64 = 15_000_000;
    for (profile, seed, name) in cases {
        let samples = a2_samples(profile, seed, 100, 25.0).unwrap();
        let lag = |from: f64, to: f64| {
            let a = noisy_angle(&samples, Axis::Yaw, Some(Noise { var: from, seed: 1 })).unwrap();
            let b = noisy_angle(&samples, Axis::Yaw, Some(Noise { var: to, seed: 2 })).unwrap();
            let mut est = NoiseEstimator::new(0.5, 0.01).unwrap();
            for (k, s) in samples.iter().enumerate() {
                let y = if s.t_us < SWITCH_US { a[k] } else { b[k] };
                est.update(s.t_us, y);
                let v = f64::from(est.variance().unwrap_or(0.0));
                let reached = if to > from {
                    v >= 0.8 * to
                } else {
                    v <= 1.2 * to
                };
                if s.t_us >= SWITCH_US && reached {
                    return (s.t_us - SWITCH_US) as f64 * 1e-6;
                }
            }
            f64::INFINITY
        };
        let (up, down) = (lag(0.01, 0.5), lag(0.5, 0.01));
        eprintln!("{name:10} noise 0.01 -> 0.5 deg^2: {up:.2} s; 0.5 -> 0.01: {down:.2} s");
        assert!(up <= 1.0, "{name}: up {up} s");
        assert!(down <= 3.0, "{name}: down {down} s");
    }
}
