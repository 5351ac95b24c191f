//! Steady-state constant-acceleration Kalman tracker (alpha-beta-gamma filter): the reference
//! an engineer would otherwise use. Not from the paper.

use crate::error::positive;
use crate::family::{coordinate, geometric, search_range, Gains, Scorer, SearchPoint};
use crate::law::Law;
use crate::{ConfigError, Hold, Real};

/// Parameters of the tracker in physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct KalmanConfig {
    /// Nominal sample period `dt0`, s (NAV440 at 100 Hz: 0.01). The steady-state gains are for
    /// this period; the prediction uses each sample's actual `dt`.
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
/// equation (iterated once at construction in `f64`). Per sample (`dt` = actual interval):
///
/// ```text
/// predict: x- = x + v dt + a dt^2/2,  v- = v + a dt,  a- = a
/// update:  r = y - x-;  x = x- + K0 r,  v = v- + K1 r,  a = a- + K2 r
/// ```
///
/// Outputs `v` (deg/s) and `a` (deg/s^2). RAM: 6 words of `T`.
#[derive(Clone, Copy, Debug)]
pub struct Kalman<T: Real> {
    k: [T; 3],
    x: T,
    v: T,
    a: T,
}

impl<T: Real> Kalman<T> {
    /// Builds the tracker; the Riccati iteration runs here (at most 2000 iterations of 3x3
    /// `f64` algebra). Errors: non-positive or non-finite `dt`, `q`, `r`.
    pub fn new(cfg: &KalmanConfig) -> Result<Self, ConfigError> {
        let dt = positive("dt", f64::from(cfg.dt))?;
        let q = positive("q", f64::from(cfg.q))?;
        let r = positive("r", f64::from(cfg.r))?;
        let k = steady_state_gain(dt, q, r);
        Ok(Self {
            k: [T::from_f64(k[0]), T::from_f64(k[1]), T::from_f64(k[2])],
            x: T::ZERO,
            v: T::ZERO,
            a: T::ZERO,
        })
    }

    /// The steady-state gain `[K0, K1 (1/s), K2 (1/s^2)]`.
    pub fn gain(&self) -> [T; 3] {
        self.k
    }

    /// Starts at position `y0` with zero velocity and acceleration.
    pub fn reset(&mut self, y0: T) {
        self.x = y0;
        self.v = T::ZERO;
        self.a = T::ZERO;
    }

    /// One predict + update with the measurement `y` (input unit) taken `dt` seconds (as `T`)
    /// after the previous one.
    ///
    /// Convention: the measurement first, then the *interval* in seconds; the first
    /// measurement goes to [`Self::reset`] instead. The banks and [`crate::SampleAdapter`]
    /// take the other order and an absolute time: `update(t_us, y)`, the sample's time stamp
    /// in integer microseconds first, and compute the interval themselves (as
    /// [`KalmanParams`], the bank's tracker, does: `dt = round(interval / h) h`).
    #[inline]
    pub fn update(&mut self, y: T, dt: T) {
        let xp = self.x + dt * (self.v + (self.a * dt).div_int(2));
        let vp = self.v + self.a * dt;
        let r = y - xp;
        let [k0, k1, k2] = self.k;
        self.x = xp + k0 * r;
        self.v = vp + k1 * r;
        self.a = self.a + k2 * r;
    }

    /// Adds `d` to the position estimate (moves the tracker to a shifted input frame).
    pub fn translate(&mut self, d: T) {
        self.x = self.x + d;
    }

    /// Position estimate (unit of `y`).
    pub fn position(&self) -> T {
        self.x
    }

    /// Velocity estimate (unit/s).
    pub fn velocity(&self) -> T {
        self.v
    }

    /// Acceleration estimate (unit/s^2).
    pub fn acceleration(&self) -> T {
        self.a
    }
}

/// Which estimate a [`KalmanParams`] law reports as its output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum KalmanOutput {
    /// The velocity estimate `v` (unit/s).
    #[default]
    Velocity,
    /// The acceleration estimate `a` (unit/s^2).
    Acceleration,
}

/// The tracker of [`Kalman`] as a [`Law`]: validated steady-state gains, the step `h` and the
/// reported estimate. One [`Law::advance`] over `n` steps is one predict + update with
/// `dt = n h` (one measurement per sample, as the tracker is meant to run); one
/// [`Law::step`] is the same with `dt = h`. State: [`KalmanState`].
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

impl<T: Real> KalmanParams<T> {
    /// Validates `cfg` and computes the steady-state gain for the nominal period `cfg.dt`;
    /// `h` is the step (s, a whole number of microseconds) that sample intervals are counted
    /// in; `output` the reported estimate.
    pub fn new(cfg: &KalmanConfig, h: f32, output: KalmanOutput) -> Result<Self, ConfigError> {
        let h_us = crate::adapter::step_us(h)?;
        let kf = Kalman::<T>::new(cfg)?;
        let h = T::from_f64(h_us as f64 * 1e-6);
        // Steps per nominal period (as the sample clock counts them); 0 if out of range.
        let n0 = libm::round(f64::from(cfg.dt) * 1e6 / h_us as f64);
        let n0 = if (1.0..=1e6).contains(&n0) {
            n0 as u32
        } else {
            0
        };
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
        let xp = s.x + dt * (s.v + (s.a * dt).div_int(2));
        let vp = s.v + s.a * dt;
        let r = y - xp;
        let [k0, k1, k2] = self.k;
        s.x = xp + k0 * r;
        s.v = vp + k1 * r;
        s.a = s.a + k2 * r;
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

    /// One predict + update with `dt = n h` and the measurement `y_new` (`n = 0`: nothing).
    #[inline]
    fn advance(&self, s: &mut KalmanState<T>, _y_prev: T, y_new: T, n: u32, _hold: Hold) -> T {
        if n > 0 {
            let dt = if n == self.n0 {
                self.dt0
            } else {
                Self::dt(self.h, n)
            };
            self.update(s, y_new, dt);
        }
        self.output(s)
    }
}

type M3 = [[f64; 3]; 3];

fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn transpose(a: &M3) -> M3 {
    let mut t = [[0.0; 3]; 3];
    for (i, row) in t.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[j][i];
        }
    }
    t
}

/// Steady-state Kalman gain of the constant-acceleration model (see [`Kalman`]).
pub fn steady_state_gain(dt: f64, q: f64, r: f64) -> [f64; 3] {
    let f: M3 = [[1.0, dt, dt * dt / 2.0], [0.0, 1.0, dt], [0.0, 0.0, 1.0]];
    let d2 = dt * dt;
    let d3 = d2 * dt;
    let d4 = d3 * dt;
    let d5 = d4 * dt;
    let qm: M3 = [
        [q * d5 / 20.0, q * d4 / 8.0, q * d3 / 6.0],
        [q * d4 / 8.0, q * d3 / 3.0, q * d2 / 2.0],
        [q * d3 / 6.0, q * d2 / 2.0, q * dt],
    ];
    let ft = transpose(&f);
    let mut p = qm;
    let mut k = [0.0; 3];
    for _ in 0..2000 {
        // predict
        let mut pp = mat_mul(&mat_mul(&f, &p), &ft);
        for (row, qr) in pp.iter_mut().zip(qm.iter()) {
            for (x, qv) in row.iter_mut().zip(qr.iter()) {
                *x += qv;
            }
        }
        // update
        let s = pp[0][0] + r;
        let kn = [pp[0][0] / s, pp[1][0] / s, pp[2][0] / s];
        let mut pn = pp;
        for i in 0..3 {
            for j in 0..3 {
                pn[i][j] = pp[i][j] - kn[i] * pp[0][j];
            }
        }
        let change = (0..3)
            .map(|i| libm::fabs(kn[i] - k[i]) / (libm::fabs(kn[i]) + 1e-300))
            .fold(0.0, f64::max);
        k = kn;
        p = pn;
        if change < 1e-13 {
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

/// On one line: `KalmanNoise { q: .., r: .. }`.
impl crate::RustLiteral for KalmanNoise {
    const RUST_TYPES: &'static [&'static str] = &["KalmanNoise"];

    fn write_rust(&self, w: &mut dyn core::fmt::Write, _: crate::Indent<'_>) -> core::fmt::Result {
        write!(w, "KalmanNoise {{ q: {:?}, r: {:?} }}", self.q, self.r)
    }
}

impl Gains for KalmanNoise {
    /// `q` and `r` geometrically.
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        KalmanNoise {
            q: geometric(self.q, other.q, w),
            r: geometric(self.r, other.r, w),
        }
    }

    /// `(q)`: only `q / r` matters for the steady-state gain, so `r` is kept.
    fn search_point(&self) -> SearchPoint {
        SearchPoint::from_array([f64::from(self.q)])
    }

    fn with_search_point(&self, x: &[f64]) -> Self {
        KalmanNoise {
            q: coordinate(x, 0, self.q),
            r: self.r,
        }
    }

    /// `q` in `[1, 1e12]` deg^2/s^5.
    fn search_box(_h_s: f64) -> (SearchPoint, SearchPoint) {
        search_range([1.0], [1e12])
    }

    /// The tracker (it needs the nominal sample period, which the scorer knows: it checks
    /// the noise when it builds the tracker).
    fn score<S: Scorer>(&self, _h: f32, scorer: &S) -> Result<S::Score, ConfigError> {
        Ok(scorer.tracker(*self))
    }

    fn describe(&self, w: &mut dyn core::fmt::Write) -> core::fmt::Result {
        write!(w, "q={} r={}", self.q, self.r)
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
