//! Decoding the firmware's defmt output (`firmware-example/src/out.rs`) into text: the CSV of
//! `nav440 estimate` (formatted here by `nav440_pipeline::csv`, exactly as the host CLI does)
//! on stdout, the `firmware: ...` diagnostics and counters on stderr.
//!
//! The frames are decoded with `defmt-decoder` from the ELF's defmt table, here ([`Stream`],
//! [`decode_frames`]: QEMU's semihosting output, a saved RTT log) or by probe-rs, which prints
//! each message as text ([`decode_lines`]: `cargo xtask flash`, a saved probe-rs log); either
//! way each message goes through one [`Converter`]. A `row` message
//! carries one byte payload of little-endian 32-bit words (`firmware-example/src/out.rs`): the
//! sample time (u64, us), a flags word (a byte per estimated axis), then per axis with an
//! estimate a block whose numbers are in the format the header names: `f32` rows carry the
//! angle (f32), the rate column (f32: the Euler reference rate, or the body rate when the
//! header names `body_rate`), the bank's channel values (f32) and, when its flags say so, the
//! angle's f64 residual; `fx` rows (the fixed-point banks) the wrapped angle (Q31.32 raw
//! bits), the rate column (f32), the channel values (Q31.32) and, when its flags say so, the
//! turn count (i64), which are rounded here as `nav440 estimate --fixed` rounds them
//! (`estimators::Real::output_angle_f32`, `output_value_f32`). The values are rebuilt from
//! their bytes, so they are the exact bits the firmware's bank computed, and written by
//! `nav440_pipeline::wire::Layout`, as `nav440 rows` writes the rows of the firmware's output
//! UART.

use defmt_decoder::{DecodeError, StreamDecoder, Table};
use estimators::{Fx, Real};
use nav440_pipeline::wire::{AxisFrame, Layout, LayoutError, RowFrame};
use std::path::Path;

/// The format string of the firmware's row message.
const ROW_FORMAT: &str = "row {=[u8]}";

/// The defmt table of `elf` if that firmware sends its output as defmt rows (the firmware
/// binary); `None` for images with text output (bench, embassy example, panic check).
pub fn table(elf: &Path) -> Result<Option<Table>, String> {
    let bytes = std::fs::read(elf).map_err(|e| format!("{}: {e}", elf.display()))?;
    let table =
        Table::parse(&bytes).map_err(|e| format!("{}: bad defmt table: {e}", elf.display()))?;
    Ok(table.filter(|t| t.raw_symbols().any(|s| s.contains(ROW_FORMAT))))
}

/// Turns decoded messages into CSV text and diagnostic lines.
#[derive(Default)]
pub struct Converter {
    /// The rows' axes and bank, from the header message (`nav440_pipeline::wire::Layout`, which
    /// also writes the rows of the firmware's output UART for `nav440 rows`).
    layout: Option<Layout>,
    /// The rows carry raw `Fx` values (the header's number format `fx`), not `f32`.
    fx: bool,
}

/// What a chunk of frames gave.
#[derive(Default)]
pub struct Text {
    /// CSV lines (header and rows), each ending in `\n`.
    pub csv: String,
    /// Other messages (diagnostics, counters), one line each.
    pub diag: String,
}

impl Converter {
    /// Converts one decoded message (the text of `Frame::display_message`).
    pub fn message(&mut self, msg: &str, out: &mut Text) -> Result<(), String> {
        if let Some(rest) = msg.strip_prefix("header ") {
            let bad = || format!("bad header message `{msg}`");
            // `header MASK NUMBER COLUMNS`
            let mut parts = rest.trim().splitn(3, ' ');
            let (Some(mask), Some(number), Some(columns)) =
                (parts.next(), parts.next(), parts.next())
            else {
                return Err(bad());
            };
            let mask: u8 = mask.parse().map_err(|_| bad())?;
            let fx = match number {
                "f32" => false,
                "fx" => true,
                _ => return Err(format!("unknown number format `{number}` in `{msg}`")),
            };
            let layout = Layout::from_parts(mask, columns).map_err(|e| match e {
                LayoutError::UnknownBank => format!(
                    "the firmware runs a bank this decoder does not know (channels `{columns}`)"
                ),
                e => format!("{e}: `{msg}`"),
            })?;
            self.fx = fx;
            layout
                .write_header(&mut out.csv)
                .map_err(|_| "header".to_owned())?;
            out.csv.push('\n');
            self.layout = Some(layout);
        } else if let Some(rest) = msg.strip_prefix("row ") {
            let layout = self
                .layout
                .ok_or_else(|| format!("row before the header: `{msg}`"))?;
            let bad = || format!("bad row message `{msg}`");
            let row = parse_row(rest, &layout, self.fx).ok_or_else(bad)?;
            layout
                .write_row(&mut out.csv, &row)
                .map_err(|e| format!("{e}: `{msg}`"))?;
            out.csv.push('\n');
        } else {
            out.diag.push_str(msg);
            out.diag.push('\n');
        }
        Ok(())
    }
}

/// Flag bit of an axis: the rate column is present (the firmware's `out::RATE`).
const RATE: u8 = 1;

/// Flag bit of an axis: the axis has no estimate in the row, and no block follows for it (the
/// firmware's `out::NO_ESTIMATE`).
const NO_ESTIMATE: u8 = 2;

/// Flag bit of an axis (`f32` rows): its block ends with the angle's f64 residual (the
/// firmware's `out::RESIDUAL`).
const RESIDUAL: u8 = 4;

/// Flag bit of an axis (`fx` rows): its block ends with the turn count (the firmware's
/// `out::TURNS`).
const TURNS: u8 = 8;

/// Parses `[B, B, ...]` (the display of a row message's byte payload after `row `) into the
/// row's values (`fx`: the blocks carry raw `Fx` values).
fn parse_row(s: &str, layout: &Layout, fx: bool) -> Option<RowFrame> {
    let list = s.trim().strip_prefix('[')?.strip_suffix(']')?;
    let bytes = list
        .split(", ")
        .map(|b| b.parse::<u8>().ok())
        .collect::<Option<Vec<u8>>>()?;
    let channels = layout.bank.channels();
    let t = u64::from_le_bytes(take(&bytes, 0)?);
    let flags: [u8; 4] = take(&bytes, 8)?;
    let mut at = 12;
    let mut axes = heapless::Vec::new();
    for &f in flags.get(..layout.axes.len())? {
        // Flag bit 1: the axis has no estimate in this row (roll and yaw near gimbal lock).
        let axis = if f & NO_ESTIMATE != 0 {
            None
        } else {
            let (axis, n) = parse_axis(bytes.get(at..)?, f, channels, fx)?;
            at += n;
            Some(axis)
        };
        axes.push(axis).ok()?;
    }
    if at != bytes.len() || flags[layout.axes.len()..].iter().any(|&f| f != 0) {
        return None;
    }
    Some(RowFrame { t_us: t, axes })
}

/// The `N` bytes at `b[at..]`.
fn take<const N: usize>(b: &[u8], at: usize) -> Option<[u8; N]> {
    b.get(at..at + N)?.try_into().ok()
}

/// Parses the block of an axis with the flags `flags` at the start of `b`: the angle, the rate
/// column, `channels` values, the tail when flagged; returns it and its length in bytes. `f32`
/// rows: the angle and values as `f32`, the tail the angle's f64 residual ([`RESIDUAL`]); `fx`
/// rows: the wrapped angle and values as Q31.32 raw bits, the tail the turn count ([`TURNS`]),
/// rounded as the host's fixed-point bank rounds them.
fn parse_axis(b: &[u8], flags: u8, channels: usize, fx: bool) -> Option<(AxisFrame, usize)> {
    let (width, tail_flag, other_flag) = if fx {
        (8, TURNS, RESIDUAL)
    } else {
        (4, RESIDUAL, TURNS)
    };
    if flags & other_flag != 0 {
        return None;
    }
    let raw = |at: usize| take(b, at).map(|w| Fx::from_bits(i64::from_le_bytes(w)));
    let value = |at: usize| {
        if fx {
            raw(at).map(Fx::output_value_f32)
        } else {
            take(b, at).map(f32::from_le_bytes)
        }
    };
    let reference = f32::from_le_bytes(take(b, width)?);
    let end = width + 4 + width * channels;
    let mut values = heapless::Vec::new();
    for at in (width + 4..end).step_by(width) {
        values.push(value(at)?).ok()?;
    }
    let tail: Option<[u8; 8]> = match flags & tail_flag {
        0 => None,
        _ => Some(take(b, end)?),
    };
    let (angle_deg, residual_deg) = if fx {
        let turns = tail.map_or(0, i64::from_le_bytes);
        Fx::output_angle_f32((turns, raw(0)?))
    } else {
        (value(0)?, tail.map_or(0.0, f64::from_le_bytes))
    };
    let axis = AxisFrame {
        angle_deg,
        residual_deg,
        reference_deg_s: (flags & RATE != 0).then_some(reference),
        values,
    };
    Some((axis, end + if tail.is_some() { 8 } else { 0 }))
}

/// Decodes a stream of defmt frames chunk by chunk.
pub struct Stream<'t> {
    decoder: Box<dyn StreamDecoder + Send + Sync + 't>,
    conv: Converter,
}

impl<'t> Stream<'t> {
    /// A decoder for the frames of the firmware whose table is `table`.
    pub fn new(table: &'t Table) -> Self {
        Stream {
            decoder: table.new_stream_decoder(),
            conv: Converter::default(),
        }
    }

    /// Feeds received bytes; returns the text of the frames they completed.
    pub fn feed(&mut self, bytes: &[u8]) -> Result<Text, String> {
        self.decoder.received(bytes);
        let mut text = Text::default();
        let conv = &mut self.conv;
        messages(
            &mut *self.decoder,
            "malformed defmt frame in the firmware's output",
            |msg| conv.message(msg, &mut text),
        )?;
        Ok(text)
    }
}

/// Gives `each` the text (`Frame::display_message`) of every frame `decoder` holds complete;
/// a malformed frame is the error `malformed`.
fn messages(
    decoder: &mut (dyn StreamDecoder + '_),
    malformed: &str,
    mut each: impl FnMut(&str) -> Result<(), String>,
) -> Result<(), String> {
    loop {
        match decoder.decode() {
            Ok(frame) => each(&frame.display_message().to_string())?,
            Err(DecodeError::UnexpectedEof) => return Ok(()),
            Err(DecodeError::Malformed) => return Err(malformed.to_owned()),
        }
    }
}

/// Bytes of the firmware's output a [`Read`] keeps (`raw`): a CI run's whole output, and a
/// bounded part of a long one.
const KEEP_BYTES: usize = 16 << 20;

/// What [`spawn_reader`]'s thread read.
#[derive(Default)]
pub struct Read {
    /// The collected stdout: CSV (empty when inherited), or the text of a text image.
    pub stdout: String,
    /// Diagnostic lines.
    pub diag: String,
    /// The firmware's output bytes as received (the defmt frames), at most [`KEEP_BYTES`].
    pub raw: Vec<u8>,
    /// More bytes than [`KEEP_BYTES`] came: `raw` is their beginning only.
    pub raw_cut: bool,
}

/// Reads the firmware's semihosting stdout on a thread. With a defmt `table` (see [`table`])
/// the frames are decoded: the CSV goes to this process's stdout when `inherit` (else it is
/// collected), the diagnostics are collected. Without a table the bytes are text, copied or
/// collected.
pub fn spawn_reader(
    mut from: impl std::io::Read + Send + 'static,
    table: Option<Table>,
    inherit: bool,
) -> std::thread::JoinHandle<Read> {
    std::thread::spawn(move || {
        use std::io::Write as _;
        let mut stdout = String::new();
        let mut diag = String::new();
        let mut raw = Vec::new();
        let mut raw_cut = false;
        let mut stream = table.as_ref().map(Stream::new);
        let mut buf = [0u8; 8192];
        loop {
            let n = match from.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => n,
            };
            let room = KEEP_BYTES.saturating_sub(raw.len()).min(n);
            raw_cut |= room < n;
            if stream.is_some() || !inherit {
                raw.extend_from_slice(&buf[..room]);
            }
            let Some(s) = stream.as_mut() else {
                if inherit {
                    let mut o = std::io::stdout().lock();
                    let _ = o.write_all(&buf[..n]);
                    let _ = o.flush();
                }
                continue;
            };
            match s.feed(&buf[..n]) {
                Ok(t) => {
                    if inherit {
                        let mut o = std::io::stdout().lock();
                        let _ = o.write_all(t.csv.as_bytes());
                        let _ = o.flush();
                    } else {
                        stdout.push_str(&t.csv);
                    }
                    diag.push_str(&t.diag);
                }
                Err(e) => {
                    diag.push_str(&format!("xtask: {e}; decoding stopped\n"));
                    // Drain the rest so the firmware is never blocked on a full pipe.
                    while let Ok(n) = from.read(&mut buf) {
                        if n == 0 {
                            break;
                        }
                    }
                    break;
                }
            }
        }
        if table.is_none() {
            stdout = String::from_utf8_lossy(&raw).into_owned();
        }
        Read {
            stdout,
            diag,
            raw,
            raw_cut,
        }
    })
}

/// Decodes a whole log of defmt frames (what the firmware writes to RTT's `defmt` channel or
/// QEMU's semihosting stdout) with the ELF's table.
pub fn decode_frames(table: &Table, bytes: &[u8]) -> Result<Text, String> {
    Stream::new(table).feed(bytes)
}

/// The messages of a log of defmt frames as text, one line each: what probe-rs prints for
/// them with `--log-format "{s}"`.
pub fn frame_lines(table: &Table, bytes: &[u8]) -> Result<String, String> {
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut lines = String::new();
    messages(&mut *decoder, "malformed defmt frame in the log", |msg| {
        lines.push_str(msg);
        lines.push('\n');
        Ok(())
    })?;
    Ok(lines)
}

/// Converts messages printed as text, one per line (probe-rs's output with `--log-format
/// "{s}"`): the CSV and the other lines, as [`decode_frames`] gives them for the frames.
pub fn decode_lines(text: &str) -> Result<Text, String> {
    let mut conv = Converter::default();
    let mut out = Text::default();
    for line in text.lines() {
        conv.message(line, &mut out)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimators::{PaperOutput, ProductOutput};
    use nav440_pipeline::csv;

    /// A converter that has taken the header message `header` (and the text it wrote).
    fn started(header: &str) -> (Converter, Text) {
        let mut c = Converter::default();
        let mut t = Text::default();
        c.message(header, &mut t).unwrap();
        (c, t)
    }

    /// One axis of a test row: flags, angle, residual, reference, channel values.
    type TestAxis<'a> = (u8, f32, f64, f32, &'a [f32]);

    /// The payload of a row message (layout of `firmware-example/src/out.rs`): the time, the
    /// flags word, the blocks of the axes with an estimate.
    fn payload(t_us: u64, axes: &[TestAxis<'_>]) -> Vec<u8> {
        let mut b = t_us.to_le_bytes().to_vec();
        let mut flags = [0u8; 4];
        let mut blocks = Vec::new();
        for (i, &(f, angle, residual, reference, vals)) in axes.iter().enumerate() {
            flags[i] = f;
            if f & NO_ESTIMATE != 0 {
                continue;
            }
            blocks.extend(angle.to_le_bytes());
            blocks.extend(reference.to_le_bytes());
            for v in vals {
                blocks.extend(v.to_le_bytes());
            }
            if f & RESIDUAL != 0 {
                blocks.extend(residual.to_le_bytes());
            }
        }
        b.extend(flags);
        b.extend(blocks);
        b
    }

    /// A row message as defmt-decoder displays it (`{:?}` of the payload bytes) gives the CSV
    /// line `nav440 estimate` writes for the same values (formatted by `csv::write_row`,
    /// checked here against hand-written text: time 0.0100 s from 10000 us, `{}` of each f32,
    /// empty reference field when flag bit 0 is clear).
    #[test]
    fn row_message_becomes_csv_line() {
        let (mut c, mut t) = started(&format!("header 4 f32 {}", <PaperOutput>::CSV_COLUMNS));
        assert_eq!(t.csv, format!("{}\n", csv::HEADER));
        let vals = [
            0.5, 1e-5, -2.25, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0,
        ];
        let msg = |t_us: u64, flags: u8, reference: f32| {
            format!(
                "row {:?}",
                payload(t_us, &[(flags, 12.5, 0.0, reference, &vals)])
            )
        };
        c.message(&msg(10000, 1, -0.75), &mut t).unwrap();
        c.message(&msg(10049, 0, 0.0), &mut t).unwrap();
        let lines: Vec<&str> = t.csv.lines().collect();
        assert_eq!(
            lines[1],
            "0.0100,12.5,-0.75,0.5,0.00001,-2.25,3,4,5,6,7,8,9,10,11,12,13"
        );
        assert_eq!(
            lines[2],
            "0.0100,12.5,,0.5,0.00001,-2.25,3,4,5,6,7,8,9,10,11,12,13"
        );
        // Flag bit 1: no estimate (near gimbal lock): no block, the axis's fields are empty.
        let b = payload(10100, &[(2, 0.0, 0.0, 0.0, &[])]);
        assert_eq!(b.len(), 12);
        c.message(&format!("row {b:?}"), &mut t).unwrap();
        assert_eq!(t.csv.lines().nth(3), Some("0.0101,,,,,,,,,,,,,,,,"));
        // Flag bit 2: the block ends with the residual; the angle is their exact f64 sum.
        let b = payload(10200, &[(1 | 4, 16_777_216.0, 0.5, 1.0, &vals)]);
        c.message(&format!("row {b:?}"), &mut t).unwrap();
        assert_eq!(
            t.csv.lines().nth(4),
            Some("0.0102,16777216.5,1,0.5,0.00001,-2.25,3,4,5,6,7,8,9,10,11,12,13")
        );
        // Without the flag the same bytes are 8 too many.
        let mut b = payload(10200, &[(1, 16_777_216.0, 0.0, 1.0, &vals)]);
        b.extend(0.5f64.to_le_bytes());
        assert!(c.message(&format!("row {b:?}"), &mut t).is_err());
        c.message("firmware: bytes=3", &mut t).unwrap();
        assert_eq!(t.diag, "firmware: bytes=3\n");
        // A payload of the wrong length is an error, not a row.
        assert!(c.message("row [1, 2]", &mut t).is_err());
    }

    /// The product bank's header names its two channels, and its rows carry two values per
    /// axis (hand-written expected text, the contract of `nav440 estimate --bank product`).
    #[test]
    fn product_rows_have_the_product_columns() {
        let (mut c, mut t) = started(&format!("header 7 f32 {}", <ProductOutput>::CSV_COLUMNS));
        let [v, a] = <ProductOutput>::NAMES;
        assert_eq!(
            t.csv,
            format!("t,roll,roll_rate,roll_{v},roll_{a},pitch,pitch_rate,pitch_{v},pitch_{a},yaw,yaw_rate,yaw_{v},yaw_{a}\n")
        );
        let b = payload(
            20_000,
            &[
                (1, 1.5, 0.0, 2.0, &[3.0, -4.5]),
                (0, -2.0, 0.0, 0.0, &[0.25, 8.0]),
                (1, 170.0, 0.0, 30.0, &[29.5, 1e-3]),
            ],
        );
        c.message(&format!("row {b:?}"), &mut t).unwrap();
        assert_eq!(
            t.csv.lines().nth(1),
            Some("0.0200,1.5,2,3,-4.5,-2,,0.25,8,170,30,29.5,0.001")
        );
        // A paper-sized axis block is not a product row.
        let long = payload(
            0,
            &[
                (1, 1.5, 0.0, 2.0, &[0.0; 14]),
                (2, 0.0, 0.0, 0.0, &[]),
                (2, 0.0, 0.0, 0.0, &[]),
            ],
        );
        assert!(c.message(&format!("row {long:?}"), &mut t).is_err());
        // An unknown bank is refused at the header.
        assert!(Converter::default()
            .message("header 4 f32 foo_v", &mut Text::default())
            .is_err());
    }

    /// The header of an image without the Euler reference (feature `no-reference`) names
    /// `body_rate` before the channels: the CSV header of `nav440 estimate --no-reference`,
    /// rows written alike (hand-written expected text).
    #[test]
    fn body_rate_header_names_the_body_rate_columns() {
        let (mut c, mut t) = started(&format!(
            "header 7 f32 body_rate,{}",
            <ProductOutput>::CSV_COLUMNS
        ));
        assert_eq!(
            t.csv,
            "t,roll,roll_body_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_body_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_body_rate,yaw_ilo1_v,yaw_kf_a\n"
        );
        let b = payload(
            20_000,
            &[
                (1, 1.5, 0.0, 2.0, &[3.0, -4.5]),
                (1, -2.0, 0.0, -0.5, &[0.25, 8.0]),
                (2, 0.0, 0.0, 0.0, &[]),
            ],
        );
        c.message(&format!("row {b:?}"), &mut t).unwrap();
        assert_eq!(
            t.csv.lines().nth(1),
            Some("0.0200,1.5,2,3,-4.5,-2,-0.5,0.25,8,,,,")
        );
        let mut t = Text::default();
        Converter::default()
            .message(
                &format!("header 4 f32 body_rate,{}", <PaperOutput>::CSV_COLUMNS),
                &mut t,
            )
            .unwrap();
        assert_eq!(
            t.csv,
            format!("{}\n", csv::HEADER.replace("yaw_rate", "yaw_body_rate"))
        );
    }

    /// An `fx` row (a fixed-point image's): raw Q31.32 values rounded here as the host's
    /// fixed-point bank rounds them, checked against hand-computed text: 1 + 2^-32 rounds to
    /// the f32 1 (nearest), and as the angle it is exact in the CSV (the f64 sum
    /// 1.0000000002328306, Python's `repr(1 + 2**-32)`); 170 deg after 2 turns is 890.
    #[test]
    fn fx_rows_are_rounded_as_the_host_rounds_them() {
        let (mut c, mut t) = started(&format!("header 4 fx {}", <ProductOutput>::CSV_COLUMNS));
        assert_eq!(t.csv, "t,yaw,yaw_rate,ilo1_v,kf_a\n");
        let q = |x: f64| ((x * 4_294_967_296.0) as i64).to_le_bytes();
        let row = |flags: u8, wrapped: [u8; 8], turns: Option<i64>| {
            let mut b = 30_000u64.to_le_bytes().to_vec();
            b.extend([flags, 0, 0, 0]);
            b.extend(wrapped);
            b.extend(29.5f32.to_le_bytes());
            b.extend(((1i64 << 32) + 1).to_le_bytes());
            b.extend(q(-4.5));
            if let Some(n) = turns {
                b.extend(n.to_le_bytes());
            }
            format!("row {b:?}")
        };
        c.message(&row(1, ((1i64 << 32) + 1).to_le_bytes(), None), &mut t)
            .unwrap();
        c.message(&row(1 | TURNS, q(170.0), Some(2)), &mut t)
            .unwrap();
        let lines: Vec<&str> = t.csv.lines().collect();
        assert_eq!(lines[1], "0.0300,1.0000000002328306,29.5,1,-4.5");
        assert_eq!(lines[2], "0.0300,890,29.5,1,-4.5");
        // A turn count without its flag is 8 bytes too many; an f32 row's residual flag is
        // not an fx row's.
        let mut bad = row(1, q(170.0), None);
        bad.insert_str(bad.len() - 1, ", 0, 0, 0, 0, 0, 0, 0, 0");
        assert!(c.message(&bad, &mut t).is_err());
        assert!(c
            .message(&row(1 | RESIDUAL, q(1.0), Some(0)), &mut t)
            .is_err());
        // An unknown number format is refused at the header.
        assert!(Converter::default()
            .message("header 4 f16 ilo1_v,kf_a", &mut Text::default())
            .is_err());
    }
}
