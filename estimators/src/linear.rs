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
//! `Phi` and `g` are computed once at construction in `f64`: the one-step map `(M, B)` is read
//! off `DIM + 1` steps of the same Euler law, then raised to `n` steps by binary powering
//! (about `2 log2 n` matrix products instead of `(DIM + 1) n` steps: 14 for 100 Hz at
//! `h = 1e-4`), so the map equals `n` Euler steps up to rounding (no approximation of the law:
//! it is the Euler recursion's own closed form). Working relative to `y_prev` keeps the numbers
//! small (an error, not an absolute angle) so nothing cancels.

use crate::law::{Law, Stateful};
use crate::words::{WordReader, Words};
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
/// RAM (parameters): the inner law plus `(M^2 + M)` words of `T` and the `n`/mode tag, where
/// `M` (`DIM <= M <= LIN_MAX`, checked at compile time) is the map's storage: `LIN_MAX` by
/// default, the law's `DIM` for the least RAM (the banks' ILO and AD rows: 2).
#[derive(Clone, Copy, Debug)]
pub struct ClosedForm<E: LinearLaw, const M: usize = LIN_MAX> {
    inner: E,
    n: u32,
    hold: Hold,
    phi: [[E::Num; M]; M],
    g: [E::Num; M],
}

/// Its words ([`crate::words`]): the inner law's, `n`, the hold, the map's matrix (row by row)
/// and its input vector.
impl<E: LinearLaw + Words, const M: usize> Words for ClosedForm<E, M>
where
    E::Num: Words,
{
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        self.inner.put_words(out);
        self.n.put_words(out);
        self.hold.put_words(out);
        self.phi.put_words(out);
        self.g.put_words(out);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        Self {
            inner: E::take_words(r),
            n: u32::take_words(r),
            hold: Hold::take_words(r),
            phi: Words::take_words(r),
            g: Words::take_words(r),
        }
    }
}

impl<E: LinearLaw> ClosedForm<E> {
    /// Precomputes the `n`-step map of `inner` for `hold` (`n >= 1`; `n = 0` gives a map that
    /// is never used), stored for `LIN_MAX` states ([`ClosedForm::sized`]: for `M`).
    pub fn new(inner: E, n: u32, hold: Hold) -> Self {
        Self::sized(inner, n, hold)
    }

    /// [`Self::new`], or a copy of `prev` when `prev` was built from the same `inner`, `n` and
    /// `hold`: the map is a pure function of those, so the result is bit for bit what `new`
    /// computes, without its `(DIM + 1) n` steps in `f64` (what makes a gain change of
    /// [`crate::AdaptiveBank`] cheap when only some rows' gains change).
    pub fn new_reusing(inner: E, n: u32, hold: Hold, prev: Option<&Self>) -> Self
    where
        E: PartialEq,
    {
        Self::sized_reusing(inner, n, hold, prev)
    }

    /// The estimator object of `inner`'s parameters with the map (state reset to 0).
    pub fn of(inner: &Stateful<E>, n: u32, hold: Hold) -> Stateful<Self> {
        Stateful::from_law(Self::new(*inner.law(), n, hold))
    }
}

impl<E: LinearLaw, const M: usize> ClosedForm<E, M> {
    const DIM_OK: () = assert!(
        E::DIM <= M && M <= LIN_MAX,
        "a closed-form map needs DIM <= M <= LIN_MAX"
    );

    /// [`ClosedForm::new`] with the map stored for `M` states (`DIM <= M <= LIN_MAX`, checked
    /// at compile time).
    pub fn sized(inner: E, n: u32, hold: Hold) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::DIM_OK;
        let (phi64, g64) = n_step_map(&inner, n, hold);
        let zero = <E::Num as Real>::ZERO;
        let mut phi = [[zero; M]; M];
        for (row, src) in phi.iter_mut().zip(phi64.iter()) {
            for (dst, x) in row.iter_mut().zip(src.iter()) {
                *dst = E::Num::from_f64(*x);
            }
        }
        let mut g = [zero; M];
        for (dst, src) in g.iter_mut().zip(g64.iter()) {
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

    /// [`ClosedForm::new_reusing`] with the map stored for `M` states.
    pub fn sized_reusing(inner: E, n: u32, hold: Hold, prev: Option<&Self>) -> Self
    where
        E: PartialEq,
    {
        match prev {
            Some(p) if p.inner == inner && p.n == n && p.hold == hold => *p,
            _ => Self::sized(inner, n, hold),
        }
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

type Mat = [[f64; LIN_MAX]; LIN_MAX];
type Vector = [f64; LIN_MAX];

fn mat_mul(a: &Mat, b: &Mat) -> Mat {
    let mut c = [[0.0; LIN_MAX]; LIN_MAX];
    for (ci, ai) in c.iter_mut().zip(a) {
        for (x, bk) in ai.iter().zip(b) {
            for (cij, bkj) in ci.iter_mut().zip(bk) {
                *cij += x * bkj;
            }
        }
    }
    c
}

fn mat_vec(a: &Mat, v: &Vector) -> Vector {
    let mut out = [0.0; LIN_MAX];
    for (o, row) in out.iter_mut().zip(a.iter()) {
        *o = row.iter().zip(v.iter()).map(|(x, y)| x * y).sum();
    }
    out
}

fn add(a: &Vector, b: &Vector) -> Vector {
    let mut out = *a;
    for (o, x) in out.iter_mut().zip(b.iter()) {
        *o += x;
    }
    out
}

fn scaled(a: &Vector, k: f64) -> Vector {
    let mut out = *a;
    for o in out.iter_mut() {
        *o *= k;
    }
    out
}

/// `(Phi, g)` of `law`'s `n`-step map for `hold` (module documentation), in `f64`. The one-step
/// map `s' = M s + B u` is read off `DIM + 1` steps of [`LinearLaw::lin_step_f64`] (unit
/// states with input 0, then the zero state with input 1); then, by binary powering over the
/// bits of `n` (`2 log2 n` doublings or increments instead of `(DIM + 1) n` steps):
///
/// ```text
/// Phi = M^n,   S(m) = sum_{i<m} M^i B,   T(m) = sum_{i<m} i M^i B
/// S(2m) = S(m) + M^m S(m),   T(2m) = T(m) + M^m (T(m) + m S(m))
/// S(m+1) = B + M S(m),       T(m+1) = M (T(m) + S(m))
/// g = S(n) (zero-order hold),   g = S(n) - T(n) / n (linear hold: u_j = j / n)
/// ```
///
/// Equal to `n` Euler steps of the law up to rounding.
#[inline(never)]
fn n_step_map<E: LinearLaw>(law: &E, n: u32, hold: Hold) -> (Mat, Vector) {
    let mut m: Mat = [[0.0; LIN_MAX]; LIN_MAX];
    for i in 0..E::DIM.min(LIN_MAX) {
        let mut s = [0.0f64; LIN_MAX];
        s[i] = 1.0;
        law.lin_step_f64(&mut s, 0.0);
        for (row, x) in m.iter_mut().zip(s.iter()) {
            row[i] = *x;
        }
    }
    let mut b = [0.0f64; LIN_MAX];
    law.lin_step_f64(&mut b, 1.0);
    let mut power: Mat = [[0.0; LIN_MAX]; LIN_MAX];
    for (i, row) in power.iter_mut().enumerate().take(E::DIM) {
        row[i] = 1.0;
    }
    // (M^k, S(k), T(k)) for the prefix k of n's bits, most significant first.
    let mut sum = [0.0f64; LIN_MAX];
    let mut weighted = [0.0f64; LIN_MAX];
    let mut k = 0u32;
    for bit in (0..u32::BITS - n.leading_zeros()).rev() {
        if k > 0 {
            let ks = scaled(&sum, f64::from(k));
            weighted = add(&weighted, &mat_vec(&power, &add(&weighted, &ks)));
            sum = add(&sum, &mat_vec(&power, &sum));
            power = mat_mul(&power, &power);
            k *= 2;
        }
        if n >> bit & 1 == 1 {
            weighted = mat_vec(&m, &add(&weighted, &sum));
            sum = add(&b, &mat_vec(&m, &sum));
            power = mat_mul(&power, &m);
            k += 1;
        }
    }
    let g = match hold {
        Hold::ZeroOrder => sum,
        Hold::Linear if n > 0 => add(&sum, &scaled(&weighted, -1.0 / f64::from(n))),
        Hold::Linear => sum,
    };
    (power, g)
}

impl<E: LinearLaw, const M: usize> Law for ClosedForm<E, M> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{IloConfig, IloParams, Series};

    /// `(Phi, g)` by the definition: `n` Euler steps in `f64` from each unit state with input 0,
    /// and from the zero state through the hold's inputs.
    fn stepped<E: LinearLaw>(law: &E, n: u32, hold: Hold) -> (Mat, Vector) {
        let mut phi = [[0.0; LIN_MAX]; LIN_MAX];
        for i in 0..E::DIM {
            let mut s = [0.0; LIN_MAX];
            s[i] = 1.0;
            for _ in 0..n {
                law.lin_step_f64(&mut s, 0.0);
            }
            for (row, x) in phi.iter_mut().zip(s) {
                row[i] = x;
            }
        }
        let mut g = [0.0; LIN_MAX];
        for j in 1..=n {
            let u = match hold {
                Hold::Linear => f64::from(j) / f64::from(n),
                Hold::ZeroOrder => 1.0,
            };
            law.lin_step_f64(&mut g, u);
        }
        (phi, g)
    }

    fn max_rel(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale
    }

    /// The binary-powering map equals `n` Euler steps to rounding (relative 1e-8) for every
    /// `n` up to 300 and for long intervals (2 Hz at `h = 1e-4` is 5,000 steps), with both
    /// holds, for a state of dimension 2 (ILO, `D = 1`) and 4 (a series of two). Neither is
    /// exact: on the series with a zero-order hold the input's transient is 100 times the
    /// result, and stepping itself is off by 1.0e-9 of the result at `n = 112`, binary powering
    /// by 1.7e-10 at `n = 300` (both measured against exact rational arithmetic, see
    /// [`powering_matches_exact_arithmetic`]).
    #[test]
    fn powering_equals_stepping() {
        let ilo = test_ilo();
        let series = Series::new(ilo, ilo);
        let ns = (1..=300).chain([1_000, 4_999, 5_000, 12_345]);
        let mut worst = 0.0f64;
        for n in ns {
            for hold in [Hold::Linear, Hold::ZeroOrder] {
                let (p, g) = n_step_map(&ilo, n, hold);
                let (ps, gs) = stepped(&ilo, n, hold);
                let d = max_rel(p.as_flattened(), ps.as_flattened()).max(max_rel(&g, &gs));
                assert!(d < 1e-8, "ILO n={n} {hold:?}: {d:e}");
                worst = worst.max(d);
                let (p, g) = n_step_map(&series, n, hold);
                let (ps, gs) = stepped(&series, n, hold);
                let d = max_rel(p.as_flattened(), ps.as_flattened()).max(max_rel(&g, &gs));
                assert!(d < 1e-8, "series n={n} {hold:?}: {d:e}");
                worst = worst.max(d);
            }
        }
        assert!(
            worst > 0.0,
            "the two computations round differently somewhere"
        );
    }

    /// ILO1-like gains at the paper's step (`h = 1e-4` s as `f32`).
    fn test_ilo() -> IloParams<f64, 1> {
        IloParams::<f64, 1>::new(
            &IloConfig {
                k1: 0.7,
                l: 40.0,
                k2: 900.0,
            },
            1e-4,
        )
        .unwrap()
    }

    /// `g` of the series of two [`test_ilo`] over `n = 112` steps against its value in exact
    /// rational arithmetic (Python's `fractions` on the same `f64` coefficients, stepping the
    /// definition): relative 1e-11 (measured: 3.5e-13 with the zero-order hold, 4.3e-13 with
    /// the linear one).
    #[test]
    fn powering_matches_exact_arithmetic() {
        let series = Series::new(test_ilo(), test_ilo());
        let exact = [
            (
                Hold::ZeroOrder,
                [
                    0.9999999986292719,
                    -2.063927156508632e-06,
                    -0.00012446771544610247,
                    0.1719356049346791,
                ],
            ),
            (
                Hold::Linear,
                [
                    0.979558268825185,
                    88.11090431522885,
                    88.11090568127769,
                    -0.01101409445079264,
                ],
            ),
        ];
        for (hold, want) in exact {
            let (_, g) = n_step_map(&series, 112, hold);
            let d = max_rel(&g, &want);
            assert!(d < 1e-11, "{hold:?}: {g:?} vs {want:?}: {d:e}");
        }
    }
}
