//! The estimator banks shared by the firmware and the host CLI, each a tuple of rows behind
//! one input stage ([`Bank`]): [`PaperBank`] (the paper's 14 estimators) and [`ProductBank`]
//! (one velocity and one acceleration estimator).

mod config;
mod input;
mod paper;
mod product;
mod rows;

pub use config::*;
pub use input::*;
pub use paper::*;
pub use product::*;
pub use rows::*;
