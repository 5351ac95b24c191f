//! The CSV rows shared by the host CLI (`nav440 estimate`) and the firmware, so the two
//! outputs compare byte for byte.
//!
//! Columns per axis: the angle, its reference rate, then the 7 velocity estimates
//! (`ave_v, ilo1_v, ilo2_v, ilo3_v, ad_v, ed_v, kf_v`) and the 7 acceleration estimates
//! (`ave_a, ..., kf_a`). One axis: `t,yaw,yaw_rate,ave_v,...,kf_a` ([`HEADER`]; `roll`,
//! `roll_rate` or `pitch`, `pitch_rate` in place of `yaw`, `yaw_rate` for those axes). Several
//! axes: `t`, then for each axis in the order roll, pitch, yaw its 16 columns prefixed with
//! the axis name (`roll,roll_rate,roll_ave_v,...,roll_kf_a,pitch,...,yaw_kf_a`).

use crate::{Axes, AxisRow, Row};
use core::fmt::Write;
use estimators::{BankOutput, Channel};

/// The header line of the yaw axis alone (without line terminator): the default of
/// `nav440 estimate`.
pub const HEADER: &str = "t,yaw,yaw_rate,ave_v,ilo1_v,ilo2_v,ilo3_v,ad_v,ed_v,kf_v,ave_a,ilo1_a,ilo2_a,ilo3_a,ad_a,ed_a,kf_a";

/// Writes the header line (without line terminator) of the rows of `axes`.
pub fn write_header<W: Write>(w: &mut W, axes: Axes) -> core::fmt::Result {
    w.write_str("t")?;
    let prefixed = axes.len() > 1;
    for axis in axes.iter() {
        let name = axis.name();
        write!(w, ",{name},{name}_rate")?;
        // The column names come from the bank's table (`estimators::Channel`).
        for ch in Channel::ALL {
            let col = ch.name();
            if prefixed {
                write!(w, ",{name}_{col}")?;
            } else {
                write!(w, ",{col}")?;
            }
        }
    }
    Ok(())
}

/// Writes the time `t_us` as seconds with 4 decimals (`{:.4}`), computed in integers
/// (`t_us / 1e6`, rounded half up to 0.1 ms): no floating point, no precision loss.
pub fn write_time<W: Write>(w: &mut W, t_us: u64) -> core::fmt::Result {
    let tenths_ms = t_us / 100 + u64::from(t_us % 100 >= 50);
    write!(w, "{}.{:04}", tenths_ms / 10_000, tenths_ms % 10_000)
}

/// Writes one axis's 16 fields, each preceded by a comma:
///
/// * the angle: the exact unwrapped angle, `out.yaw_unwrapped_deg` (f32 Display) when f32
///   holds it exactly (`yaw_residual_deg == 0`), else the exact f64 value
///   `yaw_unwrapped_deg + yaw_residual_deg` (f64 Display), so the column stays exact for any
///   number of turns;
/// * the reference rate (deg/s), empty when there is none (near gimbal lock);
/// * then `out.values` in channel order (`estimators::Channel`: the 7 velocities, then the 7
///   accelerations),
///
/// every `f32` with Rust's `{}` Display (shortest round-trip form), so identical `f32` bits
/// give identical text on host and target.
pub fn write_axis<W: Write>(
    w: &mut W,
    reference_deg_s: Option<f32>,
    out: &BankOutput,
) -> core::fmt::Result {
    if out.yaw_residual_deg == 0.0 {
        write!(w, ",{}", out.yaw_unwrapped_deg)?;
    } else {
        write!(
            w,
            ",{}",
            f64::from(out.yaw_unwrapped_deg) + out.yaw_residual_deg
        )?;
    }
    match reference_deg_s {
        Some(r) => write!(w, ",{r}")?,
        None => w.write_str(",")?,
    }
    for x in out.values.iter() {
        write!(w, ",{x}")?;
    }
    Ok(())
}

/// Writes one row (without line terminator): the time, then the fields of each axis of
/// `axes` ([`write_axis`]; 16 empty fields for an axis the row lacks, which the pipeline
/// never emits).
pub fn write_row<W: Write>(w: &mut W, row: &Row, axes: Axes) -> core::fmt::Result {
    write_time(w, row.t_us)?;
    for axis in axes.iter() {
        match row.axis(axis) {
            Some(AxisRow {
                reference_deg_s,
                out,
            }) => write_axis(w, *reference_deg_s, out)?,
            None => w.write_str(",,,,,,,,,,,,,,,,")?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Axis;

    fn header(axes: Axes) -> heapless::String<1024> {
        let mut s = heapless::String::new();
        write_header(&mut s, axes).unwrap();
        s
    }

    /// The header contracts of issue 10 (spelled out there).
    #[test]
    fn headers() {
        assert_eq!(header(Axes::only(Axis::Yaw)).as_str(), HEADER);
        assert_eq!(
            header(Axes::only(Axis::Roll)).as_str(),
            HEADER.replace("yaw", "roll").as_str()
        );
        assert_eq!(
            header(Axes::only(Axis::Pitch)).as_str(),
            "t,pitch,pitch_rate,ave_v,ilo1_v,ilo2_v,ilo3_v,ad_v,ed_v,kf_v,ave_a,ilo1_a,ilo2_a,ilo3_a,ad_a,ed_a,kf_a"
        );
        let all = header(Axes::ALL);
        let cols: heapless::Vec<&str, 64> = all.split(',').collect();
        assert_eq!(cols.len(), 1 + 3 * 16);
        assert_eq!(&cols[..4], ["t", "roll", "roll_rate", "roll_ave_v"]);
        assert_eq!(cols[16], "roll_kf_a");
        assert_eq!(&cols[17..19], ["pitch", "pitch_rate"]);
        assert_eq!(cols[33], "yaw");
        assert_eq!(cols[48], "yaw_kf_a");
    }

    #[test]
    fn time_and_empty_reference() {
        let out = BankOutput {
            yaw_unwrapped_deg: 1.5,
            yaw_residual_deg: 0.0,
            values: [
                1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25,
            ],
        };
        let mut s = heapless::String::<256>::new();
        write_time(&mut s, 12_345_650).unwrap();
        write_axis(&mut s, None, &out).unwrap();
        assert_eq!(
            s.as_str(),
            "12.3457,1.5,,1,1,1,1,1,1,1,0.25,0.25,0.25,0.25,0.25,0.25,0.25"
        );
    }

    /// The angle column is exact at any number of turns: 10^7 turns + 170 deg is
    /// 3600000170 deg, which f32 cannot hold: the f64 text of the exact value.
    #[test]
    fn exact_angle_text_at_many_turns() {
        let mut bank = estimators::YawBank::<f32>::new(&estimators::BankConfig::default()).unwrap();
        bank.set_turns(10_000_000);
        let out = bank.update(0, 170.0).unwrap();
        let mut s = heapless::String::<512>::new();
        write_axis(&mut s, Some(0.0), &out).unwrap();
        assert!(s.starts_with(",3600000170,0,"), "{s}");
        let mut bank = estimators::YawBank::<f32>::new(&estimators::BankConfig::default()).unwrap();
        let out = bank.update(0, 170.0).unwrap();
        s.clear();
        write_axis(&mut s, Some(0.0), &out).unwrap();
        assert!(s.starts_with(",170,0,"), "{s}");
    }
}
