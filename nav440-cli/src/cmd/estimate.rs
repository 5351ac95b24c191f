//! `nav440 estimate`: the estimator bank on a capture, one CSV row per packet, streamed.

use std::path::PathBuf;

use super::{print_warnings, with_name, EstimateArgs};
use crate::error::Result;
use crate::output::{self, OutputFile};
use crate::replay;

/// Arguments of `nav440 estimate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input.
    file: PathBuf,
    #[command(flatten)]
    estimate: EstimateArgs,
    /// Write the CSV here instead of stdout (`-`: stdout).
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
}

/// Streams the capture through the bank; the CSV goes to stdout or `-o`, warnings to stderr.
/// `-o FILE` is written through a temporary file renamed at the end ([`OutputFile`]): a
/// failure at any point leaves an existing FILE as it was; `-o` naming the capture (or the
/// gains file) is refused before anything is read.
pub fn run(a: Args) -> Result<()> {
    let opts = a.estimate.options()?;
    let out = a
        .output
        .unwrap_or_else(|| PathBuf::from(output::STDOUT_NAME));
    let mut inputs = vec![a.file.as_path()];
    inputs.extend(a.estimate.bank.gains.as_deref());
    output::check_not_input("-o", &out, &inputs)?;
    let mut w = OutputFile::create(&out)?;
    let mut r = replay::open_capture(&a.file)?;
    let name = r.name().to_string();
    let report = with_name(&name, replay::estimate_stream(&mut r, &opts, &mut w))?;
    w.commit()?;
    print_warnings(&report);
    Ok(())
}
