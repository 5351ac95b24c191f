//! The firmware's output as defmt messages: no text formatting on the MCU.
//!
//! * [`header`]: once per run, the estimated axes (`AXES`, as a bit mask roll=1, pitch=2,
//!   yaw=4) and the bank's channel names (its CSV columns, e.g. `ilo1_v,kf_a`); the host writes
//!   the CSV header line of `nav440 estimate --bank ... --axis ...` from them.
//! * [`row`]: one message per sample, `row {=[u8]}`: one packed byte payload (little-endian),
//!   the sample time (u64, us since the first sample), then per estimated axis (roll, pitch,
//!   yaw order) [`AXIS_BYTES`] bytes: a flag byte (bit 0: a reference rate is present; bit 1,
//!   [`NO_ESTIMATE`]: the axis has no estimate in this row, near gimbal lock, and the rest of
//!   the block is 0), the
//!   unwrapped angle (deg, f32), its f64 residual (deg, 0 while f32 holds the angle), the
//!   reference rate (deg/s, f32; 0 when absent) and the bank's channel values (in the order of
//!   its names, f32: 14 for the paper bank, 2 for the product bank). One argument, so the transport gets one write for the
//!   whole payload (one semihosting call instead of one per value).
//! * [`summary`]: the counters line; it and the other diagnostics, the stream watchdog's
//!   included, are the `firmware: ...` messages of `nav440_pipeline::report`, shared with the
//!   embassy firmware (see `main.rs`).
//!
//! The host (`cargo xtask qemu/demo/unit`, through `defmt-decoder` and the ELF's defmt table)
//! turns each `row` message back into the exact `f32`/`f64` bits and formats the line with
//! `nav440_pipeline::csv`, so the CSV equals `nav440 estimate`'s byte for byte.
//!
//! Transport: `defmt-semihosting` (frames on the semihosting stdout) on the emulated boards,
//! `defmt-rtt` on the real board (`board-stm32f405` without `semihosting-log`), read by
//! probe-rs.

use crate::pipeline::AXES;
use crate::{Bank, Output};
use estimators::{EstimatorBank, EstimatorOutput};
use nav440_pipeline::{AxisRow, Row};

/// Marker of the row message (the host finds it in the ELF's defmt table).
pub const ROW_TAG: &str = "row";

/// Flag bit of an axis block: no estimate for the axis in this row (roll and yaw while the
/// pitch is at or beyond the gimbal-lock limit, `nav440_pipeline::euler::near_lock`).
pub const NO_ESTIMATE: u8 = 2;

/// Bytes of one axis in a [`row`] payload: flags (1), angle (f32), residual (f64), reference
/// rate (f32), the channel values (f32 each).
pub const AXIS_BYTES: usize = 1 + 4 + 8 + 4 + 4 * <Bank as EstimatorBank>::CHANNELS;

/// Bytes of a [`row`] payload with the axes of [`AXES`]: the time (u64) and one
/// [`AXIS_BYTES`] block per axis.
pub const ROW_BYTES: usize = 8 + AXIS_BYTES * AXES.len();

/// Copies `v` to `dst[at..]` (constant offsets: no bounds check left after inlining).
#[inline(always)]
fn put<const N: usize>(dst: &mut [u8; AXIS_BYTES], at: usize, v: [u8; N]) {
    dst[at..at + N].copy_from_slice(&v);
}

/// Packs one axis (see the module doc for the layout).
#[inline(always)]
fn put_axis(dst: &mut [u8; AXIS_BYTES], a: &AxisRow<Output>) {
    let o = &a.out;
    dst[0] = u8::from(a.reference_deg_s.is_some());
    put(dst, 1, o.unwrapped_deg().to_le_bytes());
    put(dst, 5, o.residual_deg().to_le_bytes());
    put(dst, 13, a.reference_deg_s.unwrap_or(0.0).to_le_bytes());
    for (i, v) in o.values().iter().enumerate() {
        put(dst, 17 + 4 * i, v.to_le_bytes());
    }
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

/// Sends the header message: the axes of the rows (bit mask roll=1, pitch=2, yaw=4) and the
/// bank's channel names (its CSV columns, comma-separated).
pub fn header() {
    let mut mask = 0u8;
    for a in AXES.iter() {
        mask |= 1 << a.index();
    }
    defmt::println!("header {=u8} {=str}", mask, COLUMNS);
}

/// Sends one sample's row message: one block per axis of [`AXES`], [`NO_ESTIMATE`] for an
/// axis the row has no estimate for.
pub fn row(r: &Row<Output>) {
    let mut buf = [0u8; ROW_BYTES];
    let (time, rest) = buf.split_at_mut(8);
    time.copy_from_slice(&r.t_us.to_le_bytes());
    let (blocks, _) = rest.as_chunks_mut::<AXIS_BYTES>();
    for (dst, axis) in blocks.iter_mut().zip(AXES.iter()) {
        match r.axis(axis) {
            Some(a) => put_axis(dst, a),
            None => dst[0] = NO_ESTIMATE,
        }
    }
    defmt::println!("row {=[u8]}", &buf[..]);
}

/// Sends the counters line ([`nav440_pipeline::report::summary`], the same in every firmware)
/// of `pipe` with `uart`'s overruns and stalls, `unit_bytes` (bytes the unit sent, or received
/// so far) and the stack's high-water mark ([`crate::stack::peak`]).
pub fn summary(pipe: &crate::pipeline::Pipeline, uart: &crate::uart::Uart0, unit_bytes: u64) {
    nav440_pipeline::report::summary(
        pipe,
        uart.overruns(),
        uart.stalls(),
        unit_bytes,
        crate::stack::peak(),
    );
}
