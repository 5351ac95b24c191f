//! The timed attitude samples of a capture (what `paper`, `tune` and `plot` keep), and angle unwrapping.

use super::*;

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
pub(crate) fn check_front(front: &Frontend) -> Result<()> {
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
/// samples', not the capture's (at most [`MAX_SAMPLES`]). Errors name the capture.
pub fn read_samples(path: &Path) -> Result<Vec<Sample>> {
    read_samples_and_faults(path).map(|(s, _)| s)
}

/// [`read_samples`] and the time-stamp faults met on the way.
pub fn read_samples_and_faults(path: &Path) -> Result<(Vec<Sample>, TimeFaults)> {
    read_samples_until(path, None, "cut the capture into parts").map(|c| (c.samples, c.faults))
}

/// The most samples a command keeps in memory: [`MAX_CAPTURE_BYTES`] (1 GiB) of [`Sample`]s
/// (40 bytes each: 26,843,545, 74.6 h at 100 Hz).
pub const MAX_SAMPLES: usize = MAX_CAPTURE_BYTES as usize / std::mem::size_of::<Sample>();

/// The samples of a capture that a command keeps ([`read_samples_until`]), with what the
/// reading met over the whole capture.
#[derive(Clone, Debug, Default)]
pub struct CaptureSamples {
    /// The samples kept: a prefix of the capture's.
    pub samples: Vec<Sample>,
    /// Samples the whole capture gave (kept or not).
    pub total: u64,
    /// Time of the capture's last sample, us since the first.
    pub last_t_us: u64,
    /// Time-stamp faults over the whole capture.
    pub faults: TimeFaults,
    /// Samples dropped for a BIT failure.
    pub bit: BitCounts,
    /// Bytes at the end of the input that did not complete a frame.
    pub end_dropped_bytes: u64,
}

impl CaptureSamples {
    /// The warnings `nav440 estimate` prints about its input, the same lines by the same code
    /// ([`StreamReport::warnings`]): BIT failures, samples the bank rejected, time faults and
    /// gaps, the end of input. `summary` is a run of the bank over the samples (its rejections
    /// and gaps); samples near gimbal lock are left to each command's own note.
    pub fn warnings(&self, summary: &EstimationSummary) -> impl Iterator<Item = String> {
        StreamReport {
            summary: EstimationSummary {
                near_lock: 0,
                lock_passes: 0,
                ..*summary
            },
            faults: self.faults,
            bit: self.bit,
            schedule_misfit_us: None,
            end_dropped_bytes: self.end_dropped_bytes,
        }
        .warnings()
    }
}

/// Reads the samples of a capture in chunks and keeps the prefix a causal computation up to
/// `until_us` needs: every sample up to the last at or before `until_us`, then
/// [`WARMUP_SAMPLES`] more (so an epoch that starts by then has its whole period warm-up), and
/// at least the first [`WARMUP_SAMPLES`]; every sample with `None`. The rest of the capture
/// is read for its counts (faults, total, duration) and not kept. Keeping more than
/// [`MAX_SAMPLES`] is an [`Error::Input`] (exit 3) with `hint`, found while reading. A stream
/// without a sample is an [`Error::NotNav440`]; errors name the capture.
pub fn read_samples_until(
    path: &Path,
    until_us: Option<u64>,
    hint: &str,
) -> Result<CaptureSamples> {
    let mut r = open_capture(path)?;
    let name = r.name().to_string();
    let mut reader = SampleReader::new();
    let mut out = CaptureSamples::default();
    let mut past = 0usize;
    let over = std::cell::Cell::new(false);
    let mut keep = |s: Sample, out: &mut CaptureSamples| {
        out.total += 1;
        out.last_t_us = s.t_us;
        let beyond = until_us.is_some_and(|u| s.t_us > u);
        if beyond || past > 0 {
            if past >= WARMUP_SAMPLES && out.samples.len() >= WARMUP_SAMPLES {
                return;
            }
            past += 1;
        }
        if out.samples.len() >= MAX_SAMPLES {
            over.set(true);
            return;
        }
        out.samples.push(s);
    };
    r.for_each_chunk(|c| {
        reader.feed(c, |s| keep(s, &mut out));
        Ok(!over.get())
    })?;
    if !over.get() {
        reader.finish(|s| keep(s, &mut out));
    }
    if over.get() {
        return Err(too_large(
            &name,
            &format!(
                "its samples ({} bytes each) take",
                std::mem::size_of::<Sample>()
            ),
            hint,
        ));
    }
    reader.check_nonempty().map_err(|e| match e {
        Error::NotNav440(m) => Error::NotNav440(format!("{name}: {m}")),
        other => other,
    })?;
    out.faults = reader.faults();
    out.bit = reader.bit();
    out.end_dropped_bytes = reader.front.counters().end_dropped_bytes;
    Ok(out)
}

/// The summary of a run of the bank `opts` over `samples` (rejections, gaps), no row kept.
pub fn summary_of(samples: &[Sample], opts: &EstimateOptions) -> Result<EstimationSummary> {
    let mut est = Estimation::new(opts)?;
    let mut drop_row = |_: Row| Ok(());
    for &s in samples {
        est.push(s, &mut drop_row)?;
    }
    est.finish(&mut drop_row)
}

/// Unwraps a wrapped angle sequence (deg) so consecutive values differ by at most 180 deg.
pub fn unwrap_deg(wrapped: &[f32]) -> Vec<f32> {
    let mut u = DegUnwrapper::default();
    wrapped.iter().map(|&w| u.push(w)).collect()
}

/// [`unwrap_deg`] one angle at a time (f64 offset in whole turns, deg).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct DegUnwrapper {
    offset: f64,
    prev: Option<f64>,
}

impl DegUnwrapper {
    /// The next wrapped angle (deg), unwrapped (deg).
    pub(crate) fn push(&mut self, wrapped: f32) -> f32 {
        let w = f64::from(wrapped);
        if let Some(p) = self.prev {
            self.offset -= 360.0 * ((w - p) / 360.0).round();
        }
        self.prev = Some(w);
        (w + self.offset) as f32
    }
}
