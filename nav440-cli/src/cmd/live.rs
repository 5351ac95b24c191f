//! `nav440 live`: configure a unit, then print the estimate CSV while receiving
//! ([`crate::serial`]).

use crate::error::Result;
use crate::replay::{self, EstimateOptions};
use crate::serial::{open_and_boot, report_json, stream_after_boot, PortArgs};

/// Arguments of `nav440 live`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(flatten)]
    pub(crate) port: PortArgs,
    /// Stop after this many seconds (default: when the port closes).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
}

/// `nav440 live`: the boot sequence, then the estimate CSV on stdout while receiving.
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    a.port.check()?;
    if let Some(s) = a.duration {
        crate::limits::seconds("--duration", s, false)?;
    }
    let (d, report, t) = open_and_boot(&a.port)?;
    eprintln!("nav440 live: {}", report_json(&a.port.port, &report, &t));
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    // The same streaming pipeline as `nav440 estimate` (warm-up, bank with the shipped
    // preset's gains for the unit's packet rate, CSV, warnings).
    let opts = EstimateOptions {
        follow_rate: true,
        ..EstimateOptions::default()
    };
    let source = replay::FnChunks(|f: &mut dyn FnMut(&[u8]) -> Result<bool>| {
        stream_after_boot(d, a.duration, f).map(|_| ())
    });
    let report = replay::estimate_stream(source, &opts, &mut out)?;
    for w in report.warnings() {
        eprintln!("nav440: warning: {w}");
    }
    Ok(())
}
