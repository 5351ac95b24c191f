//! The configuration of a bank: [`BankConfig`](crate::BankConfig), and the named gain sets of
//! its halves ([`BankGains`], declared with the family list in `bank/paper.rs`).

use super::BankGains;
use crate::presets::*;
use crate::{EdScheme, Hold, KalmanNoise};

impl BankGains {
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
    /// Velocity gains of [`BankConfig::NAV440`]: the first band of the rate table
    /// ([`BankConfig::NAV440_RATES`], `estimators/src/rates.rs`; see [`BankConfig::NAV440`]
    /// how they were produced: printed by
    /// `cargo test --release -p host-tests --test preset -- --ignored --nocapture`). The AVE
    /// keeps the leaky `deltahat` law of [`AVE_DEFAULT`]; each ILO was tuned to beat its own
    /// paper preset, so ILO1-3 differ; the tracker's `q/r` is what was tuned.
    pub const NAV440_VELOCITY: Self = crate::rates::band_gains(0, 0);
    /// Acceleration gains of [`BankConfig::NAV440`] (both stages of each series).
    pub const NAV440_ACCELERATION: Self = crate::rates::band_gains(0, 1);
}

/// Default tracker noise (our choice, not the paper's): `r = 0.01 deg^2` (the paper's smaller
/// noise level), `q = 1e6 deg^2/s^5` (hand rotation: jerk of order 1e4 deg/s^3 over 0.1 s).
pub const KF_DEFAULT: KalmanNoise = KalmanNoise { q: 1.0e6, r: 0.01 };

/// Configuration of a [`PaperBank`](crate::PaperBank).
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
    /// sample. Default [`GAP_PERIODS`] (25: 0.25 s at 100 Hz, 12.5 s at 2 Hz); at most
    /// [`MAX_GAP_PERIODS`] (1000).
    pub max_gap_periods: f32,
    /// Nominal sample period, s: **set it to the sensor's** (e.g. 0.005 at 200 Hz). Default
    /// 0.01 (100 Hz, the NAV440's), and nothing warns when it is wrong: the bank runs any
    /// interval (`round(dt / h)` steps per sample), but the closed-form maps are precomputed
    /// for `round(sample_period_s / h)` steps, the Kalman tracker's steady-state gains are
    /// computed for this period, and the gap rule is a multiple of it.
    /// `nav440_pipeline::period` measures it from a stream's first samples (what the host CLI
    /// and the firmware do).
    pub sample_period_s: f32,
    /// Use the exact closed-form multi-step maps for the linear laws (default `true`); `false`
    /// steps every law `n` times (same results to rounding).
    pub closed_form: bool,
    /// Discretisation of the ED and ED-ED (default [`EdScheme::Euler`], the paper's).
    pub ed_scheme: EdScheme,
    /// How the input angle is unwrapped (default [`Wrap::Deg180`]: yaw and roll, reported
    /// within +-180 deg; pitch, within +-90 deg, and any signal that does not wrap take
    /// [`Wrap::None`]: with the default, a jump of more than 180 between two samples is taken
    /// as a wrap).
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
    /// (docs/PRESETS.md). These gains are for 20-100 Hz: at a lower
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

/// Default gap rule, in nominal sample periods: 25 (0.25 s at 100 Hz). The bank integrates
/// across up to 24 lost packets at any packet rate.
pub const GAP_PERIODS: f32 = 25.0;

/// Longest gap rule a bank accepts ([`BankConfig::max_gap_periods`]), in nominal sample periods:
/// 1000, below the Kalman tracker's [`crate::kalman::MAX_SUBSTEPS`] (1024), so that every
/// interval a bank integrates across is one the tracker sub-steps (a longer one is the bank's
/// gap, counted by its `reinit_count`). Larger: [`crate::ConfigError::GapTooLong`].
pub const MAX_GAP_PERIODS: f32 = 1000.0;

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
