//! Levant's robust exact differentiator, ED (paper eqs. 5-7; Levant 1998).

use crate::error::positive;
use crate::{ConfigError, Estimator, ExactSqrt, Real, SqrtFn};
use core::marker::PhantomData;

/// Parameters of the exact differentiator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EdConfig {
    /// Gain `lambda` of the `|e|^(1/2)` term, unit^(1/2)/s (paper: 700, in deg^(1/2)/s).
    pub lambda: f32,
    /// Gain `alpha` of the integral switching term, unit/s^2 (paper: 770 deg/s^2); must exceed
    /// the bound `C` of the input's second derivative for exactness.
    pub alpha: f32,
}

/// How the ED's discontinuous law is discretised.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EdScheme {
    /// Explicit Euler (paper-faithful default). Chatters: `z` oscillates around `y` with
    /// `|e| ~ (lambda h)^2` and `u` with an amplitude of order `lambda^2 h` (about 25-50 deg/s
    /// at `h = 1e-4`, `lambda = 700`).
    #[default]
    Euler,
    /// Implicit (backward) Euler of the differential inclusion in the sign and root terms
    /// (Acary-Brogliato style): no numerical chattering; on the sliding set the output is the
    /// exact finite difference of the input. Same cost (one square root per step).
    Implicit,
}

/// Levant's first-order robust exact differentiator, `e = z - y`:
///
/// ```text
/// dz/dt  = u                                  (eq. 5)
/// u      = u1 - lambda |e|^(1/2) sgn(e)       (eq. 6)
/// du1/dt = -alpha sgn(e)                      (eq. 7)
/// ```
///
/// Output: `u` (deg/s for `y` in deg); [`Ed::u1`] exposes the integrator state. Exact in finite
/// time on noise-free inputs with `|y''| <= C < alpha` and `lambda` large enough; with noise of
/// amplitude `eps` the error is of order `sqrt(eps)`.
///
/// `|e|^(1/2)` uses the exact square root `S` (default [`ExactSqrt`] = [`Real::sqrt`]; a
/// firmware may plug in its FPU instruction, see [`SqrtFn`]); `micromath`'s fast approximation
/// would bias it (measured in the tests, see the crate README).
///
/// RAM: 10 words of `T` and the scheme tag (see [`crate::ram`]).
#[derive(Clone, Copy, Debug)]
pub struct Ed<T: Real, S: SqrtFn<T> = ExactSqrt> {
    h: T,
    halpha: T,
    lambda: T,
    h2alpha: T,
    inv_h2alpha: T,
    half_hl: T,
    half_hl_sq: T,
    implicit: bool,
    z: T,
    u1: T,
    u: T,
    sqrt: PhantomData<S>,
}

impl<T: Real, S: SqrtFn<T>> Ed<T, S> {
    /// Builds the differentiator for step `h` (s) with the paper's explicit Euler scheme.
    /// Errors: non-positive or non-finite `lambda`, `alpha`, `h`.
    pub fn new(cfg: &EdConfig, h: f32) -> Result<Self, ConfigError> {
        Self::with_scheme(cfg, h, EdScheme::Euler)
    }

    /// Builds the differentiator with the given discretisation scheme.
    pub fn with_scheme(cfg: &EdConfig, h: f32, scheme: EdScheme) -> Result<Self, ConfigError> {
        let h = positive("h", f64::from(h))?;
        let lambda = positive("lambda", f64::from(cfg.lambda))?;
        let alpha = positive("alpha", f64::from(cfg.alpha))?;
        Ok(Self {
            h: T::from_f64(h),
            halpha: T::from_f64(h * alpha),
            lambda: T::from_f64(lambda),
            h2alpha: T::from_f64(h * h * alpha),
            inv_h2alpha: T::from_f64(1.0 / (h * h * alpha)),
            half_hl: T::from_f64(0.5 * h * lambda),
            half_hl_sq: T::from_f64(0.25 * h * h * lambda * lambda),
            implicit: scheme == EdScheme::Implicit,
            z: T::ZERO,
            u1: T::ZERO,
            u: T::ZERO,
            sqrt: PhantomData,
        })
    }

    /// The integrator state `u1` of eq. 7 (unit/s).
    pub fn u1(&self) -> T {
        self.u1
    }

    /// The output `u` of eq. 6 (unit/s), same as [`Estimator::output`].
    pub fn u(&self) -> T {
        self.u
    }

    /// The position estimate `z` (unit of `y`).
    pub fn z(&self) -> T {
        self.z
    }

    /// One step of [`EdScheme::Implicit`] (see [`Estimator::step`]). Kept out of line so the
    /// default explicit step stays as short as without the option.
    #[inline(never)]
    fn step_implicit(&mut self, y: T) -> T {
        let p = (self.z - y) + self.h * self.u1;
        let ap = p.abs();
        let u = if ap <= self.h2alpha {
            self.u1 = self.u1 - self.halpha * (p * self.inv_h2alpha);
            self.u1
        } else {
            let r = S::sqrt(self.half_hl_sq + (ap - self.h2alpha)) - self.half_hl;
            let lr = self.lambda * r;
            if p > T::ZERO {
                self.u1 = self.u1 - self.halpha;
                self.u1 - lr
            } else {
                self.u1 = self.u1 + self.halpha;
                self.u1 + lr
            }
        };
        self.z = self.z + self.h * u;
        self.u = u;
        u
    }
}

impl<T: Real, S: SqrtFn<T>> Estimator<T> for Ed<T, S> {
    fn reset(&mut self, y0: T) {
        self.z = y0;
        self.u1 = T::ZERO;
        self.u = T::ZERO;
    }

    /// Explicit Euler step, `e_n = z_n - y_n`, `s_n = sgn(e_n)`:
    ///
    /// ```text
    /// u_n      = u1_n - lambda |e_n|^(1/2) s_n
    /// z_{n+1}  = z_n + h u_n
    /// u1_{n+1} = u1_n - h alpha s_n
    /// ```
    /// Returns `u_n`. (Explicit Euler chatters: `|e| ~ (lambda h)^2`, `u` by `~ lambda^2 h`.)
    ///
    /// [`EdScheme::Implicit`]: the sign and root terms are taken at the new error
    /// `e_{n+1} = z_{n+1} - y_n`, `s in Sgn(e_{n+1})` (set-valued at 0), which has the unique
    /// solution, with `p = z_n - y_n + h u1_n`:
    ///
    /// ```text
    /// |p| <= h^2 alpha:  s = p / (h^2 alpha),  r = 0           (sliding: e_{n+1} = 0)
    /// otherwise:         s = sgn p,            r = sqrt((h lambda / 2)^2 + |p| - h^2 alpha) - h lambda / 2
    /// u1_{n+1} = u1_n - h alpha s,   u_n = u1_{n+1} - lambda r s,   z_{n+1} = z_n + h u_n
    /// ```
    /// (`r = |e_{n+1}|^(1/2)` solves `r^2 + h lambda r = |p| - h^2 alpha`.)
    #[inline]
    fn step(&mut self, y: T) -> T {
        if self.implicit {
            return self.step_implicit(y);
        }
        let e = self.z - y;
        let (u, du1) = if e > T::ZERO {
            (self.u1 - self.lambda * S::sqrt(e), -self.halpha)
        } else if e < T::ZERO {
            (self.u1 + self.lambda * S::sqrt(-e), self.halpha)
        } else {
            (self.u1, T::ZERO)
        };
        self.z = self.z + self.h * u;
        self.u1 = self.u1 + du1;
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
