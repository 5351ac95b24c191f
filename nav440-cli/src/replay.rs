//! Replay of a recorded byte stream through `nav440_pipeline` (the firmware's pipeline):
//! parser -> attitude packets -> BIT check -> timed samples -> estimator banks -> CSV.
//!
//! What `nav440 stats|decode|estimate`, the paper protocol, the tuner, the plots and the
//! integration tests all call.

use crate::error::{Error, Result};
use estimators::{
    BankConfig, EstimatorBank, EstimatorOutput, Fx, GainSchedule, Hold, PaperBank, PaperOutput,
    ProductBank, ProductOutput, SampleError, YawBank,
};
pub use nav440_pipeline::bit::BitCounts;
use nav440_pipeline::period::PeriodEstimator;
pub use nav440_pipeline::period::WARMUP_SAMPLES;
use nav440_pipeline::{adaptive_axis_bank, axis_bank, AxisBank, Frontend, Pipeline};
use nav440_proto::Parser;
pub use nav440_proto::TimeFaults;
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::Path;

/// The capture name that means standard input.
pub const STDIN_NAME: &str = "-";

/// Size of one read from a capture, bytes: every command reads its input in chunks of this
/// size, so its memory does not grow with the capture.
pub const READ_CHUNK: usize = 64 * 1024;

/// `true` if `path` is `-` (standard input).
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == STDIN_NAME
}

/// The name of a capture in messages: its path, or "standard input" for `-`.
pub fn capture_name(path: &Path) -> String {
    if is_stdin(path) {
        "standard input".to_string()
    } else {
        path.display().to_string()
    }
}

/// A capture (file or standard input) read chunk by chunk.
pub struct CaptureReader {
    name: String,
    inner: Box<dyn std::io::Read>,
    bytes: u64,
}

impl std::fmt::Debug for CaptureReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CaptureReader")
            .field("name", &self.name)
            .field("bytes", &self.bytes)
            .finish()
    }
}

/// Opens a capture for reading: a file, or standard input for `-`. A missing or unreadable
/// file is an [`Error::Input`].
pub fn open_capture(path: &Path) -> Result<CaptureReader> {
    let name = capture_name(path);
    let inner: Box<dyn std::io::Read> = if is_stdin(path) {
        Box::new(std::io::stdin())
    } else {
        let f = std::fs::File::open(path)
            .map_err(|e| Error::Input(format!("cannot read {name}: {}", io_reason(&e))))?;
        if f.metadata().is_ok_and(|m| m.is_dir()) {
            return Err(Error::Input(format!("cannot read {name}: is a directory")));
        }
        Box::new(f)
    };
    Ok(CaptureReader {
        name,
        inner,
        bytes: 0,
    })
}

impl CaptureReader {
    /// The capture's name in messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Reads the next chunk into `buf`: `Ok(None)` at the end of the input. A read failure is an
    /// [`Error::Input`], and so is an input that ends before its first byte ("is empty").
    pub fn next_chunk<'a>(&mut self, buf: &'a mut [u8]) -> Result<Option<&'a [u8]>> {
        loop {
            match self.inner.read(buf) {
                Ok(0) if self.bytes == 0 => {
                    return Err(Error::Input(format!("{} is empty", self.name)))
                }
                Ok(0) => return Ok(None),
                Ok(n) => {
                    self.bytes += n as u64;
                    return Ok(buf.get(..n));
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    return Err(Error::Input(format!(
                        "cannot read {}: {}",
                        self.name,
                        io_reason(&e)
                    )))
                }
            }
        }
    }

    /// Reads the whole input in chunks of [`READ_CHUNK`] bytes, calling `f` on each, until the
    /// end or until `f` returns `Ok(false)` (stop) or an error.
    pub fn for_each_chunk(&mut self, mut f: impl FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        let mut buf = vec![0u8; READ_CHUNK];
        while let Some(chunk) = self.next_chunk(&mut buf)? {
            if !f(chunk)? {
                break;
            }
        }
        Ok(())
    }
}

/// Reads a whole capture into memory (file, or standard input for `-`); a missing, unreadable
/// or empty input is an [`Error::Input`]. The commands stream instead (see [`CaptureReader`]).
pub fn read_capture(path: &Path) -> Result<Vec<u8>> {
    let mut r = open_capture(path)?;
    let mut bytes = Vec::new();
    r.for_each_chunk(|c| {
        bytes.extend_from_slice(c);
        Ok(true)
    })?;
    Ok(bytes)
}

fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_string(),
        std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
        _ => e.to_string(),
    }
}

/// Parser statistics of a whole stream, with frames counted by type name.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StreamStats {
    /// Bytes fed to the parser.
    pub bytes: u64,
    /// CRC-checked frames by type name ("A2", "NAK", "z1", "??").
    pub frames: BTreeMap<String, u64>,
    /// Candidate frames rejected by their CRC.
    pub crc_errors: u64,
    /// Bytes that were not part of any valid frame (not counting `pending_bytes`).
    pub skipped_bytes: u64,
    /// Bytes at the end of the stream held by the parser as the start of a frame that the
    /// stream cut off (a truncated final frame, or a lone `55` that might start one): neither
    /// in a frame nor skipped. `bytes = frame bytes + skipped_bytes + pending_bytes`.
    pub pending_bytes: u64,
    /// Attitude packets whose BIT word flags a failure (masterFail; not estimated).
    pub bit: BitCounts,
}

impl StreamStats {
    /// Total number of valid frames.
    pub fn total_frames(&self) -> u64 {
        self.frames.values().sum()
    }

    /// The `nav440 stats` JSON object; a `bit_failures` object is appended only when some
    /// attitude packet flags a BIT failure (`{"flag": "masterFail", "packets": N,
    /// "hardware_error": N, "com_error": N, "software_error": N, "last_word": "0x0009"}`), so
    /// the output of a healthy capture is unchanged.
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = serde_json::json!({
            "bytes": self.bytes,
            "frames": self.frames,
            "crc_errors": self.crc_errors,
            "skipped_bytes": self.skipped_bytes,
            "pending_bytes": self.pending_bytes,
        });
        if self.bit.failed > 0 {
            if let Some(o) = v.as_object_mut() {
                o.insert(
                    "bit_failures".into(),
                    serde_json::json!({
                        "flag": nav440_pipeline::bit::FAILURE_FLAG,
                        "packets": self.bit.failed,
                        "hardware_error": self.bit.hardware_error,
                        "com_error": self.bit.com_error,
                        "software_error": self.bit.software_error,
                        "last_word": format!("0x{:04x}", self.bit.last_word),
                    }),
                );
            }
        }
        v
    }
}

/// [`StreamStats`] of a stream fed in any number of chunks (constant memory).
#[derive(Default)]
pub struct StatsCounter {
    parser: Parser,
    frames: BTreeMap<String, u64>,
    bit: BitCounts,
}

impl std::fmt::Debug for StatsCounter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StatsCounter")
            .field("frames", &self.frames)
            .finish()
    }
}

impl StatsCounter {
    /// A counter that has seen nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds the next bytes of the stream.
    pub fn push(&mut self, bytes: &[u8]) {
        let frames = &mut self.frames;
        let bit = &mut self.bit;
        self.parser.feed(bytes, |f| {
            if let Some(a) = nav440_proto::Packet::decode(f)
                .ok()
                .and_then(|p| nav440_pipeline::attitude(&p))
            {
                bit.check(a.bit);
            }
            let name = f.packet_type.name();
            match frames.get_mut(name) {
                Some(n) => *n += 1,
                None => {
                    frames.insert(name.to_string(), 1);
                }
            }
        });
    }

    /// The statistics of everything fed so far.
    pub fn stats(&self) -> StreamStats {
        let s = self.parser.stats();
        StreamStats {
            bytes: s.bytes,
            frames: self.frames.clone(),
            crc_errors: s.crc_errors,
            skipped_bytes: s.skipped_bytes,
            pending_bytes: s.pending_bytes(),
            bit: self.bit,
        }
    }
}

/// Runs the parser over `bytes` and counts frames by type.
pub fn stream_stats(bytes: &[u8]) -> StreamStats {
    let mut c = StatsCounter::new();
    c.push(bytes);
    c.stats()
}

pub use nav440_pipeline::{Axes, Axis, AxisRow, Rejections, Row, Sample};

/// Streaming sample extraction: `nav440_pipeline::Frontend` (bytes -> parser -> attitude
/// packets -> BIT check -> `nav440_proto::TimeBase` -> [`Sample`]s, the firmware's front end),
/// for the commands that need the samples themselves (`paper`, `tune`, `plot`, tests). Feed it
/// bytes in any chunking; call [`SampleReader::finish`] at the end of input.
#[derive(Debug, Default)]
pub struct SampleReader {
    front: Frontend,
}

impl SampleReader {
    /// A reader at the start of a stream.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds bytes; `out` gets every sample released.
    pub fn feed(&mut self, bytes: &[u8], out: impl FnMut(Sample)) {
        self.front.feed(bytes, out);
    }

    /// End of input: releases a held sample if the time rules allow it.
    pub fn finish(&mut self, out: impl FnMut(Sample)) {
        self.front.finish(out);
    }

    /// Time-stamp faults so far.
    pub fn faults(&self) -> TimeFaults {
        *self.front.time_faults()
    }

    /// Samples dropped for a BIT failure so far.
    pub fn bit(&self) -> BitCounts {
        self.front.counters().bit
    }

    /// Valid (CRC-checked) frames so far.
    pub fn frames(&self) -> u64 {
        self.front.counters().frames
    }

    /// Packets carrying the attitude (and yaw) so far, before the BIT and time rules.
    pub fn yaw_packets(&self) -> u64 {
        self.front.counters().attitude_packets
    }

    /// Samples released so far.
    pub fn samples(&self) -> u64 {
        self.front.counters().samples
    }

    /// Parser statistics so far.
    pub fn parser_stats(&self) -> &nav440_proto::Stats {
        self.front.parser_stats()
    }

    /// The error for a finished stream that gave no sample ([`Error::NotNav440`]), or `Ok`.
    pub fn check_nonempty(&self) -> Result<()> {
        check_front(&self.front)
    }
}

/// [`check_yaw_stream`] for a front end, naming BIT failures when they took every sample.
fn check_front(front: &Frontend) -> Result<()> {
    let c = front.counters();
    if c.frames > 0 && c.samples == 0 && c.bit.failed > 0 {
        return Err(Error::NotNav440(format!(
            "{} NAV440 frames but every one of the {} attitude packets flags a BIT failure ({}); nothing to estimate",
            c.frames,
            c.attitude_packets,
            nav440_pipeline::bit::FAILURE_FLAG
        )));
    }
    check_yaw_stream(c.frames, c.samples)
}

/// [`Error::NotNav440`] for a stream of `frames` valid frames of which `samples` gave a timed
/// yaw sample, when either is 0 (shared by every reader of captures, `nav440 sim` too).
pub fn check_yaw_stream(frames: u64, samples: u64) -> Result<()> {
    if frames == 0 {
        return Err(Error::NotNav440(
            "no NAV440 frame found (not a NAV440 capture?)".into(),
        ));
    }
    if samples == 0 {
        return Err(Error::NotNav440(format!(
            "{frames} NAV440 frames but none carries yaw with a usable time stamp (need A0/A1/A2/N0/N1/B1)"
        )));
    }
    Ok(())
}

/// Extracts the timed samples of every packet that carries the attitude, in stream order
/// (BIT failures dropped). A stream without any valid frame, or without any such packet, is
/// an [`Error::NotNav440`].
pub fn samples(bytes: &[u8]) -> Result<Vec<Sample>> {
    samples_and_faults(bytes).map(|(s, _)| s)
}

/// [`samples`] and the time-stamp faults met on the way.
pub fn samples_and_faults(bytes: &[u8]) -> Result<(Vec<Sample>, TimeFaults)> {
    let mut reader = SampleReader::new();
    let mut out = Vec::new();
    reader.feed(bytes, |s| out.push(s));
    reader.finish(|s| out.push(s));
    reader.check_nonempty()?;
    Ok((out, reader.faults()))
}

/// [`samples`] of a capture read in chunks (file, or standard input for `-`): memory is the
/// samples', not the capture's. Errors name the capture.
pub fn read_samples(path: &Path) -> Result<Vec<Sample>> {
    read_samples_and_faults(path).map(|(s, _)| s)
}

/// [`read_samples`] and the time-stamp faults met on the way.
pub fn read_samples_and_faults(path: &Path) -> Result<(Vec<Sample>, TimeFaults)> {
    let mut r = open_capture(path)?;
    let mut reader = SampleReader::new();
    let mut out = Vec::new();
    r.for_each_chunk(|c| {
        reader.feed(c, |s| out.push(s));
        Ok(true)
    })?;
    reader.finish(|s| out.push(s));
    reader.check_nonempty().map_err(|e| match e {
        Error::NotNav440(m) => Error::NotNav440(format!("{}: {m}", r.name())),
        other => other,
    })?;
    Ok((out, reader.faults()))
}

/// Gaussian noise added to the angles before estimation (the paper's protocol).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Variance, deg^2.
    pub var: f64,
    /// Seed of the generator (xoshiro256++, one N(0, var) draw per sample in order). Each axis
    /// has its own generator: yaw seeded with `seed` (so the yaw noise does not depend on the
    /// other axes), roll and pitch with [`axis_seed`].
    pub seed: u64,
}

/// The seed of `axis`'s noise generator for the seed `seed`: `seed` for yaw, `seed` XOR a
/// fixed odd constant per axis for roll and pitch.
pub fn axis_seed(seed: u64, axis: Axis) -> u64 {
    match axis {
        Axis::Yaw => seed,
        Axis::Roll => seed ^ 0x9E37_79B9_7F4A_7C15,
        Axis::Pitch => seed ^ 0xD1B5_4A32_D192_ED03,
    }
}

/// The yaw of each sample plus noise (if any), degrees.
pub fn noisy_yaw(samples: &[Sample], noise: Option<Noise>) -> Result<Vec<f32>> {
    noisy_angle(samples, Axis::Yaw, noise)
}

/// The angle of `axis` of each sample plus noise (if any; the axis's generator, see
/// [`Noise::seed`]), degrees.
pub fn noisy_angle(samples: &[Sample], axis: Axis, noise: Option<Noise>) -> Result<Vec<f32>> {
    match noise {
        None => Ok(samples.iter().map(|s| s.angle(axis)).collect()),
        Some(n) => {
            let normal = Normal::new(0.0, n.var.max(0.0).sqrt())
                .map_err(|e| Error::Usage(format!("bad noise variance {}: {e}", n.var)))?;
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(axis_seed(n.seed, axis));
            Ok(samples
                .iter()
                .map(|s| (f64::from(s.angle(axis)) + normal.sample(&mut rng)) as f32)
                .collect())
        }
    }
}

/// Options of `nav440 estimate` (and of every replay through the bank).
#[derive(Clone, Debug)]
pub struct EstimateOptions {
    /// Sample adapter input mode.
    pub hold: Hold,
    /// Observer step h, s.
    pub step_s: f32,
    /// Noise added to each estimated angle.
    pub noise: Option<Noise>,
    /// Run the fixed-point bank (`YawBank<Fx>`) instead of f32.
    pub fixed: bool,
    /// Bank configuration with gains (from `--preset`, `--gains`); `None` =
    /// `BankConfig::NAV440` (with [`EstimateOptions::paper_law`]: `BankConfig::PAPER`).
    pub config: Option<BankConfig>,
    /// Replace the gains by the shipped preset's for the measured packet period
    /// (`BankConfig::with_nav440_gains`) once the warm-up has measured it, then apply
    /// [`EstimateOptions::overlay`]: what `nav440 estimate` does with the default `--preset
    /// nav440`, as the firmware does. Default `false`: `config`'s gains as they are.
    pub follow_rate: bool,
    /// The `--gains` file's gains, if one was given (`nav440 paper` names them in its
    /// settings). With [`EstimateOptions::follow_rate`] they are applied over the rate's preset
    /// gains (the families the file leaves out keep the preset's); without, `config` already
    /// holds them.
    pub overlay: Option<crate::gains::GainsFile>,
    /// Where the noise enters (per packet, or per observer step).
    pub noise_at: NoiseAt,
    /// The estimated axes (`--axis`; default yaw only).
    pub axes: Axes,
    /// A gain schedule (`--gains schedule.toml`): run the noise-adaptive bank
    /// (`estimators::AdaptiveBank`, `AdaptiveConfig::DEFAULT`) with `config`'s step, hold and
    /// period instead of fixed gains (paper bank only).
    pub schedule: Option<GainSchedule>,
    /// The bank `nav440 estimate` runs (`--bank`; default the paper bank). Only
    /// [`estimate_stream`] (and [`estimate_csv`]) run a bank other than the paper bank; the
    /// row APIs ([`Estimation`], [`estimate_rows`], ...) are the paper bank's and refuse
    /// another (a usage error).
    pub bank: BankKind,
}

/// Which estimator bank `nav440 estimate` runs (`--bank`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BankKind {
    /// `estimators::PaperBank` (or `AdaptiveBank` with a gain schedule): the paper's 14
    /// estimators, CSV `t,yaw,yaw_rate,ave_v,...,kf_a` (the default).
    #[default]
    Paper,
    /// `estimators::ProductBank`: ILO1 velocity (`cfg.velocity.ilo[0]`) and Kalman
    /// acceleration (`cfg.acceleration.kf`), CSV `t,yaw,yaw_rate,ilo1_v,kf_a`: what the
    /// product firmware prints.
    Product,
}

impl BankKind {
    /// The `--bank` name.
    pub fn name(self) -> &'static str {
        match self {
            BankKind::Paper => "paper",
            BankKind::Product => "product",
        }
    }
}

/// Where the added noise enters the estimators.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NoiseAt {
    /// One N(0, V) draw per packet, added to its angle (the protocol as stated; default).
    #[default]
    Sample,
    /// The packets' unwrapped angle is linearly interpolated onto the observer's step grid
    /// (every `h` s) and an independent N(0, V) draw is added at every step; the bank is fed
    /// every step (`n = 1`) and a row is reported at each packet time. This is what a
    /// simulation that resamples the recording to the 1e-4 s integration step and adds the
    /// noise there computes (our reading of how the paper's small noise MSEs arise).
    Step,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        EstimateOptions {
            hold: Hold::Linear,
            step_s: 1e-4,
            noise: None,
            fixed: false,
            config: None,
            follow_rate: false,
            overlay: None,
            noise_at: NoiseAt::Sample,
            axes: Axes::only(Axis::Yaw),
            schedule: None,
            bank: BankKind::Paper,
        }
    }
}

impl EstimateOptions {
    /// The bank configuration these options describe (gains from `config` or the shipped
    /// preset `BankConfig::NAV440`, step and hold from the options), before adapting it to a
    /// capture.
    pub fn bank_config(&self) -> BankConfig {
        let mut cfg = self.config.unwrap_or(BankConfig::NAV440);
        cfg.h = self.step_s;
        cfg.hold = self.hold;
        cfg
    }

    /// The first estimated axis (the one `paper`, `tune` and `plot` score; yaw if none).
    pub fn axis(&self) -> Axis {
        self.axes.iter().next().unwrap_or(Axis::Yaw)
    }

    /// These options with the paper's laws as the base when no gains file is given
    /// (`BankConfig::PAPER`: the AVE's `deltahat` only grows), for the paper's experiment
    /// (`nav440 paper`, `nav440 tune`); `nav440 estimate` and the firmware run
    /// `BankConfig::NAV440` (tuned gains, leaky `deltahat`, docs/CALIBRATION.md).
    pub fn paper_law(&self) -> Self {
        Self {
            config: Some(self.config.unwrap_or(BankConfig::PAPER)),
            ..self.clone()
        }
    }

    /// [`EstimateOptions::bank_config`] with the nominal sample period set from the capture by
    /// `nav440_pipeline::period`, the causal rule the firmware uses too: the upper median of
    /// the intervals between the first [`WARMUP_SAMPLES`] samples (0.01 s for a 100 Hz capture,
    /// i.e. `BankConfig::PAPER`'s value), whatever the rate does later; a capture shorter than
    /// the warm-up uses the intervals it has, a single sample keeps the configured period. The
    /// closed-form maps and the Kalman gains are computed for it.
    pub fn bank_config_for(&self, samples: &[Sample]) -> BankConfig {
        self.at_period(
            PeriodEstimator::from_times(samples.iter().map(|s| s.t_us).take(WARMUP_SAMPLES))
                .apply(self.bank_config()),
        )
    }

    /// The configuration the bank runs once the warm-up has set `cfg`'s nominal sample
    /// period: with [`EstimateOptions::follow_rate`], the shipped preset's gains for that
    /// period with [`EstimateOptions::overlay`] over them; else `cfg` itself.
    pub fn at_period(&self, cfg: BankConfig) -> BankConfig {
        if !self.follow_rate {
            return cfg;
        }
        let cfg = cfg.with_nav440_gains();
        match &self.overlay {
            Some(g) => g.apply(cfg),
            None => cfg,
        }
    }

    /// The nominal sample period the bank runs at on `samples`, s: the step `step_s` with
    /// `--noise-at step` (the bank sees one sample per step), else
    /// [`EstimateOptions::bank_config_for`]'s.
    pub fn bank_period_s(&self, samples: &[Sample]) -> f32 {
        match self.noise_at {
            NoiseAt::Step => self.step_s,
            NoiseAt::Sample => self.bank_config_for(samples).sample_period_s,
        }
    }
}

/// What a run of the bank gives: rows and the counts of samples it did not turn into rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// One row per accepted sample.
    pub rows: Vec<Row>,
    /// Samples the bank rejected (non-finite or out-of-range angle).
    pub rejected: usize,
    /// Gaps longer than the gap rule (`BankConfig::max_gap_periods` nominal periods): the bank
    /// re-initialised there (`YawBank::reinit_count`).
    pub gaps: u32,
}

/// Runs the estimator bank over `samples`. A sample the bank rejects (non-finite or
/// out-of-range angle) yields no row; the count of those is returned too.
pub fn estimate(samples: &[Sample], opts: &EstimateOptions) -> Result<(Vec<Row>, usize)> {
    estimate_report(samples, opts).map(|e| (e.rows, e.rejected))
}

/// [`estimate`] with the bank's gap count.
pub fn estimate_report(samples: &[Sample], opts: &EstimateOptions) -> Result<Estimate> {
    let (rows, summary) = estimate_rows(samples, opts)?;
    Ok(Estimate {
        rows,
        rejected: usize::try_from(summary.rejected.total()).unwrap_or(usize::MAX),
        gaps: summary.gaps,
    })
}

/// [`estimate`] with the rejected samples counted by reason.
pub fn estimate_rows(
    samples: &[Sample],
    opts: &EstimateOptions,
) -> Result<(Vec<Row>, EstimationSummary)> {
    let mut rows = Vec::with_capacity(samples.len());
    let mut est = Estimation::new(opts)?;
    let mut keep = |r: Row| {
        rows.push(r);
        Ok(())
    };
    for &s in samples {
        est.push(s, &mut keep)?;
    }
    let summary = est.finish(&mut keep)?;
    Ok((rows, summary))
}

/// The one-line `nav440 estimate` warning for time faults and gaps (`None` when there were
/// none): `time faults: impossible=N bad_backward=N bad_forward=N backward_jumps=N
/// kind_switches=N other_kind=N duplicates=N gaps=N`.
pub fn fault_warning(f: &TimeFaults, gaps: u32) -> Option<String> {
    (f.any() || f.duplicates > 0 || gaps > 0).then(|| {
        format!(
            "time faults: impossible={} bad_backward={} bad_forward={} backward_jumps={} kind_switches={} other_kind={} duplicates={} gaps={}",
            f.impossible, f.bad_backward, f.bad_forward, f.backward_jumps, f.kind_switches, f.other_kind, f.duplicates, gaps
        )
    })
}

/// The one-line warning for samples not estimated because of their BIT word (`None` when
/// there were none): `BIT failure: N samples not estimated (masterFail; ...)`.
pub fn bit_warning(b: &BitCounts) -> Option<String> {
    let mut s = String::new();
    b.write_warning(&mut s).ok()?;
    (!s.is_empty()).then_some(s)
}

/// The end of an [`Estimation`]: the samples that gave no row, and the gaps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EstimationSummary {
    /// Samples the bank rejected, by reason.
    pub rejected: Rejections,
    /// Gaps longer than the gap rule, where the bank re-initialised (new epochs not counted).
    pub gaps: u32,
}

/// What [`estimate_stream`] reports besides the CSV.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamReport {
    /// Rejected samples and gaps.
    pub summary: EstimationSummary,
    /// Time-stamp faults met by the sample extraction.
    pub faults: TimeFaults,
    /// Samples not estimated because their BIT word flags a failure.
    pub bit: BitCounts,
    /// With a gain schedule tuned at another sample period than the capture's
    /// (`estimators::GainSchedule::fits_period`): (the schedule's period, the bank's), us.
    pub schedule_misfit_us: Option<(u64, u64)>,
}

impl StreamReport {
    /// The warning lines `nav440 estimate` (and `nav440 live`) print on stderr: BIT failures,
    /// rejected samples, then time faults and gaps (none when everything was clean).
    pub fn warnings(&self) -> impl Iterator<Item = String> {
        bit_warning(&self.bit)
            .into_iter()
            .chain(rejection_warning(&self.summary.rejected))
            .chain(fault_warning(&self.faults, self.summary.gaps))
            .chain(self.schedule_misfit_us.map(schedule_warning))
    }
}

/// The CLI's warning for a gain schedule run at another sample period than it was tuned at
/// (periods in us).
pub fn schedule_warning((tuned_us, run_us): (u64, u64)) -> String {
    let at = |us: u64| {
        let (s, hz) = (us as f64 / 1e6, (1e9 / us.max(1) as f64).round() / 1e3);
        format!("{s} s ({hz} Hz)")
    };
    format!(
        "the gain schedule was tuned at a sample period of {}, the bank runs at {} on this capture: a schedule's gains are tuned to its rate and can do worse here than the fixed NAV440 preset (docs/CALIBRATION.md, Low packet rates); tune one on a capture at this rate (nav440 tune CAPTURE --schedule ...)",
        at(tuned_us),
        at(run_us)
    )
}

/// The CLI's one-line warning for rejected samples, `None` if nothing was rejected, e.g. "3
/// samples rejected by the estimator bank: 2 with time not increasing, 1 with |yaw| above
/// 1000000 deg".
pub fn rejection_warning(r: &Rejections) -> Option<String> {
    if r.total() == 0 {
        return None;
    }
    let mut parts = Vec::new();
    if r.time_not_increasing > 0 {
        parts.push(format!(
            "{} with time not increasing",
            r.time_not_increasing
        ));
    }
    if r.angle_out_of_range > 0 {
        parts.push(format!(
            "{} with |yaw| above {} deg",
            r.angle_out_of_range,
            YawBank::<f32>::MAX_ABS_YAW_DEG
        ));
    }
    if r.angle_not_finite > 0 {
        parts.push(format!("{} with yaw NaN or infinite", r.angle_not_finite));
    }
    Some(format!(
        "{} samples rejected by the estimator bank: {}",
        r.total(),
        parts.join(", ")
    ))
}

/// The part of `estimators::EstimatorBank` the host calls per sample, as an object (one
/// boxed bank per axis whatever its number type).
pub trait DynBank<O> {
    /// `EstimatorBank::update`.
    fn update(&mut self, t_us: u64, angle_deg: f32) -> std::result::Result<O, SampleError>;
    /// `EstimatorBank::new_epoch`.
    fn new_epoch(&mut self);
    /// `EstimatorBank::reinit_count`.
    fn reinit_count(&self) -> u32;
}

impl<B: EstimatorBank> DynBank<B::Output> for B {
    fn update(&mut self, t_us: u64, deg: f32) -> std::result::Result<B::Output, SampleError> {
        EstimatorBank::update(self, t_us, deg)
    }

    fn new_epoch(&mut self) {
        EstimatorBank::new_epoch(self);
    }

    fn reinit_count(&self) -> u32 {
        EstimatorBank::reinit_count(self)
    }
}

/// A built host bank: the bank, and for a noise-adaptive bank whose schedule was tuned at
/// another sample period (`AdaptiveBank::period_fits`): (the schedule's period, the bank's), s.
pub type BuiltBank<O> = (Box<dyn DynBank<O>>, Option<(f32, f32)>);

/// The output of a bank `nav440 estimate` can run: how the host builds that bank (f32 or
/// fixed point, fixed or scheduled gains) for an axis.
pub trait HostOutput: EstimatorOutput + 'static {
    /// The bank of `axis` for `cfg` (built by `nav440_pipeline::axis_bank` or
    /// `adaptive_axis_bank`, which set the axis's unwrapping): `fixed` selects `Fx`,
    /// `schedule` the noise-adaptive bank. Errors are the CLI's messages.
    fn build(
        axis: Axis,
        cfg: &BankConfig,
        fixed: bool,
        schedule: Option<&GainSchedule>,
    ) -> std::result::Result<BuiltBank<Self>, String>;
}

/// The CLI's message for a configuration the bank refuses.
fn bad_config(cfg: &BankConfig, e: estimators::ConfigError) -> String {
    let mut m = format!("bad estimator configuration: {e}");
    if e == estimators::ConfigError::SamplePeriodTooLong {
        m.push_str(&format!(
            " (nominal sample period {} s from the capture's first {WARMUP_SAMPLES} samples, h = {} s; use a larger --step)",
            cfg.sample_period_s, cfg.h
        ));
    }
    m
}

/// `(fits, schedule's period, bank's period)` of an adaptive bank -> the misfit, if any.
fn misfit(fits: bool, tuned: &GainSchedule, run: f32) -> Option<(f32, f32)> {
    if fits {
        return None;
    }
    Some((tuned.sample_period_s()?, run))
}

impl HostOutput for PaperOutput {
    fn build(
        axis: Axis,
        cfg: &BankConfig,
        fixed: bool,
        schedule: Option<&GainSchedule>,
    ) -> std::result::Result<BuiltBank<Self>, String> {
        let bad = |e| bad_config(cfg, e);
        if let Some(sched) = schedule {
            return Ok(if fixed {
                let b: estimators::AdaptiveBank<Fx> =
                    adaptive_axis_bank(axis, cfg, sched).map_err(bad)?;
                let m = misfit(b.period_fits(), b.schedule(), b.sample_period_s());
                (Box::new(b), m)
            } else {
                let b: estimators::AdaptiveBank<f32> =
                    adaptive_axis_bank(axis, cfg, sched).map_err(bad)?;
                let m = misfit(b.period_fits(), b.schedule(), b.sample_period_s());
                (Box::new(b), m)
            });
        }
        Ok(if fixed {
            (
                Box::new(axis_bank::<PaperBank<Fx>>(axis, cfg).map_err(bad)?),
                None,
            )
        } else {
            (
                Box::new(axis_bank::<PaperBank<f32>>(axis, cfg).map_err(bad)?),
                None,
            )
        })
    }
}

impl HostOutput for ProductOutput {
    fn build(
        axis: Axis,
        cfg: &BankConfig,
        fixed: bool,
        schedule: Option<&GainSchedule>,
    ) -> std::result::Result<BuiltBank<Self>, String> {
        if schedule.is_some() {
            return Err(PRODUCT_SCHEDULE.to_string());
        }
        let bad = |e| bad_config(cfg, e);
        Ok(if fixed {
            (
                Box::new(axis_bank::<ProductBank<Fx>>(axis, cfg).map_err(bad)?),
                None,
            )
        } else {
            (
                Box::new(axis_bank::<ProductBank<f32>>(axis, cfg).map_err(bad)?),
                None,
            )
        })
    }
}

/// Why `--bank product` refuses a gain schedule.
const PRODUCT_SCHEDULE: &str = "--bank product runs fixed gains; a gain schedule (a --gains file written by `nav440 tune --schedule`) runs the noise-adaptive paper bank: use --bank paper, or a fixed gains file";

/// The added noise: N(0, var) draws from xoshiro256++ seeded with the seed, in order.
struct NoiseGen {
    normal: Normal<f64>,
    rng: Xoshiro256PlusPlus,
    active: bool,
}

impl NoiseGen {
    fn new(noise: Option<Noise>, axis: Axis) -> Result<Self> {
        let (var, seed) = noise.map_or((0.0, 0), |n| (n.var, axis_seed(n.seed, axis)));
        let normal = Normal::new(0.0, var.max(0.0).sqrt())
            .map_err(|e| Error::Usage(format!("bad noise variance {var}: {e}")))?;
        Ok(NoiseGen {
            normal,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
            active: var > 0.0,
        })
    }

    /// `y` plus the next draw (exactly `y` without noise).
    fn add(&mut self, y: f64) -> f32 {
        if self.active {
            (y + self.normal.sample(&mut self.rng)) as f32
        } else {
            y as f32
        }
    }
}

/// What the [`NoiseAt::Step`] mode remembers between samples.
struct StepState {
    /// Observer step, us.
    h_us: u64,
    /// The gap rule of the packet-rate bank ([`NoiseAt::Sample`]), us: an interval beyond it
    /// is not interpolated; the bank re-initialises there, as in sample mode.
    gap_us: u64,
    /// Restarts at such gaps.
    gaps: u32,
    /// Unwrapping (the rule of [`unwrap_deg`]; `None` for pitch, which does not wrap).
    unwrap: Option<DegUnwrapper>,
    /// The previous sample's time (us) and unwrapped angle (deg).
    prev: Option<(u64, f32)>,
}

/// The host's bank of one axis: the f32 or fixed-point bank of output `O` (the paper bank's
/// by default, [`HostOutput`]), the added noise and the per-mode state; `nav440_pipeline`
/// drives it ([`AxisBank`]).
pub struct HostBank<O = PaperOutput> {
    bank: Box<dyn DynBank<O>>,
    misfit: Option<(f32, f32)>,
    noise: NoiseGen,
    step: Option<StepState>,
}

impl<O> std::fmt::Debug for HostBank<O> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostBank").finish_non_exhaustive()
    }
}

impl<O: HostOutput> HostBank<O> {
    /// The bank of `axis` for the options `opts` and the warm-up's configuration `cfg`.
    fn new(
        axis: Axis,
        opts: &EstimateOptions,
        cfg: &BankConfig,
    ) -> std::result::Result<Self, String> {
        let mut cfg = opts.at_period(*cfg);
        let noise = NoiseGen::new(opts.noise, axis).map_err(|e| e.to_string())?;
        let step = if opts.noise_at == NoiseAt::Step {
            // The packet-level gap rule (the bank itself sees one sample per step).
            let gap_us = s_to_us(cfg.max_gap_s());
            // The bank sees one sample per step: closed-form maps and Kalman gains for that
            // period.
            cfg.sample_period_s = opts.step_s;
            Some(StepState {
                h_us: (f64::from(opts.step_s) * 1e6).round().max(1.0) as u64,
                gap_us,
                gaps: 0,
                unwrap: axis.wraps().then(DegUnwrapper::default),
                prev: None,
            })
        } else {
            None
        };
        let (bank, misfit) = O::build(axis, &cfg, opts.fixed, opts.schedule.as_ref())?;
        Ok(HostBank {
            bank,
            misfit,
            noise,
            step,
        })
    }

    /// For a noise-adaptive bank whose schedule was tuned at another sample period
    /// (`AdaptiveBank::period_fits`): (the schedule's period, the bank's), s.
    fn schedule_misfit(&self) -> Option<(f32, f32)> {
        self.misfit
    }
}

impl<O: HostOutput> AxisBank for HostBank<O> {
    type Output = O;

    /// The per-sample step of both noise modes.
    fn step(&mut self, s: &Sample, angle_deg: f32) -> std::result::Result<O, SampleError> {
        let r = self;
        match r.step.as_mut() {
            None => {
                if s.new_epoch {
                    r.bank.new_epoch();
                }
                let y = r.noise.add(f64::from(angle_deg));
                r.bank.update(s.t_us, y)
            }
            Some(st) => {
                let y = match st.unwrap.as_mut() {
                    Some(u) => u.push(angle_deg),
                    None => angle_deg,
                };
                let prev = st.prev.replace((s.t_us, y));
                match prev {
                    None => r.bank.update(s.t_us, r.noise.add(f64::from(y))),
                    // A new epoch, or a gap the sample-mode bank re-initialises on: no
                    // interpolation across it; the bank restarts from this sample.
                    Some((pt, _)) if s.new_epoch || s.t_us.saturating_sub(pt) > st.gap_us => {
                        if !s.new_epoch {
                            st.gaps = st.gaps.saturating_add(1);
                        }
                        r.bank.new_epoch();
                        r.bank.update(s.t_us, r.noise.add(f64::from(y)))
                    }
                    Some((pt, py)) if s.t_us > pt => {
                        let h_us = st.h_us;
                        let n = ((s.t_us - pt + h_us / 2) / h_us).max(1);
                        let mut last = Err(SampleError::NonIncreasingTime);
                        for j in 1..=n {
                            let t = if j == n { s.t_us } else { pt + j * h_us };
                            let yi = f64::from(py)
                                + (f64::from(y) - f64::from(py)) * j as f64 / n as f64;
                            last = r.bank.update(t, r.noise.add(yi));
                        }
                        last
                    }
                    Some(_) => Err(SampleError::NonIncreasingTime),
                }
            }
        }
    }

    fn gaps(&self) -> u32 {
        match &self.step {
            Some(st) => st.gaps,
            None => self.bank.reinit_count(),
        }
    }
}

/// The host's bank constructor (captures the options).
type BuildFn<O = PaperOutput> =
    Box<dyn FnMut(Axis, &BankConfig) -> std::result::Result<HostBank<O>, String>>;

fn build_fn<O: HostOutput>(opts: &EstimateOptions) -> BuildFn<O> {
    let opts = opts.clone();
    Box::new(move |axis, cfg| HostBank::new(axis, &opts, cfg))
}

/// `nav440 estimate`'s pipeline: `nav440_pipeline::Pipeline` with the host's banks.
type HostPipeline<O> = Pipeline<HostBank<O>, String, BuildFn<O>>;

/// The options' bank is one the row APIs run (the paper bank's).
fn check_paper_bank(opts: &EstimateOptions) -> Result<()> {
    match opts.bank {
        BankKind::Paper => Ok(()),
        k => Err(Error::Usage(format!(
            "--bank {} is for `nav440 estimate` only (its CSV); this command runs the paper bank",
            k.name()
        ))),
    }
}

/// The options' bank accepts the options: a gain schedule needs the paper bank (a usage
/// error otherwise).
pub fn check_bank_options(opts: &EstimateOptions) -> Result<()> {
    if opts.bank == BankKind::Product && opts.schedule.is_some() {
        return Err(Error::Usage(PRODUCT_SCHEDULE.to_string()));
    }
    Ok(())
}

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
fn forward_rows<T>(
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
            inner: nav440_pipeline::Estimation::new(opts.axes, opts.bank_config(), build_fn(opts)),
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
        Ok(EstimationSummary {
            rejected: c.rejected,
            gaps: c.gaps,
        })
    }
}

/// The CSV header of yaw alone (`nav440 estimate`'s default), shared with the firmware.
pub const CSV_HEADER: &str = nav440_pipeline::csv::HEADER;

/// The paper bank's CSV header line of `axes` (see `nav440_pipeline::csv`).
pub fn csv_header(axes: Axes) -> String {
    csv_header_of::<PaperOutput>(axes)
}

/// The CSV header line of `axes` for the bank `kind` (`nav440 estimate --bank`).
pub fn bank_csv_header(kind: BankKind, axes: Axes) -> String {
    match kind {
        BankKind::Paper => csv_header_of::<PaperOutput>(axes),
        BankKind::Product => csv_header_of::<ProductOutput>(axes),
    }
}

/// The CSV header line of `axes` for a bank of output `O` (`nav440_pipeline::csv`).
fn csv_header_of<O: EstimatorOutput>(axes: Axes) -> String {
    let mut s = String::new();
    // Writing into a String cannot fail.
    let _ = nav440_pipeline::csv::write_header_of::<O>(&mut s, axes);
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
pub fn estimate_stream<'a, W: std::io::Write + ?Sized>(
    input: impl IntoChunks<'a>,
    opts: &EstimateOptions,
    w: &mut W,
) -> Result<StreamReport> {
    check_bank_options(opts)?;
    match opts.bank {
        BankKind::Paper => stream_bank::<PaperOutput, W>(input, opts, w),
        BankKind::Product => stream_bank::<ProductOutput, W>(input, opts, w),
    }
}

/// [`estimate_stream`] with the banks of output `O`.
fn stream_bank<'a, O: HostOutput, W: std::io::Write + ?Sized>(
    input: impl IntoChunks<'a>,
    opts: &EstimateOptions,
    w: &mut W,
) -> Result<StreamReport> {
    NoiseGen::new(opts.noise, Axis::Yaw)?;
    let mut pipe: HostPipeline<O> =
        Pipeline::new(opts.axes, opts.bank_config(), build_fn::<O>(opts));
    let mut sink = CsvSink::new(w, opts.axes, csv_header_of::<O>(opts.axes));
    input.chunks(&mut |chunk| {
        let res = pipe.feed(chunk, &mut |r| sink.row(r));
        sink.take_error()?;
        res.map_err(Error::Usage)?;
        sink.flush()?;
        Ok(!sink.closed)
    })?;
    if sink.closed {
        return Ok(StreamReport::default());
    }
    let res = pipe.finish(&mut |r| sink.row(r));
    sink.take_error()?;
    check_front(pipe.front())?;
    res.map_err(Error::Usage)?;
    sink.end()?;
    let c = pipe.estimation().counters();
    Ok(StreamReport {
        summary: EstimationSummary {
            rejected: c.rejected,
            gaps: c.gaps,
        },
        faults: *pipe.front().time_faults(),
        bit: pipe.front().counters().bit,
        schedule_misfit_us: opts
            .axes
            .iter()
            .find_map(|a| pipe.estimation().bank(a)?.schedule_misfit())
            .map(|(t, p)| (s_to_us(t), s_to_us(p))),
    })
}

/// A period in s as whole us (rounded).
fn s_to_us(s: f32) -> u64 {
    (f64::from(s) * 1e6).round() as u64
}

/// A byte stream given in chunks: a slice (one chunk) or a [`CaptureReader`].
pub trait IntoChunks<'a> {
    /// Calls `f` on each chunk until the end or until `f` returns `Ok(false)`.
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()>;
}

impl<'a> IntoChunks<'a> for &'a [u8] {
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        f(self).map(|_| ())
    }
}

/// A byte source that pushes its chunks itself (e.g. a serial port read until it closes):
/// `FnChunks(|f| { ...; f(chunk)?; ... })`; it should stop when `f` returns `Ok(false)`.
pub struct FnChunks<F>(pub F);

impl<'a, F> IntoChunks<'a> for FnChunks<F>
where
    F: FnOnce(&mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()>,
{
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        (self.0)(f)
    }
}

impl<'a> IntoChunks<'a> for &'a mut CaptureReader {
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        self.for_each_chunk(f)
    }
}

/// The result of a write to the command's output: a closed pipe (`nav440 ... | head`) sets
/// `closed` and is not an error (the command stops quietly); any other failure is an
/// [`Error::Output`].
pub fn output_result(r: std::io::Result<()>, closed: &mut bool) -> Result<()> {
    match r {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            *closed = true;
            Ok(())
        }
        Err(e) => Err(Error::Output(format!("cannot write output: {e}"))),
        Ok(()) => Ok(()),
    }
}

/// Writes the estimate CSV as rows come: the header before the first row (or at the end). A
/// write error is kept (and later rows dropped) until [`CsvSink::take_error`].
struct CsvSink<'w, W: std::io::Write + ?Sized> {
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

/// Unwraps a wrapped angle sequence (deg) so consecutive values differ by at most 180 deg.
pub fn unwrap_deg(wrapped: &[f32]) -> Vec<f32> {
    let mut u = DegUnwrapper::default();
    wrapped.iter().map(|&w| u.push(w)).collect()
}

/// [`unwrap_deg`] one angle at a time (f64 offset in whole turns, deg).
#[derive(Clone, Copy, Debug, Default)]
struct DegUnwrapper {
    offset: f64,
    prev: Option<f64>,
}

impl DegUnwrapper {
    /// The next wrapped angle (deg), unwrapped (deg).
    fn push(&mut self, wrapped: f32) -> f32 {
        let w = f64::from(wrapped);
        if let Some(p) = self.prev {
            self.offset -= 360.0 * ((w - p) / 360.0).round();
        }
        self.prev = Some(w);
        (w + self.offset) as f32
    }
}
