//! The AVE's `deltahat` options and parameter validation.

use estimators::presets::AVE_PAPER;
use estimators::{Ave, AveConfig, ConfigError, DeltaMode, Estimator};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Runs the AVE on a noisy sine for 3 s at h = 1e-4 and returns the `deltahat` trace maximum,
/// its final value and the max |e| seen.
fn run(delta: DeltaMode) -> (f64, f64, f64) {
    let mut a = Ave::<f64>::new(&AveConfig { delta, ..AVE_PAPER }, 1e-4).unwrap();
    a.reset(0.0);
    let (mut dmax, mut emax, mut prev) = (0.0f64, 0.0f64, 0.0f64);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    for i in 0..30_000 {
        let n: f64 = rng.random_range(-0.1..0.1);
        let y = 20.0 * (i as f64 * 1e-4 * 6.0).sin() + n;
        emax = emax.max((a.xhat() - y).abs());
        a.step(y);
        let d = a.deltahat();
        if matches!(delta, DeltaMode::Paper) {
            assert!(d >= prev, "paper law: deltahat never decreases");
        }
        prev = d;
        dmax = dmax.max(d);
    }
    (dmax, prev, emax)
}

/// Paper law: `deltahat` = integral of |e| only grows. Bounded: never above `max`. Leaky:
/// `d deltahat/dt = |e| - sigma deltahat` keeps it below `max|e| / sigma`.
#[test]
fn deltahat_modes() {
    let (_, paper_end, _) = run(DeltaMode::Paper);
    let (bmax, _, _) = run(DeltaMode::Bounded { max: 0.01 });
    let (lmax, _, emax) = run(DeltaMode::Leaky { sigma: 50.0 });
    println!("deltahat after 3 s: paper {paper_end:.4}; bounded max {bmax:.4}; leaky max {lmax:.4} (bound {:.4})", emax / 50.0);
    assert!(paper_end > 0.01);
    assert!(bmax <= 0.01 + 1e-15);
    assert!(lmax <= emax / 50.0);
    assert!(lmax < paper_end);
}

#[test]
fn invalid_parameters_are_refused() {
    let bad = |k: f32, g: f32, d: DeltaMode, h: f32| {
        Ave::<f32>::new(
            &AveConfig {
                k,
                gamma1: g,
                delta: d,
            },
            h,
        )
        .err()
    };
    assert_eq!(
        bad(-1.0, 1.0, DeltaMode::Paper, 1e-4),
        Some(ConfigError::NotPositive("k"))
    );
    assert_eq!(
        bad(500.0, f32::NAN, DeltaMode::Paper, 1e-4),
        Some(ConfigError::NotFinite("gamma1"))
    );
    assert_eq!(
        bad(500.0, 2e4, DeltaMode::Paper, 0.01),
        Some(ConfigError::StepTooLarge("k"))
    );
    assert_eq!(
        bad(500.0, 2e4, DeltaMode::Leaky { sigma: 2e4 }, 1e-4),
        Some(ConfigError::StepTooLarge("sigma"))
    );
    assert_eq!(
        bad(500.0, 2e4, DeltaMode::Bounded { max: -1.0 }, 1e-4),
        Some(ConfigError::Negative("max"))
    );
    assert!(bad(500.0, 2e4, DeltaMode::Paper, 1e-4).is_none());
}
