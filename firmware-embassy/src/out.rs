//! The pipeline (product bank on the three axes) and its output as defmt messages.
//!
//! * [`header`]: `header {=str}`, the channels of each axis's block in a row.
//! * [`row`]: `row {=u64} {=[?]}`, the sample time (us since the first sample) and per axis
//!   (roll, pitch, yaw) the unwrapped angle (deg), the ILO1 velocity (deg/s) and the Kalman
//!   acceleration (deg/s^2): nine `f32`, NaN for an axis without an estimate in the row (roll
//!   and yaw near gimbal lock).
//!
//! The diagnostics and the counters are firmware-example's messages, from one implementation
//! (`nav440_pipeline::report`): the stream watchdog's faults, the period change, `counters
//! after N s of stream:` and the `key=value` counters line.

use estimators::{BankConfig, EstimatorBank, EstimatorOutput};
use nav440_pipeline::{Axes, Axis};

/// The bank of each axis: the product bank (ILO1 velocity + Kalman acceleration) in `f32`
/// whose gains follow the angle's measured noise and the motion's jerk (the product default,
/// `estimators::AdaptiveProductBank`; the pipeline gives it each row's rate about the axis).
pub type Bank = estimators::AdaptiveProductBank<f32>;

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

/// Builds an axis's bank for the measured packet period, starting with the NAV440 preset's
/// gains for that period (`BankConfig::with_nav440_gains`), as `nav440 estimate --bank
/// product` does. Out of line: the constructor is large.
#[inline(never)]
fn build_bank(axis: Axis, cfg: &BankConfig) -> Result<Bank, estimators::ConfigError> {
    nav440_pipeline::adaptive_product_axis_bank(axis, &cfg.with_nav440_gains())
}

/// A pipeline with the NAV440 preset on all three axes (built in place).
#[inline(always)]
pub fn pipeline() -> Pipeline {
    Pipeline::with_slots(Axes::ALL, BankConfig::NAV440, build_bank)
}

/// The bank's channel names.
const NAMES: &[&[&str]] = &[<Output as EstimatorOutput>::CHANNEL_NAMES];
/// [`NAMES`] joined with `,` (the CSV columns), built at compile time.
const COLUMN_BYTES: [u8; estimators::columns_len(NAMES)] = estimators::join_columns(NAMES);
/// [`COLUMN_BYTES`] as text.
const COLUMNS: &str = match core::str::from_utf8(&COLUMN_BYTES) {
    Ok(s) => s,
    Err(_) => panic!("the channel names are not UTF-8"),
};

/// Sends the header message: the channels of one axis's block.
pub fn header() {
    defmt::println!("header angle_deg,{=str}", COLUMNS);
}

/// Sends one sample's row message (see the module doc).
pub fn row(r: &Row) {
    let mut v = [f32::NAN; 3 * AXIS_VALUES];
    for (block, axis) in v.chunks_exact_mut(AXIS_VALUES).zip(Axis::ALL) {
        if let Some(a) = r.axis(axis) {
            block[0] = a.out.unwrapped_deg();
            for (d, v) in block[1..].iter_mut().zip(a.out.values()) {
                *d = v;
            }
        }
    }
    defmt::println!("row {=u64} {=[?]}", r.t_us, &v[..]);
}
