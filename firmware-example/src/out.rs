//! The firmware's output as defmt messages: no text formatting on the MCU.
//!
//! * [`header`]: once per run, the estimated axes (`AXES`, as a bit mask roll=1, pitch=2,
//!   yaw=4), the number format of the rows ([`RowNumber::NAME`]: `f32`, or `fx` for the
//!   fixed-point banks' raw Q31.32 values) and the bank's channel names (its CSV columns, e.g.
//!   `ilo1_v,kf_a`), preceded by `body_rate` when the rows carry the body rates (feature
//!   `no-reference`, `nav440_pipeline::RateColumn::header_names`); the host writes the CSV
//!   header line of `nav440 estimate --bank ... --axis ... [--no-reference]` from them.
//! * [`row`]: one message per sample, `row {=[u8]}`: one byte payload of little-endian 32-bit
//!   words: the sample time (u64, us since the first sample, low word first), a flags word (one
//!   byte per axis of `AXES`, in roll, pitch, yaw order: bit 0, [`RATE`]: the rate column is
//!   present; bit 1, [`NO_ESTIMATE`]: the axis has no estimate in this row, near gimbal lock,
//!   and no block follows for it; bit 2, [`RESIDUAL`], or bit 3, [`TURNS`]: the block ends
//!   with a tail of two words), then per axis with an estimate a block, its numbers as the
//!   bank's output holds them ([`RowNumber`]):
//!   * `f32` rows: the unwrapped angle (deg, f32), the rate column (Euler reference or body
//!     rate, deg/s, f32; 0 when absent), the bank's channel values (in the order of its names,
//!     f32: 14 for the paper bank, 2 for the product bank) and, only while the f32 angle does
//!     not hold the angle exactly, its residual (deg, f64; [`RESIDUAL`]);
//!   * `fx` rows (`estimators::Fx` banks, the targets without an FPU): the wrapped angle (deg,
//!     Q31.32 raw bits, two words), the rate column (f32), the channel values (Q31.32, two
//!     words each) and, only after a turn, the unwrapper's turn count (i64; [`TURNS`]). The
//!     host rounds them as `nav440 estimate --fixed` does (`Real::output_value_f32`,
//!     `Real::output_angle_f32`): the device converts nothing.
//!
//!   The payload is packed in place in the logger's word-aligned buffer
//!   ([`crate::log::in_place`]), which hands the frame on without copying it: one write to
//!   the transport for the whole message (one semihosting call instead of one per value).
//! * [`summary`]: the counters line; it and the other diagnostics, the stream watchdog's
//!   included, are the `firmware: ...` messages of `nav440_pipeline::report`, shared with the
//!   embassy firmware (see `main.rs`).
//!
//! The host (`cargo xtask qemu/demo/unit`, through `defmt-decoder` and the ELF's defmt table)
//! turns each `row` message back into the exact `f32`/`f64` bits (rounding an `fx` row's raw
//! values as the host's fixed-point bank does) and formats the line with
//! `nav440_pipeline::csv`, so the CSV equals `nav440 estimate`'s byte for byte.
//!
//! Transport: the defmt global logger of [`crate::log`]: the semihosting stdout on the
//! emulated boards, RTT on the real boards, read by probe-rs.
//!
//! With the feature `uart-rows` the header and every row also go out of the board's rows UART
//! (UART2 on the mps2 boards) as framed binary messages ([`nav440_pipeline::wire`]: postcard in
//! COBS frames): a delimiter and the header frame first, then one frame per row, and the header
//! again every [`HEADER_EVERY_ROWS`] rows, so that a reader joining the stream finds it. `nav440
//! rows` turns them into the same CSV (docs/UART-ROWS.md).

use crate::pipeline::AXES;
use crate::{Bank, Num, Output};
use estimators::{EstimatorBank, EstimatorOutput, Fx, Real};
use nav440_pipeline::{AxisRow, Row};

/// Marker of the row message (the host finds it in the ELF's defmt table).
pub const ROW_TAG: &str = "row";

/// Flag bit of an axis: the rate column is present.
pub const RATE: u8 = 1;

/// Flag bit of an axis: no estimate for the axis in this row (roll and yaw while the pitch is
/// at or beyond the gimbal-lock limit, `nav440_pipeline::euler::near_lock`); no block follows.
pub const NO_ESTIMATE: u8 = 2;

/// Flag bit of an axis (`f32` rows): its block ends with the angle's f64 residual (not 0).
pub const RESIDUAL: u8 = 4;

/// Flag bit of an axis (`fx` rows): its block ends with the unwrapper's turn count (i64, not
/// 0).
pub const TURNS: u8 = 8;

/// How a row carries the bank's numbers ([`Num`]): what the bank's output holds
/// (`estimators::Real::OutputValue`, `OutputAngle`), as it holds it, so that the device
/// converts nothing.
pub trait RowNumber: Real {
    /// The number format's name in the header message: `f32` or `fx` (Q31.32).
    const NAME: &'static str;
    /// Words of one value: 1 (`f32` bits) or 2 (`Fx`'s raw bits, low word first).
    const WORDS: usize;
    /// Writes `v` at `w[..WORDS]`.
    fn put_value(v: Self::OutputValue, w: &mut [u32]);
    /// Writes the angle's words (`WORDS` of them) at `w`; returns the tail (residual or turn
    /// count, two words) and its flag when it is not 0.
    fn put_angle(a: Self::OutputAngle, w: &mut [u32]) -> Option<(u64, u8)>;
}

impl RowNumber for f32 {
    const NAME: &'static str = "f32";
    const WORDS: usize = 1;
    #[inline(always)]
    fn put_value(v: f32, w: &mut [u32]) {
        w[0] = v.to_bits();
    }
    #[inline(always)]
    fn put_angle((angle, residual): (f32, f64), w: &mut [u32]) -> Option<(u64, u8)> {
        w[0] = angle.to_bits();
        // Sent while its bits are not 0 (a -0.0 too: the host gets the very bits).
        let r = residual.to_bits();
        (r != 0).then_some((r, RESIDUAL))
    }
}

impl RowNumber for Fx {
    const NAME: &'static str = "fx";
    const WORDS: usize = 2;
    #[inline(always)]
    fn put_value(v: Fx, w: &mut [u32]) {
        let b = v.to_bits();
        w[0] = b as u32;
        w[1] = (b >> 32) as u32;
    }
    #[inline(always)]
    fn put_angle((turns, wrapped): (i64, Fx), w: &mut [u32]) -> Option<(u64, u8)> {
        Self::put_value(wrapped, w);
        (turns != 0).then_some((turns as u64, TURNS))
    }
}

/// Words of an axis block without its tail: the angle, the rate column, the channels.
pub const AXIS_WORDS: usize = Num::WORDS + 1 + Num::WORDS * <Bank as EstimatorBank>::CHANNELS;

/// Words of the longest [`row`] payload: the time, the flags, an [`AXIS_WORDS`] block and a
/// tail (2 words) per axis of [`AXES`].
pub const ROW_WORDS: usize = 3 + (AXIS_WORDS + 2) * AXES.len();

const _: () = assert!(AXES.len() <= 4, "one flags byte per axis in a word");
const _: () = assert!(
    cfg!(target_endian = "little"),
    "the payload's words are stored as they are in memory"
);

/// Packs one axis's block at `w[..]` (see the module doc); returns its flags and its words.
#[inline(always)]
fn put_axis(w: &mut [u32; AXIS_WORDS + 2], a: &AxisRow<Output>) -> (u8, usize) {
    let o = &a.out;
    let mut flags = 0;
    let tail = Num::put_angle(o.angle, &mut w[..Num::WORDS]);
    w[Num::WORDS] = match a.reference_deg_s {
        Some(v) => {
            flags |= RATE;
            v.to_bits()
        }
        None => 0,
    };
    for (d, &v) in w[Num::WORDS + 1..AXIS_WORDS]
        .chunks_exact_mut(Num::WORDS)
        .zip(o.values.iter())
    {
        Num::put_value(v, d);
    }
    let Some((t, flag)) = tail else {
        return (flags, AXIS_WORDS);
    };
    w[AXIS_WORDS] = t as u32;
    w[AXIS_WORDS + 1] = (t >> 32) as u32;
    (flags | flag, AXIS_WORDS + 2)
}

/// Packs a row's payload into `w` (see the module doc); returns its length in bytes.
#[inline(always)]
fn pack(r: &Row<Output>, w: &mut [u32; crate::log::PAYLOAD_WORDS]) -> usize {
    w[0] = r.t_us as u32;
    w[1] = (r.t_us >> 32) as u32;
    let mut flags = 0u32;
    let mut at = 3;
    for (i, axis) in AXES.iter().enumerate() {
        let f = match r.axis(axis) {
            Some(a) => {
                // `at` + a block with the residual stays within `ROW_WORDS`.
                let Some(block) = w
                    .get_mut(at..at + AXIS_WORDS + 2)
                    .and_then(|b| <&mut [u32; AXIS_WORDS + 2]>::try_from(b).ok())
                else {
                    break;
                };
                let (f, n) = put_axis(block, a);
                at += n;
                f
            }
            None => NO_ESTIMATE,
        };
        flags |= u32::from(f) << (8 * i);
    }
    w[2] = flags;
    4 * at
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
    defmt::println!("header {=u8} {=str} {=str}", mask, Num::NAME, COLUMNS);
    #[cfg(feature = "uart-rows")]
    {
        crate::board::rows_write(&[nav440_pipeline::wire::DELIMITER]);
        rows::header();
    }
}

/// Sends one sample's row message: a block per axis of [`AXES`] with an estimate,
/// [`NO_ESTIMATE`] in the flags of an axis without.
pub fn row(r: &Row<Output>) {
    crate::log::in_place(
        |w| pack(r, w),
        |payload| defmt::println!("row {=[u8]}", payload),
    );
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
