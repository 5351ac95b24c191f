//! Tests of the gain schedule, the noise estimate and the adaptive bank.

use super::*;
use crate::presets::{ILO1_TABLE2, ILO3_TABLE2};
use crate::IloConfig;

/// Independent N(0, 1) draws (rand's xoshiro256++ and rand_distr's normal distribution).
struct Gauss(rand::rngs::Xoshiro256PlusPlus);
impl Gauss {
    fn new(seed: u64) -> Self {
        Self(rand::SeedableRng::seed_from_u64(seed))
    }
    fn next(&mut self) -> f64 {
        rand_distr::Distribution::sample(&rand_distr::StandardNormal, &mut self.0)
    }
}

/// On a smooth motion at 100 Hz, the estimate is the noise variance within 10 % (time
/// constant 5 s: about 1000 independent terms), and it follows a step of the noise.
#[test]
fn noise_estimate_matches_the_added_variance() {
    let mut g = Gauss::new(3);
    let mut e = NoiseEstimator::new(5.0, 0.01).unwrap();
    assert_eq!(e.variance(), None);
    let mut at = |e: &mut NoiseEstimator, k: u64, var: f64| {
        let t = k as f64 * 0.01;
        // 90 deg amplitude, 0.5 Hz: jerk 90 * pi^3 = 2.8e3 deg/s^3.
        let y = 90.0 * libm::sin(core::f64::consts::PI * t) + var.sqrt() * g.next();
        e.update(k * 10_000, y as f32);
    };
    for k in 0..6000 {
        at(&mut e, k, 0.25);
    }
    let v = e.variance().unwrap();
    assert!((v - 0.25).abs() < 0.025, "{v}");
    for k in 6000..12000 {
        at(&mut e, k, 0.01);
    }
    let v = e.variance().unwrap();
    assert!((v - 0.01).abs() < 0.001, "{v}");
}

/// An angle that is exactly constant at first (no noise above the quantisation: every term
/// 0) does not hold the estimate at 0: when N(0, 0.5) noise starts at 1 s, the estimate reads
/// 0.5 within 20 % 2 s later (one time constant is 0.5 s; the growth from the clip's floor
/// takes under 1 s). Without the floor it stayed at exactly 0 for ever (found on `nav440
/// synth --profile tumble`, which starts at rest).
#[test]
fn a_constant_start_does_not_lock_the_estimate_at_zero() {
    let mut g = Gauss::new(5);
    let mut e = NoiseEstimator::new(0.5, 0.01).unwrap();
    for k in 0..300u64 {
        let noise = if k >= 100 {
            0.5f64.sqrt() * g.next()
        } else {
            0.0
        };
        e.update(k * 10_000, (12.5 + noise) as f32);
        if k == 99 {
            assert_eq!(e.variance(), Some(0.0));
        }
    }
    let v = e.variance().unwrap();
    assert!((v - 0.5).abs() < 0.1, "{v}");
}

/// At 20 Hz the time constant is 50 periods (2.5 s), not the 0.5 s asked for: the
/// estimator is the same as one asked for 2.5 s, and on N(0, 0.01) noise over a smooth
/// motion it stays within 0.5x to 2x of 0.01 once started (with 0.5 s, 10 terms, it read
/// 0.003 to 0.035 on a synthetic spin at 20 Hz; at 100 Hz with 0.5 s: 0.005 to 0.02).
#[test]
fn the_time_constant_is_at_least_fifty_periods() {
    assert_eq!(
        NoiseEstimator::new(0.5, 0.05).unwrap(),
        NoiseEstimator::new(2.5, 0.05).unwrap()
    );
    assert_ne!(
        NoiseEstimator::new(0.5, 0.01).unwrap(),
        NoiseEstimator::new(2.5, 0.01).unwrap()
    );
    let mut g = Gauss::new(11);
    let mut e = NoiseEstimator::new(0.5, 0.05).unwrap();
    let (mut lo, mut hi) = (f32::MAX, 0.0f32);
    for k in 0..2400u64 {
        let t = k as f64 * 0.05;
        // 30 deg amplitude, 0.2 Hz: jerk 30 (0.4 pi)^3 = 60 deg/s^3, (jerk dt^3)^2 = 5e-5.
        let y = 30.0 * libm::sin(0.4 * core::f64::consts::PI * t) + 0.1 * g.next();
        e.update(k * 50_000, y as f32);
        if t >= 10.0 {
            let v = e.variance().unwrap();
            (lo, hi) = (lo.min(v), hi.max(v));
        }
    }
    assert!(lo > 0.005 && hi < 0.02, "{lo} {hi}");
}

/// A schedule records the period it was tuned at and fits banks within 1.2x of it.
#[test]
fn a_schedule_fits_the_period_it_was_tuned_at() {
    let s = GainSchedule::new(&[level(0.01, 100.0, ILO1_TABLE2)]).unwrap();
    assert_eq!(s.sample_period_s(), None);
    assert!(s.fits_period(0.01) && s.fits_period(0.5));
    assert_eq!(
        s.with_sample_period(f32::NAN),
        Err(ConfigError::NotFinite("sample_period_s"))
    );
    assert_eq!(
        s.with_sample_period(0.0),
        Err(ConfigError::NotPositive("sample_period_s"))
    );
    let s = s.with_sample_period(0.01).unwrap();
    assert_eq!(s.sample_period_s(), Some(0.01));
    // 100 Hz fits 100 Hz and periods within 1.2x (0.0085 to 0.0118 s); not 80 Hz
    // (0.0125 s), 125 Hz (0.008 s), 50 Hz or 10 Hz: the NAV440's neighbouring rates.
    for (p, fits) in [
        (0.01, true),
        (0.0085, true),
        (0.0118, true),
        (0.0125, false),
        (0.008, false),
        (0.02, false),
        (0.1, false),
    ] {
        assert_eq!(s.fits_period(p), fits, "{p}");
    }
    // The bank runs it at any period and tells.
    for (p, fits) in [(0.01, true), (0.05, false)] {
        let base = BankConfig {
            sample_period_s: p,
            ..BankConfig::PAPER
        };
        let b = AdaptiveBank::<f32>::new(&base, &s, &AdaptiveConfig::DEFAULT).unwrap();
        assert_eq!(b.period_fits(), fits);
        assert_eq!(b.sample_period_s(), p);
        assert_eq!(b.schedule().sample_period_s(), Some(0.01));
    }
}

/// A wrapping spin (500 deg/s, through +-180 deg) without noise reads as (almost) no
/// noise: the differences are taken modulo 360.
#[test]
fn wraps_are_not_noise() {
    let mut e = NoiseEstimator::new(0.5, 0.01).unwrap();
    for k in 0..500u64 {
        let mut y = (k as f64 * 5.0) % 360.0;
        if y > 180.0 {
            y -= 360.0;
        }
        e.update(k * 10_000, y as f32);
    }
    assert!(e.variance().unwrap() < 1e-6, "{:?}", e.variance());
}

fn level(noise_var: f32, k: f32, ilo: IloConfig) -> ScheduleLevel {
    let mut g = BankConfig::PAPER.velocity;
    g.ave.k = k;
    g.ilo = [ilo; 3];
    ScheduleLevel {
        noise_var,
        velocity: g,
        acceleration: BankConfig::PAPER.acceleration,
        ave_deltahat: None,
        switch_up: None,
    }
}

fn with_deltahat(mut l: ScheduleLevel, velocity: f32, acceleration: [f32; 2]) -> ScheduleLevel {
    l.ave_deltahat = Some(AveDeltahat {
        velocity,
        acceleration,
    });
    l
}

/// The recorded switching gains are validated, and read from the level whose AVE gains
/// the schedule uses (the nearer one by default, interpolated with the geometric blend).
#[test]
fn ave_deltahat_follows_the_ave_gains_level() {
    let lo = with_deltahat(level(0.01, 100.0, ILO1_TABLE2), 0.1, [1.0, 10.0]);
    let hi = with_deltahat(level(1.0, 10_000.0, ILO3_TABLE2), 10.0, [4.0, 40.0]);
    let s = GainSchedule::new(&[lo, hi]).unwrap();
    for (v, want) in [(0.001, lo), (0.09, lo), (0.11, hi), (5.0, hi)] {
        assert_eq!(s.ave_deltahat_at(v), want.ave_deltahat, "{v}");
        assert_eq!(s.gains_at(v).0.ave, want.velocity.ave, "{v}");
    }
    // Geometric: half-way in ln(noise), the geometric means.
    let g = s.with_blend(Blend::Geometric).ave_deltahat_at(0.1).unwrap();
    assert!((g.velocity - 1.0).abs() < 1e-5, "{g:?}");
    assert!((g.acceleration[0] - 2.0).abs() < 1e-5, "{g:?}");
    assert!((g.acceleration[1] - 20.0).abs() < 1e-4, "{g:?}");
    // A level without: none where it is needed.
    let s = GainSchedule::new(&[lo, level(1.0, 10_000.0, ILO3_TABLE2)]).unwrap();
    assert!(s.ave_deltahat_at(0.09).is_some());
    assert_eq!(s.ave_deltahat_at(0.11), None);
    // Validation.
    let bad = |v: f32| {
        GainSchedule::new(&[with_deltahat(
            level(0.01, 100.0, ILO1_TABLE2),
            1.0,
            [v, 1.0],
        )])
    };
    assert_eq!(bad(f32::NAN), Err(ConfigError::NotFinite("ave_deltahat")));
    assert_eq!(
        bad(f32::INFINITY),
        Err(ConfigError::NotFinite("ave_deltahat"))
    );
    assert_eq!(bad(-0.5), Err(ConfigError::Negative("ave_deltahat")));
    assert!(bad(0.0).is_ok());
}

/// Each observer family moves to the next level at its own recorded switch point
/// (`ScheduleLevel::switch_up`, clamped to the two levels), the AD and the tracker stay
/// interpolated, the AVE's `deltahat` follows the AVE's level; without switch points, the
/// geometric midpoint (0.1 for levels 0.01 and 1). Invalid points are refused.
#[test]
fn observers_switch_at_their_recorded_points() {
    let lo = with_deltahat(level(0.01, 100.0, ILO1_TABLE2), 0.1, [1.0, 10.0]);
    let mut hi = with_deltahat(level(1.0, 10_000.0, ILO3_TABLE2), 10.0, [4.0, 40.0]);
    hi.velocity.ad_t = 0.1;
    hi.velocity.ed.lambda = 99.0;
    let sw = ObserverSwitch {
        ave: 0.5,
        ilo: [0.02, 0.05, 5.0],
        ed: 0.001,
    };
    let s = GainSchedule::new(&[
        ScheduleLevel {
            switch_up: Some(sw),
            ..lo
        },
        hi,
    ])
    .unwrap();
    let midpoint = GainSchedule::new(&[lo, hi]).unwrap();
    for v in [0.011f32, 0.03, 0.09, 0.11, 0.49, 0.5, 0.9] {
        let (g, m) = (s.gains_at(v).0, midpoint.gains_at(v).0);
        let pick = |at: f32| if v >= at { &hi } else { &lo };
        assert_eq!(g.ave, pick(0.5).velocity.ave, "AVE at {v}");
        assert_eq!(g.ilo[0], pick(0.02).velocity.ilo[0], "ILO1 at {v}");
        assert_eq!(g.ilo[1], pick(0.05).velocity.ilo[1], "ILO2 at {v}");
        // Past the upper level: clamped to it (the ILO3 moves only at 1).
        assert_eq!(g.ilo[2], lo.velocity.ilo[2], "ILO3 at {v}");
        // Below the lower level: clamped to it (the ED takes the upper level's at once).
        assert_eq!(g.ed, hi.velocity.ed, "ED at {v}");
        assert_eq!(
            s.ave_deltahat_at(v),
            pick(0.5).ave_deltahat,
            "deltahat at {v}"
        );
        // The AD and the tracker do not depend on the switch points.
        assert_eq!((g.ad_t, g.kf), (m.ad_t, m.kf), "{v}");
        assert_eq!(m.ave, pick(0.1).velocity.ave, "midpoint AVE at {v}");
        assert_eq!(m.ed, pick(0.1).velocity.ed, "midpoint ED at {v}");
    }
    assert_eq!(s.gains_at(1.0).0.ilo[2], hi.velocity.ilo[2]);
    // Geometric blend: the switch points do not apply.
    assert_eq!(
        s.with_blend(Blend::Geometric).gains_at(0.1),
        midpoint.with_blend(Blend::Geometric).gains_at(0.1)
    );
    for (bad, err) in [
        (f32::NAN, ConfigError::NotFinite("switch_up")),
        (0.0, ConfigError::NotPositive("switch_up")),
        (-1.0, ConfigError::NotPositive("switch_up")),
    ] {
        let l = ScheduleLevel {
            switch_up: Some(ObserverSwitch { ed: bad, ..sw }),
            ..lo
        };
        assert_eq!(GainSchedule::new(&[l, hi]), Err(err));
    }
}

/// A bumpless retune (no replay, `replay_samples: 0`) that changes the velocity AVE's
/// gains sets its `deltahat` to the level's recorded value; the acceleration series' AVEs,
/// whose gains do not change here, keep theirs; a retune within the same AVE gains keeps
/// every `deltahat`; a schedule without recorded values keeps them all (f32 and Fx).
#[test]
fn a_retune_sets_the_recorded_deltahat() {
    fn check<T: Real>() {
        let lo = with_deltahat(level(0.01, 100.0, ILO1_TABLE2), 0.1, [1.0, 10.0]);
        let hi = with_deltahat(level(1.0, 400.0, ILO3_TABLE2), 10.0, [4.0, 40.0]);
        let never = AdaptiveConfig {
            retune_ratio: f32::MAX,
            replay_samples: 0,
            ..AdaptiveConfig::DEFAULT
        };
        let close = |a: f32, b: f32| (a - b).abs() < 1e-3;
        for recorded in [true, false] {
            let s = if recorded {
                GainSchedule::new(&[lo, hi]).unwrap()
            } else {
                GainSchedule::new(&[
                    ScheduleLevel {
                        ave_deltahat: None,
                        ..lo
                    },
                    ScheduleLevel {
                        ave_deltahat: None,
                        ..hi
                    },
                ])
                .unwrap()
            };
            let mut b = AdaptiveBank::<T>::new(&BankConfig::PAPER, &s, &never).unwrap();
            let mut k = 0u64;
            let mut run = |b: &mut AdaptiveBank<T>, n: u64| {
                for _ in 0..n {
                    // A 30 deg/s ramp with a 0.1 deg alternation: deltahat grows.
                    let y = 0.3 * k as f32 + if k.is_multiple_of(2) { 0.1 } else { -0.1 };
                    b.update(k * 10_000, y).unwrap();
                    k += 1;
                }
            };
            run(&mut b, 200);
            let before = b.bank().ave_deltahat();
            assert!(
                before.velocity > 0.05 && before.acceleration[1] > 0.0,
                "{before:?}"
            );
            b.retune(1.0);
            let after = b.bank().ave_deltahat();
            let want = if recorded { 10.0 } else { before.velocity };
            assert!(close(after.velocity, want), "{recorded}: {after:?}");
            assert_eq!(after.acceleration, before.acceleration);
            run(&mut b, 50);
            let before = b.bank().ave_deltahat();
            b.retune(0.5);
            assert_eq!(b.bank().ave_deltahat(), before);
            b.retune(0.01);
            let after = b.bank().ave_deltahat();
            let want = if recorded { 0.1 } else { before.velocity };
            assert!(close(after.velocity, want), "{recorded}: {after:?}");
            assert_eq!(after.acceleration, before.acceleration);
            assert_eq!(b.retune_count(), 3);
        }
    }
    check::<f32>();
    check::<crate::Fx>();
}

/// `PaperBank::set_ave_deltahat` sets what `ave_deltahat` reads (the shared first stage
/// of the AVE-AVE series reads as the velocity AVE's) and ignores negative and
/// non-finite values.
#[test]
fn set_ave_deltahat_round_trips() {
    let mut b = PaperBank::<f32>::new(&BankConfig::PAPER).unwrap();
    assert_eq!(
        BankConfig::PAPER.velocity.ave,
        BankConfig::PAPER.acceleration.ave
    );
    b.update(0, 1.0).unwrap();
    let d = AveDeltahat {
        velocity: 2.0,
        acceleration: [3.0, 4.0],
    };
    b.set_ave_deltahat(&d);
    // Shared: the first stage is the velocity AVE.
    assert_eq!(b.ave_deltahat().velocity, 2.0);
    assert_eq!(b.ave_deltahat().acceleration, [2.0, 4.0]);
    b.set_ave_deltahat(&AveDeltahat {
        velocity: -1.0,
        acceleration: [f32::NAN, f32::INFINITY],
    });
    assert_eq!(b.ave_deltahat().velocity, 2.0);
    assert_eq!(b.ave_deltahat().acceleration, [2.0, 4.0]);
    let mut cfg = BankConfig::PAPER;
    cfg.acceleration.ave.k = 400.0;
    let mut b = PaperBank::<f32>::new(&cfg).unwrap();
    b.update(0, 1.0).unwrap();
    b.set_ave_deltahat(&d);
    assert_eq!(b.ave_deltahat(), d);
}

/// `set_gains` reuses the closed-form maps of rows whose gains did not change: the
/// parameters after each gain change are bit for bit those of a fresh build for the same
/// configuration (compared through `Debug`, which prints every float's shortest
/// round-trip form), for changes within one level's band (only the AD and the tracker
/// change), across levels, back, and to the same gains; f32 and Fx.
#[test]
fn set_gains_equals_a_fresh_build() {
    extern crate std;
    use std::format;
    fn check<T: Real>() {
        let s = GainSchedule::new(&[
            level(0.01, 100.0, ILO1_TABLE2),
            level(1.0, 10_000.0, ILO3_TABLE2),
        ])
        .unwrap();
        let base = BankConfig::PAPER;
        let mut bank = PaperBank::<T>::new(&s.config_at(&base, 0.01)).unwrap();
        for v in [0.02, 0.03, 0.5, 0.9, 0.9, 0.05, 0.011, 1.0] {
            let cfg = s.config_at(&base, v);
            bank.set_gains(&cfg).unwrap();
            let (_, n0) = crate::BankInput::<T>::new(&cfg).unwrap();
            let fresh =
                <crate::PaperRows as crate::Rows<T, crate::NativeSqrt>>::build(&cfg, n0, None)
                    .unwrap();
            type R = crate::PaperRows;
            assert_eq!(
                format!(
                    "{:?}",
                    <R as crate::Rows<T, crate::NativeSqrt>>::params_debug(bank.params())
                ),
                format!(
                    "{:?}",
                    <R as crate::Rows<T, crate::NativeSqrt>>::params_debug(&fresh)
                ),
                "noise {v}"
            );
        }
    }
    check::<f32>();
    check::<crate::Fx>();
}

/// A noisy ramp at 100 Hz that crosses +180 deg (so the history holds frame shifts),
/// with a 0.3 s gap (a re-initialisation) at sample 20 when `gap` is set.
fn wrapping_ramp(k: u64, gap: bool, g: &mut Gauss) -> (u64, f32) {
    let t_us = k * 10_000 + if gap && k >= 20 { 300_000 } else { 0 };
    let y = 150.0 + 120.0 * k as f64 * 0.01 + 0.3 * g.next();
    let y = if y > 180.0 { y - 360.0 } else { y };
    (t_us, y as f32)
}

/// `set_gains_replaying` over every sample since the bank's last (re-)initialisation is
/// exact: afterwards the bank is, bit for bit, a bank that ran the new gains from the start
/// (its state through `Debug`, every float's shortest round-trip form, and the outputs of
/// the next 100 samples), across frame shifts (the ramp crosses +180 deg) and a gap that
/// re-initialises the laws inside the history; f32 and Fx.
#[test]
fn a_replayed_gain_change_is_a_bank_run_with_the_new_gains() {
    extern crate std;
    use std::{format, vec::Vec};
    fn check<T: Real>(gap: bool) {
        let s = GainSchedule::new(&[
            level(0.01, 100.0, ILO1_TABLE2),
            level(1.0, 10_000.0, ILO3_TABLE2),
        ])
        .unwrap();
        let (a, b) = (
            s.config_at(&BankConfig::PAPER, 0.01),
            s.config_at(&BankConfig::PAPER, 1.0),
        );
        let mut old = PaperBank::<T>::new(&a).unwrap();
        let mut fresh = PaperBank::<T>::new(&b).unwrap();
        let mut g = Gauss::new(5);
        let mut history = Vec::new();
        for k in 0..60 {
            let (t, y) = wrapping_ramp(k, gap, &mut g);
            let (_, fed) = old.update_fed(t, y).unwrap();
            history.push(fed);
            fresh.update(t, y).unwrap();
        }
        assert!(history.iter().any(|f| f.shift.is_some()));
        old.set_gains_replaying(&b, &history, |_| {}).unwrap();
        let state = |b: &PaperBank<T>| {
            format!(
                "{:?}",
                <crate::PaperRows as crate::Rows<T, crate::NativeSqrt>>::state_debug(b.state())
            )
        };
        assert_eq!(state(&old), state(&fresh));
        for k in 60..160 {
            let (t, y) = wrapping_ramp(k, gap, &mut g);
            assert_eq!(
                old.update(t, y).unwrap(),
                fresh.update(t, y).unwrap(),
                "{k}"
            );
        }
    }
    for gap in [false, true] {
        check::<f32>(gap);
        check::<crate::Fx>(gap);
    }
}

/// `AdaptiveBank::retune` with the default warm start (the history holds every sample
/// since the first, 50 < `REPLAY_CAPACITY`): the replayed rows whose gains changed (here
/// the velocity ILOs and AD, the trackers, and the AVE row, started at the level's
/// recorded `deltahat`) continue as a bank that ran the new gains from the start with that
/// `deltahat`; the ED row and the ILO-ILO and AD-AD series continue as the bumpless retune
/// (`replay_samples: 0`) does; a retune to the same gains changes nothing (f32).
#[test]
fn a_warm_retune_replays_the_changed_rows() {
    let lo = with_deltahat(level(0.01, 100.0, ILO1_TABLE2), 0.1, [1.0, 10.0]);
    let hi = with_deltahat(level(1.0, 400.0, ILO3_TABLE2), 10.0, [4.0, 40.0]);
    let s = GainSchedule::new(&[lo, hi]).unwrap();
    let never = AdaptiveConfig {
        retune_ratio: f32::MAX,
        ..AdaptiveConfig::DEFAULT
    };
    let bumpless = AdaptiveConfig {
        replay_samples: 0,
        ..never
    };
    let base = BankConfig::PAPER;
    let mut warm = AdaptiveBank::<f32>::new(&base, &s, &never).unwrap();
    let mut cold = AdaptiveBank::<f32>::new(&base, &s, &bumpless).unwrap();
    let mut fresh = PaperBank::<f32>::new(&s.config_at(&base, 1.0)).unwrap();
    let mut g = Gauss::new(8);
    for k in 0..50 {
        let (t, y) = wrapping_ramp(k, false, &mut g);
        warm.update(t, y).unwrap();
        cold.update(t, y).unwrap();
        fresh.update(t, y).unwrap();
        if k == 0 {
            fresh.set_ave_deltahat(&hi.ave_deltahat.unwrap());
        }
    }
    extern crate std;
    let state = |s: &crate::PaperState<f32>| {
        std::format!(
            "{:?}",
            <crate::PaperRows as crate::Rows<f32, crate::NativeSqrt>>::state_debug(s)
        )
    };
    let before = *warm.bank().state();
    warm.retune(0.01);
    assert_eq!(state(warm.bank().state()), state(&before));
    warm.retune(1.0);
    cold.retune(1.0);
    for k in 50..150 {
        let (t, y) = wrapping_ramp(k, false, &mut g);
        let (w, c, f) = (
            warm.update(t, y).unwrap(),
            cold.update(t, y).unwrap(),
            fresh.update(t, y).unwrap(),
        );
        for ch in crate::Channel::ALL {
            use crate::Channel::{AdA, EdA, EdV, Ilo1A, Ilo2A, Ilo3A};
            let want = if matches!(ch, EdV | EdA | Ilo1A | Ilo2A | Ilo3A | AdA) {
                c[*ch]
            } else {
                f[*ch]
            };
            assert_eq!(w[*ch], want, "{k} {}", ch.name());
        }
    }
}

#[test]
fn gains_are_interpolated_geometrically_in_the_noise() {
    let s = GainSchedule::new(&[
        level(0.01, 100.0, ILO1_TABLE2),
        level(1.0, 10_000.0, ILO3_TABLE2),
    ])
    .unwrap()
    .with_blend(Blend::Geometric);
    // At the levels and beyond them: the levels' gains.
    assert_eq!(s.gains_at(0.01).0.ave.k, 100.0);
    assert_eq!(s.gains_at(1e-4).0.ave.k, 100.0);
    assert_eq!(s.gains_at(1.0).0.ave.k, 10_000.0);
    assert_eq!(s.gains_at(50.0).0.ilo[0], ILO3_TABLE2);
    // Half-way in ln(noise): the geometric mean of the gains, sqrt(100 * 10000) = 1000;
    // L: sqrt(4 * 1) = 2; the leak 1 - K1 from 0 (ILO1) to 0.3 (ILO3): linear, 0.15.
    let (v, _) = s.gains_at(0.1);
    assert!((v.ave.k - 1000.0).abs() < 0.1, "{}", v.ave.k);
    assert!((v.ilo[0].l - 2.0).abs() < 1e-5);
    assert!((v.ilo[0].k1 - 0.85).abs() < 1e-6);
    // The default blend: the nearer level for the observers, geometric for the AD's T.
    let d = s.with_blend(Blend::NearestObservers);
    assert_eq!(d.gains_at(0.09).0.ave.k, 100.0);
    assert_eq!(d.gains_at(0.11).0.ave.k, 10_000.0);
    assert_eq!(d.gains_at(0.11).0.ilo[0], ILO3_TABLE2);
    assert_eq!(s.gains_at(0.1).0.ad_t, 0.01);
    assert!(GainSchedule::new(&[]).is_err());
    assert!(
        GainSchedule::new(&[level(0.1, 1.0, ILO1_TABLE2), level(0.1, 1.0, ILO1_TABLE2)]).is_err()
    );
    assert!(GainSchedule::new(&[level(0.0, 1.0, ILO1_TABLE2)]).is_err());
}

/// A 30 deg/s ramp at 100 Hz through a bank built with `a`: 6 s, then `set_gains(b)`,
/// then 1 s more, each of those samples handed to `check` (sample index, the velocities
/// of the last sample before the change, the output).
fn ramp_across_a_gain_change<T: Real>(
    a: &BankConfig,
    b: &BankConfig,
    mut check: impl FnMut(u64, [f32; crate::FAMILY_COUNT], &crate::PaperOutput<T>),
) {
    let mut bank = PaperBank::<T>::new(a).unwrap();
    let y = |k: u64| (30.0 * k as f64 * 0.01) as f32;
    let mut before = [0.0f32; crate::FAMILY_COUNT];
    for k in 0..600u64 {
        before = bank.update(k * 10_000, y(k)).unwrap().velocities();
    }
    bank.set_gains(b).unwrap();
    for k in 600..700u64 {
        check(k, before, &bank.update(k * 10_000, y(k)).unwrap());
    }
}

/// A gain change is bumpless (`Law::retune_state`): on a ramp of 30 deg/s, after the
/// bank settled with one schedule level's ILO gains (`K1 = 0.99966, L = 3.52,
/// K2 = 0.0345`, the 1 deg^2 level of a tuned schedule: a slow ILO whose steady state is
/// `V K2 / (K2 + L (1 - K1))` = 29.0 deg/s) and AD `T = 0.01 s`, the gains change to
/// another level's (`K1 = 0.99924, L = 0.506, K2 = 37.0`: a lightly damped ILO ringing
/// near 100 Hz; AD `T = 0.04 s`) and their series' (ILO-ILO, AD-AD). Kept as they were,
/// the ILO states meet the new `K2` with the old steady error (`(1 - K1) / K2 * v` =
/// 0.28 deg) and the ILO velocity swings between -97 and +97 deg/s in the next 0.2 s
/// (measured with the ILO's `retune_state` disabled). Here every velocity stays within
/// 2 deg/s of the ramp's 30 deg/s (the ILO moves from 29.0 to its new steady state, 30.0,
/// overshooting to 30.9) and every acceleration within 3 deg/s^2 of 0, f32 and Fx; but
/// the ED's: its paper gains (not changed here) sit in a limit cycle on this ramp (f32:
/// 44.6 deg/s, 2684 deg/s^2), so its velocity is only held within 0.5 deg/s of its value
/// before the change.
#[test]
fn gain_changes_are_bumpless() {
    fn check<T: Real>() {
        let slow = IloConfig {
            k1: 0.999_664_07,
            l: 3.523_521_4,
            k2: 0.034_486_07,
        };
        let ringing = IloConfig {
            k1: 0.999_241_3,
            l: 0.506_463_9,
            k2: 36.988_247,
        };
        let mut a = BankConfig::PAPER;
        a.velocity.ilo = [slow; 3];
        a.acceleration.ilo = [crate::presets::ILO2_TABLE4; 3];
        let mut b = a;
        b.velocity.ilo = [ringing; 3];
        b.velocity.ad_t = 0.04;
        b.acceleration.ilo = [IloConfig {
            k1: 0.999_456,
            l: 5.096_741_7,
            k2: 0.028_180_722,
        }; 3];
        b.acceleration.ad_t = 0.2;
        ramp_across_a_gain_change::<T>(&a, &b, |k, before, o| {
            for (i, (v, v0)) in o.velocities().iter().zip(before).enumerate() {
                let bound = if i == 5 { 0.5 } else { 2.0 };
                let reference = if i == 5 { v0 } else { 30.0 };
                assert!((v - reference).abs() < bound, "k {k} velocity {i}: {v}");
            }
            for (i, acc) in o.accelerations().iter().enumerate() {
                assert!(i == 5 || acc.abs() < 3.0, "k {k} acceleration {i}: {acc}");
            }
        });
    }
    check::<f32>();
    check::<crate::Fx>();
}

/// A row whose series shared the velocity law's first stage (the AVE with equal velocity
/// and acceleration gains: the first stage is not computed) and no longer does after a
/// gain change starts the series' first stage from the velocity law's state: on a ramp of
/// 30 deg/s the AVE velocity stays within 0.1 deg/s of 30 and the AVE-AVE within
/// 1 deg/s^2 of 0 when the new series gains are slower (`gamma1` 15,000: the AVE's
/// `retune_state` keeps `xhat`), within 10 deg/s^2 when faster (`gamma1` 25,000: the second
/// stage starts at `xhat` = the first stage's last output, which chatters about 0.04 deg/s
/// around 30, and the new `gamma1` turns that into 8.1 deg/s^2 in the first sample, f32);
/// f32 and Fx. Without the copy the first stage restarts from a state that last moved when
/// the bank was built, and the AVE-AVE jumps (to 1.7e5 deg/s^2 in the first sample,
/// measured with the copy disabled).
#[test]
fn a_row_that_stops_sharing_continues() {
    fn check<T: Real>() {
        for (gamma1, bound) in [(15_000.0, 1.0), (25_000.0, 10.0)] {
            let a = BankConfig::PAPER;
            let mut b = a;
            b.acceleration.ave.k = 400.0;
            b.acceleration.ave.gamma1 = gamma1;
            ramp_across_a_gain_change::<T>(&a, &b, |k, _, o| {
                let (v, acc) = (o.velocities()[0], o.accelerations()[0]);
                assert!(
                    (v - 30.0).abs() < 0.1 && acc.abs() < bound,
                    "gamma1 {gamma1} k {k}: {v} {acc}"
                );
            });
        }
    }
    check::<f32>();
    check::<crate::Fx>();
}

/// The adaptive bank moves its gains to the level of the noise it is fed, changing them
/// at most once per `retune_every` samples.
#[test]
fn adaptive_bank_follows_the_noise() {
    let s = GainSchedule::new(&[
        level(0.01, 500.0, ILO1_TABLE2),
        level(0.5, 100.0, ILO3_TABLE2),
    ])
    .unwrap();
    let cfg = AdaptiveConfig::DEFAULT;
    let mut b = AdaptiveBank::<f32>::new(&BankConfig::PAPER, &s, &cfg).unwrap();
    assert_eq!(b.gain_level(), 0.01);
    let mut g = Gauss::new(9);
    let n = 1000u64;
    for k in 0..n {
        let var = if k < 500 { 0.01 } else { 0.5 };
        let y = 20.0 + libm::sqrt(var) * g.next();
        b.update(k * 10_000, y as f32).unwrap();
        if k == 499 {
            let l = b.gain_level();
            assert!(l < 0.0125 * cfg.retune_ratio, "{l}");
        }
    }
    // The estimate reached the upper level (clamped there).
    assert!(
        b.gain_level() > 0.5 / cfg.retune_ratio,
        "{}",
        b.gain_level()
    );
    assert!(b.retune_count() >= 1 && u64::from(b.retune_count()) <= n / 20);
}

/// A sine of `amp` deg at `hz` Hz sampled at 100 Hz, with N(0, `var`) noise on the angle
/// (wrapped to +-180 deg): `(t_us, angle, rate)`.
fn noisy_sine(k: u64, amp: f64, hz: f64, var: f64, g: &mut Gauss) -> (u64, f32, f32) {
    let t = k as f64 * 0.01;
    let w = 2.0 * core::f64::consts::PI * hz;
    let y = amp * libm::sin(w * t) + var.sqrt() * g.next();
    let wrapped = y - 360.0 * libm::round(y / 360.0);
    (
        k * 10_000,
        wrapped as f32,
        (amp * w * libm::cos(w * t)) as f32,
    )
}

/// What [`AdaptiveProductConfig`] refuses.
#[test]
fn adaptive_product_config_is_checked() {
    let cfg = crate::BankConfig::NAV440;
    let with = |f: fn(&mut AdaptiveProductConfig)| {
        let mut c = AdaptiveProductConfig::DEFAULT;
        f(&mut c);
        AdaptiveProductBank::<f32>::new(&cfg, &c).map(|_| ())
    };
    assert_eq!(with(|_| {}), Ok(()));
    assert_eq!(
        with(|c| c.ilo1_c = f32::NAN),
        Err(ConfigError::NotFinite("ilo1_c"))
    );
    assert_eq!(
        with(|c| c.kappa_s = 0.0),
        Err(ConfigError::NotPositive("kappa_s"))
    );
    assert_eq!(with(|c| c.ilo1_zeta = 1.0), Err(ConfigError::ObserverPoles));
    assert_eq!(with(|c| c.ilo1_alias = 0), Err(ConfigError::ObserverPoles));
    assert_eq!(
        with(|c| c.ilo1_jitter_max = 1.0),
        Err(ConfigError::NotPositive("ilo1_jitter_max"))
    );
    assert_eq!(
        with(|c| c.ilo1_ratio = 0.9),
        Err(ConfigError::NotPositive("ilo1_ratio"))
    );
    assert!(
        with(|c| c.noise_tau_s = -1.0).is_err(),
        "a negative time constant"
    );
}

/// ILO1 starts at the rule's gains for fig5's jerk power at 0.001 deg^2 (`wn` = 0.6245 x
/// (3.68e6 / 0.00001)^(1/6) = 52.9 rad/s at 100 Hz, computed here again), the Kalman at the
/// configuration's; without a rate the gains never move: the output is that of the plain
/// product bank built with those gains, bit for bit.
#[test]
fn without_a_rate_the_adaptive_product_bank_is_the_product_bank() {
    fn check<T: Real>() {
        let cfg = crate::BankConfig::NAV440;
        let f = AdaptiveProductConfig::DEFAULT;
        let mut a = AdaptiveProductBank::<T>::new(&cfg, &f).unwrap();
        let wn0 = f64::from(f.ilo1_c) * libm::pow(3.68e6 / (0.001 * 0.01), 1.0 / 6.0);
        assert!((wn0 - 52.9).abs() < 0.1, "{wn0}");
        assert!((a.ilo1_wn().unwrap() / wn0 - 1.0).abs() < 1e-6);
        let mut start = cfg;
        start.velocity.ilo[0] = IloConfig::per_sample_alias(
            wn0,
            f64::from(f.ilo1_zeta),
            f.ilo1_alias,
            f64::from(cfg.h),
            0.01,
        )
        .unwrap();
        assert_eq!(a.config(), &start);
        let mut b = crate::ProductBank::<T>::new(&start).unwrap();
        let mut g = Gauss::new(11);
        for k in 0..2000 {
            let (t, y, _) = noisy_sine(k, 200.0, 1.0, 0.1, &mut g);
            let (oa, ob) = (a.update(t, y).unwrap(), b.update(t, y).unwrap());
            assert_eq!(oa, ob, "sample {k}");
        }
        assert_eq!(a.retune_count(), 0);
        assert!((a.ilo1_wn().unwrap() / wn0 - 1.0).abs() < 1e-6);
        assert!(a.estimates().0.is_some() && a.estimates().1.is_none());
    }
    check::<f32>();
    check::<crate::Fx>();
}

/// ILO1 runs through the configured alias while the sample interval is steady, and through
/// the first once it jitters: intervals of 9 and 11 ms in turn (a jitter of 0.1, computed
/// here again from the intervals' mean deviation) against a steady 10 ms. One sample in
/// seven dropped (an interval of two periods) is no jitter. Without any rate (no estimate of
/// the jerk) the alias falls back all the same, at the start's bandwidth.
#[test]
fn a_jittering_interval_puts_ilo1_at_the_first_alias() {
    let cfg = crate::BankConfig::NAV440;
    let f = AdaptiveProductConfig::DEFAULT;
    let run = |jitter_us: u64, with_rate: bool| {
        let mut a = AdaptiveProductBank::<f32>::new(&cfg, &f).unwrap();
        assert_eq!(a.ilo1_alias(), AdaptiveProductConfig::ILO1_ALIAS);
        let mut g = Gauss::new(13);
        for k in 0..600 {
            let (t, y, r) = noisy_sine(k, 100.0, 1.0, 0.1, &mut g);
            let t = t + (k % 2) * jitter_us;
            if jitter_us == 0 && k % 7 == 3 {
                continue;
            }
            if with_rate {
                a.observe_rate(t, r);
            }
            a.update(t, y).unwrap();
        }
        (a.ilo1_alias(), a.interval_jitter().unwrap(), a.ilo1_wn())
    };
    let (alias, jitter, _) = run(0, true);
    assert_eq!((alias, jitter), (AdaptiveProductConfig::ILO1_ALIAS, 0.0));
    let (alias, jitter, _) = run(1_000, true);
    assert_eq!(alias, 1);
    assert!((jitter - 0.1).abs() < 1e-3, "{jitter}");
    let start = AdaptiveProductBank::<f32>::new(&cfg, &f).unwrap().ilo1_wn();
    let (alias, _, wn) = run(1_000, false);
    assert_eq!((alias, wn), (1, start));
}

/// With the rate, ILO1's bandwidth is the rule's for the bank's own estimates, computed here
/// again from them: `wn = c (J / (V dt))^(1/6)` within the retune ratio (it moves only when
/// the rule moved by more), and the Kalman's `q / r` is `kappa J / V` within its ratio. A
/// faster motion (8x the jerk power at the same noise) gets a bandwidth 8^(1/6) = 1.41 times
/// higher, within the ratio.
#[test]
fn the_adaptive_product_bank_follows_its_estimates() {
    let cfg = crate::BankConfig::NAV440;
    let f = AdaptiveProductConfig::DEFAULT;
    let run = |amp: f64| {
        let mut a = AdaptiveProductBank::<f32>::new(&cfg, &f).unwrap();
        let mut g = Gauss::new(12);
        // The rule for the estimates and the gains, over the last `retune_every` samples: one
        // of them is the last gain check (the estimates move on between checks).
        let n = 3000;
        extern crate std;
        let mut last = std::vec::Vec::new();
        for k in 0..n {
            let (t, y, r) = noisy_sine(k, amp, 1.0, 0.1, &mut g);
            a.observe_rate(t, r);
            a.update(t, y).unwrap();
            if k + u64::from(f.retune_every) >= n {
                let (v, j) = a.estimates();
                let (v, j) = (f64::from(v.unwrap()), f64::from(j.unwrap()));
                let rule = f64::from(f.ilo1_c) * libm::pow(j / (v * 0.01), 1.0 / 6.0);
                let kf = a.config().acceleration.kf;
                let q_ratio = f64::from(kf.q / kf.r) / (f64::from(f.kappa_s) * j / v);
                last.push((rule, a.ilo1_wn().unwrap(), q_ratio));
            }
        }
        assert!(
            last.iter()
                .any(|(rule, wn, _)| wn / rule <= 1.2 && rule / wn <= 1.2),
            "amplitude {amp}: (rule, wn, q/r ratio) {last:?}"
        );
        assert!(
            last.iter().any(|(_, _, q)| (1.0 / 1.5..=1.5).contains(q)),
            "amplitude {amp}: (rule, wn, q/r ratio) {last:?}"
        );
        let (rule, wn, _) = last[last.len() - 1];
        assert!(a.retune_count() >= 1);
        (rule, wn)
    };
    let (slow, _) = run(100.0);
    let (fast, _) = run(100.0 * 8f64.sqrt());
    let r = fast / slow / 8f64.powf(1.0 / 6.0);
    assert!((0.9..1.1).contains(&r), "{r}");
}

/// The angle given as a sensor's integers (`update_scaled`) gives the same outputs as the
/// same angle as `f32`, in `Fx` (an angle that `f32` holds exactly).
#[test]
fn the_adaptive_product_bank_takes_scaled_angles() {
    use crate::EstimatorBank;
    let cfg = crate::BankConfig::NAV440;
    let f = AdaptiveProductConfig::DEFAULT;
    let mut a = AdaptiveProductBank::<crate::Fx>::new(&cfg, &f).unwrap();
    let mut b = AdaptiveProductBank::<crate::Fx>::new(&cfg, &f).unwrap();
    let mut g = Gauss::new(13);
    for k in 0..2000 {
        let (t, y, r) = noisy_sine(k, 150.0, 2.0, 0.1, &mut g);
        // The NAV440's angle LSB, 360/2^16 deg = 45 * 2^-13.
        let lsb = libm::round(f64::from(y) / (360.0 / 65536.0)) as i32;
        let y = (f64::from(lsb) * 360.0 / 65536.0) as f32;
        a.observe_rate(t, r);
        b.observe_rate(t, r);
        let oa = EstimatorBank::update_scaled(&mut a, t, 45 * lsb, -13).unwrap();
        let ob = EstimatorBank::update(&mut b, t, y).unwrap();
        assert_eq!(oa, ob, "sample {k}");
    }
    assert!(a.retune_count() >= 1);
}

/// What [`SelfTuneConfig`] refuses.
#[test]
fn self_tune_config_is_checked() {
    let cfg = crate::BankConfig::NAV440;
    let with = |f: fn(&mut SelfTuneConfig)| {
        let mut c = SelfTuneConfig::DEFAULT;
        f(&mut c);
        SelfTuningProductBank::<f32>::new(&cfg, &c).err()
    };
    assert_eq!(with(|_| {}), None);
    assert_eq!(
        with(|c| c.wn0_rad_s = f32::NAN),
        Some(ConfigError::NotFinite("wn0_rad_s"))
    );
    assert_eq!(
        with(|c| c.zeta = 0.0),
        Some(ConfigError::NotPositive("zeta"))
    );
    assert_eq!(with(|c| c.zeta = 1.0), Some(ConfigError::ObserverPoles));
    assert_eq!(
        with(|c| c.step = 1.0),
        Some(ConfigError::NotPositive("step"))
    );
    assert_eq!(
        with(|c| c.min_step = 2.0),
        Some(ConfigError::NotPositive("step - min_step"))
    );
    assert_eq!(
        with(|c| c.margin = -0.1),
        Some(ConfigError::Negative("margin"))
    );
    assert_eq!(
        with(|c| c.margin = 1.0),
        Some(ConfigError::NotPositive("1 - margin"))
    );
    assert_eq!(
        with(|c| c.window = 0),
        Some(ConfigError::NotPositive("window"))
    );
    assert_eq!(
        with(|c| c.settled_after = 0),
        Some(ConfigError::NotPositive("settled_after"))
    );
    assert_eq!(
        with(|c| c.span = 0.5),
        Some(ConfigError::NotPositive("span - 1"))
    );
}

/// The product bank with ILO1's per-sample poles at `wn` rad/s and `zeta`.
fn product_at<T: Real>(cfg: &crate::BankConfig, wn: f64, zeta: f64) -> crate::ProductBank<T> {
    let mut c = *cfg;
    c.velocity.ilo[0] = IloConfig::per_sample(wn, zeta, f64::from(c.h), 0.01).unwrap();
    crate::ProductBank::new(&c).unwrap()
}

/// Without a rate, or with rates of other times only, the self-tuning bank never moves and is
/// the product bank at its starting poles, bit for bit (f32 and `Fx`; the angle as `f32` and
/// as a sensor's integers).
#[test]
fn without_a_valid_rate_the_self_tuning_bank_never_moves() {
    fn check<T: Real>() {
        use crate::EstimatorBank;
        let cfg = crate::BankConfig::NAV440;
        let tune = SelfTuneConfig::DEFAULT;
        let mut a = SelfTuningProductBank::<T>::new(&cfg, &tune).unwrap();
        let mut b = SelfTuningProductBank::<T>::new(&cfg, &tune).unwrap();
        let mut c = product_at::<T>(&cfg, 25.5, 0.25);
        let mut g = Gauss::new(21);
        for k in 0..3000 {
            let (t, y, r) = noisy_sine(k, 300.0, 2.0, 0.01, &mut g);
            // a: no rate; b: the rate of the time before, or not finite.
            b.observe_rate(t.saturating_sub(1), r);
            if k % 2 == 0 {
                b.observe_rate(t, f32::NAN);
            }
            let lsb = libm::round(f64::from(y) / (360.0 / 65536.0)) as i32;
            let oa = EstimatorBank::update_scaled(&mut a, t, 45 * lsb, -13).unwrap();
            let ob = EstimatorBank::update_scaled(&mut b, t, 45 * lsb, -13).unwrap();
            let oc = EstimatorBank::update_scaled(&mut c, t, 45 * lsb, -13).unwrap();
            assert_eq!((oa, ob), (oc, oc), "sample {k}");
        }
        for s in [&a, &b] {
            assert_eq!((s.move_count(), s.settle_count()), (0, 0));
            assert_eq!(s.gains(), (25.5, 0.25));
        }
    }
    check::<f32>();
    check::<crate::Fx>();
}

/// With the exact rate of a fast noise-free motion (2 Hz, 380 deg/s), the self-tuning bank
/// climbs from its default start, one step per window at most, within the validated range; the bank that
/// runs is a [`crate::ProductBank`] whose gains are set ([`crate::ProductBank::set_gains`],
/// bumpless) at the same samples, bit for bit; and over the last 10 s its velocity error is a
/// fraction of what the starting gains give on the same samples.
#[test]
fn the_self_tuning_bank_climbs_to_a_fast_motion_one_step_per_window() {
    let cfg = crate::BankConfig::NAV440;
    let tune = SelfTuneConfig::DEFAULT;
    let mut a = SelfTuningProductBank::<f32>::new(&cfg, &tune).unwrap();
    let mut replica = product_at::<f32>(&cfg, 25.5, 0.25);
    let mut start = product_at::<f32>(&cfg, 25.5, 0.25);
    let mut g = Gauss::new(22);
    let (mut err_a, mut err_start, mut moves) = (0.0, 0.0, 0);
    let n = 4000;
    for k in 0..n {
        let (t, y, r) = noisy_sine(k, 30.0, 2.0, 0.0, &mut g);
        a.observe_rate(t, r);
        let before = a.move_count();
        let oa = a.update(t, y).unwrap();
        let or = replica.update(t, y).unwrap();
        assert_eq!(oa, or, "sample {k}");
        if a.move_count() != before {
            moves += 1;
            replica.set_gains(&a.config()).unwrap();
        }
        let os = start.update(t, y).unwrap();
        if k >= n - 1000 {
            err_a += (f64::from(oa.values[0]) - f64::from(r)).powi(2);
            err_start += (f64::from(os.values[0]) - f64::from(r)).powi(2);
        }
        let (wn, zeta) = a.gains();
        let wd = wn * libm::sqrt(1.0 - zeta * zeta);
        assert!(
            wn >= 2.0 && wd <= 0.8 * core::f64::consts::PI / f64::from(0.01f32) * (1.0 + 1e-12),
            "{wn} {zeta}"
        );
        assert!((0.05..=0.9).contains(&zeta));
    }
    // A window is 50 settling and 200 compared samples: at most one move per 250 samples.
    assert!(moves >= 3 && moves <= n / 250, "{moves} moves");
    assert_eq!(a.move_count(), moves as u32);
    let (wn, _) = a.gains();
    assert!(wn > 50.0, "wn {wn}");
    assert!(err_a < err_start / 10.0, "{err_a} vs {err_start}");
}

/// On a slow motion under heavy noise, started far too fast (200 rad/s), the self-tuning bank
/// descends and settles; the gains it reports are those it runs.
#[test]
fn the_self_tuning_bank_descends_under_noise_and_settles() {
    let cfg = crate::BankConfig::NAV440;
    let tune = SelfTuneConfig {
        wn0_rad_s: 200.0,
        ..SelfTuneConfig::DEFAULT
    };
    let mut a = SelfTuningProductBank::<f32>::new(&cfg, &tune).unwrap();
    let mut g = Gauss::new(23);
    for k in 0..12_000 {
        let (t, y, r) = noisy_sine(k, 30.0, 0.2, 0.5, &mut g);
        a.observe_rate(t, r);
        a.update(t, y).unwrap();
    }
    let (wn, zeta) = a.gains();
    assert!(wn < 50.0, "wn {wn}");
    assert!(a.settle_count() >= 1);
    if let Some(s) = a.settled() {
        assert_eq!((s.wn_rad_s, s.zeta), (wn as f32, zeta as f32));
        assert_eq!(a.config().velocity.ilo[0], s.ilo1);
    }
}

/// Settled on a slow noisy motion, the self-tuning bank follows when the motion turns fast
/// and quiet: its step grows back on moves the same way, and within 60 s its velocity error is
/// a fraction of what the gains it had settled at give on the same samples.
#[test]
fn the_self_tuning_bank_follows_a_change_of_motion() {
    let cfg = crate::BankConfig::NAV440;
    let mut a = SelfTuningProductBank::<f32>::new(&cfg, &SelfTuneConfig::DEFAULT).unwrap();
    let mut g = Gauss::new(24);
    let n = 6000;
    for k in 0..n {
        let (t, y, r) = noisy_sine(k, 30.0, 0.2, 0.5, &mut g);
        a.observe_rate(t, r);
        a.update(t, y).unwrap();
    }
    assert!(a.settle_count() >= 1);
    let (slow_wn, slow_zeta) = a.gains();
    let mut before = product_at::<f32>(&cfg, slow_wn, slow_zeta);
    let (mut err_a, mut err_before) = (0.0, 0.0);
    for k in n..2 * n {
        let (t, y, r) = noisy_sine(k, 30.0, 2.0, 0.01, &mut g);
        a.observe_rate(t, r);
        let oa = a.update(t, y).unwrap();
        let ob = before.update(t, y).unwrap();
        if k >= 2 * n - 1000 {
            err_a += (f64::from(oa.values[0]) - f64::from(r)).powi(2);
            err_before += (f64::from(ob.values[0]) - f64::from(r)).powi(2);
        }
    }
    let (wn, _) = a.gains();
    assert!(wn > 2.0 * slow_wn, "wn {slow_wn} -> {wn}");
    assert!(err_a < err_before / 5.0, "{err_a} vs {err_before}");
}

/// At the NAV440's lowest packet rate (2 Hz) the start (25.5 rad/s) is beyond the damped
/// frequency's limit (80 % of Nyquist, 5.03 rad/s): the bank starts within every bound, the
/// damping in [0.05, 0.9]; and so does a bank that takes over from one tuned at 100 Hz.
#[test]
fn the_self_tuning_bank_starts_within_its_bounds_at_2_hz() {
    use crate::EstimatorBank;
    let within = |b: &SelfTuningProductBank<f32>, dt: f64| {
        let (wn, zeta) = b.gains();
        let wd = wn * libm::sqrt(1.0 - zeta * zeta);
        assert!((0.05..=0.9).contains(&zeta), "zeta {zeta}");
        assert!(wn >= 2.0 && wd <= 0.8 * core::f64::consts::PI / dt * (1.0 + 1e-12));
    };
    let mut slow = crate::BankConfig::NAV440;
    slow.sample_period_s = 0.5;
    let slow = slow.with_nav440_gains();
    let tune = SelfTuneConfig::DEFAULT;
    let mut a = SelfTuningProductBank::<f32>::new(&slow, &tune).unwrap();
    within(&a, f64::from(0.5f32));
    let fast = SelfTuningProductBank::<f32>::new(
        &crate::BankConfig::NAV440,
        &SelfTuneConfig {
            wn0_rad_s: 129.0,
            ..tune
        },
    )
    .unwrap();
    a.take_over(&fast);
    within(&a, f64::from(0.5f32));
}

/// The jerk power and the acceleration power of [`on_the_sine`]'s motion, measured.
fn sine_powers() -> (f32, f32) {
    let w = 2.0 * core::f64::consts::PI;
    let mut measured = JerkEstimator::new(1e12, 0.01).unwrap().with_acceleration();
    for k in 0..2000u64 {
        let t = k as f64 * 0.01;
        measured.update(k * 10_000, (20.0 * w * libm::cos(w * t)) as f32);
    }
    (
        measured.power().unwrap(),
        measured.acceleration_power().unwrap(),
    )
}

/// The paper bank following `schedule` on 20 s of a 1 Hz sine of 20 deg at 100 Hz with
/// N(0, 0.1) deg^2 of noise (seed 5), given the sine's rate when `rates`.
fn on_the_sine(schedule: &GainSchedule, rates: bool) -> AdaptiveBank<f32> {
    on_the_sine_for(schedule, rates, 2000)
}

/// [`on_the_sine`] for `samples` samples.
fn on_the_sine_for(schedule: &GainSchedule, rates: bool, samples: u64) -> AdaptiveBank<f32> {
    let w = 2.0 * core::f64::consts::PI;
    let mut b =
        AdaptiveBank::<f32>::new(&BankConfig::PAPER, schedule, &AdaptiveConfig::DEFAULT).unwrap();
    let mut g = Gauss::new(5);
    for k in 0..samples {
        let t = k as f64 * 0.01;
        let y = 20.0 * libm::sin(w * t) + libm::sqrt(0.1) * g.next();
        if rates {
            b.observe_rate(k * 10_000, (20.0 * w * libm::cos(w * t)) as f32);
        }
        b.update(k * 10_000, y as f32).unwrap();
    }
    b
}

/// A schedule that records its tuning motion's jerk power follows the motion as well as the
/// noise: on a 1 Hz sine of 20 deg (jerk power `(20 (2 pi)^3)^2 / 2` = 1.23e7 (deg/s^3)^2)
/// with N(0, 0.1) deg^2 of noise, tuned on a motion 100 times gentler, the gains go to the
/// level `0.1 x 8 / 100` = 0.008 deg^2 (the margin 8 of `AdaptiveConfig::jerk_margin`);
/// tuned on a motion 40 times harder, up to `0.1 x 40 / 8` = 0.5 deg^2; tuned on this very
/// motion or one 4 times harder, or given no rate, or without the record, they stay at the
/// noise's 0.1. Records that are not finite and positive, and margins below 1, are refused.
#[test]
fn a_schedule_with_its_tuning_jerk_follows_the_motion() {
    let s = GainSchedule::new(&[
        level(0.001, 100.0, ILO1_TABLE2),
        level(0.1, 1000.0, ILO1_TABLE2),
    ])
    .unwrap();
    assert_eq!(s.tuned_jerk(), None);
    for bad in [f32::NAN, f32::INFINITY] {
        assert_eq!(
            s.with_tuned_jerk(bad),
            Err(ConfigError::NotFinite("tuned_jerk_power"))
        );
    }
    for bad in [0.0, -1.0] {
        assert_eq!(
            s.with_tuned_jerk(bad),
            Err(ConfigError::NotPositive("tuned_jerk_power"))
        );
    }
    let w = 2.0 * core::f64::consts::PI;
    let j = (20.0 * w * w * w).powi(2) / 2.0;
    let run = |schedule: &GainSchedule, rates: bool| {
        let b = on_the_sine(schedule, rates);
        (b.gain_level(), b.jerk_power())
    };
    let wide = GainSchedule::new(&[
        level(0.001, 100.0, ILO1_TABLE2),
        level(0.1, 1000.0, ILO1_TABLE2),
        level(1.0, 2000.0, ILO1_TABLE2),
    ])
    .unwrap();
    let gentle = s.with_tuned_jerk((j / 100.0) as f32).unwrap();
    let (level, power) = run(&gentle, true);
    let power = f64::from(power.unwrap());
    assert!((power / j - 1.0).abs() < 0.05, "{power} vs {j}");
    assert!(level > 0.005 && level < 0.012, "{level}");
    let same = s.with_tuned_jerk(j as f32).unwrap();
    for (schedule, rates) in [(&same, true), (&gentle, false), (&s, true)] {
        let (level, _) = run(schedule, rates);
        assert!(level > 0.08, "{level} {rates}");
    }
    // Tuned on a motion 40 times harder (this one moves less than 1/8 as hard): the gains go
    // up to the level `0.1 x 40 / 8` = 0.5 deg^2; 4 times harder (within the margin): the
    // noise's 0.1; each within the retune band (`AdaptiveConfig::retune_ratio`, 1.5).
    let (up, _) = run(&wide.with_tuned_jerk((j * 40.0) as f32).unwrap(), true);
    assert!(up > 0.5 / 1.5 && up < 0.5 * 1.5, "{up}");
    let (kept, _) = run(&wide.with_tuned_jerk((j * 4.0) as f32).unwrap(), true);
    assert!(kept > 0.1 / 1.5 && kept < 0.1 * 1.5, "{kept}");
    for bad in [0.5, f32::NAN] {
        let cfg = AdaptiveConfig {
            jerk_margin: bad,
            ..AdaptiveConfig::DEFAULT
        };
        assert_eq!(
            AdaptiveBank::<f32>::new(&BankConfig::PAPER, &gentle, &cfg).err(),
            Some(ConfigError::NotPositive("jerk_margin"))
        );
    }
}

/// Each family follows its own measure of the motion (`Follows`): on the sine of
/// [`a_schedule_with_its_tuning_jerk_follows_the_motion`] with N(0, 0.1) deg^2 of noise, a
/// schedule that records a jerk power 16 times this motion's and an acceleration power 4 times
/// its own (both as a `JerkEstimator` measures them over the run) raises the observers to
/// `0.1 x 16 / 8` = 0.2 deg^2 (margin 8), the tracker to `0.1 x 16 / 4` = 0.4 (margin 4,
/// `AdaptiveConfig::smooth_jerk_margin`) and the AD to `0.1 x 4` = 0.4 (the acceleration, no
/// margin); with a jerk power twice this motion's (within both margins) and an acceleration
/// power a tenth of its own, the observers and the tracker stay at the noise's 0.1 and the AD
/// goes down to 0.01; without the acceleration record the AD follows the jerk as the tracker
/// does. Each level within the retune band (`AdaptiveConfig::retune_ratio`, 1.5). A smooth
/// margin below 1 and an acceleration record that is not finite and positive are refused.
#[test]
fn each_family_follows_its_own_measure_of_the_motion() {
    let s = GainSchedule::new(&[
        level(0.001, 100.0, ILO1_TABLE2),
        level(0.1, 1000.0, ILO1_TABLE2),
        level(1.0, 2000.0, ILO1_TABLE2),
    ])
    .unwrap();
    assert_eq!(s.tuned_acceleration(), None);
    assert_eq!(
        s.with_tuned_acceleration(f32::NAN),
        Err(ConfigError::NotFinite("tuned_acceleration_power"))
    );
    assert_eq!(
        s.with_tuned_acceleration(0.0),
        Err(ConfigError::NotPositive("tuned_acceleration_power"))
    );
    let (j, a) = sine_powers();
    let run = |schedule: &GainSchedule| on_the_sine(schedule, true).gain_levels();
    let column = |label: &str| {
        crate::FAMILIES
            .iter()
            .position(|f| f.label == label)
            .unwrap()
    };
    let (ave, ilo1, ad, ed, kf) = (
        column("AVE"),
        column("ILO1"),
        column("AD"),
        column("ED"),
        column("KF"),
    );
    let near = |levels: &Levels, col: usize, want: f32| {
        let l = levels.0[col];
        assert!(l > want / 1.5 && l < want * 1.5, "{col}: {l} vs {want}");
    };
    let harder = s
        .with_tuned_jerk(16.0 * j)
        .unwrap()
        .with_tuned_acceleration(4.0 * a)
        .unwrap();
    let l = run(&harder);
    for col in [ave, ilo1, ed] {
        near(&l, col, 0.2);
    }
    near(&l, kf, 0.4);
    near(&l, ad, 0.4);
    let gentler = s
        .with_tuned_jerk(2.0 * j)
        .unwrap()
        .with_tuned_acceleration(0.1 * a)
        .unwrap();
    let l = run(&gentler);
    for col in [ave, ilo1, ed, kf] {
        near(&l, col, 0.1);
    }
    near(&l, ad, 0.01);
    let jerk_only = run(&s.with_tuned_jerk(16.0 * j).unwrap());
    near(&jerk_only, ad, 0.4);
    near(&jerk_only, kf, 0.4);
    let cfg = AdaptiveConfig {
        smooth_jerk_margin: 0.5,
        ..AdaptiveConfig::DEFAULT
    };
    assert_eq!(
        AdaptiveBank::<f32>::new(&BankConfig::PAPER, &harder, &cfg).err(),
        Some(ConfigError::NotPositive("smooth_jerk_margin"))
    );
}

/// The gains of each family come from the level its own noise variance picks
/// (`GainSchedule::gains_for`): the AD's from the upper level and every other family's from
/// the lower one, or the other way round, as `gains_at` gives each level's.
#[test]
fn gains_for_takes_each_family_from_its_own_level() {
    let with_ad = |mut l: ScheduleLevel, t: f32| {
        l.velocity.ad_t = t;
        l.acceleration.ad_t = 2.0 * t;
        l
    };
    let s = GainSchedule::new(&[
        with_ad(level(0.01, 100.0, ILO1_TABLE2), 0.01),
        with_ad(level(1.0, 2000.0, ILO3_TABLE2), 0.05),
    ])
    .unwrap();
    let ad = crate::FAMILIES
        .iter()
        .position(|f| f.label == "AD")
        .unwrap();
    let (lo, hi) = (s.gains_at(0.01), s.gains_at(1.0));
    let mut levels = Levels::all(0.01);
    levels.0[ad] = 1.0;
    let (v, acc) = s.gains_for(levels);
    assert_eq!((hi.0.ad_t, hi.1.ad_t), (0.05, 0.1));
    assert_eq!(v.ad_t, hi.0.ad_t);
    assert_eq!(acc.ad_t, hi.1.ad_t);
    assert_eq!((v.ave, v.ilo), (lo.0.ave, lo.0.ilo));
    let mut levels = Levels::all(1.0);
    levels.0[ad] = 0.01;
    let (v, _) = s.gains_for(levels);
    assert_eq!(v.ad_t, lo.0.ad_t);
    assert_eq!((v.ave, v.ilo), (hi.0.ave, hi.0.ilo));
    assert_eq!(s.gains_for(Levels::all(0.3)), s.gains_at(0.3));
}

/// A restart of the laws: a steady rate (no jerk: the rule's bandwidth falls to its lowest,
/// 2 rad/s, with the rate given) of 200 deg/s for 10 s, then the rate turns to -200 deg/s
/// across a new epoch, or across a gap of 0.5 s (over the gap rule's 0.25 s: the bank
/// re-initialises). ILO1 restarts from 0 at the start's gains, `ilo1_wn()` 52.9 rad/s
/// (within 1 %), and is within 10 % of the rate 0.2 s later; once settled (0.26 s), the gains
/// follow the estimates again, back to the lowest bandwidth, and 1 s after the restart ILO1 is
/// still within 10 %. (Restarting at the lowest bandwidth instead, measured once with the
/// restart disabled: -74 deg/s after 0.3 s, -253 after 1 s.)
#[test]
fn a_restart_runs_at_the_start_gains_until_it_settles() {
    let cfg = crate::BankConfig::NAV440;
    let f = AdaptiveProductConfig::DEFAULT;
    for gap in [false, true] {
        let mut a = AdaptiveProductBank::<f32>::new(&cfg, &f).unwrap();
        let mut g = Gauss::new(14);
        let mut t_us = 0u64;
        let mut angle = 0.0f64;
        let mut feed = |a: &mut AdaptiveProductBank<f32>, t_us: u64, angle: f64, rate: f64| {
            let y = angle + 0.1 * g.next();
            let wrapped = y - 360.0 * libm::round(y / 360.0);
            a.observe_rate(t_us, rate as f32);
            a.update(t_us, wrapped as f32).unwrap()
        };
        for _ in 0..1000 {
            t_us += 10_000;
            angle += 2.0;
            feed(&mut a, t_us, angle, 200.0);
        }
        let low = a.ilo1_wn().unwrap();
        assert!(low < 2.5, "gap {gap}: wn {low} on a steady rate");
        if gap {
            t_us += 500_000;
            angle -= 100.0;
        } else {
            a.new_epoch();
            t_us += 10_000;
            angle -= 2.0;
        }
        let first = feed(&mut a, t_us, angle, -200.0);
        assert_eq!(first.values[0], 0.0, "gap {gap}: the restart starts from 0");
        let start = a.ilo1_wn().unwrap();
        assert!((start / 52.9 - 1.0).abs() < 0.01, "gap {gap}: wn {start}");
        let mut v = 0.0;
        for k in 1..=100 {
            t_us += 10_000;
            angle -= 2.0;
            v = feed(&mut a, t_us, angle, -200.0).values[0];
            if k == 20 {
                assert!((v + 200.0).abs() < 20.0, "gap {gap}: {v} deg/s after 0.2 s");
                assert_eq!(a.ilo1_wn(), Some(start), "gap {gap}: still the start's");
            }
        }
        assert!(a.ilo1_wn().unwrap() < 2.5, "gap {gap}: {:?}", a.ilo1_wn());
        assert!((v + 200.0).abs() < 20.0, "gap {gap}: {v} deg/s after 1 s");
    }
}

/// Past the top level (beyond 8 times its noise variance) the ILOs and the ED go on: on the
/// 1 Hz sine of 20 deg with N(0, 0.1) deg^2 of noise, tuned on a motion 1,000 times harder
/// (level `0.1 x 1000 / 8` = 12.5 deg^2, past `8 x 0.1`), once the jerk estimate has run for
/// its time constant (5 s), each ILO runs `IloConfig::per_sample` at the rule's bandwidth
/// (`K1 = 1`: it holds a constant rate), the ED the top level's `alpha` halved (the
/// acceleration ratio 1/16 gives `sqrt` 1/4, floored at `ED_PAST_TOP_MIN`) and `lambda` by
/// `sqrt(1/2)`, every other family the top level's. Before the jerk estimate has run that
/// long, or for a motion only 40 times gentler (0.5 deg^2: past the top, within 8 times it), or for a schedule without a
/// recorded tuning jerk, every family has the top level's gains.
#[test]
fn past_the_top_level_the_ilos_and_the_ed_go_on() {
    let s = GainSchedule::new(&[
        level(0.001, 100.0, ILO1_TABLE2),
        level(0.1, 1000.0, ILO1_TABLE2),
    ])
    .unwrap();
    let top = s.gains_at(0.1);
    let (j, a) = sine_powers();
    let gentle = s
        .with_tuned_jerk(1000.0 * j)
        .unwrap()
        .with_tuned_acceleration(16.0 * a)
        .unwrap();
    let run = |schedule: &GainSchedule, samples: u64| on_the_sine_for(schedule, true, samples);
    let b = run(&gentle, 2000);
    let ilo1 = crate::FAMILIES
        .iter()
        .position(|f| f.label == "ILO1")
        .unwrap();
    let level = b.gain_levels().0[ilo1];
    assert!(level > 12.5 / 1.5 && level < 12.5 * 1.5, "{level}");
    let wn = past_top_wn(1000.0 * j, level, 0.01);
    let zeta = f64::from(SelfTuneConfig::ZETA);
    let rule = IloConfig::per_sample(wn, zeta, 1e-4, 0.01).unwrap();
    let (velocity, acceleration) = b.gains;
    assert_eq!(velocity.ilo, [rule; 3]);
    assert_eq!(rule.k1, 1.0);
    assert_eq!(rule.constant_rate_gain(), 1.0);
    assert!(
        wn > product::WN_MIN && wn < 0.5 * core::f64::consts::PI / 0.01,
        "{wn}"
    );
    let floor = crate::ed::ED_PAST_TOP_MIN;
    assert_eq!(velocity.ed.alpha, top.0.ed.alpha * floor);
    let lambda = top.0.ed.lambda * libm::sqrtf(floor);
    assert!((velocity.ed.lambda / lambda - 1.0).abs() < 1e-6);
    let rest = |g: &BankGains| BankGains {
        ilo: top.0.ilo,
        ed: top.0.ed,
        ..*g
    };
    assert_eq!(rest(&velocity), top.0);
    assert_eq!(acceleration, top.1);
    // The jerk estimate after 3 s has not run its 5 s time constant.
    assert_eq!(run(&gentle, 300).gains, top);
    let nearer = s
        .with_tuned_jerk(40.0 * j)
        .unwrap()
        .with_tuned_acceleration(16.0 * a)
        .unwrap();
    assert_eq!(run(&nearer, 2000).gains, top);
    assert_eq!(run(&s, 2000).gains, top);
}

/// Sample `k` at 100 Hz of a unit at rest until sample `onset` that then starts a 1 Hz sine
/// of 20 deg (its rate steps from 0 to 126 deg/s), with N(0, 0.1) deg^2 of noise on the
/// angle: time (us), angle (deg) and the exact rate (deg/s).
fn rest_then_sine(k: u64, onset: u64, g: &mut Gauss) -> (u64, f32, f32) {
    let w = 2.0 * core::f64::consts::PI;
    let t = k.saturating_sub(onset) as f64 * 0.01;
    let (x, r) = if k >= onset {
        (20.0 * libm::sin(w * t), 20.0 * w * libm::cos(w * t))
    } else {
        (0.0, 0.0)
    };
    let y = x + libm::sqrt(0.1) * g.next();
    (k * 10_000, y as f32, r as f32)
}

/// A motion that picks up between two retune ticks is retuned at once: a unit at rest for
/// 10 s (N(0, 0.1) deg^2 of noise, rate 0) that starts a 1 Hz sine of 20 deg (its rate
/// steps from 0 to 126 deg/s) at a sample 14 samples before the next tick (ticks every
/// `retune_every` = 20 samples), under a schedule tuned on a motion 10^4 times gentler:
/// the observers' level falls from the top (at rest) by more than the jerk margin, and the
/// gains change within 2 samples of the onset, not at the tick. Between two ticks there is
/// at most one early retune (at most two gain changes per 20 samples); a schedule that
/// follows the noise alone waits for the tick.
#[test]
fn a_motion_that_picks_up_is_retuned_at_once() {
    let s = GainSchedule::new(&[
        level(0.001, 100.0, ILO1_TABLE2),
        level(0.1, 1000.0, ILO1_TABLE2),
    ])
    .unwrap();
    let (j, _) = sine_powers();
    let gentle = s.with_tuned_jerk(j / 1e4).unwrap();
    const ONSET: u64 = 1005;
    // The retune count after each sample.
    let counts = |schedule: &GainSchedule| {
        let mut b =
            AdaptiveBank::<f32>::new(&BankConfig::PAPER, schedule, &AdaptiveConfig::DEFAULT)
                .unwrap();
        let mut g = Gauss::new(5);
        let mut counts = [0u32; 1400];
        for (k, count) in (0..1400u64).zip(counts.iter_mut()) {
            let (t_us, y, r) = rest_then_sine(k, ONSET, &mut g);
            b.observe_rate(t_us, r);
            b.update(t_us, y).unwrap();
            *count = b.retune_count();
        }
        counts
    };
    let tick = |k: u64| (k + 1).is_multiple_of(20);
    let c = counts(&gentle);
    let first = (ONSET as usize..c.len())
        .find(|&k| c[k] > c[k - 1])
        .unwrap() as u64;
    assert!(first <= ONSET + 2 && !tick(first), "{first}");
    for k in (19..c.len() - 20).step_by(20) {
        assert!(c[k + 20] - c[k] <= 2, "{k}: {} -> {}", c[k], c[k + 20]);
    }
    let c = counts(&s);
    for k in 1..c.len() {
        assert!(c[k] == c[k - 1] || tick(k as u64), "{k}");
    }
}

/// The product bank that follows the motion checks its gains at once when the motion picks
/// up: the unit of [`a_motion_that_picks_up_is_retuned_at_once`] (at rest for 10 s, then a
/// 1 Hz sine of 20 deg whose rate steps from 0 to 126 deg/s): ILO1's gains change within 2
/// samples of the onset, for two onsets 10 samples apart (ticks come every `retune_every` =
/// 20 samples, so at most one of them can be that close to a tick), and never more than
/// twice per 20 samples.
#[test]
fn the_adaptive_product_bank_follows_a_motion_that_picks_up_at_once() {
    let f = AdaptiveProductConfig::DEFAULT;
    assert_eq!(f.retune_every, 20);
    for onset in [1005u64, 1015] {
        let mut a = AdaptiveProductBank::<f32>::new(&crate::BankConfig::NAV440, &f).unwrap();
        let mut g = Gauss::new(5);
        let mut counts = [0u32; 1400];
        for (k, count) in (0..1400u64).zip(counts.iter_mut()) {
            let (t_us, y, r) = rest_then_sine(k, onset, &mut g);
            a.observe_rate(t_us, r);
            a.update(t_us, y).unwrap();
            *count = a.ilo1_retune_count();
        }
        let first = (onset as usize..counts.len())
            .find(|&k| counts[k] > counts[k - 1])
            .unwrap() as u64;
        assert!(first <= onset + 2, "{onset}: {first}");
        for k in 0..counts.len() - 20 {
            assert!(counts[k + 20] - counts[k] <= 2, "{onset}: {k}");
        }
    }
}
