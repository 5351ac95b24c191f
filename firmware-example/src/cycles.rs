//! Counting executed instructions with SysTick under `qemu -icount shift=6`.
//!
//! With `-icount shift=6` every guest instruction takes 64 ns of virtual time, and SysTick with
//! CLKSOURCE = core runs at 25 MHz (40 ns per tick) on the mps2 boards, so the instructions
//! executed between two reads are `(ticks * 40 + 32) / 64`, exact to +-1 (shared notes,
//! EMBEDDED.md). SysTick is a 24-bit down-counter: a region [`Counter::measure`] counts must
//! stay below 2^24 ticks (about 10.5 million instructions); [`Counter::measure_long`] counts
//! the counter's wraps in the SysTick interrupt and has no such limit. Meaningless without
//! `-icount` or on real hardware.

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
    pub fn instructions(ticks: u64) -> u64 {
        (ticks * 40 + 32) / 64
    }

    /// Runs `f` once and returns the instructions it took (including a constant overhead of
    /// the two counter reads, see [`Counter::overhead`]).
    #[inline(always)]
    pub fn measure<R>(&self, f: impl FnOnce() -> R) -> (u64, R) {
        let start = self.now();
        let r = f();
        let end = self.now();
        (Self::instructions(u64::from(Self::ticks(start, end))), r)
    }

    /// [`Self::measure`] for a region that may exceed 2^24 ticks: the SysTick interrupt is on
    /// meanwhile and counts the wraps (in [`crate::time`]'s millisecond counter, which the
    /// bench does not otherwise use). Each wrap adds the handler's dozen instructions, one per
    /// 10.5 million.
    pub fn measure_long<R>(&mut self, f: impl FnOnce() -> R) -> (u64, R) {
        self.syst.enable_interrupt();
        let (w0, c0) = Self::read_wraps();
        let r = f();
        let (w1, c1) = Self::read_wraps();
        self.syst.disable_interrupt();
        let wraps = u64::from(w1.wrapping_sub(w0));
        let ticks =
            (wraps * (u64::from(MAX_TICKS) + 1) + u64::from(c0)).saturating_sub(u64::from(c1));
        (Self::instructions(ticks), r)
    }

    /// The wrap count and the counter, read consistently (again when a wrap came between).
    fn read_wraps() -> (u32, u32) {
        loop {
            let w = crate::time::now_ms();
            let c = SYST::get_current();
            if w == crate::time::now_ms() {
                return (w, c);
            }
        }
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
