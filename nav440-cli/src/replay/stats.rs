//! Parser statistics of a byte stream (`nav440 stats`).

use super::*;

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
    /// Bytes at the end of the stream that did not complete a frame once every complete frame
    /// among them was found (a truncated final frame, a false header with nothing valid behind
    /// it, or a lone `55` that might start one): neither in a frame nor skipped.
    /// `bytes = frame bytes + skipped_bytes + pending_bytes`.
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
    /// Bytes [`StatsCounter::finish`] found not to complete a frame (reported as pending).
    end_dropped: u64,
}

/// Counts frame `f` by type name, and the BIT word of an attitude packet.
fn count_frame(
    f: nav440_proto::Frame<'_>,
    frames: &mut BTreeMap<String, u64>,
    bit: &mut BitCounts,
) {
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
        let (frames, bit) = (&mut self.frames, &mut self.bit);
        self.parser.feed(bytes, |f| count_frame(f, frames, bit));
    }

    /// Ends the stream: counts the complete frames the parser still holds (behind a false
    /// header at the end of the input); the bytes that did not complete a frame stay
    /// `pending_bytes`.
    pub fn finish(&mut self) {
        let (frames, bit) = (&mut self.frames, &mut self.bit);
        let dropped = self.parser.finish(|f| count_frame(f, frames, bit));
        self.end_dropped = dropped as u64;
    }

    /// The statistics of everything fed so far.
    pub fn stats(&self) -> StreamStats {
        let s = self.parser.stats();
        StreamStats {
            bytes: s.bytes,
            frames: self.frames.clone(),
            crc_errors: s.crc_errors,
            skipped_bytes: s.skipped_bytes - self.end_dropped,
            pending_bytes: s.pending_bytes() + self.end_dropped,
            bit: self.bit,
        }
    }
}

/// Runs the parser over `bytes` and counts frames by type.
pub fn stream_stats(bytes: &[u8]) -> StreamStats {
    let mut c = StatsCounter::new();
    c.push(bytes);
    c.finish();
    c.stats()
}
