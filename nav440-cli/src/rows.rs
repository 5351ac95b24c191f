//! The rows a `uart-rows` firmware sends out of its output UART (framed binary messages,
//! [`nav440_pipeline::wire`], docs/UART-ROWS.md) turned back into the CSV of `nav440 estimate`
//! (`nav440 rows`).
//!
//! [`RowsReader`] takes the stream in any chunks: the bytes before the first frame delimiter
//! are skipped (a stream joined mid-frame), the first header frame gives the CSV header line
//! (a later copy must be the same), each row frame one CSV line. Frames that do not decode and
//! rows that do not fit the header are counted and reported on stderr ([`MAX_REPORTED`] lines,
//! then only the counts at the end); nothing panics on any input.

use std::io::Write;

use nav440_pipeline::wire::{Deframer, FrameError, Layout, LayoutError, Message, VERSION};

use crate::error::{Error, Result};

/// The longest frame the reader takes, bytes (the longest row frame, the paper bank's three
/// axes, is 239).
pub const MAX_FRAME: usize = 1024;

/// Bad frames and rows reported one by one on stderr; the rest are counted.
pub const MAX_REPORTED: u64 = 10;

/// What a [`RowsReader`] has read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RowsCounters {
    /// CSV rows written.
    pub rows: u64,
    /// Header frames read (the first and its copies).
    pub headers: u64,
    /// Row frames before the first usable header, skipped.
    pub rows_before_header: u64,
    /// Frames that did not decode ([`FrameError`]), headers this reader cannot use and rows
    /// that do not fit the header.
    pub bad: u64,
}

/// The stream of a `uart-rows` firmware's output UART into CSV text.
pub struct RowsReader {
    deframer: Box<Deframer<MAX_FRAME>>,
    layout: Option<Layout>,
    counters: RowsCounters,
    /// Why the headers seen could not be used (the last reason), for the end of a stream
    /// without a usable one.
    unusable: Option<String>,
    line: String,
    /// The output is a pipe its reader closed (`nav440 rows F | head`): nothing more is read.
    closed: bool,
}

impl Default for RowsReader {
    fn default() -> Self {
        Self::new()
    }
}

impl RowsReader {
    /// A reader at the start of a stream.
    pub fn new() -> Self {
        RowsReader {
            deframer: Box::new(Deframer::new()),
            layout: None,
            counters: RowsCounters::default(),
            unusable: None,
            line: String::new(),
            closed: false,
        }
    }

    /// What it has read so far.
    pub fn counters(&self) -> RowsCounters {
        self.counters
    }

    /// The output was a pipe its reader closed: [`Self::feed`] wrote nothing more (not an
    /// error; the command stops quietly).
    pub fn output_closed(&self) -> bool {
        self.closed
    }

    /// Feeds bytes: the CSV lines they complete go to `out`, the reports of bad frames to
    /// `warn` (one line each, without prefix). An error of `out` stops and is returned, and so
    /// does a header that differs from the first (the columns would change mid-stream).
    pub fn feed(
        &mut self,
        bytes: &[u8],
        out: &mut dyn Write,
        warn: &mut dyn FnMut(&str),
    ) -> Result<()> {
        if self.closed {
            return Ok(());
        }
        let mut result = Ok(());
        let (layout, counters, unusable, line, closed) = (
            &mut self.layout,
            &mut self.counters,
            &mut self.unusable,
            &mut self.line,
            &mut self.closed,
        );
        // A closed pipe stops the reading quietly; any other write failure is an error.
        let mut write = |closed: &mut bool, text: &str| match out.write_all(text.as_bytes()) {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                *closed = true;
                Ok(())
            }
            r => r.map_err(|e| Error::Output(format!("cannot write output: {e}"))),
        };
        let mut report = |counters: &mut RowsCounters, what: String| {
            counters.bad += 1;
            if counters.bad <= MAX_REPORTED {
                warn(&what);
            }
        };
        self.deframer.feed(bytes, |m| {
            if result.is_err() || *closed {
                return;
            }
            match m {
                Err(e) => {
                    if let FrameError::Version { .. } = e {
                        *unusable = Some(e.to_string());
                    }
                    report(counters, format!("undecodable frame: {e}"));
                }
                Ok(Message::Header(h)) => {
                    counters.headers += 1;
                    match (Layout::from_header(&h), *layout) {
                        (Ok(l), None) => {
                            line.clear();
                            // Writing into a String cannot fail.
                            let _ = l.write_header(line);
                            line.push('\n');
                            result = write(closed, line);
                            *layout = Some(l);
                        }
                        (Ok(l), Some(first)) if l == first => {}
                        (Ok(_), Some(_)) => {
                            result = Err(Error::Other(format!(
                                "the stream's header changed: axes mask {} and columns `{}` after the first header's; one stream is one CSV",
                                h.axes, h.columns
                            )));
                        }
                        (Err(e), _) => {
                            let why = match e {
                                LayoutError::UnknownBank => format!(
                                    "header names a bank this nav440 does not know (columns `{}`)",
                                    h.columns
                                ),
                                e => e.to_string(),
                            };
                            *unusable = Some(why.clone());
                            report(counters, why);
                        }
                    }
                }
                Ok(Message::Row(r)) => {
                    let Some(l) = layout else {
                        counters.rows_before_header += 1;
                        return;
                    };
                    line.clear();
                    match l.write_row(line, &r) {
                        Ok(()) => {
                            line.push('\n');
                            counters.rows += 1;
                            result = write(closed, line);
                        }
                        Err(e) => {
                            report(counters, format!("row at t = {} us: {e}", r.t_us));
                        }
                    }
                }
            }
        });
        result
    }

    /// The end of the stream: the warnings about what was skipped (one line each, without
    /// prefix), or the error of a stream without a usable header (exit 4).
    pub fn finish(&self) -> Result<Vec<String>> {
        let d = self.deframer.counters();
        let c = self.counters;
        if self.layout.is_none() {
            let why = match &self.unusable {
                Some(u) => format!("no usable header frame ({u})"),
                None if d.frames + d.bad_frames == 0 => format!(
                    "no frame found in {} bytes (not the output UART of a `uart-rows` firmware?)",
                    d.bytes
                ),
                None => format!(
                    "no header frame among {} frames ({} undecodable); rows need the header that names their columns",
                    d.frames + d.bad_frames,
                    d.bad_frames
                ),
            };
            return Err(Error::NotNav440(why));
        }
        let mut w = Vec::new();
        if c.bad > 0 {
            w.push(format!(
                "{} bad frames or rows skipped (format version {VERSION}; undecodable frames are corrupted or cut ones)",
                c.bad
            ));
        }
        if d.skipped_bytes > 0 {
            w.push(format!(
                "{} bytes before the first frame delimiter skipped (the stream was joined mid-frame)",
                d.skipped_bytes
            ));
        }
        if c.rows_before_header > 0 {
            w.push(format!(
                "{} rows before the first header frame skipped",
                c.rows_before_header
            ));
        }
        let pending = self.deframer.pending_bytes();
        if pending > 0 {
            w.push(format!(
                "the stream ends inside a frame: its {pending} bytes are dropped"
            ));
        }
        Ok(w)
    }
}
