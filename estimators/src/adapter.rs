//! From samples at the sensor rate to steps of size `h`.

use crate::words::{WordReader, Words};
use crate::{ConfigError, Estimator, Hold, Real, SampleError};

/// What the sample clock decided for one accepted sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Tick {
    /// First sample (k = 0): initialise every state from it, report 0.
    Init,
    /// Run this many steps `n_k = round((t_k - t_{k-1}) / h) >= 1` from the previous sample to
    /// this one.
    Steps(u32),
    /// The interval exceeded the maximum gap: re-initialise from this sample, report 0.
    Gap,
}

/// Counts steps between integer-microsecond timestamps.
///
/// At sample `k >= 1`, `n_k = round((t_k - t_{k-1}) / h)`, at least 1 (an interval shorter than
/// `h/2` still runs one step, so every accepted sample is seen). An interval longer than
/// `max_gap` gives [`Tick::Gap`]. A timestamp not later than the previous one is refused and
/// leaves the clock unchanged.
#[derive(Clone, Copy, Debug)]
pub struct SampleClock {
    h_us: u64,
    max_gap_us: u64,
    last: Option<u64>,
    /// The last interval that gave `Tick::Steps` and its step count (0: none yet): a stream
    /// at a steady rate then costs no 64-bit division per sample.
    last_dt: u64,
    last_n: u32,
}

impl SampleClock {
    /// `h`: step in s, a whole number of microseconds in `[1e-6, 1]`; `max_gap_s`: longest
    /// interval integrated across, s (`>= h`).
    pub fn new(h: f32, max_gap_s: f32) -> Result<Self, ConfigError> {
        let h_us = step_us(h)?;
        let g = f64::from(max_gap_s);
        if !g.is_finite() {
            return Err(ConfigError::NotFinite("max_gap_s"));
        }
        let gap_us = libm::round(g * 1e6);
        if gap_us < h_us as f64 || gap_us > 4.0e9 {
            return Err(ConfigError::GapTooShort);
        }
        Ok(Self {
            h_us,
            max_gap_us: gap_us as u64,
            last: None,
            last_dt: 0,
            last_n: 0,
        })
    }

    /// The step `h` in microseconds.
    pub fn step_us(&self) -> u64 {
        self.h_us
    }

    /// Classifies the sample at `t_us` (µs) and, if accepted, records it as the last one.
    #[inline]
    pub fn tick(&mut self, t_us: u64) -> Result<Tick, SampleError> {
        if let Some(prev) = self.last {
            // Same interval as last time (`last_dt` is 0 until a `Steps` interval was seen,
            // and every interval is > 0): same step count as `peek` would compute.
            if t_us > prev && t_us - prev == self.last_dt {
                self.last = Some(t_us);
                return Ok(Tick::Steps(self.last_n));
            }
        }
        let tick = self.peek(t_us)?;
        if let (Tick::Steps(n), Some(p)) = (tick, self.last) {
            self.last_dt = t_us - p;
            self.last_n = n;
        }
        self.last = Some(t_us);
        Ok(tick)
    }

    /// Like [`SampleClock::tick`] without recording the sample.
    #[inline(never)]
    pub fn peek(&self, t_us: u64) -> Result<Tick, SampleError> {
        match self.last {
            None => Ok(Tick::Init),
            Some(prev) if t_us <= prev => Err(SampleError::NonIncreasingTime),
            Some(prev) => {
                let dt = t_us - prev;
                if dt > self.max_gap_us {
                    Ok(Tick::Gap)
                } else {
                    // h_us >= 1 by construction; checked_div keeps the path panic-free.
                    let n = (dt + self.h_us / 2).checked_div(self.h_us).unwrap_or(dt);
                    // dt <= max_gap <= 4e9 us, h >= 1 us: n fits in u32.
                    Ok(Tick::Steps(u32::try_from(n.max(1)).unwrap_or(u32::MAX)))
                }
            }
        }
    }

    /// Forgets the last sample (the next one is a k = 0 sample).
    pub fn clear(&mut self) {
        self.last = None;
    }
}

/// Its words ([`crate::words`]): the step and the gap rule, in us; it reads back with no
/// sample seen, as [`SampleClock::new`] builds it.
impl Words for SampleClock {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        self.h_us.put_words(out);
        self.max_gap_us.put_words(out);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        Self {
            h_us: u64::take_words(r),
            max_gap_us: u64::take_words(r),
            last: None,
            last_dt: 0,
            last_n: 0,
        }
    }
}

/// Checks and converts the step `h` (s) to whole microseconds.
pub(crate) fn step_us(h: f32) -> Result<u64, ConfigError> {
    let h = f64::from(h);
    if !h.is_finite() {
        return Err(ConfigError::NotFinite("h"));
    }
    let us = libm::round(h * 1e6);
    if !(1.0..=1e6).contains(&us) || libm::fabs(us - h * 1e6) > 1e-3 {
        return Err(ConfigError::StepNotWholeMicroseconds);
    }
    Ok(us as u64)
}

/// One estimator behind the sample adapter: feed it `(t_us, y)` samples at the sensor rate.
///
/// * k = 0: the estimator is reset to `y_0` (position = `y_0`, all velocity / learning /
///   delay states 0) and the reported estimate is 0.
/// * k >= 1: `n_k = round((t_k - t_{k-1}) / h)` steps as [`Hold`] prescribes, then the output
///   of the last step is reported.
/// * interval > `max_gap`: re-initialised from the new sample as at k = 0, reports 0.
/// * NaN / infinite `y` or non-increasing `t`: error, state unchanged.
#[derive(Clone, Copy, Debug)]
pub struct SampleAdapter<T: Real, E: Estimator<T>> {
    est: E,
    clock: SampleClock,
    hold: Hold,
    y_prev: T,
}

impl<T: Real, E: Estimator<T>> SampleAdapter<T, E> {
    /// Wraps `est`, which must have been built for the same step `h` (s).
    pub fn new(est: E, h: f32, max_gap_s: f32, hold: Hold) -> Result<Self, ConfigError> {
        Ok(Self {
            est,
            clock: SampleClock::new(h, max_gap_s)?,
            hold,
            y_prev: T::ZERO,
        })
    }

    /// Feeds one sample: `t_us`, its time stamp in integer microseconds (absolute, increasing),
    /// then `y`, the sample in the estimator's input unit; returns the estimate.
    ///
    /// Convention: the time stamp first, as the banks' `update(t_us, angle_deg)`; the
    /// adapter computes the interval from the previous sample. [`crate::Kalman::update`]
    /// takes the other order and a relative time: `update(y, dt)`, the measurement first and
    /// the interval in seconds.
    pub fn update(&mut self, t_us: u64, y: f32) -> Result<T, SampleError> {
        if !y.is_finite() {
            return Err(SampleError::NotFinite);
        }
        let yt = T::from_f32(y);
        match self.clock.tick(t_us)? {
            Tick::Init | Tick::Gap => {
                self.est.reset(yt);
                self.y_prev = yt;
                Ok(T::ZERO)
            }
            Tick::Steps(n) => {
                let out = self.est.advance(self.y_prev, yt, n, self.hold);
                self.y_prev = yt;
                Ok(out)
            }
        }
    }

    /// Forgets the last sample: the next one re-initialises the estimator from itself and
    /// reports 0, as the first sample does (what a bank's `new_epoch` does to each of its
    /// estimators).
    pub fn restart(&mut self) {
        self.clock.clear();
    }

    /// The wrapped estimator.
    pub fn estimator(&self) -> &E {
        &self.est
    }
}
