//! NUCLEO-F411RE (feature `board-nucleo-f411re`; stm32f4xx-hal with `stm32f411`), a Cortex-M4F
//! at up to 100 MHz with 512 KiB flash and 128 KiB RAM. Built, linked and memory-map checked;
//! QEMU has no STM32F411 board, so it is not emulated.
//!
//! * Clocks: the 16 MHz HSI, no PLL (see [`super::stm32f4_hal`]).
//! * NAV440: USART1, TX PA9 (Arduino D8), RX PA10 (Arduino D2), AF7, IRQ 37.
//! * Control channel: USART2, TX PA2, RX PA3 (AF7): the ST-LINK virtual COM port of the
//!   Nucleo; not needed on a board (only the QEMU harness sends the end message).
//! * Time base: SysTick on HCLK (16 MHz), [`crate::time`].
//! * Output: defmt frames into the RTT up-channel `defmt`, read by probe-rs through the
//!   on-board ST-LINK.
//! * Memory map: generated from `boards/src/description.rs` (flash at `0x0800_0000`).
//! * Probe: `probe-rs run --chip STM32F411RETx` (`cargo run`, through `cargo xtask flash`).

pub use super::stm32f4_hal::*;

/// Reply time-out of each boot request, ms.
pub const REPLY_TIMEOUT_MS: u32 = 1000;
/// A failed boot or a unit reset is retried for ever (one diagnostic line per attempt).
pub const RETRY_FOREVER: bool = true;
/// Pause between two boot attempts, ms.
pub const RETRY_PAUSE_MS: u32 = 1000;
/// Always talks to a unit.
pub const REPLAY: bool = false;
/// Slots of the NAV440 receive queue ([`crate::uart`], which holds one byte less): 89 ms of
/// stream at 57,600 Bd.
pub const RX_QUEUE_SLOTS: usize = 512;
/// Bytes of the logger's frame buffer ([`crate::log`]): a longer frame is handed on in pieces.
pub const LOG_FRAME_BYTES: usize = 512;
/// defmt frames go to RTT.
pub const RTT: bool = true;
/// Bytes of the RTT up-channel's buffer.
pub const RTT_BUFFER: usize = 4096;
