//! Helpers shared by the tests that score the estimators on the synthetic motion family
//! (`motion_family.rs`, `self_tune.rs`): the reference rate, an MSE over a span, and the
//! gains tuned on a motion.

use estimators::{BankConfig, Hold};
use nav440_cli::optim::Method;
use nav440_cli::replay::{self, Axis, EstimateOptions};
use nav440_cli::tune::{tune_with, Families, TuneSpec};

/// The yaw reference rate (deg/s) at each sample: the rows of a replay without noise, one per
/// sample (none rejected).
pub fn reference(samples: &[replay::Sample]) -> Vec<f64> {
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

/// The MSE over `range` (s) of `values` (one per sample) against `reference` (one per sample;
/// a NaN reference sample is left out).
pub fn mse_of(
    samples: &[replay::Sample],
    values: &[f64],
    reference: &[f64],
    range: (f64, f64),
) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for ((s, x), r) in samples.iter().zip(values).zip(reference) {
        let t = s.t_us as f64 * 1e-6;
        if t >= range.0 && t <= range.1 && r.is_finite() {
            sum += (x - r).powi(2);
            n += 1;
        }
    }
    sum / n as f64
}

/// The families `families` tuned on `samples` at noise `var` (one seed, linear hold, the span
/// `range`, s), over the shipped gains, as a bank configuration.
pub fn tuned_over(
    samples: &[replay::Sample],
    var: f64,
    families: Families,
    range: (f64, f64),
) -> BankConfig {
    tune_with(
        samples,
        &EstimateOptions::default(),
        &TuneSpec {
            noise_var: var,
            seeds: 1,
            train: range,
            test: None,
            method: Method::Search,
            holds: vec![Hold::Linear],
            families,
        },
    )
    .unwrap()
    .gains
    .apply(BankConfig::NAV440)
}
