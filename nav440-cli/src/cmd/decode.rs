//! `nav440 decode`: one CSV row per frame with its fields in SI units, streamed.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::with_name;
use crate::decode::{DecodedRow, FrameDecoder, Header};
use crate::error::Result;
use crate::replay;

/// Arguments of `nav440 decode`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input.
    file: PathBuf,
    /// Only frames of this type (e.g. A2, N1, S1, NAK).
    #[arg(long = "type", value_name = "TYPE")]
    packet_type: Option<String>,
}

/// Decodes the capture named in `a`.
pub fn run(a: &Args) -> Result<()> {
    decode(&a.file, a.packet_type.as_deref())
}

/// Bytes of standard input (or of a pipe) that `decode` reads before it fixes its header.
const DECODE_LOOKAHEAD: u64 = 64 * 1024;

/// Writes to stdout; a closed pipe stops the command quietly.
struct Stdout<'a> {
    w: std::io::BufWriter<std::io::StdoutLock<'a>>,
    closed: bool,
}

impl Stdout<'_> {
    fn new() -> Self {
        Stdout {
            w: std::io::BufWriter::new(std::io::stdout().lock()),
            closed: false,
        }
    }

    fn io(&mut self, r: std::io::Result<()>) -> Result<()> {
        replay::output_result(r, &mut self.closed)
    }

    /// Writes `text` and flushes.
    fn send(&mut self, text: &str) -> Result<()> {
        if self.closed {
            return Ok(());
        }
        let r = self
            .w
            .write_all(text.as_bytes())
            .and_then(|_| self.w.flush());
        self.io(r)
    }
}

/// `nav440 decode`, streamed. A regular file is read twice: a first pass collects the header
/// (the union of the columns, without formatting any value), the second writes the rows as it
/// reads. Standard input (or any pipe) is read once: the header is the union of the columns
/// of the frames in its first `DECODE_LOOKAHEAD` bytes (the whole input if shorter); a later
/// frame with a column outside it loses that cell and is counted in a warning.
fn decode(file: &Path, only: Option<&str>) -> Result<()> {
    let mut r = replay::open_capture(file)?;
    let name = r.name().to_string();
    let regular = !replay::is_stdin(file) && std::fs::metadata(file).is_ok_and(|m| m.is_file());
    let mut out = Stdout::new();
    let mut dec = FrameDecoder::new(only);
    let mut header = Header::new();
    let mut line = String::new();
    if regular {
        let mut parser = nav440_proto::Parser::new();
        let mut frames = 0u64;
        r.for_each_chunk(|b| {
            frames += header.scan(&mut parser, b, only);
            Ok(true)
        })?;
        if frames == 0 {
            return with_name(&name, dec.finish());
        }
        out.send(&header.line())?;
        let mut r = replay::open_capture(file)?;
        r.for_each_chunk(|b| {
            line.clear();
            dec.push(b, |row| {
                header.row_line(&row, &mut line);
            });
            out.send(&line)?;
            Ok(!out.closed)
        })?;
        return Ok(());
    }
    let mut held: Vec<DecodedRow> = Vec::new();
    let mut started = false;
    let mut outside = 0u64;
    let mut outside_types: std::collections::BTreeSet<String> = Default::default();
    let mut read = 0u64;
    r.for_each_chunk(|b| {
        line.clear();
        read += b.len() as u64;
        dec.push(b, |row| {
            if started {
                if !header.row_line(&row, &mut line) {
                    outside += 1;
                    outside_types.insert(row.name.clone());
                }
            } else {
                header.add_row(&row);
                held.push(row);
            }
        });
        if !started && read >= DECODE_LOOKAHEAD && !held.is_empty() {
            started = true;
            line.push_str(&header.line());
            for row in held.drain(..) {
                header.row_line(&row, &mut line);
            }
        }
        out.send(&line)?;
        Ok(!out.closed)
    })?;
    if out.closed {
        return Ok(());
    }
    with_name(&name, dec.finish())?;
    if !started {
        line.clear();
        line.push_str(&header.line());
        for row in held.drain(..) {
            header.row_line(&row, &mut line);
        }
        out.send(&line)?;
    }
    if outside > 0 {
        eprintln!(
            "nav440: warning: {outside} frames after the first {} KiB of {name} have columns outside the CSV header (types {}); those cells are left out (decode the capture from a file to get every column)",
            DECODE_LOOKAHEAD / 1024,
            outside_types.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    Ok(())
}
