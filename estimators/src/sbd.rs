//! Smoothed backward difference, SBD: the backward difference of the input behind a first-order
//! low-pass of time constant `T`.

use crate::error::positive;
use crate::family::{geometric, Gains, LawVisitor};
use crate::law::Law;
use crate::{BankConfig, Channels, ConfigError, Real, Row, RowValues, SqrtFn, VelAcc, Warm};

/// The smoothed backward difference `v_{n+1} = v_n + (h / T) ((y_n - y_{n-1}) / h - v_n)`: the
/// slope of the input between two steps, low-passed with the time constant `T` (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SbdParams<T: Real> {
    inv_h: T,
    a: T,
}

/// State of the SBD: the last input `y` and the estimate `v`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SbdState<T: Real> {
    /// Last input (unit of `y`).
    pub y: T,
    /// Estimate (unit/s).
    pub v: T,
}

impl<T: Real> SbdParams<T> {
    /// Validates the time constant `cfg.t` (s) for the step `h` (s). Errors: non-positive or
    /// non-finite `t`, `h`; `h >= t`.
    pub fn new(cfg: &SbdConfig, h: f32) -> Result<Self, ConfigError> {
        let t = positive("T", f64::from(cfg.t))?;
        let h = positive("h", f64::from(h))?;
        if h >= t {
            return Err(ConfigError::StepTooLarge("1/T"));
        }
        Ok(Self {
            inv_h: T::from_f64(1.0 / h),
            a: T::from_f64(h / t),
        })
    }
}

impl<T: Real> Law for SbdParams<T> {
    type Num = T;
    type State = SbdState<T>;

    fn init(&self, y0: T) -> SbdState<T> {
        SbdState { y: y0, v: T::ZERO }
    }

    #[inline(always)]
    fn step(&self, s: &mut SbdState<T>, y: T) -> T {
        let d = (y - s.y) * self.inv_h;
        s.v = s.v + self.a * (d - s.v);
        s.y = y;
        s.v
    }

    #[inline]
    fn output(&self, s: &SbdState<T>) -> T {
        s.v
    }

    #[inline]
    fn translate(&self, s: &mut SbdState<T>, d: T) {
        s.y = s.y + d;
    }
}

/// Gains of the SBD.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct SbdConfig {
    /// Time constant `T`, s.
    pub t: f32,
}

/// The SBD's velocity gains in the paper bank's default set (`T = 0.01` s).
pub const SBD_VELOCITY: SbdConfig = SbdConfig { t: 0.01 };
/// The SBD's acceleration gains (each stage of the SBD-SBD series, `T = 0.1` s).
pub const SBD_ACCELERATION: SbdConfig = SbdConfig { t: 0.1 };

impl Gains for SbdConfig {
    /// `T` geometrically.
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        SbdConfig {
            t: geometric(self.t, other.t, w),
        }
    }

    /// [`SbdParams`].
    fn build<V: LawVisitor>(&self, h: f32, to: V) -> Result<V::Output, ConfigError> {
        Ok(to.law(SbdParams::<f32>::new(self, h)?))
    }
}

crate::family::family! {
    /// The SBD family of the paper bank: SBD velocity, SBD-SBD acceleration (one
    /// [`SbdRow`]); gains [`BankGains::sbd`](crate::BankGains::sbd).
    SbdFamily {
        gains: SbdConfig = BankGains::sbd,
        name: "sbd",
        label: "SBD",
        channels: SbdV, SbdA,
        scheduling: Smooth,
    }
}

/// SBD velocity and SBD-SBD acceleration (`cfg.velocity.sbd`, `cfg.acceleration.sbd`; one
/// shared first stage when the two are equal). Moved bumplessly on a warm gain change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SbdRow;

impl Channels for SbdRow {
    const VELOCITY: &'static [&'static str] = &["sbd_v"];
    const ACCELERATION: &'static [&'static str] = &["sbd_a"];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for SbdRow {
    type Law = VelAcc<SbdParams<T>>;
    fn build(cfg: &BankConfig, _: u32, _: Option<&Self::Law>) -> Result<Self::Law, ConfigError> {
        let (v, a) = (&cfg.velocity.sbd, &cfg.acceleration.sbd);
        let pa = SbdParams::new(a, cfg.h)?;
        Ok(VelAcc::new(SbdParams::new(v, cfg.h)?, pa, pa, v == a))
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_>) {
        out.velocity(law.velocity(s));
        out.acceleration(law.acceleration(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::bumpless_if(
            (old.velocity.sbd, old.acceleration.sbd) != (new.velocity.sbd, new.acceleration.sbd),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Series, Stateful};

    /// On a ramp the SBD settles on its slope, the SBD-SBD series on zero; on a parabola the
    /// series settles on its curvature; a step not below `T` is refused.
    #[test]
    fn sbd_tracks_slope_and_curvature() {
        let h = 1e-3;
        let p = SbdParams::<f64>::new(&SbdConfig { t: 0.01 }, h).unwrap();
        let mut v = Stateful::from_law(p);
        let mut a = Stateful::from_law(Series::new(p, p));
        let (mut out_v, mut out_a) = (0.0, 0.0);
        for k in 0..2000 {
            let t = f64::from(k) * f64::from(h);
            out_v = crate::Estimator::step(&mut v, 30.0 * t);
            out_a = crate::Estimator::step(&mut a, 2.0 * t * t);
        }
        assert!((out_v - 30.0).abs() < 1e-6, "{out_v}");
        assert!((out_a - 4.0).abs() < 1e-3, "{out_a}");
        assert!(SbdParams::<f32>::new(&SbdConfig { t: 1e-3 }, 1e-3).is_err());
        assert!(SbdParams::<f32>::new(&SbdConfig { t: -1.0 }, 1e-3).is_err());
    }
}
