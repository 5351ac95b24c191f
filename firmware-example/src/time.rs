//! The firmware's time base: SysTick interrupting at 1 kHz on the core clock, a millisecond
//! counter, the microseconds since start, and [`Delay`], an `embedded_hal::delay::DelayNs`
//! for the boot sequence's time-outs.
//!
//! Under QEMU without `-icount` SysTick follows the host's wall clock, which is what a
//! time-out needs. On `netduinoplus2` QEMU clocks SysTick at its fixed 168 MHz while the
//! firmware runs the STM32 on its 16 MHz HSI (see `uart::hw`), so there every time-out lasts
//! 16/168 of its nominal length; on a real board it is exact to the clock's accuracy.
//! (The bench binary uses SysTick differently, as a free-running instruction counter:
//! [`crate::cycles`]; it never calls [`start`].)

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SCB, SYST};
use cortex_m_rt::exception;

/// Milliseconds since [`start`] (wraps after 49.7 days).
static MILLIS: AtomicU32 = AtomicU32::new(0);
/// SysTick ticks per millisecond (the reload value + 1), 0 before [`start`].
static TICKS_PER_MS: AtomicU32 = AtomicU32::new(0);

#[exception]
fn SysTick() {
    // Single writer (this handler), so a load/store pair is an atomic increment here, also
    // on thumbv6m which has no read-modify-write atomics.
    MILLIS.store(
        MILLIS.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// Starts SysTick on the core clock (`core_clock_hz`) with a 1 ms period and its interrupt
/// enabled; returns the delay provider.
pub fn start(mut syst: SYST, core_clock_hz: u32) -> Delay {
    let ticks = (core_clock_hz / 1000).clamp(2, 0x0100_0000);
    TICKS_PER_MS.store(ticks, Ordering::Relaxed);
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(ticks - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    Delay { _syst: syst }
}

/// Milliseconds since [`start`].
pub fn now_ms() -> u32 {
    MILLIS.load(Ordering::Relaxed)
}

/// Microseconds since [`start`] (0 before it), consistent across a millisecond boundary.
pub fn now_us() -> u64 {
    let ticks = TICKS_PER_MS.load(Ordering::Relaxed);
    if ticks == 0 {
        return 0;
    }
    loop {
        let ms = MILLIS.load(Ordering::Relaxed);
        let pending_before = SCB::is_pendst_pending();
        let current = SYST::get_current();
        let pending_after = SCB::is_pendst_pending();
        // A wrap between the reads, or a tick taken meanwhile: read again. A tick pending on
        // both sides (interrupts masked) happened before `current` was read: count it.
        if pending_before != pending_after || ms != MILLIS.load(Ordering::Relaxed) {
            continue;
        }
        let ms = u64::from(ms) + u64::from(pending_before);
        let into = u64::from(ticks.saturating_sub(1).saturating_sub(current));
        return ms * 1000 + into * 1000 / u64::from(ticks);
    }
}

/// `embedded_hal::delay::DelayNs` on SysTick: waits at least the requested time, sleeping in
/// `wfi` between interrupts (the 1 ms tick or a received byte wakes it).
pub struct Delay {
    _syst: SYST,
}

impl embedded_hal::delay::DelayNs for Delay {
    fn delay_ns(&mut self, ns: u32) {
        let start = now_us();
        let wait = u64::from(ns).div_ceil(1000);
        while now_us().wrapping_sub(start) < wait {
            cortex_m::asm::wfi();
        }
    }
}
