//! Board support and the NAV440 pipeline shared by the firmware binaries.
//!
//! * [`board`]: one module per board (clocks, UART pins, output transport, memory map), picked
//!   by a `board-*` feature; the QEMU `mps2` boards without one. See docs/PORTING.md.
//! * [`uart`]: the NAV440 UART: interrupt-driven receive into a `heapless` SPSC queue, polled
//!   transmit, run-time baud change, as `embedded_io` 0.7 and `embedded_hal_nb` traits, on the
//!   board's hardware; plus the harness's control channel and its end message
//!   ([`uart::EndMessage`]).
//! * [`log`]: the defmt transport (RTT for a probe, semihosting for QEMU).
//! * [`time`]: SysTick at 1 kHz, microseconds since start, `embedded_hal::delay::DelayNs`.
//! * [`host`]: semihosting output, exit codes, the panic handler (every board) and the
//!   HardFault handler
//!   (every failure ends the run with a non-zero exit status instead of hanging).
//! * [`out`]: the output as defmt messages (header, one row per sample, counters); with the
//!   feature `uart-rows` also as framed binary messages out of a second UART.
//! * [`cycles`]: instruction counting with SysTick under `qemu -icount` (see the bench binary).
//! * [`pipeline`]: the firmware's `nav440_pipeline::Pipeline` (parser -> attitude -> BIT ->
//!   `TimeBase` -> one `PaperBank` per axis -> CSV rows).
//! * [`stack`]: stack high-water mark (the stack cortex-m-rt's `paint-stack` painted).
//! * `sqrt`: the ED's square root as the `VSQRT.F32` instruction (FPU builds).
//!
//! This is the only crate of the workspace with `unsafe` (register access, the stack scan, the
//! `VSQRT` instruction, NVIC unmasking); every `unsafe` block carries a `// SAFETY:` comment.
#![no_std]

pub mod board;
pub mod cycles;
pub mod host;
pub mod log;
pub mod out;
pub mod pipeline;
#[cfg(not(any(feature = "fixed-point", not(target_abi = "eabihf"))))]
pub mod sqrt;
pub mod stack;
pub mod time;
pub mod uart;

/// Numeric type of the estimator bank: `f32` on an FPU target (`thumbv7em-none-eabihf`), the
/// saturating fixed-point [`estimators::Fx`] on targets without an FPU or with the
/// `fixed-point` feature.
#[cfg(not(any(feature = "fixed-point", not(target_abi = "eabihf"))))]
pub type Num = f32;
/// Numeric type of the estimator bank: `f32` on an FPU target (`thumbv7em-none-eabihf`), the
/// saturating fixed-point [`estimators::Fx`] on targets without an FPU or with the
/// `fixed-point` feature.
#[cfg(any(feature = "fixed-point", not(target_abi = "eabihf")))]
pub type Num = estimators::Fx;

/// Square root used by the bank's ED: `VSQRT.F32` on an FPU target (bit-identical to the
/// host's `libm::sqrtf`), the portable exact root otherwise.
#[cfg(not(any(feature = "fixed-point", not(target_abi = "eabihf"))))]
pub type BankSqrt = sqrt::Vsqrt;
/// Square root used by the bank's ED: `VSQRT.F32` on an FPU target (bit-identical to the
/// host's `libm::sqrtf`), the portable exact root otherwise.
#[cfg(any(feature = "fixed-point", not(target_abi = "eabihf")))]
pub type BankSqrt = estimators::NativeSqrt;

#[cfg(all(
    feature = "uart-rows",
    any(
        feature = "board-stm32f405",
        feature = "board-nucleo-f411re",
        feature = "board-rp-pico",
        feature = "board-nucleo-g031k8"
    )
))]
compile_error!(
    "`uart-rows`: only the QEMU mps2 boards have the rows' output UART (docs/UART-ROWS.md)"
);

#[cfg(all(feature = "follow", feature = "self-tune"))]
compile_error!("`follow` and `self-tune` are two ways to move the product bank's gains: pick one");

#[cfg(all(
    feature = "fixed-gains",
    any(feature = "follow", feature = "self-tune", feature = "tuned-gains")
))]
compile_error!(
    "`fixed-gains` keeps the shipped gains fixed: not with `follow`, `self-tune` or `tuned-gains`"
);

#[cfg(all(feature = "self-tune", feature = "no-reference"))]
compile_error!(
    "`self-tune` tunes ILO1 against the Euler reference rate: it needs the reference (drop `no-reference`)"
);

#[cfg(all(feature = "bank-product", feature = "adaptive-gains"))]
compile_error!("`bank-product` and `adaptive-gains` are two different banks: pick one");

/// The estimator bank the firmware runs on each axis: the paper's 14 estimators (the default).
#[cfg(not(any(feature = "adaptive-gains", feature = "bank-product")))]
pub type Bank = estimators::PaperBank<Num, BankSqrt>;
/// The estimator bank the firmware runs on each axis: with `fixed-gains` or `tuned-gains`,
/// the product bank with fixed gains (`estimators::ProductBank`: ILO1 velocity and Kalman
/// acceleration).
#[cfg(all(
    feature = "bank-product",
    not(any(follow_gains, feature = "self-tune"))
))]
pub type Bank = estimators::ProductBank<Num, BankSqrt>;
/// The estimator bank the firmware runs on each axis: with `bank-product` alone (or
/// `follow`), the product bank whose gains follow the measured noise and the motion's jerk
/// (`estimators::AdaptiveProductBank`, fed each row's rate about the axis by the pipeline).
#[cfg(follow_gains)]
pub type Bank = estimators::AdaptiveProductBank<Num, BankSqrt>;
/// The estimator bank the firmware runs on each axis: with `self-tune`, the product bank that
/// tunes ILO1 online against each row's Euler reference rate
/// (`estimators::SelfTuningProductBank`, fed the valid rates by the pipeline).
#[cfg(feature = "self-tune")]
pub type Bank = estimators::SelfTuningProductBank<Num, BankSqrt>;
/// The estimator bank the firmware runs on each axis: with `adaptive-gains`, the
/// noise-adaptive bank (`estimators::AdaptiveBank`, gains from [`pipeline::SCHEDULE`]).
#[cfg(feature = "adaptive-gains")]
pub type Bank = estimators::AdaptiveBank<Num, BankSqrt>;

/// What [`Bank`] gives per sample (the channels and their names come from it).
pub type Output = <Bank as estimators::EstimatorBank>::Output;

/// Copies `src` to the start of `dst` (nothing when `dst` is shorter: the firmware's copies fit
/// by construction). Unlike `copy_from_slice` on a range, it has no panic path, whose message
/// would link `core`'s number formatting (about 1 KB) into every image.
#[inline]
pub fn copy_bytes(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}
