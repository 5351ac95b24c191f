//! The firmware's output as defmt messages: no text formatting on the MCU.
//!
//! * [`header`]: once per run, the estimated axes (`AXES`, as a bit mask roll=1, pitch=2,
//!   yaw=4) and the bank's channel names (its CSV columns, e.g. `ilo1_v,kf_a`), preceded by
//!   `body_rate` when the rows carry the body rates (feature `no-reference`,
//!   `nav440_pipeline::RateColumn::header_names`); the host writes the CSV header line of
//!   `nav440 estimate --bank ... --axis ... [--no-reference]` from them.
//! * [`row`]: one message per sample, `row {=[u8]}`: one packed byte payload (little-endian),
//!   the sample time (u64, us since the first sample), then per estimated axis (roll, pitch,
//!   yaw order) [`AXIS_BYTES`] bytes: a flag byte (bit 0: a reference rate is present; bit 1,
//!   [`NO_ESTIMATE`]: the axis has no estimate in this row, near gimbal lock, and the rest of
//!   the block is 0), the
//!   unwrapped angle (deg, f32), its f64 residual (deg, 0 while f32 holds the angle), the
//!   rate column (Euler reference or body rate, deg/s, f32; 0 when absent) and the bank's
//!   channel values (in the order of
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
//!
//! With the feature `uart-rows` the header and every row also go out of the board's rows UART
//! (UART2 on the mps2 boards) as framed binary messages ([`nav440_pipeline::wire`]: postcard in
//! COBS frames): a delimiter and the header frame first, then one frame per row, and the header
//! again every [`HEADER_EVERY_ROWS`] rows, so that a reader joining the stream finds it. `nav440
//! rows` turns them into the same CSV (docs/UART-ROWS.md).

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

/// The rate column's marker (none for the Euler reference) and the bank's channel names.
const NAMES: &[&[&str]] = &[
    <crate::pipeline::Reference as nav440_pipeline::Reference>::COLUMN.header_names(),
    <Output as EstimatorOutput>::CHANNEL_NAMES,
];
/// [`NAMES`] joined with `,` (the CSV columns), built at compile time.
const COLUMN_BYTES: [u8; estimators::columns_len(NAMES)] = estimators::join_columns(NAMES);
/// [`COLUMN_BYTES`] as text.
const COLUMNS: &str = match core::str::from_utf8(&COLUMN_BYTES) {
    Ok(s) => s,
    Err(_) => panic!("the channel names are not UTF-8"),
};

/// Sends the header message: the axes of the rows (bit mask roll=1, pitch=2, yaw=4) and the
/// bank's channel names (its CSV columns, comma-separated), after `body_rate` for rows with
/// the body rates.
pub fn header() {
    let mut mask = 0u8;
    for a in AXES.iter() {
        mask |= 1 << a.index();
    }
    defmt::println!("header {=u8} {=str}", mask, COLUMNS);
    #[cfg(feature = "uart-rows")]
    {
        crate::board::rows_write(&[nav440_pipeline::wire::DELIMITER]);
        rows::header();
    }
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
    #[cfg(feature = "uart-rows")]
    rows::row(r);
}

/// The header frame is sent again after this many row frames (feature `uart-rows`).
#[cfg(feature = "uart-rows")]
pub const HEADER_EVERY_ROWS: u32 = 100;

/// The rows' output UART (feature `uart-rows`): the frames and their counters.
#[cfg(feature = "uart-rows")]
mod rows {
    use super::{Output, AXES, COLUMNS, HEADER_EVERY_ROWS};
    use core::sync::atomic::{AtomicU32, Ordering};
    use estimators::EstimatorOutput;
    use nav440_pipeline::wire::{self, Header, Message, RowFrame};
    use nav440_pipeline::Row;

    /// The longest frame: a row's ([`wire::max_row_frame_bytes`]) or the header's (its columns,
    /// a few bytes of fields, COBS's overhead and the delimiter).
    const FRAME_BYTES: usize = {
        let row = wire::max_row_frame_bytes(AXES.len(), <Output as EstimatorOutput>::CHANNELS);
        let header = COLUMNS.len() + 8 + COLUMNS.len().div_ceil(254) + 1;
        if row > header {
            row
        } else {
            header
        }
    };

    /// Frames sent, bytes sent, frames that did not encode (0: the buffer fits every frame).
    static FRAMES: AtomicU32 = AtomicU32::new(0);
    static BYTES: AtomicU32 = AtomicU32::new(0);
    static ENCODE_ERRORS: AtomicU32 = AtomicU32::new(0);
    /// Row frames since the last header frame.
    static SINCE_HEADER: AtomicU32 = AtomicU32::new(0);

    /// Single-core increment that works on thumbv6m (no atomic read-modify-write); only the
    /// main thread sends.
    fn add(c: &AtomicU32, n: u32) {
        c.store(c.load(Ordering::Relaxed).wrapping_add(n), Ordering::Relaxed);
    }

    fn send(m: &Message<'_>) {
        let mut buf = [0u8; FRAME_BYTES];
        match wire::encode(m, &mut buf) {
            Ok(frame) => {
                crate::board::rows_write(frame);
                add(&FRAMES, 1);
                add(&BYTES, frame.len() as u32);
            }
            Err(_) => add(&ENCODE_ERRORS, 1),
        }
    }

    /// The header frame.
    pub(super) fn header() {
        send(&Message::Header(Header::new(AXES, COLUMNS)));
        SINCE_HEADER.store(0, Ordering::Relaxed);
    }

    /// One row's frame (and the header after [`HEADER_EVERY_ROWS`] rows).
    pub(super) fn row(r: &Row<Output>) {
        if SINCE_HEADER.load(Ordering::Relaxed) >= HEADER_EVERY_ROWS {
            header();
        }
        send(&Message::Row(RowFrame::from_row(r, AXES)));
        add(&SINCE_HEADER, 1);
    }

    /// The counters line of the rows UART.
    pub(super) fn summary() {
        defmt::println!(
            "firmware: uart rows: rows_frames={=u32} rows_bytes={=u32} rows_encode_errors={=u32}",
            FRAMES.load(Ordering::Relaxed),
            BYTES.load(Ordering::Relaxed),
            ENCODE_ERRORS.load(Ordering::Relaxed)
        );
    }
}

/// Sends the counters line ([`nav440_pipeline::report::summary`], the same in every firmware)
/// of `pipe` with `uart`'s overruns and stalls, `unit_bytes` (bytes the unit sent, or received
/// so far) and the stack's high-water mark ([`crate::stack::peak`]).
pub fn summary(pipe: &crate::pipeline::Pipeline, uart: &crate::uart::Uart0, unit_bytes: u64) {
    #[cfg(feature = "uart-rows")]
    rows::summary();
    nav440_pipeline::report::summary(
        pipe,
        uart.overruns(),
        uart.stalls(),
        unit_bytes,
        crate::stack::peak(),
    );
}
