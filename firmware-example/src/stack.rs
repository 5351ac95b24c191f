//! Stack high-water mark: [`paint`] fills the unused stack with a pattern at start-up,
//! [`peak`] finds how deep the stack has reached since (the lowest overwritten word).
//! With the bank and parser living in `main`'s frame, this plus the static RAM from
//! `llvm-size` is the firmware's whole RAM use (no heap).

const PATTERN: u32 = 0xC0FF_EE55;
/// Words left unpainted just below the current stack pointer: room for this function's frame.
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

/// True if an interrupt source is already enabled: one of the first 64 NVIC lines (every
/// interrupt the firmware's boards use; ISER0 alone on ARMv6-M) or the SysTick interrupt.
fn interrupts_enabled() -> bool {
    // SAFETY: reads of the NVIC's interrupt set-enable registers and of SysTick's CSR: always
    // present on these cores, reading has no side effect.
    let (iser0, iser1, syst_csr) = unsafe {
        let nvic = &*cortex_m::peripheral::NVIC::PTR;
        // ARMv6-M (no 32-bit atomic RMW: the one cfg that tells it apart) has 32 lines only.
        let iser1 = if cfg!(target_has_atomic = "32") {
            nvic.iser[1].read()
        } else {
            0
        };
        (
            nvic.iser[0].read(),
            iser1,
            (*cortex_m::peripheral::SYST::PTR).csr.read(),
        )
    };
    const SYST_CSR_TICKINT: u32 = 1 << 1;
    iser0 != 0 || iser1 != 0 || syst_csr & SYST_CSR_TICKINT != 0
}

/// Fills the stack below the current stack pointer (minus a guard) with the pattern.
/// Call once, first thing in `main`, before any interrupt is enabled (so that the high-water
/// mark covers the interrupt handlers too): panics if an interrupt is already enabled.
#[inline(never)]
pub fn paint() {
    if interrupts_enabled() {
        panic!("stack::paint called after an interrupt was enabled: paint first");
    }
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
