//! Every law of the paper and product banks (and of the noise-adaptive bank), in `f32` and in
//! fixed point ([`Fx`]), stays bounded for a bounded input under any sequence of sample
//! intervals: jitter, single dropouts of any length (past the gap rule too), a lasting rate
//! below or above the nominal one, from 2 Hz to 1 kHz around nominal periods of 5 ms to 0.5 s.
//!
//! The input is `y = A sin(w t)` (A = 60 deg, w = pi rad/s: rate amplitude `A w` = 188.5 deg/s,
//! acceleration `A w^2` = 592 deg/s^2), quantised to the NAV440's yaw LSB (360/2^16 deg). Bounds
//! (derived from the input, with a factor 10):
//!
//! * velocity channels: `10 A w` = 1885 deg/s. The laws see the samples joined by straight
//!   lines, whose slopes are secants of the sine, at most `A w` (mean value theorem), plus a
//!   quantisation step over the shortest interval (0.0055 deg / 1 ms = 5.5 deg/s);
//! * acceleration channels: `10 (A w^2 + 2 A w W)` = 3.8e6 deg/s^2, with `W` = 1000 rad/s:
//!   between two straight pieces the slope jumps by at most `2 A w`, and a series or a tracker
//!   turns a slope step into an acceleration pulse of height about the step times its loop
//!   bandwidth, below `W` for every law here (the fastest, the AVE's `sqrt(gamma1)` = 141 rad/s
//!   and the ED's, stay well under `0.1 / h`).
//!
//! Before the Kalman tracker sub-stepped long intervals (`estimators::kalman`), a lasting rate
//! of a fifth of the nominal one drove `kf_v` and `kf_a` to 1e16 (f32) or to the Q31.32 limit,
//! 2.1e9 (Fx): far above these bounds. 64 cases per bank, each a few seconds of signal: about
//! 2-4 s for the whole file in the dev profile.

use estimators::{
    AdaptiveBank, AdaptiveConfig, AdaptiveProductBank, AdaptiveProductConfig, BankConfig,
    BankGains, EstimatorBank, EstimatorOutput, Fx, GainSchedule, PaperBank, ProductBank,
    ScheduleLevel,
};
use proptest::prelude::*;

/// Amplitude, deg.
const A: f64 = 60.0;
/// Angular frequency, rad/s.
const W_SIG: f64 = core::f64::consts::PI;
/// The NAV440 yaw LSB, deg.
const LSB: f64 = 360.0 / 65536.0;
/// Upper bound of every law's loop bandwidth, rad/s (see the module documentation).
const W_LAW: f64 = 1000.0;
/// Factor on the bounds.
const FACTOR: f64 = 10.0;

/// How the intervals of one stretch of samples are drawn (as multiples of the nominal
/// period).
#[derive(Clone, Copy, Debug)]
enum Stretch {
    /// Each interval `nominal * U(1 - j, 1 + j)`.
    Jitter(f64),
    /// A lasting rate: every interval `m` nominal periods (`m` in `[1/8, 16]`).
    Rate(f64),
    /// One interval of `k` nominal periods (a dropout; the gap rule is 25), then nominal.
    Dropout(f64),
}

fn stretch() -> impl Strategy<Value = (Stretch, usize)> {
    let kind = prop_oneof![
        2 => (0.0f64..0.5).prop_map(Stretch::Jitter),
        3 => (-3.0f64..4.0).prop_map(|e| Stretch::Rate(2f64.powf(e))),
        2 => (1.5f64..40.0).prop_map(Stretch::Dropout),
    ];
    (kind, 1usize..30)
}

/// A case: the nominal period (s, 5 ms to 0.5 s), the stretches and the jitter seed.
fn case() -> impl Strategy<Value = (f64, Vec<(Stretch, usize)>, u64)> {
    (
        (-2.3f64..-0.3).prop_map(|e| 10f64.powf(e)),
        prop::collection::vec(stretch(), 1..6),
        any::<u64>(),
    )
}

/// The sample times (us) of a case: at most `max_s` s of signal, every interval at least
/// 1 ms (2 Hz to 1 kHz around the nominal rate, and longer dropouts).
fn times(nominal_s: f64, stretches: &[(Stretch, usize)], mut seed: u64, max_s: f64) -> Vec<u64> {
    let mut uniform = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut t = 0.0f64;
    let mut out = vec![0u64];
    'outer: for &(kind, len) in stretches {
        for i in 0..len {
            let m = match kind {
                Stretch::Jitter(j) => 1.0 + j * (2.0 * uniform() - 1.0),
                Stretch::Rate(m) => m,
                Stretch::Dropout(k) if i == 0 => k,
                Stretch::Dropout(_) => 1.0,
            };
            t += (nominal_s * m).max(1e-3);
            if t > max_s {
                break 'outer;
            }
            out.push((t * 1e6).round() as u64);
        }
    }
    out
}

/// The quantised input at `t_us`, deg.
fn input(t_us: u64) -> f32 {
    let y = A * (W_SIG * t_us as f64 * 1e-6).sin();
    ((y / LSB).round() * LSB) as f32
}

/// Runs `bank` over `times`; returns the largest |value| of the velocity channels (the first
/// half of the channel list ending in `_v`) and of the acceleration channels.
fn run<B: EstimatorBank>(bank: &mut B, times: &[u64]) -> (f64, f64, String) {
    run_rated(bank, times, false)
}

/// [`run`], giving the bank the input's exact rate (deg/s) before each sample when `rated`.
fn run_rated<B: EstimatorBank>(bank: &mut B, times: &[u64], rated: bool) -> (f64, f64, String) {
    let names = B::CHANNEL_NAMES;
    let (mut vmax, mut amax) = (0.0f64, 0.0f64);
    let mut worst = String::new();
    for &t in times {
        if rated {
            let rate = A * W_SIG * (W_SIG * t as f64 * 1e-6).cos();
            bank.observe_rate(t, rate as f32);
        }
        let out = bank.update(t, input(t)).expect("a valid sample");
        for (name, v) in names.iter().zip(out.values()) {
            let v = f64::from(v).abs();
            assert!(v.is_finite(), "{name} not finite at t = {t} us");
            let m = if name.ends_with("_v") {
                &mut vmax
            } else {
                &mut amax
            };
            if v > *m {
                *m = v;
                worst = format!("{name} = {v} at t = {t} us");
            }
        }
    }
    (vmax, amax, worst)
}

fn config(nominal_s: f64) -> BankConfig {
    BankConfig {
        sample_period_s: nominal_s as f32,
        ..BankConfig::NAV440
    }
}

/// A two-level schedule (the NAV440 gains at 0.01 deg^2, the paper's at 0.5 deg^2).
fn schedule() -> GainSchedule {
    let level = |noise_var, velocity, acceleration| ScheduleLevel {
        noise_var,
        velocity,
        acceleration,
        ave_deltahat: None,
        switch_up: None,
    };
    GainSchedule::new(&[
        level(
            0.01,
            BankGains::NAV440_VELOCITY,
            BankGains::NAV440_ACCELERATION,
        ),
        level(
            0.5,
            BankGains::PAPER_VELOCITY,
            BankGains::PAPER_ACCELERATION,
        ),
    ])
    .unwrap()
}

fn check(bank: &str, (vmax, amax, worst): (f64, f64, String)) -> Result<(), TestCaseError> {
    let v_bound = FACTOR * A * W_SIG;
    let a_bound = FACTOR * (A * W_SIG * W_SIG + 2.0 * A * W_SIG * W_LAW);
    prop_assert!(
        vmax < v_bound && amax < a_bound,
        "{bank}: max |v| {vmax} (bound {v_bound}), max |a| {amax} (bound {a_bound}); largest: {worst}"
    );
    Ok(())
}

/// Simulated seconds of one case: 30 nominal periods, within [1.5 s, 6 s].
fn duration(nominal_s: f64) -> f64 {
    (30.0 * nominal_s).clamp(1.5, 6.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn paper_bank_is_bounded_under_any_timing((nominal, stretches, seed) in case()) {
        let ts = times(nominal, &stretches, seed, duration(nominal));
        let cfg = config(nominal);
        check("PaperBank<f32>", run(&mut PaperBank::<f32>::new(&cfg).unwrap(), &ts))?;
        check("PaperBank<Fx>", run(&mut PaperBank::<Fx>::new(&cfg).unwrap(), &ts))?;
    }

    #[test]
    fn product_bank_is_bounded_under_any_timing((nominal, stretches, seed) in case()) {
        let ts = times(nominal, &stretches, seed, duration(nominal));
        let cfg = config(nominal);
        check("ProductBank<f32>", run(&mut ProductBank::<f32>::new(&cfg).unwrap(), &ts))?;
        check("ProductBank<Fx>", run(&mut ProductBank::<Fx>::new(&cfg).unwrap(), &ts))?;
        // The paper's gains too (the product bank's ILO1 and tracker with the paper preset).
        let paper = BankConfig { sample_period_s: nominal as f32, ..BankConfig::PAPER };
        check("ProductBank<f32> paper", run(&mut ProductBank::<f32>::new(&paper).unwrap(), &ts))?;
        // The bank that follows the motion, given no rate: its start (ILO1 through the fifth
        // alias) and the fall back to the first alias when the interval jitters.
        let follow = AdaptiveProductConfig::DEFAULT;
        check(
            "AdaptiveProductBank<f32>",
            run(&mut AdaptiveProductBank::<f32>::new(&cfg, &follow).unwrap(), &ts),
        )?;
        check(
            "AdaptiveProductBank<Fx>",
            run(&mut AdaptiveProductBank::<Fx>::new(&cfg, &follow).unwrap(), &ts),
        )?;
    }

    #[test]
    fn adaptive_bank_is_bounded_under_any_timing((nominal, stretches, seed) in case()) {
        let ts = times(nominal, &stretches, seed, duration(nominal).min(3.0));
        let cfg = config(nominal);
        let s = schedule();
        check(
            "AdaptiveBank<f32>",
            run(&mut AdaptiveBank::<f32>::new(&cfg, &s, &AdaptiveConfig::DEFAULT).unwrap(), &ts),
        )?;
        check(
            "AdaptiveBank<Fx>",
            run(&mut AdaptiveBank::<Fx>::new(&cfg, &s, &AdaptiveConfig::DEFAULT).unwrap(), &ts),
        )?;
        // Following the motion too, given the rate: a schedule tuned on a motion of jerk power
        // 1 (deg/s^3)^2, so that this one always counts as harder. The jerk estimate runs
        // under every timing; the noise-free input already keeps the gains at the lowest
        // level, so this checks the estimate and the index, not a gain change (those are
        // `adaptive::tests::a_schedule_with_its_tuning_jerk_follows_the_motion`'s).
        let hard = s.with_tuned_jerk(1.0).unwrap();
        check(
            "AdaptiveBank<f32> following the motion",
            run_rated(&mut AdaptiveBank::<f32>::new(&cfg, &hard, &AdaptiveConfig::DEFAULT).unwrap(), &ts, true),
        )?;
        check(
            "AdaptiveBank<Fx> following the motion",
            run_rated(&mut AdaptiveBank::<Fx>::new(&cfg, &hard, &AdaptiveConfig::DEFAULT).unwrap(), &ts, true),
        )?;
    }
}

/// Nominal 10 ms, then a lasting rate of a fifth (one packet in five delivered): every channel
/// stays within the bounds above, in both number types (a tracker that updates once per
/// interval with the nominal gain passes 1e6 deg/s within 2 s here).
#[test]
fn one_packet_in_five() {
    let mut ts: Vec<u64> = (0..50).map(|k| k * 10_000).collect();
    ts.extend((1..200).map(|k| 490_000 + k * 50_000));
    let cfg = config(0.01);
    for (name, r) in [
        (
            "PaperBank<f32>",
            run(&mut PaperBank::<f32>::new(&cfg).unwrap(), &ts),
        ),
        (
            "PaperBank<Fx>",
            run(&mut PaperBank::<Fx>::new(&cfg).unwrap(), &ts),
        ),
        (
            "ProductBank<f32>",
            run(&mut ProductBank::<f32>::new(&cfg).unwrap(), &ts),
        ),
        (
            "ProductBank<Fx>",
            run(&mut ProductBank::<Fx>::new(&cfg).unwrap(), &ts),
        ),
    ] {
        println!(
            "{name}: max |v| {:.1} deg/s, max |a| {:.0} deg/s^2 ({})",
            r.0, r.1, r.2
        );
        check(name, r).unwrap();
    }
}
