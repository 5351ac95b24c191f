//! The back end (timed samples -> warm-up/period rule -> one bank per axis -> rows) and the
//! whole pipeline (front end + back end), as the firmware and `nav440 estimate` run them.
//!
//! Nominal sample period: the banks precompute their closed-form maps and Kalman gains for
//! the packet rate (`BankConfig::sample_period_s`). It is set by [`crate::period`]: the upper
//! median of the intervals between the first [`WARMUP_SAMPLES`] samples of each time epoch. A
//! streaming device cannot build the banks before it knows that period, so [`Estimation`] holds
//! back those first samples, then builds the banks and runs them and all later ones through
//! them; rows are only delayed by the warm-up (0.16 s at 100 Hz). A stream shorter than the
//! warm-up is decided at its end ([`Estimation::finish`]) from the intervals it has (none: the
//! configured period).
//!
//! Every new time epoch (a confirmed backward jump: the unit was reset, re-booted, or another
//! recording starts) is a new warm-up: its first [`WARMUP_SAMPLES`] samples (fewer if the
//! next epoch starts sooner or the stream ends) are held back and measured by the same rule.
//! The same period: the banks run on as before (rows identical to a run without the hold-back,
//! only later). Another period: every bank is built again for it (the builder decides the
//! gains for the rate, as at the start), takes over the old bank's turn count and gap count
//! ([`EstimatorBank::take_over`]), and [`Counters::period_changes`] counts the change
//! ([`Estimation::period_s`] is the period in use); the host prints it on stderr, the firmware
//! as a `firmware:` message. An epoch with fewer than two samples keeps the period in use.
//!
//! Time faults follow `nav440_proto::TimeBase` (see [`crate::Frontend`]): an impossible or
//! single bad stamp costs its own sample only, a confirmed backward jump starts a new epoch
//! (the banks re-initialise), GPSITOW samples in a timeITOW stream are ignored; each is
//! counted. A sample any selected axis's bank rejects (non-finite or out-of-range angle, time
//! not increasing) yields no row and is counted by reason (the first rejecting axis's).
//!
//! Gimbal lock: while the pitch is at or beyond [`crate::euler::PITCH_LIMIT_DEG`] (80 deg),
//! the roll and yaw angles swing with the heading of the pole, up to 100 deg between two
//! samples, and their banks would ring for a second after each pass. They are not fed there:
//! the row carries no roll and yaw fields (empty CSV fields; the pitch is estimated as
//! always), and the first sample below the limit restarts their banks from itself, as a new
//! time epoch does ([`Counters::near_lock`], [`Counters::lock_passes`]). The pause is the same
//! whatever the rows' rate column ([`Reference`]): it follows the pitch angle.
//!
//! The rate column of each axis is chosen by the type parameter `R: Reference` of
//! [`Estimation`] and [`Pipeline`] (default [`EulerReference`]: the Euler reference rate;
//! [`crate::BodyRates`]: the unit's body rate, without the trigonometry).

use crate::period::{seconds, PeriodEstimator, WARMUP_SAMPLES};
use crate::reference::{EulerReference, Reference};
use crate::sample::{AllPackets, Decoder, Frontend, Sample};
use crate::watch::{Event, StreamWatch};
use crate::{Axes, Axis};
use core::marker::PhantomData;
use estimators::{
    AdaptiveBank, AdaptiveConfig, AdaptiveProductBank, AdaptiveProductConfig, Bank, BankConfig,
    EstimatorBank, EstimatorOutput, GainSchedule, PaperOutput, Real, Rows, SampleError,
    SelfTuneConfig, SelfTuningProductBank, SqrtFn, Wrap,
};
use nav440_proto::{PacketRate, PacketType};

/// `cfg` for `axis`: the +-180 deg unwrapping switched off for pitch ([`Axis::wraps`]).
pub fn axis_config(axis: Axis, cfg: &BankConfig) -> BankConfig {
    let wrap = if axis.wraps() {
        Wrap::Deg180
    } else {
        Wrap::None
    };
    BankConfig { wrap, ..*cfg }
}

/// The bank of one axis: `Bank::new(cfg)` (any [`Bank`]: `PaperBank`, `ProductBank`, a
/// custom tuple of rows), with the +-180 deg unwrapping switched off for pitch
/// ([`Axis::wraps`]).
pub fn axis_bank<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>>(
    axis: Axis,
    cfg: &BankConfig,
) -> Result<Bank<R, N, T, S>, estimators::ConfigError> {
    Bank::new(&axis_config(axis, cfg))
}

/// The noise-adaptive bank of one axis (what `nav440 estimate --gains schedule.toml` runs):
/// `AdaptiveBank::new` with `cfg` (step, hold, period, gap rule; unwrapping as
/// [`axis_bank`]), the gain `schedule` and [`AdaptiveConfig::DEFAULT`].
pub fn adaptive_axis_bank<T: Real, S: SqrtFn<T>>(
    axis: Axis,
    cfg: &BankConfig,
    schedule: &GainSchedule,
) -> Result<AdaptiveBank<T, S>, estimators::ConfigError> {
    AdaptiveBank::new(&axis_config(axis, cfg), schedule, &AdaptiveConfig::DEFAULT)
}

/// The motion-adaptive product bank of one axis (what `nav440 estimate --bank product`
/// runs by default, and the firmware feature `bank-product`): `AdaptiveProductBank::new` with `cfg` (unwrapping as [`axis_bank`]) and
/// [`AdaptiveProductConfig::DEFAULT`]. The pipeline gives it each row's rate about the axis
/// ([`EstimatorBank::observe_rate`]).
pub fn adaptive_product_axis_bank<T: Real, S: SqrtFn<T>>(
    axis: Axis,
    cfg: &BankConfig,
) -> Result<AdaptiveProductBank<T, S>, estimators::ConfigError> {
    AdaptiveProductBank::new(&axis_config(axis, cfg), &AdaptiveProductConfig::DEFAULT)
}

/// The self-tuning product bank of one axis (what `nav440 estimate --bank product
/// --self-tune` runs): `SelfTuningProductBank::new` with `cfg` (unwrapping as [`axis_bank`])
/// and [`SelfTuneConfig::DEFAULT`]. The pipeline gives it each row's valid rate about the axis
/// ([`EstimatorBank::observe_rate`]): the Euler reference rate, `None` near gimbal lock, and
/// no sample at all for a packet whose BIT word flags a failure.
pub fn self_tuning_product_axis_bank<T: Real, S: SqrtFn<T>>(
    axis: Axis,
    cfg: &BankConfig,
) -> Result<SelfTuningProductBank<T, S>, estimators::ConfigError> {
    SelfTuningProductBank::new(&axis_config(axis, cfg), &SelfTuneConfig::DEFAULT)
}

/// One axis of a row: the rate column and the bank's output `O` (e.g.
/// `estimators::PaperOutput`, the default, or `estimators::ProductOutput`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisRow<O = PaperOutput> {
    /// The axis's rate column, deg/s, as the pipeline's [`Reference`] gives it: the angle's
    /// reference rate from the Euler kinematics ([`EulerReference`]; `None` near gimbal lock,
    /// see [`crate::euler`]) or the unit's body rate about the axis ([`crate::BodyRates`];
    /// `None` when not sent).
    pub reference_deg_s: Option<f32>,
    /// Unwrapped angle (deg) and the bank's channels (velocities in deg/s, accelerations in
    /// deg/s^2).
    pub out: O,
}

/// One output row of a bank with output `O` ([`EstimatorBank::Output`]; default the paper
/// bank's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row<O = PaperOutput> {
    /// Sample time, us since the first sample.
    pub t_us: u64,
    /// Roll, pitch, yaw ([`Axis::index`]); `Some` for the selected axes, except roll and yaw
    /// near gimbal lock ([`crate::euler::near_lock`]: their banks are not fed there).
    pub axes: [Option<AxisRow<O>>; 3],
}

impl<O> Row<O> {
    /// The row's data for `axis` (`None` if the axis is not estimated).
    pub fn axis(&self, axis: Axis) -> Option<&AxisRow<O>> {
        self.axes[axis.index()].as_ref()
    }

    /// The same row with every axis's output mapped by `f` (e.g. `BankOutput::to_f32`, the
    /// output held as `f32` whatever the bank's number type).
    pub fn map<P>(&self, mut f: impl FnMut(&O) -> P) -> Row<P> {
        Row {
            t_us: self.t_us,
            axes: self.axes.each_ref().map(|a| {
                a.as_ref().map(|a| AxisRow {
                    reference_deg_s: a.reference_deg_s,
                    out: f(&a.out),
                })
            }),
        }
    }
}

/// Samples the banks refused (they give no row), by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rejections {
    /// Time stamp not later than the previous sample's.
    pub time_not_increasing: u64,
    /// Angle (with any added noise) beyond the banks' limit (1e6 deg,
    /// `PaperBank::MAX_ABS_DEG`).
    pub angle_out_of_range: u64,
    /// Angle (with any added noise) NaN or infinite.
    pub angle_not_finite: u64,
}

impl Rejections {
    /// All rejected samples.
    pub fn total(&self) -> u64 {
        self.time_not_increasing
            .saturating_add(self.angle_out_of_range)
            .saturating_add(self.angle_not_finite)
    }

    /// Counts one rejection.
    pub fn count(&mut self, e: SampleError) {
        let c = match e {
            SampleError::NonIncreasingTime => &mut self.time_not_increasing,
            SampleError::OutOfRange => &mut self.angle_out_of_range,
            SampleError::NotFinite => &mut self.angle_not_finite,
        };
        *c = c.saturating_add(1);
    }
}

/// Counters of the back end (saturating). Once the banks run: `samples = rows +
/// rejected.total()` (plus the firmware's format errors).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Samples taken (held warm-up samples included).
    pub samples: u64,
    /// Rows emitted.
    pub rows: u64,
    /// Samples rejected by a bank.
    pub rejected: Rejections,
    /// Gaps longer than the gap rule (the most of any axis's bank).
    pub gaps: u32,
    /// Samples at or beyond the gimbal-lock limit ([`crate::euler::near_lock`]) whose roll and
    /// yaw were not estimated (counted when a roll or yaw bank runs).
    pub near_lock: u64,
    /// Returns from the gimbal-lock limit: the roll and yaw banks restarted.
    pub lock_passes: u32,
    /// New epochs whose measured nominal period differed from the one in use: the banks were
    /// built again for it ([`Estimation::period_s`]).
    pub period_changes: u32,
}

/// Where the back end is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    /// Collecting the first samples of the stream or of a new epoch.
    Warmup,
    /// Running: one bank per selected axis.
    Running,
}

/// The back end: timed samples -> warm-up/period rule -> one bank per selected axis ->
/// [`Row`]s of the bank's output (`Row<B::Output>`). `build(axis, cfg)` makes an axis's bank once the period is known (e.g.
/// [`axis_bank`]); its error is returned by the call that ends the warm-up and by every later
/// one.
///
/// `N` (default 3) is the number of bank slots: the selected axes take the slots in CSV
/// order, so a one-axis firmware sets `N = 1` and holds one bank instead of three (RAM on a
/// small MCU). Axes beyond the first `N` of the selection are not estimated (see
/// [`Estimation::with_slots`]).
///
/// `R` (default [`EulerReference`]) is the rows' rate column ([`Reference`], zero-sized):
/// `Estimation<B, E, F, 3, BodyRates>` gives the body rates and links no Euler kinematics.
pub struct Estimation<B, E, F, const N: usize = 3, R = EulerReference> {
    axes: Axes,
    cfg: BankConfig,
    build: F,
    phase: Phase,
    /// The first samples, held until the period is known.
    held: heapless::Vec<Sample, WARMUP_SAMPLES>,
    /// One bank per selected axis once running, in the order of `axes` (empty before).
    banks: heapless::Vec<B, N>,
    /// A bank could not be built for the measured period.
    failed: Option<E>,
    /// The nominal sample period the banks were built for, s (`None` before the first
    /// build): they run `cfg` with this period.
    built: Option<f32>,
    /// The measured period the banks were built for, us (`None` before the first build, or
    /// when they run the configuration's own period: fewer than two samples).
    built_us: Option<u64>,
    counters: Counters,
    /// The last sample was near gimbal lock: the roll and yaw banks restart at the next one.
    in_lock: bool,
    reference: PhantomData<R>,
}

impl<B, E, F, const N: usize, R> core::fmt::Debug for Estimation<B, E, F, N, R> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Estimation")
            .field("axes", &self.axes)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl<
        B: EstimatorBank,
        E: Clone,
        F: FnMut(Axis, &BankConfig) -> Result<B, E>,
        const N: usize,
        R: Reference,
    > Estimation<B, E, F, N, R>
{
    /// A back end with `N` bank slots for `axes`, the configuration `cfg` (its sample period
    /// is replaced by the measured one) and the bank constructor `build`. Only the first `N`
    /// selected axes (CSV order) are kept ([`Estimation::axes`] tells which). `N` and the
    /// rate column `R` come from the type the caller names (e.g. `let e: Estimation<_, _, _,
    /// 3, BodyRates> = Estimation::with_slots(..)`).
    // Out of line: the value is then written straight into the caller's place; inlined, the
    // compiler builds it in a temporary and copies it, bank slots included (a second
    // pipeline-sized stack frame on a small MCU).
    #[inline(never)]
    pub fn with_slots(axes: Axes, cfg: BankConfig, build: F) -> Self {
        let mut kept = Axes::NONE;
        for a in axes.iter().take(N) {
            kept = kept.with(a);
        }
        Self {
            axes: kept,
            cfg,
            build,
            phase: Phase::Warmup,
            held: heapless::Vec::new(),
            banks: heapless::Vec::new(),
            failed: None,
            built: None,
            built_us: None,
            counters: Counters::default(),
            in_lock: false,
            reference: PhantomData,
        }
    }

    /// The estimated axes.
    pub fn axes(&self) -> Axes {
        self.axes
    }

    /// Counters so far.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// The nominal sample period the banks run with, s (`None` before they are built): the
    /// one measured at the start or at the last epoch whose period changed.
    pub fn period_s(&self) -> Option<f32> {
        self.built
    }

    /// [`Estimation::period_s`] as the period rule measured it, us (`None` before the banks
    /// are built, or when they run the configuration's own period: a stream of fewer than
    /// two samples).
    pub fn period_us(&self) -> Option<u64> {
        self.built_us
    }

    /// The bank of `axis`, once built (`None` before, after a failed build, or for an axis
    /// that is not estimated).
    pub fn bank(&self, axis: Axis) -> Option<&B> {
        if self.built.is_none() || self.failed.is_some() {
            return None;
        }
        let slot = self.axes.iter().position(|a| a == axis)?;
        self.banks.get(slot)
    }

    /// Takes the next sample; `emit` gets every row that is ready (none during the warm-up,
    /// then the held-back ones and one per accepted sample).
    pub fn push(&mut self, s: Sample, emit: &mut dyn FnMut(&Row<B::Output>)) -> Result<(), E> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        self.counters.samples = self.counters.samples.saturating_add(1);
        // A new epoch is a new warm-up; the one under way ends with the samples it has (the
        // stream's first warm-up only once it has an interval).
        if s.new_epoch && (self.built.is_some() || self.held.len() >= 2) {
            self.start(emit)?;
            self.phase = Phase::Warmup;
        }
        match self.phase {
            Phase::Running => {
                run_sample::<B, R>(
                    &mut self.banks,
                    self.axes,
                    &mut self.counters,
                    &mut self.in_lock,
                    &s,
                    emit,
                );
                Ok(())
            }
            Phase::Warmup => {
                // Cannot fail: the warm-up ends as soon as the buffer is full.
                let _ = self.held.push(s);
                if self.held.is_full() {
                    self.start(emit)?;
                }
                Ok(())
            }
        }
    }

    /// End of a finite stream: a stream shorter than the warm-up runs with the intervals it
    /// has.
    pub fn finish(&mut self, emit: &mut dyn FnMut(&Row<B::Output>)) -> Result<(), E> {
        self.start(emit)
    }

    /// Ends the warm-up: builds the banks for the measured period (again, after a new epoch
    /// whose period differs from the one in use) and runs the held samples (nothing if already
    /// running).
    #[inline(never)]
    fn start(&mut self, emit: &mut dyn FnMut(&Row<B::Output>)) -> Result<(), E> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        if self.phase == Phase::Running {
            return Ok(());
        }
        // The configuration the banks are built with is kept in place (one copy on the small
        // parts' RAM): only its period changes, and it is read only here. So its period is
        // the one in use: the configuration's until the first build, then the last build's.
        // Fewer than two samples keep it.
        let base_s = self.cfg.sample_period_s;
        let measured_us = held_period_us(&self.held);
        self.cfg.sample_period_s = measured_us.map(seconds).unwrap_or(base_s);
        let cfg = &self.cfg;
        self.phase = Phase::Running;
        if self.built.is_none() {
            for axis in self.axes.iter().take(N) {
                match (self.build)(axis, cfg) {
                    // Cannot fail: at most `N` axes are kept.
                    Ok(b) => {
                        let _ = self.banks.push(b);
                    }
                    Err(e) => return Err(self.fail(e)),
                }
            }
        } else if cfg.sample_period_s.to_bits() != base_s.to_bits() {
            // (Compared by their bits: periods are finite and >= 0, so this is `!=` without a
            // float comparison.)
            // Another period after a new epoch: every bank again, for it, one at a time in
            // its slot (one bank on the stack, not `N`: the small parts' RAM).
            let mut failed = None;
            for (axis, slot) in self.axes.iter().zip(self.banks.iter_mut()) {
                match (self.build)(axis, cfg) {
                    Ok(mut b) => {
                        b.take_over(slot);
                        *slot = b;
                    }
                    Err(e) => {
                        failed = Some(e);
                        break;
                    }
                }
            }
            if let Some(e) = failed {
                return Err(self.fail(e));
            }
            self.counters.period_changes = self.counters.period_changes.saturating_add(1);
        }
        self.built = Some(self.cfg.sample_period_s);
        self.built_us = measured_us.or(self.built_us);
        for s in &self.held {
            run_sample::<B, R>(
                &mut self.banks,
                self.axes,
                &mut self.counters,
                &mut self.in_lock,
                s,
                emit,
            );
        }
        self.held.clear();
        Ok(())
    }

    /// A bank could not be built: no bank runs from now on, `e` is returned by every call.
    #[cold]
    fn fail(&mut self, e: E) -> E {
        self.banks.clear();
        self.failed = Some(e.clone());
        e
    }
}

impl<B: EstimatorBank, E: Clone, F: FnMut(Axis, &BankConfig) -> Result<B, E>> Estimation<B, E, F> {
    /// A back end for `axes` (any of the three) with the configuration `cfg` (its sample
    /// period is replaced by the measured one) and the bank constructor `build`, whose rows
    /// carry the Euler reference rates (another [`Reference`]: [`Estimation::with_slots`]).
    pub fn new(axes: Axes, cfg: BankConfig, build: F) -> Self {
        Self::with_slots(axes, cfg, build)
    }
}

/// The nominal period the held samples' time stamps give, us (`None` with fewer than two):
/// [`PeriodEstimator`] on their times. Out of line, so the estimator's intervals are not in
/// the frame of [`Estimation::start`] while it builds the banks.
#[inline(never)]
fn held_period_us(held: &[Sample]) -> Option<u64> {
    PeriodEstimator::from_times(held.iter().map(|s| s.t_us)).period_us()
}

/// Runs one sample through every selected axis's bank and emits its row, with `R`'s rate
/// column. Near gimbal lock the roll and yaw banks are skipped (their fields stay `None`); the
/// first sample after it reaches them as the start of a new epoch (`in_lock` carries the state
/// between samples).
#[inline(never)]
fn run_sample<B: EstimatorBank, R: Reference>(
    banks: &mut [B],
    axes: Axes,
    counters: &mut Counters,
    in_lock: &mut bool,
    s: &Sample,
    emit: &mut dyn FnMut(&Row<B::Output>),
) {
    let refs = R::rates_deg_s(s.angles_deg(), s.rates_deg_s);
    let mut row: Row<B::Output> = Row {
        t_us: s.t_us,
        axes: [None; 3],
    };
    let near_lock = s.near_lock();
    let singular_axes = axes.iter().any(Axis::singular_near_lock);
    if singular_axes && near_lock {
        counters.near_lock = counters.near_lock.saturating_add(1);
    }
    let leaving_lock = *in_lock && !near_lock;
    if singular_axes && leaving_lock {
        counters.lock_passes = counters.lock_passes.saturating_add(1);
    }
    *in_lock = near_lock;
    // The roll and yaw banks' input on the first sample after the lock: a new epoch.
    let restart = leaving_lock.then_some(Sample {
        new_epoch: true,
        ..*s
    });
    let mut err = None;
    let mut gaps = 0;
    for (bank, axis) in banks.iter_mut().zip(axes.iter()) {
        let i = axis.index();
        let singular = axis.singular_near_lock();
        if singular && near_lock {
            gaps = gaps.max(bank.reinit_count());
            continue;
        }
        let input = match &restart {
            Some(r) if singular => r,
            _ => s,
        };
        if input.new_epoch {
            bank.new_epoch();
        }
        // The row's rate about the axis, for a bank that follows the motion (a no-op for the
        // others).
        if let Some(rate) = refs[i] {
            bank.observe_rate(input.t_us, rate);
        }
        // The packet's integer angle, `45 raw * 2^-13` deg, or an edited sample's degrees as
        // the same form: exact in the bank's number type, one input path.
        let scaled = match s.angles_raw() {
            Some(raw) => {
                let (mult, exp2) = nav440_proto::scale::ANGLE_DEG_SCALED;
                Some((i32::from(raw[i]) * mult, exp2))
            }
            None => estimators::f32_scaled(s.angle(axis)),
        };
        let out = match scaled {
            Some((m, e)) => bank.update_scaled(input.t_us, m, e),
            None => Err(SampleError::NotFinite),
        };
        match out {
            Ok(out) => {
                row.axes[i] = Some(AxisRow {
                    reference_deg_s: refs[i],
                    out,
                })
            }
            Err(e) => {
                err.get_or_insert(e);
            }
        }
        gaps = gaps.max(bank.reinit_count());
    }
    counters.gaps = gaps;
    match err {
        Some(e) => counters.rejected.count(e),
        None => {
            counters.rows = counters.rows.saturating_add(1);
            emit(&row);
        }
    }
}

/// Longest CSV row of three axes of the paper bank: 49 fields of up to ~30 characters plus
/// separators (a bank with more than 14 channels needs a larger line, [`Pipeline::feed`] with
/// its own formatting).
pub const ROW_CAPACITY: usize = 1600;

/// One formatted CSV row (with its trailing newline).
pub type CsvLine = heapless::String<ROW_CAPACITY>;

/// The whole pipeline: [`Frontend`] (bytes -> frames -> BIT check -> clock -> samples) and
/// [`Estimation`] (warm-up/period -> banks -> rows), and on a device the stream watchdog
/// ([`StreamWatch`], armed by [`Pipeline::watch`]) fed with the front end's frames. The
/// firmware runs it as is; `nav440 estimate` runs it with its own bank type (noise, fixed
/// point) and no watch. `N`: the bank slots, `R`: the rows' rate column (default the Euler
/// reference rate; see [`Estimation`]).
///
/// ```
/// use estimators::{BankConfig, ProductBank};
/// use nav440_pipeline::{axis_bank, csv, Axes, Axis, BodyRates, Pipeline};
///
/// // The product bank on all axes, rows with the body rates instead of the Euler reference.
/// type Build = fn(Axis, &BankConfig) -> Result<ProductBank<f32>, estimators::ConfigError>;
/// let build: Build = |axis, cfg| axis_bank(axis, cfg);
/// let pipe: Pipeline<_, _, Build, 3, BodyRates> =
///     Pipeline::with_slots(Axes::ALL, BankConfig::NAV440, build);
/// let mut header = String::new();
/// csv::write_header_for::<estimators::ProductOutput>(&mut header, Axes::only(Axis::Yaw), pipe.rate_column())
///     .unwrap();
/// assert_eq!(header, "t,yaw,yaw_body_rate,ilo1_v,kf_a");
/// ```
pub struct Pipeline<B, E, F, const N: usize = 3, R = EulerReference, D = AllPackets> {
    front: Frontend<D>,
    est: Estimation<B, E, F, N, R>,
    format_errors: u64,
    watch: Option<StreamWatch>,
}

impl<B, E, F, const N: usize, R, D: core::fmt::Debug> core::fmt::Debug
    for Pipeline<B, E, F, N, R, D>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Pipeline")
            .field("front", &self.front)
            .field("est", &self.est)
            .field("watch", &self.watch)
            .finish()
    }
}

impl<
        B: EstimatorBank,
        E: Clone,
        F: FnMut(Axis, &BankConfig) -> Result<B, E>,
        const N: usize,
        R: Reference,
        D: Decoder,
    > Pipeline<B, E, F, N, R, D>
{
    /// A pipeline with `N` bank slots estimating the first `N` of `axes`, rows with the rate
    /// column `R` (see [`Estimation::with_slots`]).
    pub fn with_slots(axes: Axes, cfg: BankConfig, build: F) -> Self {
        Self {
            front: Frontend::default(),
            est: Estimation::with_slots(axes, cfg, build),
            format_errors: 0,
            watch: None,
        }
    }

    /// Feeds received bytes; `emit` gets every row in order. Fails (now and on every later
    /// call) if a bank cannot be built for the measured packet period. The stream watchdog,
    /// if armed, does not see these bytes (a device feeds them with [`Pipeline::feed_watched`]).
    pub fn feed(&mut self, bytes: &[u8], emit: &mut dyn FnMut(&Row<B::Output>)) -> Result<(), E> {
        self.feed_inner(bytes, None, emit)
    }

    /// [`Pipeline::feed`] of bytes received at `now_ms` (a free-running millisecond clock,
    /// wrapping) with the stream watchdog: every frame the front end parses goes to the watch
    /// armed by [`Pipeline::watch`] (none armed: no event), and `on_event` gets what it
    /// reports at the frame where it is seen ([`StreamWatch::frame`]), in stream order with
    /// the rows.
    pub fn feed_watched(
        &mut self,
        bytes: &[u8],
        now_ms: u32,
        emit: &mut dyn FnMut(&Row<B::Output>),
        on_event: &mut dyn FnMut(Event),
    ) -> Result<(), E> {
        self.feed_inner(bytes, Some((now_ms, on_event)), emit)
    }

    /// The one parse of [`Pipeline::feed`] and [`Pipeline::feed_watched`]: frames to the
    /// watch (with `watched`'s time and event sink), samples to the back end.
    fn feed_inner(
        &mut self,
        bytes: &[u8],
        watched: Option<(u32, &mut dyn FnMut(Event))>,
        emit: &mut dyn FnMut(&Row<B::Output>),
    ) -> Result<(), E> {
        let Self {
            front, est, watch, ..
        } = self;
        let mut watched =
            watched.and_then(|(now_ms, on_event)| Some((watch.as_mut()?, now_ms, on_event)));
        let mut res = Ok(());
        front.feed_frames(
            bytes,
            |frame| {
                if let Some((w, now_ms, on_event)) = watched.as_mut() {
                    w.frame(frame, *now_ms, &mut **on_event);
                }
            },
            |s| {
                if res.is_ok() {
                    res = est.push(s, emit);
                }
            },
        );
        res
    }

    /// Arms the stream watchdog at `now_ms` for a unit configured to stream `packet` at
    /// `rate` (after every configuration; see [`crate::watch`]). Its periodic reports'
    /// stream time continues from the watch it replaces (across re-configurations).
    pub fn watch(&mut self, packet: PacketType, rate: PacketRate, now_ms: u32) {
        let frames = self.watch.as_ref().map_or(0, StreamWatch::frames);
        self.watch = Some(StreamWatch::new(packet, rate, now_ms).continuing(frames));
    }

    /// The stream watchdog, once armed ([`Pipeline::watch`]).
    pub fn stream_watch(&self) -> Option<&StreamWatch> {
        self.watch.as_ref()
    }

    /// Checks the armed watch for silence at `now_ms` ([`StreamWatch::poll`]: at most one
    /// [`Event::Silence`] per silence; `None` without a watch).
    pub fn poll_watch(&mut self, now_ms: u32) -> Option<Event> {
        self.watch.as_mut()?.poll(now_ms)
    }

    /// End of a finite input: the sample the clock holds, and a stream shorter than the
    /// warm-up.
    pub fn finish(&mut self, emit: &mut dyn FnMut(&Row<B::Output>)) -> Result<(), E> {
        let Self { front, est, .. } = self;
        let mut res = Ok(());
        front.finish(|s| res = est.push(s, emit));
        res?;
        est.finish(emit)
    }

    /// [`Pipeline::feed`] with every row formatted as a CSV line ([`crate::csv::write_row`],
    /// newline-terminated); a row that does not fit [`CsvLine`] is counted
    /// ([`Pipeline::format_errors`]), not emitted.
    pub fn feed_csv(&mut self, bytes: &[u8], mut emit: impl FnMut(&str)) -> Result<(), E> {
        let axes = self.est.axes();
        let mut format_errors = 0u64;
        let res = self.feed(bytes, &mut |row| {
            format_line(row, axes, &mut format_errors, &mut emit)
        });
        self.format_errors = self.format_errors.saturating_add(format_errors);
        res
    }

    /// [`Pipeline::finish`] with CSV lines (see [`Pipeline::feed_csv`]).
    pub fn finish_csv(&mut self, mut emit: impl FnMut(&str)) -> Result<(), E> {
        let axes = self.est.axes();
        let mut format_errors = 0u64;
        let res = self.finish(&mut |row| format_line(row, axes, &mut format_errors, &mut emit));
        self.format_errors = self.format_errors.saturating_add(format_errors);
        res
    }

    /// The front end (parser statistics, front counters, time faults).
    pub fn front(&self) -> &Frontend<D> {
        &self.front
    }

    /// The back end (counters, banks).
    pub fn estimation(&self) -> &Estimation<B, E, F, N, R> {
        &self.est
    }

    /// The rows' rate column (`R::COLUMN`): what the CSV header names it
    /// ([`crate::csv::write_header_for`]).
    pub fn rate_column(&self) -> crate::RateColumn {
        R::COLUMN
    }

    /// Rows that did not fit [`CsvLine`] (never expected; counted, not hidden).
    pub fn format_errors(&self) -> u64 {
        self.format_errors
    }

    /// Writes the one-line summary of all counters (`key=value` pairs) into `w`.
    pub fn summary(
        &self,
        w: &mut impl core::fmt::Write,
        uart_overruns: u32,
        uart_stalls: u32,
    ) -> core::fmt::Result {
        let s = self.front.parser_stats();
        let fc = self.front.counters();
        let c = self.est.counters();
        let f = self.front.time_faults();
        write!(
            w,
            "bytes={} frames={} crc_errors={} skipped={} decode_errors={} samples={} rows={} rejected={} format_errors={} uart_overruns={} uart_stalls={}",
            s.bytes, s.frames, s.crc_errors, s.skipped_bytes, fc.decode_errors, c.samples, c.rows, c.rejected.total(), self.format_errors, uart_overruns, uart_stalls
        )?;
        write!(
            w,
            " yaw_packets={} impossible={} bad_backward={} bad_forward={} backward_jumps={} kind_switches={} other_kind={} duplicates={} gaps={} near_lock={} lock_passes={}",
            fc.attitude_packets, f.impossible, f.bad_backward, f.bad_forward, f.backward_jumps, f.kind_switches, f.other_kind, f.duplicates, c.gaps, c.near_lock, c.lock_passes
        )?;
        write!(
            w,
            " bit_failed={} bit_flag={} bit_hardware_error={} bit_com_error={} bit_software_error={} bit_last=0x{:04x}",
            fc.bit.failed,
            crate::bit::FAILURE_FLAG,
            fc.bit.hardware_error,
            fc.bit.com_error,
            fc.bit.software_error,
            fc.bit.last_word
        )
    }
}

impl<B: EstimatorBank, E: Clone, F: FnMut(Axis, &BankConfig) -> Result<B, E>> Pipeline<B, E, F> {
    /// A pipeline estimating `axes` (any of the three; see [`Estimation::new`]), rows with the
    /// Euler reference rates (another [`Reference`]: [`Pipeline::with_slots`]).
    pub fn new(axes: Axes, cfg: BankConfig, build: F) -> Self {
        Self::with_slots(axes, cfg, build)
    }
}

/// Formats `row` into a [`CsvLine`] and emits it, or counts a format error.
fn format_line<O: EstimatorOutput>(
    row: &Row<O>,
    axes: Axes,
    format_errors: &mut u64,
    emit: &mut impl FnMut(&str),
) {
    let mut line = CsvLine::new();
    let ok = crate::csv::write_row(&mut line, row, axes).is_ok() && line.push('\n').is_ok();
    if ok {
        emit(line.as_str());
    } else {
        *format_errors = format_errors.saturating_add(1);
    }
}
