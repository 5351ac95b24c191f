//! The CLI's error type and its exit codes.

use std::fmt;

/// An error of the `nav440` tool; each kind maps to a documented exit code.
#[derive(Debug)]
pub enum Error {
    /// Bad argument value (exit 2, like clap's own usage errors).
    Usage(String),
    /// Input file missing, unreadable or empty (exit 3).
    Input(String),
    /// Input contains no valid NAV440 frame, or no frame of the needed kind (exit 4).
    NotNav440(String),
    /// Output could not be written (exit 5).
    Output(String),
    /// Anything else: estimator configuration/sample errors, encoder errors (exit 1).
    Other(String),
}

impl Error {
    /// Process exit code: 1 other, 2 usage, 3 input missing/unreadable/empty,
    /// 4 not NAV440 data, 5 output failure.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Other(_) => 1,
            Error::Usage(_) => 2,
            Error::Input(_) => 3,
            Error::NotNav440(_) => 4,
            Error::Output(_) => 5,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Usage(m)
            | Error::Input(m)
            | Error::NotNav440(m)
            | Error::Output(m)
            | Error::Other(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {}

/// Result alias of the host crate.
pub type Result<T> = std::result::Result<T, Error>;
