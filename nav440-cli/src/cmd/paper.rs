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
    // The MSEs are causal: only the samples up to the window's end are kept.
    let cap = replay::read_samples_until(
        &a.file,
        Some(paper::window_end_us(a.window)),
        "a shorter --window keeps fewer samples; `nav440 estimate` streams a capture of any length",
    )?;
    let name = replay::capture_name(&a.file);
    let total = usize::try_from(cap.total).unwrap_or(usize::MAX);
    let duration_s = cap.last_t_us as f64 * 1e-6;
    let res = paper::run_counted(&cap.samples, (total, duration_s), &opts, a.window, &name);
    // The input's warnings as `estimate` prints them, also when the samples are too few.
    let summary = match &res {
        Ok(r) => r.summary,
        Err(_) => replay::summary_of(&cap.samples, &opts.paper_law()).unwrap_or_default(),
    };
    for w in cap.warnings(&summary) {
        eprintln!("nav440: warning: {w}");
    }
    let res = res?;
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
