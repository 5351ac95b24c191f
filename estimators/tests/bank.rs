//! The PaperBank and the sample adapter: unwrap, gaps, bad samples, hold modes, closed-form maps,
//! fixed point vs f32, the CSV row.

use estimators::presets::*;
use estimators::EstimatorOutput as _;
use estimators::{
    Ad, BankConfig, ClosedForm, Estimator, Fx, Hold, Ilo, IloConfig, PaperBank, PaperOutput, Real,
    SampleAdapter, SampleError, Series, Unwrapper,
};

/// A smooth hand-rotation-like yaw profile like the paper's experiment (Fig. 5):
/// `yaw = 70 sin(pi t) + 20 sin(2.2 pi t + 1) sin(0.3 pi t)` deg - within +-90 deg, rate within
/// +-300 deg/s, acceleration within +-2000 deg/s^2. Returns (yaw, rate, acceleration).
fn profile(t: f64) -> (f64, f64, f64) {
    use std::f64::consts::PI;
    let (w1, w2, w3) = (PI, 2.2 * PI, 0.3 * PI);
    let (s2, c2) = ((w2 * t + 1.0).sin(), (w2 * t + 1.0).cos());
    let (s3, c3) = ((w3 * t).sin(), (w3 * t).cos());
    let y = 70.0 * (w1 * t).sin() + 20.0 * s2 * s3;
    let v = 70.0 * w1 * (w1 * t).cos() + 20.0 * (w2 * c2 * s3 + w3 * s2 * c3);
    let a = -70.0 * w1 * w1 * (w1 * t).sin()
        + 20.0 * (-(w2 * w2 + w3 * w3) * s2 * s3 + 2.0 * w2 * w3 * c2 * c3);
    (y, v, a)
}

/// Deterministic N(0, 1) samples (xorshift64* + Box-Muller).
struct Gauss(u64);
impl Gauss {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn next(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

fn wrap180(x: f64) -> f64 {
    (x + 180.0).rem_euclid(360.0) - 180.0
}

/// The first-order leaky ILO's DC gain from a ramp's rate to `v`:
/// `v = K2/(1-K1) e`, `L e + v = r`  =>  `v / r = (K2/(1-K1)) / (L + K2/(1-K1))` (1 for K1 = 1).
fn ilo_ramp_gain(c: &IloConfig) -> f64 {
    if c.k1 >= 1.0 {
        return 1.0;
    }
    let g = f64::from(c.k2) / (1.0 - f64::from(c.k1));
    g / (f64::from(c.l) + g)
}

fn ramp_check<T: Real>(rate: f64) {
    let mut bank = PaperBank::<T>::new(&BankConfig::default()).unwrap();
    let y0 = 170.0;
    let mut out = PaperOutput::<T>::default();
    for k in 0..=1000u64 {
        let t = k as f64 * 0.01;
        let yaw = wrap180(y0 + rate * t);
        out = bank.update(k * 10_000, yaw as f32).unwrap();
        let unwrapped = y0 + rate * t;
        assert!(
            (f64::from(out.unwrapped_deg()) - unwrapped).abs() < 1e-3 * unwrapped.abs().max(1.0),
            "{} vs {unwrapped}",
            out.unwrapped_deg()
        );
    }
    let v = out.velocities().map(f64::from);
    let expect = [
        rate,
        rate,
        rate * ilo_ramp_gain(&ILO2_TABLE2),
        rate * ilo_ramp_gain(&ILO3_TABLE2),
        rate,
        rate,
        rate,
    ];
    for i in [0, 1, 2, 3, 4, 6] {
        assert!(
            (v[i] - expect[i]).abs() < 2e-3 * rate.abs(),
            "vel[{i}] = {} vs {}",
            v[i],
            expect[i]
        );
    }
    // ED: within its Euler chatter band 0.75 lambda^2 h (see tests/levant.rs)
    assert!(
        (v[5] - rate).abs() < 0.75 * 700.0f64.powi(2) * 1e-4,
        "ED {}",
        v[5]
    );
    // Acceleration of a ramp: 0 (ED-ED excluded: chatter of the first stage is its input)
    for i in [0, 1, 2, 3, 4, 6] {
        assert!(
            out.channel(estimators::Channel::ACCELERATION[i]).abs() < 1.0,
            "acc[{i}] = {}",
            out.channel(estimators::Channel::ACCELERATION[i])
        );
    }
}

/// A constant rate of 400 deg/s (11 turns in 10 s) and -250 deg/s, wrapped to +-180 deg: the
/// unwrapped yaw follows the ramp, every velocity estimator reports the rate (ILO2/3 the
/// leaky DC gain `ilo_ramp_gain` of it), every acceleration estimator 0.
#[test]
fn unwrap_across_many_turns() {
    ramp_check::<f32>(400.0);
    ramp_check::<f32>(-250.0);
    ramp_check::<Fx>(400.0);
    ramp_check::<Fx>(-250.0);
    // the unwrapper alone over 1000 turns in 7 deg steps
    let mut u = Unwrapper::<f64>::new();
    for k in 0..=(1000 * 360 / 7) {
        let x = 7.0 * k as f64 - 180.0;
        assert!((u.unwrap(wrap180(x)) - x).abs() < 1e-6);
    }
}

/// The first sample reports zeros; a gap longer than the gap rule (25 periods = 0.25 s at 100 Hz) re-initialises
/// (zeros, counter), shorter gaps are integrated across without a spike.
#[test]
fn gap_handling() {
    let mut bank = PaperBank::<f32>::new(&BankConfig::default()).unwrap();
    let rate = 100.0;
    let first = bank.update(0, 12.5).unwrap();
    assert_eq!(
        first,
        <PaperOutput>::new(12.5, 0.0, [0.0; estimators::Channel::COUNT])
    );
    bank.restart();
    let mut t_us = 0u64;
    let mut yaw = 0.0f64;
    for _ in 0..200 {
        bank.update(t_us, yaw as f32).unwrap();
        t_us += 10_000;
        yaw += rate * 0.01;
    }
    // short gap: 3 packets lost (40 ms), linear interpolation across it
    t_us += 30_000;
    yaw += rate * 0.03;
    for k in 0..50 {
        let out = bank.update(t_us, yaw as f32).unwrap();
        for (i, v) in out.velocities().iter().enumerate() {
            if i != 5 && !(2..4).contains(&i) {
                assert!(
                    (f64::from(*v) - rate).abs() < 0.05 * rate,
                    "k={k} vel[{i}]={v}"
                );
            }
        }
        t_us += 10_000;
        yaw += rate * 0.01;
    }
    assert_eq!(bank.reinit_count(), 0);
    // long gap: 0.5 s in which the yaw moved 120 deg (unknown path): re-initialised, and
    // afterwards the estimates rise from 0 to the rate with at most the overshoot of a
    // second-order loop (< 2 r); a bank that integrated across the gap (gap rule 100 periods = 1 s) reports a
    // spike from the 120 deg "ramp" instead.
    let mut integrating = PaperBank::<f32>::new(&BankConfig {
        max_gap_periods: 100.0,
        ..BankConfig::default()
    })
    .unwrap();
    let mut ti = 0u64;
    for k in 0..=250u64 {
        ti = k * 10_000;
        integrating
            .update(ti, (rate * k as f64 * 0.01) as f32)
            .unwrap();
    }
    let spike = integrating
        .update(ti + 500_000, (rate * 2.5 + 120.0) as f32)
        .unwrap();
    assert!(
        spike[estimators::Channel::VELOCITY[4]] > 2.0 * rate as f32,
        "AD integrating across the gap: {}",
        spike[estimators::Channel::VELOCITY[4]]
    );
    t_us += 490_000;
    yaw += 120.0;
    let out = bank.update(t_us, yaw as f32).unwrap();
    assert_eq!(out.velocities(), [0.0; estimators::FAMILY_COUNT]);
    assert_eq!(out.accelerations(), [0.0; estimators::FAMILY_COUNT]);
    assert_eq!(bank.reinit_count(), 1);
    for _ in 0..100 {
        t_us += 10_000;
        yaw += rate * 0.01;
        let out = bank.update(t_us, yaw as f32).unwrap();
        for (i, v) in out.velocities().iter().enumerate() {
            if i != 5 {
                assert!(v.abs() < 2.0 * rate as f32, "vel[{i}] = {v}");
            }
        }
    }
}

fn bad_samples<T: Real>() {
    let mut bank = PaperBank::<T>::new(&BankConfig::default()).unwrap();
    for k in 0..100u64 {
        bank.update(k * 10_000, profile(k as f64 * 0.01).0 as f32)
            .unwrap();
    }
    let twin = bank;
    let last_t = 99 * 10_000;
    for y in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(bank.update(last_t + 10_000, y), Err(SampleError::NotFinite));
    }
    for y in [1.0e6 + 64.0, -2.0e6, 3.4e38, -f32::MAX] {
        assert_eq!(
            bank.update(last_t + 10_000, y),
            Err(SampleError::OutOfRange)
        );
    }
    assert_eq!(
        bank.update(last_t, 1.0),
        Err(SampleError::NonIncreasingTime)
    );
    assert_eq!(
        bank.update(last_t - 5_000, 1.0),
        Err(SampleError::NonIncreasingTime)
    );
    let mut twin = twin;
    for k in 100..200u64 {
        let y = profile(k as f64 * 0.01).0 as f32;
        let a = bank.update(k * 10_000, y).unwrap();
        let b = twin.update(k * 10_000, y).unwrap();
        assert_eq!(
            format!("{a:?}"),
            format!("{b:?}"),
            "bad samples changed the state"
        );
    }
}

/// NaN / infinite samples and non-increasing timestamps are refused and leave the state
/// bit-for-bit unchanged (the bank continues exactly like a twin that never saw them).
#[test]
fn bad_samples_leave_state_unchanged() {
    bad_samples::<f32>();
    bad_samples::<Fx>();
    // the single-estimator adapter too
    let ad = Ad::<f32>::new(0.01, 1e-4).unwrap();
    let mut a = SampleAdapter::new(ad, 1e-4, 0.25, Hold::Linear).unwrap();
    assert_eq!(a.update(0, 1.0), Ok(0.0));
    assert_eq!(a.update(10_000, f32::NAN), Err(SampleError::NotFinite));
    assert_eq!(a.update(0, 2.0), Err(SampleError::NonIncreasingTime));
    assert!(a.update(10_000, 2.0).unwrap() > 0.0);
}

/// Zero-order hold vs linear interpolation on a 100 deg/s ramp at 100 Hz. Linear: the AD
/// reports the rate exactly. ZOH: the input is a staircase; in the periodic steady state the
/// AD's error `d = y_k - z` jumps by `r dt` at each sample and decays by `a = 1 - h/T` per
/// step, so the reported `u = d_n / T = r dt a^(n-1) / (T (1 - a^n))` = 0.583 r for
/// `T = dt = 0.01`, `n = 100` - a 42 % low bias. Every fast estimator is biased low (printed).
#[test]
fn zoh_bias_vs_linear() {
    let rate = 100.0;
    let run = |hold: Hold| {
        let cfg = BankConfig {
            hold,
            ..BankConfig::default()
        };
        let mut bank = PaperBank::<f64>::new(&cfg).unwrap();
        let mut out = PaperOutput::<f64>::default();
        for k in 0..=300u64 {
            out = bank
                .update(k * 10_000, (rate * k as f64 * 0.01) as f32)
                .unwrap();
        }
        out.velocities().map(|v| f64::from(v) / rate)
    };
    let lin = run(Hold::Linear);
    let zoh = run(Hold::ZeroOrder);
    println!("v / r, linear: {lin:.4?}\nv / r, ZOH:    {zoh:.4?}");
    let a: f64 = 1.0 - 1e-4 / 0.01;
    let zoh_ad = a.powi(99) / (1.0 - a.powi(100));
    assert!((lin[4] - 1.0).abs() < 1e-4);
    assert!((zoh[4] - zoh_ad).abs() < 1e-3, "{} vs {zoh_ad}", zoh[4]);
    // AVE and AD clearly low (ILO2/3 too; ILO1 barely: it is slow; ED: chatter aliasing; KF
    // runs per sample and does not see the hold)
    for i in [0, 2, 3, 4] {
        assert!(
            zoh[i] < lin[i] - 0.1,
            "estimator {i} not biased low under ZOH"
        );
    }
}

/// Max |closed form - stepping| / max |output| over a noisy paper-like run, for one law.
fn closed_vs_steps<T: Real, E: estimators::LinearLaw<Num = T>>(
    law: estimators::Stateful<E>,
    hold: Hold,
) -> f64 {
    let mut stepped = law;
    let mut closed = ClosedForm::of(&law, 100, hold);
    let mut g = Gauss(7);
    let y_at = |k: u64, g: &mut Gauss| T::from_f64(profile(k as f64 * 0.01).0 + 0.1 * g.next());
    let mut y_prev = y_at(0, &mut g);
    stepped.reset(y_prev);
    closed.reset(y_prev);
    let (mut max_diff, mut max_out): (f64, f64) = (0.0, 0.0);
    for k in 1..600u64 {
        let y = y_at(k, &mut g);
        // mostly 100 steps per sample, sometimes jitter (falls back to stepping)
        let n = match k % 50 {
            17 => 99,
            33 => 101,
            _ => 100,
        };
        let a = stepped.advance(y_prev, y, n, hold).to_f64();
        let b = closed.advance(y_prev, y, n, hold).to_f64();
        max_diff = max_diff.max((a - b).abs());
        max_out = max_out.max(a.abs());
        y_prev = y;
    }
    max_diff / max_out
}

/// The closed-form n-step maps equal n Euler steps to rounding: relative difference below
/// 1e-9 in f64, 1e-3 in f32 (the map sums 100 steps at once; the f32 stepping itself carries
/// a rounding error of that order on 100 deg angles), 1e-6 in Q31.32.
#[test]
fn closed_form_equals_stepping() {
    let h = H_PAPER;
    fn check<T: Real>(h: f32, tol: f64) {
        for hold in [Hold::Linear, Hold::ZeroOrder] {
            for c in [ILO1_TABLE2, ILO2_TABLE2, ILO3_TABLE2] {
                let d = closed_vs_steps::<T, _>(Ilo::<T, 1>::new(&c, h).unwrap(), hold);
                assert!(d < tol, "ILO {c:?} {hold:?}: {d:e}");
            }
            for c in [ILO1_TABLE4, ILO2_TABLE4, ILO3_TABLE4] {
                let s = Series::of(
                    &Ilo::<T, 1>::new(&c, h).unwrap(),
                    &Ilo::<T, 1>::new(&c, h).unwrap(),
                );
                let d = closed_vs_steps::<T, _>(s, hold);
                assert!(d < tol, "ILO-ILO {c:?} {hold:?}: {d:e}");
            }
            let d = closed_vs_steps::<T, _>(Ad::<T>::new(AD_VELOCITY_T, h).unwrap(), hold);
            assert!(d < tol, "AD {hold:?}: {d:e}");
            let s = Series::of(
                &Ad::<T>::new(AD_ACCELERATION_T, h).unwrap(),
                &Ad::<T>::new(AD_ACCELERATION_T, h).unwrap(),
            );
            let d = closed_vs_steps::<T, _>(s, hold);
            assert!(d < tol, "AD-AD {hold:?}: {d:e}");
            // the ILO with a longer delay line (D = 3, state dimension 4)
            let d = closed_vs_steps::<T, _>(Ilo::<T, 3>::new(&ILO2_TABLE2, h).unwrap(), hold);
            assert!(d < tol, "ILO D=3 {hold:?}: {d:e}");
        }
    }
    check::<f64>(h, 1e-9);
    check::<f32>(h, 1e-3);
    check::<Fx>(h, 1e-6);
    for (name, d) in [
        (
            "f64",
            closed_vs_steps::<f64, _>(Ilo::<f64, 1>::new(&ILO3_TABLE2, h).unwrap(), Hold::Linear),
        ),
        (
            "f32",
            closed_vs_steps::<f32, _>(Ilo::<f32, 1>::new(&ILO3_TABLE2, h).unwrap(), Hold::Linear),
        ),
        (
            "Fx",
            closed_vs_steps::<Fx, _>(Ilo::<Fx, 1>::new(&ILO3_TABLE2, h).unwrap(), Hold::Linear),
        ),
    ] {
        println!("ILO3 closed form vs 100 Euler steps, {name}: max rel diff {d:.2e}");
    }
}

/// Runs a bank on the paper-like experiment (noise seed 42); returns the outputs per sample.
fn experiment<T: Real>(cfg: &BankConfig, noise_var: f64, seconds: f64) -> Vec<PaperOutput> {
    experiment_seed::<T>(cfg, noise_var, seconds, 42)
}

/// [`experiment`] with the noise generator seeded with `seed`.
fn experiment_seed<T: Real>(
    cfg: &BankConfig,
    noise_var: f64,
    seconds: f64,
    seed: u64,
) -> Vec<PaperOutput> {
    let mut bank = PaperBank::<T>::new(cfg).unwrap();
    let mut g = Gauss(seed);
    let n = (seconds * 100.0) as u64;
    (0..=n)
        .map(|k| {
            let y = profile(k as f64 * 0.01).0 + noise_var.sqrt() * g.next();
            bank.update(k * 10_000, wrap180(y) as f32).unwrap().to_f32()
        })
        .collect()
}

fn mse(outs: &[PaperOutput], acc: bool, i: usize, from_s: f64) -> f64 {
    let (mut s, mut c) = (0.0, 0.0);
    for (k, o) in outs.iter().enumerate() {
        let t = k as f64 * 0.01;
        if t >= from_s {
            let (_, v, a) = profile(t);
            let (est, truth) = if acc {
                (o[estimators::Channel::ACCELERATION[i]], a)
            } else {
                (o[estimators::Channel::VELOCITY[i]], v)
            };
            s += (f64::from(est) - truth).powi(2);
            c += 1.0;
        }
    }
    s / c
}

/// The noise seeds of the fixed-point accuracy check (10 independent noise records).
const ACCURACY_SEEDS: [u64; 10] = [42, 1, 2, 3, 4, 5, 6, 7, 8, 9];

/// Fixed point against f32 (and f64) on the paper-like experiment: yaw within +-90 deg, rate
/// within +-300 deg/s, acceleration within +-2000 deg/s^2, 100 Hz samples, noise sigma^2 =
/// 0.01 deg^2, 10 s, over the 10 noise seeds of [`ACCURACY_SEEDS`] (seed-robust, not
/// seed-lucky). The MSE is against the true rate / acceleration of `profile` (an
/// independent computation), pooled over the 10 runs (a single run's ED / ED-ED MSE depends
/// on its chatter, which a tiny difference changes: the per-seed ratios are printed, not
/// asserted).
///
/// Tolerance, for every estimator, velocity and acceleration: the fixed-point MSE is within
/// 2 % of the f64 bank's (the precise reference of the same laws) and at most 2 % above the
/// f32 bank's; where f32 itself is within 2 % of f64 (every channel but ED-ED), the fixed-point
/// MSE is also within 2 % of f32's both ways. ED-ED in f32 is about 10 % worse than f64 and
/// fixed point: its second stage chatters around a ~300 deg/s input, where f32's resolution
/// (3e-5) is a sizeable part of the `|e| ~ (lambda h)^2 = 5e-3` switching band. The linear
/// laws' and the Kalman tracker's outputs agree with f32 sample by sample within 0.05 deg/s
/// and 1 deg/s^2 on every seed.
///
/// The AVE row: the fixed-point AVE / AVE-AVE run Euler steps of `2 h`
/// (`Real::AVE_STEP_FACTOR`, docs/FIXED-POINT.md, "The AVE row at `2 h`"), the f32 and f64 banks steps of `h`, so
/// sample by sample they differ by the discretisation, not only by the arithmetic. Checked
/// apart, every sample of every seed: (a) the arithmetic: Fx against the f64 bank run at
/// `h = 2e-4` (its AVE row is the same recursion at `2 h`, 50 steps per sample at the same
/// input positions; an independent computation in f64): within 1e-3 deg/s and 1e-2 deg/s^2
/// (measured 1.8e-4 and 2.9e-3, a few f32 ulps of the outputs); f32 against f64 at `h`
/// within the linear laws' 0.05 deg/s and 1 deg/s^2 (measured 0.016 and 0.58); (b) the
/// discretisation, f64 at `2 h` against f64 at `h`: first order (its maximum is 1.8 .. 2.2
/// times that of f64 at `h` against f64 at `h / 2`; measured 2.005 and 2.009, as for Euler's
/// global error) and below 1.0 deg/s and 65 deg/s^2 (measured 0.909 and 59.8, at the first
/// sample, the start-up transient; 0.38 and 17.8 from t = 1 s on, the MSE window). The
/// measured `|Fx - f32|` (printed: 0.909 deg/s and 59.8 deg/s^2 at t = 0.01 s) must then be
/// at most the sum of (a)'s bound, (b)'s and f32's measured maxima (triangle inequality).
/// The pooled MSE bounds above are the accuracy criterion and are the same for the AVE as for
/// every estimator.
#[test]
#[allow(clippy::needless_range_loop)] // `i` indexes the channels and three MSE tables
fn fixed_point_matches_f32_on_paper_experiment() {
    let cfg = BankConfig::default();
    let mut sum = [[[0.0f64; estimators::FAMILY_COUNT]; 2]; 3]; // [f32, Fx, f64][vel, acc][estimator]
    let (mut dv, mut da) = (0.0f32, 0.0f32);
    // The AVE row: [vel, acc] maxima over all samples and seeds of |Fx - f64 at 2h| (the
    // arithmetic), |f64 at 2h - f64 at h| (the discretisation), |f32 - f64| at h (f32's
    // arithmetic) and |Fx - f32| (what the old check bounded); `(value, seed, t)` of the last.
    let (mut ave_arith, mut ave_disc, mut ave_f32) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
    let mut ave_fx_f32 = [(0.0f64, 0u64, 0.0f64); 2];
    // The same two from t = 1 s on (the MSE window, after the start-up transient).
    let (mut ave_disc_1s, mut ave_fx_f32_1s) = ([0.0f64; 2], [0.0f64; 2]);
    // |f64 at h - f64 at h/2|: the next halving, for the first-order check.
    let mut ave_disc_half = [0.0f64; 2];
    // The 2 h discretisation of the fixed-point AVE (`Real::AVE_STEP_FACTOR`), run in f64: the
    // f64 bank at step 2 h (its AVE row is the same Euler recursion at 2 h, 50 steps per
    // sample at the 2 h grid's input positions; the other rows are not used).
    let cfg2 = BankConfig {
        h: cfg.h * Fx::AVE_STEP_FACTOR as f32,
        ..cfg
    };
    let cfg_half = BankConfig {
        h: cfg.h / 2.0,
        ..cfg
    };
    for seed in ACCURACY_SEEDS {
        let f = experiment_seed::<f32>(&cfg, 0.01, 10.0, seed);
        let x = experiment_seed::<Fx>(&cfg, 0.01, 10.0, seed);
        let d = experiment_seed::<f64>(&cfg, 0.01, 10.0, seed);
        let d2 = experiment_seed::<f64>(&cfg2, 0.01, 10.0, seed);
        let dh = experiment_seed::<f64>(&cfg_half, 0.01, 10.0, seed);
        for (k, ((((a, b), c), c2), ch2)) in f.iter().zip(&x).zip(&d).zip(&d2).zip(&dh).enumerate()
        {
            for (j, ch) in [estimators::Channel::AveV, estimators::Channel::AveA]
                .into_iter()
                .enumerate()
            {
                let (fa, xa, da, d2a) = (
                    f64::from(a[ch]),
                    f64::from(b[ch]),
                    f64::from(c[ch]),
                    f64::from(c2[ch]),
                );
                ave_arith[j] = ave_arith[j].max((xa - d2a).abs());
                ave_disc[j] = ave_disc[j].max((d2a - da).abs());
                ave_disc_half[j] = ave_disc_half[j].max((da - f64::from(ch2[ch])).abs());
                ave_f32[j] = ave_f32[j].max((fa - da).abs());
                if k >= 100 {
                    ave_disc_1s[j] = ave_disc_1s[j].max((d2a - da).abs());
                    ave_fx_f32_1s[j] = ave_fx_f32_1s[j].max((xa - fa).abs());
                }
                if (xa - fa).abs() > ave_fx_f32[j].0 {
                    ave_fx_f32[j] = ((xa - fa).abs(), seed, k as f64 * 0.01);
                }
            }
        }
        let mut line = format!("seed {seed:2}: Fx/f32 MSE");
        for (h, acc) in [false, true].into_iter().enumerate() {
            for i in 0..7 {
                let m = [
                    mse(&f, acc, i, 1.0),
                    mse(&x, acc, i, 1.0),
                    mse(&d, acc, i, 1.0),
                ];
                for (k, v) in m.iter().enumerate() {
                    sum[k][h][i] += v;
                }
                line += &format!(" {:.3}", m[1] / m[0]);
            }
        }
        println!("{line}");
        for (a, b) in f.iter().zip(&x) {
            for i in [1, 2, 3, 4, 6] {
                let (cv, ca) = (
                    estimators::Channel::VELOCITY[i],
                    estimators::Channel::ACCELERATION[i],
                );
                dv = dv.max((a[cv] - b[cv]).abs());
                da = da.max((a[ca] - b[ca]).abs());
            }
        }
    }
    for (h, acc) in [false, true].into_iter().enumerate() {
        for i in 0..7 {
            let [mf, mx, md] = [
                sum[0][h][i] / 10.0,
                sum[1][h][i] / 10.0,
                sum[2][h][i] / 10.0,
            ];
            let name = estimators::VELOCITY_NAMES[i];
            let what = if acc { "acc" } else { "vel" };
            println!(
                "{what} {name}: MSE over 10 seeds f32 {mf:.3}, fixed point {mx:.3}, f64 {md:.3} (fixed/f32 {:.4}, fixed/f64 {:.4})",
                mx / mf,
                mx / md
            );
            assert!(
                (mx / md - 1.0).abs() < 0.02,
                "{what} {name}: fixed {mx} vs f64 {md}"
            );
            assert!(mx / mf < 1.02, "{what} {name}: fixed {mx} vs f32 {mf}");
            if (mf / md - 1.0).abs() < 0.02 {
                assert!(
                    (mx / mf - 1.0).abs() < 0.02,
                    "{what} {name}: fixed {mx} vs f32 {mf}"
                );
            }
        }
    }
    println!("max |f32 - fixed|: linear + Kalman vel {dv} deg/s, acc {da} deg/s^2");
    println!(
        "AVE (vel deg/s, acc deg/s^2), max over samples and seeds: |Fx - f64 at 2h| {:.3e} {:.3e}; |f64 at 2h - f64 at h| {:.4} {:.4}; |f32 - f64| at h {:.4} {:.4}; |Fx - f32| {:.4} (seed {}, t {:.2} s) {:.4} (seed {}, t {:.2} s)",
        ave_arith[0], ave_arith[1], ave_disc[0], ave_disc[1], ave_f32[0], ave_f32[1],
        ave_fx_f32[0].0, ave_fx_f32[0].1, ave_fx_f32[0].2,
        ave_fx_f32[1].0, ave_fx_f32[1].1, ave_fx_f32[1].2
    );
    println!(
        "AVE: |f64 at h - f64 at h/2| {:.4} {:.4} (ratio of the 2h-h to the h-h/2 difference {:.3} {:.3})",
        ave_disc_half[0],
        ave_disc_half[1],
        ave_disc[0] / ave_disc_half[0],
        ave_disc[1] / ave_disc_half[1]
    );
    println!(
        "AVE from t = 1 s: |f64 at 2h - f64 at h| {:.4} {:.4}; |Fx - f32| {:.4} {:.4}",
        ave_disc_1s[0], ave_disc_1s[1], ave_fx_f32_1s[0], ave_fx_f32_1s[1]
    );
    assert!(dv < 0.05 && da < 1.0, "{dv} {da}");
    // The AVE row. (a) The arithmetic: Fx against the independent f64 run of the same 2 h
    // recursion, sample by sample.
    assert!(
        ave_arith[0] < 1e-3 && ave_arith[1] < 1e-2,
        "AVE |Fx - f64 at 2h|: {ave_arith:?}"
    );
    // f32's own arithmetic at h (the same bounds as the linear laws' above).
    assert!(
        ave_f32[0] < 0.05 && ave_f32[1] < 1.0,
        "AVE |f32 - f64| at h: {ave_f32:?}"
    );
    // (b) The discretisation: first order (halving h halves the difference, as for Euler's
    // global error), and bounded as measured (0.909 deg/s, 59.8 deg/s^2, at the first sample).
    for j in 0..2 {
        let r = ave_disc[j] / ave_disc_half[j];
        assert!((1.8..2.2).contains(&r), "AVE 2h-h / h-h/2 ratio {r}");
    }
    assert!(
        ave_disc[0] < 1.0 && ave_disc[1] < 65.0,
        "AVE |f64 at 2h - f64 at h|: {ave_disc:?}"
    );
    // |Fx - f32| is then what (a), (b) and f32's arithmetic explain (triangle inequality).
    for j in 0..2 {
        let explained = ave_disc[j] + [1e-3, 1e-2][j] + ave_f32[j];
        assert!(
            ave_fx_f32[j].0 <= explained,
            "AVE |Fx - f32| {:?} > {explained}",
            ave_fx_f32[j]
        );
    }
}

/// The bank with and without closed-form maps gives the same rows (to f32 rounding) for the
/// linear laws, and identical rows for the others.
#[test]
fn bank_closed_form_matches_stepping() {
    let a = experiment::<f32>(&BankConfig::default(), 0.01, 3.0);
    let b = experiment::<f32>(
        &BankConfig {
            closed_form: false,
            ..BankConfig::default()
        },
        0.01,
        3.0,
    );
    for (x, y) in a.iter().zip(&b) {
        for i in [0, 5, 6] {
            assert_eq!(
                x[estimators::Channel::VELOCITY[i]],
                y[estimators::Channel::VELOCITY[i]]
            );
            assert_eq!(
                x[estimators::Channel::ACCELERATION[i]],
                y[estimators::Channel::ACCELERATION[i]]
            );
        }
        for i in 1..5 {
            assert!(
                (x[estimators::Channel::VELOCITY[i]] - y[estimators::Channel::VELOCITY[i]]).abs()
                    < 0.05,
                "{} {}",
                x[estimators::Channel::VELOCITY[i]],
                y[estimators::Channel::VELOCITY[i]]
            );
            assert!(
                (x[estimators::Channel::ACCELERATION[i]] - y[estimators::Channel::ACCELERATION[i]])
                    .abs()
                    < 1.0,
                "{} {}",
                x[estimators::Channel::ACCELERATION[i]],
                y[estimators::Channel::ACCELERATION[i]]
            );
        }
    }
}

/// Invalid configurations are refused with a typed error, never accepted and never a panic.
#[test]
fn invalid_bank_config_is_refused() {
    use estimators::ConfigError;
    let d = BankConfig::default();
    let err = |c: BankConfig| PaperBank::<f32>::new(&c).err();
    assert_eq!(
        err(BankConfig { h: 1.25e-5, ..d }),
        Some(ConfigError::StepNotWholeMicroseconds)
    );
    assert_eq!(
        err(BankConfig { h: f32::NAN, ..d }),
        Some(ConfigError::NotFinite("h"))
    );
    assert_eq!(
        err(BankConfig { h: 0.0, ..d }),
        Some(ConfigError::StepNotWholeMicroseconds)
    );
    assert_eq!(
        err(BankConfig {
            max_gap_periods: 0.0,
            ..d
        }),
        Some(ConfigError::GapTooShort)
    );
    assert_eq!(
        err(BankConfig {
            sample_period_s: 0.0,
            ..d
        }),
        Some(ConfigError::SamplePeriodTooShort)
    );
    // 200 s at h = 1e-4 s is 2e6 steps: too long, and said so.
    assert_eq!(
        err(BankConfig {
            sample_period_s: 200.0,
            ..d
        }),
        Some(ConfigError::SamplePeriodTooLong)
    );
    let mut v = d.velocity;
    v.ilo[1].k1 = 1.2;
    assert_eq!(
        err(BankConfig { velocity: v, ..d }),
        Some(ConfigError::K1OutOfRange)
    );
    let mut a = d.acceleration;
    a.ad_t = 1e-5;
    assert_eq!(
        err(BankConfig {
            acceleration: a,
            ..d
        }),
        Some(ConfigError::StepTooLarge("1/T"))
    );
    assert!(PaperBank::<Fx>::new(&BankConfig { h: 1e-5, ..d }).is_ok());
}

/// The ED/ED-ED with the implicit scheme in the bank, on the paper-like experiment
/// (sigma^2 = 0.01 deg^2): lower velocity and acceleration MSE than the paper's explicit Euler
/// (no chatter). Q31.32 agrees with f32 within 1 % in the ED's MSE and 15 % in ED-ED's: the
/// second stage's sliding band `|p| <= h^2 alpha = 7.7e-6` (deg/s) is below the f32 resolution
/// of its input (ulp(300 deg/s) = 3e-5), so f32 cannot resolve it while Q31.32 (2.3e-10) can -
/// Q31.32 is the more accurate of the two there.
#[test]
fn implicit_ed_in_bank() {
    use estimators::EdScheme;
    let euler = experiment::<f32>(&BankConfig::default(), 0.01, 10.0);
    let cfg = BankConfig {
        ed_scheme: EdScheme::Implicit,
        ..BankConfig::default()
    };
    let imp = experiment::<f32>(&cfg, 0.01, 10.0);
    let imp_fx = experiment::<Fx>(&cfg, 0.01, 10.0);
    let (ve, vi, vx) = (
        mse(&euler, false, 5, 1.0),
        mse(&imp, false, 5, 1.0),
        mse(&imp_fx, false, 5, 1.0),
    );
    let (ae, ai, ax) = (
        mse(&euler, true, 5, 1.0),
        mse(&imp, true, 5, 1.0),
        mse(&imp_fx, true, 5, 1.0),
    );
    println!("ED vel MSE: Euler {ve:.2}, implicit {vi:.2} (Q31.32 {vx:.2}); ED-ED acc MSE: Euler {ae:.0}, implicit {ai:.0} (Q31.32 {ax:.0})");
    assert!(vi < ve && ai < ae, "{vi} vs {ve}, {ai} vs {ae}");
    assert!((vi / vx - 1.0).abs() < 0.01, "{vi} {vx}");
    assert!((ai / ax - 1.0).abs() < 0.15, "{ai} {ax}");
}

/// `update_scaled` (an integer angle times a power of two, converted to the number type
/// directly) gives the outputs of `update` with the same angle as `f32`, bit for bit: the paper
/// and product banks, `f32` and `Fx`, on 4,000 samples of NAV440 angle fields (`45 raw *
/// 2^-13` deg) spinning through many turns with a gap; and the same errors for angles beyond
/// `MAX_ABS_DEG` (`raw` 2^24 at 2^-4 deg: 1,048,576 deg).
#[test]
fn update_scaled_equals_update_of_the_f32() {
    fn run<B: estimators::EstimatorBank>(mut a: B, mut b: B) {
        let mut t = 0u64;
        for k in 0..4000i32 {
            t += if k == 2000 { 500_000 } else { 10_000 };
            // 900 deg/s with a wobble, wrapped to the field's +-180 deg (i16 wraps at 2^15).
            let deg = 900.0 * f64::from(k) * 0.01 + 40.0 * (f64::from(k) * 0.05).sin();
            let raw = (deg * 65536.0 / 360.0).round() as i64 as i16;
            let scaled = i32::from(raw) * 45;
            let f = scaled as f32 / 8192.0;
            assert_eq!(
                a.update(t, f),
                b.update_scaled(t, scaled, -13),
                "sample {k}"
            );
        }
        assert_eq!(
            a.update(t + 10_000, 1_048_576.0),
            b.update_scaled(t + 10_000, 1 << 24, -4)
        );
        assert_eq!(a.reinit_count(), b.reinit_count());
    }
    let cfg = BankConfig::default();
    run(
        PaperBank::<f32>::new(&cfg).unwrap(),
        PaperBank::<f32>::new(&cfg).unwrap(),
    );
    run(
        PaperBank::<Fx>::new(&cfg).unwrap(),
        PaperBank::<Fx>::new(&cfg).unwrap(),
    );
    run(
        estimators::ProductBank::<Fx>::new(&cfg).unwrap(),
        estimators::ProductBank::<Fx>::new(&cfg).unwrap(),
    );
    run(
        estimators::ProductBank::<f32>::new(&cfg).unwrap(),
        estimators::ProductBank::<f32>::new(&cfg).unwrap(),
    );
}
