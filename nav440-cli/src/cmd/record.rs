//! `nav440 record`: configure a unit, then record its stream to a file ([`crate::serial`]).

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::output;
use crate::serial::{open_and_boot, report_json, stream_until, PortArgs};

/// Arguments of `nav440 record`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(flatten)]
    pub(crate) port: PortArgs,
    /// Capture file to write (the bytes after the read-back reply); `-`: standard output. It
    /// is opened (and an existing file replaced) only once the unit answered and is
    /// configured; every chunk is written to it as it arrives.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Stop after this many seconds (default: when the port closes, or at SIGINT/SIGTERM).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
}

/// `nav440 record`: the boot sequence, then the stream after the read-back into a file.
///
/// The file is checked before the port is opened (without changing it), created only after
/// the boot sequence succeeded, and written chunk by chunk as the port delivers (no buffer in
/// the process). SIGINT (Ctrl-C) and SIGTERM end the recording like the end of the stream:
/// the file is synced and closed, the byte count printed, exit 0.
pub fn run(a: &Args) -> Result<()> {
    a.port.check()?;
    if let Some(s) = a.duration {
        crate::limits::seconds("--duration", s, false)?;
    }
    output::check_writable(&a.output)?;
    let name = output::output_name(&a.output);
    let (d, report, t) = open_and_boot(&a.port)?;
    eprintln!(
        "nav440 record: {}",
        report_json(&a.port.link.port, &report, &t)
    );
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .map_err(|e| Error::Other(format!("cannot handle SIGINT/SIGTERM: {e}")))?;
    }
    let werr = |e: std::io::Error| Error::Output(format!("cannot write {name}: {e}"));
    let mut out: Box<dyn Write> = if output::is_stdout(&a.output) {
        Box::new(std::io::stdout())
    } else {
        Box::new(std::fs::File::create(&a.output).map_err(werr)?)
    };
    let total = stream_until(d, a.duration, Some(&stop), |b| {
        out.write_all(b)
            .and_then(|()| out.flush())
            .map(|()| true)
            .map_err(werr)
    })?;
    out.flush().map_err(werr)?;
    drop(out);
    if !output::is_stdout(&a.output) {
        std::fs::File::open(&a.output)
            .and_then(|f| f.sync_all())
            .map_err(werr)?;
    }
    let why = if stop.load(Ordering::Relaxed) {
        "interrupted: "
    } else {
        ""
    };
    eprintln!("nav440 record: {why}{total} bytes written to {name}");
    Ok(())
}
