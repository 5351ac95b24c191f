//! The pipeline (product bank on the three axes) and its output as defmt messages.
//!
//! * [`header`]: `header {=str}`, the channels of each axis's block in a row.
//! * [`row`]: `row {=u64} {=[?]}`, the sample time (us since the first sample) and per axis
//!   (roll, pitch, yaw) the unwrapped angle (deg), the ILO1 velocity (deg/s) and the Kalman
//!   acceleration (deg/s^2): nine `f32`, NaN for an axis without an estimate in the row (roll
//!   and yaw near gimbal lock).
//! * [`counters`]: `firmware: counters parser=.. front=.. back=.. uart_errors=..`: the
//!   parser's statistics (`nav440_proto::Stats`), the front end's and the back end's counters
//!   (`nav440_pipeline::FrontCounters`, `nav440_pipeline::Counters`), each as its struct with
//!   every field, and the UART errors.

use estimators::{BankConfig, EstimatorBank, EstimatorOutput};
use nav440_pipeline::{Axes, Axis};

/// The bank of each axis: the product bank (ILO1 velocity + Kalman acceleration) in `f32`.
pub type Bank = estimators::ProductBank<f32>;

/// What the bank gives per sample.
pub type Output = <Bank as EstimatorBank>::Output;

/// One row of the pipeline.
pub type Row = nav440_pipeline::Row<Output>;

/// The bank constructor the pipeline calls after the warm-up.
type BuildFn = fn(Axis, &BankConfig) -> Result<Bank, estimators::ConfigError>;

/// The firmware's pipeline: one bank per axis.
pub type Pipeline = nav440_pipeline::Pipeline<Bank, estimators::ConfigError, BuildFn, 3>;

/// Values per axis in a [`row`] message: the angle and the bank's channels.
const AXIS_VALUES: usize = 1 + <Bank as EstimatorBank>::CHANNELS;

/// Builds an axis's bank for the measured packet period with the NAV440 preset's gains for
/// that period (`BankConfig::with_nav440_gains`, as `nav440 estimate --bank product` does).
/// Out of line: the constructor is large.
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, estimators::ConfigError> {
    nav440_pipeline::axis_bank(axis, &cfg.with_nav440_gains())
}

/// A pipeline with the NAV440 preset on all three axes (built in place).
#[inline(always)]
pub fn pipeline() -> Pipeline {
    Pipeline::with_slots(Axes::ALL, BankConfig::NAV440, build_bank)
}

/// Sends the header message: the channels of one axis's block.
pub fn header() {
    defmt::println!(
        "header angle_deg,{}",
        <Output as EstimatorOutput>::CSV_COLUMNS
    );
}

/// Sends one sample's row message (see the module doc).
pub fn row(r: &Row) {
    let mut v = [f32::NAN; 3 * AXIS_VALUES];
    for (block, axis) in v.chunks_exact_mut(AXIS_VALUES).zip(Axis::ALL) {
        if let Some(a) = r.axis(axis) {
            block[0] = a.out.unwrapped_deg();
            block[1..].copy_from_slice(a.out.values());
        }
    }
    defmt::println!("row {=u64} {=[?]}", r.t_us, &v[..]);
}

/// Sends the counters message (see the module doc).
pub fn counters(pipe: &Pipeline, uart_errors: u32) {
    defmt::println!(
        "firmware: counters parser={} front={} back={} uart_errors={=u32}",
        pipe.front().parser_stats(),
        pipe.front().counters(),
        pipe.estimation().counters(),
        uart_errors,
    );
}

/// Reports a new time epoch at another packet rate while it happens (the pipeline measured the
/// period on the epoch's first samples and rebuilt the banks for it) when `pipe`'s count of
/// period changes has moved past `before`: `firmware: new time epoch at another packet rate:
/// nominal sample period now N us; banks rebuilt`, as firmware-example prints it.
pub fn period_change(pipe: &Pipeline, before: u32) {
    if pipe.estimation().counters().period_changes != before {
        defmt::println!(
            "firmware: new time epoch at another packet rate: nominal sample period now {=u32} us; banks rebuilt",
            pipe.estimation().period_s().map_or(0, |p| (p * 1e6) as u32)
        );
    }
}
