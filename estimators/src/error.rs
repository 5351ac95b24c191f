//! Typed errors.

/// A parameter set that a constructor rejects. Every constructor validates its physical
/// parameters once; an accepted configuration can never make an update panic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// A parameter is NaN or infinite (the payload names it, e.g. `"gamma1"`).
    NotFinite(&'static str),
    /// A gain or time constant that must be `> 0` is not (the payload names it).
    NotPositive(&'static str),
    /// A gain that must be `>= 0` is negative (the payload names it).
    Negative(&'static str),
    /// `K1` is outside `(0, 1]` (Theorem 3.1 needs `0 < K1^T K1 <= 1`).
    K1OutOfRange,
    /// The step `h` is not a whole number of microseconds in `[1 us, 1 s]` (the sample adapter
    /// counts steps on integer microsecond timestamps).
    StepNotWholeMicroseconds,
    /// The explicit-Euler step is too large for a gain: `h * gain` must stay below 1 (stability
    /// of the forward-Euler update; the payload names the gain).
    StepTooLarge(&'static str),
    /// A switching gain moves its integrator by more than [`crate::ED_MAX_H_ALPHA`] (1e6
    /// unit/s) in one step: `h * gain` is past that (the payload names the gain, e.g. the
    /// ED's `"alpha"`, whose integrator `u1` changes by `h alpha` per step, and the output
    /// with it).
    StepRateTooLarge(&'static str),
    /// The maximum gap is shorter than one step `h`.
    GapTooShort,
    /// A bank's gap rule is more than [`crate::MAX_GAP_PERIODS`] (1000) nominal periods (the
    /// Kalman tracker sub-steps an interval of at most [`crate::kalman::MAX_SUBSTEPS`]).
    GapTooLong,
    /// The nominal sample period is not at least one step `h`.
    SamplePeriodTooShort,
    /// The nominal sample period is more than `10^6` steps `h` (the closed-form maps and the
    /// step count of one interval are limited to that).
    SamplePeriodTooLong,
    /// The image holds no bank built for this nominal sample period: a firmware whose banks
    /// were built on the host at build time has them for the NAV440's packet rates only
    /// (docs/FOOTPRINT.md).
    SamplePeriodNotPrebuilt,
    /// A gain schedule needs 1 to `MAX_LEVELS` levels with strictly increasing noise
    /// variances > 0.
    ScheduleLevels,
    /// Per-sample observer poles that ILO1 cannot take ([`crate::IloConfig::per_sample`]): the
    /// damping is not in `(0, 1)`, the damped frequency is not below the Nyquist frequency
    /// `pi / dt`, or the gains it needs break the Euler step's bound.
    ObserverPoles,
}

/// A sample that [`crate::PaperBank::update`] (or [`crate::SampleAdapter`]) refuses. The state is
/// left exactly as it was before the call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleError {
    /// The sample value is NaN or infinite.
    NotFinite,
    /// The timestamp is not later than the previous accepted one.
    NonIncreasingTime,
    /// `|angle| >` [`crate::PaperBank::MAX_ABS_DEG`] (only the banks check this): far beyond
    /// any angle, wrapped or already unwrapped, that f32 laws still resolve, and a value near
    /// `f32::MAX` would overflow the f32 states to NaN for good.
    OutOfRange,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotFinite(p) => write!(f, "parameter `{p}` is not finite"),
            Self::NotPositive(p) => write!(f, "parameter `{p}` must be > 0"),
            Self::Negative(p) => write!(f, "parameter `{p}` must be >= 0"),
            Self::K1OutOfRange => f.write_str("K1 must be in (0, 1]"),
            Self::StepNotWholeMicroseconds => {
                f.write_str("step h must be a whole number of microseconds in [1e-6, 1] s")
            }
            Self::StepTooLarge(p) => write!(f, "h * `{p}` must be < 1 for the Euler step"),
            Self::StepRateTooLarge(p) => write!(
                f,
                "h * `{p}` must be at most 1e6 (the change of the output in one step, unit/s)"
            ),
            Self::GapTooShort => f.write_str(
                "the gap rule (max_gap_periods x sample_period_s) must be at least one step h",
            ),
            Self::GapTooLong => f.write_str(
                "the gap rule (max_gap_periods) must be at most 1000 nominal sample periods",
            ),
            Self::SamplePeriodTooShort => f.write_str("sample period must be at least h"),
            Self::SamplePeriodTooLong => f.write_str("sample period must be at most 1e6 steps h"),
            Self::SamplePeriodNotPrebuilt => f.write_str(
                "no bank was built for this sample period: the image holds banks for the NAV440's packet rates only",
            ),
            Self::ScheduleLevels => f.write_str(
                "a gain schedule needs 1 to 8 levels with noise variances > 0, strictly increasing",
            ),
            Self::ObserverPoles => f.write_str(
                "per-sample observer poles need a damping in (0, 1), a damped frequency below pi / dt and h * L < 1",
            ),
        }
    }
}

impl core::fmt::Display for SampleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotFinite => f.write_str("sample is NaN or infinite"),
            Self::NonIncreasingTime => f.write_str("timestamp not later than the previous one"),
            Self::OutOfRange => f.write_str("|angle| above MAX_ABS_DEG (1e6 deg)"),
        }
    }
}

impl core::error::Error for ConfigError {}
impl core::error::Error for SampleError {}

/// Checks that `x` is finite and `> 0`.
pub(crate) fn positive(name: &'static str, x: f64) -> Result<f64, ConfigError> {
    if !x.is_finite() {
        Err(ConfigError::NotFinite(name))
    } else if x <= 0.0 {
        Err(ConfigError::NotPositive(name))
    } else {
        Ok(x)
    }
}

/// Checks that `x` is finite and `>= 0`.
pub(crate) fn non_negative(name: &'static str, x: f64) -> Result<f64, ConfigError> {
    if !x.is_finite() {
        Err(ConfigError::NotFinite(name))
    } else if x < 0.0 {
        Err(ConfigError::Negative(name))
    } else {
        Ok(x)
    }
}
