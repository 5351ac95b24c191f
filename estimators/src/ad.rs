//! Approximate differentiator, AD: `s / (T s + 1)`.

use crate::bank::{BankGains, Channel};
use crate::error::positive;
use crate::family::{geometric, Family, Follows, Gains, LawVisitor, Scheduling};
use crate::law::{Law, Stateful};
use crate::linear::{LinearLaw, LIN_MAX};
use crate::{ConfigError, Real};

/// The approximate differentiator `G(s) = s / (T s + 1)` (a derivative behind a first-order
/// low-pass of time constant `T`), realised as `u = (y - z) / T`, `dz/dt = u`.
///
/// Output `u`: deg/s for `y` in deg. Paper: `T = 0.01 s` for velocity, a series of two with
/// `T = 0.1 s` for acceleration. The validated coefficients ([`crate::Law`]); the state is
/// [`AdState`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdParams<T: Real> {
    inv_t: T,
    h: T,
}

/// State of the AD: the low-passed input `z` and the last output `u`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdState<T: Real> {
    /// Low-passed input `z` (unit of `y`).
    pub z: T,
    /// Last output `u` (unit/s).
    pub u: T,
}

/// The AD as one object (parameters and state, [`crate::Estimator`]).
/// RAM: 4 words of `T` (see [`crate::ram`]).
pub type Ad<T> = Stateful<AdParams<T>>;

impl<T: Real> AdParams<T> {
    /// Validates the time constant `t` (s) for step `h` (s). Errors: non-positive or
    /// non-finite `t`, `h`; `h >= t` (forward Euler needs `h / T < 1`).
    pub fn new(t: f32, h: f32) -> Result<Self, ConfigError> {
        let t = positive("T", f64::from(t))?;
        let h = positive("h", f64::from(h))?;
        if h >= t {
            return Err(ConfigError::StepTooLarge("1/T"));
        }
        Ok(Self {
            inv_t: T::from_f64(1.0 / t),
            h: T::from_f64(h),
        })
    }
}

impl<T: Real> Ad<T> {
    /// Builds the differentiator (see [`AdParams::new`]).
    pub fn new(t: f32, h: f32) -> Result<Self, ConfigError> {
        Ok(Self::from_law(AdParams::new(t, h)?))
    }
}

impl<T: Real> Law for AdParams<T> {
    type Num = T;
    type State = AdState<T>;

    fn init(&self, y0: T) -> AdState<T> {
        AdState { z: y0, u: T::ZERO }
    }

    /// Explicit Euler step of `dz/dt = (y - z) / T`:
    ///
    /// ```text
    /// u_n     = (y_n - z_n) / T
    /// z_{n+1} = z_n + h u_n
    /// ```
    /// Returns `u_n`.
    #[inline(always)]
    fn step(&self, s: &mut AdState<T>, y: T) -> T {
        let u = (y - s.z) * self.inv_t;
        s.z = s.z + self.h * u;
        s.u = u;
        u
    }

    #[inline]
    fn output(&self, s: &AdState<T>) -> T {
        s.u
    }

    #[inline]
    fn translate(&self, s: &mut AdState<T>, d: T) {
        s.z = s.z + d;
    }

    /// In equilibrium `y - z = T u`: `z = y - T u`, the output `u` kept, so the next step at
    /// `y` returns `u`. `T` in f64. Nothing when `T` did not change.
    fn retune_state(&self, old: &Self, s: &mut AdState<T>, y: T) {
        if self == old {
            return;
        }
        let t = 1.0 / self.inv_t.to_f64();
        s.z = y - T::from_f64(t * s.u.to_f64());
    }
}

impl<T: Real> LinearLaw for AdParams<T> {
    const DIM: usize = 2;
    const POSITION: [bool; LIN_MAX] = [true, false, false, false];

    /// `[z, u]`.
    #[inline]
    fn lin_state(&self, s: &AdState<T>) -> [T; LIN_MAX] {
        [s.z, s.u, T::ZERO, T::ZERO]
    }

    #[inline]
    fn set_lin_state(&self, st: &mut AdState<T>, s: &[T; LIN_MAX]) {
        st.z = s[0];
        st.u = s[1];
    }

    fn lin_step_f64(&self, s: &mut [f64; LIN_MAX], y: f64) -> f64 {
        let u = (y - s[0]) * self.inv_t.to_f64();
        s[0] += self.h.to_f64() * u;
        s[1] = u;
        u
    }
}

/// Parameters of the approximate differentiator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct AdConfig {
    /// Time constant `T`, s (paper: 0.01 for velocity, 0.1 for each acceleration stage).
    pub t: f32,
}

/// The AD family of the paper bank: AD velocity, AD-AD acceleration; gains
/// [`BankGains::ad_t`] (the time constant, as an [`AdConfig`]).
#[derive(Clone, Copy, Debug)]
pub struct AdFamily;

impl Family for AdFamily {
    type Gains = AdConfig;
    const NAME: &'static str = "ad";
    const LABEL: &'static str = "AD";
    const VELOCITY: Channel = Channel::AdV;
    const ACCELERATION: Channel = Channel::AdA;
    const SCHEDULING: Scheduling = Scheduling::Smooth;
    const FOLLOWS: Follows = Follows::Acceleration;

    fn get(half: &BankGains) -> AdConfig {
        AdConfig { t: half.ad_t }
    }

    fn set(half: &mut BankGains, gains: AdConfig) {
        half.ad_t = gains.t;
    }
}

impl Gains for AdConfig {
    /// `T` geometrically.
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        AdConfig {
            t: geometric(self.t, other.t, w),
        }
    }

    /// [`AdParams`].
    fn build<V: LawVisitor>(&self, h: f32, to: V) -> Result<V::Output, ConfigError> {
        Ok(to.law(AdParams::<f32>::new(self.t, h)?))
    }
}
