//! The yaw estimator bank shared by the firmware and the host CLI.

use crate::adapter::{SampleClock, Tick};
use crate::kalman::{Kalman, KalmanConfig};
use crate::presets::*;
use crate::{
    Ad, Ave, AveConfig, ClosedForm, ConfigError, Ed, EdConfig, EdScheme, Estimator, ExactSqrt,
    Hold, Ilo, IloConfig, Real, SampleError, Series, SqrtFn, Unwrapper,
};

/// Names of the seven columns of [`BankOutput::vel`] and [`BankOutput::acc`], in order.
pub const VELOCITY_NAMES: [&str; 7] = ["ave", "ilo1", "ilo2", "ilo3", "ad", "ed", "kf"];

/// Noise model of the Kalman tracker (see [`Kalman`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KalmanNoise {
    /// White-jerk power spectral density `q`, deg^2/s^5.
    pub q: f32,
    /// Yaw measurement variance `r`, deg^2.
    pub r: f32,
}

/// Gains of one half of the bank: the velocity estimators, or the acceleration series (where
/// both stages of a series get the same gains).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BankGains {
    /// AVE.
    pub ave: AveConfig,
    /// ILO1, ILO2, ILO3 (learning delay `tau = h`, `D = 1`).
    pub ilo: [IloConfig; 3],
    /// AD time constant `T`, s.
    pub ad_t: f32,
    /// Levant ED.
    pub ed: EdConfig,
    /// Kalman tracker noise (the velocity column uses the velocity half's tracker, the
    /// acceleration column the acceleration half's).
    pub kf: KalmanNoise,
}

impl BankGains {
    /// The paper's velocity set: AVE (500, 20000), Table 2 ILOs, AD `T = 0.01`, ED (700, 770),
    /// and the default tracker noise.
    pub const PAPER_VELOCITY: Self = Self {
        ave: AVE_PAPER,
        ilo: [ILO1_TABLE2, ILO2_TABLE2, ILO3_TABLE2],
        ad_t: AD_VELOCITY_T,
        ed: ED_PAPER,
        kf: KF_DEFAULT,
    };
    /// [`Self::PAPER_VELOCITY`] with the product's AVE law ([`AVE_DEFAULT`], leaky deltahat).
    pub const DEFAULT_VELOCITY: Self = Self {
        ave: AVE_DEFAULT,
        ..Self::PAPER_VELOCITY
    };
    /// [`Self::PAPER_ACCELERATION`] with the product's AVE law ([`AVE_DEFAULT`]).
    pub const DEFAULT_ACCELERATION: Self = Self {
        ave: AVE_DEFAULT,
        ..Self::PAPER_ACCELERATION
    };
    /// The paper's acceleration set: AVE-AVE, Table 4 ILO-ILO, AD-AD `T = 0.1`, ED-ED.
    pub const PAPER_ACCELERATION: Self = Self {
        ave: AVE_PAPER,
        ilo: [ILO1_TABLE4, ILO2_TABLE4, ILO3_TABLE4],
        ad_t: AD_ACCELERATION_T,
        ed: ED_PAPER,
        kf: KF_DEFAULT,
    };
}

/// Default tracker noise (our choice, not the paper's): `r = 0.01 deg^2` (the paper's smaller
/// noise level), `q = 1e6 deg^2/s^5` (hand rotation: jerk of order 1e4 deg/s^3 over 0.1 s).
pub const KF_DEFAULT: KalmanNoise = KalmanNoise { q: 1.0e6, r: 0.01 };

/// Configuration of a [`YawBank`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BankConfig {
    /// Step `h` of every law, s; a whole number of microseconds. Default `1e-4` (paper).
    pub h: f32,
    /// How samples are presented between sample instants. Default [`Hold::Linear`].
    pub hold: Hold,
    /// Gap rule: the longest sample interval integrated across, in nominal sample periods
    /// ([`BankConfig::sample_period_s`]); a longer gap re-initialises the bank from the new
    /// sample. Default [`GAP_PERIODS`] (25: 0.25 s at 100 Hz, 12.5 s at 2 Hz).
    pub max_gap_periods: f32,
    /// Nominal sample period, s (default 0.01 = 100 Hz): the closed-form maps are precomputed
    /// for `round(sample_period_s / h)` steps and the Kalman gains for this period.
    /// `nav440_pipeline::period` sets it from a stream's first samples (host CLI and firmware).
    pub sample_period_s: f32,
    /// Use the exact closed-form multi-step maps for the linear laws (default `true`); `false`
    /// steps every law `n` times (same results to rounding).
    pub closed_form: bool,
    /// Discretisation of the ED and ED-ED (default [`EdScheme::Euler`], the paper's).
    pub ed_scheme: EdScheme,
    /// Velocity estimators' gains.
    pub velocity: BankGains,
    /// Acceleration series' gains.
    pub acceleration: BankGains,
}

impl BankConfig {
    /// The product default ([`Default`]): [`BankConfig::PAPER`] with the leaky AVE law
    /// ([`AVE_DEFAULT`]) in the AVE and AVE-AVE, which does not degrade over long runs.
    pub const DEFAULT: Self = Self {
        velocity: BankGains::DEFAULT_VELOCITY,
        acceleration: BankGains::DEFAULT_ACCELERATION,
        ..Self::PAPER
    };
    /// The paper's configuration, every law as published (AVE `deltahat` only grows).
    pub const PAPER: Self = Self {
        h: H_PAPER,
        hold: Hold::Linear,
        max_gap_periods: GAP_PERIODS,
        sample_period_s: 0.01,
        closed_form: true,
        ed_scheme: EdScheme::Euler,
        velocity: BankGains::PAPER_VELOCITY,
        acceleration: BankGains::PAPER_ACCELERATION,
    };
}

impl BankConfig {
    /// The gap rule in seconds: `max_gap_periods * sample_period_s` (computed in f64).
    pub fn max_gap_s(&self) -> f32 {
        (f64::from(self.max_gap_periods) * f64::from(self.sample_period_s)) as f32
    }
}

/// Default gap rule, in nominal sample periods: 25 (the former fixed 0.25 s at 100 Hz). The
/// bank integrates across up to 24 lost packets at any packet rate.
pub const GAP_PERIODS: f32 = 25.0;

impl Default for BankConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// One output row of the bank.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BankOutput {
    /// The unwrapped yaw, deg, rounded to f32 (see [`BankOutput::yaw_residual_deg`]).
    pub yaw_unwrapped_deg: f32,
    /// What f32 rounding took off the unwrapped yaw, deg: the exact unwrapped yaw is
    /// `yaw_unwrapped_deg as f64 + yaw_residual_deg` (0 while f32 holds it exactly; exact in
    /// f64 for NAV440 yaw, a multiple of 360/2^16 deg, up to 2^33 turns).
    pub yaw_residual_deg: f64,
    /// Velocity estimates, deg/s, in the order of [`VELOCITY_NAMES`]: ave, ilo1, ilo2, ilo3,
    /// ad, ed, kf.
    pub vel: [f32; 7],
    /// Acceleration estimates, deg/s^2, same order (series AVE-AVE, ILO-ILO (Table 4),
    /// AD-AD (T = 0.1), ED-ED, Kalman).
    pub acc: [f32; 7],
}

/// The unwrapped yaw `360 turns + wrapped` (deg) as (f32 rounding, exact residual in f64).
fn exact_yaw<T: Real>(turns: i64, wrapped: T) -> (f32, f64) {
    let exact = turns as f64 * 360.0 + wrapped.to_f64();
    let rounded = exact as f32;
    (rounded, exact - f64::from(rounded))
}

type IloCf<T> = ClosedForm<T, Ilo<T, 1>>;
type Ilo2Cf<T> = ClosedForm<T, Series<Ilo<T, 1>, Ilo<T, 1>>>;

/// The whole estimator bank for one yaw axis: unwrap -> sample adapter -> AVE, ILO1-3
/// (Table 2), AD (T = 0.01), ED (700/770), Kalman for velocity, and AVE-AVE, ILO1-3-ILO1-3
/// (Table 4), AD-AD (T = 0.1), ED-ED, Kalman for acceleration.
///
/// Generic over [`Real`]: `YawBank<f32>` for FPU targets, `YawBank<Fx>` for Cortex-M0/M3 (the
/// `f32` inputs and outputs are only converted; all arithmetic is integer). No heap; the whole
/// state is inline (see [`crate::ram`] for its size). `S` is the ED's square root (default
/// [`ExactSqrt`]; see [`SqrtFn`] for plugging in an FPU instruction with identical results).
#[derive(Clone, Copy, Debug)]
pub struct YawBank<T: Real, S: SqrtFn<T> = ExactSqrt> {
    clock: SampleClock,
    hold: Hold,
    h: T,
    unwrap: Unwrapper<T>,
    /// `false`: the angle is taken as is (no +-180 deg unwrapping; e.g. pitch).
    unwrapping: bool,
    y_prev: T,
    reinits: u32,
    ave: Ave<T>,
    ilo: [IloCf<T>; 3],
    ad: ClosedForm<T, Ad<T>>,
    ed: Ed<T, S>,
    kf_v: Kalman<T>,
    ave2: Series<Ave<T>, Ave<T>>,
    ilo2: [Ilo2Cf<T>; 3],
    ad2: ClosedForm<T, Series<Ad<T>, Ad<T>>>,
    ed2: Series<Ed<T, S>, Ed<T, S>>,
    kf_a: Kalman<T>,
}

impl<T: Real, S: SqrtFn<T>> YawBank<T, S> {
    /// Builds the bank (validates every parameter; computes the closed-form maps and the
    /// Kalman gains).
    pub fn new(cfg: &BankConfig) -> Result<Self, ConfigError> {
        let h = cfg.h;
        // The period first: the gap rule is a multiple of it, so a bad period would otherwise
        // be reported as a bad gap rule.
        let h_us = crate::adapter::step_us(h)?;
        let period = f64::from(cfg.sample_period_s);
        if !period.is_finite() {
            return Err(ConfigError::NotFinite("sample_period_s"));
        }
        let n0f = libm::round(period * 1e6 / h_us as f64);
        if n0f < 1.0 {
            return Err(ConfigError::SamplePeriodTooShort);
        }
        if n0f > 1e6 {
            return Err(ConfigError::SamplePeriodTooLong);
        }
        let clock = SampleClock::new(h, cfg.max_gap_s())?;
        let n0 = if cfg.closed_form { n0f as u32 } else { 0 };
        let hold = cfg.hold;
        let v = &cfg.velocity;
        let a = &cfg.acceleration;
        let ilo_cf = |c: &IloConfig| -> Result<IloCf<T>, ConfigError> {
            Ok(ClosedForm::new(Ilo::new(c, h)?, n0, hold))
        };
        let ilo2_cf = |c: &IloConfig| -> Result<Ilo2Cf<T>, ConfigError> {
            Ok(ClosedForm::new(
                Series::new(Ilo::new(c, h)?, Ilo::new(c, h)?),
                n0,
                hold,
            ))
        };
        let kf = |n: &KalmanNoise| {
            Kalman::new(&KalmanConfig {
                dt: cfg.sample_period_s,
                q: n.q,
                r: n.r,
            })
        };
        let [v1, v2, v3] = &v.ilo;
        let [a1, a2, a3] = &a.ilo;
        let mut bank = Self {
            clock,
            hold,
            h: T::from_f64(h_us as f64 * 1e-6),
            unwrap: Unwrapper::new(),
            unwrapping: true,
            y_prev: T::ZERO,
            reinits: 0,
            ave: Ave::new(&v.ave, h)?,
            ilo: [ilo_cf(v1)?, ilo_cf(v2)?, ilo_cf(v3)?],
            ad: ClosedForm::new(Ad::new(v.ad_t, h)?, n0, hold),
            ed: Ed::with_scheme(&v.ed, h, cfg.ed_scheme)?,
            kf_v: kf(&v.kf)?,
            ave2: Series::new(Ave::new(&a.ave, h)?, Ave::new(&a.ave, h)?),
            ilo2: [ilo2_cf(a1)?, ilo2_cf(a2)?, ilo2_cf(a3)?],
            ad2: ClosedForm::new(
                Series::new(Ad::new(a.ad_t, h)?, Ad::new(a.ad_t, h)?),
                n0,
                hold,
            ),
            ed2: Series::new(
                Ed::with_scheme(&a.ed, h, cfg.ed_scheme)?,
                Ed::with_scheme(&a.ed, h, cfg.ed_scheme)?,
            ),
            kf_a: kf(&a.kf)?,
        };
        bank.reset_all(T::ZERO);
        Ok(bank)
    }

    fn reset_all(&mut self, y: T) {
        self.y_prev = y;
        self.ave.reset(y);
        for e in &mut self.ilo {
            e.reset(y);
        }
        self.ad.reset(y);
        self.ed.reset(y);
        self.kf_v.reset(y);
        self.ave2.reset(y);
        for e in &mut self.ilo2 {
            e.reset(y);
        }
        self.ad2.reset(y);
        self.ed2.reset(y);
        self.kf_a.reset(y);
    }

    /// Largest accepted `|yaw_deg|`, deg (2778 turns). The bank expects wrapped yaw (+-180 deg)
    /// but also takes an already unwrapped angle; beyond this bound f32 resolves the angle to
    /// no better than 0.06 deg, and values near `f32::MAX` would overflow the states.
    pub const MAX_ABS_YAW_DEG: f32 = 1.0e6;

    /// Feeds one sample. `t_us`: sample time in µs (monotonic, e.g. from `ItowClock`);
    /// `yaw_deg`: wrapped yaw in deg (within +-180).
    ///
    /// The first sample, and the first after a gap longer than `max_gap_s`, initialise every
    /// state from it and report 0 velocities and accelerations. Otherwise every law runs
    /// `n = round(dt / h)` steps (see [`crate::SampleAdapter`]).
    ///
    /// Errors (state unchanged): [`SampleError::NotFinite`] for NaN/infinite yaw,
    /// [`SampleError::OutOfRange`] for `|yaw_deg|` above [`Self::MAX_ABS_YAW_DEG`],
    /// [`SampleError::NonIncreasingTime`] for `t_us` not later than the previous sample.
    pub fn update(&mut self, t_us: u64, yaw_deg: f32) -> Result<BankOutput, SampleError> {
        if !yaw_deg.is_finite() {
            return Err(SampleError::NotFinite);
        }
        if !(-Self::MAX_ABS_YAW_DEG..=Self::MAX_ABS_YAW_DEG).contains(&yaw_deg) {
            return Err(SampleError::OutOfRange);
        }
        let tick = self.clock.tick(t_us)?;
        // The laws run in a local frame whose origin is the unwrapper's current multiple of
        // 360 deg: they see the wrapped yaw, so f32 states stay within about +-180 deg (full
        // f32 resolution) however many turns the unwrapped yaw makes. When the offset changes,
        // every law is translated into the new frame (exact: the laws are invariant to input
        // offsets, see `Estimator::translate`).
        let yw = T::from_f32(yaw_deg);
        let before = self.unwrap.turns();
        let turns = if self.unwrapping {
            self.unwrap.update(yw)
        } else {
            before
        };
        if turns != before && tick != Tick::Init && tick != Tick::Gap {
            // One turn per sample at most: the shift is exactly +-360 deg in `T`.
            let shift = T::from_i32(if turns > before { 360 } else { -360 });
            self.translate_all(-shift);
        }
        let unwrapped = exact_yaw(turns, yw);
        let y = yw;
        let n = match tick {
            Tick::Init => {
                self.reset_all(y);
                return Ok(self.zero_output(unwrapped));
            }
            Tick::Gap => {
                self.reinits = self.reinits.saturating_add(1);
                self.reset_all(y);
                return Ok(self.zero_output(unwrapped));
            }
            Tick::Steps(n) => n,
        };
        let (yp, hold) = (self.y_prev, self.hold);
        let vel = [
            self.ave.advance(yp, y, n, hold),
            self.ilo[0].advance(yp, y, n, hold),
            self.ilo[1].advance(yp, y, n, hold),
            self.ilo[2].advance(yp, y, n, hold),
            self.ad.advance(yp, y, n, hold),
            self.ed.advance(yp, y, n, hold),
            {
                let dt = self.h * T::from_i32(i32::try_from(n).unwrap_or(i32::MAX));
                self.kf_v.update(y, dt);
                self.kf_a.update(y, dt);
                self.kf_v.velocity()
            },
        ];
        let acc = [
            self.ave2.advance(yp, y, n, hold),
            self.ilo2[0].advance(yp, y, n, hold),
            self.ilo2[1].advance(yp, y, n, hold),
            self.ilo2[2].advance(yp, y, n, hold),
            self.ad2.advance(yp, y, n, hold),
            self.ed2.advance(yp, y, n, hold),
            self.kf_a.acceleration(),
        ];
        self.y_prev = y;
        Ok(BankOutput {
            yaw_unwrapped_deg: unwrapped.0,
            yaw_residual_deg: unwrapped.1,
            vel: vel.map(Real::to_f32),
            acc: acc.map(Real::to_f32),
        })
    }

    fn translate_all(&mut self, d: T) {
        self.y_prev = self.y_prev + d;
        self.ave.translate(d);
        for e in &mut self.ilo {
            e.translate(d);
        }
        self.ad.translate(d);
        self.ed.translate(d);
        self.kf_v.translate(d);
        self.ave2.translate(d);
        for e in &mut self.ilo2 {
            e.translate(d);
        }
        self.ad2.translate(d);
        self.ed2.translate(d);
        self.kf_a.translate(d);
    }

    fn zero_output(&self, y: (f32, f64)) -> BankOutput {
        BankOutput {
            yaw_unwrapped_deg: y.0,
            yaw_residual_deg: y.1,
            vel: [0.0; 7],
            acc: [0.0; 7],
        }
    }

    /// How many times a gap longer than `max_gap_s` re-initialised the bank.
    pub fn reinit_count(&self) -> u32 {
        self.reinits
    }

    /// Starts a new epoch (a confirmed time jump, see `nav440_proto::TimeBase`): the next
    /// sample re-initialises every law from itself and reports 0, whatever its time; the
    /// unwrapper keeps its turn count. Not counted in [`Self::reinit_count`].
    pub fn new_epoch(&mut self) {
        self.clock.clear();
    }

    /// Sets the unwrapper's turn count to `turns` (e.g. to resume an absolute heading after a
    /// restart, or to test a long spin without running it): only the yaw column moves by
    /// `360 * delta` deg; the laws run in the local frame and are unaffected, bit for bit.
    pub fn set_turns(&mut self, turns: i64) {
        self.unwrap.set_turns(turns);
    }

    /// Switches the +-180 deg unwrapping on (the default: roll, yaw) or off (an angle that
    /// does not wrap, e.g. pitch in [-90, 90] deg: it is then estimated as given, and the
    /// output's unwrapped angle is the input). Switch it before the first sample.
    pub fn set_unwrapping(&mut self, on: bool) {
        self.unwrapping = on;
    }

    /// Forgets everything: the next sample is treated as the first one.
    pub fn restart(&mut self) {
        self.clock.clear();
        self.unwrap = Unwrapper::new();
        self.reset_all(T::ZERO);
    }
}
