//! Adaptive velocity estimator, AVE (paper eq. 4).

use crate::error::{non_negative, positive};
use crate::family::{geometric, Gains, LawVisitor};
use crate::fxk::{
    advance_one, advance_two, frac, mag, mulf, mulf32, run, smul, Coef, Kernel, Stage,
};
use crate::law::{step_n, Interval, Law, Stateful};
use crate::real::{fx_mul, umul32};
use crate::{ConfigError, Hold, Real};

/// What happens to the switching gain `deltahat`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum DeltaMode {
    /// The paper's law `d deltahat/dt = |e|`: `deltahat` grows without bound while `e != 0`
    /// (default, paper-faithful).
    #[default]
    Paper,
    /// The paper's law, with `deltahat` clamped to `[0, max]` (deg/s).
    Bounded {
        /// Upper bound of `deltahat`, deg/s.
        max: f32,
    },
    /// Leakage (sigma-modification): `d deltahat/dt = |e| - sigma * deltahat`, `sigma` in 1/s;
    /// `deltahat` then stays below `max|e| / sigma`.
    Leaky {
        /// Leakage rate, 1/s (`h * sigma < 1`).
        sigma: f32,
    },
}

/// Parameters of the AVE in physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct AveConfig {
    /// Position feedback gain `k`, 1/s (paper: 500). `h * k < 1`.
    pub k: f32,
    /// Velocity adaptation gain `gamma1`, 1/s^2 (paper: 20000). `h * gamma1 < k` (stability
    /// of the explicit Euler step, see [`AveParams::new`]).
    pub gamma1: f32,
    /// `deltahat` law.
    pub delta: DeltaMode,
}

/// The `deltahat` law as validated coefficients (see [`DeltaMode`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DeltaLaw<T: Real> {
    /// `deltahat += h |e|`.
    Paper,
    /// `deltahat = min(deltahat + h |e|, max)`.
    Bounded {
        /// Upper bound, unit/s.
        max: T,
    },
    /// `deltahat += h |e| - h sigma deltahat`.
    Leaky {
        /// `h * sigma`, dimensionless.
        hsigma: T,
    },
}

/// The fixed-point AVE's coarse step `m h` ([`AveParams`]) is used only when it is at least
/// this many times shorter than the longest stable Euler step `k / gamma1`: the Euler map
/// keeps the fraction `1 - m h gamma1 / k` of the linear part's damping per unit time, so at
/// least 90 % here. Gains tuned close to the step `h`'s own limit (a lightly damped observer
/// at `h gamma1 / k` close to 1, as tuned schedule levels can be: docs/ADAPTIVE-GAINS.md,
/// "Gains at the edge of the Euler step") would be unstable at `2 h`; they step at `h`.
pub const COARSE_STABILITY_MARGIN: f64 = 10.0;

/// The adaptive velocity estimator of eq. 4 for `dx/dt = theta1(t)`, `e = xhat - y`:
///
/// ```text
/// dxhat/dt      = -k e + theta1hat - deltahat sgn(e)
/// dtheta1hat/dt = -gamma1 e
/// ddeltahat/dt  = |e|                  (DeltaMode::Paper)
/// ```
///
/// Output: `theta1hat` (deg/s for `y` in deg). Linearised (`deltahat = 0`) the noise-to-error
/// transfer is `gamma1 s / (s^2 + k s + gamma1)`.
///
/// The validated coefficients of one step `h` ([`crate::Law`]); the state is [`AveState`].
///
/// For [`crate::Fx`] ([`Real::AVE_STEP_FACTOR`] = 2) the parameters also hold the
/// coefficients of one Euler step of `2 h` (`2 h k`, `2 h gamma1`, `2 h`, `2 h sigma`,
/// computed in `f64` from the configuration like those of `h`), used by [`Law::advance`] for
/// whole pairs of steps ([`Law::coarse`], docs/FIXED-POINT.md, "The AVE row at `2 h`"); they
/// exist when the
/// `deltahat` law is bounded ([`DeltaMode::Leaky`], the banks' default, or
/// [`DeltaMode::Bounded`]; not [`DeltaMode::Paper`], whose `deltahat` grows without bound),
/// `2 h` passes the same validation as `h` (`2 h k < 1`, `2 h gamma1 < k`, `2 h sigma < 1`)
/// and the step `2 h` is at least [`COARSE_STABILITY_MARGIN`] times shorter than the
/// longest stable step `k / gamma1` (so that it keeps at least 90 % of the linear part's
/// damping per unit time, as the step `h` does); otherwise that AVE steps at `h`. For `f32`
/// and `f64` that field is zero-sized and unused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AveParams<T: Real> {
    c: AveCoef<T>,
    coarse: T::Coarse<AveCoef<T>>,
}

/// The coefficients of one Euler step of the AVE (of `h`, or of `2 h` for the coarse step).
#[derive(Clone, Copy, Debug, PartialEq)]
struct AveCoef<T: Real> {
    hk: T,
    hg: T,
    h: T,
    delta: DeltaLaw<T>,
}

/// State of the AVE: `xhat` (unit of `y`), `theta1hat` (unit/s), `deltahat` (unit/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AveState<T: Real> {
    /// Position estimate `xhat`.
    pub xhat: T,
    /// Velocity estimate `theta1hat` (the output).
    pub theta: T,
    /// Switching gain `deltahat`.
    pub delta: T,
}

/// The AVE as one object (parameters and state, [`crate::Estimator`]).
/// RAM: see [`crate::ram`].
pub type Ave<T> = Stateful<AveParams<T>>;

impl<T: Real> AveParams<T> {
    /// Validates `cfg` for step `h` (s). Errors: non-finite or non-positive `k`,
    /// `gamma1`, `h`; `h * k >= 1` ([`ConfigError::StepTooLarge`]`("k")`) or
    /// `h * gamma1 >= k` (`StepTooLarge("gamma1 / k")`): the explicit Euler map of the linear
    /// part (`deltahat = 0`), `[[1 - h k, h], [-h gamma1, 1]]`, is stable (Jury) exactly when
    /// `h gamma1 < k` (given `h k < 1`), and loses the fraction `h gamma1 / k` of the
    /// continuous law's damping per unit time; negative bound or leakage; `h * sigma >= 1`.
    /// For [`crate::Fx`], also the coefficients of the coarse step `2 h` (see
    /// [`AveParams`]).
    ///
    /// ```
    /// use estimators::{AveConfig, AveParams, ConfigError, DeltaMode};
    /// let cfg = |gamma1| AveConfig { k: 50.0, gamma1, delta: DeltaMode::Paper };
    /// // h = 1e-4 s: stable below gamma1 = k / h = 5e5 1/s^2.
    /// assert!(AveParams::<f32>::new(&cfg(4.9e5), 1e-4).is_ok());
    /// assert_eq!(
    ///     AveParams::<f32>::new(&cfg(5.1e5), 1e-4),
    ///     Err(ConfigError::StepTooLarge("gamma1 / k"))
    /// );
    /// ```
    pub fn new(cfg: &AveConfig, h: f32) -> Result<Self, ConfigError> {
        let h = positive("h", f64::from(h))?;
        let c = AveCoef::new(cfg, h)?;
        let m = T::AVE_STEP_FACTOR;
        // The coarse step needs a bounded deltahat (Leaky, Bounded): with the paper's law
        // deltahat, and with it the switching term's jump `m h deltahat` per step, grows
        // without bound, and so does the effect of the step size (docs/FIXED-POINT.md, "The
        // AVE row at `2 h`": over a long spin the paper's law at 2 h no longer behaves as at h).
        let resolved =
            |step: f64| step * f64::from(cfg.gamma1) * COARSE_STABILITY_MARGIN <= f64::from(cfg.k);
        let coarse = if m > 1 && cfg.delta != DeltaMode::Paper && resolved(h * f64::from(m)) {
            AveCoef::new(cfg, h * f64::from(m)).ok()
        } else {
            None
        };
        Ok(Self {
            c,
            coarse: T::coarse_new(coarse),
        })
    }

    /// The steps `h` one Euler step of [`Law::advance`] spans inside an interval: 2 for
    /// [`crate::Fx`] when the coarse step is valid (see [`AveParams`]), else 1.
    pub fn step_factor(&self) -> u32 {
        self.coarse().map_or(1, |c| c.1)
    }
}

impl<T: Real> AveCoef<T> {
    /// The coefficients of an Euler step `h` (s), validated (see [`AveParams::new`]).
    fn new(cfg: &AveConfig, h: f64) -> Result<Self, ConfigError> {
        let k = positive("k", f64::from(cfg.k))?;
        let g = positive("gamma1", f64::from(cfg.gamma1))?;
        if h * k >= 1.0 {
            return Err(ConfigError::StepTooLarge("k"));
        }
        if h * g >= k {
            return Err(ConfigError::StepTooLarge("gamma1 / k"));
        }
        let delta = match cfg.delta {
            DeltaMode::Paper => DeltaLaw::Paper,
            DeltaMode::Bounded { max } => DeltaLaw::Bounded {
                max: T::from_f64(non_negative("max", f64::from(max))?),
            },
            DeltaMode::Leaky { sigma } => {
                let s = non_negative("sigma", f64::from(sigma))?;
                if h * s >= 1.0 {
                    return Err(ConfigError::StepTooLarge("sigma"));
                }
                DeltaLaw::Leaky {
                    hsigma: T::from_f64(h * s),
                }
            }
        };
        Ok(Self {
            hk: T::from_f64(h * k),
            hg: T::from_f64_q28(h * g),
            h: T::from_f64(h),
            delta,
        })
    }
}

impl<T: Real> Ave<T> {
    /// Builds the estimator for step `h` (s) (see [`AveParams::new`]).
    pub fn new(cfg: &AveConfig, h: f32) -> Result<Self, ConfigError> {
        Ok(Self::from_law(AveParams::new(cfg, h)?))
    }

    /// Position estimate `xhat` (unit of `y`).
    pub fn xhat(&self) -> T {
        self.state().xhat
    }

    /// Switching gain `deltahat` (unit of `y` per second).
    pub fn deltahat(&self) -> T {
        self.state().delta
    }
}

impl<T: Real> Law for AveParams<T> {
    type Num = T;
    type State = AveState<T>;

    fn init(&self, y0: T) -> AveState<T> {
        AveState {
            xhat: y0,
            theta: T::ZERO,
            delta: T::ZERO,
        }
    }

    /// Explicit Euler step of eq. 4, with `e_n = xhat_n - y_n`:
    ///
    /// ```text
    /// xhat_{n+1}   = xhat_n + h (-k e_n + theta_n - delta_n sgn e_n)
    /// theta_{n+1}  = theta_n - h gamma1 e_n
    /// delta_{n+1}  = delta_n + h |e_n|            (Paper; Bounded clamps to [0, max];
    ///                                              Leaky subtracts h sigma delta_n)
    /// ```
    /// Returns `theta_{n+1}`, which already contains `y_n`.
    #[inline(always)]
    fn step(&self, s: &mut AveState<T>, y: T) -> T {
        let c = &self.c;
        let e = s.xhat - y;
        let sw = if e > T::ZERO {
            s.delta
        } else if e < T::ZERO {
            -s.delta
        } else {
            T::ZERO
        };
        s.xhat = s.xhat + (c.h * (s.theta - sw) - c.hk * e);
        s.theta = s.theta - c.hg * e;
        let inc = c.h * e.abs();
        s.delta = match c.delta {
            DeltaLaw::Paper => s.delta + inc,
            DeltaLaw::Bounded { max } => (s.delta + inc).min(max),
            DeltaLaw::Leaky { hsigma } => s.delta + inc - hsigma * s.delta,
        };
        s.theta
    }

    #[inline]
    fn output(&self, s: &AveState<T>) -> T {
        s.theta
    }

    /// New gains keep `theta1hat` (the output) and `deltahat` (a gain schedule may set it,
    /// `PaperBank::set_ave_deltahat`), and start from `xhat = y` (the last input) when the new
    /// `gamma1` is at least the old one: the position error a slower gain set left (at 20 Hz,
    /// a noise-sized fraction of a degree) would otherwise meet the new, larger `gamma1` and
    /// swing the velocity by hundreds of deg/s. To a smaller `gamma1` (slower gains) `xhat`
    /// is kept: the faster gains left it close to the input, and the last input itself
    /// carries a full noise sample, which the slow, lightly damped AVE turns into ringing
    /// (about `sqrt(gamma1)` times the offset in deg/s). Nothing when the gains did not
    /// change (docs/ADAPTIVE-GAINS.md, "How a gain change keeps the estimates").
    fn retune_state(&self, old: &Self, s: &mut AveState<T>, y: T) {
        if self == old || self.c.hg < old.c.hg {
            return;
        }
        s.xhat = y;
    }

    #[inline]
    fn translate(&self, s: &mut AveState<T>, d: T) {
        s.xhat = s.xhat + d;
    }

    /// The coarse step `2 h` of the fixed-point AVE (see [`AveParams`]); `None` for the float
    /// types.
    #[inline(always)]
    fn coarse(&self) -> Option<(Self, u32)> {
        T::coarse_get(&self.coarse).map(|c| {
            (
                Self {
                    c,
                    coarse: self.coarse,
                },
                T::AVE_STEP_FACTOR,
            )
        })
    }

    /// [`crate::Fx`]: the integer kernel (same results, see docs/FIXED-POINT.md); otherwise, or if
    /// the kernel gives up, [`step_n`] (with the coarse steps of [`Law::coarse`]).
    #[inline]
    fn advance(&self, s: &mut AveState<T>, y_prev: T, y_new: T, n: u32, hold: Hold) -> T {
        if advance_one(AveK::of(self), s, y_prev, y_new, n, hold) {
            return s.theta;
        }
        step_n(self, s, y_prev, y_new, n, hold)
    }

    #[inline]
    fn advance_pair(
        v: &Self,
        a2: &Self,
        sv: &mut AveState<T>,
        sa: &mut AveState<T>,
        interval: Interval<T>,
    ) -> bool {
        advance_two(AveK::of(v), AveK::of(a2), sv, sa, interval)
    }
}

/// The fixed-point AVE's kernel coefficients: those of the step `h` and, when the law has
/// one, of its coarse step `m h` ([`Law::coarse`]).
#[derive(Clone, Copy, Debug)]
struct AveK {
    fine: AveFx,
    coarse: Option<(AveFx, u32)>,
}

impl AveK {
    /// `None` for the float types or when a coefficient is outside the kernel's classes.
    #[inline(always)]
    fn of<T: Real>(p: &AveParams<T>) -> Option<Self> {
        let coarse = match p.coarse() {
            Some((c, m)) => Some((AveFx::of(&c.c)?, m)),
            None => None,
        };
        Some(Self {
            fine: AveFx::of(&p.c)?,
            coarse,
        })
    }
}

impl<T: Real> Kernel<AveState<T>> for AveK {
    /// The kernel over one interval of `n >= 1` steps `h` (`a2`: the series' second stage fed
    /// by `self`): `floor(n / m)` coarse steps, then `n mod m` steps `h`, with the inputs of
    /// [`crate::law::stepped_inputs`]; the states are written only when every part succeeds
    /// (else the caller steps the whole interval with the generic code, from the same state).
    #[inline(always)]
    fn advance(
        &self,
        a2: Option<&Self>,
        sv: &mut AveState<T>,
        sa: &mut AveState<T>,
        (first, inc, y_new): (i64, i64, i64),
        n: u32,
    ) -> bool {
        let (Some(mut v), Some(mut a)) = (AveFxState::of(sv), AveFxState::of(sa)) else {
            return false;
        };
        let mut y0 = first;
        let mut left = n;
        if let Some((cv, m)) = self.coarse {
            let ca = match a2.map(|k| k.coarse) {
                None => None,
                Some(Some((ca, ma))) if ma == m => Some(ca),
                // The stages disagree on the coarse step: the generic code decides.
                Some(_) => return false,
            };
            let q = n / m;
            let r = n % m;
            if q > 0 {
                // The coarse steps see first + j m inc (j = 1 .. q), the last y_new when no
                // step h follows: the values the generic loop accumulates (exact, no wrap:
                // between y_prev and y_new).
                let y_end = if r == 0 {
                    y_new
                } else {
                    first.wrapping_add(inc.wrapping_mul(i64::from(q * m)))
                };
                let ys = (first, inc.wrapping_mul(i64::from(m)), y_end);
                if !cv.run(ca.as_ref(), &mut v, &mut a, ys, q) {
                    return false;
                }
                y0 = y_end;
            }
            left = r;
        } else if a2.is_some_and(|k| k.coarse.is_some()) {
            return false;
        }
        if left > 0
            && !self
                .fine
                .run(a2.map(|k| &k.fine), &mut v, &mut a, (y0, inc, y_new), left)
        {
            return false;
        }
        v.store(sv);
        if a2.is_some() {
            a.store(sa);
        }
        true
    }
}

/// The `deltahat` law of [`AveFx`].
#[derive(Clone, Copy, Debug)]
enum DeltaFx {
    Paper,
    Bounded(i64),
    Leaky(i32),
}

/// The AVE's coefficients as raw Q31.32 bits for the integer kernel ([`crate::fxk`]): `h`,
/// `h k` and `h sigma` fractions below 1/2, `h gamma1` below 8 and a multiple of 2^-28
/// ([`Real::from_f64_q28`]; `hg28` = its raw bits / 16, an `i32`); `bound`: the range guard
/// `2^(B - 32)` on the states' high words, `B = 60 - G`, `|h gamma1| < 2^G` (see
/// [`AveStage::step`]).
#[derive(Clone, Copy, Debug)]
struct AveFx {
    h: i32,
    hk: i32,
    hg: Coef,
    hg28: i32,
    delta: DeltaFx,
    bound: u32,
}

crate::fxk::fx_state! {
    /// [`AveState`] as raw Q31.32 bits.
    AveFxState for AveState { x: xhat, th: theta, d: delta }
}

const PAPER: u8 = 0;
const BOUNDED: u8 = 1;
const LEAKY: u8 = 2;

impl AveFx {
    /// `None` for the float types or when a coefficient is outside the kernel's classes.
    #[inline(always)]
    fn of<T: Real>(p: &AveCoef<T>) -> Option<Self> {
        let hg = Coef::of(p.hg)?;
        // h gamma1 = hg28 / 2^28 exactly (Real::from_f64_q28), below 8 in magnitude.
        if hg.raw & 15 != 0 {
            return None;
        }
        let hg28 = i32::try_from(hg.raw >> 4).ok()?;
        let b = 60u32.checked_sub(hg.log2_bound())?;
        if b < 40 {
            return None;
        }
        Some(Self {
            h: frac(p.h)?,
            hk: frac(p.hk)?,
            hg,
            hg28,
            delta: match p.delta {
                DeltaLaw::Paper => DeltaFx::Paper,
                DeltaLaw::Bounded { max } => DeltaFx::Bounded(max.fx_bits()?),
                DeltaLaw::Leaky { hsigma } => DeltaFx::Leaky(frac(hsigma)?),
            },
            bound: 1 << (b - 32),
        })
    }

    fn law(&self) -> u8 {
        match self.delta {
            DeltaFx::Paper => PAPER,
            DeltaFx::Bounded(_) => BOUNDED,
            DeltaFx::Leaky(_) => LEAKY,
        }
    }

    /// [`crate::fxk::run`] of `n >= 1` steps with these coefficients (`a2`: the series' second
    /// stage fed by `self`) on the raw states; `false` when the range guard fails (the states
    /// are then unspecified: the caller drops them).
    #[inline(always)]
    fn run(
        &self,
        a2: Option<&AveFx>,
        v: &mut AveFxState,
        a: &mut AveFxState,
        ys: (i64, i64, i64),
        n: u32,
    ) -> bool {
        let bound = match a2 {
            Some(a2) if a2.law() != self.law() => return false,
            Some(a2) => self.bound.min(a2.bound),
            None => self.bound,
        };
        let ok = match self.law() {
            PAPER => run_law::<PAPER>(self, a2, v, a, ys, n, bound),
            BOUNDED => run_law::<BOUNDED>(self, a2, v, a, ys, n, bound),
            _ => run_law::<LEAKY>(self, a2, v, a, ys, n, bound),
        };
        ok.is_some()
    }
}

/// [`crate::fxk::run`] for the `deltahat` law `D`.
#[inline(never)]
fn run_law<const D: u8>(
    k: &AveFx,
    a2: Option<&AveFx>,
    v: &mut AveFxState,
    a: &mut AveFxState,
    ys: (i64, i64, i64),
    n: u32,
    bound: u32,
) -> Option<()> {
    let a2 = a2.map(|x| AveStage::<D>(*x));
    run(&AveStage::<D>(*k), a2.as_ref(), v, a, ys, n, bound)
}

/// The AVE with the `deltahat` law `D` as a kernel stage.
#[derive(Clone, Copy, Debug)]
struct AveStage<const D: u8>(AveFx);

impl<const D: u8> Stage for AveStage<D> {
    type S = AveFxState;

    /// [`AveParams::step`] on raw bits: the same operations in the same order, wrapping.
    ///
    /// Range (raw bits): with `|x|, |y|, |th|, |d| <= 2^B` and `B = 60 - G`: `|e| <= 2^(B+1)`,
    /// `|th - sw| <= 2^(B+1)`, `|h (th - sw)|, |h k e|, |h |e||, |h sigma d| <= 2^B` (fractions
    /// below 1/2), `|h gamma1 e| < 2^(B+1+G) = 2^61`, and the new `|x|, |d| <= 2^(B+2)`,
    /// `|th| < 2^62`: no operation leaves `i64`, so each is exact and equal to the saturating
    /// one. ([`crate::fxk::run`] checks the bound before every step.)
    #[inline(always)]
    fn step(&self, s: &mut AveFxState, y: i64) -> i64 {
        let k = &self.0;
        let e = s.x.wrapping_sub(y);
        let (sw, ke, ge, ie) = match i32::try_from(e) {
            // |e| < 1/2 (the usual case): one 32-bit product each.
            Ok(e32) => {
                let sw = if e32 == 0 {
                    0
                } else {
                    // d or -d by the sign of e.
                    let m = i64::from(e32 >> 31);
                    (s.d ^ m).wrapping_sub(m)
                };
                let ie = (umul32(e32.unsigned_abs(), k.h as u32) >> 32) as i64;
                // h gamma1 e = hg28 e / 2^28 (hg28 = raw / 16): one product, exact.
                (sw, mulf32(k.hk, e32), smul(k.hg28, e32) >> 28, ie)
            }
            Err(_) => {
                let sw = if e > 0 { s.d } else { s.d.wrapping_neg() };
                (
                    sw,
                    mulf(k.hk, e),
                    fx_mul(k.hg.raw, e),
                    mulf(k.h, e.wrapping_abs()),
                )
            }
        };
        let t = s.th.wrapping_sub(sw);
        s.x = s.x.wrapping_add(mulf(k.h, t).wrapping_sub(ke));
        s.th = s.th.wrapping_sub(ge);
        s.d = match (D, k.delta) {
            (BOUNDED, DeltaFx::Bounded(max)) => s.d.wrapping_add(ie).min(max),
            (LEAKY, DeltaFx::Leaky(hs)) => s.d.wrapping_add(ie).wrapping_sub(mulf(hs, s.d)),
            _ => s.d.wrapping_add(ie),
        };
        s.th
    }

    #[inline(always)]
    fn mag(s: &AveFxState) -> u32 {
        mag(s.x) | mag(s.th) | mag(s.d)
    }
}

impl Gains for AveConfig {
    /// `k` and `gamma1` geometrically; the `deltahat` law of the nearer one.
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        AveConfig {
            k: geometric(self.k, other.k, w),
            gamma1: geometric(self.gamma1, other.gamma1, w),
            delta: if w < 0.5 { self.delta } else { other.delta },
        }
    }

    /// [`AveParams`].
    fn build<V: LawVisitor>(&self, h: f32, to: V) -> Result<V::Output, ConfigError> {
        Ok(to.law(AveParams::<f32>::new(self, h)?))
    }
}

crate::family::family! {
    /// The AVE family of the paper bank: AVE velocity, AVE-AVE acceleration (one
    /// [`crate::VelAcc`] row, sharing its first stage when both halves have the same gains);
    /// gains [`BankGains::ave`](crate::BankGains::ave).
    AveFamily {
        gains: AveConfig = BankGains::ave,
        name: "ave",
        label: "AVE",
        channels: AveV, AveA,
        scheduling: Observer,
        switch: ObserverSwitch::ave,
    }
}
