//! The one interface of every estimator bank: [`EstimatorBank`] (one sample in, one output
//! out) and its output [`EstimatorOutput`] (the unwrapped angle and one value per channel,
//! with the channels' names).
//!
//! Every [`crate::Bank`] implements it ([`crate::PaperBank`], [`crate::ProductBank`] and any
//! custom tuple of rows, built by `Bank::new`), and so does [`crate::AdaptiveBank`] (built
//! from a gain schedule).
//! Code that drives "a bank" (the `nav440-pipeline` crate, its CSV writer, a firmware) is
//! generic over [`EstimatorBank`] and takes the channel count and names from it.

use crate::{Columns, SampleError};

/// One output of a bank for one sample: the unwrapped input angle and the channels' values.
///
/// The channel consts describe the type, so a firmware can size a buffer in a const context:
/// `[u8; 4 * <ProductOutput as EstimatorOutput>::CHANNELS]` (or through the bank,
/// `<ProductBank<Fx> as EstimatorBank>::CHANNELS`).
///
/// Invariant: `CHANNEL_NAMES.len() == CHANNELS`, `value(i)` is a channel's for `i < CHANNELS`, and
/// `CSV_COLUMNS` is `CHANNEL_NAMES` joined with `,` ([`crate::BankOutput`] satisfies it by
/// construction).
///
/// [`ProductOutput`]: crate::ProductOutput
pub trait EstimatorOutput: Copy + core::fmt::Debug + PartialEq {
    /// The number of channels (values per output).
    const CHANNELS: usize;
    /// The channels' names (their CSV column names), in output order: e.g. `"ilo1_v"`
    /// (a velocity, deg/s) or `"kf_a"` (an acceleration, deg/s^2).
    const CHANNEL_NAMES: &'static [&'static str];
    /// [`Self::CHANNEL_NAMES`] joined with `,` when displayed (e.g. `ilo1_v,kf_a`).
    const CSV_COLUMNS: Columns = Columns(Self::CHANNEL_NAMES);

    /// The unwrapped input angle rounded to f32, deg.
    fn unwrapped_deg(&self) -> f32;

    /// What f32 rounding took off the unwrapped angle, deg: the exact unwrapped angle is
    /// `unwrapped_deg() as f64 + residual_deg()` (0 while f32 holds it exactly).
    fn residual_deg(&self) -> f64;

    /// The value of channel `channel` ([`Self::CHANNEL_NAMES`] order) as `f32`: a velocity in
    /// deg/s or an acceleration in deg/s^2 (per input unit when the input is not in degrees);
    /// NaN past the last channel. A fixed-point bank's output holds the raw numbers and rounds
    /// them here (nearest, ties to even).
    fn value(&self, channel: usize) -> f32;

    /// The channels' values in [`Self::CHANNEL_NAMES`] order, as `f32` ([`Self::value`]).
    fn values(&self) -> Values<'_, Self>
    where
        Self: Sized,
    {
        Values { out: self, next: 0 }
    }

    /// The exact unwrapped angle, deg (`unwrapped_deg() + residual_deg()` in f64).
    fn unwrapped_deg_f64(&self) -> f64 {
        f64::from(self.unwrapped_deg()) + self.residual_deg()
    }
}

/// The channels' values of an [`EstimatorOutput`] as `f32`, in channel order
/// ([`EstimatorOutput::values`]).
#[derive(Clone, Debug)]
pub struct Values<'a, O> {
    out: &'a O,
    next: usize,
}

impl<O: EstimatorOutput> Iterator for Values<'_, O> {
    type Item = f32;

    fn next(&mut self) -> Option<f32> {
        if self.next >= O::CHANNELS {
            return None;
        }
        self.next += 1;
        Some(self.out.value(self.next - 1))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = O::CHANNELS.saturating_sub(self.next);
        (n, Some(n))
    }
}

impl<O: EstimatorOutput> ExactSizeIterator for Values<'_, O> {}

/// An estimator bank for one angle: timed samples in, one [`EstimatorOutput`] per accepted
/// sample out.
///
/// The channel consts default to the output's ([`EstimatorOutput::CHANNELS`], ...) and are
/// meant to be left so; they name a concrete bank's channels in a const context, e.g.
/// `<ProductBank<Fx> as EstimatorBank>::CHANNELS` (2) or `<PaperBank<f32> as
/// EstimatorBank>::CSV_COLUMNS`.
///
/// `no_std`, no heap: implementations keep their whole state inline.
pub trait EstimatorBank {
    /// What [`Self::update`] returns for an accepted sample.
    type Output: EstimatorOutput;

    /// The number of channels ([`EstimatorOutput::CHANNELS`] of [`Self::Output`]).
    const CHANNELS: usize = <Self::Output as EstimatorOutput>::CHANNELS;
    /// The channels' names, in output order ([`EstimatorOutput::CHANNEL_NAMES`]).
    const CHANNEL_NAMES: &'static [&'static str] = <Self::Output as EstimatorOutput>::CHANNEL_NAMES;
    /// The channels' names joined with `,` ([`EstimatorOutput::CSV_COLUMNS`]).
    const CSV_COLUMNS: Columns = <Self::Output as EstimatorOutput>::CSV_COLUMNS;

    /// Feeds one sample: `t_us`, its time in µs (increasing); `angle_deg`, the angle in deg
    /// (within +-180 when the bank unwraps, `BankConfig::wrap`).
    ///
    /// The first sample, and the first after a gap longer than the gap rule or after
    /// [`Self::new_epoch`], initialise every estimator from it and report 0 for every
    /// channel. Errors (state unchanged): [`SampleError::NotFinite`] for a NaN or infinite
    /// angle, [`SampleError::OutOfRange`] for `|angle_deg|` above 1e6 deg,
    /// [`SampleError::NonIncreasingTime`] for a time not later than the previous sample's.
    fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<Self::Output, SampleError>;

    /// [`Self::update`] with the angle `raw * 2^exp2` deg, a sensor's fixed-point reading (a
    /// NAV440 angle field `a`, 360/2^16 deg per LSB, is `raw = 45 a`, `exp2 = -13`). The same
    /// output as `update` of that angle as `f32` where `f32` holds it exactly (`|raw| <
    /// 2^24`); a [`crate::Bank`] converts it to its number type directly
    /// ([`crate::Real::from_scaled`]), so a fixed-point bank's input takes no `f32` on the
    /// way. The default goes through `f32` (`raw` rounded to it when `|raw| >= 2^24`).
    fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> Result<Self::Output, SampleError> {
        self.update(t_us, <f32 as crate::Real>::from_scaled(raw, exp2))
    }

    /// The rate about the bank's axis at `t_us` (deg/s), measured by a gyro (the unit's body
    /// rate about the axis, or the Euler rate built from its rates), given before
    /// [`Self::update`] of the same sample. A bank that follows the motion
    /// ([`crate::AdaptiveProductBank`]) estimates the motion's jerk from it; the default
    /// ignores it.
    #[inline]
    fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        let _ = (t_us, rate_deg_s);
    }

    /// Starts a new epoch (a confirmed time jump): the next sample re-initialises every
    /// estimator from itself, whatever its time; the unwrapped angle keeps its turns. Not
    /// counted in [`Self::reinit_count`].
    fn new_epoch(&mut self);

    /// How many times a gap longer than the gap rule re-initialised the bank.
    fn reinit_count(&self) -> u32;

    /// Takes over from `old`, the bank this one replaces (built for another nominal period
    /// after a new epoch, as `nav440_pipeline` does), what spans epochs: the unwrapper (its
    /// turn count and last angle) and [`Self::reinit_count`]. The laws' states are not taken
    /// (the next sample starts a new epoch). The default takes nothing.
    fn take_over(&mut self, old: &Self)
    where
        Self: Sized,
    {
        let _ = old;
    }
}
