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

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// Bytes of the frame buffer: the largest frame the firmware sends in one piece (a row of
/// three paper-bank axes is 227 bytes); a longer frame is handed on in pieces of this size.
const FRAME_BUFFER: usize = 512;

/// Bytes of the RTT up-channel's buffer: the board's.
#[cfg(feature = "rtt")]
const RTT_BUFFER: usize = crate::board::RTT_BUFFER;

#[defmt::global_logger]
struct Logger;

/// Where the encoded bytes go: the frame buffer and the RTT channel.
struct Sink {
    frame: heapless::Vec<u8, FRAME_BUFFER>,
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
        frame: heapless::Vec::new(),
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
    /// Hands the buffered bytes on to the transports and empties the buffer.
    fn hand_on(&mut self) {
        if self.frame.is_empty() {
            return;
        }
        #[cfg(feature = "rtt")]
        if let Some(ch) = self.rtt.as_mut() {
            // NoBlockSkip writes all or nothing.
            if ch.write(&self.frame) == 0 {
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
                let _ = out.write_all(&self.frame);
            }
        }
        self.frame.clear();
    }

    /// Appends encoded bytes to the frame buffer, handing full buffers on.
    fn put(&mut self, mut bytes: &[u8]) {
        while !bytes.is_empty() {
            let room = FRAME_BUFFER - self.frame.len();
            let (now, later) = bytes.split_at(room.min(bytes.len()));
            // Cannot fail: `now` fits the room left.
            let _ = self.frame.extend_from_slice(now);
            if self.frame.is_full() {
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
