//! The CSV row shared by the host CLI (`nav440 estimate`) and the firmware, so the two
//! outputs compare byte for byte.

use crate::BankOutput;
use core::fmt::Write;

/// The header line (without line terminator).
pub const HEADER: &str = "t,yaw,yaw_rate,ave_v,ilo1_v,ilo2_v,ilo3_v,ad_v,ed_v,kf_v,ave_a,ilo1_a,ilo2_a,ilo3_a,ad_a,ed_a,kf_a";

/// Writes one row (without line terminator) into `w`:
///
/// * `t`: `t_us` as seconds with 4 decimals (`{:.4}`), computed in integers (`t_us / 1e6`,
///   rounded half up to 0.1 ms), so no floating point and no precision loss for long runs;
/// * `yaw`: the exact unwrapped yaw: `out.yaw_unwrapped_deg` (f32 Display) when f32 holds it
///   exactly (`yaw_residual_deg == 0`), else the exact f64 value
///   `yaw_unwrapped_deg + yaw_residual_deg` (f64 Display), so the column stays exact for any
///   number of turns; `yaw_rate`: `yaw_rate_deg_s` (the sensor's rate);
/// * then `out.values` in channel order ([`crate::Channel`]: the 7 velocities, then the 7
///   accelerations),
///
/// every `f32` with Rust's `{}` Display (shortest round-trip form), so identical `f32` bits
/// give identical text on host and target.
pub fn write_row<W: Write>(
    w: &mut W,
    t_us: u64,
    yaw_rate_deg_s: f32,
    out: &BankOutput,
) -> core::fmt::Result {
    let tenths_ms = t_us / 100 + u64::from(t_us % 100 >= 50);
    write!(w, "{}.{:04}", tenths_ms / 10_000, tenths_ms % 10_000)?;
    if out.yaw_residual_deg == 0.0 {
        write!(w, ",{}", out.yaw_unwrapped_deg)?;
    } else {
        write!(
            w,
            ",{}",
            f64::from(out.yaw_unwrapped_deg) + out.yaw_residual_deg
        )?;
    }
    write!(w, ",{}", yaw_rate_deg_s)?;
    for x in out.values.iter() {
        write!(w, ",{x}")?;
    }
    Ok(())
}
