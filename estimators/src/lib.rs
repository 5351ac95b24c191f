//! Velocity and acceleration estimators of Kawakami et al. (2013), "Velocity and acceleration
//! estimation by iterative learning observer and performance validation with MEMS-based
//! inertial sensors": the adaptive velocity estimator ([`Ave`], eq. 4), the iterative learning
//! observer ([`Ilo`], eqs. 9/13, and the general [`gilo::GeneralIlo`] with the Theorem 3.1
//! check), the approximate differentiator ([`Ad`]), Levant's exact differentiator ([`Ed`],
//! eqs. 5-7), their series connections ([`Series`], acceleration) and a constant-acceleration
//! Kalman tracker ([`Kalman`]) as an engineer's reference.
//!
//! `no_std`, no heap, no `unsafe`, no panics on any input. Every law is generic over [`Real`]:
//! `f32`, `f64` or the saturating fixed-point [`Fx`] (Q31.32), through one code path.
//!
//! Laws are continuous-time and stepped with explicit Euler at a step `h` (paper: 1e-4 s);
//! samples arriving at the sensor rate are fed through the [`SampleAdapter`] (or the
//! [`PaperBank`]), which runs `n = round(dt / h)` steps per sample with linear interpolation
//! ([`Hold::Linear`], default) or a zero-order hold. Linear laws (ILO, AD and their series)
//! can use their exact multi-step map ([`ClosedForm`]) instead of `n` steps.
//!
//! * [`Law`]: every law keeps its validated coefficients (`AveParams`, `IloParams`, `AdParams`,
//!   `EdParams`, `KalmanParams`, [`Series`], [`ClosedForm`]) apart from its small state and
//!   steps with `step(&self, &mut State, y)`; [`Stateful`] (aliases [`Ave`], [`Ilo`], [`Ad`],
//!   [`Ed`]) binds the two into the classic [`Estimator`] object.
//! * A bank is a tuple of rows ([`Row`]: a law, how it is built from the [`BankConfig`], its
//!   channels) behind one input stage: [`Bank`]. [`PaperBank`] (the paper's 14 estimators,
//!   output indexed by [`Channel`]) and [`ProductBank`] (one velocity and one acceleration
//!   estimator) are two of them. [`BankConfig::wrap`] picks
//!   the unwrapping per axis ([`Wrap`]). See docs/BANK.md.
//! * [`family`]: the paper bank's estimator families (one per column of the paper's tables),
//!   listed once ([`FAMILIES`], [`for_each_family`]): the channel lists, the gain schedule's
//!   interpolation and the host tools' gains file iterate them.
//! * Another sensor: [`ProductBank`] with [`BankConfig::sample_period_s`] set to the sensor's
//!   period (the default is 100 Hz) and [`Wrap::None`] for a signal that does not wrap
//!   (`examples/other_imu_200hz.rs`, docs/OTHER-IMU.md).
//! * [`EstimatorBank`]: the one trait of every bank (every [`Bank`] and [`AdaptiveBank`]):
//!   `update`, `new_epoch`, `reinit_count`, `take_over`, and its [`EstimatorOutput`]
//!   (unwrapped angle and channel values) with the channels' count and names as consts
//!   (`<ProductBank<Fx> as EstimatorBank>::CHANNELS`).
//! * Feature `serde`: `Serialize`/`Deserialize` on the configuration types (no_std, no alloc).
//! * Units: inputs in deg (any position-like unit works), velocities in unit/s, accelerations
//!   in unit/s^2, times in s (`h`, `T`, `tau`) or integer microseconds (sample timestamps).
//! * [`presets`]: every parameter set of the paper; [`ram`]: `size_of` of every estimator
//!   (checked at compile time); [`gilo`]: the general ILO and Theorem 3.1. (The CSV row and
//!   the nominal-period rule live in the `nav440-pipeline` crate, with the one pipeline of
//!   the host CLI and the firmware.)
//! * Fixed point: [`Fx`] (Q31.32, saturating) matches `f32` on a paper-like experiment (yaw
//!   within +-90 deg, rate +-300 deg/s, 100 Hz) within 1 % in every MSE (ED 5 %, ED-ED 20 %) and
//!   0.05 deg/s / 1 deg/s^2 sample by sample (the bounds `tests/bank.rs` asserts; `cargo test
//!   --release -p velocity-estimators --test bank fixed_point -- --nocapture` prints the
//!   figures); its update path is integer
//!   only and panic-free (no FPU needed on Cortex-M0/M3).
//! * Bad input: NaN/infinite samples and non-increasing timestamps return [`SampleError`] and
//!   leave the state unchanged; invalid parameters return [`ConfigError`] at construction.
//!
//! ```
//! use estimators::{BankConfig, Channel, EstimatorOutput, Fx, PaperBank};
//!
//! // The paper's bank: AVE, ILO1-3, AD, ED, Kalman; acceleration by series connections.
//! let mut bank = PaperBank::<f32>::new(&BankConfig::default()).unwrap();
//! let mut fixed = PaperBank::<Fx>::new(&BankConfig::default()).unwrap();
//! // yaw = 30 deg/s * t, wrapping at +-180, sampled at 100 Hz
//! for k in 0..200u64 {
//!     let t_us = k * 10_000;
//!     let yaw = ((30.0 * k as f32 * 0.01 + 180.0).rem_euclid(360.0)) - 180.0;
//!     let out = bank.update(t_us, yaw).unwrap();
//!     let out_fx = fixed.update(t_us, yaw).unwrap();
//!     if k == 199 {
//!         assert!((out[Channel::AveV] - 30.0).abs() < 0.1); // AVE velocity, deg/s
//!         // A fixed-point output holds raw `Fx` values; `channel` reads one as f32.
//!         assert!((out_fx.channel(Channel::AveV) - 30.0).abs() < 0.1);
//!         assert!(out[Channel::AveA].abs() < 1.0); // AVE-AVE acceleration, deg/s^2
//!         assert!((out.unwrapped_deg() - 59.7).abs() < 1e-3); // unwrapped yaw, deg
//!     }
//! }
//! // Bad input leaves the state unchanged and is reported.
//! assert!(bank.update(2_000_000, f32::NAN).is_err());
//! assert!(bank.update(1_000_000, 0.0).is_err());
//! ```
#![no_std]
#![forbid(unsafe_code)]

mod ad;
pub mod adapter;
pub mod adaptive;
mod ave;
mod bank;
mod ed;
mod error;
mod estimator;
pub mod family;
mod fxk;
pub mod gilo;
mod ilo;
pub mod kalman;
pub mod law;
pub mod linear;
mod pair;
pub mod presets;
pub mod ram;
mod rates;
mod real;
mod series;
mod traits;
mod unwrap;
pub mod words;

pub use ad::{Ad, AdConfig, AdFamily, AdParams, AdState};
pub use adapter::{SampleAdapter, SampleClock, Tick};
pub use adaptive::{
    AdaptiveBank, AdaptiveConfig, AdaptiveKalman, AdaptiveKalmanConfig, AdaptiveProductBank,
    AdaptiveProductConfig, AveDeltahat, Blend, GainSchedule, JerkEstimator, Levels, NoiseEstimator,
    ObserverSwitch, ScheduleLevel, SelfTuneConfig, SelfTuningProductBank, Settled, PAST_TOP_FACTOR,
};
pub use ave::{
    Ave, AveConfig, AveFamily, AveParams, AveState, DeltaLaw, DeltaMode, COARSE_STABILITY_MARGIN,
};
pub use bank::{
    columns_len, join_columns, replay, Accepted, AdA, AdAdMap, AdMap, AdV, AveRow, Bank,
    BankConfig, BankGains, BankInput, BankOutput, Channel, ChannelLists, Channels, Columns, EdRow,
    Fed, Feed, IloA, IloMap, IloV, KfA, KfV, PaperBank, PaperOutput, PaperParams, PaperRows,
    PaperState, ProductBank, ProductChannel, ProductOutput, ProductParams, ProductRows,
    ProductState, Row, RowValues, Rows, Warm, Wrap, GAP_PERIODS, KF_DEFAULT, MAX_GAP_PERIODS,
    VELOCITY_NAMES,
};
pub use ed::{
    Ed, EdConfig, EdFamily, EdParams, EdScheme, EdState, ED_MAX_H_ALPHA, ED_PAST_TOP_MIN,
};
pub use error::{ConfigError, SampleError};
pub use estimator::{advance_by_steps, Estimator, Hold};
pub use family::{
    for_each_family, Family, FamilyInfo, FamilyVisitor, Follows, Gains, LawVisitor, PastTop,
    Scheduling, FAMILIES, FAMILY_COUNT,
};
pub use ilo::{Ilo, IloConfig, IloFamily, IloParams, IloState};
pub use kalman::{
    Kalman, KalmanConfig, KalmanNoise, KalmanOutput, KalmanParams, KalmanState, KfFamily,
};
pub use law::{Law, Stateful};
pub use linear::{ClosedForm, LinearLaw};
pub use pair::{VelAcc, VelAccState};
pub use rates::RateGains;
pub use real::{f32_scaled, Fx, NativeSqrt, Real, SqrtFn};
pub use series::{Series, SeriesState};
pub use traits::{EstimatorBank, EstimatorOutput, Values};
pub use unwrap::Unwrapper;

/// The examples of the crate README, compiled and run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
