//! `nav440 stats`: parser statistics of a capture as one JSON object.

use std::path::PathBuf;

use crate::error::{Error, Result};
use crate::replay;

/// Arguments of `nav440 stats`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file (raw NAV440 byte stream); `-` reads standard input.
    file: PathBuf,
}

/// Counts the frames, CRC errors, skipped and pending bytes of the input, streamed.
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    let mut r = replay::open_capture(&a.file)?;
    let mut counter = replay::StatsCounter::new();
    r.for_each_chunk(|b| {
        counter.push(b);
        Ok(true)
    })?;
    counter.finish();
    let stats = counter.stats();
    if stats.total_frames() == 0 {
        return Err(Error::NotNav440(format!(
            "{}: no NAV440 frame found (not a NAV440 capture?)",
            r.name()
        )));
    }
    super::stdout_or_file(None, |w| writeln!(w, "{}", stats.to_json()))
}
