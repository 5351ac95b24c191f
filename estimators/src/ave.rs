//! Adaptive velocity estimator, AVE (paper eq. 4).

use crate::error::{non_negative, positive};
use crate::{ConfigError, Estimator, Real};

/// What happens to the switching gain `deltahat`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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
pub struct AveConfig {
    /// Position feedback gain `k`, 1/s (paper: 500). `h * k < 1`.
    pub k: f32,
    /// Velocity adaptation gain `gamma1`, 1/s^2 (paper: 20000). `h^2 * gamma1 < 1`.
    pub gamma1: f32,
    /// `deltahat` law.
    pub delta: DeltaMode,
}

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
/// RAM: 4 state/coefficient words of `T` plus the mode (see [`crate::ram`]).
#[derive(Clone, Copy, Debug)]
pub struct Ave<T: Real> {
    hk: T,
    hg: T,
    h: T,
    hsigma: T,
    dmax: T,
    mode: u8,
    xhat: T,
    theta: T,
    delta: T,
}

const MODE_PAPER: u8 = 0;
const MODE_BOUNDED: u8 = 1;
const MODE_LEAKY: u8 = 2;

impl<T: Real> Ave<T> {
    /// Builds the estimator for step `h` (s). Errors: non-finite or non-positive `k`,
    /// `gamma1`, `h`; `h * k >= 1` or `h^2 * gamma1 >= 1` (forward-Euler stability); negative
    /// bound or leakage; `h * sigma >= 1`.
    pub fn new(cfg: &AveConfig, h: f32) -> Result<Self, ConfigError> {
        let h = positive("h", f64::from(h))?;
        let k = positive("k", f64::from(cfg.k))?;
        let g = positive("gamma1", f64::from(cfg.gamma1))?;
        if h * k >= 1.0 {
            return Err(ConfigError::StepTooLarge("k"));
        }
        if h * h * g >= 1.0 {
            return Err(ConfigError::StepTooLarge("gamma1"));
        }
        let (mode, dmax, sigma) = match cfg.delta {
            DeltaMode::Paper => (MODE_PAPER, 0.0, 0.0),
            DeltaMode::Bounded { max } => (MODE_BOUNDED, non_negative("max", f64::from(max))?, 0.0),
            DeltaMode::Leaky { sigma } => {
                let s = non_negative("sigma", f64::from(sigma))?;
                if h * s >= 1.0 {
                    return Err(ConfigError::StepTooLarge("sigma"));
                }
                (MODE_LEAKY, 0.0, s)
            }
        };
        Ok(Self {
            hk: T::from_f64(h * k),
            hg: T::from_f64(h * g),
            h: T::from_f64(h),
            hsigma: T::from_f64(h * sigma),
            dmax: T::from_f64(dmax),
            mode,
            xhat: T::ZERO,
            theta: T::ZERO,
            delta: T::ZERO,
        })
    }

    /// Position estimate `xhat` (unit of `y`).
    pub fn xhat(&self) -> T {
        self.xhat
    }

    /// Switching gain `deltahat` (unit of `y` per second).
    pub fn deltahat(&self) -> T {
        self.delta
    }
}

impl<T: Real> Estimator<T> for Ave<T> {
    fn reset(&mut self, y0: T) {
        self.xhat = y0;
        self.theta = T::ZERO;
        self.delta = T::ZERO;
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
    #[inline]
    fn step(&mut self, y: T) -> T {
        let e = self.xhat - y;
        let sw = if e > T::ZERO {
            self.delta
        } else if e < T::ZERO {
            -self.delta
        } else {
            T::ZERO
        };
        self.xhat = self.xhat + (self.h * (self.theta - sw) - self.hk * e);
        self.theta = self.theta - self.hg * e;
        let inc = self.h * e.abs();
        self.delta = match self.mode {
            MODE_PAPER => self.delta + inc,
            MODE_BOUNDED => (self.delta + inc).min(self.dmax),
            _ => self.delta + inc - self.hsigma * self.delta,
        };
        self.theta
    }

    fn output(&self) -> T {
        self.theta
    }

    fn translate(&mut self, d: T) {
        self.xhat = self.xhat + d;
    }
}
