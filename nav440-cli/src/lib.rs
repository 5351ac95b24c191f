//! Host side of the project: replay of NAV440 captures through the same parser and estimator
//! bank the firmware runs, capture synthesis, the paper's experiment, gain tuning and plots.
//! The `nav440` binary (src/main.rs) parses [`cmd::Cli`]; each command is a thin layer over these modules, so the
//! integration tests (and the firmware's equivalence test) can call the pipeline directly.

pub mod cmd;
pub mod corrupt;
pub mod decode;
pub mod error;
pub mod gains;
pub mod limits;
pub mod live_plot;
pub mod motion;
pub mod optim;
pub mod output;
pub mod paper;
pub mod plot;
pub mod plots;
pub mod progress;
pub mod raw_sample;
pub mod replay;
pub mod rows;
pub mod rust_literal;
pub mod score;
pub mod search;
pub mod serial;
pub mod sim;
pub mod synth;
pub mod tune;

/// The Rust examples of the top-level README, compiled and run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
