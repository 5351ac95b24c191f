//! Levant's robust exact differentiator, ED (paper eqs. 5-7; Levant 1998).

use crate::error::positive;
use crate::family::{geometric, Gains, LawVisitor};
use crate::fxk::{advance_one, advance_two, frac, mag, mulf, run, sqrt_fast, Coef, Kernel, Stage};
use crate::law::{step_n, Interval, Law, Stateful};
use crate::{ConfigError, Hold, NativeSqrt, Real, SqrtFn};
use core::marker::PhantomData;

/// The largest `h * alpha` an [`EdParams`] accepts, unit/s (deg/s for an angle): the change
/// of the ED's integrator `u1`, and of its output, in one step `h`. Past it the output
/// chatters by more than 1e6 deg/s (the banks' whole angle range, `MAX_ABS_DEG` = 1e6 deg,
/// per second): no rate is left to read (`alpha = 1e30` gave 8e28 deg/s). The paper's `alpha = 770` at `h = 1e-4` s is 0.077; the tuner's
/// search box (`alpha` up to 1e6) stays within it at every step `h <= 1` s.
pub const ED_MAX_H_ALPHA: f64 = 1e6;

/// Parameters of the exact differentiator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
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
/// Output: `u` (deg/s for `y` in deg); [`EdState::u1`] is the integrator state. Exact in
/// finite time on noise-free inputs with `|y''| <= C < alpha` and `lambda` large enough; with
/// noise of amplitude `eps` the error is of order `sqrt(eps)`.
///
/// `|e|^(1/2)` uses the exact square root `S` (default [`NativeSqrt`] = [`Real::sqrt`]; a
/// firmware may plug in its FPU instruction, see [`SqrtFn`]); `micromath`'s fast approximation
/// would bias it (measured in the tests, see the crate README).
///
/// The validated coefficients ([`crate::Law`]); the state is [`EdState`].
#[derive(Clone, Copy, Debug)]
pub struct EdParams<T: Real, S: SqrtFn<T> = NativeSqrt> {
    h: T,
    halpha: T,
    lambda: T,
    h2alpha: T,
    inv_h2alpha: T,
    half_hl: T,
    half_hl_sq: T,
    scheme: EdScheme,
    sqrt: PhantomData<S>,
}

/// State of the ED.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EdState<T: Real> {
    /// Position estimate `z` (unit of `y`).
    pub z: T,
    /// Integrator state `u1` of eq. 7 (unit/s).
    pub u1: T,
    /// Output `u` of eq. 6 (unit/s).
    pub u: T,
}

/// The ED as one object (parameters and state, [`crate::Estimator`]).
/// RAM: see [`crate::ram`].
pub type Ed<T, S = NativeSqrt> = Stateful<EdParams<T, S>>;

impl<T: Real, S: SqrtFn<T>> EdParams<T, S> {
    /// Validates `cfg` for step `h` (s) and the discretisation `scheme`. Errors:
    /// non-positive or non-finite `lambda`, `alpha`, `h`; `h * alpha` above [`ED_MAX_H_ALPHA`]
    /// ([`ConfigError::StepRateTooLarge`]`("alpha")`).
    pub fn new(cfg: &EdConfig, h: f32, scheme: EdScheme) -> Result<Self, ConfigError> {
        let h = positive("h", f64::from(h))?;
        let lambda = positive("lambda", f64::from(cfg.lambda))?;
        let alpha = positive("alpha", f64::from(cfg.alpha))?;
        // The integrator u1 (and the output u with it) moves by h alpha in every step: past
        // ED_MAX_H_ALPHA the output carries no rate.
        if h * alpha > ED_MAX_H_ALPHA {
            return Err(ConfigError::StepRateTooLarge("alpha"));
        }
        Ok(Self {
            h: T::from_f64(h),
            halpha: T::from_f64(h * alpha),
            lambda: T::from_f64(lambda),
            h2alpha: T::from_f64(h * h * alpha),
            inv_h2alpha: T::from_f64(1.0 / (h * h * alpha)),
            half_hl: T::from_f64(0.5 * h * lambda),
            half_hl_sq: T::from_f64(0.25 * h * h * lambda * lambda),
            scheme,
            sqrt: PhantomData,
        })
    }

    /// One step of [`EdScheme::Implicit`] (see [`Law::step`]). Kept out of line so the
    /// default explicit step stays as short as without the option.
    #[inline(never)]
    fn step_implicit(&self, s: &mut EdState<T>, y: T) -> T {
        let p = (s.z - y) + self.h * s.u1;
        let ap = p.abs();
        let u = if ap <= self.h2alpha {
            s.u1 = s.u1 - self.halpha * (p * self.inv_h2alpha);
            s.u1
        } else {
            let r = S::sqrt(self.half_hl_sq + (ap - self.h2alpha)) - self.half_hl;
            let lr = self.lambda * r;
            if p > T::ZERO {
                s.u1 = s.u1 - self.halpha;
                s.u1 - lr
            } else {
                s.u1 = s.u1 + self.halpha;
                s.u1 + lr
            }
        };
        s.z = s.z + self.h * u;
        s.u = u;
        u
    }

    /// Explicit Euler step (see [`Law::step`]).
    #[inline(always)]
    fn step_euler(&self, s: &mut EdState<T>, y: T) -> T {
        let e = s.z - y;
        let (u, du1) = if e > T::ZERO {
            (s.u1 - self.lambda * S::sqrt(e), -self.halpha)
        } else if e < T::ZERO {
            (s.u1 + self.lambda * S::sqrt(-e), self.halpha)
        } else {
            (s.u1, T::ZERO)
        };
        s.z = s.z + self.h * u;
        s.u1 = s.u1 + du1;
        s.u = u;
        u
    }
}

impl<T: Real, S: SqrtFn<T>> Ed<T, S> {
    /// Builds the differentiator for step `h` (s) with the paper's explicit Euler scheme.
    /// Errors: non-positive or non-finite `lambda`, `alpha`, `h`.
    pub fn new(cfg: &EdConfig, h: f32) -> Result<Self, ConfigError> {
        Self::with_scheme(cfg, h, EdScheme::Euler)
    }

    /// Builds the differentiator with the given discretisation scheme.
    pub fn with_scheme(cfg: &EdConfig, h: f32, scheme: EdScheme) -> Result<Self, ConfigError> {
        Ok(Self::from_law(EdParams::new(cfg, h, scheme)?))
    }

    /// The integrator state `u1` of eq. 7 (unit/s).
    pub fn u1(&self) -> T {
        self.state().u1
    }

    /// The output `u` of eq. 6 (unit/s), same as [`crate::Estimator::output`].
    pub fn u(&self) -> T {
        self.state().u
    }

    /// The position estimate `z` (unit of `y`).
    pub fn z(&self) -> T {
        self.state().z
    }
}

impl<T: Real, S: SqrtFn<T>> Law for EdParams<T, S> {
    type Num = T;
    type State = EdState<T>;

    fn init(&self, y0: T) -> EdState<T> {
        EdState {
            z: y0,
            u1: T::ZERO,
            u: T::ZERO,
        }
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
    #[inline(always)]
    fn step(&self, s: &mut EdState<T>, y: T) -> T {
        match self.scheme {
            EdScheme::Euler => self.step_euler(s, y),
            EdScheme::Implicit => self.step_implicit(s, y),
        }
    }

    #[inline]
    fn output(&self, s: &EdState<T>) -> T {
        s.u
    }

    #[inline]
    fn translate(&self, s: &mut EdState<T>, d: T) {
        s.z = s.z + d;
    }

    /// Bumpless gain change: `z = y + h u`, `u1 = u`, the equilibrium of any gains at the
    /// present output (the state holds the next step's position, so the next error is
    /// `h (u - rate)`, about 0, and the integrator carries the rate): the next output
    /// continues from `u` whatever `lambda` becomes. Leaving the state as it was would be
    /// bumpless only while the ED slides (`e` near 0). A set tuned for low noise can work away
    /// from sliding (a small `alpha`, where the root term carries the rate on a `|e|` of
    /// tenths of a degree); changing `lambda` there would make the output jump by
    /// `(lambda_new - lambda_old) |e|^(1/2)` for as long as `alpha` takes to catch up
    /// (docs/ADAPTIVE-GAINS.md, "How a gain change keeps the estimates"). Gains unchanged: the
    /// state is kept.
    fn retune_state(&self, old: &Self, s: &mut EdState<T>, y: T) {
        let same = self.h == old.h
            && self.lambda == old.lambda
            && self.halpha == old.halpha
            && self.scheme == old.scheme;
        if !same {
            s.z = y + self.h * s.u;
            s.u1 = s.u;
        }
    }

    #[inline]
    fn advance_pair(
        v: &Self,
        a2: &Self,
        sv: &mut EdState<T>,
        sa: &mut EdState<T>,
        interval: Interval<T>,
    ) -> bool {
        advance_two(EdFx::of(v), EdFx::of(a2), sv, sa, interval)
    }

    /// `n` steps; the scheme is chosen once per interval, not per step. [`crate::Fx`] with
    /// the explicit scheme: the integer kernel (same results, see docs/FIXED-POINT.md).
    #[inline]
    fn advance(&self, s: &mut EdState<T>, y_prev: T, y_new: T, n: u32, hold: Hold) -> T {
        if advance_one(EdFx::of(self), s, y_prev, y_new, n, hold) {
            return s.u;
        }
        match self.scheme {
            EdScheme::Euler => step_n(&Euler(*self), s, y_prev, y_new, n, hold),
            EdScheme::Implicit => step_n(self, s, y_prev, y_new, n, hold),
        }
    }
}

/// The explicit scheme alone (no per-step scheme test).
#[derive(Clone, Copy, Debug)]
struct Euler<T: Real, S: SqrtFn<T>>(EdParams<T, S>);

impl<T: Real, S: SqrtFn<T>> Law for Euler<T, S> {
    type Num = T;
    type State = EdState<T>;
    fn init(&self, y0: T) -> EdState<T> {
        self.0.init(y0)
    }
    #[inline(always)]
    fn step(&self, s: &mut EdState<T>, y: T) -> T {
        self.0.step_euler(s, y)
    }
    fn output(&self, s: &EdState<T>) -> T {
        s.u
    }
    fn translate(&self, s: &mut EdState<T>, d: T) {
        self.0.translate(s, d);
    }
}

/// The explicit ED's coefficients as raw Q31.32 bits for the integer kernel
/// ([`crate::fxk`]): `h` a fraction below 1/2, `lambda` below 2^13, `h alpha` below 2^28 in
/// magnitude, and its negation.
#[derive(Clone, Copy, Debug)]
struct EdFx {
    h: i32,
    lambda: Coef,
    halpha: i64,
    neg_halpha: i64,
}

/// The ED kernel's range guard: every state and input below `2^(ED_B - 32)` (raw `2^ED_B`).
const ED_B: u32 = 60;
const ED_BOUND: u32 = 1 << (ED_B - 32);

crate::fxk::fx_state! {
    /// [`EdState`] as raw Q31.32 bits.
    EdFxState for EdState { z: z, u1: u1, u: u }
}

impl EdFx {
    /// `None` for the float types, the implicit scheme, or a coefficient outside the kernel's
    /// classes.
    #[inline(always)]
    fn of<T: Real, S: SqrtFn<T>>(p: &EdParams<T, S>) -> Option<Self> {
        if p.scheme != EdScheme::Euler {
            return None;
        }
        let lambda = Coef::of(p.lambda)?;
        let halpha = p.halpha.fx_bits()?;
        if lambda.log2_bound() > 13 || halpha.unsigned_abs() >= 1 << 60 {
            return None;
        }
        Some(Self {
            h: frac(p.h)?,
            lambda,
            halpha,
            neg_halpha: (-p.halpha).fx_bits()?,
        })
    }
}

impl<T: Real> Kernel<EdState<T>> for EdFx {
    /// The kernel over one interval (`a2`: the series' second stage fed by `self`); the states
    /// are written only when it succeeds.
    #[inline(always)]
    fn advance(
        &self,
        a2: Option<&EdFx>,
        sv: &mut EdState<T>,
        sa: &mut EdState<T>,
        ys: (i64, i64, i64),
        n: u32,
    ) -> bool {
        let (Some(mut v), Some(mut a)) = (EdFxState::of(sv), EdFxState::of(sa)) else {
            return false;
        };
        if run_ed(self, a2, &mut v, &mut a, ys, n).is_none() {
            return false;
        }
        v.store(sv);
        if a2.is_some() {
            a.store(sa);
        }
        true
    }
}

/// [`crate::fxk::run`] for the ED.
#[inline(never)]
fn run_ed(
    k: &EdFx,
    a2: Option<&EdFx>,
    v: &mut EdFxState,
    a: &mut EdFxState,
    ys: (i64, i64, i64),
    n: u32,
) -> Option<()> {
    run(k, a2, v, a, ys, n, ED_BOUND)
}

impl Stage for EdFx {
    type S = EdFxState;

    /// [`EdParams::step_euler`] on raw bits: the same operations in the same order, wrapping;
    /// the bank's root [`sqrt_fast`] (`Real::ed_sqrt` of `Fx`) in 32-bit words and one
    /// 32 x 32-bit product per word of `lambda`.
    ///
    /// Range (raw bits): with `|z|, |y|, |u1| <= 2^60`: `|e| <= 2^61`, `sqrt|e| < 2^47`,
    /// `|lambda sqrt|e|| < 2^60` (`lambda < 2^13`), `|u| < 2^61`, `|h u| < 2^60`, new
    /// `|z| < 2^62`, `|u1| < 2^61` (`|h alpha| < 2^60`): no operation leaves `i64`, so each is
    /// exact and equal to the saturating one. ([`crate::fxk::run`] checks the bound before
    /// every step.)
    #[inline(always)]
    fn step(&self, s: &mut EdFxState, y: i64) -> i64 {
        let e = s.z.wrapping_sub(y);
        let ae = e.wrapping_abs();
        // lambda sqrt|e| (0 when e = 0; the generic code then adds nothing either), with the
        // bank's root `sqrt_fast` (`Real::ed_sqrt` of `Fx`); `|e| <= 2^61` (the guard), so the
        // root is below 2^47.
        let lr = if let Ok(a32) = u32::try_from(ae) {
            self.lambda.mul_u32(sqrt_fast(i64::from(a32)) as u32)
        } else {
            self.lambda.mul_u47(sqrt_fast(ae))
        };
        let (u, du1) = if e > 0 {
            (s.u1.wrapping_sub(lr), self.neg_halpha)
        } else if e < 0 {
            (s.u1.wrapping_add(lr), self.halpha)
        } else {
            (s.u1, 0)
        };
        s.z = s.z.wrapping_add(mulf(self.h, u));
        s.u1 = s.u1.wrapping_add(du1);
        s.u = u;
        u
    }

    #[inline(always)]
    fn mag(s: &EdFxState) -> u32 {
        mag(s.z) | mag(s.u1) | mag(s.u)
    }
}

impl Gains for EdConfig {
    /// `lambda` and `alpha` geometrically.
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        EdConfig {
            lambda: geometric(self.lambda, other.lambda, w),
            alpha: geometric(self.alpha, other.alpha, w),
        }
    }

    /// [`EdParams`] with the paper's explicit Euler scheme ([`EdScheme::Euler`]).
    fn build<V: LawVisitor>(&self, h: f32, to: V) -> Result<V::Output, ConfigError> {
        Ok(to.law(EdParams::<f32>::new(self, h, EdScheme::Euler)?))
    }

    const PAST_TOP: bool = true;

    /// `alpha` scaled by the root of the acceleration ratio `k = sqrt(A / A_tuned)` (at
    /// least [`ED_PAST_TOP_MIN`], at most 1: never raised), `lambda` by `sqrt(k)` (Levant's
    /// `lambda` goes as `sqrt(alpha)`): `alpha` bounds the input's second derivative, and
    /// the top level's stands to the tuning motion's RMS acceleration as these do to the
    /// motion's.
    fn past_top(&self, rule: &crate::family::PastTop) -> Self {
        let k = libm::sqrtf(rule.acceleration_ratio).clamp(ED_PAST_TOP_MIN, 1.0);
        EdConfig {
            lambda: self.lambda * libm::sqrtf(k),
            alpha: self.alpha * k,
        }
    }
}

/// The least factor [`EdConfig::past_top`] scales `alpha` by: a choice for robustness, not a
/// measured optimum. `alpha` must stay above the motion's largest acceleration, which the
/// acceleration power (a 0.5 s mean square) does not bound (docs/MOTION-FAMILY.md, "Past
/// the top level").
pub const ED_PAST_TOP_MIN: f32 = 0.5;

crate::family::family! {
    /// The ED family of the paper bank: Levant ED velocity, ED-ED acceleration (one
    /// [`crate::VelAcc`] row); gains [`BankGains::ed`](crate::BankGains::ed).
    EdFamily {
        gains: EdConfig = BankGains::ed,
        name: "ed",
        label: "ED",
        channels: EdV, EdA,
        scheduling: Observer,
        switch: ObserverSwitch::ed,
    }
}
