//! The estimator banks shared by the firmware and the host CLI, each generated from one table
//! by [`crate::estimator_bank!`]: [`PaperBank`] (the paper's 14 estimators) and
//! [`ProductBank`] (one velocity and one acceleration estimator).

mod config;
mod input;
mod paper;
mod product;
mod table;

pub use config::*;
pub use input::*;
pub use paper::*;
pub use product::*;
