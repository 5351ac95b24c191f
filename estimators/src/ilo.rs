//! Iterative learning observer (Chen & Chowdhury 2007, paper eq. 9) as a velocity estimator
//! (paper eq. 13).

use crate::adaptive::ObserverSwitch;
use crate::bank::{BankGains, Channel};
use crate::error::positive;
use crate::family::{geometric, Family, Gains, LawVisitor, Scheduling};
use crate::law::{Law, Stateful};
use crate::linear::{LinearLaw, LIN_MAX};
use crate::words::{WordReader, Words};
use crate::{ConfigError, Real};

/// Parameters of the ILO velocity estimator in physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct IloConfig {
    /// Learning gain `K1`, dimensionless, in `(0, 1]` (1: pure discrete integral update,
    /// < 1: leaky).
    pub k1: f32,
    /// Observer gain `L`, 1/s, `> 0`.
    pub l: f32,
    /// Learning gain `K2`, dimensionless per update (velocity per unit position error per
    /// `tau`), `> 0`. From a Lyapunov weight `Q` use [`IloConfig::from_lq`].
    pub k2: f32,
}

impl IloConfig {
    /// The fraction of a constant rate the velocity estimate settles at (dimensionless): on
    /// `y = r t` the observer settles with a constant error `e = y - xhat`, `v = K1 v + K2 e`
    /// gives `v = K2 e / (1 - K1)` and `L e + v = r`, so `v = r K2 / (K2 + L (1 - K1))`.
    /// 1 with `K1 = 1` (the integral update holds any constant rate); below 1 for a leaky
    /// update (`K1 < 1`), which reads a sustained rotation low by `1 -` this fraction: the
    /// paper's ILO2 (Table 2: `K1` 0.9, `L` 5, `K2` 10) by 4.8 %. Computed in `f64`.
    pub fn constant_rate_gain(&self) -> f64 {
        let (k1, l, k2) = (f64::from(self.k1), f64::from(self.l), f64::from(self.k2));
        k2 / (k2 + l * (1.0 - k1))
    }

    /// ILO1's gains (`K1 = 1`, learning delay `tau = h`) whose dynamics seen at the samples are
    /// those of the second-order observer `s^2 + 2 zeta wn s + wn^2` sampled every `dt_s`:
    /// the one-step map of the `N = round(dt_s / h_s)` Euler steps of one sample has the
    /// eigenvalues `exp(s dt)` of its poles `s = -zeta wn +- i wn sqrt(1 - zeta^2)`.
    ///
    /// Within one step the observer turns `2 pi / dt` rad/s faster than that: its poles are
    /// the sampled ones' first alias, `s + i 2 pi / dt`, whose `N`-th power of the step's
    /// eigenvalue `exp(h (s + i 2 pi / dt))` is the same `exp(s dt)`. That alias is where ILO1
    /// tuned on a motion lands (the shipped and tuned sets with `K2` of 36 to 3,900): at the
    /// same per-sample poles it follows a motion more closely than the observer without the
    /// alias (docs/MOTION-FAMILY.md, "ILO1 as a one-gain observer"). With the step's
    /// eigenvalues `mu`, `mu bar`, the Euler step's matrix (on `xhat` and the delayed `v`) has
    /// the trace `2 - h (L + K2)` and the determinant `1 - h L`, so the gains are exact:
    /// `L = (1 - |mu|^2) / h` and `K2 = (2 - 2 Re(mu)) / h - L`.
    ///
    /// `wn_rad_s > 0` (rad/s), `0 < zeta < 1`, the damped frequency below `pi / dt_s`; `h_s`
    /// and `dt_s` in s with `dt_s >= h_s`. Computed in `f64` (`libm`).
    pub fn per_sample(wn_rad_s: f64, zeta: f64, h_s: f64, dt_s: f64) -> Result<Self, ConfigError> {
        Self::per_sample_alias(wn_rad_s, zeta, 1, h_s, dt_s)
    }

    /// [`Self::per_sample`] through the `alias`-th alias: within one step the observer turns
    /// `alias 2 pi / dt` rad/s faster than its sampled poles, `s + i alias 2 pi / dt`. Every
    /// alias has the same poles at the samples and other zeros: ILO1 tuned on a fast sine
    /// lands near the tenth, and the fifth follows the motions of docs/MOTION-FAMILY.md
    /// within 1.5x of ILO1 tuned on each ("ILO1 by the jerk index").
    ///
    /// `alias >= 1` and the step's angle `(wd + alias 2 pi / dt) h` below `pi`, else
    /// [`ConfigError::ObserverPoles`]; the rest as [`Self::per_sample`].
    pub fn per_sample_alias(
        wn_rad_s: f64,
        zeta: f64,
        alias: u32,
        h_s: f64,
        dt_s: f64,
    ) -> Result<Self, ConfigError> {
        let wn = positive("wn", wn_rad_s)?;
        let h = positive("h", h_s)?;
        let dt = positive("dt", dt_s)?;
        if !zeta.is_finite() {
            return Err(ConfigError::NotFinite("zeta"));
        }
        let steps = libm::round(dt / h);
        if steps < 1.0 {
            return Err(ConfigError::SamplePeriodTooShort);
        }
        let dt = steps * h;
        if !(zeta > 0.0 && zeta < 1.0) || alias == 0 {
            return Err(ConfigError::ObserverPoles);
        }
        let wd = wn * libm::sqrt(1.0 - zeta * zeta);
        if wd * dt >= core::f64::consts::PI {
            return Err(ConfigError::ObserverPoles);
        }
        // The step's eigenvalue: exp(h (-zeta wn + i (wd + alias 2 pi / dt))).
        let radius = libm::exp(-zeta * wn * h);
        let angle = (wd + f64::from(alias) * 2.0 * core::f64::consts::PI / dt) * h;
        if angle >= core::f64::consts::PI {
            return Err(ConfigError::ObserverPoles);
        }
        let l = (1.0 - radius * radius) / h;
        let k2 = (2.0 - 2.0 * radius * libm::cos(angle)) / h - l;
        if !(h * l < 1.0 && k2 > 0.0) {
            return Err(ConfigError::ObserverPoles);
        }
        Ok(Self {
            k1: 1.0,
            l: l as f32,
            k2: k2 as f32,
        })
    }

    /// Gains from `(K1, L, Q)` by Theorem 3.1 for the scalar case `A = 0, C = F = 1`:
    /// `(-L) P + P (-L) = -Q` gives `P = Q / (2L)` and `P F = K2 C` gives `K2 = Q / (2L)`.
    pub const fn from_lq(k1: f32, l: f32, q: f32) -> Self {
        Self {
            k1,
            l,
            k2: q / (2.0 * l),
        }
    }
}

/// The ILO velocity estimator (`A = 0, B = 0, C = 1, F = 1`) with learning delay
/// `tau = D * h` held in a statically sized buffer `[T; D]`:
///
/// ```text
/// dxhat/dt = L (y - xhat) + v(t)
/// v(t)     = K1 v(t - tau) + K2 (y - xhat)
/// ```
///
/// Output: `v` (deg/s for `y` in deg). `D = 0` does not compile. The validated coefficients
/// ([`crate::Law`]); the state is [`IloState`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IloParams<T: Real, const D: usize> {
    hl: T,
    h: T,
    k1: T,
    k2: T,
}

/// State of the ILO: `xhat`, the last output and the delay line of the last `D` outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IloState<T: Real, const D: usize> {
    /// Position estimate `xhat` (unit of `y`).
    pub xhat: T,
    /// Last output `v` (unit/s).
    pub out: T,
    /// `buf[head]` is the oldest value `v_{n-D}`.
    buf: [T; D],
    head: u32,
}

/// The ILO as one object (parameters and state, [`crate::Estimator`]).
/// RAM: `(D + 6)` words of `T` plus the ring index (see [`crate::ram`]).
pub type Ilo<T, const D: usize> = Stateful<IloParams<T, D>>;

/// Its words ([`crate::words`]): `h L`, `h`, `K1`, `K2` in `T`.
impl<T: Real + Words, const D: usize> Words for IloParams<T, D> {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        [self.hl, self.h, self.k1, self.k2].put_words(out);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        let [hl, h, k1, k2] = <[T; 4]>::take_words(r);
        Self { hl, h, k1, k2 }
    }
}

impl<T: Real, const D: usize> IloParams<T, D> {
    const D_POSITIVE: () = assert!(
        D >= 1 && D <= u32::MAX as usize,
        "the ILO delay D must be at least 1 step"
    );

    /// Validates `cfg` for step `h` (s); `tau = D * h`. Errors: `K1` outside `(0, 1]`,
    /// non-positive or non-finite `L`, `K2`, `h`; `h * L >= 1`.
    pub fn new(cfg: &IloConfig, h: f32) -> Result<Self, ConfigError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::D_POSITIVE;
        let h = positive("h", f64::from(h))?;
        let l = positive("L", f64::from(cfg.l))?;
        let k2 = positive("K2", f64::from(cfg.k2))?;
        let k1 = f64::from(cfg.k1);
        if !k1.is_finite() {
            return Err(ConfigError::NotFinite("K1"));
        }
        if !(k1 > 0.0 && k1 <= 1.0) {
            return Err(ConfigError::K1OutOfRange);
        }
        if h * l >= 1.0 {
            return Err(ConfigError::StepTooLarge("L"));
        }
        Ok(Self {
            hl: T::from_f64(h * l),
            h: T::from_f64(h),
            k1: T::from_f64(k1),
            k2: T::from_f64(k2),
        })
    }

    /// The learning delay `tau = D * h` in steps.
    pub const DELAY_STEPS: usize = D;
}

impl<T: Real, const D: usize> Ilo<T, D> {
    /// Builds the estimator for step `h` (s) (see [`IloParams::new`]).
    pub fn new(cfg: &IloConfig, h: f32) -> Result<Self, ConfigError> {
        Ok(Self::from_law(IloParams::new(cfg, h)?))
    }

    /// Position estimate `xhat` (unit of `y`).
    pub fn xhat(&self) -> T {
        self.state().xhat
    }
}

impl<T: Real, const D: usize> Law for IloParams<T, D> {
    type Num = T;
    type State = IloState<T, D>;

    fn init(&self, y0: T) -> IloState<T, D> {
        IloState {
            xhat: y0,
            out: T::ZERO,
            buf: [T::ZERO; D],
            head: 0,
        }
    }

    /// Explicit Euler step with `e_n = y_n - xhat_n`:
    ///
    /// ```text
    /// v_n        = K1 v_{n-D} + K2 e_n
    /// xhat_{n+1} = xhat_n + h (L e_n + v_n)
    /// ```
    /// Returns `v_n`.
    #[inline(always)]
    fn step(&self, s: &mut IloState<T, D>, y: T) -> T {
        let e = y - s.xhat;
        let hd = s.head as usize;
        let old = s.buf.get(hd).copied().unwrap_or(T::ZERO);
        let v = self.k1 * old + self.k2 * e;
        if let Some(slot) = s.buf.get_mut(hd) {
            *slot = v;
        }
        s.head = if hd + 1 >= D { 0 } else { s.head + 1 };
        s.xhat = s.xhat + (self.hl * e + self.h * v);
        s.out = v;
        v
    }

    #[inline]
    fn output(&self, s: &IloState<T, D>) -> T {
        s.out
    }

    #[inline]
    fn translate(&self, s: &mut IloState<T, D>, d: T) {
        s.xhat = s.xhat + d;
    }

    /// In equilibrium `v = K1 v + K2 e`, so the error `e = y - xhat` is `c v` with
    /// `c = (1 - K1) / K2` (s): `xhat = y - c v`, the output `v` and the delay line kept; the
    /// next step at `y` returns `K1 v + K2 c v = v`. Between two sets with `K1 = 1` (no
    /// offset: the equilibrium does not depend on the gains) the state is kept as it is,
    /// with the position the observer filtered: setting `xhat` to the last sample would turn
    /// that sample's noise into a transient, large for the `K2` near 1,000 of ILO1 placed
    /// through a higher alias ([`IloConfig::per_sample_alias`]). `c` in f64 (a retune is
    /// rare). Nothing when the gains did not change.
    fn retune_state(&self, old: &Self, s: &mut IloState<T, D>, y: T) {
        if self == old || (self.k1 == T::ONE && old.k1 == T::ONE) {
            return;
        }
        let c = (1.0 - self.k1.to_f64()) / self.k2.to_f64();
        s.xhat = y - T::from_f64(c * s.out.to_f64());
    }
}

impl<T: Real, const D: usize> LinearLaw for IloParams<T, D> {
    const DIM: usize = 1 + D;
    const POSITION: [bool; LIN_MAX] = [true, false, false, false];

    /// `[xhat, v_{n-1}, v_{n-2}, .., v_{n-D}]` (newest first).
    #[inline]
    fn lin_state(&self, st: &IloState<T, D>) -> [T; LIN_MAX] {
        let mut s = [T::ZERO; LIN_MAX];
        if let Some(x) = s.get_mut(0) {
            *x = st.xhat;
        }
        for i in 0..D.min(LIN_MAX - 1) {
            // newest is at head - 1, then head - 2, ...
            let idx = (st.head as usize + D - 1 - i) % D;
            if let (Some(dst), Some(src)) = (s.get_mut(1 + i), st.buf.get(idx)) {
                *dst = *src;
            }
        }
        s
    }

    #[inline]
    fn set_lin_state(&self, st: &mut IloState<T, D>, s: &[T; LIN_MAX]) {
        st.xhat = s[0];
        st.head = 0;
        // buf[0] must be the oldest: v_{n-D} = s[D], ..., newest v_{n-1} = s[1] at buf[D-1].
        for j in 0..D.min(LIN_MAX - 1) {
            if let (Some(dst), Some(src)) = (st.buf.get_mut(j), s.get(D - j)) {
                *dst = *src;
            }
        }
        st.out = s[1];
    }

    fn lin_step_f64(&self, s: &mut [f64; LIN_MAX], y: f64) -> f64 {
        let e = y - s[0];
        let oldest = s.get(D).copied().unwrap_or(0.0);
        let v = self.k1.to_f64() * oldest + self.k2.to_f64() * e;
        s[0] += self.hl.to_f64() * e + self.h.to_f64() * v;
        // shift the delay line: newest first
        let mut i = D.min(LIN_MAX - 1);
        while i > 1 {
            s[i] = s[i - 1];
            i -= 1;
        }
        s[1] = v;
        v
    }
}

/// The ILO families of the paper bank: `IloFamily<0>` is ILO1 (velocity, Table 2 preset 1)
/// and ILO1-ILO1 (acceleration, Table 4 preset 1), `IloFamily<1>` ILO2, `IloFamily<2>` ILO3;
/// gains [`BankGains::ilo`]`[I]`.
#[derive(Clone, Copy, Debug)]
pub struct IloFamily<const I: usize>;

impl<const I: usize> Family for IloFamily<I> {
    type Gains = IloConfig;
    const NAME: &'static str = ["ilo1", "ilo2", "ilo3"][I];
    const LABEL: &'static str = ["ILO1", "ILO2", "ILO3"][I];
    const VELOCITY: Channel = [Channel::Ilo1V, Channel::Ilo2V, Channel::Ilo3V][I];
    const ACCELERATION: Channel = [Channel::Ilo1A, Channel::Ilo2A, Channel::Ilo3A][I];
    const SCHEDULING: Scheduling = Scheduling::Observer;

    fn get(half: &BankGains) -> IloConfig {
        half.ilo[I]
    }

    fn set(half: &mut BankGains, gains: IloConfig) {
        half.ilo[I] = gains;
    }

    fn switch_up_mut(switch: &mut ObserverSwitch) -> Option<&mut f32> {
        Some(&mut switch.ilo[I])
    }
}

impl Gains for IloConfig {
    /// `L` and `K2` geometrically, `K1` through its leak `1 - K1` (linearly where a leak is
    /// 0).
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        IloConfig {
            k1: 1.0 - geometric(1.0 - self.k1, 1.0 - other.k1, w),
            l: geometric(self.l, other.l, w),
            k2: geometric(self.k2, other.k2, w),
        }
    }

    /// [`IloParams`] with `D = 1` (learning delay `tau = h`), as in the bank.
    fn build<V: LawVisitor>(&self, h: f32, to: V) -> Result<V::Output, ConfigError> {
        Ok(to.law(IloParams::<f32, 1>::new(self, h)?))
    }

    const PAST_TOP: bool = true;

    /// [`IloConfig::per_sample`] at the rule's bandwidth and damping (`K1 = 1`: it holds a
    /// constant rate); `self` where that fails.
    fn past_top(&self, rule: &crate::family::PastTop) -> Self {
        IloConfig::per_sample(rule.wn_rad_s, rule.zeta, rule.h_s, rule.dt_s).unwrap_or(*self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-sample map of `n` Euler steps of ILO1 (`tau = h`) on the state `(xhat, v)` with
    /// the input held at 0, multiplied out step by step, and its eigenvalues.
    fn sample_map_eigenvalues(c: &IloConfig, h: f64, n: u32) -> [(f64, f64); 2] {
        let (k1, l, k2) = (f64::from(c.k1), f64::from(c.l), f64::from(c.k2));
        // One step: v' = K1 v - K2 x; x' = x + h (-L x + v').
        let m = [[1.0 - h * l - h * k2, h * k1], [-k2, k1]];
        let mut p = [[1.0, 0.0], [0.0, 1.0]];
        for _ in 0..n {
            p = [
                [
                    m[0][0] * p[0][0] + m[0][1] * p[1][0],
                    m[0][0] * p[0][1] + m[0][1] * p[1][1],
                ],
                [
                    m[1][0] * p[0][0] + m[1][1] * p[1][0],
                    m[1][0] * p[0][1] + m[1][1] * p[1][1],
                ],
            ];
        }
        let (tr, det) = (p[0][0] + p[1][1], p[0][0] * p[1][1] - p[0][1] * p[1][0]);
        let disc = tr * tr / 4.0 - det;
        assert!(disc < 0.0, "complex poles expected: {disc}");
        let im = libm::sqrt(-disc);
        [(tr / 2.0, im), (tr / 2.0, -im)]
    }

    /// `per_sample` places the sampled poles where asked: the map of one sample's 100 steps has
    /// the eigenvalues `exp(s dt)` (to 1e-6, the gains being `f32`), at bandwidths from 5 to
    /// 250 rad/s and dampings from 0.1 to 0.7, at 100 Hz and at 20 Hz, through the first and
    /// the fifth alias.
    #[test]
    fn per_sample_places_the_sampled_poles() {
        for (h, dt, alias) in [
            (1e-4, 0.01, 1),
            (1e-4, 0.05, 1),
            (1e-4, 0.01, 5),
            (1e-4, 0.05, 5),
        ] {
            let n = libm::round(dt / h) as u32;
            for wn in [5.0, 20.0, 60.0, 250.0] {
                for zeta in [0.1, 0.2, 0.45, 0.7] {
                    let wd = wn * libm::sqrt(1.0 - zeta * zeta);
                    if wd * dt >= core::f64::consts::PI {
                        assert_eq!(
                            IloConfig::per_sample_alias(wn, zeta, alias, h, dt),
                            Err(ConfigError::ObserverPoles)
                        );
                        continue;
                    }
                    let c = IloConfig::per_sample_alias(wn, zeta, alias, h, dt).unwrap();
                    assert_eq!(c.k1, 1.0);
                    let r = libm::exp(-zeta * wn * dt);
                    let want = (r * libm::cos(wd * dt), r * libm::sin(wd * dt));
                    let got = sample_map_eigenvalues(&c, h, n);
                    let d = (got[0].0 - want.0).abs() + (got[0].1.abs() - want.1).abs();
                    assert!(d < 1e-6, "wn {wn} zeta {zeta} dt {dt}: {got:?} vs {want:?}");
                }
            }
        }
    }

    /// ILO1 tuned on fig5 at 0.01 deg^2 (`nav440 tune`: `K1` 0.99952, `L` 5.867, `K2` 43.66) is
    /// such an observer: its 100-step map's poles (33 rad/s, damping 0.16) given to
    /// `per_sample` give back its `K2` within 1 %, and its `L` plus its leak `(1 - K1) / h`
    /// within 2 %.
    #[test]
    fn per_sample_matches_a_tuned_set() {
        let tuned = IloConfig {
            k1: 0.999_518_16,
            l: 5.866_687_3,
            k2: 43.662_82,
        };
        let (h, dt) = (1e-4, 0.01);
        let [(re, im), _] = sample_map_eigenvalues(&tuned, h, 100);
        // s = ln(z) / dt.
        let (sr, si) = (
            libm::log(libm::hypot(re, im)) / dt,
            libm::atan2(im, re) / dt,
        );
        let wn = libm::hypot(sr, si);
        let zeta = -sr / wn;
        assert!(
            (wn - 33.2).abs() < 0.5 && (zeta - 0.16).abs() < 0.01,
            "{wn} {zeta}"
        );
        let c = IloConfig::per_sample(wn, zeta, h, dt).unwrap();
        let leak = (1.0 - f64::from(tuned.k1)) / h;
        assert!(
            (f64::from(c.k2) / f64::from(tuned.k2) - 1.0).abs() < 0.01,
            "{c:?}"
        );
        assert!(
            (f64::from(c.l) / (f64::from(tuned.l) + leak) - 1.0).abs() < 0.02,
            "{c:?}"
        );
    }

    #[test]
    fn per_sample_refuses_what_it_cannot_place() {
        let ok = |wn, zeta| IloConfig::per_sample(wn, zeta, 1e-4, 0.01);
        assert_eq!(ok(0.0, 0.2), Err(ConfigError::NotPositive("wn")));
        assert_eq!(ok(f64::NAN, 0.2), Err(ConfigError::NotFinite("wn")));
        assert_eq!(ok(30.0, 0.0), Err(ConfigError::ObserverPoles));
        assert_eq!(ok(30.0, 1.0), Err(ConfigError::ObserverPoles));
        assert_eq!(ok(30.0, f64::NAN), Err(ConfigError::NotFinite("zeta")));
        // Damped frequency at Nyquist (pi / dt = 314 rad/s).
        assert_eq!(ok(400.0, 0.1), Err(ConfigError::ObserverPoles));
        assert_eq!(
            IloConfig::per_sample(30.0, 0.2, 1e-4, 1e-5),
            Err(ConfigError::SamplePeriodTooShort)
        );
        // No alias 0, and none whose step turns by pi or more (dt / 2h = 50 at 100 Hz).
        let alias = |a| IloConfig::per_sample_alias(30.0, 0.2, a, 1e-4, 0.01);
        assert_eq!(alias(0), Err(ConfigError::ObserverPoles));
        assert!(alias(49).is_ok());
        assert_eq!(alias(50), Err(ConfigError::ObserverPoles));
    }

    /// A gain change between two sets with `K1 = 1` keeps the state as it is (their
    /// equilibrium `xhat = y` does not depend on the gains); to a leaky set (`K1 < 1`) `xhat`
    /// goes to that set's equilibrium for the output, `y - (1 - K1) / K2 * v`, and the output
    /// is kept either way.
    #[test]
    fn a_gain_change_keeps_the_state_unless_the_equilibrium_moves() {
        let build = |c: IloConfig| IloParams::<f64, 1>::new(&c, 1e-4).unwrap();
        let a = build(IloConfig::per_sample(30.0, 0.25, 1e-4, 0.01).unwrap());
        let b = build(IloConfig::per_sample_alias(40.0, 0.3, 5, 1e-4, 0.01).unwrap());
        let leaky = build(IloConfig {
            k1: 0.99,
            l: 5.0,
            k2: 50.0,
        });
        let mut s = a.init(0.0);
        for k in 0..300 {
            // A ramp of 100 deg/s with an alternating 0.1 deg disturbance.
            let y = 0.01 * f64::from(k) + if k % 2 == 0 { 0.1 } else { -0.1 };
            a.step(&mut s, y);
        }
        let before = s;
        b.retune_state(&a, &mut s, 3.5);
        assert_eq!(s, before);
        leaky.retune_state(&b, &mut s, 3.5);
        assert_eq!(s.out, before.out);
        let want = 3.5 - (1.0 - 0.99_f32 as f64) / 50.0 * before.out;
        assert!((s.xhat - want).abs() < 1e-9, "{} vs {want}", s.xhat);
    }

    /// The law run on a ramp of 200 deg/s (steps of `h` = 1e-4 s, 40 s) settles at the rate
    /// times [`IloConfig::constant_rate_gain`]: the paper's ILO2 at 95.2 % (`10 / (10 + 5 x
    /// 0.1)`), a leaky set with little `K2` (the form `nav440 tune` gives on a zero-mean motion
    /// at high noise, `K1` 0.99966, `L` 3.52, `K2` 0.0345) at 96.7 %, ILO1 (`K1` = 1) at 100 %.
    #[test]
    fn a_constant_rate_settles_at_the_constant_rate_gain() {
        let rate = 200.0;
        for (c, want) in [
            (crate::presets::ILO2_TABLE2, 10.0 / 10.5),
            (
                IloConfig {
                    k1: 0.999_664_07,
                    l: 3.523_521_4,
                    k2: 0.034_486_07,
                },
                0.9668,
            ),
            (crate::presets::ILO1_TABLE2, 1.0),
        ] {
            let gain = c.constant_rate_gain();
            assert!((gain - want).abs() < 1e-4, "{c:?}: {gain} vs {want}");
            let law = IloParams::<f64, 1>::new(&c, 1e-4).unwrap();
            let mut s = law.init(0.0);
            let mut v = 0.0;
            for k in 0..400_000 {
                v = law.step(&mut s, rate * 1e-4 * f64::from(k));
            }
            assert!(
                (v / rate - gain).abs() < 1e-5,
                "{c:?}: {} vs {gain}",
                v / rate
            );
        }
    }

    /// ILO1 tuned on the fast sine at 0.01 deg^2 (`nav440 tune`: `K1` 0.99575, `L` 7.176,
    /// `K2` 3,904) turns by 0.636 rad per step: 63.6 rad per sample of 100 steps, ten turns
    /// (62.8 rad) beyond its per-sample angle. It lies near the tenth alias, not the first.
    #[test]
    fn a_tuned_set_lies_near_a_higher_alias() {
        let (k1, l, k2, h) = (0.995_751_44_f64, 7.176_077_f64, 3_904.464_4_f64, 1e-4);
        // The step's matrix on (xhat, delayed v): trace 1 - h (L + K2) + K1, determinant
        // K1 (1 - h L).
        let (tr, det) = (1.0 - h * (l + k2) + k1, k1 * (1.0 - h * l));
        let step_angle = libm::acos(tr / (2.0 * libm::sqrt(det)));
        let turns = libm::floor(step_angle * 100.0 / (2.0 * core::f64::consts::PI));
        assert_eq!(turns, 10.0, "{step_angle}");
    }
}
