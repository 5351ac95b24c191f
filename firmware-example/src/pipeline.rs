//! The firmware's pipeline: `nav440_pipeline::Pipeline` (the one pipeline `nav440 estimate`
//! runs too) with the firmware's bank type ([`crate::Bank`]) on the axes [`AXES`] selects.
//!
//! bytes -> parser -> attitude packets -> BIT check -> `TimeBase` -> warm-up/period rule ->
//! one bank per axis (`BankConfig::NAV440`: h = 1e-4 s, linear hold, gains tuned for the packet rate) -> one CSV row per
//! sample, formatted by `nav440_pipeline::csv` exactly as the host does. See
//! docs/PIPELINE.md and docs/RELIABILITY.md.
//!
//! Each row's rate column is [`Reference`]'s: the Euler reference rate by default, the body
//! rates with the feature `no-reference` (no trigonometry linked).

use estimators::BankConfig;
pub use nav440_pipeline::{Axes, Axis, CsvLine, ROW_CAPACITY};

use crate::Bank;

/// The axes the firmware estimates (all three by default; one bank each). `nav440 estimate
/// --axis all` prints the same CSV for [`Axes::ALL`]; for one axis use `--axis NAME`.
#[cfg(not(feature = "one-axis"))]
pub const AXES: Axes = Axes::ALL;
/// The axes the firmware estimates: yaw only (feature `one-axis`; `nav440 estimate --axis
/// yaw` prints the same CSV).
#[cfg(feature = "one-axis")]
pub const AXES: Axes = Axes::only(Axis::Yaw);

/// The bank could not be built (from the defaults, or for the measured packet period).
pub type ConfigError = estimators::ConfigError;

/// The configuration the banks run for the measured packet period's `cfg`: with
/// [`FOLLOW_RATE`], the shipped preset's gains for that period (`BankConfig::with_nav440_gains`,
/// as `nav440 estimate` does); else `cfg`.
#[cfg(any(
    follow_gains,
    feature = "self-tune",
    not(any(feature = "adaptive-gains", prebuilt_banks))
))]
fn at_rate(cfg: &BankConfig) -> BankConfig {
    if FOLLOW_RATE {
        cfg.with_nav440_gains()
    } else {
        *cfg
    }
}

/// Builds an axis's bank for the measured packet period (out of line: the constructor is
/// large): with [`FOLLOW_RATE`], the shipped preset's gains for that period
/// (`BankConfig::with_nav440_gains`, as `nav440 estimate` does).
#[cfg(not(any(
    feature = "adaptive-gains",
    follow_gains,
    feature = "self-tune",
    prebuilt_banks
)))]
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, ConfigError> {
    nav440_pipeline::axis_bank(axis, &at_rate(cfg))
}

/// Builds an axis's following product bank (`bank-product` alone, or `follow`) for the measured packet period:
/// with [`FOLLOW_RATE`], starting with the shipped preset's gains for that period, as `nav440
/// estimate --bank product --follow` does (`nav440_pipeline::adaptive_product_axis_bank`).
#[cfg(follow_gains)]
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, ConfigError> {
    nav440_pipeline::adaptive_product_axis_bank(axis, &at_rate(cfg))
}

/// Builds an axis's self-tuning product bank (feature `self-tune`) for the measured packet
/// period: ILO1 at `estimators::SelfTuneConfig::DEFAULT`'s start, the Kalman with the shipped
/// preset's gains for that period ([`FOLLOW_RATE`]), as `nav440 estimate --bank product
/// --self-tune` does (`nav440_pipeline::self_tuning_product_axis_bank`).
#[cfg(feature = "self-tune")]
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, ConfigError> {
    nav440_pipeline::self_tuning_product_axis_bank(axis, &at_rate(cfg))
}

/// The banks build.rs built on the host for the product images with the shipped preset
/// (`banks.rs` in `OUT_DIR`, see `prebuilt_banks` in build.rs), in the image's number type.
#[cfg(prebuilt_banks)]
mod prebuilt {
    include!(concat!(env!("OUT_DIR"), "/banks.rs"));
}

/// An axis's bank for the measured packet period, read back from the table build.rs built on
/// the host ([`prebuilt`]: the bank [`PRESET`] with [`FOLLOW_RATE`] gives, for each NAV440
/// packet rate): integer operations only, no floating-point construction linked. A period
/// that is not one of the NAV440's rates is [`ConfigError::SamplePeriodNotPrebuilt`] (the
/// firmware reports it and stops, docs/FOOTPRINT.md); `nav440 estimate` builds a bank for
/// any period.
#[cfg(prebuilt_banks)]
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, ConfigError> {
    let key = cfg.sample_period_s.to_bits();
    let (_, bytes) = prebuilt::BANKS
        .iter()
        .find(|(k, _)| *k == key)
        .ok_or(ConfigError::SamplePeriodNotPrebuilt)?;
    // Cannot fail: the bytes are the words of this very type (build.rs).
    let mut rest: &[u8] = bytes;
    let mut next = || {
        let (w, r) = postcard::take_from_bytes::<i64>(rest).ok()?;
        rest = r;
        Some(w)
    };
    let mut bank = Bank::from_words(&mut next);
    // The table holds the banks of the axes that wrap; the others unwrap nothing.
    if let (Some(b), false) = (&mut bank, axis.wraps()) {
        b.set_wrap(estimators::Wrap::None);
    }
    bank.ok_or(ConfigError::SamplePeriodNotPrebuilt)
}

/// The gain schedule of the noise-adaptive bank (feature `adaptive-gains`), as `nav440 tune
/// --schedule 0.001,0.01,0.1,0.5,1 --rust` wrote it (`src/gains/schedule_fig5.rs`, the twin of
/// the `host-tests/data/gains/schedule_fig5.toml` that `nav440 estimate --gains` reads;
/// `host-tests/tests/schedule.rs` checks the two agree). Its hold is
/// [`PRESET`]'s (linear; the file's header names the hold it was tuned with).
#[cfg(feature = "adaptive-gains")]
#[allow(missing_docs)] // generated file: its constant is documented at the `pub use` below
mod schedule {
    include!("gains/schedule_fig5.rs");
}
/// The schedule's levels (noise variance, deg^2 -> velocity and acceleration gains), the
/// nominal sample period they were tuned at (s) and the jerk and acceleration powers of the
/// motion they were tuned on ((deg/s^3)^2 and (deg/s^2)^2: the bank follows the motion too,
/// docs/MOTION-FAMILY.md).
#[cfg(feature = "adaptive-gains")]
pub use schedule::{SCHEDULE, SCHEDULE_PERIOD_S, SCHEDULE_TUNED_ACCELERATION, SCHEDULE_TUNED_JERK};

/// Builds an axis's noise-adaptive bank (out of line: the constructor is large). A schedule
/// tuned at another packet rate than the measured one still runs, with a warning line
/// (`estimators::AdaptiveBank::period_fits`; `nav440 estimate --gains` warns the same way).
#[cfg(feature = "adaptive-gains")]
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, ConfigError> {
    let schedule = estimators::GainSchedule::new(&SCHEDULE)?.with_records(
        SCHEDULE_PERIOD_S,
        SCHEDULE_TUNED_JERK,
        SCHEDULE_TUNED_ACCELERATION,
    )?;
    let bank = nav440_pipeline::adaptive_axis_bank(axis, cfg, &schedule)?;
    if !bank.period_fits() {
        defmt::println!(
            "firmware: warning: {=str}: the gain schedule was tuned at a sample period of {=f32} s, the unit's is {=f32} s: tune a schedule at this rate (docs/CALIBRATION.md, Low packet rates)",
            axis.name(),
            SCHEDULE_PERIOD_S.unwrap_or(0.0),
            cfg.sample_period_s
        );
    }
    Ok(bank)
}

/// The bank constructor the pipeline calls after the warm-up.
pub type BuildFn = fn(Axis, &BankConfig) -> Result<Bank, ConfigError>;

/// Bank slots of the firmware's pipeline: one per axis of [`AXES`] (RAM: one bank with
/// `one-axis` instead of three).
pub const BANK_SLOTS: usize = AXES.len();

/// The rows' rate column: the Euler reference rate (`<axis>_rate`, the default).
#[cfg(not(feature = "no-reference"))]
pub type Reference = nav440_pipeline::EulerReference;
/// The rows' rate column (feature `no-reference`): the unit's body rate about each axis
/// (`<axis>_body_rate`, deg/s as sent; `nav440 estimate --no-reference` prints the same CSV).
#[cfg(feature = "no-reference")]
pub type Reference = nav440_pipeline::BodyRates;

/// The packets the front end decodes: every type (the default), as `nav440 estimate` does.
#[cfg(not(feature = "only-a2"))]
pub type Decoder = nav440_pipeline::AllPackets;
/// The packets the front end decodes (feature `only-a2`): A2 only, the type the firmware
/// configures (`TARGET`); another type's frames are not estimated from.
#[cfg(feature = "only-a2")]
pub type Decoder = nav440_pipeline::OnlyA2;

/// The firmware's pipeline with the rate column `R` (the bench measures both).
pub type PipelineWith<R> =
    nav440_pipeline::Pipeline<Bank, ConfigError, BuildFn, BANK_SLOTS, R, Decoder>;

/// The firmware's pipeline.
pub type Pipeline = PipelineWith<Reference>;

/// The bank preset the firmware runs: the one `nav440 estimate` runs by default
/// (`BankConfig::NAV440`; the paper's presets are `BankConfig::PAPER`, `nav440 estimate
/// --preset paper`).
#[cfg(not(feature = "tuned-gains"))]
pub const PRESET: BankConfig = BankConfig::NAV440;

/// Gains tuned for the product bank by `nav440 tune --bank product --rust` (feature
/// `tuned-gains`): `src/gains/product_fig5.rs`, the twin of the
/// `host-tests/data/gains/product_fig5.toml` that `nav440 estimate --bank product --gains`
/// reads (`host-tests/tests/gains_snippet.rs` checks the two agree).
#[cfg(feature = "tuned-gains")]
#[allow(missing_docs)] // generated file: its constant is documented at the `PRESET` below
mod tuned {
    include!("gains/product_fig5.rs");
}
/// The bank preset the firmware runs (feature `tuned-gains`): the tuned gains at every
/// packet rate ([`FOLLOW_RATE`] is `false`).
#[cfg(feature = "tuned-gains")]
pub const PRESET: BankConfig = tuned::TUNED;

/// Whether the banks run the shipped preset's gains for the unit's measured packet rate
/// (`BankConfig::NAV440_RATES`) instead of [`PRESET`]'s own: `true` for the NAV440 preset,
/// whose gains are a table per packet rate; `false` runs fixed gains (e.g.
/// `BankConfig::PAPER` or `nav440 tune --rust` output, as the feature `tuned-gains` does) at
/// every rate. The `adaptive-gains` banks take their gains from the schedule.
pub const FOLLOW_RATE: bool = !cfg!(feature = "tuned-gains");

/// Checks once, at start, that [`PRESET`] builds, so that a bad configuration fails at start.
/// Out of line, so the bank it builds is not in the frame of `main`, which every other call
/// stacks on.
#[inline(never)]
pub fn check() -> Result<(), ConfigError> {
    build_bank(Axis::Yaw, &PRESET).map(|_| ())
}

/// A pipeline with [`PRESET`] (see [`check`]). Infallible, so that the caller's binding is
/// built in place (no second, pipeline-sized `Result` on the stack; the back end's
/// constructor is out of line for the same reason, see `Estimation::with_slots`).
#[inline(always)]
pub fn new() -> Pipeline {
    new_with()
}

/// [`new`] with the rate column `R` instead of [`Reference`].
#[inline(always)]
pub fn new_with<R: nav440_pipeline::Reference>() -> PipelineWith<R> {
    PipelineWith::with_slots(AXES, PRESET, build_bank)
}

/// Writes the CSV header line of [`AXES`] (without line terminator).
pub fn write_header(w: &mut impl core::fmt::Write) -> core::fmt::Result {
    nav440_pipeline::csv::write_header_for::<crate::Output>(
        w,
        AXES,
        <Reference as nav440_pipeline::Reference>::COLUMN,
    )
}
