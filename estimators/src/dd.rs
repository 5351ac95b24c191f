//! Trial: a "dirty derivative" `s / (T s + 1)` as a new law (to count the places a new
//! paper-bank estimator touches).

use crate::bank::{BankGains, Channel};
use crate::error::positive;
use crate::family::{coordinate, geometric, Family, Gains, Scheduling, Scorer, SearchPoint};
use crate::law::Law;
use crate::{ConfigError, Real};

/// Configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct DdConfig {
    /// Time constant, s.
    pub t: f32,
}

/// Parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DdParams<T: Real> {
    inv_t: T,
    h: T,
}

/// State.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DdState<T: Real> {
    /// Low-passed input.
    pub z: T,
    /// Output.
    pub u: T,
}

impl<T: Real> DdParams<T> {
    /// Validates.
    pub fn new(c: &DdConfig, h: f32) -> Result<Self, ConfigError> {
        let t = positive("T", f64::from(c.t))?;
        let h = positive("h", f64::from(h))?;
        Ok(Self {
            inv_t: T::from_f64(1.0 / t),
            h: T::from_f64(h),
        })
    }
}

impl<T: Real> Law for DdParams<T> {
    type Num = T;
    type State = DdState<T>;
    fn init(&self, y0: T) -> DdState<T> {
        DdState { z: y0, u: T::ZERO }
    }
    fn step(&self, s: &mut DdState<T>, y: T) -> T {
        let u = (y - s.z) * self.inv_t;
        s.z = s.z + self.h * u;
        s.u = u;
        u
    }
    fn output(&self, s: &DdState<T>) -> T {
        s.u
    }
    fn translate(&self, s: &mut DdState<T>, d: T) {
        s.z = s.z + d;
    }
}

/// The DD family.
#[derive(Clone, Copy, Debug)]
pub struct DdFamily;

impl Family for DdFamily {
    type Gains = DdConfig;
    const NAME: &'static str = "dd";
    const LABEL: &'static str = "DD";
    const VELOCITY: Channel = Channel::DdV;
    const ACCELERATION: Channel = Channel::DdA;
    const SCHEDULING: Scheduling = Scheduling::Smooth;
    fn get(half: &BankGains) -> DdConfig {
        half.dd
    }
    fn set(half: &mut BankGains, gains: DdConfig) {
        half.dd = gains;
    }
}

impl Gains for DdConfig {
    fn interpolate(&self, other: &Self, w: f32) -> Self {
        DdConfig {
            t: geometric(self.t, other.t, w),
        }
    }
    fn search_point(&self) -> SearchPoint {
        SearchPoint::from_array([f64::from(self.t)])
    }
    fn with_search_point(&self, x: &[f64]) -> Self {
        DdConfig {
            t: coordinate(x, 0, self.t),
        }
    }
    fn search_box(_h_s: f64) -> (SearchPoint, SearchPoint) {
        (
            SearchPoint::from_array([1e-4]),
            SearchPoint::from_array([1.0]),
        )
    }
    fn score<S: Scorer>(&self, h: f32, scorer: &S) -> Result<S::Score, ConfigError> {
        Ok(scorer.law(DdParams::<f32>::new(self, h)?))
    }
    fn describe(&self, w: &mut dyn core::fmt::Write) -> core::fmt::Result {
        write!(w, "T={}", self.t)
    }
}

impl crate::RustLiteral for DdConfig {
    const RUST_TYPES: &'static [&'static str] = &["DdConfig"];

    fn write_rust(&self, w: &mut dyn core::fmt::Write, _: crate::Indent<'_>) -> core::fmt::Result {
        write!(w, "DdConfig {{ t: {:?} }}", self.t)
    }
}
