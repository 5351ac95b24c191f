//! Board support: one module per board, described in `boards/src/description.rs` and picked
//! by at most one `board-*` feature (none: the QEMU `mps2` boards). `build.rs` declares the
//! selected board's module here (with its shared backend module, if any) and generates its
//! memory map from the description. Each board module has its clocks, UARTs and pins and its
//! output transport, and provides the same items:
//!
//! * identity: [`NAME`] (from the description; also written into the ELF as the symbol
//!   `NAV440_BOARD`, which `cargo xtask flash` and the memory-map check read);
//! * behaviour: [`REPLY_TIMEOUT_MS`], [`RETRY_FOREVER`] (a real board retries a failed boot
//!   and a unit reset; the QEMU boards end the run with a status), [`REPLAY`] (the board may
//!   run a capture instead of a unit, `cargo xtask qemu FILE`);
//! * buffers: [`RX_QUEUE_SLOTS`] (the NAV440 receive queue) and [`LOG_FRAME_BYTES`] (the
//!   logger's frame buffer), sized to the board's RAM;
//! * transport: [`RTT`] (defmt frames into an RTT up-channel that probe-rs reads; with it
//!   `RTT_BUFFER`, the channel's bytes, sized to the board's RAM) and
//!   [`host_present`] (a semihosting host services calls: QEMU; defmt frames, exit status);
//! * the NAV440 UART's hardware: `init`, `Tx`, `Control`, `rx_full`, `poll_rx`,
//!   `take_overrun`, `clear_rx_interrupt`, `pause_rx`, `resume_rx`, `RX_IRQ` (used by
//!   [`crate::uart`]).
//!
//! Porting to another board: docs/PORTING.md, docs/HOWTO-BOARD.md.

// The selected board (build.rs): `board_modules!` declares `mod <backend>;` if any,
// `mod <board>; pub use <board>::*;` and `NAME`, resolved in this directory.
include!(concat!(env!("OUT_DIR"), "/board.rs"));
board_modules!();

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
