//! Talking to the host through ARM semihosting: text output, exit status, and the handlers
//! that turn a panic or a fault into a non-zero exit instead of a hang.
//!
//! Under QEMU (`-semihosting-config enable=on,target=native`) the exit status becomes QEMU's
//! exit code: 0 for [`exit`]`(true)`, 1 for `exit(false)`, a panic or a HardFault.
//! On a real board the debug probe (probe-rs) services the same calls.

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

/// Writes formatted text to the host's standard error (counters, diagnostics).
pub fn stderr(args: core::fmt::Arguments<'_>) {
    if let Ok(mut err) = hio::hstderr() {
        let _ = err.write_fmt(args);
    }
}

/// Ends the program: semihosting exit with status 0 (`success`) or 1.
pub fn exit(success: bool) -> ! {
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Only reached without a debugger/host that services semihosting: park the core.
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    cortex_m::interrupt::disable();
    stderr(format_args!("firmware: panic: {info}\n"));
    exit(false)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    // Integer-only code: safe to run on a core without an FPU (e.g. a hard-float image
    // started on the Cortex-M3 board faults at its first FP instruction and lands here).
    stderr(format_args!(
        "firmware: HardFault at pc={:#010x} lr={:#010x}\n",
        frame.pc(),
        frame.lr()
    ));
    exit(false)
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == crate::uart::RX_IRQ as i16 {
        crate::uart::on_rx_interrupt();
    } else {
        stderr(format_args!("firmware: unexpected exception/IRQ {irqn}\n"));
        exit(false)
    }
}
