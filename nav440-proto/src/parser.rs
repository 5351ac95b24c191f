//! Streaming frame parser with one-byte resynchronisation.

use core::marker::PhantomData;
use core::ops::ControlFlow;

use crate::crc16::{Crc16Table, DefaultCrcTable};
use crate::types::PacketType;
use crate::{MAX_FRAME, PREAMBLE_BYTE};

/// One CRC-checked frame: its type and its payload (length byte excluded).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame<'a> {
    /// The two type bytes.
    pub packet_type: PacketType,
    /// The payload, 0..=255 bytes.
    pub payload: &'a [u8],
}

impl Frame<'_> {
    /// Length of the whole frame on the wire in bytes (preamble, type, length, payload, CRC).
    pub const fn wire_len(&self) -> usize {
        self.payload.len() + crate::FRAME_OVERHEAD
    }
}

/// Parser counters. Every byte fed is eventually counted exactly once, either in a frame
/// (`frame_bytes`) or as `skipped_bytes`; bytes of an incomplete candidate frame at the end of
/// the input so far are pending (`bytes - frame_bytes - skipped_bytes`, at most 261).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stats {
    /// Bytes fed in total.
    pub bytes: u64,
    /// CRC-checked frames emitted.
    pub frames: u64,
    /// Bytes belonging to emitted frames (preamble and CRC included).
    pub frame_bytes: u64,
    /// Candidate frames (preamble + plausible header, complete) whose CRC did not match.
    pub crc_errors: u64,
    /// Candidates rejected from their header alone (type bytes that no packet uses).
    pub header_errors: u64,
    /// Bytes dropped while searching for a frame (garbage, failed candidates' first bytes).
    pub skipped_bytes: u64,
    /// Frames per known type, indexed like [`PacketType::KNOWN`] (NAK is index 12).
    pub per_type: [u64; 22],
    /// Frames of any other type (e.g. OpenIMU lower-case packets).
    pub other_types: u64,
}

impl Stats {
    const fn new() -> Self {
        Self {
            bytes: 0,
            frames: 0,
            frame_bytes: 0,
            crc_errors: 0,
            header_errors: 0,
            skipped_bytes: 0,
            per_type: [0; 22],
            other_types: 0,
        }
    }

    /// Frames counted for type `t` (known types individually, others together).
    pub fn count(&self, t: PacketType) -> u64 {
        match t.known_index() {
            Some(i) => self.per_type.get(i).copied().unwrap_or(0),
            None => self.other_types,
        }
    }

    /// NAK frames received.
    pub fn naks(&self) -> u64 {
        self.count(PacketType::NAK)
    }

    /// Bytes held in the parser waiting for the rest of a candidate frame.
    pub fn pending_bytes(&self) -> u64 {
        self.bytes
            .saturating_sub(self.frame_bytes)
            .saturating_sub(self.skipped_bytes)
    }

    #[inline]
    fn count_frame(&mut self, t: PacketType, wire_len: usize) {
        self.frames += 1;
        self.frame_bytes += wire_len as u64;
        match t.known_index().and_then(|i| self.per_type.get_mut(i)) {
            Some(c) => *c += 1,
            None => self.other_types += 1,
        }
    }
}

/// Streaming NAV440 frame parser: feed bytes in any chunking, get CRC-checked [`Frame`]s.
///
/// * Fixed buffer of [`MAX_FRAME`] bytes, no heap, never panics.
/// * Complete frames inside the bytes of one [`feed`](Self::feed) call are checked in place
///   (zero copy); only an incomplete frame at the end of a call is copied into the buffer.
/// * Resynchronisation: a candidate starts at `55 55`. If its type bytes are impossible (see
///   below) or its CRC fails, exactly ONE byte is dropped and the search restarts at the next
///   byte, so a valid frame that begins inside the span of a corrupted one is still found,
///   including frames that were already buffered behind the bad candidate.
/// * Plausible type bytes: both printable ASCII (0x21..=0x7E) with the first one not `U`
///   (0x55, which would make the preamble ambiguous), or NAK `15 15`. Anything else is an
///   impossible header and is rejected without waiting for its length.
///
/// `C` picks the CRC table variant (see [module `crc16`](mod@crate::crc16)); `Parser::new()` uses
/// [`DefaultCrcTable`].
pub struct Parser<C: Crc16Table = DefaultCrcTable> {
    buf: [u8; MAX_FRAME],
    len: usize,
    stats: Stats,
    _crc: PhantomData<C>,
}

impl Parser<DefaultCrcTable> {
    /// A parser with the [`DefaultCrcTable`], empty buffer and zeroed counters.
    pub const fn new() -> Self {
        Self::with_crc_table()
    }
}

impl Default for Parser<DefaultCrcTable> {
    fn default() -> Self {
        Self::new()
    }
}

impl<C: Crc16Table> core::fmt::Debug for Parser<C> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Parser")
            .field("pending", &self.len)
            .field("stats", &self.stats)
            .finish()
    }
}

#[cfg(feature = "defmt")]
impl<C: Crc16Table> defmt::Format for Parser<C> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "Parser {{ pending: {}, stats: {} }}",
            self.len,
            self.stats
        )
    }
}

/// True when `t0 t1` can start a frame (see [`Parser`]).
#[inline(always)]
const fn plausible_type(t0: u8, t1: u8) -> bool {
    (t0 >= 0x21 && t0 <= 0x7E && t0 != PREAMBLE_BYTE && t1 >= 0x21 && t1 <= 0x7E)
        || (t0 == 0x15 && t1 == 0x15)
}

/// First index `k` with `d[k] == 0x55` and (`d[k+1] == 0x55` or `k` is the last index).
#[inline]
fn find_preamble(d: &[u8]) -> Option<usize> {
    let mut i = 0;
    while let Some(rest) = d.get(i..) {
        let k = i + rest.iter().position(|&b| b == PREAMBLE_BYTE)?;
        match d.get(k + 1) {
            None | Some(&PREAMBLE_BYTE) => return Some(k),
            Some(_) => i = k + 2,
        }
    }
    None
}

/// Scans `data`, emits every valid frame, returns the index where an incomplete candidate
/// begins (`data.len()` when nothing is left) and whether `on_frame` asked to stop (then the
/// index is the first byte after that frame). Bytes before that index are counted.
#[inline(always)]
fn scan<C: Crc16Table>(
    data: &[u8],
    stats: &mut Stats,
    on_frame: &mut impl FnMut(Frame<'_>) -> ControlFlow<()>,
) -> (usize, bool) {
    let mut i = 0usize;
    loop {
        let Some(rest) = data.get(i..) else {
            return (data.len(), false);
        };
        // Fast path: back-to-back frames start right here.
        let start = match rest {
            [PREAMBLE_BYTE, PREAMBLE_BYTE, ..] => 0,
            _ => match find_preamble(rest) {
                Some(k) => k,
                None => {
                    stats.skipped_bytes += rest.len() as u64;
                    return (data.len(), false);
                }
            },
        };
        stats.skipped_bytes += start as u64;
        i += start;
        let Some(cand) = data.get(i..) else {
            return (data.len(), false);
        };
        match cand {
            [_, _, t0, t1, n, ..] => {
                if !plausible_type(*t0, *t1) {
                    stats.header_errors += 1;
                    stats.skipped_bytes += 1;
                    i += 1;
                    continue;
                }
                let n = *n as usize;
                let end = n + 5;
                let (Some(msg), Some(&[hi, lo])) = (cand.get(2..end), cand.get(end..end + 2))
                else {
                    return (i, false); // incomplete
                };
                let got = u16::from_be_bytes([hi, lo]);
                if C::message_crc(msg) == got {
                    let packet_type = PacketType([*t0, *t1]);
                    let payload = msg.get(3..).unwrap_or(&[]);
                    stats.count_frame(packet_type, end + 2);
                    let flow = on_frame(Frame {
                        packet_type,
                        payload,
                    });
                    i += end + 2;
                    if flow.is_break() {
                        return (i, true);
                    }
                } else {
                    stats.crc_errors += 1;
                    stats.skipped_bytes += 1;
                    i += 1;
                }
            }
            // Fewer than 5 bytes: reject early if the type bytes seen so far are impossible.
            [_, _, t0, t1] if !plausible_type(*t0, *t1) => {
                stats.header_errors += 1;
                stats.skipped_bytes += 1;
                i += 1;
            }
            [_, _, t0] if !plausible_type(*t0, b'0') && *t0 != 0x15 => {
                stats.header_errors += 1;
                stats.skipped_bytes += 1;
                i += 1;
            }
            _ => return (i, false),
        }
    }
}

impl<C: Crc16Table> Parser<C> {
    /// A parser using the CRC table variant `C` (e.g. `Parser::<crc::Table<1>>::with_crc_table()`).
    pub const fn with_crc_table() -> Self {
        Self {
            buf: [0; MAX_FRAME],
            len: 0,
            stats: Stats::new(),
            _crc: PhantomData,
        }
    }

    /// The counters.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Resets the counters (the buffered partial frame is kept).
    pub fn reset_stats(&mut self) {
        let pending = self.len as u64;
        self.stats = Stats::new();
        // Keep `bytes = frame_bytes + skipped_bytes + pending` true.
        self.stats.bytes = pending;
    }

    /// Drops a buffered partial frame (counted as skipped), e.g. after a baud change.
    pub fn clear(&mut self) {
        self.stats.skipped_bytes += self.len as u64;
        self.len = 0;
    }

    /// Number of bytes buffered for an incomplete candidate frame (0..[`MAX_FRAME`]).
    pub fn pending(&self) -> usize {
        self.len
    }

    /// The raw bytes buffered for an incomplete candidate frame, in stream order: after
    /// [`feed_until`](Self::feed_until) stopped, every byte fed after the stopping frame that
    /// the returned count includes (feeding them to a fresh parser continues the stream).
    pub fn pending_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    /// Ends a finite input: resolves the bytes still buffered ([`pending_bytes`](Self::pending_bytes)).
    /// A buffered candidate can no longer complete, so it is rejected the way a failed CRC is
    /// (its first byte dropped) and the bytes behind it are scanned again; `on_frame` gets
    /// every complete frame found among them, in stream order. Returns the number of bytes
    /// that did not complete a frame (0..[`MAX_FRAME`]), now counted as skipped; the buffer is
    /// empty afterwards and the parser can take a new stream.
    pub fn finish(&mut self, mut on_frame: impl FnMut(Frame<'_>)) -> usize {
        let skipped_before = self.stats.skipped_bytes;
        let mut on_frame = |f: Frame<'_>| {
            on_frame(f);
            ControlFlow::Continue(())
        };
        while self.len > 0 {
            let (consumed, _) = scan::<C>(
                self.buf.get(..self.len).unwrap_or(&[]),
                &mut self.stats,
                &mut on_frame,
            );
            let consumed = consumed.min(self.len);
            shift_out(&mut self.buf, consumed, self.len);
            self.len -= consumed;
            if self.len > 0 {
                // An incomplete candidate at the end: drop its first byte, rescan the rest.
                self.stats.skipped_bytes += 1;
                shift_out(&mut self.buf, 1, self.len);
                self.len -= 1;
            }
        }
        (self.stats.skipped_bytes - skipped_before) as usize
    }

    /// Feeds any number of bytes (any chunking); calls `on_frame` for every CRC-checked frame,
    /// in stream order. Frames borrow either `bytes` or the parser's buffer.
    #[inline]
    pub fn feed(&mut self, bytes: &[u8], mut on_frame: impl FnMut(Frame<'_>)) {
        self.feed_until(bytes, |f| {
            on_frame(f);
            ControlFlow::Continue(())
        });
    }

    /// Like [`feed`](Self::feed), but stops right after the frame for which `on_frame` returns
    /// `ControlFlow::Break`: no later frame is emitted by this call. Returns how many bytes of
    /// `bytes` were taken (`bytes.len()` unless it stopped); the bytes taken after the stopping
    /// frame stay buffered ([`pending_bytes`](Self::pending_bytes)) and are scanned by the next
    /// call, so feeding the rest of `bytes` next continues the stream exactly.
    pub fn feed_until(
        &mut self,
        bytes: &[u8],
        mut on_frame: impl FnMut(Frame<'_>) -> ControlFlow<()>,
    ) -> usize {
        self.feed_until_dyn(bytes, &mut on_frame)
    }

    /// [`feed_until`](Self::feed_until) for any callback: one copy of the code per CRC
    /// implementation, not one per caller's closure.
    fn feed_until_dyn(
        &mut self,
        bytes: &[u8],
        mut on_frame: &mut dyn FnMut(Frame<'_>) -> ControlFlow<()>,
    ) -> usize {
        let mut input = bytes;
        let taken = |input: &[u8]| bytes.len() - input.len();
        // 1. Complete (or reject) the buffered candidate using as few input bytes as needed.
        while self.len > 0 {
            // A candidate's length is known from its fifth byte. Bytes left behind a stop
            // (`feed_until`) need not start a candidate: they are scanned at once.
            let need = match (self.buf.get(..2), self.buf.get(4)) {
                (Some([PREAMBLE_BYTE, PREAMBLE_BYTE]), Some(&n)) if self.len >= 5 => {
                    n as usize + crate::FRAME_OVERHEAD
                }
                _ => 5,
            };
            let take = need.saturating_sub(self.len).min(input.len());
            if take == 0 && self.len < need {
                // No input left for an incomplete candidate. (Complete frames left behind a
                // stop are scanned even by an empty call.)
                self.stats.bytes += bytes.len() as u64;
                return bytes.len();
            }
            let (head, tail) = input.split_at(take);
            if let Some(dst) = self.buf.get_mut(self.len..self.len + take) {
                crate::copy_bytes(dst, head);
            } else {
                // Unreachable: need <= MAX_FRAME. Count as skipped rather than panic.
                self.stats.skipped_bytes += (self.len + take) as u64;
                self.len = 0;
                input = tail;
                continue;
            }
            self.len += take;
            input = tail;
            if self.len >= 5 && self.len < need {
                // Header already checked when the first 5 bytes were in; wait for the rest.
                self.stats.bytes += bytes.len() as u64;
                return bytes.len();
            }
            let (consumed, stop) = scan::<C>(
                self.buf.get(..self.len).unwrap_or(&[]),
                &mut self.stats,
                &mut on_frame,
            );
            shift_out(&mut self.buf, consumed.min(self.len), self.len);
            self.len -= consumed.min(self.len);
            if stop {
                let n = taken(input);
                self.stats.bytes += n as u64;
                return n;
            }
        }
        // 2. Zero-copy scan of the rest of the input.
        let (consumed, stop) = scan::<C>(input, &mut self.stats, &mut on_frame);
        let n = if stop {
            taken(input) + consumed.min(input.len())
        } else {
            let tail = input.get(consumed..).unwrap_or(&[]);
            match self.buf.get_mut(..tail.len()) {
                Some(dst) => {
                    crate::copy_bytes(dst, tail);
                    self.len = tail.len();
                }
                None => {
                    // Unreachable: an incomplete candidate is shorter than MAX_FRAME.
                    self.stats.skipped_bytes += tail.len() as u64;
                    self.len = 0;
                }
            }
            bytes.len()
        };
        self.stats.bytes += n as u64;
        n
    }
}

/// Moves `buf[n..len]` to the front of `buf` (drops the first `n` of `len` buffered bytes).
/// A forward byte loop: the move always goes down, so no `memmove` is needed for it.
fn shift_out(buf: &mut [u8], n: usize, len: usize) {
    let len = len.min(buf.len());
    for i in n..len {
        if let Some(&b) = buf.get(i) {
            if let Some(d) = buf.get_mut(i - n) {
                *d = b;
            }
        }
    }
}
