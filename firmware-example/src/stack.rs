//! Stack high-water mark: cortex-m-rt's `paint-stack` feature fills the whole stack region with
//! `cortex_m_rt::STACK_PAINT_VALUE` in the reset handler, before `main`; [`peak`] finds how
//! deep the stack has reached since (the lowest overwritten word). Everything that runs,
//! interrupt handlers included, is covered. With the bank and parser living in `main`'s frame,
//! this plus the static RAM from `llvm-size` is the firmware's whole RAM use (no heap).

use cortex_m_rt::STACK_PAINT_VALUE;

extern "C" {
    /// End of `.bss`/`.uninit`: the lowest address the stack may grow to (cortex-m-rt).
    static _stack_end: u32;
    /// Initial stack pointer, top of RAM (cortex-m-rt).
    static _stack_start: u32;
}

fn bounds() -> (usize, usize) {
    // Only the addresses of the two linker symbols are taken, never their contents.
    (
        core::ptr::addr_of!(_stack_end) as usize,
        core::ptr::addr_of!(_stack_start) as usize,
    )
}

/// Bytes of stack used at the deepest point since reset (from the top of RAM).
pub fn peak() -> usize {
    let (low, top) = bounds();
    let mut p = low;
    while p < top {
        // SAFETY: [low, top) is RAM of this program (stack region), aligned words; reading it
        // has no side effect.
        if unsafe { core::ptr::read_volatile(p as *const u32) } != STACK_PAINT_VALUE {
            break;
        }
        p += 4;
    }
    top - p
}
