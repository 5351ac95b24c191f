//! Steady-state constant-acceleration Kalman tracker (alpha-beta-gamma filter): the reference
//! an engineer would otherwise use. Not from the paper.
//!
//! # Any sample interval
//!
//! The gain is the steady-state one for the nominal period `dt0` (s). Only the dimensionless
//! `q dt0^5 / r` (`q` in deg^2/s^5, `r` in deg^2) sets it. A sample interval `dt` longer than
//! `dt0` is not one predict + update over `dt`: with the gain for `dt0`, the error loop
//! `(I - K H) F(dt)` is unstable once `dt` is a few `dt0` (at `q` = 1e8 deg^2/s^5, `r` = 0.01
//! deg^2, `dt0` = 10 ms, so `q dt0^5 / r = 1`: spectral radius 0.62 at `dt0`, 0.74 at `2 dt0`,
//! 1.5 at `3 dt0`, 6.2 at `5 dt0`). It is `k = ceil(dt / dt0)` sub-steps of `dt / k` (at most
//! `dt0`) each, every one a predict + update with the nominal gain and the input interpolated
//! as the [`Hold`] says (linear: `y_prev + (y - y_prev) j / k` at the `j`-th sub-step). Each
//! sub-step is a loop the nominal gain is stable for (`(I - K H) F(m dt0)` with `0 < m <= 1`:
//! spectral radius below 1 for every `q dt0^5 / r` from `2^-40` to `2^30`, e.g. 0.61 at
//! `m = 1`, 0.95 at `m = 0.1`, 0.995 at `m = 0.01` for `q dt0^5 / r = 1`; random and
//! alternating sequences of such sub-steps contract too, measured in `f64`), so that the
//! tracker is one fixed-gain filter stepped at (at most) its nominal period whatever the
//! interval sequence: a bounded input gives a bounded output for jitter, dropouts, a lasting
//! rate below or above the nominal one (`estimators/tests/timing.rs`). Shorter intervals
//! (`dt <= dt0`) are one predict + update over `dt`. Cost: `k` updates of 9 multiplications for an interval of
//! `k` nominal periods (the nominal rate's work per second) and one division by `k`.
//!
//! Re-deriving the steady-state gain for each interval instead (the dimensionless gains
//! `(alpha, beta, gamma)` are functions of `q dt^5 / r` alone, a small table would do) is
//! stable at any fixed interval but not under switching: random and alternating sequences of
//! 5 ms and 0.25 s intervals at `q dt0^5 / r = 100` (`dt0` = 10 ms) grow the error by up to 1.9
//! per update (measured, `f64`). A time-varying covariance would be stable but needs 6 more
//! words per tracker and a dynamic range (`q dt` up to 1e12 deg^2/s^4, `q dt^5 / 20` down to
//! 1e-22 deg^2) that the fixed-point type does not have.
//!
//! An interval of more than [`MAX_SUBSTEPS`] nominal periods re-initialises the tracker at the
//! new sample (what a bank's gap rule does much earlier: a bank refuses a gap rule above
//! [`crate::MAX_GAP_PERIODS`], so it never reaches this); [`Kalman::restarts`] counts it for the
//! stand-alone tracker.

use crate::error::positive;
use crate::family::{geometric, Gains, LawVisitor};
use crate::law::Law;
use crate::words::{WordReader, Words};
use crate::{ConfigError, Hold, Real};

/// Longest sample interval the tracker integrates across, in nominal periods: an interval of
/// `n` steps `h` runs `ceil(n / n0)` sub-steps (see the [module documentation](self)), at most
/// this many; a longer one re-initialises the tracker at the new sample. Above
/// [`crate::MAX_GAP_PERIODS`] (the longest gap rule a bank accepts) so that a bank's gap rule
/// always acts first.
pub const MAX_SUBSTEPS: u32 = 1024;

/// Parameters of the tracker in physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct KalmanConfig {
    /// Nominal sample period `dt0`, s (NAV440 at 100 Hz: 0.01). The steady-state gains are for
    /// this period; an interval `dt <= dt0` is one update over `dt`, a longer one
    /// `ceil(dt / dt0)` sub-steps (see the [module documentation](self)).
    pub dt: f32,
    /// Power spectral density `q` of the white jerk driving the model, unit^2/s^5 (deg^2/s^5
    /// for an angle in deg): how fast the acceleration may change. Only `q / r` sets the
    /// steady-state gain; the three closed-loop poles lie near `|s| = (q / (r dt))^(1/6)`
    /// rad/s, so `q = r dt w0^6` gives the bandwidth `w0` (each factor 10 in `q / r` moves it
    /// by 1.47). Larger follows faster motion with more noise.
    pub q: f32,
    /// Measurement noise variance `r` of the input, unit^2 (deg^2): e.g. 0.01 for 0.1 deg RMS
    /// noise ([`crate::NoiseEstimator`] measures it on a moving signal).
    pub r: f32,
}

/// Constant-acceleration model `x' = v, v' = a, a' = w` (white jerk of PSD `q`), position
/// measured with variance `r`, discretised exactly at `dt0`:
///
/// ```text
/// F = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]],   H = [1, 0, 0]
/// Q = q [[dt^5/20, dt^4/8, dt^3/6], [dt^4/8, dt^3/3, dt^2/2], [dt^3/6, dt^2/2, dt]]
/// ```
///
/// The steady-state gain `K = [alpha, beta/dt0, 2 gamma/dt0^2]` solves the discrete Riccati
/// equation (solved once at construction in `f64`, see [`steady_state_gain`]). Per update over `dt` (the sample
/// interval when `dt <= dt0`, else each of its `k = ceil(dt / dt0)` sub-steps `dt / k`, with
/// the input `y` linearly interpolated from the previous measurement; see the
/// [module documentation](self)):
///
/// ```text
/// predict: x- = x + v dt + a dt^2/2,  v- = v + a dt,  a- = a
/// update:  r = y - x-;  x = x- + K0 r,  v = v- + K1 r,  a = a- + K2 r
/// ```
///
/// Outputs `v` (deg/s) and `a` (deg/s^2). RAM: 9 words of `T` and a `u32`.
#[derive(Clone, Copy, Debug)]
pub struct Kalman<T: Real> {
    k: [T; 3],
    /// Nominal period, s.
    dt0: T,
    s: KalmanState<T>,
    /// The last measurement (start of the next interval's interpolation).
    y_prev: T,
    restarts: u32,
}

impl<T: Real> Kalman<T> {
    /// Builds the tracker; the Riccati recursion runs here (at most 2,000 iterations in `f64`,
    /// see [`steady_state_gain`]). Errors: non-positive or non-finite `dt`, `q`, `r`.
    pub fn new(cfg: &KalmanConfig) -> Result<Self, ConfigError> {
        let dt = positive("dt", f64::from(cfg.dt))?;
        let q = positive("q", f64::from(cfg.q))?;
        let r = positive("r", f64::from(cfg.r))?;
        let k = steady_state_gain(dt, q, r);
        Ok(Self {
            k: [T::from_f64(k[0]), T::from_f64(k[1]), T::from_f64(k[2])],
            dt0: T::from_f64(dt),
            s: KalmanState::default(),
            y_prev: T::ZERO,
            restarts: 0,
        })
    }

    /// The steady-state gain `[K0, K1 (1/s), K2 (1/s^2)]`.
    pub fn gain(&self) -> [T; 3] {
        self.k
    }

    /// Changes the noise model to `q`, `r` (as [`KalmanConfig`]; the nominal period stays),
    /// keeping the state: the estimates go on from where they are with the new steady-state
    /// gain (bumpless). The Riccati recursion runs here, as in [`Self::new`]. Errors (nothing
    /// changed): non-positive or non-finite `q`, `r`.
    pub fn set_noise(&mut self, q: f32, r: f32) -> Result<(), ConfigError> {
        let q = positive("q", f64::from(q))?;
        let r = positive("r", f64::from(r))?;
        let k = steady_state_gain(self.dt0.to_f64(), q, r);
        self.k = [T::from_f64(k[0]), T::from_f64(k[1]), T::from_f64(k[2])];
        Ok(())
    }

    /// Starts at position `y0` with zero velocity and acceleration.
    pub fn reset(&mut self, y0: T) {
        self.s = KalmanState {
            x: y0,
            v: T::ZERO,
            a: T::ZERO,
        };
        self.y_prev = y0;
    }

    /// One predict + update with the measurement `y` (input unit) taken `dt` seconds (as `T`)
    /// after the previous one.
    ///
    /// Convention: the measurement first, then the *interval* in seconds; the first
    /// measurement goes to [`Self::reset`] instead. The banks and [`crate::SampleAdapter`]
    /// take the other order and an absolute time: `update(t_us, y)`, the sample's time stamp
    /// in integer microseconds first, and compute the interval themselves (as
    /// [`KalmanParams`], the bank's tracker, does: `dt = round(interval / h) h`).
    ///
    /// `dt <= dt0` (the nominal period): one predict + update over `dt`. Longer: `k` sub-steps
    /// `dt / k` (`k` the smallest count with `k dt0 >= dt - 2^-10 dt0`), the `j`-th measuring
    /// `y_prev + (y - y_prev) j / k` (`y_prev` the previous measurement); `k` above
    /// [`MAX_SUBSTEPS`] re-initialises at `y` instead (counted, [`Self::restarts`]).
    #[inline]
    pub fn update(&mut self, y: T, dt: T) {
        let y_prev = self.y_prev;
        self.y_prev = y;
        // The smallest k with k dt0 >= dt, give or take 2^-10 dt0 (so that an interval of
        // exactly k periods, rounded, is k sub-steps).
        let slack = self.dt0.div_int(1024);
        if dt <= self.dt0 + slack {
            predict_update(&self.k, &mut self.s, y, dt);
            return;
        }
        let mut k = 2u32;
        while T::from_i32(k as i32) * self.dt0 < dt - slack {
            if k >= MAX_SUBSTEPS {
                self.restarts = self.restarts.saturating_add(1);
                self.reset(y);
                return;
            }
            k += 1;
        }
        let d = y - y_prev;
        let dts = dt.div_int(k);
        for j in 1..k {
            let yj = y_prev + (d * T::from_i32(j as i32)).div_int(k);
            predict_update(&self.k, &mut self.s, yj, dts);
        }
        predict_update(&self.k, &mut self.s, y, dts);
    }

    /// Intervals longer than [`MAX_SUBSTEPS`] nominal periods, each of which re-initialised
    /// the tracker at its new measurement.
    pub fn restarts(&self) -> u32 {
        self.restarts
    }

    /// Adds `d` to the position estimate (moves the tracker to a shifted input frame).
    pub fn translate(&mut self, d: T) {
        self.s.x = self.s.x + d;
        self.y_prev = self.y_prev + d;
    }

    /// Position estimate (unit of `y`).
    pub fn position(&self) -> T {
        self.s.x
    }

    /// Velocity estimate (unit/s).
    pub fn velocity(&self) -> T {
        self.s.v
    }

    /// Acceleration estimate (unit/s^2).
    pub fn acceleration(&self) -> T {
        self.s.a
    }
}

/// One predict over `dt` and update with the measurement `y` and the gain `k` (see
/// [`Kalman`]).
#[inline(always)]
fn predict_update<T: Real>(k: &[T; 3], s: &mut KalmanState<T>, y: T, dt: T) {
    let xp = s.x + dt * (s.v + (s.a * dt).div_int(2));
    let vp = s.v + s.a * dt;
    let r = y - xp;
    let [k0, k1, k2] = *k;
    s.x = xp + k0 * r;
    s.v = vp + k1 * r;
    s.a = s.a + k2 * r;
}

/// Which estimate a [`KalmanParams`] law reports as its output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KalmanOutput {
    /// The velocity estimate `v` (unit/s).
    #[default]
    Velocity,
    /// The acceleration estimate `a` (unit/s^2).
    Acceleration,
}

/// The tracker of [`Kalman`] as a [`Law`]: validated steady-state gains, the step `h` and the
/// reported estimate. One [`Law::advance`] over `n` steps with `n <= n0` (`n0 = round(dt0 /
/// h)`, the nominal period; `n <= n0 (1 + 2^-10)` in fact) is one predict + update with
/// `dt = n h` (one measurement per sample, as the tracker is meant to run); a longer interval
/// is `k = ceil(n / n0)` sub-steps of `dt = n h / k` each (at most `dt0`), the `j`-th
/// measuring the input as the [`Hold`] presents it at the end of the sub-step (linear:
/// `y_prev + (y_new - y_prev) j / k`; zero-order hold: `y_new`): bit for bit what
/// [`Kalman::update`] does with `dt = n h` (see the [module documentation](self)).
/// `k >` [`MAX_SUBSTEPS`]: the state is re-initialised at `y_new` (a bank's gap rule acts
/// before). One [`Law::step`] is one predict + update with `dt = h`. State: [`KalmanState`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KalmanParams<T: Real> {
    k: [T; 3],
    h: T,
    /// `n0` and `n0 h` (the interval of a nominal sample period, precomputed: the same
    /// product the update would compute).
    n0: u32,
    dt0: T,
    output: KalmanOutput,
}

/// State of the tracker: position, velocity, acceleration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KalmanState<T: Real> {
    /// Position (unit of `y`).
    pub x: T,
    /// Velocity (unit/s).
    pub v: T,
    /// Acceleration (unit/s^2).
    pub a: T,
}

/// Its words ([`crate::words`]): the gain `K`, `h`, `n0`, `n0 h` and the reported estimate.
impl<T: Real + Words> Words for KalmanParams<T> {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        self.k.put_words(out);
        self.h.put_words(out);
        self.n0.put_words(out);
        self.dt0.put_words(out);
        self.output.put_words(out);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        Self {
            k: Words::take_words(r),
            h: T::take_words(r),
            n0: u32::take_words(r),
            dt0: T::take_words(r),
            output: KalmanOutput::take_words(r),
        }
    }
}

impl<T: Real> KalmanParams<T> {
    /// Validates `cfg` and computes the steady-state gain for the nominal period `cfg.dt`;
    /// `h` is the step (s, a whole number of microseconds) that sample intervals are counted
    /// in; `output` the reported estimate.
    pub fn new(cfg: &KalmanConfig, h: f32, output: KalmanOutput) -> Result<Self, ConfigError> {
        let h_us = crate::adapter::step_us(h)?;
        let kf = Kalman::<T>::new(cfg)?;
        let h = T::from_f64(h_us as f64 * 1e-6);
        // Steps per nominal period (as the sample clock counts them), within [1, 1e6].
        let n0 = libm::round(f64::from(cfg.dt) * 1e6 / h_us as f64).clamp(1.0, 1e6) as u32;
        Ok(Self {
            k: kf.k,
            h,
            n0,
            dt0: Self::dt(h, n0),
            output,
        })
    }

    /// The velocity estimate of `s` (unit/s), whatever the configured output.
    #[inline]
    pub fn velocity(&self, s: &KalmanState<T>) -> T {
        s.v
    }

    /// The acceleration estimate of `s` (unit/s^2), whatever the configured output.
    #[inline]
    pub fn acceleration(&self, s: &KalmanState<T>) -> T {
        s.a
    }

    /// `n h` as [`Law::advance`] computes it.
    #[inline(always)]
    fn dt(h: T, n: u32) -> T {
        h * T::from_i32(i32::try_from(n).unwrap_or(i32::MAX))
    }

    #[inline(always)]
    fn update(&self, s: &mut KalmanState<T>, y: T, dt: T) {
        predict_update(&self.k, s, y, dt);
    }

    /// One update over `n` steps `h` (`dt0` when `n = n0`: the same product).
    #[inline(always)]
    fn update_steps(&self, s: &mut KalmanState<T>, y: T, n: u32) {
        let dt = if n == self.n0 {
            self.dt0
        } else {
            Self::dt(self.h, n)
        };
        self.update(s, y, dt);
    }

    /// The number of sub-steps of an interval of `n` steps: the smallest `k >= 1` with
    /// `k n0 >= n - n0 / 1024` (`ceil(n / n0)` but for a 2^-10 slack, the rule of
    /// [`Kalman::update`]).
    #[inline(always)]
    fn substeps(&self, n: u32) -> u64 {
        let (n, n0) = (u64::from(n), u64::from(self.n0));
        (1024 * n).saturating_sub(n0).div_ceil(1024 * n0).max(1)
    }

    /// The `k` sub-steps of an interval of `k > 1` nominal periods (see [`KalmanParams`]).
    #[inline(never)]
    fn advance_long(
        &self,
        s: &mut KalmanState<T>,
        y_prev: T,
        y_new: T,
        n: u32,
        k: u64,
        hold: Hold,
    ) {
        let Ok(k) = u32::try_from(k) else {
            *s = self.init(y_new);
            return;
        };
        if k > MAX_SUBSTEPS {
            *s = self.init(y_new);
            return;
        }
        let dt = Self::dt(self.h, n).div_int(k);
        let d = y_new - y_prev;
        for j in 1..k {
            let y = if hold == Hold::ZeroOrder {
                y_new
            } else {
                y_prev + (d * T::from_i32(j as i32)).div_int(k)
            };
            self.update(s, y, dt);
        }
        self.update(s, y_new, dt);
    }
}

impl<T: Real> Law for KalmanParams<T> {
    type Num = T;
    type State = KalmanState<T>;

    fn init(&self, y0: T) -> KalmanState<T> {
        KalmanState {
            x: y0,
            v: T::ZERO,
            a: T::ZERO,
        }
    }

    fn step(&self, s: &mut KalmanState<T>, y: T) -> T {
        self.update(s, y, self.h);
        self.output(s)
    }

    #[inline]
    fn output(&self, s: &KalmanState<T>) -> T {
        match self.output {
            KalmanOutput::Velocity => s.v,
            KalmanOutput::Acceleration => s.a,
        }
    }

    #[inline]
    fn translate(&self, s: &mut KalmanState<T>, d: T) {
        s.x = s.x + d;
    }

    /// `n <= n0`: one predict + update with `dt = n h` and the measurement `y_new` (`n = 0`:
    /// nothing); `n > n0`: `ceil(n / n0)` sub-steps (see [`KalmanParams`]).
    #[inline]
    fn advance(&self, s: &mut KalmanState<T>, y_prev: T, y_new: T, n: u32, hold: Hold) -> T {
        if n > self.n0 {
            match self.substeps(n) {
                1 => self.update_steps(s, y_new, n),
                k => self.advance_long(s, y_prev, y_new, n, k, hold),
            }
        } else if n > 0 {
            self.update_steps(s, y_new, n);
        }
        self.output(s)
    }
}

/// Steady-state Kalman gain of the constant-acceleration model (see [`Kalman`]): the filter's
/// Riccati recursion
///
/// ```text
/// P- = F P F' + Q,   K = P- H' / (H P- H' + r),   P = (I - K H) P-
/// ```
///
/// iterated from `P = Q` until no gain changes by more than 1e-13 of itself (66 iterations at
/// 100 Hz with the default noise model; at most 2,000), on the six distinct entries of the
/// symmetric covariance with `F`'s structure written out: 21 multiplications and 3 divisions
/// per iteration, and a few hundred bytes of stack.
#[inline(never)]
pub fn steady_state_gain(dt: f64, q: f64, r: f64) -> [f64; 3] {
    let (a, b) = (dt, dt * dt / 2.0);
    let d2 = dt * dt;
    let d3 = d2 * dt;
    let d4 = d3 * dt;
    let d5 = d4 * dt;
    // Q: [q00, q01, q02, q11, q12, q22]
    let qm = [
        q * d5 / 20.0,
        q * d4 / 8.0,
        q * d3 / 6.0,
        q * d3 / 3.0,
        q * d2 / 2.0,
        q * dt,
    ];
    // The updated covariance, same order.
    let mut p = qm;
    let mut k = [0.0; 3];
    for _ in 0..2000 {
        let [p00, p01, p02, p11, p12, p22] = p;
        // predict: F P F' + Q, with the needed entries of F P first
        let m00 = p00 + a * p01 + b * p02;
        let m01 = p01 + a * p11 + b * p12;
        let m02 = p02 + a * p12 + b * p22;
        let m11 = p11 + a * p12;
        let m12 = p12 + a * p22;
        let s00 = m00 + a * m01 + b * m02 + qm[0];
        let s01 = m01 + a * m02 + qm[1];
        let s02 = m02 + qm[2];
        let s11 = m11 + a * m12 + qm[3];
        let s12 = m12 + qm[4];
        let s22 = p22 + qm[5];
        // update with H = [1, 0, 0]
        let innovation = s00 + r;
        let kn = [s00 / innovation, s01 / innovation, s02 / innovation];
        p = [
            s00 - kn[0] * s00,
            s01 - kn[0] * s01,
            s02 - kn[0] * s02,
            s11 - kn[1] * s01,
            s12 - kn[1] * s02,
            s22 - kn[2] * s02,
        ];
        let settled = kn
            .iter()
            .zip(k.iter())
            .all(|(n, o)| libm::fabs(n - o) < 1e-13 * (libm::fabs(*n) + 1e-300));
        k = kn;
        if settled {
            break;
        }
    }
    k
}

/// Noise model of the Kalman tracker in a bank half
/// ([`BankGains::kf`](crate::BankGains::kf)): with the nominal sample period as `dt` it is
/// the [`KalmanConfig`] of the half's tracker.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct KalmanNoise {
    /// White-jerk power spectral density `q`, deg^2/s^5 (see [`KalmanConfig::q`]).
    pub q: f32,
    /// Angle measurement variance `r`, deg^2.
    pub r: f32,
}

impl Gains for KalmanNoise {
    /// `q` and `r` geometrically.
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        KalmanNoise {
            q: geometric(self.q, other.q, w),
            r: geometric(self.r, other.r, w),
        }
    }

    /// The tracker ([`LawVisitor::tracker`]: it runs at the nominal sample period, which the
    /// visitor knows; the noise is checked when the tracker is built).
    fn build<V: LawVisitor>(&self, _h: f32, to: V) -> Result<V::Output, ConfigError> {
        Ok(to.tracker(*self))
    }
}

crate::family::family! {
    /// The Kalman tracker family of the paper bank: a tracker with the velocity half's noise
    /// reports the velocity, one with the acceleration half's noise the acceleration (not a
    /// series); gains [`BankGains::kf`](crate::BankGains::kf).
    KfFamily {
        gains: KalmanNoise = BankGains::kf,
        name: "kf",
        label: "KF",
        channels: KfV, KfA,
        scheduling: Smooth,
    }
}
