//! Frequency responses of the linear(ised) laws against their transfer functions.

use estimators::{Ad, Ave, AveConfig, DeltaMode, Estimator};

/// Steps `e` (fresh, reset to 0) at `h` on `y = sin(w t)`, lets it settle for `settle` s and
/// returns the (gain, phase) of the output at `w` from a correlation over whole periods.
fn response<E: Estimator<f64>>(mut e: E, h: f64, w: f64, settle: f64) -> (f64, f64) {
    e.reset(0.0);
    let period = 2.0 * std::f64::consts::PI / w;
    let periods = (0.5 / period).ceil().max(2.0);
    let n_settle = (settle / h).round() as usize;
    let n_meas = (periods * period / h).round() as usize;
    let (mut a, mut b) = (0.0, 0.0);
    for i in 0..n_settle + n_meas {
        let t = i as f64 * h;
        let out = e.step((w * t).sin());
        if i >= n_settle {
            a += out * (w * t).sin();
            b += out * (w * t).cos();
        }
    }
    let (a, b) = (2.0 * a / n_meas as f64, 2.0 * b / n_meas as f64);
    (a.hypot(b), b.atan2(a))
}

/// `G(jw) = jw / (jwT + 1)`: gain `w / sqrt(1 + (wT)^2)`, phase `pi/2 - atan(wT)`.
#[test]
fn ad_matches_s_over_ts_plus_1() {
    let (t, h) = (0.01, 1e-4);
    for w in [1.0, 10.0, 100.0, 300.0, 1000.0] {
        let (g, p) = response(Ad::<f64>::new(t as f32, h as f32).unwrap(), h, w, 0.1);
        let g_ref = w / (1.0 + (w * t).powi(2)).sqrt();
        let p_ref = std::f64::consts::FRAC_PI_2 - (w * t).atan();
        println!("AD w={w}: gain {g:.5} (tf {g_ref:.5}), phase {p:.5} (tf {p_ref:.5})");
        // Euler at h = T/100: relative gain error ~ h/(2T) = 0.5 %, phase error ~ w h / 2.
        assert!((g / g_ref - 1.0).abs() < 0.01, "w={w}: {g} vs {g_ref}");
        assert!((p - p_ref).abs() < 0.01 + w * h, "w={w}: {p} vs {p_ref}");
    }
}

/// Linearised AVE (`deltahat = 0`, i.e. `DeltaMode::Bounded { max: 0 }`): noise `n` on `y`
/// reaches the velocity estimate through `gamma1 s / (s^2 + k s + gamma1)` (a band-pass, peak
/// gain `gamma1 / k = 40` at `sqrt(gamma1) = 141 rad/s`).
#[test]
fn linearised_ave_noise_to_error_matches_band_pass() {
    let (k, g1, h) = (500.0, 20000.0, 1e-4);
    let cfg = AveConfig {
        k: k as f32,
        gamma1: g1 as f32,
        delta: DeltaMode::Bounded { max: 0.0 },
    };
    for w in [5.0, 30.0, 141.42, 500.0, 2000.0] {
        let (g, p) = response(Ave::<f64>::new(&cfg, h as f32).unwrap(), h, w, 0.3);
        // gamma1 jw / (gamma1 - w^2 + j k w)
        let (re, im) = (g1 - w * w, k * w);
        let g_ref = g1 * w / re.hypot(im);
        let p_ref = std::f64::consts::FRAC_PI_2 - im.atan2(re);
        println!("AVE w={w}: gain {g:.4} (tf {g_ref:.4}), phase {p:.4} (tf {p_ref:.4})");
        assert!((g / g_ref - 1.0).abs() < 0.03, "w={w}: {g} vs {g_ref}");
        assert!((p - p_ref).abs() < 0.01 + w * h, "w={w}: {p} vs {p_ref}");
    }
}
