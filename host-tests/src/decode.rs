//! `nav440 decode`: one CSV row per CRC-checked frame, fields in SI units.
//!
//! Units: angles rad, angular rates rad/s, accelerations m/s^2 (1 g = 9.80665 m/s^2), magnetic
//! field T (1 G = 1e-4 T), temperatures degC, velocities m/s, latitude/longitude rad, altitude
//! m, timeITOW / GPSITOW s, delta velocity m/s, delta angle rad; BIT and status words as hex.
//! Columns: `index` (frame number in the stream, from 0), `type`, then the type's fields. For
//! a stream of several types the header is the union of their columns (in order of first
//! appearance) and cells a type does not have are empty. Frames whose type is unknown or
//! whose payload does not match their type get a `payload_hex` column.

use crate::error::{Error, Result};
use nav440_proto::{Packet, Parser};

/// Standard gravity, m/s^2 per g.
pub const G0: f64 = 9.80665;
/// Tesla per gauss.
pub const TESLA_PER_GAUSS: f64 = 1e-4;

type Cols = Vec<(&'static str, String)>;

fn num(v: f64) -> String {
    format!("{v}")
}

macro_rules! cols {
    ($( $name:literal => $e:expr ),* $(,)?) => {
        vec![ $( ($name, $e) ),* ]
    };
}

fn fl(v: f32) -> String {
    format!("{v}")
}
fn g(v: f32) -> String {
    format!("{}", (f64::from(v) * G0) as f32)
}
fn tesla(v: f32) -> String {
    format!("{}", (f64::from(v) * TESLA_PER_GAUSS) as f32)
}
fn ms(v: u32) -> String {
    num(f64::from(v) / 1000.0)
}
fn hex(v: u16) -> String {
    format!("0x{v:04X}")
}
fn hex_bytes(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// The (column, value) pairs of one decoded packet.
pub fn packet_columns(p: &Packet<'_>) -> Cols {
    match p {
        Packet::S0(p) => cols!(
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "accel_z_m_s2" => g(p.accel_z_g()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "mag_x_t" => tesla(p.mag_x_gauss()),
            "mag_y_t" => tesla(p.mag_y_gauss()),
            "mag_z_t" => tesla(p.mag_z_gauss()),
            "rate_temp_x_degc" => fl(p.rate_temp_x_degc()),
            "rate_temp_y_degc" => fl(p.rate_temp_y_degc()),
            "rate_temp_z_degc" => fl(p.rate_temp_z_degc()),
            "board_temp_degc" => fl(p.board_temp_degc()),
            "gps_itow_s" => ms(u32::from(p.gps_itow())),
            "bit" => hex(p.bit()),
        ),
        Packet::S1(p) => cols!(
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "accel_z_m_s2" => g(p.accel_z_g()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "rate_temp_x_degc" => fl(p.rate_temp_x_degc()),
            "rate_temp_y_degc" => fl(p.rate_temp_y_degc()),
            "rate_temp_z_degc" => fl(p.rate_temp_z_degc()),
            "board_temp_degc" => fl(p.board_temp_degc()),
            "counter" => p.counter().to_string(),
            "bit" => hex(p.bit()),
        ),
        Packet::S2(p) => cols!(
            "delta_vel_x_m_s" => fl(p.delta_vel_x_m_s()),
            "delta_vel_y_m_s" => fl(p.delta_vel_y_m_s()),
            "delta_vel_z_m_s" => fl(p.delta_vel_z_m_s()),
            "delta_angle_x_rad" => fl(p.delta_angle_x_rad()),
            "delta_angle_y_rad" => fl(p.delta_angle_y_rad()),
            "delta_angle_z_rad" => fl(p.delta_angle_z_rad()),
            "counter" => p.counter().to_string(),
            "bit" => hex(p.bit()),
        ),
        Packet::A0(p) => cols!(
            "roll_rad" => fl(p.roll_rad()),
            "pitch_rad" => fl(p.pitch_rad()),
            "yaw_rad" => fl(p.yaw_mag_rad()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "accel_z_m_s2" => g(p.accel_z_g()),
            "mag_x_t" => tesla(p.mag_x_gauss()),
            "mag_y_t" => tesla(p.mag_y_gauss()),
            "mag_z_t" => tesla(p.mag_z_gauss()),
            "x_rate_temp_degc" => fl(p.x_rate_temp_degc()),
            "gps_itow_s" => ms(u32::from(p.gps_itow())),
            "bit" => hex(p.bit()),
        ),
        Packet::A1(p) => cols!(
            "roll_rad" => fl(p.roll_rad()),
            "pitch_rad" => fl(p.pitch_rad()),
            "yaw_rad" => fl(p.yaw_mag_rad()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "accel_z_m_s2" => g(p.accel_z_g()),
            "mag_x_t" => tesla(p.mag_x_gauss()),
            "mag_y_t" => tesla(p.mag_y_gauss()),
            "mag_z_t" => tesla(p.mag_z_gauss()),
            "x_rate_temp_degc" => fl(p.x_rate_temp_degc()),
            "time_itow_s" => ms(p.time_itow()),
            "bit" => hex(p.bit()),
        ),
        Packet::A2(p) => cols!(
            "roll_rad" => fl(p.roll_rad()),
            "pitch_rad" => fl(p.pitch_rad()),
            "yaw_rad" => fl(p.yaw_true_rad()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "accel_z_m_s2" => g(p.accel_z_g()),
            "rate_temp_x_degc" => fl(p.rate_temp_x_degc()),
            "rate_temp_y_degc" => fl(p.rate_temp_y_degc()),
            "rate_temp_z_degc" => fl(p.rate_temp_z_degc()),
            "time_itow_s" => ms(p.time_itow()),
            "bit" => hex(p.bit()),
        ),
        Packet::N0(p) => cols!(
            "roll_rad" => fl(p.roll_rad()),
            "pitch_rad" => fl(p.pitch_rad()),
            "yaw_rad" => fl(p.yaw_true_rad()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "vel_n_m_s" => fl(p.vel_n_m_s()),
            "vel_e_m_s" => fl(p.vel_e_m_s()),
            "vel_d_m_s" => fl(p.vel_d_m_s()),
            "longitude_rad" => num(p.longitude_rad()),
            "latitude_rad" => num(p.latitude_rad()),
            "altitude_m" => fl(p.altitude_m()),
            "gps_itow_s" => ms(u32::from(p.gps_itow())),
            "bit" => hex(p.bit()),
        ),
        Packet::N1(p) => cols!(
            "roll_rad" => fl(p.roll_rad()),
            "pitch_rad" => fl(p.pitch_rad()),
            "yaw_rad" => fl(p.yaw_true_rad()),
            "rate_x_rad_s" => fl(p.rate_x_rad_s()),
            "rate_y_rad_s" => fl(p.rate_y_rad_s()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "accel_z_m_s2" => g(p.accel_z_g()),
            "vel_n_m_s" => fl(p.vel_n_m_s()),
            "vel_e_m_s" => fl(p.vel_e_m_s()),
            "vel_d_m_s" => fl(p.vel_d_m_s()),
            "longitude_rad" => num(p.longitude_rad()),
            "latitude_rad" => num(p.latitude_rad()),
            "altitude_m" => fl(p.altitude_m()),
            "x_rate_temp_degc" => fl(p.x_rate_temp_degc()),
            "time_itow_s" => ms(p.time_itow()),
            "bit" => hex(p.bit()),
        ),
        Packet::B1(p) => cols!(
            "roll_rad" => fl(p.roll_rad()),
            "pitch_rad" => fl(p.pitch_rad()),
            "yaw_rad" => fl(p.yaw_rad()),
            "rate_z_rad_s" => fl(p.rate_z_rad_s()),
            "accel_x_m_s2" => g(p.accel_x_g()),
            "accel_y_m_s2" => g(p.accel_y_g()),
            "time_itow_s" => ms(p.time_itow()),
            "bit" => hex(p.bit()),
        ),
        Packet::T0(p) => {
            let f = p.fields();
            vec![
                ("bit", hex(f.bit)),
                ("hardware_bit", hex(f.hardware_bit)),
                ("hardware_power_bit", hex(f.hardware_power_bit)),
                (
                    "hardware_environmental_bit",
                    hex(f.hardware_environmental_bit),
                ),
                ("com_bit", hex(f.com_bit)),
                ("com_serial_a_bit", hex(f.com_serial_a_bit)),
                ("com_serial_b_bit", hex(f.com_serial_b_bit)),
                ("software_bit", hex(f.software_bit)),
                ("software_algorithm_bit", hex(f.software_algorithm_bit)),
                ("software_data_bit", hex(f.software_data_bit)),
                ("hardware_status", hex(f.hardware_status)),
                ("com_status", hex(f.com_status)),
                ("software_status", hex(f.software_status)),
                ("sensor_status", hex(f.sensor_status)),
            ]
        }
        Packet::Id(p) => vec![
            ("serial", p.serial().to_string()),
            (
                "model",
                p.model_str()
                    .unwrap_or("")
                    .replace([',', '"', '\n', '\r'], " "),
            ),
        ],
        Packet::Vr(p) => {
            let f = p.fields();
            vec![(
                "version",
                format!(
                    "{}.{}.{}-{}+{}",
                    f.major, f.minor, f.patch, f.stage, f.build
                ),
            )]
        }
        Packet::Nak(p) => vec![("failed_type", p.failed_type().name().to_string())],
        Packet::GetPacket(t) => vec![("requested_type", t.name().to_string())],
        Packet::Echo(b) => vec![("payload_hex", hex_bytes(b))],
        Packet::SetFields(ids) | Packet::WriteFields(ids) => {
            vec![(
                "field_ids",
                ids.iter()
                    .map(|id| format!("0x{:04X}", id.0))
                    .collect::<Vec<_>>()
                    .join(" "),
            )]
        }
        Packet::GetFields(v) | Packet::ReadFields(v) => vec![(
            "field_values",
            v.iter()
                .map(|(id, x)| format!("0x{:04X}=0x{x:04X}", id.0))
                .collect::<Vec<_>>()
                .join(" "),
        )],
        Packet::Unknown(f) => vec![("payload_hex", hex_bytes(f.payload))],
        _ => Vec::new(),
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
            Err(_) => vec![("payload_hex", hex_bytes(f.payload))],
        };
        rows.push((i, name, cols));
    });
    if frames == 0 {
        return Err(Error::NotNav440(
            "no NAV440 frame found (not a NAV440 capture?)".into(),
        ));
    }
    let mut header: Vec<&'static str> = Vec::new();
    for (_, _, cols) in &rows {
        for (n, _) in cols {
            if !header.contains(n) {
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
    for (i, name, cols) in rows {
        out.push_str(&format!("{i},{}", csv_cell(&name)));
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
