//! Configuration and state apart: the [`Law`] trait every estimator implements.
//!
//! A law's *parameters* (`AveParams`, `IloParams`, `AdParams`, `EdParams`, `KalmanParams`,
//! their [`crate::Series`] and [`crate::ClosedForm`]) are the validated coefficients, computed
//! once from a physical configuration (`AveConfig`, ...) and never changed by an update; they
//! can be shared (both stages of a series, the closed-form maps, three axes). The *state*
//! (`Law::State`) is small, `Copy`, and is the only thing `step` writes:
//!
//! ```text
//! params = AveParams::new(&AveConfig, h)?      // validated once
//! state  = params.init(y0)                      // a few words
//! v      = params.step(&mut state, y)           // step(&self, &mut State, input)
//! ```
//!
//! [`Stateful`] binds one parameter set to one state and implements [`Estimator`]: the
//! classic one-object API (`Ave<T>`, `Ilo<T, D>`, `Ad<T>`, `Ed<T, S>` are such aliases).

use crate::{Estimator, Hold, Real};

/// One estimator law: validated coefficients (`self`) stepping a separate [`Law::State`].
///
/// Units: a velocity law fed a position in deg returns deg/s; a series (acceleration) law
/// returns deg/s^2.
pub trait Law: Copy + core::fmt::Debug {
    /// The number type the law computes in.
    type Num: Real;
    /// The law's state (positions, velocities, learning and delay states).
    type State: Copy + core::fmt::Debug;

    /// The state as if the input had been constant at `y0` forever: position states `y0`,
    /// every velocity / learning / delay state 0, output 0.
    fn init(&self, y0: Self::Num) -> Self::State;

    /// Advances `s` by one step `h` with input `y`; returns the new estimate.
    fn step(&self, s: &mut Self::State, y: Self::Num) -> Self::Num;

    /// The estimate of the last step (0 after [`Law::init`]).
    fn output(&self, s: &Self::State) -> Self::Num;

    /// Adds `d` to every position state (see [`Estimator::translate`]).
    fn translate(&self, s: &mut Self::State, d: Self::Num);

    /// Runs the `n` steps of one sample interval from `y_prev` to `y_new` as [`Hold`]
    /// prescribes and returns the last output (`n = 0`: nothing, the current output). The
    /// default steps `n` times on a local copy of the state (kept in registers).
    #[inline]
    fn advance(
        &self,
        s: &mut Self::State,
        y_prev: Self::Num,
        y_new: Self::Num,
        n: u32,
        hold: Hold,
    ) -> Self::Num {
        step_n(self, s, y_prev, y_new, n, hold)
    }

    /// The law of one *coarse* Euler step of `m` steps `h` (that is, of `m h`) and `m`, when
    /// the law advances whole groups of `m` steps at once inside an interval: [`step_n`] (so
    /// the default [`Law::advance`]) and [`crate::VelAcc`] then run `floor(n / m)` coarse steps
    /// and the remaining `n mod m` steps `h`, each coarse step seeing the input at the end of
    /// its span ([`stepped_inputs`]). `None` (the default, and every law of the float banks):
    /// every step is a step `h`. [`Law::step`] is always one step `h`. Used by the fixed-point
    /// AVE ([`crate::Real::AVE_STEP_FACTOR`], docs/FIXED-POINT.md, "The AVE row at `2 h`").
    #[inline(always)]
    fn coarse(&self) -> Option<(Self, u32)> {
        None
    }

    /// Bumpless gain change ([`crate::PaperBank::set_gains`], [`crate::AdaptiveBank`]): `s`
    /// was produced by the parameters `old` and `y` is the last input; moves `s` to the state
    /// in which `self`, at input `y`, is in equilibrium with its present output (the steady
    /// state of a ramp whose rate is that output), so that the estimate continues from where
    /// it is instead of ringing. The default leaves `s` as it is, which is right for laws
    /// whose equilibrium does not depend on their gains and whose state is on it (the Kalman
    /// tracker's physical states). The ED's equilibrium (`z = y`, `u1` = the rate) does not
    /// depend on its gains either, but a low-`alpha` set runs away from it, so its
    /// `retune_state` puts the state there (`z = y + h u`, `u1 = u`, `u` the output). The
    /// AVE's equilibrium (`xhat = y`, `theta` = the rate) does not depend on its gains either,
    /// but its state is off it by the position error the old gains left, so its
    /// `retune_state` sets `xhat = y`. The ILO's (with `K1 < 1`) and the AD's equilibrium does
    /// depend on their gains: kept as it is, the state of a lightly damped ILO meets the new
    /// gains with the old steady error and rings (docs/ADAPTIVE-GAINS.md, "How a gain change keeps the
    /// estimates").
    #[inline]
    fn retune_state(&self, old: &Self, s: &mut Self::State, y: Self::Num) {
        let _ = (old, s, y);
    }

    /// `n >= 1` steps of the velocity law `v` and of a series' second stage `a2` fed by its
    /// output in every step (a shared [`crate::VelAcc`] row), by a faster path of the law's own
    /// with exactly the results of stepping; `false` (states untouched) when the law has no such
    /// path for its number type. Internal hook of the fixed-point kernels ([`crate::Fx`]).
    #[doc(hidden)]
    #[inline(always)]
    fn advance_pair(
        v: &Self,
        a2: &Self,
        sv: &mut Self::State,
        sa: &mut Self::State,
        interval: Interval<Self::Num>,
    ) -> bool {
        let _ = (v, a2, sv, sa, interval);
        false
    }
}

/// One sample interval of [`Law::advance_pair`]: `n` steps from the input `y_prev` to
/// `y_new`, presented as `hold` prescribes.
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct Interval<T> {
    /// The previous sample.
    pub y_prev: T,
    /// The new sample.
    pub y_new: T,
    /// Steps in the interval.
    pub n: u32,
    /// How the input moves between the two samples.
    pub hold: Hold,
}

/// The stepping implementation of [`Law::advance`] (usable by overriding impls as their
/// fallback): `n` steps on a local copy of `s`, inputs as [`Hold`] prescribes.
#[inline(always)]
pub fn step_n<L: Law>(
    law: &L,
    s: &mut L::State,
    y_prev: L::Num,
    y_new: L::Num,
    n: u32,
    hold: Hold,
) -> L::Num {
    if n == 0 {
        return law.output(s);
    }
    if <L::Num as Real>::AVE_STEP_FACTOR > 1 {
        // A number type with coarse steps (Fx): one loop for every law of that type, with or
        // without its coarse step (`m = 1`: the inputs below, exactly those of the loop at
        // the end), so that the law's step is inlined once.
        let (c, m) = law.coarse().unwrap_or((*law, 1));
        let mut st = *s;
        stepped_inputs(y_prev, y_new, n, m, hold, |y, coarse| {
            let l = if coarse { &c } else { law };
            l.step(&mut st, y);
        });
        *s = st;
        return law.output(s);
    }
    let mut st = *s;
    match hold {
        Hold::ZeroOrder => {
            for _ in 0..n {
                law.step(&mut st, y_new);
            }
        }
        Hold::Linear => {
            // y_j = y_prev + j * inc; the last step gets y_new exactly (no accumulated rounding).
            let inc = (y_new - y_prev).div_int(n);
            let mut y = y_prev;
            for _ in 1..n {
                y = y + inc;
                law.step(&mut st, y);
            }
            law.step(&mut st, y_new);
        }
    }
    *s = st;
    law.output(s)
}

/// The inputs of an interval of `n >= 1` steps `h` from `y_prev` to `y_new` advanced in
/// `floor(n / m)` coarse steps of `m h` followed by `n mod m` steps `h` (`m >= 1`): calls
/// `f(y, true)` for each coarse step and `f(y, false)` for each step `h`, in time order.
/// Every step sees the input at the end of its span on the grid of [`step_n`]: with
/// [`Hold::Linear`], `y_prev + j inc` (`inc = (y_new - y_prev) / n`, accumulated with `+`
/// one `inc` per step `h` as [`step_n`] does, so the values are those [`step_n`] gives its
/// steps `m, 2m, ...`) and `y_new` for the interval's last step; with [`Hold::ZeroOrder`],
/// `y_new`. With `m = 1` these are exactly [`step_n`]'s inputs.
#[inline(always)]
pub fn stepped_inputs<T: Real>(
    y_prev: T,
    y_new: T,
    n: u32,
    m: u32,
    hold: Hold,
    mut f: impl FnMut(T, bool),
) {
    let m = m.max(1);
    // Steps 1 ..= big_end of the grid are covered by coarse steps.
    let big_end = n / m * m;
    let zoh = matches!(hold, Hold::ZeroOrder);
    let inc = if zoh {
        T::ZERO
    } else {
        (y_new - y_prev).div_int(n)
    };
    let mut y = y_prev;
    let mut j = 0;
    // One call site (the callers inline `f`, a law step, once).
    while j < n {
        let big = j < big_end;
        let adv = if big { m } else { 1 };
        for _ in 0..adv {
            y = y + inc;
        }
        j += adv;
        f(if zoh || j == n { y_new } else { y }, big);
    }
}

/// One parameter set bound to one state: the classic estimator object, implementing
/// [`Estimator`]. RAM: `size_of::<L>() + size_of::<L::State>()` (plus padding).
#[derive(Clone, Copy, Debug)]
pub struct Stateful<L: Law> {
    law: L,
    state: L::State,
}

impl<L: Law> Stateful<L> {
    /// Binds `law` to its initial state (input 0).
    pub fn from_law(law: L) -> Self {
        let state = law.init(<L::Num as Real>::ZERO);
        Self { law, state }
    }

    /// The parameters.
    pub fn law(&self) -> &L {
        &self.law
    }

    /// The state.
    pub fn state(&self) -> &L::State {
        &self.state
    }
}

impl<L: Law> Estimator<L::Num> for Stateful<L> {
    fn reset(&mut self, y0: L::Num) {
        self.state = self.law.init(y0);
    }

    #[inline]
    fn step(&mut self, y: L::Num) -> L::Num {
        self.law.step(&mut self.state, y)
    }

    fn output(&self) -> L::Num {
        self.law.output(&self.state)
    }

    fn translate(&mut self, d: L::Num) {
        self.law.translate(&mut self.state, d);
    }

    fn advance(&mut self, y_prev: L::Num, y_new: L::Num, n: u32, hold: Hold) -> L::Num {
        self.law.advance(&mut self.state, y_prev, y_new, n, hold)
    }
}
