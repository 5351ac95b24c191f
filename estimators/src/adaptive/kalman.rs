//! [`AdaptiveKalman`]: the Kalman tracker whose noise model follows the measured noise and
//! the motion's jerk.

use super::{JerkEstimator, NoiseEstimator};
use crate::{ConfigError, Kalman, KalmanConfig, Real};

/// How an [`AdaptiveKalman`] follows the noise and the motion.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdaptiveKalmanConfig {
    /// Nominal sample period, s (finite, > 0).
    pub dt: f32,
    /// `kappa`, s: the process noise is `q = kappa J` (deg^2/s^5), `J` the measured jerk
    /// power ((deg/s^3)^2). Default [`Self::KAPPA_FIG5_S`].
    pub kappa_s: f32,
    /// Time constant of the noise estimate, s ([`NoiseEstimator`]; default 0.5).
    pub noise_tau_s: f32,
    /// Time constant of the jerk estimate, s ([`JerkEstimator`]; default
    /// [`JerkEstimator::DEFAULT_TAU_S`]).
    pub jerk_tau_s: f32,
    /// The noise model before the first estimates: `q` (deg^2/s^5) and `r` (deg^2), as
    /// [`KalmanConfig`] (defaults: the paper's `q` = 1e6, `r` = 0.01).
    pub initial_q: f32,
    /// See `initial_q`.
    pub initial_r: f32,
    /// The noise model is reconsidered every this many samples (default 20: 0.2 s at
    /// 100 Hz) ...
    pub retune_every: u32,
    /// ... and changed only when `q / r` moved by more than this factor either way from the
    /// current one (default 1.5).
    pub retune_ratio: f32,
}

impl AdaptiveKalmanConfig {
    /// `kappa` from the Kalman tuned on the synthetic fig5 motion (the paper's Fig. 5) at
    /// 0.1 deg^2: `q / r` = 4.217e6 /s^5, times 0.1 deg^2, over fig5's jerk power of
    /// 3.68e6 (deg/s^3)^2 (`host-tests` `motion_family`, docs/MOTION-FAMILY.md).
    pub const KAPPA_FIG5_S: f32 = 0.1146;

    /// The defaults (see the fields) at the nominal sample period `dt` (s).
    pub const fn at(dt: f32) -> Self {
        Self {
            dt,
            kappa_s: Self::KAPPA_FIG5_S,
            noise_tau_s: 0.5,
            jerk_tau_s: JerkEstimator::DEFAULT_TAU_S,
            initial_q: 1e6,
            initial_r: 0.01,
            retune_every: 20,
            retune_ratio: 1.5,
        }
    }
}

/// The smallest and largest `q dt^5 / r` the noise model takes (the range over which the
/// tracker's sub-stepped loop is documented stable, [`crate::kalman`]).
pub(super) const LAMBDA_RANGE: (f32, f32) = (9.094_947e-13, 1.073_741_8e9); // 2^-40, 2^30

/// The least noise variance taken as `r`, deg^2: the quantisation of a NAV440 angle
/// (one LSB of 360/2^16 deg, `LSB^2 / 12` = 2.5e-6) is the noise of an angle that has none.
pub(super) const R_FLOOR: f32 = 2.5e-6;

/// The constant-acceleration Kalman tracker ([`Kalman`]) whose noise model follows what it
/// measures: `r` the angle's noise variance ([`NoiseEstimator`], from the angle's third
/// differences), `q = kappa J` with `J` the motion's jerk power ([`JerkEstimator`], from the
/// rate a gyro measures about the axis). The steady-state gain depends on `q / r` alone, and
/// tuned on one motion the best `q` follows the motion's jerk: one `kappa` tuned on the
/// paper's motion holds within 1.3x of the Kalman tuned on each of five motions from a slow
/// spin to violent strokes, at every noise level (docs/MOTION-FAMILY.md, "One index for
/// every motion", where this tracker runs them online).
///
/// At most every [`AdaptiveKalmanConfig::retune_every`] samples, when `q / r` moved by more
/// than [`AdaptiveKalmanConfig::retune_ratio`], the gain is recomputed ([`Kalman::set_noise`]:
/// the Riccati recursion in `f64`, about 0.5 million instructions on a Cortex-M4F) and the
/// state kept (bumpless). `q dt^5 / r` is held within `[2^-40, 2^30]`. Without a rate
/// (`None`) the jerk estimate stays where it is (`q` is the initial one until a rate comes).
///
/// The angle is continuous (unwrapped by the caller), in deg; outputs deg/s and deg/s^2.
#[derive(Clone, Copy, Debug)]
pub struct AdaptiveKalman<T: Real> {
    kf: Kalman<T>,
    noise: NoiseEstimator,
    jerk: JerkEstimator,
    cfg: AdaptiveKalmanConfig,
    /// The current `q` and `r`.
    q: f32,
    r: f32,
    /// The previous sample's time, us (`None` before the first).
    t_prev: Option<u64>,
    since: u32,
    retunes: u32,
}

impl<T: Real> AdaptiveKalman<T> {
    /// A tracker with `cfg` (its nominal period, time constants and initial noise model
    /// checked).
    pub fn new(cfg: &AdaptiveKalmanConfig) -> Result<Self, ConfigError> {
        if !(cfg.kappa_s.is_finite() && cfg.retune_ratio.is_finite()) {
            return Err(ConfigError::NotFinite("kappa_s"));
        }
        if cfg.kappa_s <= 0.0 || cfg.retune_ratio < 1.0 {
            return Err(ConfigError::NotPositive("kappa_s"));
        }
        Ok(Self {
            kf: Kalman::new(&KalmanConfig {
                dt: cfg.dt,
                q: cfg.initial_q,
                r: cfg.initial_r,
            })?,
            noise: NoiseEstimator::new(cfg.noise_tau_s, cfg.dt)?,
            jerk: JerkEstimator::new(cfg.jerk_tau_s, cfg.dt)?,
            cfg: *cfg,
            q: cfg.initial_q,
            r: cfg.initial_r,
            t_prev: None,
            since: 0,
            retunes: 0,
        })
    }

    /// Takes the angle `angle_deg` (deg, continuous) measured at `t_us` (µs, increasing) and
    /// the rate about the axis at that time (deg/s, `None` if not measured). A time not later
    /// than the previous one, or a non-finite angle, is ignored: nothing changes.
    pub fn update(&mut self, t_us: u64, angle_deg: f32, rate_deg_s: Option<f32>) {
        if !angle_deg.is_finite() || self.t_prev.is_some_and(|tp| t_us <= tp) {
            return;
        }
        if let Some(r) = rate_deg_s {
            self.jerk.update(t_us, r);
        }
        self.noise.update(t_us, angle_deg);
        let y = T::from_f32(angle_deg);
        match self.t_prev {
            None => self.kf.reset(y),
            Some(tp) => {
                let dt = T::from_f64((t_us - tp) as f64 * 1e-6);
                self.kf.update(y, dt);
            }
        }
        self.t_prev = Some(t_us);
        self.since = self.since.saturating_add(1);
        if self.since >= self.cfg.retune_every {
            self.since = 0;
            self.follow();
        }
    }

    /// Moves the noise model to the estimates when `q / r` moved by more than the ratio.
    fn follow(&mut self) {
        let r = self.noise.variance().map_or(self.r, |v| v.max(R_FLOOR));
        let q = self.jerk.power().map_or(self.q, |j| self.cfg.kappa_s * j);
        let dt = self.cfg.dt;
        let dt5 = dt * dt * dt * dt * dt;
        let lambda = q / r * dt5;
        let q = if lambda < LAMBDA_RANGE.0 {
            LAMBDA_RANGE.0 * r / dt5
        } else if lambda > LAMBDA_RANGE.1 {
            LAMBDA_RANGE.1 * r / dt5
        } else {
            q
        };
        let (now, want) = (self.q / self.r, q / r);
        let ratio = self.cfg.retune_ratio;
        if (want > now * ratio || want * ratio < now) && self.kf.set_noise(q, r).is_ok() {
            self.q = q;
            self.r = r;
            self.retunes = self.retunes.saturating_add(1);
        }
    }

    /// Velocity estimate, deg/s.
    pub fn velocity(&self) -> T {
        self.kf.velocity()
    }

    /// Acceleration estimate, deg/s^2.
    pub fn acceleration(&self) -> T {
        self.kf.acceleration()
    }

    /// The current noise model `(q, r)`: deg^2/s^5, deg^2.
    pub fn noise_model(&self) -> (f32, f32) {
        (self.q, self.r)
    }

    /// How many times the gain changed.
    pub fn retune_count(&self) -> u32 {
        self.retunes
    }

    /// The noise estimate, deg^2, and the jerk estimate, (deg/s^3)^2 (`None` before the
    /// first of each).
    pub fn estimates(&self) -> (Option<f32>, Option<f32>) {
        (self.noise.variance(), self.jerk.power())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine angle `A sin(w t)` with no noise: `r` goes to what the noise estimate reads
    /// (the sine's own third differences, 1e-5 deg^2), `q` to the jerk's, and the velocity
    /// follows `A w cos(w t)` closely (a light filter).
    #[test]
    fn follows_a_clean_sine_and_its_jerk() {
        follows_a_clean_sine::<f32>();
        follows_a_clean_sine::<crate::Fx>();
    }

    fn follows_a_clean_sine<T: Real>() {
        let cfg = AdaptiveKalmanConfig::at(0.01);
        let mut k = AdaptiveKalman::<T>::new(&cfg).unwrap();
        let (a, w) = (90.0f64, 2.0 * core::f64::consts::PI);
        let mut worst = 0.0f64;
        for n in 0..3000u64 {
            let t = n as f64 * 0.01;
            let angle = a * (w * t).sin();
            let rate = a * w * (w * t).cos();
            k.update(n * 10_000, angle as f32, Some(rate as f32));
            if t > 10.0 {
                worst = worst.max((k.velocity().to_f64() - rate).abs());
            }
        }
        let (v, j) = k.estimates();
        // The sine's jerk power: (A w^3)^2 / 2 times the lagged difference's response at
        // 50 ms, (sin(w L/2) / (w L/2))^4 = 0.984.
        let expected = (a * w.powi(3)).powi(2) / 2.0 * 0.9837;
        let j = f64::from(j.unwrap());
        assert!((j / expected - 1.0).abs() < 0.02, "{j} vs {expected}");
        // The noise estimate reads the sine's own third differences: (A w^3 dt^3)^2 / 2 / 20.
        let motion = (a * w.powi(3) * 1e-6).powi(2) / 40.0;
        let v = f64::from(v.unwrap());
        assert!((v / motion - 1.0).abs() < 0.1, "{v} vs {motion}");
        let (q, r) = k.noise_model();
        assert!(r < 2e-5 && q > 0.0, "{q} {r}");
        assert!(k.retune_count() >= 1);
        // 1 % of the rate's amplitude (565 deg/s).
        assert!(worst < 5.7, "{worst}");
    }

    /// Without rates the jerk stays unmeasured and `q` stays the initial one; `r` follows
    /// the noise.
    #[test]
    fn without_rates_q_stays() {
        let cfg = AdaptiveKalmanConfig::at(0.01);
        let mut k = AdaptiveKalman::<f32>::new(&cfg).unwrap();
        let mut x = 1u64;
        for n in 0..2000u64 {
            // A uniform noise of variance 0.12 (+-0.6 deg) from a small LCG.
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (x >> 40) as f32 / (1u64 << 24) as f32 - 0.5;
            k.update(n * 10_000, 1.2 * u, None);
        }
        let (q, r) = k.noise_model();
        assert_eq!(q, 1e6);
        assert!((r / 0.12 - 1.0).abs() < 0.35, "{r}");
        assert_eq!(k.estimates().1, None);
    }

    /// A repeated or earlier time stamp and a NaN angle change nothing.
    #[test]
    fn a_sample_out_of_order_changes_nothing() {
        let mut k = AdaptiveKalman::<f32>::new(&AdaptiveKalmanConfig::at(0.01)).unwrap();
        for n in 0..100u64 {
            k.update(n * 10_000, n as f32 * 0.5, Some(50.0));
        }
        let mut twin = k;
        let before = (
            k.velocity(),
            k.acceleration(),
            k.estimates(),
            k.noise_model(),
        );
        k.update(99 * 10_000, 1000.0, Some(1e6));
        k.update(50 * 10_000, -1000.0, Some(-1e6));
        k.update(100 * 10_000, f32::NAN, Some(1e6));
        let after = (
            k.velocity(),
            k.acceleration(),
            k.estimates(),
            k.noise_model(),
        );
        assert_eq!(before, after);
        // The next good sample goes on as if those had not come.
        k.update(100 * 10_000, 50.0, Some(50.0));
        twin.update(100 * 10_000, 50.0, Some(50.0));
        assert_eq!(k.velocity(), twin.velocity());
        assert_ne!(k.velocity(), before.0);
    }

    #[test]
    fn refuses_bad_configuration() {
        for cfg in [
            AdaptiveKalmanConfig {
                kappa_s: 0.0,
                ..AdaptiveKalmanConfig::at(0.01)
            },
            AdaptiveKalmanConfig {
                retune_ratio: f32::NAN,
                ..AdaptiveKalmanConfig::at(0.01)
            },
            AdaptiveKalmanConfig::at(0.0),
        ] {
            assert!(AdaptiveKalman::<f32>::new(&cfg).is_err(), "{cfg:?}");
        }
    }
}
