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
