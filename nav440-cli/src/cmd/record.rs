//! `nav440 record`: configure a unit, then record its stream to a file ([`crate::serial`]).

use std::io::Write;
use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::serial::{open_and_boot, report_json, stream_after_boot, PortArgs};

/// Arguments of `nav440 record`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(flatten)]
    pub(crate) port: PortArgs,
    /// Capture file to write (the bytes after the read-back reply).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Stop after this many seconds (default: when the port closes).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
}

/// `nav440 record`: the boot sequence, then the stream after the read-back into a file.
pub fn run(a: &Args) -> Result<()> {
    a.port.check()?;
    if let Some(s) = a.duration {
        super::seconds("--duration", s, false)?;
    }
    let out = std::fs::File::create(&a.output)
        .map_err(|e| Error::Output(format!("cannot create {}: {e}", a.output.display())))?;
    let mut w = std::io::BufWriter::new(out);
    let (d, report, t) = open_and_boot(&a.port)?;
    eprintln!("nav440 record: {}", report_json(&a.port.port, &report, &t));
    let werr =
        |e: std::io::Error| Error::Output(format!("cannot write {}: {e}", a.output.display()));
    let total = stream_after_boot(d, a.duration, |b| {
        w.write_all(b).map(|()| true).map_err(werr)
    })?;
    w.flush().map_err(werr)?;
    eprintln!(
        "nav440 record: {total} bytes written to {}",
        a.output.display()
    );
    Ok(())
}
