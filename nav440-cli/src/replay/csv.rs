//! The streamed estimation: samples in, CSV rows out, byte-identical to the firmware's ([`estimate_stream`]).

use super::*;

/// `nav440 estimate` on a stream of samples (`nav440_pipeline::Estimation`, the firmware's
/// back end, with the host's banks): push samples one by one, get rows as they come. The
/// nominal period is set from the first [`WARMUP_SAMPLES`] samples, so those are held back
/// until it is known; every later sample gives its row at once. Memory is constant.
pub struct Estimation {
    inner: nav440_pipeline::Estimation<HostBank, String, BuildFn>,
}

impl std::fmt::Debug for Estimation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.inner.fmt(f)
    }
}

/// Runs `f` with a row callback for the pipeline that forwards to `on_row` until its first
/// error, which is returned.
pub(crate) fn forward_rows<T>(
    on_row: &mut dyn FnMut(Row) -> Result<()>,
    f: impl FnOnce(&mut dyn FnMut(&Row)) -> std::result::Result<T, String>,
) -> Result<T> {
    let mut first_err = None;
    let res = f(&mut |r: &Row| {
        if first_err.is_none() {
            if let Err(e) = on_row(*r) {
                first_err = Some(e);
            }
        }
    });
    if let Some(e) = first_err {
        return Err(e);
    }
    res.map_err(Error::Usage)
}

impl Estimation {
    /// An estimation with `opts` (the noise variance is checked here; the bank configuration
    /// once the period is known).
    pub fn new(opts: &EstimateOptions) -> Result<Self> {
        check_paper_bank(opts)?;
        NoiseGen::new(opts.noise, Axis::Yaw)?;
        Ok(Estimation {
            inner: nav440_pipeline::Estimation::new(
                opts.axes,
                opts.bank_config(),
                build_fn(opts, paper_bank),
            ),
        })
    }

    /// Takes the next sample; `on_row` gets every row that is ready (none during the warm-up,
    /// then the held-back ones and one per accepted sample). An error of `on_row` stops and
    /// is returned.
    pub fn push(&mut self, s: Sample, on_row: &mut dyn FnMut(Row) -> Result<()>) -> Result<()> {
        forward_rows(on_row, |emit| self.inner.push(s, emit))
    }

    /// Ends the stream (a stream shorter than the warm-up runs with the intervals it has) and
    /// returns the rejected samples and the gaps.
    pub fn finish(
        mut self,
        on_row: &mut dyn FnMut(Row) -> Result<()>,
    ) -> Result<EstimationSummary> {
        forward_rows(on_row, |emit| self.inner.finish(emit))?;
        let c = self.inner.counters();
        Ok(EstimationSummary::of(c))
    }
}

/// The CSV header of yaw alone (`nav440 estimate`'s default), shared with the firmware.
pub const CSV_HEADER: &str = nav440_pipeline::csv::HEADER;

/// The paper bank's CSV header line of `axes` (see `nav440_pipeline::csv`).
pub fn csv_header(axes: Axes) -> String {
    csv_header_of::<PaperOutput>(axes)
}

/// The CSV header line of `axes` for the bank `kind` (`nav440 estimate --bank`), with the
/// Euler reference's `<axis>_rate` columns.
pub fn bank_csv_header(kind: BankKind, axes: Axes) -> String {
    bank_csv_header_for(kind, axes, RateColumn::Euler)
}

/// [`bank_csv_header`] with the rate column `rate` (`--no-reference`: [`RateColumn::Body`],
/// `<axis>_body_rate`).
pub fn bank_csv_header_for(kind: BankKind, axes: Axes, rate: RateColumn) -> String {
    match kind {
        BankKind::Paper => csv_header_for::<PaperOutput>(axes, rate),
        BankKind::Product => csv_header_for::<ProductOutput>(axes, rate),
    }
}

/// The CSV header line of `axes` for a bank of output `O` (`nav440_pipeline::csv`).
pub(crate) fn csv_header_of<O: EstimatorOutput>(axes: Axes) -> String {
    csv_header_for::<O>(axes, RateColumn::Euler)
}

/// [`csv_header_of`] with the rate column `rate`.
pub(crate) fn csv_header_for<O: EstimatorOutput>(axes: Axes, rate: RateColumn) -> String {
    let mut s = String::new();
    // Writing into a String cannot fail.
    let _ = nav440_pipeline::csv::write_header_for::<O>(&mut s, axes, rate);
    s
}

/// Writes one CSV line of `r` for `axes`, formatted by `nav440_pipeline::csv` (`line` is
/// scratch space).
pub fn write_row<W: std::io::Write + ?Sized, O: EstimatorOutput>(
    w: &mut W,
    r: &Row<O>,
    axes: Axes,
    line: &mut String,
) -> std::io::Result<()> {
    line.clear();
    nav440_pipeline::csv::write_row(line, r, axes)
        .map_err(|_| std::io::Error::other("formatting error"))?;
    line.push('\n');
    w.write_all(line.as_bytes())
}

/// Writes the header and one line per row, formatted by `nav440_pipeline::csv` (identical
/// text to the firmware's for identical f32 values).
pub fn write_csv<W: std::io::Write + ?Sized>(
    rows: &[Row],
    axes: Axes,
    w: &mut W,
) -> std::io::Result<()> {
    writeln!(w, "{}", csv_header(axes))?;
    let mut line = String::new();
    for r in rows {
        write_row(w, r, axes, &mut line)?;
    }
    Ok(())
}

/// The whole `nav440 estimate` pipeline on a byte stream: parse, extract samples, run the
/// banks, format the CSV (header included). Returns the CSV text and the number of samples the
/// banks rejected. This is what the firmware's equivalence test compares its output against.
pub fn estimate_csv(bytes: &[u8], opts: &EstimateOptions) -> Result<(String, usize)> {
    let mut out = Vec::new();
    let report = estimate_stream(bytes, opts, &mut out)?;
    Ok((
        String::from_utf8_lossy(&out).into_owned(),
        usize::try_from(report.summary.rejected.total()).unwrap_or(usize::MAX),
    ))
}

/// Streams `nav440 estimate` from `input` (any number of chunks, e.g. a [`CaptureReader`]'s) to
/// `w` through `nav440_pipeline::Pipeline` (the firmware's pipeline): the header and each row
/// are written as soon as they are known (after the warm-up); `w` is flushed after every
/// chunk. Memory is constant.
///
/// Errors: [`Error::NotNav440`] (no frame / no attitude packet; nothing is written then),
/// [`Error::Usage`] (estimator configuration), [`Error::Output`] (writing failed; a closed pipe
/// is not an error: the stream stops quietly).
///
/// The bank is [`EstimateOptions::bank`]'s (`--bank`); the CSV's columns are its channels.
/// The rate column is [`EstimateOptions::rate_column`]'s (`--no-reference`: the body rates,
/// through a pipeline with `nav440_pipeline::BodyRates`, as the `no-reference` firmware runs).
pub fn estimate_stream<'a, W: std::io::Write + ?Sized>(
    input: impl IntoChunks<'a>,
    opts: &EstimateOptions,
    w: &mut W,
) -> Result<StreamReport> {
    use nav440_pipeline::{BodyRates, EulerReference};
    check_bank_options(opts)?;
    match (opts.bank, opts.rate_column) {
        (BankKind::Paper, RateColumn::Euler) => {
            stream_bank::<_, _, EulerReference>(input, opts, w, paper_bank)
        }
        (BankKind::Product, RateColumn::Euler) => {
            stream_bank::<_, _, EulerReference>(input, opts, w, product_bank)
        }
        (BankKind::Paper, RateColumn::Body) => {
            stream_bank::<_, _, BodyRates>(input, opts, w, paper_bank)
        }
        (BankKind::Product, RateColumn::Body) => {
            stream_bank::<_, _, BodyRates>(input, opts, w, product_bank)
        }
    }
}

/// [`estimate_stream`] with the banks `build` builds and the rate column `R`.
pub(crate) fn stream_bank<
    'a,
    B: EstimatorBank + SelfTuneStatus + 'static,
    W: std::io::Write + ?Sized,
    R: nav440_pipeline::Reference,
>(
    input: impl IntoChunks<'a>,
    opts: &EstimateOptions,
    w: &mut W,
    build: BuildBank<B>,
) -> Result<StreamReport> {
    NoiseGen::new(opts.noise, Axis::Yaw)?;
    let mut pipe: HostPipeline<B, R> =
        Pipeline::with_slots(opts.axes, opts.bank_config(), build_fn(opts, build));
    let header = csv_header_for::<B::Output>(opts.axes, pipe.rate_column());
    let mut sink = CsvSink::new(w, opts.axes, header);
    let mut period = None;
    input.chunks(&mut |chunk| {
        let res = pipe.feed(chunk, &mut |r| sink.row(r));
        sink.take_error()?;
        res.map_err(Error::Usage)?;
        sink.flush()?;
        report_period_change(&mut period, pipe.estimation().period_s());
        Ok(!sink.closed)
    })?;
    if sink.closed {
        return Ok(StreamReport::default());
    }
    let res = pipe.finish(&mut |r| sink.row(r));
    sink.take_error()?;
    report_period_change(&mut period, pipe.estimation().period_s());
    check_front(pipe.front())?;
    res.map_err(Error::Usage)?;
    sink.end()?;
    for axis in opts.axes.iter() {
        if let Some(line) = pipe
            .estimation()
            .bank(axis)
            .and_then(HostBank::self_tune_line)
        {
            eprintln!("nav440: {line}");
        }
    }
    let c = pipe.estimation().counters();
    Ok(StreamReport {
        summary: EstimationSummary::of(c),
        faults: *pipe.front().time_faults(),
        bit: pipe.front().counters().bit,
        schedule_misfit_us: opts
            .axes
            .iter()
            .find_map(|a| pipe.estimation().bank(a)?.schedule_misfit())
            .map(|(t, p)| (s_to_us(t), s_to_us(p))),
        end_dropped_bytes: pipe.front().counters().end_dropped_bytes,
    })
}

/// Prints on stderr, as it happens, a change of the nominal sample period the banks run with
/// (a new time epoch at another packet rate: `nav440_pipeline::Estimation` rebuilt the banks
/// for it); `last` is the period seen so far, `now` the pipeline's.
pub(crate) fn report_period_change(last: &mut Option<f32>, now: Option<f32>) {
    if let (Some(before), Some(after)) = (*last, now) {
        if before != after {
            eprintln!("nav440: warning: {}", period_change_message(before, after));
        }
    }
    if now.is_some() {
        *last = now;
    }
}

/// The one-line message for a nominal sample period change (periods in s).
pub fn period_change_message(before_s: f32, after_s: f32) -> String {
    let hz = |s: f32| (1e3 / f64::from(s).max(1e-9)).round() / 1e3;
    format!(
        "new time epoch at another packet rate: nominal sample period {} s ({} Hz) -> {} s ({} Hz), measured on the epoch's first {WARMUP_SAMPLES} samples; the banks are rebuilt for it",
        before_s,
        hz(before_s),
        after_s,
        hz(after_s)
    )
}

/// A period in s as whole us (rounded).
pub(crate) fn s_to_us(s: f32) -> u64 {
    (f64::from(s) * 1e6).round() as u64
}

/// Writes the estimate CSV as rows come: the header before the first row (or at the end). A
/// write error is kept (and later rows dropped) until [`CsvSink::take_error`].
pub(crate) struct CsvSink<'w, W: std::io::Write + ?Sized> {
    w: &'w mut W,
    axes: Axes,
    /// The header line (without terminator).
    header_line: String,
    header: bool,
    closed: bool,
    error: Option<Error>,
    line: String,
}

impl<'w, W: std::io::Write + ?Sized> CsvSink<'w, W> {
    fn new(w: &'w mut W, axes: Axes, header_line: String) -> Self {
        CsvSink {
            w,
            axes,
            header_line,
            header: false,
            closed: false,
            error: None,
            line: String::new(),
        }
    }

    fn io(&mut self, r: std::io::Result<()>) -> Result<()> {
        output_result(r, &mut self.closed)
    }

    fn head(&mut self) -> Result<()> {
        if !self.header && !self.closed {
            self.header = true;
            let r = writeln!(self.w, "{}", self.header_line);
            self.io(r)?;
        }
        Ok(())
    }

    /// Writes a row (nothing after an error or a closed pipe).
    fn row<O: EstimatorOutput>(&mut self, r: &Row<O>) {
        if self.error.is_some() || self.closed {
            return;
        }
        let res = self.head().and_then(|()| {
            if self.closed {
                return Ok(());
            }
            let res = write_row(self.w, r, self.axes, &mut self.line);
            self.io(res)
        });
        if let Err(e) = res {
            self.error = Some(e);
        }
    }

    fn take_error(&mut self) -> Result<()> {
        self.error.take().map_or(Ok(()), Err)
    }

    fn flush(&mut self) -> Result<()> {
        if !self.header || self.closed {
            return Ok(());
        }
        let r = self.w.flush();
        self.io(r)
    }

    fn end(&mut self) -> Result<()> {
        self.head()?;
        self.flush()
    }
}
