//! The estimator families of the paper bank: one [`Family`] per column of the paper's tables
//! (a velocity estimator and its acceleration series), listed once in `bank/paper.rs`.
//!
//! A family says what the rest of the workspace needs to know about a column, so that code
//! which handles "every family" iterates the list instead of naming the columns:
//!
//! * its name (`ilo1`: the channels `ilo1_v`, `ilo1_a` and the gains file's `[velocity.ilo1]`
//!   table), its label in reports (`ILO1`) and its two [`Channel`]s;
//! * where its gains are in one half of a [`BankGains`] ([`Family::get`], [`Family::set`]),
//!   and what those gains can do ([`Gains`]): be interpolated between two levels of a gain
//!   schedule, and build the family's estimator at a step `h` ([`Gains::build`]);
//! * how a gain schedule blends it ([`Scheduling`]) and, for an observer, where its switch
//!   point is recorded ([`Family::switch_up_mut`]).
//!
//! [`FAMILIES`] lists the plain facts ([`FamilyInfo`]) in column order, for const contexts
//! ([`Channel::VELOCITY`], [`crate::VELOCITY_NAMES`]); [`for_each_family`] calls a
//! [`FamilyVisitor`] with each family's type, for code that needs the gains' types (the
//! noise-adaptive interpolation; on the host, the gains file and the tuner):
//!
//! ```
//! use estimators::{for_each_family, BankGains, Family, FamilyVisitor};
//!
//! /// Collects each family's name and gains, in column order.
//! struct Names(Vec<String>);
//! impl FamilyVisitor for Names {
//!     fn family<F: Family>(&mut self, column: usize) {
//!         let g = F::get(&BankGains::PAPER_VELOCITY);
//!         self.0.push(format!("{column} {} {g:?}", F::NAME));
//!     }
//! }
//! let mut names = Names(Vec::new());
//! for_each_family(&mut names);
//! assert_eq!(names.0[4], "4 ad AdConfig { t: 0.01 }");
//! assert_eq!(names.0.len(), estimators::FAMILY_COUNT);
//! ```
//!
//! # Adding an estimator to the paper bank
//!
//! Four files by hand (tried with a family `SBD` in 8ad431f, reverted in 29b3727):
//!
//! 1. Its module `src/foo.rs`, with its unit test: the law (`FooParams`, a [`crate::Law`]),
//!    its configuration `FooConfig` (the `serde` and `defmt` derives of the others; its
//!    fields are the gains file's keys and the gains a host tuner searches) with its paper
//!    values, `impl Gains for FooConfig` ([`Gains::interpolate`], [`Gains::build`]), the
//!    family marker `FooFamily` (`family!`: name, label, channels, scheduling, its field of
//!    [`BankGains`]) and its row `FooRow` (a [`crate::Row`] with its channels `foo_v`,
//!    `foo_a` and its `warm` policy; [`crate::VelAcc`] runs both in one row).
//! 2. `lib.rs`: `mod foo;` and `pub use foo::{..}`.
//! 3. `bank/paper.rs`: its entry in the family list, which declares [`BankGains`] with it
//!    (`foo: crate::FooConfig = (crate::FOO_VELOCITY, crate::FOO_ACCELERATION) =>
//!    [crate::FooFamily],`), its channels `FooV`, `FooA` in [`Channel`] and
//!    [`Channel::ALL`] (after the last velocity, after the last acceleration), and its row
//!    in [`crate::PaperRows`] (up to 16 rows).
//! 4. `ram.rs`: the sizes the compile-time check holds.
//!
//! The channel lists, the CSV header, the warm gain change, the gain schedule, the gains file,
//! the `nav440 paper` tables, the host's tuner (which reads the gains by their `serde` names
//! and builds the law with [`Gains::build`]) and its `nav440 tune --rust` printer then follow,
//! with nothing in `nav440-cli`. Regenerated, not written: the CSV contract in
//! `tests/table.rs`, the committed `nav440 tune --rust` snippets (`host-tests/data/gains/*.rs`
//! and the firmware's copies) and, re-tuned, the committed gain schedule. The tuned presets
//! ([`crate::BankConfig::NAV440_RATES`], `rates.rs`) run the paper's gains for a family their
//! tables do not list. Optional: an observer that records its own switch point per schedule
//! level needs a field in [`ObserverSwitch`] (with its line in [`ObserverSwitch::all`])
//! returned by [`Family::switch_up_mut`]; a family whose best gains follow the motion's
//! acceleration rather than its jerk sets [`Family::FOLLOWS`] (`follows: Acceleration` in
//! `family!`, as the AD's); one whose gains should go on past a schedule's top level on a
//! gentle motion sets [`Gains::PAST_TOP`] and [`Gains::past_top`] (as the ILOs' and the
//! ED's). docs/HOWTO-ESTIMATOR.md has the details.

use crate::adaptive::ObserverSwitch;
use crate::bank::{BankGains, Channel};
use crate::{ConfigError, KalmanNoise, Law};

/// A family of the paper bank: one column of the paper's tables, a velocity estimator and
/// the acceleration series of the same law (both stages with the acceleration half's gains).
///
/// Implemented by a marker type next to the law (`AveFamily` in `ave.rs`, `IloFamily<I>` in
/// `ilo.rs`, ...) and listed once, in column order, in `bank/paper.rs`.
pub trait Family {
    /// The family's gains in one half of the bank (velocity or acceleration): the law's
    /// configuration, one table of the gains file.
    type Gains: Gains;
    /// Lower-case name: the channels are `NAME_v` and `NAME_a`, the gains file's tables
    /// `[velocity.NAME]` and `[acceleration.NAME]`.
    const NAME: &'static str;
    /// Upper-case label in reports and tables (`nav440 paper`, `nav440 tune`).
    const LABEL: &'static str;
    /// The velocity channel (deg/s).
    const VELOCITY: Channel;
    /// The acceleration channel (deg/s^2).
    const ACCELERATION: Channel;
    /// How a gain schedule blends this family's gains between two levels.
    const SCHEDULING: Scheduling;
    /// Which measure of the motion a schedule that follows the motion scales this family's
    /// noise level by (default: the jerk power).
    const FOLLOWS: Follows = Follows::Jerk;

    /// The family's gains in the bank half `half`.
    fn get(half: &BankGains) -> Self::Gains;

    /// Sets the family's gains in the bank half `half`.
    fn set(half: &mut BankGains, gains: Self::Gains);

    /// Where a schedule level records the noise variance (deg^2) at which this family moves
    /// on to the next level's gains ([`ObserverSwitch`]); `None` (the default): not recorded,
    /// the family switches at the two levels' geometric midpoint.
    fn switch_up_mut(_switch: &mut ObserverSwitch) -> Option<&mut f32> {
        None
    }

    /// The recorded switch point of [`Self::switch_up_mut`], deg^2.
    fn switch_up(switch: &ObserverSwitch) -> Option<f32> {
        let mut s = *switch;
        Self::switch_up_mut(&mut s).map(|x| *x)
    }
}

/// How a gain schedule ([`crate::GainSchedule`]) blends a family's gains between two levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheduling {
    /// An observer whose tuned gains are lightly damped and tuned to the sample period (the
    /// AVE, the ILOs, the ED): a blend of two such sets rings, so with
    /// [`crate::Blend::NearestObservers`] it takes the nearer level's gains (or moves on at
    /// its recorded switch point).
    Observer,
    /// One smooth gain (the AD's time constant, the tracker's noise): interpolated
    /// geometrically between the levels.
    Smooth,
}

/// Which measure of the motion a gain schedule that records its tuning motion's
/// ([`crate::GainSchedule::with_tuned_jerk`], [`crate::GainSchedule::with_tuned_acceleration`])
/// scales a family's noise level by
/// ([`crate::AdaptiveBank`], [`crate::AdaptiveConfig::jerk_margin`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Follows {
    /// The jerk power, beyond a margin (the observers: [`crate::AdaptiveConfig::jerk_margin`];
    /// the tracker, whose best process noise grows with the jerk:
    /// [`crate::AdaptiveConfig::smooth_jerk_margin`]).
    Jerk,
    /// The acceleration power, without a margin: the AD, whose lag costs about `T^2 A` and
    /// whose noise `V / T^2` (time constant `T`, acceleration power `A`, noise variance `V`),
    /// so that its best `T` goes as `(V / A)^(1/4)` and a motion of acceleration power `A`
    /// wants the gains tuned for `V x A_tuned / A`. With a schedule that records no
    /// acceleration power, as [`Self::Jerk`].
    Acceleration,
}

/// The plain facts of a [`Family`] (its consts), for const contexts: see [`FAMILIES`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FamilyInfo {
    /// [`Family::NAME`].
    pub name: &'static str,
    /// [`Family::LABEL`].
    pub label: &'static str,
    /// [`Family::VELOCITY`].
    pub velocity: Channel,
    /// [`Family::ACCELERATION`].
    pub acceleration: Channel,
    /// [`Family::SCHEDULING`].
    pub scheduling: Scheduling,
    /// [`Family::FOLLOWS`].
    pub follows: Follows,
    /// [`Gains::PAST_TOP`] of the family's gains.
    pub past_top: bool,
}

impl FamilyInfo {
    /// The facts of `F`.
    pub const fn of<F: Family>() -> Self {
        Self {
            name: F::NAME,
            label: F::LABEL,
            velocity: F::VELOCITY,
            acceleration: F::ACCELERATION,
            scheduling: F::SCHEDULING,
            follows: F::FOLLOWS,
            past_top: <F::Gains as Gains>::PAST_TOP,
        }
    }
}

/// Something done for every family: [`for_each_family`] calls [`FamilyVisitor::family`] once
/// per family, in column order.
pub trait FamilyVisitor {
    /// Called with the family `F` and its column (0-based, the order of [`FAMILIES`]).
    fn family<F: Family>(&mut self, column: usize);
}

/// The gains of one family in one half of the bank (the law's configuration, e.g.
/// [`crate::IloConfig`]): what a gain schedule does with them, the estimator they build (and,
/// with the `serde` feature, what a gains file reads and writes: the configuration's fields,
/// by name, which host tools also read as the family's named gains).
pub trait Gains: Copy + PartialEq + core::fmt::Debug + SerdeIfEnabled + 'static {
    /// The gains between `self` (weight `1 - w`) and `other` (weight `w`, in `[0, 1]`), for a
    /// gain schedule: each gain geometrically ([`geometric`]: gains span decades); settings
    /// that are not numbers (the AVE's `deltahat` law) from the nearer one.
    fn interpolate(&self, other: &Self, w: f32) -> Self;

    /// Builds the estimator of the family's velocity column with these gains at the step `h`
    /// (s) and hands it to `to`: a law stepped at `h` ([`LawVisitor::law`]; the acceleration
    /// column is two of it in series) or a tracker run once per sample
    /// ([`LawVisitor::tracker`]). The error of the law's constructor if these gains do not
    /// build one at `h`.
    fn build<V: LawVisitor>(&self, h: f32, to: V) -> Result<V::Output, ConfigError>;

    /// `true` if the family's velocity gains go on past a gain schedule's top level
    /// ([`Self::past_top`]); `false` (the default): they stay the top level's.
    const PAST_TOP: bool = false;

    /// The velocity gains for a motion that moves more gently, or a noise that is larger, than
    /// the top level of a schedule that follows the motion reaches ([`PastTop`]), from `self`,
    /// the top level's: `self` (the default) for a family whose [`Self::PAST_TOP`] is
    /// `false`.
    fn past_top(&self, _rule: &PastTop) -> Self {
        *self
    }
}

/// Where an observer's gains go past a gain schedule's top level ([`Gains::past_top`]): the
/// ILOs to per-sample poles at the bandwidth `wn_rad_s` (rad/s) with the damping `zeta`, for
/// the law's step `h_s` and the sample period `dt_s` (s) ([`crate::IloConfig::per_sample`]);
/// the ED by the motion's acceleration ratio.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PastTop {
    /// The bandwidth, rad/s.
    pub wn_rad_s: f64,
    /// The damping, in (0, 1).
    pub zeta: f64,
    /// The law's step, s.
    pub h_s: f64,
    /// The nominal sample period, s.
    pub dt_s: f64,
    /// The motion's acceleration power over that of the motion the schedule was tuned on
    /// (dimensionless, >= 0; 1 where either is not known).
    pub acceleration_ratio: f32,
}

/// What receives the estimator a family's gains build ([`Gains::build`]).
pub trait LawVisitor {
    /// What the visitor makes of the estimator.
    type Output;

    /// A law stepped at `h` between samples, its output the velocity estimate (in the bank the
    /// acceleration column runs two of it in series, both with the acceleration half's gains).
    fn law<L: Law<Num = f32>>(self, law: L) -> Self::Output;

    /// A Kalman tracker with the noise `noise`, run once per sample at the nominal sample
    /// period (the bank's [`crate::KalmanParams`]; its velocity or its acceleration output).
    fn tracker(self, noise: KalmanNoise) -> Self::Output;
}

/// `a^(1-w) b^w` for positive `a`, `b` (linear in `ln`); `a + (b - a) w` otherwise; `a` for
/// `w <= 0`, `b` for `w >= 1`. How a gain schedule interpolates one gain.
pub fn geometric(a: f32, b: f32, w: f32) -> f32 {
    if a == b || w <= 0.0 {
        a
    } else if w >= 1.0 {
        b
    } else if a > 0.0 && b > 0.0 {
        a * libm::expf(w * libm::logf(b / a))
    } else {
        a + (b - a) * w
    }
}

/// `Serialize + DeserializeOwned` with the `serde` feature (so that a gains file can read and
/// write every family's gains), nothing without it.
#[cfg(feature = "serde")]
pub trait SerdeIfEnabled: serde::Serialize + serde::de::DeserializeOwned {}
#[cfg(feature = "serde")]
impl<T: serde::Serialize + serde::de::DeserializeOwned> SerdeIfEnabled for T {}
/// `Serialize + DeserializeOwned` with the `serde` feature (so that a gains file can read and
/// write every family's gains), nothing without it.
#[cfg(not(feature = "serde"))]
pub trait SerdeIfEnabled {}
#[cfg(not(feature = "serde"))]
impl<T> SerdeIfEnabled for T {}

/// Defines the paper bank's families and the gains of one half of the bank from one list:
/// the struct [`BankGains`] (one field per entry, with its docs), its paper sets
/// [`BankGains::PAPER_VELOCITY`] and [`BankGains::PAPER_ACCELERATION`], and the family list
/// [`FAMILIES`] and [`for_each_family`].
///
/// An entry is `field: Type = (paper velocity, paper acceleration) => [Family, ..]`: the
/// field of [`BankGains`] and its type, its values in the two paper sets, and the families
/// whose gains it holds (one, or one per element of an array field), in column order.
macro_rules! families {
    (
        $(#[$sm:meta])*
        pub struct BankGains {
            $(
                $(#[$m:meta])*
                $field:ident: $ty:ty = ($velocity:expr, $acceleration:expr) => [$($F:ty),+],
            )+
        }
    ) => {
        $(#[$sm])*
        pub struct BankGains {
            $(
                $(#[$m])*
                pub $field: $ty,
            )+
        }

        impl BankGains {
            /// The paper's velocity set, the first paper value of each entry of the family
            /// list: AVE (500, 20000), Table 2 ILOs, AD `T = 0.01`, ED (700, 770), and the
            /// default tracker noise.
            pub const PAPER_VELOCITY: Self = Self {
                $($field: $velocity,)+
            };

            /// The paper's acceleration set, the second paper value of each entry: AVE-AVE,
            /// Table 4 ILO-ILO, AD-AD `T = 0.1`, ED-ED, and the default tracker noise.
            pub const PAPER_ACCELERATION: Self = Self {
                $($field: $acceleration,)+
            };

        }

        /// The families of the paper bank, in column order (the order of
        /// [`crate::Channel::VELOCITY`] and of every per-family table and report).
        pub const FAMILIES: [$crate::FamilyInfo; [$($(stringify!($F)),+),+].len()] =
            [$($($crate::FamilyInfo::of::<$F>()),+),+];

        /// The number of families ([`FAMILIES`]`.len()`).
        pub const FAMILY_COUNT: usize = FAMILIES.len();

        /// Calls `visitor.family::<F>(column)` for each family `F` of [`FAMILIES`], in order.
        pub fn for_each_family<V: $crate::FamilyVisitor>(visitor: &mut V) {
            let mut column = 0;
            $($(
                visitor.family::<$F>(column);
                column += 1;
            )+)+
            let _ = column;
        }
    };
}
pub(crate) use families;

/// A family marker whose gains are one field of each [`BankGains`] half: the marker type
/// (with its docs) and its [`Family`] implementation. `switch:` names the field of
/// [`ObserverSwitch`] an observer records its switch point in ([`Family::switch_up_mut`]);
/// without it the family has none. `follows:` names the [`Follows`] variant of
/// [`Family::FOLLOWS`]; without it the default (the jerk).
macro_rules! family {
    (
        $(#[$m:meta])*
        $marker:ident {
            gains: $gains:ident = BankGains::$field:ident,
            name: $name:literal,
            label: $label:literal,
            channels: $velocity:ident, $acceleration:ident,
            scheduling: $scheduling:ident,
            $(follows: $follows:ident,)?
            $(switch: ObserverSwitch::$switch:ident,)?
        }
    ) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug)]
        pub struct $marker;

        impl $crate::family::Family for $marker {
            type Gains = $gains;
            const NAME: &'static str = $name;
            const LABEL: &'static str = $label;
            const VELOCITY: $crate::bank::Channel = $crate::bank::Channel::$velocity;
            const ACCELERATION: $crate::bank::Channel = $crate::bank::Channel::$acceleration;
            const SCHEDULING: $crate::family::Scheduling =
                $crate::family::Scheduling::$scheduling;
            $(const FOLLOWS: $crate::family::Follows = $crate::family::Follows::$follows;)?

            fn get(half: &$crate::bank::BankGains) -> $gains {
                half.$field
            }

            fn set(half: &mut $crate::bank::BankGains, gains: $gains) {
                half.$field = gains;
            }

            $(
                fn switch_up_mut(
                    switch: &mut $crate::adaptive::ObserverSwitch,
                ) -> Option<&mut f32> {
                    Some(&mut switch.$switch)
                }
            )?
        }
    };
}
pub(crate) use family;

pub use crate::bank::{for_each_family, FAMILIES, FAMILY_COUNT};

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::{BankConfig, EdConfig};
    use std::{format, vec::Vec};

    family! {
        /// A family declared with `follows:` (the ED's gains and channels).
        FollowsAcceleration {
            gains: EdConfig = BankGains::ed,
            name: "fa",
            label: "FA",
            channels: EdV, EdA,
            scheduling: Observer,
            follows: Acceleration,
        }
    }

    /// `family!` sets `Family::FOLLOWS` from `follows:`, and leaves the default (the jerk)
    /// without it; the AD follows the acceleration, every other family of the bank the jerk.
    #[test]
    fn follows_is_the_jerk_unless_declared() {
        assert_eq!(FollowsAcceleration::FOLLOWS, Follows::Acceleration);
        assert_eq!(crate::EdFamily::FOLLOWS, Follows::Jerk);
        let following: Vec<&str> = FAMILIES
            .iter()
            .filter(|f| f.follows == Follows::Acceleration)
            .map(|f| f.label)
            .collect();
        assert_eq!(following, ["AD"]);
    }

    /// The families' facts as the visitor sees them.
    struct Collect(Vec<(usize, FamilyInfo)>);
    impl FamilyVisitor for Collect {
        fn family<F: Family>(&mut self, column: usize) {
            self.0.push((column, FamilyInfo::of::<F>()));
        }
    }

    /// The list is consistent: the visitor sees [`FAMILIES`] in order; each family's channels
    /// are its name with `_v` and `_a`, and every channel of the paper bank belongs to
    /// exactly one family.
    #[test]
    fn the_families_cover_the_channels_once() {
        let mut seen = Collect(Vec::new());
        for_each_family(&mut seen);
        let want: Vec<_> = FAMILIES.iter().copied().enumerate().collect();
        assert_eq!(seen.0, want);
        for f in FAMILIES {
            assert_eq!(f.velocity.name(), format!("{}_v", f.name));
            assert_eq!(f.acceleration.name(), format!("{}_a", f.name));
        }
        for c in Channel::ALL {
            let owners = FAMILIES
                .iter()
                .filter(|f| f.velocity == *c || f.acceleration == *c)
                .count();
            assert_eq!(owners, 1, "{}", c.name());
        }
    }

    /// `set` writes what `get` reads, and only there: setting every family's gains of one
    /// half into the other gives the first half.
    #[test]
    fn get_and_set_cover_the_bank_gains() {
        struct Copy(BankGains, BankGains);
        impl FamilyVisitor for Copy {
            fn family<F: Family>(&mut self, _: usize) {
                F::set(&mut self.1, F::get(&self.0));
                assert_eq!(F::get(&self.1), F::get(&self.0));
            }
        }
        let mut c = Copy(BankConfig::NAV440.velocity, BankConfig::PAPER.acceleration);
        for_each_family(&mut c);
        assert_eq!(c.1, c.0);
    }
}
