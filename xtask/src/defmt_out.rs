//! Decoding the firmware's defmt output (`firmware-example/src/out.rs`) into the text the
//! text firmware used to print: the CSV of `nav440 estimate` (formatted here by
//! `nav440_pipeline::csv`, exactly as the host CLI does) on stdout, the `firmware: ...`
//! diagnostics and counters on stderr.
//!
//! The frames are decoded with `defmt-decoder` from the ELF's defmt table. A `row` message
//! carries the sample time (u64, us) and, per estimated axis, a flag byte, the angle (f32), its
//! f64 residual, the reference rate (f32) and the 14 channel values (f32). defmt-decoder
//! prints floats in their shortest round-trip form (ryu), so parsing them back gives the
//! exact bits the firmware sent.

use defmt_decoder::{DecodeError, StreamDecoder, Table};
use estimators::BankOutput;
use nav440_pipeline::{csv, Axes, Axis, AxisRow, Row};
use std::path::Path;

/// The format string of the firmware's row message.
const ROW_FORMAT: &str = "row {=u64} {=[?]}";

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

/// Parses `T [AXIS, AXIS, ...]` (the display of a row message after `row `).
fn parse_row(s: &str, axes: Axes) -> Option<Row> {
    let (t, list) = s.split_once(' ')?;
    let t_us: u64 = t.parse().ok()?;
    let list = list.trim().strip_prefix('[')?.strip_suffix(']')?;
    let mut row = Row {
        t_us,
        axes: [None; 3],
    };
    let mut parts = list.split(", ");
    for axis in axes.iter() {
        row.axes[axis.index()] = Some(parse_axis(parts.next()?)?);
    }
    parts.next().is_none().then_some(row)
}

/// Parses one axis: `flags angle residual reference v0 .. v13`.
fn parse_axis(s: &str) -> Option<AxisRow> {
    let mut it = s.split_whitespace();
    let flags: u8 = it.next()?.parse().ok()?;
    let mut out = BankOutput {
        yaw_unwrapped_deg: it.next()?.parse().ok()?,
        yaw_residual_deg: it.next()?.parse().ok()?,
        ..BankOutput::default()
    };
    let reference: f32 = it.next()?.parse().ok()?;
    for v in out.values.iter_mut() {
        *v = it.next()?.parse().ok()?;
    }
    if it.next().is_some() {
        return None;
    }
    Some(AxisRow {
        reference_deg_s: (flags & 1 != 0).then_some(reference),
        out,
    })
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

    /// A row message as defmt-decoder displays it gives the CSV line `nav440 estimate` writes
    /// for the same values (formatted by `csv::write_row`, checked here against hand-written
    /// text: time 0.0100 s from 10000 us, `{}` of each f32, empty reference field).
    #[test]
    fn row_message_becomes_csv_line() {
        let mut c = Converter::default();
        let mut t = Text::default();
        c.message("header 4", &mut t).unwrap();
        assert_eq!(t.csv, format!("{}\n", csv::HEADER));
        let vals = "0.5 1e-5 -2.25 3 4 5 6 7 8 9 10 11 12 13";
        c.message(&format!("row 10000 [1 12.5 0.0 -0.75 {vals}]"), &mut t)
            .unwrap();
        c.message(&format!("row 10049 [0 12.5 0.0 0.0 {vals}]"), &mut t)
            .unwrap();
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
        assert!(c.message("row 1 [1 2]", &mut t).is_err());
    }
}
