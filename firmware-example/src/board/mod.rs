//! Board support: one module per board, picked by at most one `board-*` feature (none: the
//! QEMU `mps2` boards). Each board module has its clocks, UARTs and pins, its output transport
//! and its memory map (`<board>.x` beside the module, which `build.rs` links as the image's
//! `memory.x`), and provides the same items:
//!
//! * identity: [`NAME`] (also written into the ELF as the symbol `NAV440_BOARD`, which
//!   `cargo xtask flash` and the memory-map check read) and [`PROBE_CHIP`] (probe-rs chip name,
//!   `None` for an emulated-only board);
//! * behaviour: [`REPLY_TIMEOUT_MS`], [`RETRY_FOREVER`] (a real board retries a failed boot
//!   and a unit reset; the QEMU boards end the run with a status), [`REPLAY`] (the board may
//!   run a capture instead of a unit, `cargo xtask qemu FILE`);
//! * transport: [`RTT`] (defmt frames into an RTT up-channel that probe-rs reads) and
//!   [`host_present`] (a semihosting host services calls: QEMU; defmt frames, exit status);
//! * the NAV440 UART's hardware: `init`, `Tx`, `Control`, `rx_full`, `poll_rx`,
//!   `take_overrun`, `clear_rx_interrupt`, `pause_rx`, `resume_rx`, `RX_IRQ` (used by
//!   [`crate::uart`]).
//!
//! Porting to another board: docs/PORTING.md.

// At most one `board-*` feature (build.rs refuses more). build.rs sets `board_mps2` when none
// is selected, and `board_<backend>` for a board built on a shared backend module.
#[cfg(board_mps2)]
mod mps2;
#[cfg(board_mps2)]
pub use mps2::*;

#[cfg(board_stm32f4_hal)]
mod stm32f4_hal;

#[cfg(feature = "board-stm32f405")]
mod stm32f405;
#[cfg(feature = "board-stm32f405")]
pub use stm32f405::*;

#[cfg(feature = "board-nucleo-f411re")]
mod nucleo_f411re;
#[cfg(feature = "board-nucleo-f411re")]
pub use nucleo_f411re::*;

#[cfg(feature = "board-rp-pico")]
mod rp_pico;
#[cfg(feature = "board-rp-pico")]
pub use rp_pico::*;

/// The board's name in the ELF (NUL-terminated), for `cargo xtask flash` and the memory-map
/// check of `cargo xtask ci`, which read the symbol from the image instead of trusting how it
/// was built.
#[no_mangle]
#[used]
pub static NAV440_BOARD: [u8; NAME.len() + 1] = name_bytes();

const fn name_bytes() -> [u8; NAME.len() + 1] {
    let mut out = [0u8; NAME.len() + 1];
    let src = NAME.as_bytes();
    let mut i = 0;
    while i < src.len() {
        out[i] = src[i];
        i += 1;
    }
    out
}
