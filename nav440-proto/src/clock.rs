//! Continuous time from the packets' wrapping time stamps.

use crate::packets::TimeStamp;

/// One GPS week in ms: timeITOW (U4) wraps here.
pub const WEEK_MS: u32 = 604_800_000;

/// Turns successive [`TimeStamp`]s into a continuous time in microseconds since the first
/// sample, handling the U2 GPSITOW wrap every 65.536 s and the U4 timeITOW week rollover.
///
/// Rules (`update` returns the time of the sample, or `None` when it must be dropped):
/// * The first `Itow`/`GpsItow` sample is time 0.
/// * A forward step is the time difference modulo the wrap period (2^16 ms for GPSITOW,
///   604 800 000 ms for timeITOW), so wraps are invisible. A step of half the period or more
///   (>= 32.768 s for GPSITOW, >= 3.5 days for timeITOW) is taken as a backward jump.
/// * A repeated time stamp (step 0) returns `None` and changes nothing.
/// * A backward jump (or a timeITOW value >= 604 800 000, or a switch between `Itow` and
///   `GpsItow`) returns `None` and starts a new epoch: the next samples count forward from
///   this one, continuing from the last returned time, so the output never goes backwards.
/// * `TimeStamp::None` returns `None` and changes nothing.
///
/// Output resolution is 1 ms (values are multiples of 1000 us).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ItowClock {
    last: Option<TimeStamp>,
    elapsed_us: u64,
    started: bool,
}

impl ItowClock {
    /// A clock that has seen no sample yet.
    pub const fn new() -> Self {
        Self {
            last: None,
            elapsed_us: 0,
            started: false,
        }
    }

    /// The last time returned, microseconds since the first sample.
    pub const fn now_us(&self) -> u64 {
        self.elapsed_us
    }

    /// Feeds one sample's time stamp; returns its time in microseconds since the first sample,
    /// or `None` (see the type's rules).
    pub fn update(&mut self, ts: TimeStamp) -> Option<u64> {
        let step_ms: Option<u64> = match (self.last, ts) {
            (_, TimeStamp::None) => return None,
            (_, TimeStamp::Itow(t)) if t >= WEEK_MS => {
                // Impossible time of week: new epoch at the next valid sample.
                self.last = None;
                return None;
            }
            (None, _) => {
                self.last = Some(ts);
                return if !self.started {
                    self.started = true;
                    Some(0)
                } else {
                    // Re-anchoring after an impossible value: keep the output continuous.
                    None
                };
            }
            (Some(TimeStamp::Itow(prev)), TimeStamp::Itow(t)) => {
                let d = if t >= prev {
                    t - prev
                } else {
                    WEEK_MS - prev + t
                };
                (d < WEEK_MS / 2).then_some(d as u64)
            }
            (Some(TimeStamp::GpsItow(prev)), TimeStamp::GpsItow(t)) => {
                let d = t.wrapping_sub(prev);
                (d < 0x8000).then_some(d as u64)
            }
            _ => None, // kind switch
        };
        match step_ms {
            Some(0) => None,
            Some(d) => {
                self.last = Some(ts);
                self.elapsed_us += d * 1000;
                Some(self.elapsed_us)
            }
            None => {
                self.last = Some(ts);
                None
            }
        }
    }
}
