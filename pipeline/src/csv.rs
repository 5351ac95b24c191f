//! The CSV rows shared by the host CLI (`nav440 estimate`) and the firmware, so the two
//! outputs compare byte for byte.
//!
//! The columns come from the bank: per axis the angle, its rate column, then one column per
//! channel of the bank's output ([`EstimatorOutput::CHANNEL_NAMES`], in order). One axis:
//! `t,yaw,yaw_rate,<channels>` (`roll`, `roll_rate` or `pitch`, `pitch_rate` in place of
//! `yaw`, `yaw_rate` for those axes). Several axes: `t`, then for each axis in the order
//! roll, pitch, yaw its columns prefixed with the axis name (`roll,roll_rate,roll_<channel>,
//! ...,pitch,...`).
//!
//! The rate column is the Euler reference rate, `<axis>_rate`, or in a pipeline whose
//! [`crate::Reference`] is [`crate::BodyRates`] the unit's body rate about the axis,
//! `<axis>_body_rate` (`t,yaw,yaw_body_rate,<channels>`; [`write_header_for`] with
//! [`RateColumn::Body`]); the values are written alike (deg/s, empty when absent).
//!
//! * The paper bank (`estimators::PaperBank`, the default of `nav440 estimate`): the 7
//!   velocity estimates (`ave_v, ilo1_v, ilo2_v, ilo3_v, ad_v, ed_v, kf_v`) and the 7
//!   acceleration estimates (`ave_a, ..., kf_a`); yaw alone is [`HEADER`].
//! * The product bank (`estimators::AdaptiveProductBank` by default, `ProductBank` with
//!   fixed gains; `nav440 estimate --bank product`):
//!   `t,yaw,yaw_rate,ilo1_v,kf_a`; all axes
//!   `t,roll,roll_rate,roll_ilo1_v,roll_kf_a,pitch,...,yaw_kf_a`.
//!
//! ```
//! use estimators::{Fx, PaperBank, ProductBank, ProductOutput};
//! use nav440_pipeline::{csv, Axes, Axis, RateColumn};
//!
//! let mut s = String::new();
//! csv::write_header::<ProductBank<Fx>>(&mut s, Axes::only(Axis::Yaw)).unwrap();
//! assert_eq!(s, "t,yaw,yaw_rate,ilo1_v,kf_a");
//! s.clear();
//! csv::write_header::<PaperBank<f32>>(&mut s, Axes::only(Axis::Yaw)).unwrap();
//! assert_eq!(s, csv::HEADER);
//! s.clear();
//! csv::write_header_for::<ProductOutput>(&mut s, Axes::only(Axis::Yaw), RateColumn::Body)
//!     .unwrap();
//! assert_eq!(s, "t,yaw,yaw_body_rate,ilo1_v,kf_a");
//! ```

use crate::{Axes, AxisRow, RateColumn, Row};
use core::fmt::Write;
use estimators::{EstimatorBank, EstimatorOutput, PaperOutput};

/// The header line of the paper bank's yaw axis alone (without line terminator): the default
/// of `nav440 estimate` (`write_header::<PaperBank<_>>(w, Axes::only(Axis::Yaw))`), built at
/// compile time from the bank's channel names.
pub const HEADER: &str = match core::str::from_utf8(&HEADER_BYTES) {
    Ok(s) => s,
    Err(_) => panic!("the channel names are not UTF-8"),
};

/// The columns of [`HEADER`].
const HEADER_NAMES: &[&[&str]] = &[&["t", "yaw", "yaw_rate"], <PaperOutput>::NAMES.as_slice()];
/// [`HEADER`] as bytes.
const HEADER_BYTES: [u8; estimators::columns_len(HEADER_NAMES)] =
    estimators::join_columns(HEADER_NAMES);

/// Writes the header line (without line terminator) of the rows of `axes` from the bank `B`
/// (any `estimators::EstimatorBank`) with the Euler reference rate (`<axis>_rate`): the
/// column names are its output's channel names ([`EstimatorOutput::CHANNEL_NAMES`]). Another
/// rate column: [`write_header_for`].
pub fn write_header<B: EstimatorBank + ?Sized>(
    w: &mut impl Write,
    axes: Axes,
) -> core::fmt::Result {
    write_header_of::<B::Output>(w, axes)
}

/// [`write_header`] named by the bank's output type `O` instead of the bank.
pub fn write_header_of<O: EstimatorOutput>(w: &mut impl Write, axes: Axes) -> core::fmt::Result {
    write_header_for::<O>(w, axes, RateColumn::Euler)
}

/// [`write_header_of`] with the rate column `rate`: `<axis>_rate` ([`RateColumn::Euler`]) or
/// `<axis>_body_rate` ([`RateColumn::Body`]) after each axis's angle, the axis name prefixed
/// for one axis as for several (a pipeline's is [`crate::Pipeline::rate_column`]).
pub fn write_header_for<O: EstimatorOutput>(
    w: &mut impl Write,
    axes: Axes,
    rate: RateColumn,
) -> core::fmt::Result {
    w.write_str("t")?;
    let prefixed = axes.len() > 1;
    let suffix = rate.suffix();
    for axis in axes.iter() {
        let name = axis.name();
        write!(w, ",{name},{name}_{suffix}")?;
        for col in O::CHANNEL_NAMES {
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

/// Writes one axis's fields (2 + the output's channels), each preceded by a comma:
///
/// * the angle: the exact unwrapped angle, `out.unwrapped_deg()` (f32 Display) when f32
///   holds it exactly (`residual_deg() == 0`), else the exact f64 value
///   `unwrapped_deg + residual_deg` (f64 Display), so the column stays exact for any number
///   of turns;
/// * the rate column (deg/s: the reference rate or the body rate), empty when there is none
///   (the Euler reference near gimbal lock, a body rate the packet does not send);
/// * then `out.values()` in channel order ([`EstimatorOutput::CHANNEL_NAMES`]; the paper
///   bank's: the 7 velocities, then the 7 accelerations),
///
/// every `f32` with Rust's `{}` Display (shortest round-trip form), so identical `f32` bits
/// give identical text on host and target.
pub fn write_axis<W: Write, O: EstimatorOutput>(
    w: &mut W,
    reference_deg_s: Option<f32>,
    out: &O,
) -> core::fmt::Result {
    if out.residual_deg() == 0.0 {
        write!(w, ",{}", out.unwrapped_deg())?;
    } else {
        write!(w, ",{}", out.unwrapped_deg_f64())?;
    }
    match reference_deg_s {
        Some(r) => write!(w, ",{r}")?,
        None => w.write_str(",")?,
    }
    for x in out.values() {
        write!(w, ",{x}")?;
    }
    Ok(())
}

/// Writes one row (without line terminator): the time, then the fields of each axis of
/// `axes` ([`write_axis`]; `2 + O::CHANNELS` empty fields for an axis the row lacks: roll and
/// yaw near gimbal lock, see [`crate::euler::near_lock`]).
pub fn write_row<W: Write, O: EstimatorOutput>(
    w: &mut W,
    row: &Row<O>,
    axes: Axes,
) -> core::fmt::Result {
    write_time(w, row.t_us)?;
    for axis in axes.iter() {
        match row.axis(axis) {
            Some(AxisRow {
                reference_deg_s,
                out,
            }) => write_axis(w, *reference_deg_s, out)?,
            None => {
                for _ in 0..2 + O::CHANNELS {
                    w.write_str(",")?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::Axis;
    use estimators::{Fx, PaperBank, PaperOutput, ProductBank, ProductOutput};

    fn header(axes: Axes) -> heapless::String<1024> {
        let mut s = heapless::String::new();
        write_header::<PaperBank<f32>>(&mut s, axes).unwrap();
        s
    }

    fn product_header(axes: Axes) -> heapless::String<1024> {
        let mut s = heapless::String::new();
        write_header::<ProductBank<Fx>>(&mut s, axes).unwrap();
        s
    }

    /// The product bank's header: its channels after the angle and the rate; all axes prefix
    /// each channel with the axis name (the product bank's columns themselves are checked
    /// against a literal in `estimators/tests/table.rs`).
    #[test]
    fn product_headers() {
        let cols = <estimators::ProductOutput>::NAMES;
        assert_eq!(cols.len(), 2);
        let (v, a) = (cols[0], cols[1]);
        let yaw = std::format!("t,yaw,yaw_rate,{v},{a}");
        assert_eq!(product_header(Axes::only(Axis::Yaw)).as_str(), yaw);
        assert_eq!(
            product_header(Axes::only(Axis::Pitch)).as_str(),
            yaw.replace("yaw", "pitch")
        );
        assert_eq!(
            product_header(Axes::ALL).as_str(),
            std::format!(
                "t,roll,roll_rate,roll_{v},roll_{a},pitch,pitch_rate,pitch_{v},pitch_{a},yaw,yaw_rate,yaw_{v},yaw_{a}"
            )
        );
        // The f32 bank and the output type name the same columns.
        let mut s = heapless::String::<256>::new();
        write_header::<ProductBank<f32>>(&mut s, Axes::only(Axis::Yaw)).unwrap();
        let mut t = heapless::String::<256>::new();
        write_header_of::<estimators::ProductOutput>(&mut t, Axes::only(Axis::Yaw)).unwrap();
        assert_eq!(s, t);
    }

    /// A row of the product bank: time, angle, rate, `ilo1_v`, `kf_a`; an absent axis is
    /// 4 empty fields.
    #[test]
    fn product_row() {
        let out = <estimators::ProductOutput>::new(-10.5, 0.0, [12.25, -0.5]);
        let mut axes = [None; 3];
        axes[Axis::Yaw.index()] = Some(AxisRow {
            reference_deg_s: Some(3.0),
            out,
        });
        let row = Row { t_us: 20_000, axes };
        let mut s = heapless::String::<256>::new();
        write_row(&mut s, &row, Axes::only(Axis::Yaw)).unwrap();
        assert_eq!(s.as_str(), "0.0200,-10.5,3,12.25,-0.5");
        s.clear();
        write_row(&mut s, &row, Axes::ALL).unwrap();
        assert_eq!(s.as_str(), "0.0200,,,,,,,,,-10.5,3,12.25,-0.5");
    }

    /// The body-rate headers: `<axis>_body_rate` in place of `<axis>_rate`, the axis name
    /// prefixed for one axis alone as for all; nothing else changes.
    #[test]
    fn body_rate_headers() {
        let body = |axes| {
            let mut s = heapless::String::<1024>::new();
            write_header_for::<ProductOutput>(&mut s, axes, RateColumn::Body).unwrap();
            s
        };
        assert_eq!(
            body(Axes::only(Axis::Yaw)).as_str(),
            "t,yaw,yaw_body_rate,ilo1_v,kf_a"
        );
        assert_eq!(
            body(Axes::only(Axis::Roll)).as_str(),
            "t,roll,roll_body_rate,ilo1_v,kf_a"
        );
        assert_eq!(
            body(Axes::ALL).as_str(),
            "t,roll,roll_body_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_body_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_body_rate,yaw_ilo1_v,yaw_kf_a"
        );
        for axes in [Axes::only(Axis::Pitch), Axes::ALL] {
            let mut paper = heapless::String::<1024>::new();
            write_header_for::<PaperOutput>(&mut paper, axes, RateColumn::Body).unwrap();
            assert_eq!(
                paper.as_str(),
                header(axes).replace("_rate", "_body_rate").as_str()
            );
            let mut euler = heapless::String::<1024>::new();
            write_header_for::<PaperOutput>(&mut euler, axes, RateColumn::Euler).unwrap();
            assert_eq!(euler, header(axes));
        }
    }

    /// The header contracts: the paper bank's yaw header is [`HEADER`]; one other axis renames
    /// its two columns; all axes prefix every channel with the axis name.
    #[test]
    fn headers() {
        assert_eq!(header(Axes::only(Axis::Yaw)).as_str(), HEADER);
        assert_eq!(
            header(Axes::only(Axis::Roll)).as_str(),
            HEADER.replace("yaw", "roll").as_str()
        );
        assert_eq!(
            header(Axes::only(Axis::Pitch)).as_str(),
            HEADER.replace("yaw", "pitch").as_str()
        );
        // The channels follow the angle and its rate, in the bank's order.
        let mut cols = HEADER.split(',');
        assert_eq!(
            cols.by_ref().take(3).collect::<heapless::Vec<_, 3>>(),
            ["t", "yaw", "yaw_rate"]
        );
        assert!(cols.eq(<PaperOutput>::NAMES.iter().copied()));
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
        let out = <PaperOutput>::new(
            1.5,
            0.0,
            [
                1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25,
            ],
        );
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
        let mut bank =
            estimators::PaperBank::<f32>::new(&estimators::BankConfig::default()).unwrap();
        bank.set_turns(10_000_000);
        let out = bank.update(0, 170.0).unwrap();
        let mut s = heapless::String::<512>::new();
        write_axis(&mut s, Some(0.0), &out).unwrap();
        assert!(s.starts_with(",3600000170,0,"), "{s}");
        let mut bank =
            estimators::PaperBank::<f32>::new(&estimators::BankConfig::default()).unwrap();
        let out = bank.update(0, 170.0).unwrap();
        s.clear();
        write_axis(&mut s, Some(0.0), &out).unwrap();
        assert!(s.starts_with(",170,0,"), "{s}");
    }
}
