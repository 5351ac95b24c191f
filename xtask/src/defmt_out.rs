//! Decoding the firmware's defmt output (`firmware-example/src/out.rs`) into the text the
//! text firmware used to print: the CSV of `nav440 estimate` (formatted here by
//! `nav440_pipeline::csv`, exactly as the host CLI does) on stdout, the `firmware: ...`
//! diagnostics and counters on stderr.
//!
//! The frames are decoded with `defmt-decoder` from the ELF's defmt table. A `row` message
//! carries one byte payload (little-endian): the sample time (u64, us) and, per estimated axis,
//! a flag byte, the angle (f32), its f64 residual, the reference rate (f32) and the 14 channel
//! values (f32) (`firmware-example/src/out.rs`). The values are rebuilt from their bytes, so
//! they are the exact bits the firmware sent.

use defmt_decoder::{DecodeError, StreamDecoder, Table};
use estimators::BankOutput;
use nav440_pipeline::{csv, Axes, Axis, AxisRow, Row};
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
    axes: Option<Axes>,
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
            let mask: u8 = rest
                .trim()
                .parse()
                .map_err(|_| format!("bad header message `{msg}`"))?;
            let mut axes = Axes::NONE;
            for a in Axis::ALL {
                if mask & (1 << a.index()) != 0 {
                    axes = axes.with(a);
                }
            }
            csv::write_header(&mut out.csv, axes).map_err(|_| "header".to_owned())?;
            out.csv.push('\n');
            self.axes = Some(axes);
        } else if let Some(rest) = msg.strip_prefix("row ") {
            let axes = self
                .axes
                .ok_or_else(|| format!("row before the header: `{msg}`"))?;
            let row = parse_row(rest, axes).ok_or_else(|| format!("bad row message `{msg}`"))?;
            csv::write_row(&mut out.csv, &row, axes).map_err(|_| "row".to_owned())?;
            out.csv.push('\n');
        } else {
            out.diag.push_str(msg);
            out.diag.push('\n');
        }
        Ok(())
    }
}

/// Bytes of one axis in a row payload: flags, angle (f32), residual (f64), reference (f32),
/// the channel values (f32).
const AXIS_BYTES: usize = 1 + 4 + 8 + 4 + 4 * estimators::Channel::COUNT;

/// Parses `[B, B, ...]` (the display of a row message's byte payload after `row `).
fn parse_row(s: &str, axes: Axes) -> Option<Row> {
    let list = s.trim().strip_prefix('[')?.strip_suffix(']')?;
    let bytes = list
        .split(", ")
        .map(|b| b.parse::<u8>().ok())
        .collect::<Option<Vec<u8>>>()?;
    if bytes.len() != 8 + AXIS_BYTES * axes.len() {
        return None;
    }
    let (t, rest) = bytes.split_first_chunk::<8>()?;
    let mut row = Row {
        t_us: u64::from_le_bytes(*t),
        axes: [None; 3],
    };
    let (blocks, tail) = rest.as_chunks::<AXIS_BYTES>();
    if !tail.is_empty() {
        return None;
    }
    for (axis, b) in axes.iter().zip(blocks) {
        row.axes[axis.index()] = Some(parse_axis(b));
    }
    Some(row)
}

/// The `N` bytes at `b[at..]`.
fn take<const N: usize>(b: &[u8; AXIS_BYTES], at: usize) -> [u8; N] {
    let mut v = [0u8; N];
    v.copy_from_slice(&b[at..at + N]);
    v
}

/// Parses one axis: flags, angle, residual, reference, 14 values.
fn parse_axis(b: &[u8; AXIS_BYTES]) -> AxisRow {
    let mut out = BankOutput {
        yaw_unwrapped_deg: f32::from_le_bytes(take(b, 1)),
        yaw_residual_deg: f64::from_le_bytes(take(b, 5)),
        ..BankOutput::default()
    };
    let reference = f32::from_le_bytes(take(b, 13));
    for (i, v) in out.values.iter_mut().enumerate() {
        *v = f32::from_le_bytes(take(b, 17 + 4 * i));
    }
    AxisRow {
        reference_deg_s: (b[0] & 1 != 0).then_some(reference),
        out,
    }
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
        loop {
            match self.decoder.decode() {
                Ok(frame) => {
                    let msg = frame.display_message().to_string();
                    self.conv.message(&msg, &mut text)?;
                }
                Err(DecodeError::UnexpectedEof) => break,
                Err(DecodeError::Malformed) => {
                    return Err("malformed defmt frame in the firmware's output".into())
                }
            }
        }
        Ok(text)
    }
}

/// Reads the firmware's semihosting stdout on a thread. With a defmt `table` (see [`table`])
/// the frames are decoded: the CSV goes to this process's stdout when `inherit` (else it is
/// collected), the diagnostics are collected. Without a table the bytes are text, copied or
/// collected. The thread returns (collected stdout, diagnostic lines).
pub fn spawn_reader(
    mut from: impl std::io::Read + Send + 'static,
    table: Option<Table>,
    inherit: bool,
) -> std::thread::JoinHandle<(String, String)> {
    std::thread::spawn(move || {
        use std::io::Write as _;
        let mut stdout = String::new();
        let mut diag = String::new();
        let mut raw = Vec::new();
        let mut stream = table.as_ref().map(Stream::new);
        let mut buf = [0u8; 8192];
        loop {
            let n = match from.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => n,
            };
            let Some(s) = stream.as_mut() else {
                if inherit {
                    let mut o = std::io::stdout().lock();
                    let _ = o.write_all(&buf[..n]);
                    let _ = o.flush();
                } else {
                    raw.extend_from_slice(&buf[..n]);
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
        (stdout, diag)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The payload bytes of one axis (layout of `firmware-example/src/out.rs`).
    fn axis_bytes(flags: u8, angle: f32, residual: f64, reference: f32, vals: &[f32]) -> Vec<u8> {
        let mut b = vec![flags];
        b.extend(angle.to_le_bytes());
        b.extend(residual.to_le_bytes());
        b.extend(reference.to_le_bytes());
        for v in vals {
            b.extend(v.to_le_bytes());
        }
        b
    }

    /// A row message as defmt-decoder displays it (`{:?}` of the payload bytes) gives the CSV
    /// line `nav440 estimate` writes for the same values (formatted by `csv::write_row`,
    /// checked here against hand-written text: time 0.0100 s from 10000 us, `{}` of each f32,
    /// empty reference field when flag bit 0 is clear).
    #[test]
    fn row_message_becomes_csv_line() {
        let mut c = Converter::default();
        let mut t = Text::default();
        c.message("header 4", &mut t).unwrap();
        assert_eq!(t.csv, format!("{}\n", csv::HEADER));
        let vals = [
            0.5, 1e-5, -2.25, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0,
        ];
        let msg = |t_us: u64, flags: u8, reference: f32| {
            let mut b = t_us.to_le_bytes().to_vec();
            b.extend(axis_bytes(flags, 12.5, 0.0, reference, &vals));
            format!("row {b:?}")
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
        c.message("firmware: bytes=3", &mut t).unwrap();
        assert_eq!(t.diag, "firmware: bytes=3\n");
        // A payload of the wrong length is an error, not a row.
        assert!(c.message("row [1, 2]", &mut t).is_err());
    }
}
