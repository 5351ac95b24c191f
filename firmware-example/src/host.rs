//! Talking to the host through ARM semihosting: text output, exit status, and the handlers
//! that turn a panic or a fault into a non-zero exit instead of a hang.
//!
//! Under QEMU (`-semihosting-config enable=on,target=native`) the exit status becomes QEMU's
//! exit code: 0 for [`exit`]`(true)`, 1 for `exit(false)`, a panic or a HardFault.
//! On a chip ([`crate::board::host_present`] false) no semihosting call is made (one without a
//! debugger faults): an exit parks the core, a fault parks it after probe-rs has seen it.

use core::fmt::Write as _;
use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hio};

/// Writes `bytes` to the host's standard output (one semihosting call for the whole slice).
pub fn stdout(bytes: &[u8]) {
    if let Ok(mut out) = hio::hstdout() {
        // Nothing useful can be done if the host rejects output.
        let _ = out.write_all(bytes);
    }
}

/// A diagnostic line for the host's standard error, built without `core::fmt` (the fault and
/// panic handlers are in every image; `core::fmt` would add about 4 KB to the smallest one).
/// Text beyond its 160 bytes is dropped.
struct Line {
    buf: [u8; 160],
    len: usize,
}

impl Line {
    fn new() -> Self {
        Self {
            buf: [0; 160],
            len: 0,
        }
    }

    fn str(&mut self, s: &str) -> &mut Self {
        self.bytes(s.as_bytes())
    }

    fn bytes(&mut self, b: &[u8]) -> &mut Self {
        let room = self.buf.get_mut(self.len..).unwrap_or(&mut []);
        let n = b.len().min(room.len());
        crate::copy_bytes(room, b.get(..n).unwrap_or(&[]));
        self.len += n;
        self
    }

    /// `v` in decimal.
    fn dec(&mut self, v: u32) -> &mut Self {
        let mut b = itoa::Buffer::new();
        self.str(b.format(v))
    }

    /// `v` as `0x` and eight lower-case hex digits.
    fn hex(&mut self, v: u32) -> &mut Self {
        let mut d = *b"0x00000000";
        for (i, c) in d[2..].iter_mut().enumerate() {
            *c = b"0123456789abcdef"[((v >> (28 - 4 * i)) & 0xF) as usize];
        }
        self.bytes(&d)
    }

    /// Writes the line and a newline to the host's standard error.
    fn send(&mut self) {
        self.str("\n");
        if let Ok(mut err) = hio::hstderr() {
            let _ = err.write_all(self.buf.get(..self.len).unwrap_or(&[]));
        }
    }
}

/// Writes formatted text to the host's standard error (counters, diagnostics).
pub fn stderr(args: core::fmt::Arguments<'_>) {
    if let Ok(mut err) = hio::hstderr() {
        let _ = err.write_fmt(args);
    }
}

/// Ends the program with exit status `code`: semihosting `SYS_EXIT_EXTENDED` (0x20), the call
/// that lets a 32-bit guest give QEMU a status other than 0/1 (QEMU exits with `code`).
/// `code` 0 is the same as [`exit`]`(true)`.
pub fn exit_code(code: u32) -> ! {
    if !crate::board::host_present() {
        park()
    }
    /// `ADP_Stopped_ApplicationExit`: the reason code of a normal application exit.
    const APPLICATION_EXIT: usize = 0x2_0026;
    /// `SYS_EXIT_EXTENDED`.
    const SYS_EXIT_EXTENDED: usize = 0x20;
    let block = [APPLICATION_EXIT, code as usize];
    // SAFETY: a semihosting call with a pointer to a valid two-word parameter block that
    // outlives the call; the host reads it and ends the program.
    unsafe { cortex_m_semihosting::syscall(SYS_EXIT_EXTENDED, &block) };
    // A host without SYS_EXIT_EXTENDED: fall back to the 0/1 exit.
    exit(code == 0)
}

/// The program's command line from the host (semihosting `SYS_GET_CMDLINE`) written into
/// `buf`; empty if the host gives none. Under QEMU it is the `arg=` items of
/// `-semihosting-config`, separated by spaces.
pub fn cmdline(buf: &mut [u8]) -> &[u8] {
    /// `SYS_GET_CMDLINE`.
    const SYS_GET_CMDLINE: usize = 0x15;
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: the parameter block points at `buf` with its length; the host writes at most
    // that many bytes into it and the new length into the block.
    let r = unsafe { cortex_m_semihosting::syscall1(SYS_GET_CMDLINE, block.as_mut_ptr() as usize) };
    if r != 0 {
        return &[];
    }
    let n = block[1].min(buf.len());
    let s = &buf[..n];
    // Some hosts count the terminating NUL.
    s.strip_suffix(&[0]).unwrap_or(s)
}

/// Ends the program: semihosting exit with status 0 (`success`) or 1.
pub fn exit(success: bool) -> ! {
    if !crate::board::host_present() {
        park()
    }
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Only reached without a debugger/host that services semihosting.
    park()
}

/// Stops for good: interrupts masked, the core asleep (a probe can still attach and read).
pub fn park() -> ! {
    cortex_m::interrupt::disable();
    loop {
        cortex_m::asm::wfi();
    }
}

/// Set by the first panic: a panic while reporting one (the logger taken when the first came)
/// goes straight to the fault instead of recursing.
#[cfg(feature = "rtt")]
static PANICKING: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

/// The boards with RTT output: `firmware: panic: panicked at FILE:LINE:COL: MESSAGE` as a
/// defmt message (no `core::fmt`: the message when it is a plain string), then a HardFault
/// (`UDF`), which probe-rs reports with the backtrace and where the core parks.
#[cfg(feature = "rtt")]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    use core::sync::atomic::Ordering;
    cortex_m::interrupt::disable();
    // Interrupts are off: a load/store pair (thumbv6m has no atomic swap) cannot be raced.
    if !PANICKING.load(Ordering::Relaxed) {
        PANICKING.store(true, Ordering::Relaxed);
        let (file, line, column) = info
            .location()
            .map_or(("(unknown)", 0, 0), |l| (l.file(), l.line(), l.column()));
        let message = info.message().as_str().unwrap_or("(formatted message)");
        defmt::println!(
            "firmware: panic: panicked at {=str}:{=u32}:{=u32}: {=str}",
            file,
            line,
            column,
            message
        );
    }
    cortex_m::asm::udf()
}

/// The semihosting boards: the same line on the host's standard error, then exit status 1.
#[cfg(not(feature = "rtt"))]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    cortex_m::interrupt::disable();
    // `panicked at FILE:LINE:COL` and the message when it is a plain string (a message with
    // arguments would need `core::fmt`).
    let mut line = Line::new();
    line.str("firmware: panic: panicked");
    if let Some(at) = info.location() {
        line.str(" at ")
            .str(at.file())
            .str(":")
            .dec(at.line())
            .str(":")
            .dec(at.column());
    }
    if let Some(msg) = info.message().as_str() {
        line.str(": ").str(msg);
    }
    line.send();
    exit(false)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    // Integer-only code: safe to run on a core without an FPU (e.g. a hard-float image
    // started on the Cortex-M3 board faults at its first FP instruction and lands here).
    if !crate::board::host_present() {
        park()
    }
    Line::new()
        .str("firmware: HardFault at pc=")
        .hex(frame.pc())
        .str(" lr=")
        .hex(frame.lr())
        .send();
    exit(false)
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == crate::uart::RX_IRQ as i16 {
        crate::uart::on_rx_interrupt();
    } else {
        unexpected_irq(irqn)
    }
}

/// Reports an interrupt nothing handles and exits: on the host's standard error under QEMU, and
/// on a chip (no semihosting host) through defmt, after which the core parks. Out of line, so
/// the line buffer is not in the frame every receive interrupt stacks on `main`'s (the soak's
/// stack bound counts it).
#[cold]
#[inline(never)]
fn unexpected_irq(irqn: i16) -> ! {
    if !crate::board::host_present() {
        defmt::println!("firmware: unexpected exception/IRQ {=i16}", irqn);
        park()
    }
    let mut line = Line::new();
    line.str("firmware: unexpected exception/IRQ ");
    if irqn < 0 {
        line.str("-");
    }
    line.dec(u32::from(irqn.unsigned_abs())).send();
    exit(false)
}
