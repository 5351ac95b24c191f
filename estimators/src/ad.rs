//! Approximate differentiator, AD: `s / (T s + 1)`.

use crate::error::positive;
use crate::linear::{LinearLaw, LIN_MAX};
use crate::{ConfigError, Estimator, Real};

/// The approximate differentiator `G(s) = s / (T s + 1)` (a derivative behind a first-order
/// low-pass of time constant `T`), realised as `u = (y - z) / T`, `dz/dt = u`.
///
/// Output `u`: deg/s for `y` in deg. Paper: `T = 0.01 s` for velocity, a series of two with
/// `T = 0.1 s` for acceleration.
///
/// RAM: 4 words of `T` (see [`crate::ram`]).
#[derive(Clone, Copy, Debug)]
pub struct Ad<T: Real> {
    inv_t: T,
    h: T,
    z: T,
    u: T,
}

impl<T: Real> Ad<T> {
    /// Builds the differentiator with time constant `t` (s) for step `h` (s). Errors:
    /// non-positive or non-finite `t`, `h`; `h >= t` (forward Euler needs `h / T < 1`).
    pub fn new(t: f32, h: f32) -> Result<Self, ConfigError> {
        let t = positive("T", f64::from(t))?;
        let h = positive("h", f64::from(h))?;
        if h >= t {
            return Err(ConfigError::StepTooLarge("1/T"));
        }
        Ok(Self {
            inv_t: T::from_f64(1.0 / t),
            h: T::from_f64(h),
            z: T::ZERO,
            u: T::ZERO,
        })
    }
}

impl<T: Real> Estimator<T> for Ad<T> {
    fn reset(&mut self, y0: T) {
        self.z = y0;
        self.u = T::ZERO;
    }

    /// Explicit Euler step of `dz/dt = (y - z) / T`:
    ///
    /// ```text
    /// u_n     = (y_n - z_n) / T
    /// z_{n+1} = z_n + h u_n
    /// ```
    /// Returns `u_n`.
    #[inline]
    fn step(&mut self, y: T) -> T {
        let u = (y - self.z) * self.inv_t;
        self.z = self.z + self.h * u;
        self.u = u;
        u
    }

    fn output(&self) -> T {
        self.u
    }

    fn translate(&mut self, d: T) {
        self.z = self.z + d;
    }
}

impl<T: Real> LinearLaw<T> for Ad<T> {
    const DIM: usize = 2;
    const POSITION: [bool; LIN_MAX] = [true, false, false, false];

    /// `[z, u]`.
    fn lin_state(&self) -> [T; LIN_MAX] {
        [self.z, self.u, T::ZERO, T::ZERO]
    }

    fn set_lin_state(&mut self, s: &[T; LIN_MAX]) {
        self.z = s[0];
        self.u = s[1];
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
pub struct AdConfig {
    /// Time constant `T`, s (paper: 0.01 for velocity, 0.1 for each acceleration stage).
    pub t: f32,
}
