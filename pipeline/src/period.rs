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
//!   converted as `us as f32 * 1e-6` seconds ([`seconds`]: those bits, computed with integer
//!   operations only, so that a core without an FPU links no soft-float routine for it);
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

/// `us as f32 * 1e-6` (s), bit for bit: the period rule's conversion ([module
/// documentation](self)). On a bare-metal target without hardware floating point (an ABI
/// other than `eabihf`) it is computed with integer operations only (both roundings of the
/// float expression, `us` to `f32` and the product with the `f32` nearest to 1e-6, to
/// nearest, ties to even), so no soft-float routine is linked; elsewhere it is the float
/// expression itself.
///
/// ```
/// use nav440_pipeline::period::seconds;
/// for us in [1, 59, 10_000, 20_000, 16_777_217, u64::MAX] {
///     assert_eq!(seconds(us).to_bits(), (us as f32 * 1e-6).to_bits());
/// }
/// ```
pub fn seconds(us: u64) -> f32 {
    if cfg!(all(target_os = "none", not(target_abi = "eabihf"))) {
        seconds_integer(us)
    } else {
        us as f32 * 1e-6
    }
}

/// [`seconds`] with integer operations only.
fn seconds_integer(us: u64) -> f32 {
    /// The bits of the `f32` nearest to 1e-6: significand `2^23 + fraction`, exponent.
    const MICRO: u32 = 0x3586_37BD;
    if us == 0 {
        return 0.0;
    }
    // `us as f32`: the significand `mx` (24 bits) and exponent `ex`, `us ~ mx 2^ex`.
    let (mx, ex) = nearest_24(us);
    let my = u64::from(MICRO & 0x007F_FFFF | 0x0080_0000);
    let ey = (MICRO >> 23) as i32 - 127 - 23;
    // The exact product (< 2^48) rounded to 24 bits: `q 2^e`.
    let (q, e) = nearest_24(mx * my);
    let exponent = (e + ex + ey + 23 + 127) as u32;
    f32::from_bits(exponent << 23 | (q as u32 & 0x007F_FFFF))
}

/// `x > 0` rounded to a 24-bit significand, to nearest, ties to even: `(q, e)` with `x ~ q
/// 2^e` and `2^23 <= q < 2^24`.
fn nearest_24(x: u64) -> (u64, i32) {
    let p = 63 - x.leading_zeros();
    if p <= 23 {
        return (x << (23 - p), p as i32 - 23);
    }
    let k = p - 23;
    let (q, r, half) = (x >> k, x & ((1u64 << k) - 1), 1u64 << (k - 1));
    let q = if r > half || (r == half && q & 1 == 1) {
        q + 1
    } else {
        q
    };
    if q == 1 << 24 {
        (q >> 1, k as i32 + 1)
    } else {
        (q, k as i32)
    }
}

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

    /// Nominal period, us: the upper median of the recorded intervals (`d[len / 2]` of the
    /// sorted intervals). `None` with fewer than two samples recorded.
    pub fn period_us(&self) -> Option<u64> {
        let n = self.samples.saturating_sub(1).min(INTERVALS);
        let mut sorted = self.intervals_us;
        let d = sorted.get_mut(..n)?;
        d.sort_unstable();
        d.get(d.len() / 2).copied()
    }

    /// Nominal period, s: [`PeriodEstimator::period_us`] converted by [`seconds`] (`us as f32
    /// * 1e-6`). `None` with fewer than two samples recorded.
    pub fn period_s(&self) -> Option<f32> {
        self.period_us().map(seconds)
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

#[cfg(test)]
mod tests {
    use super::seconds_integer as seconds;

    /// The integer [`super::seconds`] gives the bits of the float expression (the independent
    /// reference: the host's FPU) for every period below 2^25 us (33.6 s; both roundings
    /// exercised from 2^24 us on) and for random ones of every magnitude.
    #[test]
    fn seconds_is_the_float_expression() {
        for us in 0..1u64 << 25 {
            assert_eq!(seconds(us).to_bits(), (us as f32 * 1e-6).to_bits(), "{us}");
        }
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..1_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let us = x >> (x % 64);
            assert_eq!(seconds(us).to_bits(), (us as f32 * 1e-6).to_bits(), "{us}");
        }
    }
}
