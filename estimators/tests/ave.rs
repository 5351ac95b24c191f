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

/// Spectral radius of the explicit Euler map of the AVE's linear part (`deltahat = 0`,
/// `e = xhat - y`, `y = 0`): `[[1 - h k, h], [-h gamma1, 1]]`, from the 2 x 2 characteristic
/// polynomial `z^2 - (2 - h k) z + (1 - h k + h^2 gamma1)` in f64 (independent of the crate).
fn euler_radius(k: f64, gamma1: f64, h: f64) -> f64 {
    let tr = 2.0 - h * k;
    let det = 1.0 - h * k + h * h * gamma1;
    let disc = tr * tr - 4.0 * det;
    if disc < 0.0 {
        det.sqrt()
    } else {
        ((tr.abs() + disc.sqrt()) / 2.0).max((tr.abs() - disc.sqrt()).abs() / 2.0)
    }
}

/// The constructor accepts a gain set exactly when the Euler step is stable: `h gamma1 < k`
/// (with `h k < 1`), checked against the spectral radius computed independently above over a
/// grid of `h gamma1 / k` from 0.5 to 1.5 and several `k`. Before this check the constructor
/// tested `h^2 gamma1 < 1`, which accepted gamma1 up to 1e8 1/s^2 at h = 1e-4 s whatever `k`:
/// the fixed-point AVE's coarse step `2 h` ran gains tuned at `h gamma1 / k` = 0.9 (a tuned
/// schedule's level) and diverged to the Q31.32 limit. An accepted set just inside the bound
/// stays bounded on a noisy ramp for 10 s; the same run at 1.02x the bound (stepped without
/// the crate, in f64) grows without bound.
#[test]
fn gains_are_accepted_exactly_when_the_euler_step_is_stable() {
    // The step as the crate takes it (an f32: 1e-4 s rounds to 9.99999975e-5 s).
    let h = f64::from(1e-4f32);
    for k in [5.0f64, 47.39, 500.0, 5000.0] {
        for i in 0..=20 {
            let r = 0.5 + 0.05 * f64::from(i);
            let gamma1 = r * k / h;
            let cfg = AveConfig {
                k: k as f32,
                gamma1: gamma1 as f32,
                delta: DeltaMode::Paper,
            };
            let stable = euler_radius(f64::from(cfg.k), f64::from(cfg.gamma1), h) < 1.0;
            let accepted = Ave::<f64>::new(&cfg, h as f32).is_ok();
            assert_eq!(accepted, stable, "k {k}, h gamma1 / k {r}");
            if !accepted {
                assert_eq!(
                    Ave::<f32>::new(&cfg, h as f32).err(),
                    Some(ConfigError::StepTooLarge("gamma1 / k"))
                );
            }
        }
    }
    // Just inside (0.98, as the tuned 0.001 deg^2 level of the bundled schedule): bounded.
    let (k, r) = (47.39f64, 0.98);
    let mut a = Ave::<f64>::new(
        &AveConfig {
            k: k as f32,
            gamma1: (r * k / h) as f32,
            delta: DeltaMode::Leaky { sigma: 0.1 },
        },
        h as f32,
    )
    .unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    a.reset(0.0);
    let mut worst = 0.0f64;
    for i in 0..100_000 {
        let y = 50.0 * i as f64 * h + rng.random_range(-0.1..0.1);
        a.step(y);
        worst = worst.max((a.output() - 50.0).abs());
    }
    assert!(worst.is_finite() && worst < 1e4, "{worst}");
    // The linear Euler map itself, from a 1 deg error, over 30 s: at 0.98 of the bound it
    // decays (by exp(-0.02 k t / 2), about 1e-6), at 1.02 it grows by as much (|z|^2 =
    // 1 + 0.02 h k per step).
    let map = |ratio: f64| {
        let (g, mut x, mut th) = (ratio * k / h, 1.0f64, 0.0f64);
        for _ in 0..300_000 {
            let e = x;
            x += h * (-k * e + th);
            th -= h * g * e;
        }
        x.abs().max(th.abs() / k)
    };
    let (inside, outside) = (map(0.98), map(1.02));
    assert!(inside < 1e-3 && outside > 1e3, "{inside} {outside}");
}
