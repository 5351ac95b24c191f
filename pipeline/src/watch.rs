//! Stream watchdog: what a device notices about a configured unit's stream while it runs.
//!
//! [`StreamWatch`] consumes the frames the pipeline's front end parses ([`crate::FrameSeen`]:
//! every CRC-valid frame's type and, for an attitude packet, its time stamp; one parser for
//! the estimates and the watch). Armed with [`crate::Pipeline::watch`], it is fed by
//! [`crate::Pipeline::feed_watched`] and reports, each at the moment it is seen:
//!
//! * **silence**: no complete frame for [`StreamWatch::silence_limit_ms`] =
//!   max([`MIN_SILENCE_MS`], [`PERIODS`] nominal periods) ([`StreamWatch::poll`]);
//! * **frozen time stamps**: [`PERIODS`] frames in a row of the configured type repeating
//!   one time stamp, and the first new stamp after such a run;
//! * **another packet rate**: the period of the first [`WARMUP_SAMPLES`](crate::period::WARMUP_SAMPLES) time stamps differs
//!   from the configured one by more than [`RATE_TOLERANCE_PERCENT`] % (once);
//! * **another packet type**: a frame of a type other than the configured one (once; after a
//!   configuration this means the unit reset or was reconfigured);
//! * **periodic counters**: every [`COUNTER_INTERVAL_S`] s of stream time (counted in frames
//!   of the configured type at the nominal rate).
//!
//! Time comes from the caller as a free-running millisecond counter (`now_ms`, wrapping).

use crate::period::PeriodEstimator;
use crate::FrameSeen;
use nav440_proto::{PacketRate, PacketType, TimeStamp};

/// The shortest silence reported, ms.
pub const MIN_SILENCE_MS: u32 = 500;
/// Nominal periods of silence, or of frames with a frozen time stamp, before a report.
pub const PERIODS: u32 = 25;
/// Difference between the measured and the configured packet period, in percent of the
/// configured one, above which the rate is reported as different (compared in whole
/// microseconds: no floating point).
pub const RATE_TOLERANCE_PERCENT: u32 = 20;
/// Stream time between two periodic counter reports, s.
pub const COUNTER_INTERVAL_S: u32 = 10;

/// Something [`StreamWatch`] noticed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// No complete frame for `silent_ms` ms (>= `limit_ms`).
    Silence {
        /// Time since the last complete frame (or since the watch started), ms.
        silent_ms: u32,
        /// The silence limit, ms.
        limit_ms: u32,
    },
    /// [`PERIODS`] frames in a row carry the same time stamp `stamp_ms` (reported once per
    /// run, when the run reaches that length).
    Frozen {
        /// Frames in the run so far.
        frames: u32,
        /// The repeated time stamp, ms (timeITOW or GPSITOW).
        stamp_ms: u32,
    },
    /// The time stamps advance again after a reported run of `frames` frozen frames.
    Thawed {
        /// Frames of the run (the first of the repeated stamp included).
        frames: u32,
    },
    /// The measured packet rate differs from the configured one: their periods.
    RateMismatch {
        /// Period from the first [`WARMUP_SAMPLES`](crate::period::WARMUP_SAMPLES) time
        /// stamps (their upper median interval, [`PeriodEstimator::period_us`]), us.
        measured_us: u32,
        /// The configured rate's period, us (10,000 us at 100 Hz).
        configured_us: u32,
    },
    /// A frame of another type than the configured one.
    ForeignType {
        /// The type received.
        got: PacketType,
        /// The configured type.
        configured: PacketType,
    },
    /// Another [`COUNTER_INTERVAL_S`] s of stream time: time to report the counters.
    Periodic {
        /// Stream time so far (frames of the configured type x nominal period), s.
        stream_s: u32,
    },
}

/// The stream watchdog of one configured stream (see the [module](self) doc).
#[derive(Debug)]
pub struct StreamWatch {
    packet: PacketType,
    rate: PacketRate,
    last_frame_ms: u32,
    silence_reported: bool,
    last_stamp: Option<TimeStamp>,
    frozen_run: u32,
    period: PeriodEstimator,
    rate_checked: bool,
    foreign_reported: bool,
    frames: u64,
    /// Frames of the configured type per periodic report ([`COUNTER_INTERVAL_S`] s).
    every: u32,
    /// Frames of the configured type until the next periodic report (a count-down: no
    /// division per frame).
    to_periodic: u32,
}

impl StreamWatch {
    /// A watch of a stream of `packet` at `rate`, started at `now_ms`.
    pub fn new(packet: PacketType, rate: PacketRate, now_ms: u32) -> Self {
        let period_ms = 10 * u32::from(rate.divider().max(1));
        let every = (COUNTER_INTERVAL_S * 1000 / period_ms).max(1);
        Self {
            packet,
            rate,
            last_frame_ms: now_ms,
            silence_reported: false,
            last_stamp: None,
            frozen_run: 0,
            period: PeriodEstimator::new(),
            rate_checked: false,
            foreign_reported: false,
            frames: 0,
            every,
            to_periodic: every,
        }
    }

    /// The nominal packet period, ms (100 Hz / divider: 10 ms x divider; 10 ms for a quiet
    /// rate, which a configured stream does not use).
    pub fn period_ms(&self) -> u32 {
        10 * u32::from(self.rate.divider().max(1))
    }

    /// The silence limit: max([`MIN_SILENCE_MS`], [`PERIODS`] nominal periods), ms (500 ms
    /// at 100 Hz, 12.5 s at 2 Hz).
    pub fn silence_limit_ms(&self) -> u32 {
        (PERIODS * self.period_ms()).max(MIN_SILENCE_MS)
    }

    /// Takes one frame the front end parsed, complete at `now_ms`; `on_event` gets what it
    /// shows, in order.
    pub fn frame(&mut self, frame: &FrameSeen, now_ms: u32, mut on_event: impl FnMut(Event)) {
        self.last_frame_ms = now_ms;
        self.silence_reported = false;
        if frame.packet_type != self.packet {
            if !self.foreign_reported {
                self.foreign_reported = true;
                on_event(Event::ForeignType {
                    got: frame.packet_type,
                    configured: self.packet,
                });
            }
            return;
        }
        self.frames = self.frames.saturating_add(1);
        self.to_periodic -= 1;
        if self.to_periodic == 0 {
            self.to_periodic = self.every;
            let stream_s =
                (self.frames / u64::from(self.every)).saturating_mul(u64::from(COUNTER_INTERVAL_S));
            on_event(Event::Periodic {
                stream_s: u32::try_from(stream_s).unwrap_or(u32::MAX),
            });
        }
        let Some(stamp) = frame.time.filter(|s| *s != TimeStamp::None) else {
            return;
        };
        if self.last_stamp == Some(stamp) {
            self.frozen_run = self.frozen_run.saturating_add(1);
            if self.frozen_run == PERIODS {
                on_event(Event::Frozen {
                    frames: self.frozen_run,
                    stamp_ms: stamp_ms(stamp),
                });
            }
            return;
        }
        if self.frozen_run >= PERIODS {
            on_event(Event::Thawed {
                frames: self.frozen_run,
            });
        }
        self.frozen_run = 1;
        self.last_stamp = Some(stamp);
        if !self.rate_checked {
            self.period.push(u64::from(stamp_ms(stamp)) * 1000);
            if self.period.is_complete() {
                self.rate_checked = true;
                if let Some(p) = self.period.period_us().filter(|p| *p > 0) {
                    let configured = u64::from(self.period_ms()) * 1000;
                    if p.abs_diff(configured) * 100 > configured * u64::from(RATE_TOLERANCE_PERCENT)
                    {
                        on_event(Event::RateMismatch {
                            measured_us: u32::try_from(p).unwrap_or(u32::MAX),
                            configured_us: u32::try_from(configured).unwrap_or(u32::MAX),
                        });
                    }
                }
            }
        }
    }

    /// Checks for silence at time `now_ms`: [`Event::Silence`] once per silence (a frame ends
    /// it), when no frame has been complete for [`StreamWatch::silence_limit_ms`].
    pub fn poll(&mut self, now_ms: u32) -> Option<Event> {
        let silent_ms = now_ms.wrapping_sub(self.last_frame_ms);
        let limit_ms = self.silence_limit_ms();
        if self.silence_reported || silent_ms < limit_ms {
            return None;
        }
        self.silence_reported = true;
        Some(Event::Silence {
            silent_ms,
            limit_ms,
        })
    }

    /// Frames of the configured type seen so far (with [`StreamWatch::continuing`]'s start).
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// This watch with its stream time continuing from `frames` frames of an earlier watch of
    /// the same stream (e.g. before a re-configuration): the periodic reports keep counting.
    pub fn continuing(mut self, frames: u64) -> Self {
        self.frames = frames;
        // Cannot be 0: `frames % every < every`.
        self.to_periodic = self.every - (frames % u64::from(self.every)) as u32;
        self
    }
}

/// A time stamp's value, ms.
fn stamp_ms(s: TimeStamp) -> u32 {
    match s {
        TimeStamp::Itow(ms) => ms,
        TimeStamp::GpsItow(ms) => u32::from(ms),
        TimeStamp::None => 0,
    }
}
