//! [`JerkEstimator`]: the online estimate of a motion's jerk power (and acceleration power),
//! from its rate.

use crate::ConfigError;

/// Online estimate of a motion's jerk power, (deg/s^3)^2: how hard it moves, from the rate a
/// sensor measures about the axis (a gyro's; the NAV440's body rates or the Euler rates built
/// from them). The Kalman's best process noise follows it: tuned on one motion as `q = kappa
/// J`, it holds on motions of other jerk (docs/MOTION-FAMILY.md, "One index for every
/// motion").
///
/// Method: the rate's second difference at a lag of `L` samples,
/// `j = (r[k] - 2 r[k-L] + r[k-2L]) / (L dt)^2`, where `L dt` is the lag closest to
/// [`JerkEstimator::LAG_S`] (50 ms: `L` = 5 at 100 Hz, 1 at 20 Hz and below, at most
/// [`JerkEstimator::MAX_LAG`]). At that lag a rate quantised to 1260/2^16 deg/s (the NAV440's)
/// adds under 6 deg/s^3 of noise at 100 Hz, and a gyro's noise of 0.1 deg/s about
/// 100 deg/s^3, against a hand's motion of 10^3 to 10^5. The estimate is the exponentially
/// weighted mean of `j^2` with time constant `tau_s` (the first `tau / dt` terms averaged with
/// weight `1/k`, so that it starts at once). Built [`Self::with_acceleration`], it also
/// estimates over the same samples the acceleration power, (deg/s^2)^2: the exponentially
/// weighted mean of `a^2` for the central difference `a = (r[k] - r[k-2L]) / (2 L dt)`, with
/// time constant `tau_s x` [`Self::ACCELERATION_TAU`] ([`Self::acceleration_power`]; the AD's
/// best time constant follows it). A sample interval that differs from the previous
/// one by more than a quarter (a lost packet, a gap, a new epoch) restarts the differences
/// (the estimate is kept), as [`NoiseEstimator`](crate::NoiseEstimator) does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JerkEstimator {
    /// Weight of a new term once started, `dt / tau`.
    alpha: f32,
    /// The same for the acceleration power, `dt / (tau x ACCELERATION_TAU)`; `None`: not
    /// estimated.
    accel_alpha: Option<f32>,
    /// The lag, samples (1 to [`Self::MAX_LAG`]).
    lag: usize,
    /// `1 / (lag dt)^2` at the nominal period, 1/s^2.
    scale: f32,
    /// `1 / (2 lag dt)` at the nominal period, 1/s.
    accel_scale: f32,
    /// Estimate, (deg/s^3)^2.
    power: f32,
    /// Acceleration power estimate, (deg/s^2)^2.
    accel_power: f32,
    /// Terms averaged so far (saturates).
    count: u32,
    /// The last rates, deg/s, newest at `head`; `filled` of them valid (in a row, at a steady
    /// interval).
    rates: [f32; 2 * Self::MAX_LAG + 1],
    head: usize,
    filled: usize,
    /// Previous sample time, us, and interval, us.
    t_prev: Option<u64>,
    dt_prev: u64,
}

impl JerkEstimator {
    /// The acceleration power's time constant, as a fraction of the jerk power's (0.5 s for
    /// the default 5 s): the AD's best time constant follows the acceleration of the moment,
    /// which a unit that starts to move after a rest must reach within a fraction of a
    /// second (docs/MOTION-FAMILY.md, "A schedule that follows the motion").
    pub const ACCELERATION_TAU: f32 = 0.1;

    /// The lag the second difference aims at, s.
    pub const LAG_S: f32 = 0.05;

    /// The longest lag, samples (50 ms at 160 Hz).
    pub const MAX_LAG: usize = 8;

    /// The default time constant, s: long enough to hold a hand's typical intensity through
    /// the pauses between its strokes.
    pub const DEFAULT_TAU_S: f32 = 5.0;

    /// An estimator with time constant `tau_s` (s) for samples every `sample_period_s` (s):
    /// both finite and positive.
    pub fn new(tau_s: f32, sample_period_s: f32) -> Result<Self, ConfigError> {
        if !(tau_s.is_finite() && sample_period_s.is_finite()) {
            return Err(ConfigError::NotFinite("jerk_tau_s"));
        }
        if tau_s <= 0.0 || sample_period_s <= 0.0 {
            return Err(ConfigError::NotPositive("jerk_tau_s"));
        }
        let lag = (Self::LAG_S / sample_period_s + 0.5) as usize;
        let lag = lag.clamp(1, Self::MAX_LAG);
        let span = lag as f32 * sample_period_s;
        Ok(JerkEstimator {
            alpha: (sample_period_s / tau_s).min(1.0),
            accel_alpha: None,
            lag,
            scale: 1.0 / (span * span),
            accel_scale: 0.5 / span,
            power: 0.0,
            accel_power: 0.0,
            count: 0,
            rates: [0.0; 2 * Self::MAX_LAG + 1],
            head: 0,
            filled: 0,
            t_prev: None,
            dt_prev: 0,
        })
    }

    /// This estimator, estimating the acceleration power too (time constant `tau_s x`
    /// [`Self::ACCELERATION_TAU`]; a bank whose schedule records no acceleration power, and
    /// the product banks, leave it out and save its arithmetic per sample).
    pub fn with_acceleration(self) -> Self {
        // `alpha` is `dt / tau` capped at 1.
        let dt_over_tau = self.alpha;
        Self {
            accel_alpha: Some((dt_over_tau / Self::ACCELERATION_TAU).min(1.0)),
            ..self
        }
    }

    /// The acceleration power estimate, (deg/s^2)^2 (`None` before the first difference, or
    /// when not estimated: [`Self::with_acceleration`]).
    pub fn acceleration_power(&self) -> Option<f32> {
        (self.count > 0 && self.accel_alpha.is_some()).then_some(self.accel_power)
    }

    /// `true` once the estimate has averaged a time constant's worth of terms (it then holds
    /// the motion's intensity, not only its start's).
    pub fn settled(&self) -> bool {
        self.count as f32 * self.alpha >= 1.0
    }

    /// The lag of the second difference, samples.
    pub fn lag(&self) -> usize {
        self.lag
    }

    /// The estimate, (deg/s^3)^2 (`None` before the first second difference).
    pub fn power(&self) -> Option<f32> {
        (self.count > 0).then_some(self.power)
    }

    /// Takes the rate `rate_deg_s` (deg/s) measured at `t_us` (µs, increasing). A rate that
    /// is not finite is skipped and restarts the differences.
    pub fn update(&mut self, t_us: u64, rate_deg_s: f32) {
        if !rate_deg_s.is_finite() {
            self.restart();
            return;
        }
        if let Some(tp) = self.t_prev.replace(t_us) {
            let dt = t_us.saturating_sub(tp);
            if !super::steady_interval(dt, self.dt_prev) {
                self.filled = 0;
            }
            self.dt_prev = dt;
        }
        let n = self.rates.len();
        self.head = (self.head + 1) % n;
        self.rates[self.head] = rate_deg_s;
        self.filled = (self.filled + 1).min(n);
        if self.filled > 2 * self.lag {
            let at = |back: usize| self.rates[(self.head + n - back) % n];
            let j = (at(0) - 2.0 * at(self.lag) + at(2 * self.lag)) * self.scale;
            if let Some(alpha) = self.accel_alpha {
                let a = (at(0) - at(2 * self.lag)) * self.accel_scale;
                let mut count = self.count;
                super::mean_step(&mut self.accel_power, &mut count, alpha, a * a);
            }
            super::mean_step(&mut self.power, &mut self.count, self.alpha, j * j);
        }
    }

    /// Forgets the samples (not the estimate): the next sample starts new differences.
    pub fn restart(&mut self) {
        self.t_prev = None;
        self.dt_prev = 0;
        self.filled = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rate `A sin(w t)` has the lagged second difference
    /// `-4 sin^2(w L dt / 2) A sin(w (t - L dt))`, whose mean square over whole periods is
    /// `(4 sin^2(w L dt / 2) / (L dt)^2)^2 A^2 / 2`.
    #[test]
    fn a_sine_reads_its_closed_form() {
        let (a, f_hz, dt) = (300.0f64, 2.0f64, 0.01f64);
        let mut e = JerkEstimator::new(1000.0, dt as f32)
            .unwrap()
            .with_acceleration();
        assert_eq!(e.lag(), 5);
        let w = 2.0 * core::f64::consts::PI * f_hz;
        // 20 s: 40 periods, the first 2L samples feed no term.
        for k in 0..2000 {
            let t = k as f64 * dt;
            e.update((t * 1e6) as u64, (a * (w * t).sin()) as f32);
        }
        let l = 5.0 * dt;
        let s = (w * l / 2.0).sin();
        let expected = (4.0 * s * s / (l * l)).powi(2) * a * a / 2.0;
        let got = f64::from(e.power().unwrap());
        assert!((got / expected - 1.0).abs() < 0.01, "{got} vs {expected}");
        // The central difference over 2L of `A sin(w t)` is `A sin(w L dt) / (L dt)
        // cos(w (t - L dt))`: mean square `(A sin(w L dt) / (L dt))^2 / 2`.
        let expected = (a * (w * l).sin() / l).powi(2) / 2.0;
        let got = f64::from(e.acceleration_power().unwrap());
        assert!((got / expected - 1.0).abs() < 0.01, "{got} vs {expected}");
    }

    /// A ramp of 2 deg/s per 10 ms sample is an acceleration of 200 deg/s^2 and no jerk; an
    /// estimator built without [`JerkEstimator::with_acceleration`] reads no acceleration.
    #[test]
    fn a_constant_rate_and_a_ramp_read_zero() {
        let mut e = JerkEstimator::new(1.0, 0.01).unwrap().with_acceleration();
        assert_eq!(e.power(), None);
        assert_eq!(e.acceleration_power(), None);
        for k in 0..100u64 {
            e.update(k * 10_000, 100.0 + 2.0 * k as f32);
        }
        assert!(e.power().unwrap() < 1e-3, "{:?}", e.power());
        let a = e.acceleration_power().unwrap();
        assert!((a / 40_000.0 - 1.0).abs() < 1e-3, "{a}");
        // Without `with_acceleration`, none.
        let mut plain = JerkEstimator::new(1.0, 0.01).unwrap();
        for k in 0..100u64 {
            plain.update(k * 10_000, 100.0 + 2.0 * k as f32);
        }
        assert!(plain.power().is_some());
        assert_eq!(plain.acceleration_power(), None);
    }

    #[test]
    fn the_lag_follows_the_rate() {
        for (dt, lag) in [
            (0.01, 5),
            (0.02, 3),
            (0.04, 1),
            (0.05, 1),
            (0.5, 1),
            (0.001, 8),
        ] {
            assert_eq!(JerkEstimator::new(5.0, dt).unwrap().lag(), lag, "{dt}");
        }
        assert!(JerkEstimator::new(0.0, 0.01).is_err());
        assert!(JerkEstimator::new(5.0, f32::NAN).is_err());
    }

    /// A gap restarts the differences: a step in the rate across a gap (a new epoch) adds no
    /// term, and neither does a NaN.
    #[test]
    fn a_gap_restarts_the_differences() {
        let mut e = JerkEstimator::new(1.0, 0.01).unwrap();
        for k in 0..50u64 {
            e.update(k * 10_000, 10.0);
        }
        e.update(50 * 10_000, f32::NAN);
        for k in 0..50u64 {
            e.update(2_000_000 + k * 10_000, 500.0);
        }
        assert_eq!(e.power(), Some(0.0));
        // Without the gap the step reads.
        for k in 0..11u64 {
            e.update(2_500_000 + k * 10_000, 100.0);
        }
        assert!(e.power().unwrap() > 0.0);
    }
}
