//! The input stage every generated bank shares ([`BankInput`]): checks, sample clock, unwrapping.

use super::{BankConfig, Wrap};
use crate::adapter::{SampleClock, Tick};
use crate::words::{WordReader, Words};
use crate::{ConfigError, Hold, Real, SampleError, Unwrapper};

/// What [`BankInput::accept`] decided for one accepted sample.
#[derive(Clone, Copy, Debug)]
pub enum Feed<T: Real> {
    /// Initialise every law at `y` (first sample, after a gap or a new epoch) and report 0.
    Reset(T),
    /// Run every law over `n` steps from `y_prev` to `y` with `hold`.
    Advance {
        /// The previous sample (in the current frame).
        y_prev: T,
        /// This sample.
        y: T,
        /// Steps of `h`.
        n: u32,
        /// Input between the samples.
        hold: Hold,
    },
}

/// What a bank's laws were fed for one sample ([`PaperBank::update_fed`](crate::PaperBank::update_fed)): a frame shift
/// (deg, applied to every law first) and the feed.
#[derive(Clone, Copy, Debug)]
pub struct Fed<T: Real> {
    /// Every law was translated by this (deg) before the feed.
    pub shift: Option<T>,
    /// What the laws were fed.
    pub feed: Feed<T>,
}

/// A sample accepted by [`BankInput::accept`].
#[derive(Clone, Copy, Debug)]
pub struct Accepted<T: Real> {
    /// Translate every law by this (deg) before feeding: the frame moved by one turn.
    pub shift: Option<T>,
    /// What to do with the laws.
    pub feed: Feed<T>,
    /// The unwrapped angle as the number type holds it in an output ([`Real::OutputAngle`]).
    pub angle: T::OutputAngle,
}

/// The input stage every generated bank shares: input checks, sample clock (gap rule),
/// unwrapping into a local frame (per [`Wrap`]), the previous sample and the re-init count.
#[derive(Clone, Copy, Debug)]
pub struct BankInput<T: Real> {
    clock: SampleClock,
    hold: Hold,
    wrap: Wrap,
    unwrap: Unwrapper<T>,
    y_prev: T,
    reinits: u32,
}

impl<T: Real> BankInput<T> {
    /// Largest accepted `|angle|`, deg (2778 turns). Beyond it f32 resolves the angle to no
    /// better than 0.06 deg, and values near `f32::MAX` would overflow the states.
    pub const MAX_ABS_DEG: f32 = 1.0e6;
    /// [`Self::MAX_ABS_DEG`] as an integer.
    const MAX_ABS_DEG_I32: i32 = 1_000_000;

    /// Validates the step, period and gap rule of `cfg`; returns the input stage and the
    /// number of steps per nominal sample period the closed-form maps are built for (0 when
    /// `cfg.closed_form` is false).
    pub fn new(cfg: &BankConfig) -> Result<(Self, u32), ConfigError> {
        let h = cfg.h;
        // The period first: the gap rule is a multiple of it, so a bad period would otherwise
        // be reported as a bad gap rule.
        let h_us = crate::adapter::step_us(h)?;
        let period = f64::from(cfg.sample_period_s);
        if !period.is_finite() {
            return Err(ConfigError::NotFinite("sample_period_s"));
        }
        let n0f = libm::round(period * 1e6 / h_us as f64);
        if n0f < 1.0 {
            return Err(ConfigError::SamplePeriodTooShort);
        }
        if n0f > 1e6 {
            return Err(ConfigError::SamplePeriodTooLong);
        }
        if cfg.max_gap_periods > super::MAX_GAP_PERIODS {
            return Err(ConfigError::GapTooLong);
        }
        let clock = SampleClock::new(h, cfg.max_gap_s())?;
        let n0 = if cfg.closed_form { n0f as u32 } else { 0 };
        Ok((
            Self {
                clock,
                hold: cfg.hold,
                wrap: cfg.wrap,
                unwrap: Unwrapper::new(),
                y_prev: T::ZERO,
                reinits: 0,
            },
            n0,
        ))
    }

    /// Checks and classifies one sample (`t_us` µs, `angle_deg` deg); see [`PaperBank::update`](crate::PaperBank::update).
    #[inline(always)]
    pub fn accept(&mut self, t_us: u64, angle_deg: f32) -> Result<Accepted<T>, SampleError> {
        // `|angle| <= MAX_ABS_DEG` on the bit patterns (ordered like the magnitudes of
        // non-NaN floats; NaN and the infinities are above): no soft-float comparison on an
        // FPU-less core.
        if angle_deg.to_bits() & 0x7FFF_FFFF > Self::MAX_ABS_DEG.to_bits() {
            return Err(if angle_deg.is_finite() {
                SampleError::OutOfRange
            } else {
                SampleError::NotFinite
            });
        }
        self.accept_checked(t_us, T::from_f32(angle_deg))
    }

    /// [`Self::accept`] for an angle `y` already in the number type (deg): the same checks
    /// (`|y|` at most [`Self::MAX_ABS_DEG`]), the same result as `accept` of the `f32` it equals.
    #[inline(always)]
    pub fn accept_value(&mut self, t_us: u64, y: T) -> Result<Accepted<T>, SampleError> {
        let max = T::from_i32(Self::MAX_ABS_DEG_I32);
        if y <= max && y >= -max {
            return self.accept_checked(t_us, y);
        }
        Err(if y.is_finite() {
            SampleError::OutOfRange
        } else {
            SampleError::NotFinite
        })
    }

    /// [`Self::accept`] after the angle's checks.
    #[inline(always)]
    fn accept_checked(&mut self, t_us: u64, y: T) -> Result<Accepted<T>, SampleError> {
        let tick = self.clock.tick(t_us)?;
        // The laws run in a local frame whose origin is the unwrapper's current multiple of
        // 360 deg: they see the wrapped angle, so f32 states stay within about +-180 deg (full
        // f32 resolution) however many turns the unwrapped angle makes. When the offset
        // changes, every law is translated into the new frame (exact: the laws are invariant
        // to input offsets, see `Estimator::translate`).
        let mut shift = None;
        let turns = match self.wrap {
            Wrap::None => 0,
            Wrap::Deg180 => {
                let before = self.unwrap.turns();
                let turns = self.unwrap.update(y);
                if turns != before && tick != Tick::Init && tick != Tick::Gap {
                    // One turn per sample at most: the shift is exactly +-360 deg in `T`.
                    let d = -T::from_i32(if turns > before { 360 } else { -360 });
                    self.y_prev = self.y_prev + d;
                    shift = Some(d);
                }
                turns
            }
        };
        let angle = T::output_angle(turns, y);
        let feed = match tick {
            Tick::Init => Feed::Reset(y),
            Tick::Gap => {
                self.reinits = self.reinits.saturating_add(1);
                Feed::Reset(y)
            }
            Tick::Steps(n) => Feed::Advance {
                y_prev: self.y_prev,
                y,
                n,
                hold: self.hold,
            },
        };
        self.y_prev = y;
        Ok(Accepted { shift, feed, angle })
    }

    /// The last accepted sample in the laws' (local) frame, deg (0 before the first).
    pub fn last(&self) -> T {
        self.y_prev
    }

    /// Gaps longer than the gap rule that re-initialised the laws.
    pub fn reinit_count(&self) -> u32 {
        self.reinits
    }

    /// The next sample re-initialises the laws, whatever its time; turns are kept.
    pub fn new_epoch(&mut self) {
        self.clock.clear();
    }

    /// Sets the unwrapper's turn count (only the reported angle moves).
    pub fn set_turns(&mut self, turns: i64) {
        self.unwrap.set_turns(turns);
    }

    /// Takes the unwrapper (turns, last angle) and the re-init count of `old` (see
    /// `EstimatorBank::take_over`); the clock starts a new epoch.
    pub fn take_over(&mut self, old: &Self) {
        self.unwrap = old.unwrap;
        self.reinits = old.reinits;
        self.clock.clear();
    }

    /// Forgets everything but the configuration and the re-init count.
    pub fn restart(&mut self) {
        self.clock.clear();
        self.unwrap = Unwrapper::new();
        self.y_prev = T::ZERO;
    }

    /// Unwraps per `wrap` from now on ([`BankConfig::wrap`]), restarted ([`Self::restart`]).
    pub fn set_wrap(&mut self, wrap: Wrap) {
        self.wrap = wrap;
        self.restart();
    }
}

/// Its words ([`crate::words`]): the clock's step and gap rule, the hold and the unwrapping;
/// it reads back as [`BankInput::new`] builds it (no sample seen, no re-initialisation).
impl<T: Real> Words for BankInput<T> {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        self.clock.put_words(out);
        self.hold.put_words(out);
        self.wrap.put_words(out);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        Self {
            clock: SampleClock::take_words(r),
            hold: Hold::take_words(r),
            wrap: Wrap::take_words(r),
            unwrap: Unwrapper::new(),
            y_prev: T::ZERO,
            reinits: 0,
        }
    }
}
