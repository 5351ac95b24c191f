//! A velocity law and the acceleration series of the same family in one row of a bank.

use crate::law::{stepped_inputs, Interval, Law};
use crate::{Hold, Real};

/// A velocity law `v` and the acceleration series `a1 -> a2` of the same family (AVE and
/// AVE-AVE, ED and ED-ED) stepped together, one loop over the interval's steps.
///
/// When the series' first stage has the same parameters as the velocity law (`shared`, the
/// paper's and the default configuration: both use the same AVE and ED gains), it sees the same
/// input from the same initial state, so its trajectory is the velocity law's, bit for bit: it
/// is not computed twice; the velocity law's output of each step feeds `a2`. Otherwise `a1`
/// runs on its own. Either way the outputs are exactly those of the separate laws.
#[derive(Clone, Copy, Debug)]
pub struct VelAcc<L: Law> {
    v: L,
    a1: L,
    a2: L,
    shared: bool,
}

/// State of a [`VelAcc`].
#[derive(Clone, Copy, Debug)]
pub struct VelAccState<S> {
    /// The velocity law.
    pub v: S,
    /// The series' first stage (unused when shared).
    pub a1: S,
    /// The series' second stage.
    pub a2: S,
}

impl<L: Law> VelAcc<L> {
    /// `v` for velocity, `a1 -> a2` for acceleration; `shared` must be true only when `a1`
    /// is the same law with the same parameters as `v` (then `a1` is not computed).
    pub fn new(v: L, a1: L, a2: L, shared: bool) -> Self {
        Self { v, a1, a2, shared }
    }

    /// `true` when the series' first stage is the velocity law (not computed on its own).
    pub fn is_shared(&self) -> bool {
        self.shared
    }

    /// The velocity estimate (unit/s).
    #[inline]
    pub fn velocity(&self, s: &VelAccState<L::State>) -> L::Num {
        self.v.output(&s.v)
    }

    /// The acceleration estimate (unit/s^2), same as [`Law::output`].
    #[inline]
    pub fn acceleration(&self, s: &VelAccState<L::State>) -> L::Num {
        self.a2.output(&s.a2)
    }

    /// One step of the three laws (`a1` skipped when `SHARED`).
    #[inline(always)]
    fn one<const SHARED: bool>(&self, st: &mut VelAccState<L::State>, y: L::Num) {
        let o = self.v.step(&mut st.v, y);
        let o1 = if SHARED {
            o
        } else {
            self.a1.step(&mut st.a1, y)
        };
        self.a2.step(&mut st.a2, o1);
    }

    /// The coarse-step factor of the three laws ([`Law::coarse`]) when they agree (`a1`
    /// ignored when shared), `Some(None)` when none has a coarse step, `None` when they
    /// disagree (then the row runs every law at `h`, [`VelAcc::advance`]).
    #[inline(always)]
    fn factors(&self) -> Option<Option<u32>> {
        let f = |l: &L| l.coarse().map(|c| c.1);
        let v = f(&self.v);
        (f(&self.a2) == v && (self.shared || f(&self.a1) == v)).then_some(v)
    }

    /// `n >= 1` steps on a local copy of the state (with the laws' coarse steps when
    /// `coarse`, [`Law::coarse`]).
    #[inline(always)]
    fn run<const SHARED: bool>(
        &self,
        s: &mut VelAccState<L::State>,
        y_prev: L::Num,
        y_new: L::Num,
        n: u32,
        hold: Hold,
        coarse: bool,
    ) {
        if <L::Num as Real>::AVE_STEP_FACTOR > 1 {
            // A number type with coarse steps (Fx): one loop, with or without them (`m = 1`:
            // the inputs of the loop below), so that the steps are inlined once.
            let (c, m) = match self.coarse() {
                Some(c) if coarse => c,
                _ => (*self, 1),
            };
            let mut st = *s;
            stepped_inputs(y_prev, y_new, n, m, hold, |y, big| {
                let l = if big { &c } else { self };
                l.one::<SHARED>(&mut st, y);
            });
            *s = st;
            return;
        }
        let mut st = *s;
        match hold {
            Hold::ZeroOrder => {
                for _ in 0..n {
                    self.one::<SHARED>(&mut st, y_new);
                }
            }
            Hold::Linear => {
                let inc = (y_new - y_prev).div_int(n);
                let mut y = y_prev;
                for _ in 1..n {
                    y = y + inc;
                    self.one::<SHARED>(&mut st, y);
                }
                self.one::<SHARED>(&mut st, y_new);
            }
        }
        *s = st;
    }
}

impl<T: Real, L: Law<Num = T>> Law for VelAcc<L> {
    type Num = T;
    type State = VelAccState<L::State>;

    fn init(&self, y0: T) -> Self::State {
        let v = self.v.init(y0);
        let a1 = self.a1.init(y0);
        let a2 = self.a2.init(self.a1.output(&a1));
        VelAccState { v, a1, a2 }
    }

    /// One step of all three; returns the acceleration.
    #[inline(always)]
    fn step(&self, s: &mut Self::State, y: T) -> T {
        let o = self.v.step(&mut s.v, y);
        let o1 = if self.shared {
            o
        } else {
            self.a1.step(&mut s.a1, y)
        };
        self.a2.step(&mut s.a2, o1)
    }

    #[inline]
    fn output(&self, s: &Self::State) -> T {
        self.a2.output(&s.a2)
    }

    #[inline]
    fn translate(&self, s: &mut Self::State, d: T) {
        self.v.translate(&mut s.v, d);
        self.a1.translate(&mut s.a1, d);
    }

    /// Each law on its own. A shared row's series first stage was not computed (its state is
    /// stale): when the new row no longer shares, it starts from the velocity law's state,
    /// which is what it would have been.
    fn retune_state(&self, old: &Self, s: &mut Self::State, y: T) {
        let old_a1 = if old.shared {
            s.a1 = s.v;
            &old.v
        } else {
            &old.a1
        };
        if !self.shared {
            self.a1.retune_state(old_a1, &mut s.a1, y);
        }
        self.v.retune_state(&old.v, &mut s.v, y);
        let y2 = if self.shared {
            self.v.output(&s.v)
        } else {
            self.a1.output(&s.a1)
        };
        self.a2.retune_state(&old.a2, &mut s.a2, y2);
    }

    /// The row of the three laws' coarse steps, when all three (`a1` ignored when shared) have
    /// one with the same factor.
    #[inline(always)]
    fn coarse(&self) -> Option<(Self, u32)> {
        let (v, m) = self.v.coarse()?;
        let (a2, ma) = self.a2.coarse()?;
        let a1 = if self.shared {
            v
        } else {
            match self.a1.coarse()? {
                (a1, m1) if m1 == m => a1,
                _ => return None,
            }
        };
        (ma == m).then_some((Self::new(v, a1, a2, self.shared), m))
    }

    /// The `n` steps of the interval: through the laws' fast path ([`Law::advance_pair`], the
    /// fixed-point kernels) when they have one, else stepped here; with the laws' coarse steps
    /// ([`Law::coarse`]) when all three have the same, else (a row whose laws disagree, e.g.
    /// one AVE gain set too large for the coarse step) every law at `h`. Same results either
    /// way.
    #[inline]
    fn advance(&self, s: &mut Self::State, y_prev: T, y_new: T, n: u32, hold: Hold) -> T {
        if n > 0 {
            let interval = Interval {
                y_prev,
                y_new,
                n,
                hold,
            };
            // `None`: the laws disagree on the coarse step, all three run at `h` (below).
            let f = self.factors();
            let coarse = matches!(f, Some(Some(_)));
            if f.is_some()
                && self.shared
                && L::advance_pair(&self.v, &self.a2, &mut s.v, &mut s.a2, interval)
            {
                // The law's own fast path (the fixed-point kernels): same results.
            } else if f.is_some()
                && !self.shared
                && L::advance_pair(&self.a1, &self.a2, &mut s.a1, &mut s.a2, interval)
            {
                // Own acceleration gains (the NAV440 preset) and a fast path (the fixed-point
                // kernels): the series through it, the velocity law through its own
                // `Law::advance`. The velocity law and the series are independent, so the
                // results are those of the interleaved loop.
                self.v.advance(&mut s.v, y_prev, y_new, n, hold);
            } else if self.shared {
                self.run::<true>(s, y_prev, y_new, n, hold, coarse);
            } else {
                self.run::<false>(s, y_prev, y_new, n, hold, coarse);
            }
        }
        self.output(s)
    }
}
