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
use nav440_proto::{Field, Packet, Parser, SiValue};

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

/// `nav440_proto` unit -> (column suffix, conversion to the CSV's SI unit).
const UNITS: &[(&str, &str, Conv)] = &[
    ("rad", "rad", Conv::Same),
    ("rad/s", "rad_s", Conv::Same),
    ("g", "m_s2", Conv::Mul(G0)),
    ("gauss", "t", Conv::Mul(TESLA_PER_GAUSS)),
    ("degC", "degc", Conv::Same),
    ("m/s", "m_s", Conv::Same),
    ("m", "m", Conv::Same),
    ("ms", "s", Conv::Div(1000.0)),
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
        .map_or((q.unit, Conv::Same), |&(_, s, c)| (s, c));
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

/// Decodes every frame of `bytes` (or only those whose type name equals `only`,
/// case-insensitively, e.g. "A2", "NAK") into CSV text.
pub fn decode_csv(bytes: &[u8], only: Option<&str>) -> Result<String> {
    let mut parser = Parser::new();
    let mut rows: Vec<(usize, String, Cols)> = Vec::new();
    let mut index = 0usize;
    let mut frames = 0usize;
    parser.feed(bytes, |f| {
        frames += 1;
        let name = f.packet_type.name().to_string();
        let i = index;
        index += 1;
        if let Some(o) = only {
            if !name.eq_ignore_ascii_case(o) {
                return;
            }
        }
        let cols = match Packet::decode(f) {
            Ok(p) => packet_columns(&p),
            Err(_) => vec![("payload_hex".to_string(), hex_bytes(f.payload))],
        };
        rows.push((i, name, cols));
    });
    if frames == 0 {
        return Err(Error::NotNav440(
            "no NAV440 frame found (not a NAV440 capture?)".into(),
        ));
    }
    let mut header: Vec<&str> = Vec::new();
    for (_, _, cols) in &rows {
        for (n, _) in cols {
            if !header.contains(&n.as_str()) {
                header.push(n);
            }
        }
    }
    let mut out = String::from("index,type");
    for h in &header {
        out.push(',');
        out.push_str(h);
    }
    out.push('\n');
    for (i, name, cols) in &rows {
        out.push_str(&format!("{i},{}", csv_cell(name)));
        for h in &header {
            out.push(',');
            if let Some((_, v)) = cols.iter().find(|(n, _)| n == h) {
                out.push_str(v);
            }
        }
        out.push('\n');
    }
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
