//! `nav440 paper`: the paper's Tables 1 and 3 on a capture, next to the paper's values.

use std::path::PathBuf;

use super::{bank_options, one_axis, BankArgs, PresetArg};
use crate::error::Result;
use crate::{paper, replay};

/// Arguments of `nav440 paper`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input.
    file: PathBuf,
    #[command(flatten)]
    bank: BankArgs,
    /// Print JSON instead of tables.
    #[arg(long, conflicts_with = "markdown")]
    json: bool,
    /// Print Markdown tables (for a README) instead of text tables.
    #[arg(long)]
    markdown: bool,
    /// MSE window end, s (at most 2592000, 30 days).
    #[arg(long, default_value_t = 30.0)]
    window: f64,
}

/// Runs the paper's experiment on the capture and prints the tables (text, Markdown or JSON).
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    let opts = bank_options(&a.bank, PresetArg::Paper)?;
    one_axis(&opts, "paper")?;
    paper::check_window(a.window)?;
    let samples = replay::read_samples(&a.file)?;
    let res = paper::run(&samples, &opts, a.window, &replay::capture_name(&a.file))?;
    for w in res.warnings() {
        eprintln!("nav440: warning: {w}");
    }
    let text = if a.json {
        format!("{}\n", res.to_json())
    } else if a.markdown {
        res.to_markdown()
    } else {
        res.to_text()
    };
    super::stdout_or_file(None, |w| w.write_all(text.as_bytes()))
}
