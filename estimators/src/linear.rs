//! Exact multi-step maps for linear laws (ILO, AD and their series).
//!
//! A linear law stepped `n` times over one sample interval is a linear map of its state and of
//! the interval's input: with [`Hold::Linear`] the input is the ramp
//! `y_j = y_prev + dy * j / n`, with [`Hold::ZeroOrder`] the constant `y_prev + dy`. Because
//! every law here is invariant to adding a constant `c` to the input and to its position states
//! (`step(s + P c, y + c) = step(s, y) + P c`, `P` = [`LinearLaw::POSITION`]), the map is
//!
//! ```text
//! s_n - P y_prev = Phi (s_0 - P y_prev) + g dy,     Phi = M^n,  g = sum_j M^(n-j) B u_j
//! ```
//!
//! `Phi` and `g` are computed once at construction by stepping the same Euler law in `f64` on
//! the unit vectors, so the map equals `n` Euler steps up to rounding (no approximation of the
//! law: it is the Euler recursion's own closed form). Working relative to `y_prev` keeps the
//! numbers small (an error, not an absolute angle) so nothing cancels.

use crate::law::{Law, Stateful};
use crate::{Hold, Real};

/// The largest state dimension a closed-form map supports (a series of two ILOs with `D = 1`).
pub const LIN_MAX: usize = 4;

/// A law whose step is linear in (state, input) and invariant to a constant input offset.
/// Implemented by [`crate::IloParams`], [`crate::AdParams`] and [`crate::Series`] of two of them.
pub trait LinearLaw: Law {
    /// State dimension; must be `<= LIN_MAX` for [`ClosedForm`] (checked at compile time).
    const DIM: usize;
    /// `true` at the position states (shifted by a constant input offset).
    const POSITION: [bool; LIN_MAX];
    /// The state as a vector (entries `>= DIM` are 0). The output is a function of it.
    fn lin_state(&self, s: &Self::State) -> [Self::Num; LIN_MAX];
    /// Sets the state from a vector (and the output that goes with it).
    fn set_lin_state(&self, s: &mut Self::State, v: &[Self::Num; LIN_MAX]);
    /// One step of the same Euler law in `f64` (with this law's quantised coefficients), on the
    /// state vector; returns the step's output. Used only to precompute maps.
    fn lin_step_f64(&self, s: &mut [f64; LIN_MAX], y: f64) -> f64;
}

/// A linear law with its exact `n`-step map precomputed for the usual number of steps per
/// sample `n` (e.g. 100 for 100 Hz samples at `h = 1e-4`) and one [`Hold`] mode;
/// [`Law::advance`] uses the map when called with that `n` and mode and falls back to
/// stepping otherwise. `step`, `init` and `output` are the inner law's, and so is the state.
///
/// Cost per sample: `DIM^2 + 3 DIM` multiply-adds instead of `n` steps.
/// RAM (parameters): the inner law plus `(LIN_MAX^2 + LIN_MAX)` words of `T` and the
/// `n`/mode tag.
#[derive(Clone, Copy, Debug)]
pub struct ClosedForm<E: LinearLaw> {
    inner: E,
    n: u32,
    hold: Hold,
    phi: [[E::Num; LIN_MAX]; LIN_MAX],
    g: [E::Num; LIN_MAX],
}

impl<E: LinearLaw> ClosedForm<E> {
    const DIM_OK: () = assert!(E::DIM <= LIN_MAX, "state too large for a closed-form map");

    /// Precomputes the `n`-step map of `inner` for `hold` (`n >= 1`; `n = 0` gives a map that
    /// is never used).
    pub fn new(inner: E, n: u32, hold: Hold) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::DIM_OK;
        let zero = <E::Num as Real>::ZERO;
        let mut phi = [[zero; LIN_MAX]; LIN_MAX];
        for i in 0..E::DIM {
            let mut s = [0.0f64; LIN_MAX];
            if let Some(x) = s.get_mut(i) {
                *x = 1.0;
            }
            for _ in 0..n {
                inner.lin_step_f64(&mut s, 0.0);
            }
            for (r, row) in phi.iter_mut().enumerate() {
                if let (Some(dst), Some(src)) = (row.get_mut(i), s.get(r)) {
                    *dst = E::Num::from_f64(*src);
                }
            }
        }
        let mut s = [0.0f64; LIN_MAX];
        for j in 1..=n {
            let u = match hold {
                Hold::Linear => f64::from(j) / f64::from(n),
                Hold::ZeroOrder => 1.0,
            };
            inner.lin_step_f64(&mut s, u);
        }
        let mut g = [zero; LIN_MAX];
        for (dst, src) in g.iter_mut().zip(s.iter()) {
            *dst = E::Num::from_f64(*src);
        }
        Self {
            inner,
            n,
            hold,
            phi,
            g,
        }
    }

    /// [`Self::new`], or a copy of `prev` when `prev` was built from the same `inner`, `n` and
    /// `hold`: the map is a pure function of those, so the result is bit for bit what `new`
    /// computes, without its `(DIM + 1) n` steps in `f64` (what makes a gain change of
    /// [`crate::AdaptiveBank`] cheap when only some rows' gains change).
    pub fn new_reusing(inner: E, n: u32, hold: Hold, prev: Option<&Self>) -> Self
    where
        E: PartialEq,
    {
        match prev {
            Some(p) if p.inner == inner && p.n == n && p.hold == hold => *p,
            _ => Self::new(inner, n, hold),
        }
    }

    /// The estimator object of `inner`'s parameters with the map (state reset to 0).
    pub fn of(inner: &Stateful<E>, n: u32, hold: Hold) -> Stateful<Self> {
        Stateful::from_law(Self::new(*inner.law(), n, hold))
    }

    /// The fallback of [`Law::advance`]: `n` Euler steps (an interval of another length).
    #[cold]
    #[inline(never)]
    fn advance_stepping(
        &self,
        st: &mut E::State,
        y_prev: E::Num,
        y_new: E::Num,
        n: u32,
        hold: Hold,
    ) -> E::Num {
        self.inner.advance(st, y_prev, y_new, n, hold)
    }

    /// The wrapped law.
    pub fn inner(&self) -> &E {
        &self.inner
    }

    /// The number of steps per sample the map is for.
    pub fn steps(&self) -> u32 {
        self.n
    }
}

impl<E: LinearLaw> Law for ClosedForm<E> {
    type Num = E::Num;
    type State = E::State;

    fn init(&self, y0: E::Num) -> E::State {
        self.inner.init(y0)
    }

    #[inline(always)]
    fn step(&self, s: &mut E::State, y: E::Num) -> E::Num {
        self.inner.step(s, y)
    }

    #[inline]
    fn output(&self, s: &E::State) -> E::Num {
        self.inner.output(s)
    }

    #[inline]
    fn translate(&self, s: &mut E::State, d: E::Num) {
        self.inner.translate(s, d);
    }

    fn retune_state(&self, old: &Self, s: &mut E::State, y: E::Num) {
        self.inner.retune_state(&old.inner, s, y);
    }

    /// `s' = P y_prev + Phi (s - P y_prev) + g (y_new - y_prev)` when `n` and `hold` match the
    /// precomputed map, else `n` Euler steps.
    #[inline(always)]
    fn advance(
        &self,
        st: &mut E::State,
        y_prev: E::Num,
        y_new: E::Num,
        n: u32,
        hold: Hold,
    ) -> E::Num {
        if n != self.n || hold != self.hold || n == 0 {
            return self.advance_stepping(st, y_prev, y_new, n, hold);
        }
        let zero = <E::Num as Real>::ZERO;
        let mut s = self.inner.lin_state(st);
        for (x, p) in s.iter_mut().zip(E::POSITION.iter()) {
            if *p {
                *x = *x - y_prev;
            }
        }
        let dy = y_new - y_prev;
        let mut out = [zero; LIN_MAX];
        for ((o, row), g) in out
            .iter_mut()
            .zip(self.phi.iter())
            .zip(self.g.iter())
            .take(E::DIM)
        {
            let mut acc = *g * dy;
            for (a, x) in row.iter().zip(s.iter()).take(E::DIM) {
                acc = acc + *a * *x;
            }
            *o = acc;
        }
        for (x, p) in out.iter_mut().zip(E::POSITION.iter()) {
            if *p {
                *x = *x + y_prev;
            }
        }
        self.inner.set_lin_state(st, &out);
        self.inner.output(st)
    }
}
