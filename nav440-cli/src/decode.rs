//! `nav440 decode`: one CSV row per CRC-checked frame, fields in SI units.
//!
//! Units: angles rad, angular rates rad/s, accelerations m/s^2 (1 g = 9.80665 m/s^2), magnetic
//! field T (1 G = 1e-4 T), temperatures degC, velocities m/s, latitude/longitude rad, altitude
//! m, timeITOW / GPSITOW s, delta velocity m/s, delta angle rad; BIT and status words as hex.
//! Columns: `index` (frame number in the stream, from 0), `type`, then the type's fields. For
//! a stream of several types the header is the union of their columns (in order of first
//! appearance) and cells a type does not have are empty. Frames whose type is unknown or
//! whose payload does not match their type get a `payload_hex` column.
//!
//! The fixed-layout packets' fields come from [`Packet::for_each_field`]; a table by unit
//! converts each to SI and names its column `<field>_<unit>` (`roll_rad`, `accel_x_m_s2`,
//! `time_itow_s`); magnetic and true yaw are both `yaw_rad`.

use crate::error::{Error, Result};
use nav440_proto::{Field, Frame, Packet, Parser, SiValue, Unit};

/// Standard gravity, m/s^2 per g.
pub const G0: f64 = 9.80665;
/// Tesla per gauss.
pub const TESLA_PER_GAUSS: f64 = 1e-4;

type Cols = Vec<(String, String)>;

fn num(v: f64) -> String {
    format!("{v}")
}
fn hex(v: u16) -> String {
    format!("0x{v:04X}")
}
fn hex_bytes(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// How a value in a unit of `nav440_proto` becomes a cell.
#[derive(Clone, Copy)]
enum Conv {
    /// Already SI.
    Same,
    /// Multiply by the factor (in `f64`, rounded back to the accessor's precision).
    Mul(f64),
    /// Divide by the divisor (in `f64`).
    Div(f64),
}

/// [`Unit`] of `nav440_proto` -> (column suffix, conversion to the CSV's SI unit); a unit not
/// listed keeps its value and its symbol as suffix.
const UNITS: &[(Unit, &str, Conv)] = &[
    (Unit::Rad, "rad", Conv::Same),
    (Unit::RadPerS, "rad_s", Conv::Same),
    (Unit::G, "m_s2", Conv::Mul(G0)),
    (Unit::Gauss, "t", Conv::Mul(TESLA_PER_GAUSS)),
    (Unit::DegC, "degc", Conv::Same),
    (Unit::MPerS, "m_s", Conv::Same),
    (Unit::M, "m", Conv::Same),
    (Unit::Ms, "s", Conv::Div(1000.0)),
];

/// Field names whose column is named differently: A0/A1 magnetic yaw and A2/N0/N1 true yaw
/// share the `yaw_rad` column with B1's yaw.
const RENAMED: &[(&str, &str)] = &[("yaw_mag", "yaw"), ("yaw_true", "yaw")];

/// The (column, value) of one field: `<name>_<SI unit>` in SI units, status words as hex,
/// other integers in decimal.
fn field_column(f: &Field) -> (String, String) {
    let name = RENAMED
        .iter()
        .find(|(from, _)| *from == f.name)
        .map_or(f.name, |(_, to)| to);
    let Some(q) = f.si else {
        let cell = if f.flags {
            // Status words are u16; wider ones (none today) keep all their digits.
            u16::try_from(f.raw).map_or_else(|_| format!("0x{:04X}", f.raw), hex)
        } else {
            f.raw.to_string()
        };
        return (name.to_string(), cell);
    };
    let (suffix, conv) = UNITS
        .iter()
        .find(|(u, _, _)| *u == q.unit)
        .map_or((q.unit.symbol(), Conv::Same), |&(_, s, c)| (s, c));
    let apply = |v: f64| match conv {
        Conv::Same => v,
        Conv::Mul(k) => v * k,
        Conv::Div(k) => v / k,
    };
    let cell = match q.value {
        SiValue::F32(v) => format!("{}", apply(f64::from(v)) as f32),
        SiValue::F64(v) => num(apply(v)),
    };
    let suffix = suffix.replace('/', "_").to_ascii_lowercase();
    (format!("{name}_{suffix}"), cell)
}

/// The (column, value) pairs of one decoded packet.
pub fn packet_columns(p: &Packet<'_>) -> Cols {
    let text = |name: &str, value: String| vec![(name.to_string(), value)];
    match p {
        Packet::Id(p) => vec![
            ("serial".to_string(), p.serial().to_string()),
            (
                "model".to_string(),
                p.model_str()
                    .unwrap_or("")
                    .replace([',', '"', '\n', '\r'], " "),
            ),
        ],
        Packet::Vr(p) => {
            let f = p.fields();
            text(
                "version",
                format!(
                    "{}.{}.{}-{}+{}",
                    f.major, f.minor, f.patch, f.stage, f.build
                ),
            )
        }
        Packet::Nak(p) => text("failed_type", p.failed_type().name().to_string()),
        Packet::GetPacket(t) => text("requested_type", t.name().to_string()),
        Packet::Echo(b) => text("payload_hex", hex_bytes(b)),
        Packet::SetFields(ids) | Packet::WriteFields(ids) => text(
            "field_ids",
            ids.iter()
                .map(|id| format!("0x{:04X}", id.0))
                .collect::<Vec<_>>()
                .join(" "),
        ),
        Packet::GetFields(v) | Packet::ReadFields(v) => text(
            "field_values",
            v.iter()
                .map(|(id, x)| format!("0x{:04X}=0x{x:04X}", id.0))
                .collect::<Vec<_>>()
                .join(" "),
        ),
        Packet::Unknown(f) => text("payload_hex", hex_bytes(f.payload)),
        // The fixed-layout output packets (S0..T0): every field from the protocol crate.
        _ => {
            let mut cols = Vec::new();
            p.for_each_field(|f| cols.push(field_column(&f)));
            cols
        }
    }
}

/// One decoded frame: its number in the stream, its type name and its (column, value) cells.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DecodedRow {
    /// Frame number in the stream, from 0 (frames left out by `--type` count too).
    pub index: u64,
    /// Type name ("A2", "NAK", "z1", "??").
    pub name: String,
    /// The cells.
    pub cols: Cols,
}

fn type_matches(f: &Frame<'_>, only: Option<&str>) -> bool {
    only.is_none_or(|o| f.packet_type.name().eq_ignore_ascii_case(o))
}

fn frame_cols(f: Frame<'_>) -> Cols {
    match Packet::decode(f) {
        Ok(p) => packet_columns(&p),
        Err(_) => vec![("payload_hex".to_string(), hex_bytes(f.payload))],
    }
}

/// Frames -> [`DecodedRow`]s, for a stream fed in any number of chunks (constant memory).
#[derive(Default)]
pub struct FrameDecoder {
    parser: Parser,
    only: Option<String>,
    frames: u64,
}

impl std::fmt::Debug for FrameDecoder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameDecoder")
            .field("only", &self.only)
            .field("frames", &self.frames)
            .finish()
    }
}

impl FrameDecoder {
    /// A decoder of every frame, or only of those whose type name equals `only`
    /// (case-insensitively, e.g. "A2", "nak").
    pub fn new(only: Option<&str>) -> Self {
        FrameDecoder {
            only: only.map(str::to_string),
            ..Self::default()
        }
    }

    /// Feeds the next bytes; `on_row` gets each decoded frame that passes the type filter.
    pub fn push(&mut self, bytes: &[u8], mut on_row: impl FnMut(DecodedRow)) {
        let (frames, only) = (&mut self.frames, self.only.as_deref());
        self.parser
            .feed(bytes, |f| decoded_row(f, frames, only, &mut on_row));
    }

    /// Ends the stream: `on_row` gets the frames the parser still holds (complete frames
    /// behind a false header at the end of the input). Returns the number of bytes at the end
    /// that did not complete a frame; no valid frame at all is an [`Error::NotNav440`].
    pub fn finish(&mut self, mut on_row: impl FnMut(DecodedRow)) -> Result<u64> {
        let (frames, only) = (&mut self.frames, self.only.as_deref());
        let dropped = self
            .parser
            .finish(|f| decoded_row(f, frames, only, &mut on_row));
        if self.frames == 0 {
            return Err(Error::NotNav440(
                "no NAV440 frame found (not a NAV440 capture?)".into(),
            ));
        }
        Ok(dropped as u64)
    }
}

/// Numbers frame `f` (`frames` counts all types) and passes its row to `on_row` if its type
/// passes the filter `only`.
fn decoded_row(
    f: Frame<'_>,
    frames: &mut u64,
    only: Option<&str>,
    on_row: &mut impl FnMut(DecodedRow),
) {
    let index = *frames;
    *frames += 1;
    if type_matches(&f, only) {
        on_row(DecodedRow {
            index,
            name: f.packet_type.name().to_string(),
            cols: frame_cols(f),
        });
    }
}

/// The CSV header of `nav440 decode`: `index,type`, then the union of the rows' columns in
/// order of first appearance.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    cols: Vec<String>,
    /// Frame shapes already looked at: frames of one type, payload length and decode outcome
    /// have the same columns.
    seen: Vec<([u8; 2], usize, bool)>,
}

impl Header {
    /// An empty column set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the columns of a row.
    pub fn add_row(&mut self, row: &DecodedRow) {
        for (n, _) in &row.cols {
            if !self.cols.iter().any(|c| c == n) {
                self.cols.push(n.clone());
            }
        }
    }

    /// Adds the columns of every frame of `bytes` that passes the filter `only`, without
    /// formatting their values (a frame shape seen before is skipped). Returns the number of
    /// frames (all types).
    pub fn scan(&mut self, parser: &mut Parser, bytes: &[u8], only: Option<&str>) -> u64 {
        let mut frames = 0;
        parser.feed(bytes, |f| self.scan_frame(f, only, &mut frames));
        frames
    }

    /// [`Header::scan`] of the frames `parser` still holds at the end of the input (see
    /// [`Parser::finish`]).
    pub fn scan_end(&mut self, parser: &mut Parser, only: Option<&str>) -> u64 {
        let mut frames = 0;
        parser.finish(|f| self.scan_frame(f, only, &mut frames));
        frames
    }

    fn scan_frame(&mut self, f: Frame<'_>, only: Option<&str>, frames: &mut u64) {
        *frames += 1;
        if !type_matches(&f, only) {
            return;
        }
        let key = (f.packet_type.0, f.payload.len(), Packet::decode(f).is_ok());
        if self.seen.contains(&key) {
            return;
        }
        self.seen.push(key);
        let row = DecodedRow {
            index: 0,
            name: String::new(),
            cols: frame_cols(f),
        };
        self.add_row(&row);
    }

    /// The header line (with its newline).
    pub fn line(&self) -> String {
        let mut out = String::from("index,type");
        for h in &self.cols {
            out.push(',');
            out.push_str(h);
        }
        out.push('\n');
        out
    }

    /// Appends the CSV line of `row` (with its newline) to `out`. Returns `false` if the row
    /// has a column that is not in the header (that cell is left out).
    pub fn row_line(&self, row: &DecodedRow, out: &mut String) -> bool {
        out.push_str(&row.index.to_string());
        out.push(',');
        out.push_str(&csv_cell(&row.name));
        for h in &self.cols {
            out.push(',');
            if let Some((_, v)) = row.cols.iter().find(|(n, _)| n == h) {
                out.push_str(v);
            }
        }
        out.push('\n');
        row.cols
            .iter()
            .all(|(n, _)| self.cols.iter().any(|c| c == n))
    }
}

/// Decodes every frame of `bytes` (or only those whose type name equals `only`,
/// case-insensitively, e.g. "A2", "NAK") into CSV text.
pub fn decode_csv(bytes: &[u8], only: Option<&str>) -> Result<String> {
    let mut header = Header::new();
    let mut parser = Parser::new();
    header.scan(&mut parser, bytes, only);
    header.scan_end(&mut parser, only);
    let mut dec = FrameDecoder::new(only);
    let mut out = header.line();
    dec.push(bytes, |row| {
        header.row_line(&row, &mut out);
    });
    dec.finish(|row| {
        header.row_line(&row, &mut out);
    })?;
    Ok(out)
}

fn csv_cell(s: &str) -> String {
    if s.chars()
        .all(|c| c.is_ascii_graphic() && c != ',' && c != '"')
    {
        s.to_string()
    } else {
        format!("\"{}\"", s.replace('"', "\"\""))
    }
}
