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
//! * diagnostics and counters: `firmware: ...` messages (see `main.rs`).
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

/// Sends the header message: the axes of the rows (bit mask roll=1, pitch=2, yaw=4) and the
/// bank's channel names (its CSV columns, comma-separated).
pub fn header() {
    let mut mask = 0u8;
    for a in AXES.iter() {
        mask |= 1 << a.index();
    }
    defmt::println!(
        "header {=u8} {}",
        mask,
        <Output as EstimatorOutput>::CSV_COLUMNS
    );
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

/// The count of period changes of `pipe` (`nav440_pipeline::Counters::period_changes`), to
/// hand to [`period_change`] after the next feed.
pub fn period_changes(pipe: &crate::pipeline::Pipeline) -> u32 {
    pipe.estimation().counters().period_changes
}

/// Reports a new time epoch at another packet rate while it happens (a unit reset or re-boot
/// at another rate: the pipeline measured the period on the epoch's first samples and rebuilt
/// the banks for it) when `pipe`'s count has moved past `before` ([`period_changes`]).
pub fn period_change(pipe: &crate::pipeline::Pipeline, before: u32) {
    if period_changes(pipe) != before {
        defmt::println!(
            "firmware: new time epoch at another packet rate: nominal sample period now {=u32} us; banks rebuilt",
            pipe.estimation().period_s().map_or(0, |p| (p * 1e6) as u32)
        );
    }
}

/// Sends the end-of-run counters: the `key=value` line of `nav440_pipeline::Pipeline::summary`
/// (same keys, same order) followed by `unit_bytes` and `stack_peak` (bytes).
pub fn summary(
    pipe: &crate::pipeline::Pipeline,
    uart_overruns: u32,
    uart_stalls: u32,
    unit_bytes: u64,
    stack_peak: usize,
) {
    let s = pipe.front().parser_stats();
    let fc = pipe.front().counters();
    let c = pipe.estimation().counters();
    let f = pipe.front().time_faults();
    defmt::println!(
        "firmware: bytes={=u64} frames={=u64} crc_errors={=u64} skipped={=u64} decode_errors={=u64} samples={=u64} rows={=u64} rejected={=u64} format_errors={=u64} uart_overruns={=u32} uart_stalls={=u32} yaw_packets={=u64} impossible={=u32} bad_backward={=u32} bad_forward={=u32} backward_jumps={=u32} kind_switches={=u32} other_kind={=u32} duplicates={=u32} gaps={=u32} near_lock={=u64} lock_passes={=u32} bit_failed={=u64} bit_flag={=str} bit_hardware_error={=u64} bit_com_error={=u64} bit_software_error={=u64} bit_last=0x{=u16:04x} unit_bytes={=u64} stack_peak={=usize}",
        s.bytes,
        s.frames,
        s.crc_errors,
        s.skipped_bytes,
        fc.decode_errors,
        c.samples,
        c.rows,
        c.rejected.total(),
        pipe.format_errors(),
        uart_overruns,
        uart_stalls,
        fc.attitude_packets,
        f.impossible,
        f.bad_backward,
        f.bad_forward,
        f.backward_jumps,
        f.kind_switches,
        f.other_kind,
        f.duplicates,
        c.gaps,
        c.near_lock,
        c.lock_passes,
        fc.bit.failed,
        nav440_pipeline::bit::FAILURE_FLAG,
        fc.bit.hardware_error,
        fc.bit.com_error,
        fc.bit.software_error,
        fc.bit.last_word,
        unit_bytes,
        stack_peak
    );
}
