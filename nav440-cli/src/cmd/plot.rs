//! `nav440 plot`: yaw, measured rate, velocity and acceleration estimates as an SVG.

use std::path::PathBuf;

use super::{bank_options, noise, one_axis, BankArgs, NoiseArgs, PresetArg};
use crate::error::Result;
use crate::{plots, replay};

/// Arguments of `nav440 plot`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input.
    file: PathBuf,
    /// Output SVG file; `-` writes the SVG to standard output.
    #[arg(short, long, value_name = "OUT.svg")]
    output: PathBuf,
    #[command(flatten)]
    bank: BankArgs,
    #[command(flatten)]
    noise: NoiseArgs,
    /// Plot from this time, s (0 to 2592000, 30 days).
    #[arg(long)]
    from: Option<f64>,
    /// Plot up to this time, s (0 to 2592000, 30 days).
    #[arg(long)]
    to: Option<f64>,
}

/// Runs the bank on the capture and draws the five stacked panels.
pub fn run(a: &Args) -> Result<()> {
    for (flag, t) in [("--from", a.from), ("--to", a.to)] {
        if let Some(t) = t {
            crate::limits::seconds(flag, t, true)?;
        }
    }
    let mut opts = bank_options(&a.bank, PresetArg::Nav440)?;
    one_axis(&opts, "plot")?;
    opts.noise = noise(a.noise.noise_var, a.noise.seed)?;
    let mut inputs = vec![a.file.as_path()];
    inputs.extend(a.bank.gains.as_deref());
    crate::output::check_not_input("-o", &a.output, &inputs)?;
    if crate::output::is_stdout(&a.output) {
        crate::output::check_stdout()?;
    }
    // The estimates are causal: only the samples up to --to are kept.
    let cap = replay::read_samples_until(
        &a.file,
        a.to.map(|t| (t * 1e6).round() as u64),
        "--to keeps only the samples up to it; `nav440 estimate` streams a capture of any length",
    )?;
    let res = plots::plot_capture(
        &cap.samples,
        &opts,
        &replay::capture_name(&a.file),
        &a.output,
        a.from,
        a.to,
    );
    // The input's warnings as `estimate` prints them, also when nothing could be drawn.
    let summary = match &res {
        Ok(s) => *s,
        Err(_) => replay::summary_of(&cap.samples, &opts).unwrap_or_default(),
    };
    for w in cap.warnings(&summary) {
        eprintln!("nav440: warning: {w}");
    }
    res.map(drop)
}
