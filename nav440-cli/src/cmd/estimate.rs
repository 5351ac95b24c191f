//! `nav440 estimate`: the estimator bank on a capture, one CSV row per packet, streamed.

use std::path::PathBuf;

use super::{bank_options, noise, with_name, BankArg, BankArgs, NoiseArgs, PresetArg};
use crate::error::Result;
use crate::output::{self, OutputFile};
use crate::replay;

/// Arguments of `nav440 estimate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input.
    file: PathBuf,
    /// Estimator bank: paper (the paper's 14 estimators) or product (ILO1 velocity and
    /// Kalman acceleration, what the product firmware prints).
    #[arg(
        long = "bank",
        value_enum,
        default_value = "paper",
        value_name = "BANK"
    )]
    bank_kind: BankArg,
    #[command(flatten)]
    bank: BankArgs,
    #[command(flatten)]
    noise: NoiseArgs,
    /// Run the fixed-point (Q31.32) bank, as the no-FPU firmware does, instead of f32.
    #[arg(long)]
    fixed: bool,
    /// Write the CSV here instead of stdout (`-`: stdout).
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
}

/// Streams the capture through the bank; the CSV goes to stdout or `-o`, warnings to stderr.
/// `-o FILE` is written through a temporary file renamed at the end ([`OutputFile`]): a
/// failure at any point leaves an existing FILE as it was; `-o` naming the capture (or the
/// gains file) is refused before anything is read.
pub fn run(a: Args) -> Result<()> {
    let mut opts = bank_options(&a.bank, PresetArg::Nav440)?;
    opts.noise = noise(a.noise.noise_var, a.noise.seed)?;
    opts.fixed = a.fixed;
    opts.bank = a.bank_kind.into();
    replay::check_bank_options(&opts)?;
    let out = a
        .output
        .unwrap_or_else(|| PathBuf::from(output::STDOUT_NAME));
    let mut inputs = vec![a.file.as_path()];
    inputs.extend(a.bank.gains.as_deref());
    output::check_not_input("-o", &out, &inputs)?;
    let mut w = OutputFile::create(&out)?;
    let mut r = replay::open_capture(&a.file)?;
    let name = r.name().to_string();
    let report = with_name(&name, replay::estimate_stream(&mut r, &opts, &mut w))?;
    w.commit()?;
    for w in report.warnings() {
        eprintln!("nav440: warning: {w}");
    }
    Ok(())
}
