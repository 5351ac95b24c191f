//! Replay of a recorded byte stream: parser -> packets -> timed yaw samples -> estimator bank.
//!
//! This is the host twin of the firmware's pipeline, and what `nav440 stats|decode|estimate`,
//! the paper protocol, the tuner, the plots and the integration tests all call.

use crate::error::{Error, Result};
use estimators::period::PeriodEstimator;
pub use estimators::period::WARMUP_SAMPLES;
use estimators::{BankConfig, BankOutput, Fx, Hold, YawBank};
pub use nav440_proto::TimeFaults;
use nav440_proto::{Packet, Parser, TimeBase};
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::Path;

/// Reads a capture file; a missing, unreadable or empty file is an [`Error::Input`].
pub fn read_capture(path: &Path) -> Result<Vec<u8>> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::Input(format!("cannot read {}: {}", path.display(), io_reason(&e))))?;
    if bytes.is_empty() {
        return Err(Error::Input(format!("{} is empty", path.display())));
    }
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
    /// Bytes that were not part of any valid frame.
    pub skipped_bytes: u64,
}

impl StreamStats {
    /// Total number of valid frames.
    pub fn total_frames(&self) -> u64 {
        self.frames.values().sum()
    }

    /// The `nav440 stats` JSON object.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "bytes": self.bytes,
            "frames": self.frames,
            "crc_errors": self.crc_errors,
            "skipped_bytes": self.skipped_bytes,
        })
    }
}

/// Runs the parser over `bytes` and counts frames by type.
pub fn stream_stats(bytes: &[u8]) -> StreamStats {
    let mut parser = Parser::new();
    let mut frames: BTreeMap<String, u64> = BTreeMap::new();
    parser.feed(bytes, |f| {
        *frames.entry(f.packet_type.name().to_string()).or_default() += 1
    });
    let s = parser.stats();
    StreamStats {
        bytes: s.bytes,
        frames,
        crc_errors: s.crc_errors,
        skipped_bytes: s.skipped_bytes,
    }
}

/// One timed yaw sample taken from a packet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time since the first yaw packet, microseconds (from timeITOW / GPSITOW through
    /// `nav440_proto::TimeBase`: wraps handled, strictly increasing).
    pub t_us: u64,
    /// Yaw as sent (wrapped), degrees.
    pub yaw_deg: f32,
    /// Body z rate as sent (the measured reference), deg/s.
    pub rate_deg_s: f32,
    /// First sample of a new time epoch (a confirmed backward jump of the time stamps, or the
    /// switch from GPSITOW to timeITOW): the bank re-initialises from it
    /// (`YawBank::new_epoch`).
    pub new_epoch: bool,
}

impl Sample {
    /// Time in seconds.
    pub fn t_s(&self) -> f64 {
        self.t_us as f64 * 1e-6
    }
}

/// Streaming sample extraction, the host twin of the firmware's front end: bytes -> parser ->
/// packets carrying yaw -> `nav440_proto::TimeBase` (time faults handled and counted) ->
/// [`Sample`]s. Feed it bytes in any chunking; the samples come out in stream order (a
/// suspicious time stamp is released one sample late, see `TimeBase`). Call
/// [`SampleReader::finish`] at the end of input.
#[derive(Debug, Default)]
pub struct SampleReader {
    parser: Parser,
    time: TimeBase<(f32, f32)>,
    frames: u64,
    yaw_packets: u64,
    samples: u64,
}

impl SampleReader {
    /// A reader at the start of a stream.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds bytes; `out` gets every sample released.
    pub fn feed(&mut self, bytes: &[u8], mut out: impl FnMut(Sample)) {
        let Self {
            parser,
            time,
            frames,
            yaw_packets,
            samples,
        } = self;
        parser.feed(bytes, |f| {
            *frames += 1;
            let Some(y) = Packet::decode(f).ok().and_then(|p| p.yaw_sample()) else {
                return;
            };
            *yaw_packets += 1;
            for t in time.update(y.time, (y.yaw_deg, y.yaw_rate_deg_s)) {
                *samples += 1;
                out(to_sample(t));
            }
        });
    }

    /// End of input: releases a held sample if the time rules allow it.
    pub fn finish(&mut self, mut out: impl FnMut(Sample)) {
        if let Some(t) = self.time.finish() {
            self.samples += 1;
            out(to_sample(t));
        }
    }

    /// Time-stamp faults so far.
    pub fn faults(&self) -> TimeFaults {
        *self.time.faults()
    }

    /// Valid (CRC-checked) frames so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Packets carrying yaw so far (before the time rules).
    pub fn yaw_packets(&self) -> u64 {
        self.yaw_packets
    }

    /// Samples released so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Parser statistics so far.
    pub fn parser_stats(&self) -> &nav440_proto::Stats {
        self.parser.stats()
    }

    /// The error for a finished stream that gave no sample ([`Error::NotNav440`]), or `Ok`.
    pub fn check_nonempty(&self) -> Result<()> {
        if self.frames == 0 {
            return Err(Error::NotNav440(
                "no NAV440 frame found (not a NAV440 capture?)".into(),
            ));
        }
        if self.samples == 0 {
            return Err(Error::NotNav440(format!(
                "{} NAV440 frames but none carries yaw with a usable time stamp (need A0/A1/A2/N0/N1/B1)",
                self.frames
            )));
        }
        Ok(())
    }
}

fn to_sample(t: nav440_proto::Timed<(f32, f32)>) -> Sample {
    Sample {
        t_us: t.t_us,
        yaw_deg: t.payload.0,
        rate_deg_s: t.payload.1,
        new_epoch: t.new_epoch,
    }
}

/// Extracts the timed yaw samples of every packet that carries yaw, in stream order.
/// A stream without any valid frame, or without any yaw packet, is an [`Error::NotNav440`].
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

/// Gaussian noise added to yaw before estimation (the paper's protocol).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Variance, deg^2.
    pub var: f64,
    /// Seed of the generator (xoshiro256++, one N(0, var) draw per sample in order).
    pub seed: u64,
}

/// The yaw of each sample plus noise (if any), degrees.
pub fn noisy_yaw(samples: &[Sample], noise: Option<Noise>) -> Result<Vec<f32>> {
    match noise {
        None => Ok(samples.iter().map(|s| s.yaw_deg).collect()),
        Some(n) => {
            let normal = Normal::new(0.0, n.var.max(0.0).sqrt())
                .map_err(|e| Error::Usage(format!("bad noise variance {}: {e}", n.var)))?;
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(n.seed);
            Ok(samples
                .iter()
                .map(|s| (f64::from(s.yaw_deg) + normal.sample(&mut rng)) as f32)
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
    /// Noise added to yaw.
    pub noise: Option<Noise>,
    /// Run the fixed-point bank (`YawBank<Fx>`) instead of f32.
    pub fixed: bool,
    /// Bank configuration with gains (from `--gains`), `None` = paper presets.
    pub config: Option<BankConfig>,
    /// Where the noise enters (per packet, or per observer step).
    pub noise_at: NoiseAt,
}

/// Where the added noise enters the estimators.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NoiseAt {
    /// One N(0, V) draw per packet, added to its yaw (the protocol as stated; default).
    #[default]
    Sample,
    /// The packets' unwrapped yaw is linearly interpolated onto the observer's step grid
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
            noise_at: NoiseAt::Sample,
        }
    }
}

impl EstimateOptions {
    /// The bank configuration these options describe (gains from `config` or the paper's
    /// presets, step and hold from the options), before adapting it to a capture.
    pub fn bank_config(&self) -> BankConfig {
        let mut cfg = self.config.unwrap_or_default();
        cfg.h = self.step_s;
        cfg.hold = self.hold;
        cfg
    }

    /// These options with the paper's laws as the base when no gains file is given
    /// (`BankConfig::PAPER`: the AVE's `deltahat` only grows), for the paper's experiment
    /// (`nav440 paper`, `nav440 tune`); `nav440 estimate` and the firmware run
    /// `BankConfig::default()` (leaky `deltahat`, docs/RELIABILITY.md).
    pub fn paper_law(&self) -> Self {
        Self {
            config: Some(self.config.unwrap_or(BankConfig::PAPER)),
            ..self.clone()
        }
    }

    /// [`EstimateOptions::bank_config`] with the nominal sample period set from the capture by
    /// `estimators::period`, the causal rule the firmware uses too: the upper median of the
    /// intervals between the first [`WARMUP_SAMPLES`] samples (0.01 s for a 100 Hz capture, i.e.
    /// `BankConfig::PAPER`'s value), whatever the rate does later; a capture shorter than the
    /// warm-up uses the intervals it has, a single sample keeps the configured period. The
    /// closed-form maps and the Kalman gains are computed for it.
    pub fn bank_config_for(&self, samples: &[Sample]) -> BankConfig {
        PeriodEstimator::from_times(samples.iter().map(|s| s.t_us)).apply(self.bank_config())
    }
}

/// One output row: the sample's time and reference, and the bank's output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Sample time, us since the first sample.
    pub t_us: u64,
    /// Measured yaw rate (packet z rate), deg/s.
    pub yaw_rate: f32,
    /// Unwrapped yaw, velocities and accelerations.
    pub out: BankOutput,
}

/// What a run of the bank gives: rows and the counts of samples it did not turn into rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// One row per accepted sample.
    pub rows: Vec<Row>,
    /// Samples the bank rejected (non-finite or out-of-range yaw).
    pub rejected: usize,
    /// Gaps longer than the gap rule (`BankConfig::max_gap_periods` nominal periods): the bank
    /// re-initialised there (`YawBank::reinit_count`).
    pub gaps: u32,
}

/// Runs the estimator bank over `samples`. A sample the bank rejects (non-finite or
/// out-of-range yaw) yields no row; the count of those is returned too.
pub fn estimate(samples: &[Sample], opts: &EstimateOptions) -> Result<(Vec<Row>, usize)> {
    estimate_report(samples, opts).map(|e| (e.rows, e.rejected))
}

/// [`estimate`] with the bank's gap count.
pub fn estimate_report(samples: &[Sample], opts: &EstimateOptions) -> Result<Estimate> {
    if opts.noise_at == NoiseAt::Step {
        return estimate_step_noise(samples, opts);
    }
    let cfg = opts.bank_config_for(samples);
    let yaw = noisy_yaw(samples, opts.noise)?;
    let bad =
        |e: estimators::ConfigError| Error::Usage(format!("bad estimator configuration: {e}"));
    if opts.fixed {
        let mut bank = YawBank::<Fx>::new(&cfg).map_err(bad)?;
        let mut e = run(samples, &yaw, |s, y| {
            if s.new_epoch {
                bank.new_epoch();
            }
            bank.update(s.t_us, y).ok()
        });
        e.gaps = bank.reinit_count();
        Ok(e)
    } else {
        let mut bank = YawBank::<f32>::new(&cfg).map_err(bad)?;
        let mut e = run(samples, &yaw, |s, y| {
            if s.new_epoch {
                bank.new_epoch();
            }
            bank.update(s.t_us, y).ok()
        });
        e.gaps = bank.reinit_count();
        Ok(e)
    }
}

fn run(
    samples: &[Sample],
    yaw: &[f32],
    mut update: impl FnMut(&Sample, f32) -> Option<BankOutput>,
) -> Estimate {
    let mut rows = Vec::with_capacity(samples.len());
    let mut rejected = 0;
    for (s, &y) in samples.iter().zip(yaw) {
        match update(s, y) {
            Some(out) => rows.push(Row {
                t_us: s.t_us,
                yaw_rate: s.rate_deg_s,
                out,
            }),
            None => rejected += 1,
        }
    }
    Estimate {
        rows,
        rejected,
        gaps: 0,
    }
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

/// The CSV header shared with the firmware.
pub const CSV_HEADER: &str = estimators::csv::HEADER;

/// Writes the header and one line per row, formatted by `estimators::csv` (identical text to
/// the firmware's for identical f32 values).
pub fn write_csv<W: std::io::Write + ?Sized>(rows: &[Row], w: &mut W) -> std::io::Result<()> {
    writeln!(w, "{CSV_HEADER}")?;
    let mut line = String::new();
    for r in rows {
        line.clear();
        estimators::csv::write_row(&mut line, r.t_us, r.yaw_rate, &r.out)
            .map_err(|_| std::io::Error::other("formatting error"))?;
        w.write_all(line.as_bytes())?;
        if !line.ends_with('\n') {
            w.write_all(b"\n")?;
        }
    }
    Ok(())
}

/// The whole `nav440 estimate` pipeline on a byte stream: parse, extract yaw samples, run the
/// bank, format the CSV (header included). Returns the CSV text and the number of samples the
/// bank rejected. This is what the firmware's equivalence test compares its output against.
pub fn estimate_csv(bytes: &[u8], opts: &EstimateOptions) -> Result<(String, usize)> {
    let samples = samples(bytes)?;
    let (rows, rejected) = estimate(&samples, opts)?;
    let mut out = Vec::new();
    write_csv(&rows, &mut out).map_err(|e| Error::Other(e.to_string()))?;
    Ok((String::from_utf8_lossy(&out).into_owned(), rejected))
}

/// Unwraps a wrapped angle sequence (deg) so consecutive values differ by at most 180 deg.
pub fn unwrap_deg(wrapped: &[f32]) -> Vec<f32> {
    let mut out = Vec::with_capacity(wrapped.len());
    let mut offset = 0.0f64;
    let mut prev: Option<f64> = None;
    for &w in wrapped {
        let w = f64::from(w);
        if let Some(p) = prev {
            offset -= 360.0 * ((w - p) / 360.0).round();
        }
        prev = Some(w);
        out.push((w + offset) as f32);
    }
    out
}

/// [`NoiseAt::Step`]: see there.
fn estimate_step_noise(samples: &[Sample], opts: &EstimateOptions) -> Result<Estimate> {
    let mut cfg = opts.bank_config_for(samples);
    // The packet-level gap rule (the bank itself sees one sample per step).
    let gap_us = (f64::from(cfg.max_gap_s()) * 1e6).round() as u64;
    // The bank sees one sample per step: closed-form maps and Kalman gains for that period.
    cfg.sample_period_s = opts.step_s;
    let h_us = (f64::from(opts.step_s) * 1e6).round().max(1.0) as u64;
    let yaw = unwrap_deg(&noisy_yaw(samples, None)?);
    let (var, seed) = opts.noise.map_or((0.0, 0), |n| (n.var, n.seed));
    let normal = Normal::new(0.0, var.max(0.0).sqrt())
        .map_err(|e| Error::Usage(format!("bad noise variance {var}: {e}")))?;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut noise = move || {
        if var > 0.0 {
            normal.sample(&mut rng)
        } else {
            0.0
        }
    };
    let bad =
        |e: estimators::ConfigError| Error::Usage(format!("bad estimator configuration: {e}"));
    let mut rows = Vec::with_capacity(samples.len());
    let mut rejected = 0;
    let mut feed = |update: &mut dyn FnMut(u64, f32, bool) -> Option<BankOutput>| {
        for (k, (s, &y)) in samples.iter().zip(&yaw).enumerate() {
            let prev = k
                .checked_sub(1)
                .and_then(|i| Some((samples.get(i)?, *yaw.get(i)?)));
            let out = match prev {
                None => update(s.t_us, (f64::from(y) + noise()) as f32, false),
                // A new epoch, or a gap the bank re-initialises on: no interpolation across it.
                Some((ps, _)) if s.new_epoch || s.t_us - ps.t_us > gap_us => {
                    update(s.t_us, (f64::from(y) + noise()) as f32, true)
                }
                Some((ps, py)) if s.t_us > ps.t_us => {
                    let n = ((s.t_us - ps.t_us + h_us / 2) / h_us).max(1);
                    let mut last = None;
                    for j in 1..=n {
                        let t = if j == n { s.t_us } else { ps.t_us + j * h_us };
                        let yi =
                            f64::from(py) + (f64::from(y) - f64::from(py)) * j as f64 / n as f64;
                        last = update(t, (yi + noise()) as f32, false);
                    }
                    last
                }
                Some(_) => None,
            };
            match out {
                Some(out) => rows.push(Row {
                    t_us: s.t_us,
                    yaw_rate: s.rate_deg_s,
                    out,
                }),
                None => rejected += 1,
            }
        }
    };
    let mut restarts = 0u32;
    if opts.fixed {
        let mut bank = YawBank::<Fx>::new(&cfg).map_err(bad)?;
        feed(&mut |t, y, restart| {
            if restart {
                restarts += 1;
                bank.new_epoch();
            }
            bank.update(t, y).ok()
        });
    } else {
        let mut bank = YawBank::<f32>::new(&cfg).map_err(bad)?;
        feed(&mut |t, y, restart| {
            if restart {
                restarts += 1;
                bank.new_epoch();
            }
            bank.update(t, y).ok()
        });
    }
    let epochs = samples.iter().filter(|s| s.new_epoch).count() as u32;
    Ok(Estimate {
        rows,
        rejected,
        gaps: restarts.saturating_sub(epochs),
    })
}
