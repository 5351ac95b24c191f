//! Stack high-water mark: [`paint`] fills the unused stack with a pattern at start-up,
//! [`peak`] finds how deep the stack has reached since (the lowest overwritten word).
//! With the bank and parser living in `main`'s frame, this plus the static RAM from
//! `llvm-size` is the firmware's whole RAM use (no heap).

const PATTERN: u32 = 0xC0FF_EE55;
/// Words left unpainted just below the current stack pointer: room for this function and for
/// interrupt handlers that run while it paints (the UART is already receiving).
const GUARD_WORDS: usize = 256;

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

/// Fills the stack below the current stack pointer (minus a guard) with the pattern.
/// Call once, first thing in `main`.
#[inline(never)]
pub fn paint() {
    let (low, _) = bounds();
    let sp = cortex_m::register::msp::read() as usize;
    let high = sp.saturating_sub(GUARD_WORDS * 4);
    let mut p = low;
    while p < high {
        // SAFETY: [low, high) lies between the end of the statics and the live stack (minus a
        // guard for this function's own frame): memory nothing else uses yet; aligned words.
        unsafe { core::ptr::write_volatile(p as *mut u32, PATTERN) };
        p += 4;
    }
}

/// Bytes of stack used at the deepest point since [`paint`] (from the top of RAM).
pub fn peak() -> usize {
    let (low, top) = bounds();
    let mut p = low;
    while p < top {
        // SAFETY: [low, top) is RAM of this program (stack region), aligned words; reading it
        // has no side effect.
        if unsafe { core::ptr::read_volatile(p as *const u32) } != PATTERN {
            break;
        }
        p += 4;
    }
    top - p
}
