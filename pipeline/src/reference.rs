//! The rate column of each axis of a row, chosen by type: the Euler reference rate
//! ([`EulerReference`], the default) or the unit's own body rate ([`BodyRates`]).
//!
//! The choice is a type parameter of [`crate::Pipeline`] and [`crate::Estimation`] (a
//! [`Reference`]), not a run-time flag, so that an image built with [`BodyRates`] does not link
//! the Euler kinematics ([`crate::euler::euler_rates_deg`] and its `libm::sincosf`: on a
//! Cortex-M0+ about 13,500 instructions per three-axis sample and 2.7 KB of flash).
//!
//! | `R` | column of axis `<axis>` | value, deg/s |
//! |---|---|---|
//! | [`EulerReference`] | `<axis>_rate` | the angle's time derivative from the body rates and angles ([`crate::euler`]); none for roll and yaw at \|pitch\| >= 80 deg |
//! | [`BodyRates`] | `<axis>_body_rate` | the packet's body rate about the axis as sent: roll <- p (x), pitch <- q (y), yaw <- r (z); none when not finite (B1 sends r only) |
//!
//! The column's name takes the axis as prefix in every header (`yaw_rate`, `yaw_body_rate`,
//! also for one axis alone). Near gimbal lock the pipeline pauses the roll and yaw banks
//! with either reference: the pause follows the pitch angle ([`crate::euler::near_lock`]),
//! never the rate column. When the unit is level (roll = pitch = 0) the two columns hold the
//! same values.
//!
//! ```
//! use nav440_pipeline::{BodyRates, EulerReference, RateColumn, Reference};
//!
//! // Level, turning at r = 30 deg/s: both give p, q, r.
//! let (angles, pqr) = ([0.0, 0.0, 45.0], [1.0, -2.0, 30.0]);
//! assert_eq!(EulerReference::rates_deg_s(angles, pqr), [Some(1.0), Some(-2.0), Some(30.0)]);
//! assert_eq!(BodyRates::rates_deg_s(angles, pqr), [Some(1.0), Some(-2.0), Some(30.0)]);
//! assert_eq!(BodyRates::COLUMN, RateColumn::Body);
//! assert_eq!(RateColumn::Body.suffix(), "body_rate");
//! ```

use crate::euler::euler_rates_deg;

/// What the rate column after each axis's angle holds, as a value: for the code that names or
/// reads the column at run time (the CSV header, [`crate::csv::write_header_for`], and the
/// receivers of the firmware's header, `wire::Layout`). [`Reference::COLUMN`] gives a type's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RateColumn {
    /// The Euler reference rate ([`EulerReference`]): column `<axis>_rate`.
    #[default]
    Euler,
    /// The body rate about the axis ([`BodyRates`]): column `<axis>_body_rate`.
    Body,
}

impl RateColumn {
    /// The column's name after the axis name and `_`: `"rate"` or `"body_rate"`.
    pub const fn suffix(self) -> &'static str {
        match self {
            RateColumn::Euler => "rate",
            RateColumn::Body => "body_rate",
        }
    }

    /// The names a header that lists a bank's channel names puts before them to say which
    /// column the rows carry (the firmware's defmt `header` message and the `wire::Header`
    /// frame): none for the Euler reference (the columns are the bank's, as they always
    /// were), `["body_rate"]` for the body rates.
    pub const fn header_names(self) -> &'static [&'static str] {
        match self {
            RateColumn::Euler => &[],
            RateColumn::Body => &["body_rate"],
        }
    }

    /// Splits a header's column list ([`RateColumn::header_names`] then the bank's channel
    /// names, joined with `,`) into the rate column and the bank's channel names.
    pub fn split_header(columns: &str) -> (RateColumn, &str) {
        match columns
            .strip_prefix(RateColumn::Body.header_names()[0])
            .and_then(|rest| rest.strip_prefix(','))
        {
            Some(channels) => (RateColumn::Body, channels),
            None => (RateColumn::Euler, columns),
        }
    }
}

/// The rate column a pipeline's rows carry per axis ([`crate::AxisRow::reference_deg_s`]):
/// implemented by the zero-sized [`EulerReference`] and [`BodyRates`].
pub trait Reference {
    /// The column as a value (its header name).
    const COLUMN: RateColumn;

    /// The column's values of roll, pitch and yaw (deg/s, indexed by [`crate::Axis::index`])
    /// from a sample's angles (roll, pitch, yaw, deg) and body rates `p, q, r` (deg/s), as
    /// the packet sends them; `None` where there is no value.
    fn rates_deg_s(angles_deg: [f32; 3], pqr_deg_s: [f32; 3]) -> [Option<f32>; 3];
}

/// The Euler reference rates ([`euler_rates_deg`]): each angle's time derivative, columns
/// `<axis>_rate`. The default of [`crate::Pipeline`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct EulerReference;

impl Reference for EulerReference {
    const COLUMN: RateColumn = RateColumn::Euler;

    fn rates_deg_s(angles_deg: [f32; 3], pqr_deg_s: [f32; 3]) -> [Option<f32>; 3] {
        euler_rates_deg(angles_deg[0], angles_deg[1], pqr_deg_s)
    }
}

/// No reference: each axis's column is the unit's body rate about that axis as sent, deg/s
/// (roll <- p, pitch <- q, yaw <- r; `None` when not finite), columns `<axis>_body_rate`. No
/// trigonometry: an image whose pipeline uses it links no `sincosf`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct BodyRates;

impl Reference for BodyRates {
    const COLUMN: RateColumn = RateColumn::Body;

    fn rates_deg_s(_angles_deg: [f32; 3], pqr_deg_s: [f32; 3]) -> [Option<f32>; 3] {
        pqr_deg_s.map(|x| x.is_finite().then_some(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tilted (roll 30, pitch 45 deg): the body rates are p, q, r as given, the Euler rates
    /// are not (as in `crate::euler`'s hand-computed test: with p, q, r = 1, 2, 3 deg/s,
    /// psi' = (1 + 1.5 sqrt 3) sqrt 2 = 5.088448).
    #[test]
    fn body_rates_are_the_packet_rates() {
        let (angles, pqr) = ([30.0, 45.0, 10.0], [1.0, 2.0, 3.0]);
        assert_eq!(
            BodyRates::rates_deg_s(angles, pqr),
            [Some(1.0), Some(2.0), Some(3.0)]
        );
        let yaw = EulerReference::rates_deg_s(angles, pqr)[2].unwrap();
        assert!((f64::from(yaw) - (1.0 + 1.5 * 3f64.sqrt()) * 2f64.sqrt()).abs() < 1e-5);
        // B1: p and q unknown (NaN), r given.
        assert_eq!(
            BodyRates::rates_deg_s(angles, [f32::NAN, f32::NAN, -4.5]),
            [None, None, Some(-4.5)]
        );
        // Near gimbal lock the body rates are still given (the pipeline leaves the roll and
        // yaw fields out there, for both references).
        assert_eq!(
            BodyRates::rates_deg_s([0.0, 85.0, 0.0], pqr),
            [Some(1.0), Some(2.0), Some(3.0)]
        );
    }

    #[test]
    fn header_names_split_back() {
        for c in [RateColumn::Euler, RateColumn::Body] {
            let mut s = heapless::String::<64>::new();
            for n in c.header_names() {
                s.push_str(n).unwrap();
                s.push(',').unwrap();
            }
            s.push_str("ilo1_v,kf_a").unwrap();
            assert_eq!(RateColumn::split_header(&s), (c, "ilo1_v,kf_a"));
        }
        // A bank channel that merely starts with the word is not the marker.
        assert_eq!(
            RateColumn::split_header("body_rate_v,kf_a"),
            (RateColumn::Euler, "body_rate_v,kf_a")
        );
        assert_eq!(EulerReference::COLUMN.suffix(), "rate");
    }
}
