//! The shipped gains (`BankConfig::NAV440`, what `nav440 estimate` and the firmware run) and
//! the bundled noise schedule (`nav440 estimate --gains schedule_fig5.toml`) against the
//! backward difference of the angle, on a family of yaw motions they were not tuned on, at
//! three noise levels: the velocity MSE (deg/s)^2 of every family against the exact rate the
//! packets carry, over 1-30 s of a 30 s capture at 100 Hz, noise seed 1.
//!
//! Printed with `cargo test --release -p host-tests --test motion_family -- --nocapture`
//! (docs/ADAPTIVE-RESULTS.md, "The shipped gains against the backward difference"). The
//! assertions check the backward difference against its own closed form, so that the
//! yardstick is right; whether the gains beat it is the measurement, not asserted.

use estimators::BankConfig;
use nav440_cli::motion::ProfileKind;
use nav440_cli::paper::COLUMNS;
use nav440_cli::replay::{self, noisy_angle, unwrap_deg, Axis, EstimateOptions, Noise};
use nav440_cli::synth::a2_samples;
use nav440_cli::tune::bank_mse;

mod runs;
use runs::{mse_over, schedule};

/// The motions: (profile, shape seed, label).
const MOTIONS: [(ProfileKind, u64, &str); 5] = [
    (ProfileKind::Fig5, 1, "fig5 (the paper's bounds)"),
    (ProfileKind::Spin, 1, "spin 100-300 deg/s"),
    (ProfileKind::Hand, 1, "hand strokes with pauses"),
    (ProfileKind::FastSine, 1, "fast sine 2 Hz, 400 deg/s"),
    (ProfileKind::Violent, 1, "violent, 600 deg/s"),
];

/// Noise variances added to the angle, deg^2.
const NOISE: [f64; 3] = [0.01, 0.1, 0.5];

/// Scored span, s.
const RANGE: (f64, f64) = (1.0, 30.0);

/// The packets' period, s (100 Hz).
const DT_S: f64 = 0.01;

/// The yaw reference rate (deg/s) at each sample: the rows of a replay without noise, one per
/// sample (none rejected).
fn reference(samples: &[replay::Sample]) -> Vec<f64> {
    let (rows, rejected) = replay::estimate(samples, &EstimateOptions::default()).unwrap();
    assert_eq!(rejected, 0);
    assert_eq!(rows.len(), samples.len());
    rows.iter()
        .zip(samples)
        .map(|(r, s)| {
            assert_eq!(r.t_us, s.t_us);
            f64::from(r.axis(Axis::Yaw).unwrap().reference_deg_s.unwrap())
        })
        .collect()
}

/// The velocity MSE of the backward difference `(y_k - y_(k-1)) / dt` of the noisy angle
/// (noise seed 1, as `bank_mse`) against `reference` (one value per sample), and its closed
/// form for white noise: `2 var / dt^2` plus the motion's own term, the mean of
/// `(v_k - (x_k - x_(k-1)) / dt)^2` computed from the noise-free angle.
fn backward_difference(samples: &[replay::Sample], reference: &[f64], var: f64) -> (f64, f64) {
    let noisy = unwrap_deg(&noisy_angle(samples, Axis::Yaw, Some(Noise { var, seed: 1 })).unwrap());
    let clean = unwrap_deg(&noisy_angle(samples, Axis::Yaw, None).unwrap());
    let (mut sum, mut motion, mut n) = (0.0, 0.0, 0usize);
    for k in 1..samples.len() {
        let t = samples[k].t_us as f64 * 1e-6;
        if t < RANGE.0 || t > RANGE.1 {
            continue;
        }
        let dt = (samples[k].t_us - samples[k - 1].t_us) as f64 * 1e-6;
        let bd = f64::from(noisy[k] - noisy[k - 1]) / dt;
        let bd_clean = f64::from(clean[k] - clean[k - 1]) / dt;
        sum += (bd - reference[k]).powi(2);
        motion += (bd_clean - reference[k]).powi(2);
        n += 1;
    }
    (
        sum / n as f64,
        motion / n as f64 + 2.0 * var / (DT_S * DT_S),
    )
}

#[test]
fn shipped_gains_against_the_backward_difference() {
    println!(
        "velocity MSE (deg/s)^2: the shipped gains (BankConfig::NAV440), the bundled schedule (schedule_fig5.toml) and the backward difference (BD)"
    );
    println!(
        "{:<28} {:>5} {:>9} {}",
        "motion",
        "noise",
        "BD",
        COLUMNS.map(|c| format!("{c:>9}")).join("")
    );
    // The bundled schedule as `nav440 estimate --gains schedule_fig5.toml` runs it.
    let (_, scheduled) = schedule("gains/schedule_fig5.toml");
    for (profile, seed, label) in MOTIONS {
        let samples = a2_samples(profile, seed, 100, 30.0).unwrap();
        let reference = reference(&samples);
        for var in NOISE {
            let (bd, bd_expected) = backward_difference(&samples, &reference, var);
            // The yardstick: the measured BD MSE is its closed form within the sampling
            // spread of about 2,900 squared Gaussians (and the cross term): 10 %.
            assert!(
                (bd / bd_expected - 1.0).abs() < 0.1,
                "{label} {var}: BD {bd} vs {bd_expected}"
            );
            let (v, _) = bank_mse(&samples, BankConfig::NAV440, var, 1, RANGE).unwrap();
            println!(
                "{label:<28} {var:>5} {bd:>9.0} {}",
                v.map(|x| format!("{x:>9.0}")).join("")
            );
            println!(
                "{:<28} {:>5} {:>9} {}",
                "  the schedule",
                "",
                "",
                mse_over(
                    &samples,
                    &EstimateOptions {
                        // the noise `bank_mse` adds
                        noise: Some(Noise { var, seed: 1 }),
                        ..scheduled.clone()
                    },
                    &[RANGE]
                )[0]
                .map(|x| format!("{x:>9.0}"))
                .join("")
            );
        }
    }
}
