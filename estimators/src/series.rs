//! Series connection of two estimators: the paper's acceleration estimator (section 3.2.2).

use crate::law::{Law, Stateful};
use crate::linear::{LinearLaw, LIN_MAX};
use crate::Real;

/// Two laws in series: `A` estimates `theta1 = dx/dt` from `y`, `B` estimates
/// `theta2 = dtheta1/dt` from `A`'s output. The paper's continuous-time series: in every step
/// `h`, `B` is fed `A`'s output of that same step (not once per sample).
///
/// Output: `B`'s output (deg/s^2 for `y` in deg). No stability proof exists for the series
/// (paper section 3.2.2); the ILO series with `K1 = 1` diverges (see the tests). Both stages
/// are parameter sets ([`Law`]); the state is the pair of the stages' states.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Series<A, B> {
    /// First stage (velocity).
    pub a: A,
    /// Second stage (acceleration).
    pub b: B,
}

/// State of a [`Series`]: the stages' states.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeriesState<SA, SB> {
    /// First stage.
    pub a: SA,
    /// Second stage.
    pub b: SB,
}

impl<A, B> Series<A, B> {
    /// Connects `a` -> `b`.
    pub const fn new(a: A, b: B) -> Self {
        Self { a, b }
    }
}

impl<A: Law, B: Law<Num = A::Num>> Series<A, B> {
    /// The series of two estimator objects' parameters, as one estimator object (both states
    /// start at 0; use [`crate::Estimator::reset`]).
    pub fn of(a: &Stateful<A>, b: &Stateful<B>) -> Stateful<Self> {
        Stateful::from_law(Self::new(*a.law(), *b.law()))
    }
}

impl<T: Real, A: Law<Num = T>, B: Law<Num = T>> Law for Series<A, B> {
    type Num = T;
    type State = SeriesState<A::State, B::State>;

    /// `A` starts at `y0` with velocity 0; `B` starts at `A`'s output (0) with acceleration 0.
    fn init(&self, y0: T) -> Self::State {
        let a = self.a.init(y0);
        let b = self.b.init(self.a.output(&a));
        SeriesState { a, b }
    }

    /// `o1 = A.step(y); return B.step(o1)`.
    #[inline(always)]
    fn step(&self, s: &mut Self::State, y: T) -> T {
        let o1 = self.a.step(&mut s.a, y);
        self.b.step(&mut s.b, o1)
    }

    #[inline]
    fn output(&self, s: &Self::State) -> T {
        self.b.output(&s.b)
    }

    /// Only `A` sees the input; `B`'s input (a velocity) does not move.
    #[inline]
    fn translate(&self, s: &mut Self::State, d: T) {
        self.a.translate(&mut s.a, d);
    }

    /// Each stage on its own; the second stage's input is the first stage's output.
    fn retune_state(&self, old: &Self, s: &mut Self::State, y: T) {
        self.a.retune_state(&old.a, &mut s.a, y);
        let y2 = self.a.output(&s.a);
        self.b.retune_state(&old.b, &mut s.b, y2);
    }
}

impl<T: Real, A: LinearLaw<Num = T>, B: LinearLaw<Num = T>> LinearLaw for Series<A, B> {
    const DIM: usize = A::DIM + B::DIM;
    /// Only `A`'s positions move with an input offset (`B`'s input is a velocity).
    const POSITION: [bool; LIN_MAX] = A::POSITION;

    /// `[A's state, B's state]`.
    #[inline]
    fn lin_state(&self, st: &Self::State) -> [T; LIN_MAX] {
        let sa = self.a.lin_state(&st.a);
        let sb = self.b.lin_state(&st.b);
        let mut s = sa;
        for (i, x) in sb.iter().enumerate().take(B::DIM) {
            if let Some(d) = s.get_mut(A::DIM + i) {
                *d = *x;
            }
        }
        s
    }

    #[inline]
    fn set_lin_state(&self, st: &mut Self::State, s: &[T; LIN_MAX]) {
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
        self.a.set_lin_state(&mut st.a, &sa);
        self.b.set_lin_state(&mut st.b, &sb);
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
