//! The nominal sample period of a sample stream, decided causally from its first samples.
//!
//! An `estimators::PaperBank` precomputes its closed-form multi-step maps and its Kalman
//! gains for one nominal sample period ([`BankConfig::sample_period_s`]). This module is the
//! one rule that sets it, shared by the host replay (`nav440 estimate`) and the firmware so
//! that both build the same bank by construction:
//!
//! * the time stamps of the first [`WARMUP_SAMPLES`] samples are recorded (later ones are
//!   ignored: a streaming device holds these samples back, builds the bank, then runs them and
//!   everything after through it);
//! * the nominal period is the upper median of their intervals (`d[len / 2]` of the sorted
//!   intervals, in whole microseconds; a non-increasing time stamp counts as a 0 us interval),
//!   converted as `us as f32 * 1e-6` seconds;
//! * a stream shorter than the warm-up uses the intervals it has; with fewer than two samples
//!   there is no interval and the configuration keeps its own period
//!   ([`PeriodEstimator::apply`]).
//!
//! The median ignores a few dropped packets or late time stamps among the first samples. A
//! packet rate that changes after the warm-up does not change the period (the bank still runs
//! `round(dt / h)` steps per actual interval; only the precomputed maps and gains are for the
//! warm-up rate).
//!
//! ```
//! use nav440_pipeline::period::{PeriodEstimator, WARMUP_SAMPLES};
//! use estimators::BankConfig;
//!
//! // 20 packets at 50 Hz (20 ms), then the rate changes: only the first 16 count.
//! let times = (0..20u64).map(|k| k * 20_000).chain((1..50u64).map(|k| 380_000 + k * 10_000));
//! let est = PeriodEstimator::from_times(times);
//! assert!(est.is_complete());
//! assert_eq!(est.samples(), WARMUP_SAMPLES);
//! assert_eq!(est.period_s(), Some(20_000.0 * 1e-6));
//! let cfg = est.apply(BankConfig::default());
//! assert!((cfg.sample_period_s - 0.02).abs() < 1e-9); // s
//! // Fewer than two samples: the configuration's own period is kept.
//! assert_eq!(PeriodEstimator::from_times([0]).apply(BankConfig::default()).sample_period_s, 0.01);
//! ```

use estimators::BankConfig;

/// Number of samples whose time stamps decide the nominal period (0.16 s at 100 Hz, 0.8 s at
/// 20 Hz).
pub const WARMUP_SAMPLES: usize = 16;

/// Intervals between the warm-up samples.
const INTERVALS: usize = WARMUP_SAMPLES - 1;

/// Records the time stamps of the first [`WARMUP_SAMPLES`] samples and gives their nominal
/// period (see the [module documentation](self)). No heap: 15 intervals of 8 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeriodEstimator {
    /// Time of the last recorded sample, us.
    last_us: u64,
    /// Intervals between recorded samples, us (the first `samples - 1` are valid).
    intervals_us: [u64; INTERVALS],
    /// Samples recorded, at most [`WARMUP_SAMPLES`].
    samples: usize,
}

impl Default for PeriodEstimator {
    fn default() -> Self {
        Self::new()
    }
}

impl PeriodEstimator {
    /// An estimator that has seen no sample.
    pub const fn new() -> Self {
        Self {
            last_us: 0,
            intervals_us: [0; INTERVALS],
            samples: 0,
        }
    }

    /// The estimator after the time stamps `times_us` (us, in stream order); only the first
    /// [`WARMUP_SAMPLES`] are read.
    pub fn from_times(times_us: impl IntoIterator<Item = u64>) -> Self {
        let mut est = Self::new();
        for t_us in times_us.into_iter().take(WARMUP_SAMPLES) {
            est.push(t_us);
        }
        est
    }

    /// Records the time stamp of the next sample, us. Returns `false` (and ignores it) once
    /// [`WARMUP_SAMPLES`] samples have been recorded.
    pub fn push(&mut self, t_us: u64) -> bool {
        if self.is_complete() {
            return false;
        }
        if self.samples > 0 {
            if let Some(slot) = self.intervals_us.get_mut(self.samples - 1) {
                *slot = t_us.saturating_sub(self.last_us);
            }
        }
        self.last_us = t_us;
        self.samples += 1;
        true
    }

    /// Number of samples recorded (at most [`WARMUP_SAMPLES`]).
    pub const fn samples(&self) -> usize {
        self.samples
    }

    /// `true` once [`WARMUP_SAMPLES`] samples have been recorded: the period is final.
    pub const fn is_complete(&self) -> bool {
        self.samples >= WARMUP_SAMPLES
    }

    /// Nominal period, s: the upper median of the recorded intervals (`d[len / 2]` of the
    /// sorted intervals, `us as f32 * 1e-6`). `None` with fewer than two samples recorded.
    pub fn period_s(&self) -> Option<f32> {
        let n = self.samples.saturating_sub(1).min(INTERVALS);
        let mut sorted = self.intervals_us;
        let d = sorted.get_mut(..n)?;
        d.sort_unstable();
        d.get(d.len() / 2).map(|&us| us as f32 * 1e-6)
    }

    /// `cfg` with [`BankConfig::sample_period_s`] set to [`PeriodEstimator::period_s`], or
    /// unchanged if there is no interval yet.
    pub fn apply(&self, cfg: BankConfig) -> BankConfig {
        BankConfig {
            sample_period_s: self.period_s().unwrap_or(cfg.sample_period_s),
            ..cfg
        }
    }
}
