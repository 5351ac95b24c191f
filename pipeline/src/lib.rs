//! The one NAV440 pipeline of the host CLI (`nav440 estimate`) and the firmware:
//!
//! bytes -> frames (`nav440_proto::Parser`) -> attitude packets (A0/A1/A2/N0/N1/B1:
//! roll, pitch, yaw and the body rates p, q, r) -> BIT check ([`bit`]: a masterFail sample is
//! not estimated, and counted) -> clock (`nav440_proto::TimeBase`: time faults counted) ->
//! warm-up and the nominal-period rule ([`period`]) -> one estimator bank per selected
//! [`Axis`] (any `estimators::EstimatorBank`, e.g. `PaperBank` or `ProductBank`; roll and yaw
//! unwrapped at +-180 deg, pitch not) -> [`Row`] with each angle's rate column -> CSV
//! ([`csv`], the columns named by the bank).
//!
//! The rate column is a type parameter of the pipeline ([`Reference`]): the reference rate
//! from the Euler kinematics ([`EulerReference`], [`euler`]; the default) or, for an image that
//! must not link the trigonometry, the unit's body rate about each axis ([`BodyRates`]).
//!
//! Both binaries call [`Pipeline`] (the host with its own bank type for noise and fixed
//! point), so their rows agree by construction; the CI's byte-for-byte diff
//! (`cargo xtask ci-firmware`) is the proof. See docs/PIPELINE.md.
//!
//! `no_std`, no heap (`heapless`), no `unsafe`.
//!
//! ```
//! use nav440_pipeline::{axis_bank, Axes, Axis, Pipeline};
//! use estimators::{BankConfig, PaperBank};
//! use nav440_proto::{encode_frame, A2Fields, PacketType};
//!
//! // 1 s of A2 packets at 100 Hz, yaw turning at 30 deg/s with r = 30 deg/s, level.
//! let mut bytes = Vec::new();
//! for k in 0..100u32 {
//!     let yaw = 0.3 * k as f64; // deg
//!     let p = A2Fields {
//!         yaw_true: (yaw * 65536.0 / 360.0).round() as i16,
//!         rate_z: (30.0f64.to_radians() * 65536.0 / (7.0 * std::f64::consts::PI)).round() as i16,
//!         time_itow: 1000 + 10 * k,
//!         ..Default::default()
//!     };
//!     let mut frame = [0u8; 64];
//!     let n = encode_frame(PacketType::A2, &p.payload(), &mut frame).unwrap();
//!     bytes.extend_from_slice(&frame[..n]);
//! }
//! let build = |axis: Axis, cfg: &BankConfig| -> Result<PaperBank<f32>, _> { axis_bank(axis, cfg) };
//! let mut pipe = Pipeline::new(Axes::only(Axis::Yaw), BankConfig::default(), build);
//! let mut lines = Vec::new();
//! pipe.feed_csv(&bytes, |l| lines.push(l.to_string())).unwrap();
//! pipe.finish_csv(|l| lines.push(l.to_string())).unwrap();
//! assert_eq!(lines.len(), 100);
//! let last: Vec<f64> = lines[99].trim().split(',').map(|x| x.parse().unwrap()).collect();
//! assert!((last[2] - 30.0).abs() < 0.01); // yaw_rate: the Euler yaw rate = r when level
//! assert!((last[3] - 30.0).abs() < 0.5); // AVE velocity, deg/s
//! ```
#![no_std]
#![forbid(unsafe_code)]

mod axis;
pub mod bit;
pub mod csv;
pub mod euler;
pub mod period;
mod pipeline;
mod reference;
#[cfg(feature = "defmt")]
pub mod report;
mod sample;
pub mod watch;
#[cfg(feature = "wire")]
pub mod wire;

pub use axis::{Axes, Axis};
pub use pipeline::{
    adaptive_axis_bank, adaptive_product_axis_bank, axis_bank, axis_config,
    self_tuning_product_axis_bank, AxisRow, Counters, CsvLine, Estimation, Pipeline, Rejections,
    Row, ROW_CAPACITY,
};
pub use reference::{BodyRates, EulerReference, RateColumn, Reference};
pub use sample::{
    attitude, AllPackets, Attitude, Decoder, FrameSeen, FrontCounters, Frontend, OnlyA2, Sample,
};

/// The examples of the crate README, compiled and run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
