//! Series connection of two estimators: the paper's acceleration estimator (section 3.2.2).

use crate::linear::{LinearLaw, LIN_MAX};
use crate::{Estimator, Real};

/// Two estimators in series: `A` estimates `theta1 = dx/dt` from `y`, `B` estimates
/// `theta2 = dtheta1/dt` from `A`'s output. The paper's continuous-time series: in every step
/// `h`, `B` is fed `A`'s output of that same step (not once per sample).
///
/// Output: `B`'s output (deg/s^2 for `y` in deg). No stability proof exists for the series
/// (paper section 3.2.2); the ILO series with `K1 = 1` diverges (see the tests).
///
/// RAM: `size_of::<A>() + size_of::<B>()`.
#[derive(Clone, Copy, Debug)]
pub struct Series<A, B> {
    /// First stage (velocity).
    pub a: A,
    /// Second stage (acceleration).
    pub b: B,
}

impl<A, B> Series<A, B> {
    /// Connects `a` -> `b`.
    pub const fn new(a: A, b: B) -> Self {
        Self { a, b }
    }
}

impl<T: Real, A: Estimator<T>, B: Estimator<T>> Estimator<T> for Series<A, B> {
    /// `A` starts at `y0` with velocity 0; `B` starts at `A`'s output (0) with acceleration 0.
    fn reset(&mut self, y0: T) {
        self.a.reset(y0);
        self.b.reset(self.a.output());
    }

    /// `o1 = A.step(y); return B.step(o1)`.
    #[inline]
    fn step(&mut self, y: T) -> T {
        let o1 = self.a.step(y);
        self.b.step(o1)
    }

    fn output(&self) -> T {
        self.b.output()
    }

    /// Only `A` sees the input; `B`'s input (a velocity) does not move.
    fn translate(&mut self, d: T) {
        self.a.translate(d);
    }
}

impl<T: Real, A: LinearLaw<T>, B: LinearLaw<T>> LinearLaw<T> for Series<A, B> {
    const DIM: usize = A::DIM + B::DIM;
    /// Only `A`'s positions move with an input offset (`B`'s input is a velocity).
    const POSITION: [bool; LIN_MAX] = A::POSITION;

    /// `[A's state, B's state]`.
    fn lin_state(&self) -> [T; LIN_MAX] {
        let sa = self.a.lin_state();
        let sb = self.b.lin_state();
        let mut s = sa;
        for (i, x) in sb.iter().enumerate().take(B::DIM) {
            if let Some(d) = s.get_mut(A::DIM + i) {
                *d = *x;
            }
        }
        s
    }

    fn set_lin_state(&mut self, s: &[T; LIN_MAX]) {
        let mut sa = [T::ZERO; LIN_MAX];
        let mut sb = [T::ZERO; LIN_MAX];
        for (i, x) in s.iter().enumerate() {
            if i < A::DIM {
                if let Some(d) = sa.get_mut(i) {
                    *d = *x;
                }
            } else if let Some(d) = sb.get_mut(i - A::DIM) {
                *d = *x;
            }
        }
        self.a.set_lin_state(&sa);
        self.b.set_lin_state(&sb);
    }

    fn lin_step_f64(&self, s: &mut [f64; LIN_MAX], y: f64) -> f64 {
        let mut sa = [0.0; LIN_MAX];
        let mut sb = [0.0; LIN_MAX];
        for (i, x) in s.iter().enumerate() {
            if i < A::DIM {
                if let Some(d) = sa.get_mut(i) {
                    *d = *x;
                }
            } else if let Some(d) = sb.get_mut(i - A::DIM) {
                *d = *x;
            }
        }
        let o1 = self.a.lin_step_f64(&mut sa, y);
        let o2 = self.b.lin_step_f64(&mut sb, o1);
        for (i, x) in s.iter_mut().enumerate() {
            if i < A::DIM {
                if let Some(v) = sa.get(i) {
                    *x = *v;
                }
            } else if let Some(v) = sb.get(i - A::DIM) {
                *x = *v;
            }
        }
        o2
    }
}
