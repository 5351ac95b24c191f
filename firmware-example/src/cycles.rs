//! Counting executed instructions with SysTick under `qemu -icount shift=6`.
//!
//! With `-icount shift=6` every guest instruction takes 64 ns of virtual time, and SysTick with
//! CLKSOURCE = core runs at 25 MHz (40 ns per tick) on the mps2 boards, so the instructions
//! executed between two reads are `(ticks * 40 + 32) / 64`, exact to +-1 (shared notes,
//! EMBEDDED.md). SysTick is a 24-bit down-counter: one region must stay below 2^24 ticks
//! (about 10 million instructions). Meaningless without `-icount` or on real hardware.

use cortex_m::peripheral::{syst::SystClkSource, SYST};

/// Free-running SysTick used as an instruction counter.
pub struct Counter {
    syst: SYST,
}

/// Largest tick span one region may cover.
pub const MAX_TICKS: u32 = 0x00FF_FFFF;

impl Counter {
    /// Starts SysTick on the core clock with the full 24-bit reload, interrupt off.
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(MAX_TICKS);
        syst.clear_current();
        syst.disable_interrupt();
        syst.enable_counter();
        Self { syst }
    }

    /// Current counter value (counts down).
    #[inline(always)]
    pub fn now(&self) -> u32 {
        SYST::get_current()
    }

    /// Ticks elapsed from `start` to `end` (handles one wrap of the down-counter).
    pub fn ticks(start: u32, end: u32) -> u32 {
        start.wrapping_sub(end) & MAX_TICKS
    }

    /// Instructions corresponding to `ticks` under `-icount shift=6` (40 ns ticks, 64 ns
    /// instructions), rounded to nearest.
    pub fn instructions(ticks: u32) -> u64 {
        (u64::from(ticks) * 40 + 32) / 64
    }

    /// Runs `f` once and returns the instructions it took (including a constant overhead of
    /// the two counter reads, see [`Counter::overhead`]).
    #[inline(always)]
    pub fn measure<R>(&self, f: impl FnOnce() -> R) -> (u64, R) {
        let start = self.now();
        let r = f();
        let end = self.now();
        (Self::instructions(Self::ticks(start, end)), r)
    }

    /// Instructions counted for an empty region (to subtract).
    pub fn overhead(&self) -> u64 {
        self.measure(|| ()).0
    }

    /// Gives the SysTick peripheral back.
    pub fn release(self) -> SYST {
        self.syst
    }
}
