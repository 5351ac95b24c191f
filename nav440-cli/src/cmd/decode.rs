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
    if let Some(t) = &a.packet_type {
        check_type(t)?;
    }
    crate::output::check_stdout()?;
    decode(&a.file, a.packet_type.as_deref())
}

/// A `--type` that is not a packet type of the protocol is a usage error (exit 2) naming the
/// known ones, before the capture is read.
fn check_type(t: &str) -> Result<()> {
    let known = nav440_proto::PacketType::KNOWN;
    if known.iter().any(|k| k.name().eq_ignore_ascii_case(t)) {
        Ok(())
    } else {
        Err(crate::error::Error::Usage(format!(
            "--type {t:?} is not a NAV440 packet type (one of {})",
            known
                .iter()
                .map(|k| k.name())
                .collect::<Vec<_>>()
                .join(", ")
        )))
    }
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
        frames += header.scan_end(&mut parser, only);
        if frames == 0 {
            return with_name(&name, dec.finish(|_| {}).map(drop));
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
        if out.closed {
            return Ok(());
        }
        line.clear();
        let dropped = with_name(
            &name,
            dec.finish(|row| {
                header.row_line(&row, &mut line);
            }),
        )?;
        out.send(&line)?;
        warn_end_of_input(dropped);
        return Ok(());
    }
    let mut pipe = PipeRows {
        header,
        held: Vec::new(),
        started: false,
        outside: 0,
        outside_types: Default::default(),
    };
    let mut read = 0u64;
    r.for_each_chunk(|b| {
        line.clear();
        read += b.len() as u64;
        dec.push(b, |row| pipe.row(row, &mut line));
        if !pipe.started && read >= DECODE_LOOKAHEAD && !pipe.held.is_empty() {
            pipe.start(&mut line);
        }
        out.send(&line)?;
        Ok(!out.closed)
    })?;
    if out.closed {
        return Ok(());
    }
    line.clear();
    let dropped = with_name(&name, dec.finish(|row| pipe.row(row, &mut line)))?;
    if !pipe.started {
        pipe.start(&mut line);
    }
    out.send(&line)?;
    let PipeRows {
        outside,
        outside_types,
        ..
    } = pipe;
    if outside > 0 {
        eprintln!(
            "nav440: warning: {outside} frames after the first {} KiB of {name} have columns outside the CSV header (types {}); those cells are left out (decode the capture from a file to get every column)",
            DECODE_LOOKAHEAD / 1024,
            outside_types.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    warn_end_of_input(dropped);
    Ok(())
}

/// The end-of-input warning on stderr, if the input ends inside a frame.
fn warn_end_of_input(dropped: u64) {
    if let Some(w) = replay::end_of_input_warning(dropped) {
        eprintln!("nav440: warning: {w}");
    }
}

/// The rows of a piped input: held (and the header grown) until the look-ahead is read, then
/// written as they come.
struct PipeRows {
    header: Header,
    held: Vec<DecodedRow>,
    started: bool,
    /// Rows written after the header was fixed with a column outside it.
    outside: u64,
    outside_types: std::collections::BTreeSet<String>,
}

impl PipeRows {
    /// Writes `row` to `line` (or holds it before the header is fixed).
    fn row(&mut self, row: DecodedRow, line: &mut String) {
        if self.started {
            if !self.header.row_line(&row, line) {
                self.outside += 1;
                self.outside_types.insert(row.name.clone());
            }
        } else {
            self.header.add_row(&row);
            self.held.push(row);
        }
    }

    /// Fixes the header: writes it and the held rows to `line`.
    fn start(&mut self, line: &mut String) {
        self.started = true;
        line.push_str(&self.header.line());
        for row in self.held.drain(..) {
            self.header.row_line(&row, line);
        }
    }
}
