//! [`NoiseEstimator`]: the online estimate of the angle's measurement-noise variance.

use crate::ConfigError;

/// Online estimate of the measurement-noise variance of an angle sampled at a steady rate.
///
/// Method: the third difference of the samples, `d3 = y[k] - 3 y[k-1] + 3 y[k-2] - y[k-3]`
/// (computed from wrapped first differences, so a +-180 deg wrap does not disturb it), has
/// variance `20 sigma^2` for white noise of variance `sigma^2`, while a smooth motion only
/// contributes `(jerk dt^3)^2` (at 100 Hz and a hand's jerk of 1e4 deg/s^3: 1e-4 deg^2, a
/// hundredth of `20 * 0.01`). The estimate is the exponentially weighted mean of
/// `d3^2 / 20` with time constant `tau_s`, at least [`NoiseEstimator::MIN_TAU_SAMPLES`]
/// periods (weight `dt / tau` per sample; the first `tau / dt` samples are averaged with
/// weight `1/k` so the estimate starts at once), where each term is clipped to 9 times the
/// current estimate, or [`NoiseEstimator::CLIP_FLOOR`] if that is larger (a robust mean: a motion burst or a glitch moves it by at most
/// `9 dt / tau` of itself; for Gaussian noise the clip removes under 1 % of the mean). A
/// sample interval that differs from the previous one by more than a quarter (a lost packet,
/// a gap, a new epoch) restarts the differences (the estimate is kept). Limitation: at low
/// packet rates the motion term grows as `dt^6` (20 Hz: 1.6e4 times larger than at 100 Hz),
/// so fast motion then reads as noise (at 10 Hz a hand's motion alone reads of the order of
/// the paper's small noise level, 0.01 deg^2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseEstimator {
    /// Weight of a new term once started, `dt / tau`.
    alpha: f32,
    /// Estimate, deg^2.
    var: f32,
    /// Terms averaged so far (saturates).
    count: u32,
    /// Previous sample: time (us) and angle (deg).
    prev: Option<(u64, f32)>,
    /// Previous interval, us.
    dt_prev: u64,
    /// The last first differences (newest first) and how many are valid (0 to 2).
    d: [f32; 2],
    nd: u8,
}

impl NoiseEstimator {
    /// The time constant is at least this many sample periods (the weight of a new term at
    /// most `1 / 50`): the estimate's jitter depends on how many terms it averages, not on
    /// seconds (its relative spread falls as `1 / sqrt(terms)`). At 100 Hz the default 0.5 s
    /// is exactly 50 periods; at 20 Hz the time constant becomes 2.5 s.
    pub const MIN_TAU_SAMPLES: f32 = 50.0;

    /// The least estimate the clip of a term is taken from, deg^2 (a term is clipped to 9
    /// times the estimate or this, whichever is larger): an angle that starts exactly constant
    /// (a unit at rest below one LSB of noise, 0.0055 deg, whose quantisation alone reads
    /// 2.6e-6) would otherwise hold the estimate at 0 for ever, every later term clipped to
    /// 9 x 0. From this floor the estimate grows by up to 16 % a sample: 0.5 deg^2 in under
    /// 1 s at 100 Hz.
    pub const CLIP_FLOOR: f32 = 1e-6;

    /// An estimator with time constant `tau_s` (s), or [`Self::MIN_TAU_SAMPLES`] periods if
    /// that is longer, for samples every `sample_period_s` (s).
    pub fn new(tau_s: f32, sample_period_s: f32) -> Result<Self, ConfigError> {
        if !(tau_s.is_finite() && sample_period_s.is_finite()) {
            return Err(ConfigError::NotFinite("tau_s"));
        }
        if tau_s <= 0.0 || sample_period_s <= 0.0 {
            return Err(ConfigError::NotPositive("tau_s"));
        }
        Ok(NoiseEstimator {
            alpha: (sample_period_s / tau_s).min(1.0 / Self::MIN_TAU_SAMPLES),
            var: 0.0,
            count: 0,
            prev: None,
            dt_prev: 0,
            d: [0.0; 2],
            nd: 0,
        })
    }

    /// The estimate, deg^2 (`None` before the first third difference).
    pub fn variance(&self) -> Option<f32> {
        (self.count > 0).then_some(self.var)
    }

    /// `true` once the estimate has averaged a time constant's worth of terms: from then on
    /// it falls by at most the factor `1 - dt / tau` a sample (0.98 at the least time
    /// constant, [`Self::MIN_TAU_SAMPLES`]).
    pub fn settled(&self) -> bool {
        self.count as f32 * self.alpha >= 1.0
    }

    /// Takes the sample `angle_deg` (deg, wrapped at +-180 or not) at `t_us` (µs, increasing).
    pub fn update(&mut self, t_us: u64, angle_deg: f32) {
        let Some((tp, yp)) = self.prev.replace((t_us, angle_deg)) else {
            return;
        };
        let dt = t_us.saturating_sub(tp);
        let steady = super::steady_interval(dt, self.dt_prev);
        self.dt_prev = dt;
        let mut d = angle_deg - yp;
        if d > 180.0 {
            d -= 360.0;
        } else if d < -180.0 {
            d += 360.0;
        }
        if !steady {
            self.nd = 0;
        }
        if self.nd >= 2 {
            let d3 = d - 2.0 * self.d[0] + self.d[1];
            let mut x = d3 * d3 * (1.0 / 20.0);
            let clip = 9.0 * self.var.max(Self::CLIP_FLOOR);
            if self.count >= 8 && x > clip {
                x = clip;
            }
            super::mean_step(&mut self.var, &mut self.count, self.alpha, x);
        }
        self.d = [d, self.d[0]];
        self.nd = (self.nd + 1).min(2);
    }

    /// Forgets the samples (not the estimate): the next sample starts new differences.
    pub fn restart(&mut self) {
        self.prev = None;
        self.nd = 0;
        self.dt_prev = 0;
    }
}
