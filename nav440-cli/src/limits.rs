//! The limits of the numbers the command line accepts and their checks, shared by the
//! commands (`src/cmd/`) and the modules that check the same numbers in other places (a
//! synth motion file, a schedule file, the sim's and the serial link's options): each check
//! returns the value, or a usage error that names the flag and the range.

use crate::error::{Error, Result};

/// Parses a time range `T0-T1` (s), e.g. `0-15` or `12.5-30`.
pub fn parse_range(s: &str) -> std::result::Result<(f64, f64), String> {
    let bad = || format!("expected a time range T0-T1 in s (e.g. 0-15), got {s:?}");
    let (a, b) = s.split_once('-').ok_or_else(bad)?;
    let a: f64 = a.trim().parse().map_err(|_| bad())?;
    let b: f64 = b.trim().parse().map_err(|_| bad())?;
    if a.is_finite() && b.is_finite() && a >= 0.0 && b > a && b <= MAX_SECONDS {
        Ok((a, b))
    } else {
        Err(format!(
            "time range {s:?}: needs 0 <= T0 < T1 <= {MAX_SECONDS} s (30 days)"
        ))
    }
}

/// The largest noise variance any flag accepts, deg^2 (a standard deviation of 3.2e7 deg:
/// far beyond any capture, still finite through the f32 estimators).
pub const MAX_NOISE_VAR: f64 = 1e15;

/// `v` deg^2 of the flag `flag` if it is a noise variance in [0, [`MAX_NOISE_VAR`]]; a usage
/// error otherwise.
pub fn noise_var(flag: &str, v: f64) -> Result<f64> {
    if v.is_finite() && (0.0..=MAX_NOISE_VAR).contains(&v) {
        Ok(v)
    } else {
        Err(Error::Usage(format!(
            "{flag} must be >= 0 and <= 1e15 deg^2, got {v}"
        )))
    }
}

/// The observer step h range of `--step`, s.
pub const STEP_RANGE: std::ops::RangeInclusive<f32> = 1e-7..=1.0;

/// `h` s of `--step` if it lies in [`STEP_RANGE`]; a usage error otherwise.
pub fn step(h: f32) -> Result<f32> {
    if STEP_RANGE.contains(&h) {
        Ok(h)
    } else {
        Err(Error::Usage(format!(
            "--step must be a number of seconds >= 1e-7 and <= 1, got {h}"
        )))
    }
}

/// `v` of the flag `flag` if it lies in `range`; a usage error naming the range otherwise
/// (`unit` follows the range, e.g. " bytes").
pub fn count<T>(flag: &str, v: T, range: std::ops::RangeInclusive<T>, unit: &str) -> Result<T>
where
    T: PartialOrd + std::fmt::Display + Copy,
{
    if range.contains(&v) {
        Ok(v)
    } else {
        Err(Error::Usage(format!(
            "{flag} must be {} to {}{unit}, got {v}",
            range.start(),
            range.end()
        )))
    }
}

/// The longest duration or time-out any command accepts, s (30 days).
pub const MAX_SECONDS: f64 = 30.0 * 86_400.0;

/// `v` s of the flag `flag` if it is a finite number of seconds in (0, [`MAX_SECONDS`]] (0
/// also with `zero_ok`); a usage error otherwise.
pub fn seconds(flag: &str, v: f64, zero_ok: bool) -> Result<f64> {
    let low_ok = if zero_ok { v >= 0.0 } else { v > 0.0 };
    if v.is_finite() && low_ok && v <= MAX_SECONDS {
        Ok(v)
    } else {
        let low = if zero_ok { ">= 0" } else { "> 0" };
        Err(Error::Usage(format!(
            "{flag} must be a number of seconds {low} and <= {MAX_SECONDS} (30 days), got {v}"
        )))
    }
}
