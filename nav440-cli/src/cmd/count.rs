//! `nav440 count`: the number of attitude samples in a capture.

use std::path::PathBuf;

use crate::error::Result;
use crate::replay;

/// Arguments of `nav440 count`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input.
    file: PathBuf,
}

/// Prints how many samples of the capture carry an attitude (the rows `estimate` writes).
pub fn run(a: &Args) -> Result<()> {
    let n = replay::read_samples(&a.file)?.len();
    super::stdout_or_file(None, |w| writeln!(w, "{n}"))
}
