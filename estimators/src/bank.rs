//! The estimator banks shared by the firmware and the host CLI, each generated from one table
//! by [`crate::estimator_bank!`]: [`PaperBank`] (the paper's 14 estimators, alias
//! [`YawBank`]) and [`ProductBank`] (one velocity and one acceleration estimator).

use crate::adapter::{SampleClock, Tick};
use crate::kalman::{KalmanConfig, KalmanOutput, KalmanParams};
use crate::presets::*;
use crate::{
    AdParams, AveConfig, AveParams, ClosedForm, ConfigError, EdConfig, EdParams, EdScheme,
    ExactSqrt, Hold, IloConfig, IloParams, Real, SampleError, Series, SqrtFn, Unwrapper, VelAcc,
};

/// Names of the seven estimator families of the paper bank, in column order (the velocity
/// channels are these with `_v`, the acceleration channels with `_a`, see [`Channel`]).
pub const VELOCITY_NAMES: [&str; 7] = ["ave", "ilo1", "ilo2", "ilo3", "ad", "ed", "kf"];

/// Noise model of the Kalman tracker (see [`crate::Kalman`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
    /// Velocity gains of [`BankConfig::NAV440`] (see there how they were produced: printed by
    /// `cargo test --release -p host-tests --test preset -- --ignored --nocapture`). The AVE
    /// keeps the leaky `deltahat` law of [`AVE_DEFAULT`]; each ILO was tuned to beat its own
    /// paper preset, so ILO1-3 differ; the tracker's `q/r` is what was tuned.
    pub const NAV440_VELOCITY: Self = Self {
        ave: AveConfig {
            k: 43.09086,
            gamma1: 1860.1345,
            ..AVE_DEFAULT
        },
        ilo: [
            IloConfig {
                k1: 0.9975162,
                l: 0.13922282,
                k2: 45.476727,
            },
            IloConfig {
                k1: 0.9988422,
                l: 0.81672835,
                k2: 0.072374955,
            },
            IloConfig {
                k1: 0.9975247,
                l: 0.29125896,
                k2: 0.1364848,
            },
        ],
        ad_t: 0.011006941,
        ed: EdConfig {
            lambda: 26.93642,
            alpha: 873.99744,
        },
        kf: KalmanNoise {
            q: 421696.5,
            r: 0.01,
        },
    };
    /// Acceleration gains of [`BankConfig::NAV440`] (both stages of each series).
    pub const NAV440_ACCELERATION: Self = Self {
        ave: AveConfig {
            k: 452.36716,
            gamma1: 14271.597,
            ..AVE_DEFAULT
        },
        ilo: [
            IloConfig {
                k1: 0.9987728,
                l: 2.9622777,
                k2: 0.026748411,
            },
            IloConfig {
                k1: 0.8708157,
                l: 1.530036,
                k2: 3.4881077,
            },
            IloConfig {
                k1: 0.99987406,
                l: 574.7061,
                k2: 1.5084013,
            },
        ],
        ad_t: 0.09932768,
        ed: EdConfig {
            lambda: 28.747272,
            alpha: 6858.6904,
        },
        kf: KalmanNoise {
            q: 316227.78,
            r: 0.01,
        },
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
    /// `nav440_pipeline::period` (the pipeline crate) sets it from a stream's first samples (host CLI and firmware).
    pub sample_period_s: f32,
    /// Use the exact closed-form multi-step maps for the linear laws (default `true`); `false`
    /// steps every law `n` times (same results to rounding).
    pub closed_form: bool,
    /// Discretisation of the ED and ED-ED (default [`EdScheme::Euler`], the paper's).
    pub ed_scheme: EdScheme,
    /// How the input angle is unwrapped (default [`Wrap::Deg180`]: yaw and roll; pitch,
    /// within +-90 deg, takes [`Wrap::None`]).
    pub wrap: Wrap,
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
    /// The shipped preset (`nav440 estimate` and the firmware run it; `--preset paper` or
    /// [`BankConfig::PAPER`] selects the paper's): [`BankConfig::DEFAULT`]'s laws, step, hold
    /// (linear) and gap rule with every family's gains tuned on a family of synthetic motions
    /// at 100, 50, 25 and 20 Hz and noise levels (not the bundled test captures). Produced by
    /// `cargo test --release -p host-tests --test preset -- --ignored --nocapture`
    /// (docs/CALIBRATION.md, "Shipped defaults"). These gains are for 20-100 Hz: at a lower
    /// packet rate `nav440 estimate` and the firmware run the rate's entry of
    /// [`BankConfig::NAV440_RATES`] ([`BankConfig::with_nav440_gains`] once the period is
    /// measured).
    pub const NAV440: Self = Self {
        velocity: BankGains::NAV440_VELOCITY,
        acceleration: BankGains::NAV440_ACCELERATION,
        ..Self::DEFAULT
    };
    /// The paper's configuration, every law as published (AVE `deltahat` only grows).
    pub const PAPER: Self = Self {
        h: H_PAPER,
        hold: Hold::Linear,
        max_gap_periods: GAP_PERIODS,
        sample_period_s: 0.01,
        closed_form: true,
        ed_scheme: EdScheme::Euler,
        wrap: Wrap::Deg180,
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

/// How a bank unwraps its input angle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Wrap {
    /// The input wraps at +-180 deg (yaw, roll): 360 deg jumps are removed and the laws run
    /// in a translated frame (see [`crate::Estimator::translate`]).
    #[default]
    Deg180,
    /// The input does not wrap (pitch, +-90 deg; or an already unwrapped angle): used as is.
    None,
}

impl Default for BankConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The unwrapped input `360 turns + wrapped` (deg) as (f32 rounding, exact residual in f64).
#[inline]
fn exact_angle<T: Real>(turns: i64, wrapped: T) -> (f32, f64) {
    if turns == 0 {
        // Fast path (no soft-float f64 on an FPU-less or single-precision core): the wrapped
        // value is exactly an f32 (checked by the round trip), so the residual is 0. `+ 0.0`
        // maps -0 to +0 as the f64 sum below does.
        let r = wrapped.to_f32() + 0.0;
        if T::from_f32(r) == wrapped {
            return (r, 0.0);
        }
    }
    exact_angle_f64(turns, wrapped)
}

/// [`exact_angle`] in f64 (soft-float on Cortex-M: out of line, taken only after a turn).
#[cold]
#[inline(never)]
fn exact_angle_f64<T: Real>(turns: i64, wrapped: T) -> (f32, f64) {
    let exact = turns as f64 * 360.0 + wrapped.to_f64();
    let rounded = exact as f32;
    (rounded, exact - f64::from(rounded))
}

/// What [`BankInput::accept`] decided for one accepted sample.
#[derive(Clone, Copy, Debug)]
pub enum Feed<T: Real> {
    /// Initialise every law at `y` (first sample, after a gap or a new epoch) and report 0.
    Reset(T),
    /// Run every law over `n` steps from `y_prev` to `y` with `hold`.
    Advance {
        /// The previous sample (in the current frame).
        y_prev: T,
        /// This sample.
        y: T,
        /// Steps of `h`.
        n: u32,
        /// Input between the samples.
        hold: Hold,
    },
}

/// What a bank's laws were fed for one sample ([`PaperBank::update_fed`]): a frame shift
/// (deg, applied to every law first) and the feed.
#[derive(Clone, Copy, Debug)]
pub struct Fed<T: Real> {
    /// Every law was translated by this (deg) before the feed.
    pub shift: Option<T>,
    /// What the laws were fed.
    pub feed: Feed<T>,
}

/// A sample accepted by [`BankInput::accept`].
#[derive(Clone, Copy, Debug)]
pub struct Accepted<T: Real> {
    /// Translate every law by this (deg) before feeding: the frame moved by one turn.
    pub shift: Option<T>,
    /// What to do with the laws.
    pub feed: Feed<T>,
    /// The unwrapped angle, deg: (f32 rounding, exact residual), see [`PaperOutput`].
    pub angle: (f32, f64),
}

/// The input stage every generated bank shares: input checks, sample clock (gap rule),
/// unwrapping into a local frame (per [`Wrap`]), the previous sample and the re-init count.
#[derive(Clone, Copy, Debug)]
pub struct BankInput<T: Real> {
    clock: SampleClock,
    hold: Hold,
    wrap: Wrap,
    unwrap: Unwrapper<T>,
    y_prev: T,
    reinits: u32,
}

impl<T: Real> BankInput<T> {
    /// Largest accepted `|angle|`, deg (2778 turns). Beyond it f32 resolves the angle to no
    /// better than 0.06 deg, and values near `f32::MAX` would overflow the states.
    pub const MAX_ABS_DEG: f32 = 1.0e6;

    /// Validates the step, period and gap rule of `cfg`; returns the input stage and the
    /// number of steps per nominal sample period the closed-form maps are built for (0 when
    /// `cfg.closed_form` is false).
    pub fn new(cfg: &BankConfig) -> Result<(Self, u32), ConfigError> {
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
        Ok((
            Self {
                clock,
                hold: cfg.hold,
                wrap: cfg.wrap,
                unwrap: Unwrapper::new(),
                y_prev: T::ZERO,
                reinits: 0,
            },
            n0,
        ))
    }

    /// Checks and classifies one sample (`t_us` µs, `angle_deg` deg); see [`PaperBank::update`].
    #[inline(always)]
    pub fn accept(&mut self, t_us: u64, angle_deg: f32) -> Result<Accepted<T>, SampleError> {
        if !angle_deg.is_finite() {
            return Err(SampleError::NotFinite);
        }
        if !(-Self::MAX_ABS_DEG..=Self::MAX_ABS_DEG).contains(&angle_deg) {
            return Err(SampleError::OutOfRange);
        }
        let tick = self.clock.tick(t_us)?;
        // The laws run in a local frame whose origin is the unwrapper's current multiple of
        // 360 deg: they see the wrapped angle, so f32 states stay within about +-180 deg (full
        // f32 resolution) however many turns the unwrapped angle makes. When the offset
        // changes, every law is translated into the new frame (exact: the laws are invariant
        // to input offsets, see `Estimator::translate`).
        let y = T::from_f32(angle_deg);
        let mut shift = None;
        let turns = match self.wrap {
            Wrap::None => 0,
            Wrap::Deg180 => {
                let before = self.unwrap.turns();
                let turns = self.unwrap.update(y);
                if turns != before && tick != Tick::Init && tick != Tick::Gap {
                    // One turn per sample at most: the shift is exactly +-360 deg in `T`.
                    let d = -T::from_i32(if turns > before { 360 } else { -360 });
                    self.y_prev = self.y_prev + d;
                    shift = Some(d);
                }
                turns
            }
        };
        let angle = exact_angle(turns, y);
        let feed = match tick {
            Tick::Init => Feed::Reset(y),
            Tick::Gap => {
                self.reinits = self.reinits.saturating_add(1);
                Feed::Reset(y)
            }
            Tick::Steps(n) => Feed::Advance {
                y_prev: self.y_prev,
                y,
                n,
                hold: self.hold,
            },
        };
        self.y_prev = y;
        Ok(Accepted { shift, feed, angle })
    }

    /// The last accepted sample in the laws' (local) frame, deg (0 before the first).
    pub fn last(&self) -> T {
        self.y_prev
    }

    /// Gaps longer than the gap rule that re-initialised the laws.
    pub fn reinit_count(&self) -> u32 {
        self.reinits
    }

    /// The next sample re-initialises the laws, whatever its time; turns are kept.
    pub fn new_epoch(&mut self) {
        self.clock.clear();
    }

    /// Sets the unwrapper's turn count (only the reported angle moves).
    pub fn set_turns(&mut self, turns: i64) {
        self.unwrap.set_turns(turns);
    }

    /// Forgets everything but the configuration and the re-init count.
    pub fn restart(&mut self) {
        self.clock.clear();
        self.unwrap = Unwrapper::new();
        self.y_prev = T::ZERO;
    }
}

/// Generates an estimator bank from one table: one row per estimator (a [`crate::Law`] and
/// how to build it from a [`BankConfig`]), and the channels (CSV columns) the rows report.
///
/// Generated: the bank `$Bank<T, S>` (`new(&BankConfig)`, `update(t_us, angle_deg)`,
/// `new_epoch`, `set_turns`, `reinit_count`, `restart`, `params`, `state`), its parameters
/// `$Params<T, S>` (one field per row, validated once, shareable between axes) and state
/// `$State<T, S>` (one field per row), the channel enum `$Chan` (`ALL`, `COUNT`, `name`,
/// `CSV_COLUMNS`) and the output `$Out` (indexed by `$Chan`). Adding an estimator is one row
/// (and its channel). In a row, `cfg` (the `&BankConfig`) and `n0` (steps per
/// nominal period, for [`ClosedForm`]), named by `build(cfg, n0)`, are in scope of the
/// builder, which returns
/// `Result<Law, ConfigError>`; each `Channel = method` takes the row's output from
/// `law.method(&state)`. With `build(cfg, n0, prev)` the builder also sees `prev:
/// Option<&Law>`, the row being replaced by `set_gains` (`None` in `new`), so that it can
/// keep what did not change ([`ClosedForm::new_reusing`]: a gain change that leaves a row's
/// gains alone then costs nothing for that row).
///
/// ```
/// use estimators::{estimator_bank, AdAdMap, AdParams, BankConfig, ClosedForm, Law, Series};
///
/// estimator_bank! {
///     /// AD velocity and AD-AD acceleration.
///     bank AdBank, params AdBankParams, state AdBankState, output AdOut, channel AdChannel;
///     build(cfg, n0);
///     channels {
///         /// AD velocity.
///         AdV = "ad_v",
///         /// AD-AD acceleration.
///         AdA = "ad_a",
///     }
///     rows {
///         /// AD, closed form.
///         ad_v: ClosedForm<AdParams<T>> = Ok(ClosedForm::new(AdParams::new(cfg.velocity.ad_t, cfg.h)?, n0, cfg.hold)) => [AdV = output];
///         /// AD-AD, closed form.
///         ad_a: AdAdMap<T> = {
///             let ad = AdParams::new(cfg.acceleration.ad_t, cfg.h)?;
///             Ok(ClosedForm::new(Series::new(ad, ad), n0, cfg.hold))
///         } => [AdA = output];
///     }
/// }
///
/// let mut bank = AdBank::<f32>::new(&BankConfig::default()).unwrap();
/// for k in 0..100u64 {
///     let out = bank.update(k * 10_000, 20.0 * k as f32 * 0.01).unwrap();
///     if k == 99 {
///         assert!((out[AdChannel::AdV] - 20.0).abs() < 0.01);
///     }
/// }
/// assert_eq!(AdChannel::CSV_COLUMNS, "ad_v,ad_a");
/// ```
#[macro_export]
macro_rules! estimator_bank {
    (
        $(#[$bm:meta])*
        bank $Bank:ident, params $Params:ident, state $State:ident, output $Out:ident, channel $Chan:ident;
        build($cfg:ident, $n0:ident);
        channels { $($chans:tt)* }
        rows { $($rows:tt)* }
    ) => {
        $crate::estimator_bank! {
            $(#[$bm])*
            bank $Bank, params $Params, state $State, output $Out, channel $Chan;
            build($cfg, $n0, __estimator_bank_prev);
            channels { $($chans)* }
            rows { $($rows)* }
        }
    };
    (
        $(#[$bm:meta])*
        bank $Bank:ident, params $Params:ident, state $State:ident, output $Out:ident, channel $Chan:ident;
        build($cfg:ident, $n0:ident, $prev:ident);
        channels { $( $(#[$cm:meta])* $ch:ident = $csv:literal ),+ $(,)? }
        rows { $( $(#[$rm:meta])* $field:ident : $Law:ty = $build:expr => [ $( $rch:ident = $get:ident ),+ ] ; )+ }
    ) => {
        /// The channels (output columns) of the bank, in CSV order.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $Chan {
            $( $(#[$cm])* $ch, )+
        }

        impl $Chan {
            /// Every channel, in order.
            pub const ALL: &'static [$Chan] = &[ $( $Chan::$ch ),+ ];
            /// The number of channels.
            pub const COUNT: usize = [ $( $csv ),+ ].len();
            /// The CSV column names, comma-separated, in order.
            pub const CSV_COLUMNS: &'static str = $crate::__bank_columns!($($csv),+);
            /// The CSV column names, in order.
            pub const NAMES: [&'static str; $Chan::COUNT] = [ $( $csv ),+ ];
            /// The channel's CSV column name.
            pub const fn name(self) -> &'static str {
                match self { $( $Chan::$ch => $csv, )+ }
            }
            /// The channel's position in [`Self::ALL`] and in the output.
            pub const fn index(self) -> usize {
                self as usize
            }
        }

        /// One output of the bank: the unwrapped input angle and one value per channel
        /// (velocities in deg/s, accelerations in deg/s^2).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $Out {
            /// The unwrapped angle, deg, rounded to f32 (see `yaw_residual_deg`).
            pub yaw_unwrapped_deg: f32,
            /// What f32 rounding took off the unwrapped angle, deg: the exact unwrapped angle
            /// is `yaw_unwrapped_deg as f64 + yaw_residual_deg` (0 while f32 holds it).
            pub yaw_residual_deg: f64,
            /// The channels' values, indexed by the channel (`out[channel]`).
            pub values: [f32; $Chan::COUNT],
        }

        impl Default for $Out {
            fn default() -> Self {
                Self { yaw_unwrapped_deg: 0.0, yaw_residual_deg: 0.0, values: [0.0; $Chan::COUNT] }
            }
        }

        impl core::ops::Index<$Chan> for $Out {
            type Output = f32;
            fn index(&self, c: $Chan) -> &f32 {
                &self.values[c as usize]
            }
        }

        impl $Out {
            /// `(channel, value)` pairs in CSV order.
            pub fn iter(&self) -> impl Iterator<Item = ($Chan, f32)> + '_ {
                $Chan::ALL.iter().copied().zip(self.values.iter().copied())
            }
        }

        impl $crate::EstimatorOutput for $Out {
            const CHANNELS: usize = $Chan::COUNT;
            const CHANNEL_NAMES: &'static [&'static str] = &$Chan::NAMES;
            const CSV_COLUMNS: &'static str = $Chan::CSV_COLUMNS;

            #[inline]
            fn unwrapped_deg(&self) -> f32 {
                self.yaw_unwrapped_deg
            }

            #[inline]
            fn residual_deg(&self) -> f64 {
                self.yaw_residual_deg
            }

            #[inline]
            fn values(&self) -> &[f32] {
                &self.values
            }
        }

        /// The validated parameters of every row (computed once; shareable between axes).
        #[derive(Clone, Copy, Debug)]
        pub struct $Params<T: $crate::Real, S: $crate::SqrtFn<T> = $crate::ExactSqrt> {
            $( $(#[$rm])* pub $field: $Law, )+
            _sqrt: core::marker::PhantomData<(T, S)>,
        }

        /// The state of every row.
        #[derive(Clone, Copy, Debug)]
        pub struct $State<T: $crate::Real, S: $crate::SqrtFn<T> = $crate::ExactSqrt> {
            $( $(#[$rm])* pub $field: <$Law as $crate::Law>::State, )+
            _sqrt: core::marker::PhantomData<(T, S)>,
        }

        $(#[$bm])*
        #[derive(Clone, Copy, Debug)]
        pub struct $Bank<T: $crate::Real, S: $crate::SqrtFn<T> = $crate::ExactSqrt> {
            input: $crate::BankInput<T>,
            params: $Params<T, S>,
            state: $State<T, S>,
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $Params<T, S> {
            /// Validates `cfg` and builds every row's parameters; `n0` = steps per nominal
            /// sample period for the closed-form maps (0: no map).
            pub fn new($cfg: &$crate::BankConfig, $n0: u32) -> Result<Self, $crate::ConfigError> {
                Self::new_reusing($cfg, $n0, None)
            }

            /// [`Self::new`], where each row's builder may reuse the row of `prev` (the
            /// parameters being replaced; named by the third name of `build(cfg, n0, prev)`,
            /// an `Option<&Law>` in the row's scope) instead of recomputing what did not
            /// change, e.g. `ClosedForm::new_reusing`. Same result as `new`.
            #[allow(unused_variables)]
            pub fn new_reusing(
                $cfg: &$crate::BankConfig,
                $n0: u32,
                previous: Option<&Self>,
            ) -> Result<Self, $crate::ConfigError> {
                Ok(Self {
                    $( $field: {
                        let $prev: Option<&$Law> = previous.map(|p| &p.$field);
                        let r: Result<$Law, $crate::ConfigError> = $build;
                        r?
                    }, )+
                    _sqrt: core::marker::PhantomData,
                })
            }

            /// Every row's state, initialised at `y0`.
            pub fn init(&self, y0: T) -> $State<T, S> {
                use $crate::Law as _;
                $State { $( $field: self.$field.init(y0), )+ _sqrt: core::marker::PhantomData }
            }

            /// Translates every row's state by `d` (deg).
            #[inline]
            pub fn translate(&self, s: &mut $State<T, S>, d: T) {
                use $crate::Law as _;
                $( self.$field.translate(&mut s.$field, d); )+
            }

            /// Bumpless gain change: moves every row's state `s`, produced by the parameters
            /// `old`, to the equilibrium of these parameters at the last input `y` (the
            /// laws' frame) with the same outputs (`Law::retune_state`).
            pub fn retune_state(&self, old: &Self, s: &mut $State<T, S>, y: T) {
                use $crate::Law as _;
                $( self.$field.retune_state(&old.$field, &mut s.$field, y); )+
            }

            /// Every row's state after replaying `history` (what a bank's laws were fed,
            /// oldest first, see `update_fed`) through these parameters: started at rest at
            /// the first entry's input (`init`, then `on_init`), re-initialised where the
            /// history was (`Feed::Reset`, then `on_init`), translated where the frame
            /// shifted. `None` for an empty history.
            pub fn replay<'h, I, F>(&self, history: I, mut on_init: F) -> Option<$State<T, S>>
            where
                I: IntoIterator<Item = &'h $crate::Fed<T>>,
                F: FnMut(&mut $State<T, S>),
                T: 'h,
            {
                let mut state: Option<$State<T, S>> = None;
                for fed in history {
                    match (fed.feed, state.as_mut()) {
                        ($crate::Feed::Reset(y), _) => {
                            let mut s = self.init(y);
                            on_init(&mut s);
                            state = Some(s);
                        }
                        ($crate::Feed::Advance { y_prev, y, n, hold }, Some(s)) => {
                            if let Some(d) = fed.shift {
                                self.translate(s, d);
                            }
                            self.advance(s, y_prev, y, n, hold);
                        }
                        ($crate::Feed::Advance { y_prev, y, n, hold }, None) => {
                            // `y_prev` is already in this sample's frame.
                            let mut s = self.init(y_prev);
                            on_init(&mut s);
                            self.advance(&mut s, y_prev, y, n, hold);
                            state = Some(s);
                        }
                    }
                }
                state
            }

            /// Advances every row over one sample interval.
            #[inline]
            pub fn advance(&self, s: &mut $State<T, S>, y_prev: T, y: T, n: u32, hold: $crate::Hold) {
                use $crate::Law as _;
                $( self.$field.advance(&mut s.$field, y_prev, y, n, hold); )+
            }

            /// The channels' values of state `s`.
            #[inline]
            pub fn values(&self, s: &$State<T, S>) -> [f32; $Chan::COUNT] {
                #[allow(unused_imports)]
                use $crate::Law as _;
                let mut v = [0.0f32; $Chan::COUNT];
                $( $( v[$Chan::$rch as usize] = $crate::Real::to_f32(self.$field.$get(&s.$field)); )+ )+
                v
            }
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $Bank<T, S> {
            /// Largest accepted `|angle_deg|`, deg (`BankInput::MAX_ABS_DEG`, 1e6).
            pub const MAX_ABS_YAW_DEG: f32 = $crate::BankInput::<T>::MAX_ABS_DEG;

            /// Builds the bank (validates every parameter; computes the closed-form maps and
            /// the Kalman gains).
            pub fn new(cfg: &$crate::BankConfig) -> Result<Self, $crate::ConfigError> {
                let (input, n0) = $crate::BankInput::new(cfg)?;
                let params = $Params::new(cfg, n0)?;
                let state = params.init(T::ZERO);
                Ok(Self { input, params, state })
            }

            /// Feeds one sample. `t_us`: sample time in µs (monotonic); `angle_deg`: the angle
            /// in deg (within +-180 when wrapping).
            ///
            /// The first sample, and the first after a gap longer than the gap rule,
            /// initialise every state from it and report 0 velocities and accelerations.
            /// Otherwise every law runs `n = round(dt / h)` steps (see `SampleAdapter`).
            ///
            /// Errors (state unchanged): `SampleError::NotFinite` for NaN/infinite
            /// input, `SampleError::OutOfRange` for `|angle_deg|` above
            /// `MAX_ABS_YAW_DEG`, `SampleError::NonIncreasingTime` for `t_us` not
            /// later than the previous sample.
            #[inline]
            pub fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<$Out, $crate::SampleError> {
                self.update_fed(t_us, angle_deg).map(|(out, _)| out)
            }

            /// [`Self::update`], also returning what the laws were fed (`Fed`): what
            /// [`Self::set_gains_replaying`] replays.
            #[inline(always)]
            pub fn update_fed(&mut self, t_us: u64, angle_deg: f32) -> Result<($Out, $crate::Fed<T>), $crate::SampleError> {
                let a = self.input.accept(t_us, angle_deg)?;
                if let Some(d) = a.shift {
                    self.params.translate(&mut self.state, d);
                }
                let values = match a.feed {
                    $crate::Feed::Reset(y) => {
                        self.state = self.params.init(y);
                        [0.0; $Chan::COUNT]
                    }
                    $crate::Feed::Advance { y_prev, y, n, hold } => {
                        self.params.advance(&mut self.state, y_prev, y, n, hold);
                        self.params.values(&self.state)
                    }
                };
                let out = $Out { yaw_unwrapped_deg: a.angle.0, yaw_residual_deg: a.angle.1, values };
                Ok((out, $crate::Fed { shift: a.shift, feed: a.feed }))
            }

            /// How many times a gap longer than the gap rule re-initialised the bank.
            pub fn reinit_count(&self) -> u32 {
                self.input.reinit_count()
            }

            /// Starts a new epoch (a confirmed time jump): the next sample re-initialises every
            /// law from itself and reports 0, whatever its time; the unwrapper keeps its turn
            /// count. Not counted in [`Self::reinit_count`].
            pub fn new_epoch(&mut self) {
                self.input.new_epoch();
            }

            /// Sets the unwrapper's turn count to `turns`: only the angle column moves by
            /// `360 * delta` deg; the laws run in the local frame and are unaffected.
            pub fn set_turns(&mut self, turns: i64) {
                self.input.set_turns(turns);
            }

            /// Forgets everything: the next sample is treated as the first one.
            pub fn restart(&mut self) {
                self.input.restart();
                self.state = self.params.init(T::ZERO);
            }

            /// Replaces every row's parameters by those of `cfg`; the laws continue from where
            /// they are with the new gains (what a gain schedule does, `AdaptiveBank`), their
            /// states moved so that each output continues without a jump (bumpless transfer,
            /// `Law::retune_state`: the ILO's and AD's steady state depends on their gains).
            /// Only the gains of `cfg` are meant to differ from the configuration the bank was
            /// built with: the input stage (step, hold, nominal period, gap rule, unwrapping)
            /// is kept as built. On error nothing changes.
            /// Cost: that of building the parameters (closed-form maps, Kalman gains) of the
            /// rows whose gains changed (for rows whose builder reuses the previous row, see
            /// `new_reusing` of the parameters; the same parameters as a full rebuild), see
            /// `cargo xtask bench`.
            pub fn set_gains(&mut self, cfg: &$crate::BankConfig) -> Result<(), $crate::ConfigError> {
                let (_, n0) = $crate::BankInput::<T>::new(cfg)?;
                let params = $Params::new_reusing(cfg, n0, Some(&self.params))?;
                params.retune_state(&self.params, &mut self.state, self.input.last());
                self.params = params;
                Ok(())
            }

            /// [`Self::set_gains`], with the new laws' states rebuilt by replaying `history`
            /// (oldest first: what the laws were fed for the last samples, from
            /// [`Self::update_fed`], ending with the last sample) through the new parameters
            /// (see the parameters' `replay`). The laws then continue as if they had run with
            /// the new gains over the history (warm start), not from the old gains' states.
            /// An empty history is [`Self::set_gains`]. On error nothing changes.
            /// Cost: [`Self::set_gains`] plus one advance of every row per history entry.
            pub fn set_gains_replaying<'h, I, F>(
                &mut self,
                cfg: &$crate::BankConfig,
                history: I,
                on_init: F,
            ) -> Result<(), $crate::ConfigError>
            where
                I: IntoIterator<Item = &'h $crate::Fed<T>>,
                F: FnMut(&mut $State<T, S>),
                T: 'h,
            {
                let (_, n0) = $crate::BankInput::<T>::new(cfg)?;
                let params = $Params::new_reusing(cfg, n0, Some(&self.params))?;
                match params.replay(history, on_init) {
                    Some(s) => self.state = s,
                    None => params.retune_state(&self.params, &mut self.state, self.input.last()),
                }
                self.params = params;
                Ok(())
            }

            /// The rows' validated parameters.
            pub fn params(&self) -> &$Params<T, S> {
                &self.params
            }

            /// The rows' state.
            pub fn state(&self) -> &$State<T, S> {
                &self.state
            }
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $crate::EstimatorBank for $Bank<T, S> {
            type Output = $Out;

            #[inline]
            fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<$Out, $crate::SampleError> {
                $Bank::update(self, t_us, angle_deg)
            }

            fn new_epoch(&mut self) {
                $Bank::new_epoch(self)
            }

            fn reinit_count(&self) -> u32 {
                $Bank::reinit_count(self)
            }
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $crate::FromConfig for $Bank<T, S> {
            fn from_config(cfg: &$crate::BankConfig) -> Result<Self, $crate::ConfigError> {
                $Bank::new(cfg)
            }
        }
    };
}

impl<T: Real, S: SqrtFn<T>> PaperBank<T, S> {
    /// The switching gains `deltahat` of the AVE row: the velocity AVE's (deg/s) and the
    /// AVE-AVE series' stages' (deg/s, deg/s^2; the first stage's is the velocity AVE's when
    /// the row shares it, [`VelAcc::is_shared`]).
    pub fn ave_deltahat(&self) -> crate::AveDeltahat {
        let s = &self.state.ave;
        let a1 = if self.params.ave.is_shared() {
            s.v.delta
        } else {
            s.a1.delta
        };
        crate::AveDeltahat {
            velocity: s.v.delta.to_f32(),
            acceleration: [a1.to_f32(), s.a2.delta.to_f32()],
        }
    }

    /// Sets the AVE row's switching gains (see [`Self::ave_deltahat`]; a negative or
    /// non-finite value leaves its `deltahat` as it is). What [`crate::AdaptiveBank`] does
    /// when it changes the AVE gains and its schedule records the `deltahat` they were tuned
    /// with.
    pub fn set_ave_deltahat(&mut self, d: &crate::AveDeltahat) {
        set_ave_deltahat(&mut self.state, d);
    }
}

impl<T: Real, S: SqrtFn<T>> PaperBank<T, S> {
    /// The gain change of [`crate::AdaptiveBank`] (warm start) from the gains of `old` (what
    /// the bank runs now; only its gains are read) to those of `new`:
    ///
    /// * the AVE / AVE-AVE row, the velocity ILOs and AD and both trackers, when their gains
    ///   changed, are rebuilt by replaying `history` (what the laws were fed for the last
    ///   samples, oldest first, ending with the last one; see [`Self::update_fed`] and
    ///   [`PaperParams::replay`]) through their new gains, started at rest at the history's
    ///   first sample, so that they continue as if they had run with them over the history;
    ///   the AVE row starts its replay with the switching gains `deltahat` (deg/s, deg/s^2),
    ///   or, when `None`, with those it has now;
    /// * the ED / ED-ED row and the ILO-ILO and AD-AD series, when their gains changed, keep
    ///   their state, moved bumplessly ([`crate::Law::retune_state`]): replayed from rest they
    ///   take longer than a 64-sample history to settle. The ED's velocity state moves at most
    ///   `alpha` deg/s per second and a tuned `lambda` is small (replayed, the scheduled ED's
    ///   velocity MSE in the second after the first gain change of the noise-switch capture
    ///   was 1049 (deg/s)^2 instead of 206); a series' second stage starts from zero
    ///   acceleration (replayed, the ILO-ILO's acceleration MSE over the noise switch was 7 %
    ///   above the bumpless change's, the AD-AD's 0.3 %; docs/CALIBRATION.md);
    /// * a row whose gains did not change keeps its state exactly.
    ///
    /// An empty history is [`Self::set_gains`] (every row bumpless). On error nothing changes.
    /// Cost: [`Self::set_gains`] plus one sample of the whole bank per history entry.
    pub fn set_gains_warm<'h, I>(
        &mut self,
        old: &BankConfig,
        new: &BankConfig,
        history: I,
        deltahat: Option<crate::AveDeltahat>,
    ) -> Result<(), ConfigError>
    where
        I: IntoIterator<Item = &'h Fed<T>>,
        T: 'h,
    {
        use crate::Law as _;
        let (_, n0) = BankInput::<T>::new(new)?;
        let params = PaperParams::<T, S>::new_reusing(new, n0, Some(&self.params))?;
        let deltahat = deltahat.unwrap_or_else(|| self.ave_deltahat());
        let Some(replayed) = params.replay(history, |s| set_ave_deltahat(s, &deltahat)) else {
            params.retune_state(&self.params, &mut self.state, self.input.last());
            self.params = params;
            return Ok(());
        };
        let (ov, oa, nv, na) = (
            &old.velocity,
            &old.acceleration,
            &new.velocity,
            &new.acceleration,
        );
        let (s, y) = (&mut self.state, self.input.last());
        // `$row: $changed;`: the row's gains changed.
        macro_rules! replayed_if {
            ($($row:ident: $changed:expr;)+) => {$( if $changed { s.$row = replayed.$row; } )+};
        }
        macro_rules! bumpless_if {
            ($($row:ident: $changed:expr;)+) => {$(
                if $changed {
                    params.$row.retune_state(&self.params.$row, &mut s.$row, y);
                }
            )+};
        }
        replayed_if! {
            ave: (ov.ave, oa.ave) != (nv.ave, na.ave);
            ilo1_v: ov.ilo[0] != nv.ilo[0];
            ilo2_v: ov.ilo[1] != nv.ilo[1];
            ilo3_v: ov.ilo[2] != nv.ilo[2];
            ad_v: ov.ad_t != nv.ad_t;
            kf_v: ov.kf != nv.kf;
            kf_a: oa.kf != na.kf;
        }
        bumpless_if! {
            ed: (ov.ed, oa.ed) != (nv.ed, na.ed);
            ilo1_a: oa.ilo[0] != na.ilo[0];
            ilo2_a: oa.ilo[1] != na.ilo[1];
            ilo3_a: oa.ilo[2] != na.ilo[2];
            ad_a: oa.ad_t != na.ad_t;
        }
        self.params = params;
        Ok(())
    }
}

/// Sets the AVE row's switching gains in `state` (see [`PaperBank::set_ave_deltahat`]).
pub(crate) fn set_ave_deltahat<T: Real, S: SqrtFn<T>>(
    state: &mut PaperState<T, S>,
    d: &crate::AveDeltahat,
) {
    let set = |x: &mut T, v: f32| {
        if v.is_finite() && v >= 0.0 {
            *x = T::from_f32(v);
        }
    };
    let s = &mut state.ave;
    set(&mut s.v.delta, d.velocity);
    set(&mut s.a1.delta, d.acceleration[0]);
    set(&mut s.a2.delta, d.acceleration[1]);
}

/// Comma-joins string literals (for [`estimator_bank!`]'s `CSV_COLUMNS`).
#[doc(hidden)]
#[macro_export]
macro_rules! __bank_columns {
    ($first:literal $(, $rest:literal)*) => { concat!($first $(, ",", $rest)*) };
}

/// ILO-ILO (both stages `D = 1`) through its closed-form map: the paper bank's ILO
/// acceleration row.
pub type IloIloMap<T> = ClosedForm<Series<IloParams<T, 1>, IloParams<T, 1>>>;
/// AD-AD through its closed-form map: the paper bank's AD acceleration row.
pub type AdAdMap<T> = ClosedForm<Series<AdParams<T>, AdParams<T>>>;

/// The Kalman tracker row of a gains half.
fn kalman<T: Real>(
    cfg: &BankConfig,
    g: &BankGains,
    out: KalmanOutput,
) -> Result<KalmanParams<T>, ConfigError> {
    KalmanParams::new(
        &KalmanConfig {
            dt: cfg.sample_period_s,
            q: g.kf.q,
            r: g.kf.r,
        },
        cfg.h,
        out,
    )
}

/// ILO row `i` of the velocity half, closed form.
fn ilo_v<T: Real>(
    cfg: &BankConfig,
    i: usize,
    n0: u32,
    prev: Option<&ClosedForm<IloParams<T, 1>>>,
) -> Result<ClosedForm<IloParams<T, 1>>, ConfigError> {
    let c: &IloConfig = cfg.velocity.ilo.get(i).unwrap_or(&ILO1_TABLE2);
    let p = IloParams::new(c, cfg.h)?;
    Ok(ClosedForm::new_reusing(p, n0, cfg.hold, prev))
}

/// ILO-ILO row `i` of the acceleration half (both stages the same gains), closed form.
fn ilo_a<T: Real>(
    cfg: &BankConfig,
    i: usize,
    n0: u32,
    prev: Option<&IloIloMap<T>>,
) -> Result<IloIloMap<T>, ConfigError> {
    let c: &IloConfig = cfg.acceleration.ilo.get(i).unwrap_or(&ILO1_TABLE4);
    let p = IloParams::new(c, cfg.h)?;
    Ok(ClosedForm::new_reusing(
        Series::new(p, p),
        n0,
        cfg.hold,
        prev,
    ))
}

/// AVE and AVE-AVE (shared first stage when the velocity and acceleration AVE are equal).
fn ave_pair<T: Real>(cfg: &BankConfig) -> Result<VelAcc<AveParams<T>>, ConfigError> {
    let (v, a): (&AveConfig, &AveConfig) = (&cfg.velocity.ave, &cfg.acceleration.ave);
    let pa = AveParams::new(a, cfg.h)?;
    Ok(VelAcc::new(AveParams::new(v, cfg.h)?, pa, pa, v == a))
}

/// ED and ED-ED (shared first stage when the velocity and acceleration ED are equal).
fn ed_pair<T: Real, S: SqrtFn<T>>(cfg: &BankConfig) -> Result<VelAcc<EdParams<T, S>>, ConfigError> {
    let (v, a): (&EdConfig, &EdConfig) = (&cfg.velocity.ed, &cfg.acceleration.ed);
    let pa = EdParams::new(a, cfg.h, cfg.ed_scheme)?;
    Ok(VelAcc::new(
        EdParams::new(v, cfg.h, cfg.ed_scheme)?,
        pa,
        pa,
        v == a,
    ))
}

/// AD velocity, closed form.
fn ad_v<T: Real>(
    cfg: &BankConfig,
    n0: u32,
    prev: Option<&ClosedForm<AdParams<T>>>,
) -> Result<ClosedForm<AdParams<T>>, ConfigError> {
    let p = AdParams::new(cfg.velocity.ad_t, cfg.h)?;
    Ok(ClosedForm::new_reusing(p, n0, cfg.hold, prev))
}

/// AD-AD acceleration, closed form.
fn ad_a<T: Real>(
    cfg: &BankConfig,
    n0: u32,
    prev: Option<&AdAdMap<T>>,
) -> Result<AdAdMap<T>, ConfigError> {
    let p = AdParams::new(cfg.acceleration.ad_t, cfg.h)?;
    Ok(ClosedForm::new_reusing(
        Series::new(p, p),
        n0,
        cfg.hold,
        prev,
    ))
}

estimator_bank! {
    /// The paper's bank for one angle: unwrap -> sample adapter -> AVE, ILO1-3 (Table 2),
    /// AD (T = 0.01), ED (700/770), Kalman for velocity, and AVE-AVE, ILO1-3-ILO1-3
    /// (Table 4), AD-AD (T = 0.1), ED-ED, Kalman for acceleration.
    ///
    /// Generic over [`Real`]: `PaperBank<f32>` for FPU targets, `PaperBank<Fx>` for
    /// Cortex-M0/M3 (the `f32` inputs and outputs are only converted; all arithmetic is
    /// integer). No heap; the whole state is inline (see [`crate::ram`] for its size). `S` is
    /// the ED's square root (default [`ExactSqrt`]; see [`SqrtFn`] for plugging in an FPU
    /// instruction with identical results).
    bank PaperBank, params PaperParams, state PaperState, output PaperOutput, channel Channel;
    build(cfg, n0, prev);
    channels {
        /// AVE velocity, deg/s.
        AveV = "ave_v",
        /// ILO1 (Table 2) velocity, deg/s.
        Ilo1V = "ilo1_v",
        /// ILO2 (Table 2) velocity, deg/s.
        Ilo2V = "ilo2_v",
        /// ILO3 (Table 2) velocity, deg/s.
        Ilo3V = "ilo3_v",
        /// AD (T = 0.01 s) velocity, deg/s.
        AdV = "ad_v",
        /// Levant ED velocity, deg/s.
        EdV = "ed_v",
        /// Kalman tracker velocity, deg/s.
        KfV = "kf_v",
        /// AVE-AVE acceleration, deg/s^2.
        AveA = "ave_a",
        /// ILO1-ILO1 (Table 4) acceleration, deg/s^2.
        Ilo1A = "ilo1_a",
        /// ILO2-ILO2 (Table 4) acceleration, deg/s^2.
        Ilo2A = "ilo2_a",
        /// ILO3-ILO3 (Table 4) acceleration, deg/s^2.
        Ilo3A = "ilo3_a",
        /// AD-AD (T = 0.1 s) acceleration, deg/s^2.
        AdA = "ad_a",
        /// ED-ED acceleration, deg/s^2.
        EdA = "ed_a",
        /// Kalman tracker acceleration, deg/s^2.
        KfA = "kf_a",
    }
    rows {
        /// AVE and AVE-AVE.
        ave: VelAcc<AveParams<T>> = ave_pair(cfg) => [AveV = velocity, AveA = acceleration];
        /// ILO1, Table 2 gains.
        ilo1_v: ClosedForm<IloParams<T, 1>> = ilo_v(cfg, 0, n0, prev) => [Ilo1V = output];
        /// ILO2, Table 2 gains.
        ilo2_v: ClosedForm<IloParams<T, 1>> = ilo_v(cfg, 1, n0, prev) => [Ilo2V = output];
        /// ILO3, Table 2 gains.
        ilo3_v: ClosedForm<IloParams<T, 1>> = ilo_v(cfg, 2, n0, prev) => [Ilo3V = output];
        /// AD.
        ad_v: ClosedForm<AdParams<T>> = ad_v(cfg, n0, prev) => [AdV = output];
        /// ED and ED-ED.
        ed: VelAcc<EdParams<T, S>> = ed_pair(cfg) => [EdV = velocity, EdA = acceleration];
        /// Kalman tracker with the velocity noise.
        kf_v: KalmanParams<T> = kalman(cfg, &cfg.velocity, KalmanOutput::Velocity) => [KfV = velocity];
        /// ILO1-ILO1, Table 4 gains.
        ilo1_a: IloIloMap<T> = ilo_a(cfg, 0, n0, prev) => [Ilo1A = output];
        /// ILO2-ILO2, Table 4 gains.
        ilo2_a: IloIloMap<T> = ilo_a(cfg, 1, n0, prev) => [Ilo2A = output];
        /// ILO3-ILO3, Table 4 gains.
        ilo3_a: IloIloMap<T> = ilo_a(cfg, 2, n0, prev) => [Ilo3A = output];
        /// AD-AD.
        ad_a: AdAdMap<T> = ad_a(cfg, n0, prev) => [AdA = output];
        /// Kalman tracker with the acceleration noise.
        kf_a: KalmanParams<T> = kalman(cfg, &cfg.acceleration, KalmanOutput::Acceleration) => [KfA = acceleration];
    }
}

impl PaperOutput {
    /// The seven velocities, deg/s, in [`Channel::VELOCITY`] order.
    pub fn velocities(&self) -> [f32; 7] {
        Channel::VELOCITY.map(|c| self[c])
    }

    /// The seven accelerations, deg/s^2, in [`Channel::ACCELERATION`] order.
    pub fn accelerations(&self) -> [f32; 7] {
        Channel::ACCELERATION.map(|c| self[c])
    }
}

/// The paper bank under its former name (one axis: unwrapping, `new_epoch`, `set_turns`).
pub type YawBank<T, S = ExactSqrt> = PaperBank<T, S>;
/// The paper bank's output under its former name.
pub type BankOutput = PaperOutput;

impl Channel {
    /// The seven velocity channels (ave, ilo1, ilo2, ilo3, ad, ed, kf).
    pub const VELOCITY: [Channel; 7] = [
        Channel::AveV,
        Channel::Ilo1V,
        Channel::Ilo2V,
        Channel::Ilo3V,
        Channel::AdV,
        Channel::EdV,
        Channel::KfV,
    ];
    /// The seven acceleration channels, same order.
    pub const ACCELERATION: [Channel; 7] = [
        Channel::AveA,
        Channel::Ilo1A,
        Channel::Ilo2A,
        Channel::Ilo3A,
        Channel::AdA,
        Channel::EdA,
        Channel::KfA,
    ];
}

estimator_bank! {
    /// The product preset: one velocity and one acceleration estimator per axis, the two
    /// cheapest good ones of the paper bank: ILO1 (Table 2 gains of `cfg.velocity.ilo[0]`,
    /// through its exact closed-form map; the best ILO without noise) for velocity and the
    /// Kalman tracker (`cfg.acceleration.kf`) for acceleration, each a few dozen operations per
    /// sample. Same input stage, API and output conventions as [`PaperBank`]; a firmware that
    /// wants other estimators writes its own table with [`crate::estimator_bank!`].
    bank ProductBank, params ProductParams, state ProductState, output ProductOutput, channel ProductChannel;
    build(cfg, n0, prev);
    channels {
        /// ILO1 velocity, deg/s.
        Ilo1V = "ilo1_v",
        /// Kalman tracker acceleration, deg/s^2.
        KfA = "kf_a",
    }
    rows {
        /// ILO1, Table 2 gains.
        ilo1_v: ClosedForm<IloParams<T, 1>> = ilo_v(cfg, 0, n0, prev) => [Ilo1V = output];
        /// Kalman tracker with the acceleration noise.
        kf_a: KalmanParams<T> = kalman(cfg, &cfg.acceleration, KalmanOutput::Acceleration) => [KfA = acceleration];
    }
}
