//! The defmt transport of every board: the firmware's `#[defmt::global_logger]`.
//!
//! Each defmt frame (raw encoding: no rzCOBS; semihosting and RTT are lossless) is assembled in
//! a frame buffer and handed on whole, to
//!
//! * the RTT up-channel `defmt` when the board uses RTT ([`crate::board::RTT`]), which probe-rs
//!   reads and decodes with the ELF's defmt table; the channel does not block: when the probe
//!   reads too slowly a frame is dropped whole (never cut), and counted ([`rtt_dropped`]);
//! * the semihosting stdout when a semihosting host is there ([`crate::board::host_present`]:
//!   QEMU), in one call per frame, which `cargo xtask` decodes.
//!
//! A board image with RTT therefore prints through both under QEMU and through RTT alone on a
//! chip: CI runs the very ELF that is flashed. [`init`] sets the RTT channel up (call it first
//! in `main`; frames before it only reach the semihosting host).
//!
//! [`in_place`] lends a word-aligned payload buffer that sits right after a few bytes of room:
//! when a message's last argument is that payload (`{=[u8]}`), the logger writes the frame's
//! first bytes (the message's index and the slice's length) into the room before it and hands
//! the frame on from there, without copying the payload (the row message of
//! [`crate::out::row`]).

use core::cell::UnsafeCell;
use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Bytes of the frame buffer: the largest frame the firmware copies and sends in one piece; a
/// longer frame is handed on in pieces of this size (the board's).
const FRAME_BUFFER: usize = crate::board::LOG_FRAME_BYTES;

/// Words of the [`in_place`] payload buffer: the firmware's longest row message
/// ([`crate::out::ROW_WORDS`]).
pub const PAYLOAD_WORDS: usize = crate::out::ROW_WORDS;

/// Bytes of room before the [`in_place`] payload: each frame starts there, and a frame whose
/// first `HEAD` bytes (the row message's index, 2 bytes, and its slice's length, 4) are followed
/// by the lent payload is handed on from there in one piece.
const HEAD: usize = 6;

/// The [`in_place`] buffer: the room for a frame's first bytes, then the payload (word-aligned).
#[repr(C)]
struct Placed {
    pad: [u8; 4 - HEAD % 4],
    head: [u8; HEAD],
    payload: [u32; PAYLOAD_WORDS],
}

struct PlacedCell(UnsafeCell<Placed>);

// SAFETY: the payload is only lent by `in_place` while `PLACED_BUSY` is set (one lender at a
// time), and the head is only written and read by the logger, inside its critical section.
unsafe impl Sync for PlacedCell {}

static PLACED: PlacedCell = PlacedCell(UnsafeCell::new(Placed {
    pad: [0; 4 - HEAD % 4],
    head: [0; HEAD],
    payload: [0; PAYLOAD_WORDS],
}));

/// The [`in_place`] payload is lent.
static PLACED_BUSY: AtomicBool = AtomicBool::new(false);

/// The first byte of the head room (the payload follows its `HEAD` bytes).
fn head_ptr() -> *mut u8 {
    // SAFETY: a field of the static, no reference made.
    unsafe { addr_of_mut!((*PLACED.0.get()).head).cast::<u8>() }
}

/// The first byte of the [`in_place`] payload.
fn placed_payload() -> *const u8 {
    // SAFETY: a field of the static, no reference made.
    unsafe { addr_of_mut!((*PLACED.0.get()).payload).cast::<u8>() }
}

// The payload follows the head room.
const _: () =
    assert!(core::mem::offset_of!(Placed, payload) == core::mem::offset_of!(Placed, head) + HEAD);

/// Lends the payload buffer to `fill`, which returns the payload's length in bytes, then gives
/// those bytes to `send`. When `send` logs them as a defmt message's last argument
/// (`{=[u8]}`), the logger hands the frame on from this buffer: the payload is not copied.
/// Re-entered (an interrupt sending while the main thread fills the buffer), the payload goes
/// through a buffer on the stack and is copied as any argument.
pub fn in_place(fill: impl FnOnce(&mut [u32; PAYLOAD_WORDS]) -> usize, send: impl FnOnce(&[u8])) {
    let mut local = core::mem::MaybeUninit::<[u32; PAYLOAD_WORDS]>::uninit();
    // Load and store, not a swap (thumbv6m has none): an interrupt between them runs to its
    // end, clearing the flag, before this thread goes on.
    let busy = PLACED_BUSY.load(Ordering::Relaxed);
    let words: &mut [u32; PAYLOAD_WORDS] = if busy {
        local.write([0; PAYLOAD_WORDS])
    } else {
        PLACED_BUSY.store(true, Ordering::Relaxed);
        // SAFETY: the flag was clear: no other reference to the payload exists until it is
        // cleared below; the logger touches the head only.
        unsafe { &mut *addr_of_mut!((*PLACED.0.get()).payload) }
    };
    let n = fill(words).min(4 * PAYLOAD_WORDS);
    // SAFETY: `n` bytes of the words, which are initialised and outlive `bytes`.
    let bytes = unsafe { core::slice::from_raw_parts(words.as_ptr().cast::<u8>(), n) };
    send(bytes);
    if !busy {
        PLACED_BUSY.store(false, Ordering::Relaxed);
    }
}

/// Bytes of the RTT up-channel's buffer: the board's.
#[cfg(feature = "rtt")]
const RTT_BUFFER: usize = crate::board::RTT_BUFFER;

#[defmt::global_logger]
struct Logger;

/// Where the encoded bytes go: the frame buffer and the RTT channel.
struct Sink {
    frame: [u8; FRAME_BUFFER],
    /// Bytes in `frame`.
    len: usize,
    /// Bytes in the head room (the frame so far while `frame` is empty).
    head: usize,
    /// Bytes of the lent [`in_place`] payload after a full head room (the frame is the head
    /// room and the payload), or `None`.
    placed: Option<usize>,
    /// The semihosting stdout, opened on the first frame that goes there.
    stdout: Option<cortex_m_semihosting::hio::HostStream>,
    #[cfg(feature = "rtt")]
    rtt: Option<rtt_target::UpChannel>,
}

/// The logger's state, touched only between `acquire` and `release` (inside one critical
/// section, with `TAKEN` set), and by [`init`] inside a critical section.
struct State {
    restore: critical_section::RestoreState,
    encoder: defmt::Encoder,
    sink: Sink,
}

struct Shared(UnsafeCell<State>);

// SAFETY: the state is only accessed by the logger between `acquire` and `release`, which run
// inside a critical section and refuse re-entry (`TAKEN`), and by `init` inside a critical
// section, so never from two contexts at once.
unsafe impl Sync for Shared {}

static STATE: Shared = Shared(UnsafeCell::new(State {
    restore: critical_section::RestoreState::invalid(),
    encoder: defmt::Encoder::new(),
    sink: Sink {
        frame: [0; FRAME_BUFFER],
        len: 0,
        head: 0,
        placed: None,
        stdout: None,
        #[cfg(feature = "rtt")]
        rtt: None,
    },
}));

/// The logger is held (between `acquire` and `release`).
static TAKEN: AtomicBool = AtomicBool::new(false);
/// Frames (or frame pieces) the RTT channel had no room for.
static RTT_DROPPED: AtomicU32 = AtomicU32::new(0);

/// Frames (or pieces of a frame longer than the frame buffer) dropped because the RTT
/// channel was full (the probe reads too slowly, or no probe is attached); 0 without RTT.
pub fn rtt_dropped() -> u32 {
    RTT_DROPPED.load(Ordering::Relaxed)
}

/// Sets up the RTT up-channel `defmt` (boards with [`crate::board::RTT`]; nothing otherwise).
/// Call once, first thing in `main`.
pub fn init() {
    #[cfg(feature = "rtt")]
    {
        let channels = rtt_target::rtt_init! {
            up: {
                0: { size: RTT_BUFFER, mode: rtt_target::ChannelMode::NoBlockSkip, name: "defmt" }
            }
        };
        critical_section::with(|_| {
            if TAKEN.load(Ordering::Relaxed) {
                return;
            }
            // SAFETY: inside a critical section and with the logger not held (`TAKEN` is only
            // set inside one), so nothing else accesses the state.
            let state = unsafe { &mut *STATE.0.get() };
            state.sink.rtt = Some(channels.up.0);
        });
    }
}

impl Sink {
    /// Bytes of the frame held from the head room on: the head room's and the placed
    /// payload's.
    fn held(&self) -> usize {
        self.head + self.placed.unwrap_or(0)
    }

    /// Hands the frame on to the transports and empties the buffers.
    fn hand_on(&mut self) {
        let frame = if self.len != 0 {
            self.frame.get(..self.len).unwrap_or(&[])
        } else {
            // SAFETY: the head room's `self.head` bytes, then (when placed, `self.head == HEAD`)
            // the payload lent by `in_place`, still lent: the logger is held inside its `send`.
            unsafe { core::slice::from_raw_parts(head_ptr(), self.held()) }
        };
        if frame.is_empty() {
            return;
        }
        #[cfg(feature = "rtt")]
        if let Some(ch) = self.rtt.as_mut() {
            // NoBlockSkip writes all or nothing.
            if ch.write(frame) == 0 {
                RTT_DROPPED.store(
                    RTT_DROPPED.load(Ordering::Relaxed).wrapping_add(1),
                    Ordering::Relaxed,
                );
            }
        }
        if crate::board::host_present() {
            if self.stdout.is_none() {
                self.stdout = cortex_m_semihosting::hio::hstdout().ok();
            }
            if let Some(out) = self.stdout.as_mut() {
                // Nothing useful can be done if the host rejects output.
                let _ = out.write_all(frame);
            }
        }
        self.len = 0;
        self.head = 0;
        self.placed = None;
    }

    /// Appends encoded bytes to the frame: its first [`HEAD`] bytes into the head room, the
    /// [`in_place`] payload right after a full head room (not copied), anything else into the
    /// frame buffer (after what the head room holds), handing full buffers on.
    fn put(&mut self, bytes: &[u8]) {
        if self.len == 0 {
            if self.placed.is_none() {
                let at = self.head;
                if at == HEAD && bytes.as_ptr() == placed_payload() {
                    self.placed = Some(bytes.len());
                    return;
                }
                if at + bytes.len() <= HEAD {
                    // SAFETY: the head room is only touched by the logger (held).
                    let head = unsafe { &mut *addr_of_mut!((*PLACED.0.get()).head) };
                    // Short copies of a known length: no call to `memcpy`.
                    let room = head.get_mut(at..).unwrap_or(&mut []);
                    match (bytes, room) {
                        (&[a, b], [c, d, ..]) => (*c, *d) = (a, b),
                        (&[a, b, c, d], [e, f, g, h, ..]) => (*e, *f, *g, *h) = (a, b, c, d),
                        (bytes, room) => crate::copy_bytes(room, bytes),
                    }
                    self.head = at + bytes.len();
                    return;
                }
            }
            // The frame goes on in the frame buffer, after what the head room holds.
            let n = self.held();
            self.head = 0;
            self.placed = None;
            if n != 0 {
                // SAFETY: as in `hand_on` (copied before anything writes the head room again).
                self.copy(unsafe { core::slice::from_raw_parts(head_ptr(), n) });
            }
        }
        self.copy(bytes);
    }

    /// Copies bytes into the frame buffer, handing full buffers on.
    fn copy(&mut self, mut bytes: &[u8]) {
        while !bytes.is_empty() {
            let room = FRAME_BUFFER - self.len;
            let (now, later) = bytes.split_at(room.min(bytes.len()));
            let at = self.len;
            crate::copy_bytes(self.frame.get_mut(at..).unwrap_or(&mut []), now);
            self.len = at + now.len();
            if self.len == FRAME_BUFFER {
                self.hand_on();
            }
            bytes = later;
        }
    }
}

// SAFETY: `acquire` enters a critical section and marks the logger taken; `write`, `flush` and
// `release` are only called by defmt between `acquire` and `release`, as the trait requires.
unsafe impl defmt::Logger for Logger {
    fn acquire() {
        // SAFETY: paired with the `critical_section::release` in `release`.
        let restore = unsafe { critical_section::acquire() };
        if TAKEN.load(Ordering::Relaxed) {
            panic!("defmt logger taken re-entrantly");
        }
        TAKEN.store(true, Ordering::Relaxed);
        // SAFETY: inside the critical section, with the logger just taken: exclusive access.
        let state = unsafe { &mut *STATE.0.get() };
        state.restore = restore;
        let State { encoder, sink, .. } = state;
        encoder.start_frame(|b| sink.put(b));
    }

    unsafe fn flush() {}

    unsafe fn release() {
        // SAFETY: called after `acquire` (the trait's contract): exclusive access.
        let state = unsafe { &mut *STATE.0.get() };
        let State { encoder, sink, .. } = state;
        encoder.end_frame(|b| sink.put(b));
        sink.hand_on();
        TAKEN.store(false, Ordering::Relaxed);
        let restore = state.restore;
        // SAFETY: ends the critical section `acquire` entered, with its restore state.
        unsafe { critical_section::release(restore) };
    }

    unsafe fn write(bytes: &[u8]) {
        // SAFETY: called between `acquire` and `release` (the trait's contract).
        let state = unsafe { &mut *STATE.0.get() };
        let State { encoder, sink, .. } = state;
        encoder.write(bytes, |b| sink.put(b));
    }
}
