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

/// Counts of the time-stamp faults a [`TimeBase`] handled (each saturates at `u32::MAX`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimeFaults {
    /// Repeated time stamps (step 0 ms): the sample is dropped.
    pub duplicates: u32,
    /// Impossible timeITOW values (>= 604 800 000 ms, e.g. 0xFFFFFFFF): the sample is
    /// discarded at once, nothing else changes.
    pub impossible: u32,
    /// Single stamps that went backward while the next stamp continued the old time base:
    /// the sample is discarded (also a backward stamp left unconfirmed at the end of input).
    pub bad_backward: u32,
    /// Single stamps that jumped forward (beyond [`SUSPECT_STEP_RATIO`] times the last
    /// interval) while the next stamp continued the old time base: the sample is discarded.
    pub bad_forward: u32,
    /// Backward jumps confirmed by the next stamp (unit reset, stitched recordings): a new
    /// epoch starts, the sample is kept and flagged [`Timed::new_epoch`].
    pub backward_jumps: u32,
    /// GPSITOW (U2) samples in a stream whose time base is timeITOW (U4): ignored.
    pub other_kind: u32,
    /// Switches from a GPSITOW to a timeITOW time base (the first timeITOW sample after
    /// GPSITOW ones): a new epoch, flagged [`Timed::new_epoch`].
    pub kind_switches: u32,
}

impl TimeFaults {
    /// Samples lost to time faults (duplicates excluded): impossible + bad backward + bad
    /// forward + other kind.
    pub fn discarded(&self) -> u32 {
        self.impossible
            .saturating_add(self.bad_backward)
            .saturating_add(self.bad_forward)
            .saturating_add(self.other_kind)
    }

    /// `true` when any fault (duplicates excluded) was seen.
    pub fn any(&self) -> bool {
        self.discarded() > 0 || self.backward_jumps > 0 || self.kind_switches > 0
    }
}

/// A forward step of more than `SUSPECT_STEP_RATIO` (3/2) times the last accepted interval is
/// suspicious: it is held until the next stamp confirms or contradicts it.
pub const SUSPECT_STEP_RATIO: (u32, u32) = (3, 2);

/// One sample placed on the continuous time axis by a [`TimeBase`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Timed<P> {
    /// Time since the first sample, µs (strictly increasing from sample to sample).
    pub t_us: u64,
    /// `true` for the first sample of a new epoch (confirmed backward jump or time-base kind
    /// switch): its time is the previous sample's plus the last interval, and whatever
    /// integrates over time (the estimator bank) must re-initialise from it.
    pub new_epoch: bool,
    /// The caller's data for this sample (e.g. yaw and rate).
    pub payload: P,
}

/// The samples a [`TimeBase::update`] releases, in order (zero, one or two).
#[derive(Clone, Copy, Debug)]
pub struct Released<P> {
    items: [Option<Timed<P>>; 2],
    next: usize,
}

impl<P> Released<P> {
    const fn none() -> Self {
        Self {
            items: [None, None],
            next: 0,
        }
    }

    fn push(&mut self, t: Timed<P>) {
        if let Some(slot) = self.items.iter_mut().find(|s| s.is_none()) {
            *slot = Some(t);
        }
    }
}

impl<P> Iterator for Released<P> {
    type Item = Timed<P>;
    fn next(&mut self) -> Option<Timed<P>> {
        while let Some(slot) = self.items.get_mut(self.next) {
            self.next += 1;
            if let Some(t) = slot.take() {
                return Some(t);
            }
        }
        None
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum Kind {
    Itow,
    Gps,
}

/// The last accepted stamp.
#[derive(Clone, Copy, Debug)]
struct Anchor {
    kind: Kind,
    /// timeITOW ms, or GPSITOW in the low 16 bits.
    raw: u32,
    t_us: u64,
}

/// A suspicious stamp waiting for the next one.
#[derive(Clone, Copy, Debug)]
struct Candidate<P> {
    raw: u32,
    /// Signed step from the anchor, ms.
    d_ms: i64,
    payload: P,
}

/// Signed step from `from` to `to` in ms: timeITOW modulo the week, GPSITOW modulo 2^16,
/// folded to (-period/2, period/2).
fn step_ms(kind: Kind, from: u32, to: u32) -> i64 {
    match kind {
        Kind::Itow => {
            let d = if to >= from {
                to - from
            } else {
                WEEK_MS - from + to
            };
            if d >= WEEK_MS / 2 {
                i64::from(d) - i64::from(WEEK_MS)
            } else {
                i64::from(d)
            }
        }
        Kind::Gps => i64::from((to as u16).wrapping_sub(from as u16) as i16),
    }
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

/// The time base of a sample stream: turns each packet's time stamp into a strictly
/// increasing time in µs since the first sample, and handles time faults so that ONE bad stamp
/// never shifts later times nor costs more than its own sample. The rules (the decisions are
/// documented with their tests in `docs/RELIABILITY.md`):
///
/// * **Wraps**: steps are taken modulo the week (timeITOW) or 2^16 ms (GPSITOW); a step of half
///   that period or more is a backward step.
/// * **Impossible** timeITOW (>= [`WEEK_MS`]): discarded at once and counted; nothing else
///   changes, so the next sample keeps its exact time.
/// * **Duplicate** stamp: dropped and counted.
/// * **Suspicious** stamp: backward, or forward by more than [`SUSPECT_STEP_RATIO`] times the
///   last accepted interval. It is held (with its payload) until the next stamp `N`:
///   - `N` continues the candidate forward and the candidate was forward of the anchor: a real
///     dropout (or rate change); the candidate is released with its true time;
///   - else `N` continues the old anchor: the candidate was one bad stamp; discarded, counted
///     ([`TimeFaults::bad_backward`] / [`TimeFaults::bad_forward`]);
///   - else `N` continues a backward candidate: a real backward jump (unit reset, stitched
///     recordings): the candidate starts a new epoch at the previous time plus the last
///     interval (the output time stays increasing) and is flagged [`Timed::new_epoch`];
///   - else the candidate is discarded (counted) and `N` is judged against the anchor;
///   - at the end of input ([`TimeBase::finish`]) a forward candidate is released, a
///     backward one discarded.
/// * **Kinds**: the time base is timeITOW (U4) as soon as one timeITOW sample is seen (the
///   switch from GPSITOW starts a new epoch); GPSITOW (U2) samples in a timeITOW stream are
///   ignored and counted (a polled A0 between A2 packets carries a truncated stamp and another
///   yaw: magnetic instead of free). A stream of GPSITOW packets alone runs on the 16-bit
///   stamps.
///
/// Latency: a suspicious sample is released one sample late. RAM: a few words plus two
/// payloads. `P` is the caller's data carried with each sample.
#[derive(Clone, Copy, Debug)]
pub struct TimeBase<P> {
    anchor: Option<Anchor>,
    /// Last accepted interval, ms (0 = none yet).
    ref_ms: u32,
    pending: Option<Candidate<P>>,
    faults: TimeFaults,
}

impl<P: Copy> Default for TimeBase<P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<P: Copy> TimeBase<P> {
    /// A time base that has seen no sample.
    pub const fn new() -> Self {
        Self {
            anchor: None,
            ref_ms: 0,
            pending: None,
            faults: TimeFaults {
                duplicates: 0,
                impossible: 0,
                bad_backward: 0,
                bad_forward: 0,
                backward_jumps: 0,
                other_kind: 0,
                kind_switches: 0,
            },
        }
    }

    /// Fault counts so far.
    pub const fn faults(&self) -> &TimeFaults {
        &self.faults
    }

    /// Feeds one sample's time stamp and payload; returns the samples released now, in order
    /// (see the type's rules).
    pub fn update(&mut self, ts: TimeStamp, payload: P) -> Released<P> {
        let mut out = Released::none();
        let (kind, raw) = match ts {
            TimeStamp::None => return out,
            TimeStamp::Itow(t) if t >= WEEK_MS => {
                bump(&mut self.faults.impossible);
                return out;
            }
            TimeStamp::Itow(t) => (Kind::Itow, t),
            TimeStamp::GpsItow(g) => (Kind::Gps, u32::from(g)),
        };
        let Some(anchor) = self.anchor else {
            self.anchor = Some(Anchor { kind, raw, t_us: 0 });
            out.push(Timed {
                t_us: 0,
                new_epoch: false,
                payload,
            });
            return out;
        };
        match (anchor.kind, kind) {
            (Kind::Itow, Kind::Gps) => {
                bump(&mut self.faults.other_kind);
                return out;
            }
            (Kind::Gps, Kind::Itow) => {
                if let Some(c) = self.pending.take() {
                    self.count_bad(c.d_ms);
                }
                bump(&mut self.faults.kind_switches);
                let t_us = self.epoch_time(anchor.t_us);
                self.anchor = Some(Anchor { kind, raw, t_us });
                out.push(Timed {
                    t_us,
                    new_epoch: true,
                    payload,
                });
                return out;
            }
            _ => {}
        }
        if let Some(c) = self.pending {
            let d_cn = step_ms(kind, c.raw, raw);
            let d_an = step_ms(kind, anchor.raw, raw);
            if d_cn == 0 || d_an == 0 {
                bump(&mut self.faults.duplicates);
                return out;
            }
            self.pending = None;
            if c.d_ms > 0 && d_cn > 0 {
                // Anchor < candidate < next: a real dropout or a slower rate.
                let t_us = self.accept(anchor, c.raw, c.d_ms);
                out.push(Timed {
                    t_us,
                    new_epoch: false,
                    payload: c.payload,
                });
                self.ref_ms = u32::try_from(d_cn).unwrap_or(u32::MAX);
            } else if d_an > 0 && self.within(d_an, 2) {
                // The next stamp continues the old base: the candidate was one bad stamp.
                self.count_bad(c.d_ms);
            } else if c.d_ms < 0 && d_cn > 0 {
                // A real backward jump: a new epoch from the candidate.
                bump(&mut self.faults.backward_jumps);
                let t_us = self.epoch_time(anchor.t_us);
                self.anchor = Some(Anchor {
                    kind,
                    raw: c.raw,
                    t_us,
                });
                out.push(Timed {
                    t_us,
                    new_epoch: true,
                    payload: c.payload,
                });
            } else {
                self.count_bad(c.d_ms);
            }
        }
        if let Some(t) = self.judge(kind, raw, payload) {
            out.push(t);
        }
        out
    }

    /// End of input: releases a pending forward candidate (nothing contradicts it) or discards
    /// a pending backward one (counted in [`TimeFaults::bad_backward`]).
    pub fn finish(&mut self) -> Option<Timed<P>> {
        let c = self.pending.take()?;
        let anchor = self.anchor?;
        if c.d_ms > 0 {
            let t_us = self.accept(anchor, c.raw, c.d_ms);
            Some(Timed {
                t_us,
                new_epoch: false,
                payload: c.payload,
            })
        } else {
            self.count_bad(c.d_ms);
            None
        }
    }

    /// Judges a stamp against the anchor (no candidate pending).
    fn judge(&mut self, kind: Kind, raw: u32, payload: P) -> Option<Timed<P>> {
        let anchor = self.anchor?;
        let d = step_ms(kind, anchor.raw, raw);
        if d == 0 {
            bump(&mut self.faults.duplicates);
            return None;
        }
        if d > 0 && self.within(d, 1) {
            self.ref_ms = u32::try_from(d).unwrap_or(u32::MAX);
            let t_us = self.accept(anchor, raw, d);
            return Some(Timed {
                t_us,
                new_epoch: false,
                payload,
            });
        }
        self.pending = Some(Candidate {
            raw,
            d_ms: d,
            payload,
        });
        None
    }

    /// `d` (ms, > 0) is within `slots` suspicion limits of the last interval (always, before
    /// the first interval).
    fn within(&self, d: i64, slots: i64) -> bool {
        let (num, den) = SUSPECT_STEP_RATIO;
        self.ref_ms == 0 || d * i64::from(den) <= slots * i64::from(num) * i64::from(self.ref_ms)
    }

    fn accept(&mut self, anchor: Anchor, raw: u32, d_ms: i64) -> u64 {
        let t_us = anchor
            .t_us
            .saturating_add(u64::try_from(d_ms).unwrap_or(0).saturating_mul(1000));
        self.anchor = Some(Anchor {
            kind: anchor.kind,
            raw,
            t_us,
        });
        t_us
    }

    /// Time of the first sample of a new epoch: the last time plus the last interval (1 ms
    /// if none yet).
    fn epoch_time(&self, last_us: u64) -> u64 {
        last_us.saturating_add(u64::from(self.ref_ms.max(1)).saturating_mul(1000))
    }

    fn count_bad(&mut self, d_ms: i64) {
        if d_ms < 0 {
            bump(&mut self.faults.bad_backward);
        } else {
            bump(&mut self.faults.bad_forward);
        }
    }
}
