//! The ED's square root on the Cortex-M4F: the `VSQRT.F32` instruction.
//!
//! `estimators` computes `|e|^(1/2)` through the [`SqrtFn`] type parameter; its default is the
//! portable `libm::sqrtf` (software, about 45 instructions). `VSQRT.F32` returns the correctly
//! rounded IEEE 754 square root, which is also what `libm::sqrtf` returns, so the outputs are
//! bit-identical to the host's (`cargo xtask ci` checks the CSV text for equality).

use estimators::SqrtFn;

/// `VSQRT.F32` (FPv4-SP), for `PaperBank<f32, Vsqrt>`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Vsqrt;

impl SqrtFn<f32> for Vsqrt {
    #[inline(always)]
    fn sqrt(x: f32) -> f32 {
        let bits: u32;
        // SAFETY: only core and FPU registers are used, no memory and no stack; S0 is saved in
        // a core register and restored, so no FPU register the compiler uses changes (the FP
        // register classes need the `vfp2` target feature, which stable Rust does not let this
        // crate name, hence the moves through core registers). The FPU is present and enabled
        // on this target (eabihf: cortex-m-rt enables it in the reset handler before `main`).
        unsafe {
            core::arch::asm!(
                "vmov {save}, s0",
                "vmov s0, {x}",
                "vsqrt.f32 s0, s0",
                "vmov {r}, s0",
                "vmov s0, {save}",
                x = in(reg) x.to_bits(),
                r = lateout(reg) bits,
                save = out(reg) _,
                options(pure, nomem, nostack, preserves_flags)
            );
        }
        f32::from_bits(bits)
    }
}
