//! STM32F405/F407 boards (feature `board-stm32f405`; stm32f4xx-hal with `stm32f405`), e.g. the
//! Netduino Plus 2, an STM32F4DISCOVERY (F407) or any F405RG board.
//!
//! * Clocks: the 16 MHz HSI, no PLL (see [`super::stm32f4_hal`]).
//! * NAV440: USART1, TX PA9, RX PA10 (AF7), IRQ 37, interrupt-driven receive.
//! * Control channel (test harness only): USART2, TX PA2, RX PA3 (AF7), polled.
//! * Time base: SysTick on HCLK (16 MHz), [`crate::time`].
//! * Output: defmt frames into the RTT up-channel `defmt` (probe-rs reads it); under QEMU
//!   `netduinoplus2` ([`host_present`]) the same frames also go to the semihosting stdout, so
//!   CI runs the very ELF that is flashed.
//! * Memory map: generated from `boards/src/description.rs` (flash at `0x0800_0000`).
//! * Probe: `probe-rs run --chip STM32F405RGTx` (`cargo run`, through `cargo xtask flash`).

pub use super::stm32f4_hal::*;

/// Reply time-out of each boot request, ms. Under QEMU `netduinoplus2` SysTick runs 168/16
/// times fast (see `crate::time`), so 1000 ms nominal is about 95 ms of wall time there, still
/// well above the emulated round trip; on a board a failed search takes 12 s per attempt.
pub const REPLY_TIMEOUT_MS: u32 = 1000;
/// A failed boot or a unit reset is retried for ever (one diagnostic line per attempt).
pub const RETRY_FOREVER: bool = true;
/// Pause between two boot attempts, ms (nominal; about 95 ms of wall time under QEMU).
pub const RETRY_PAUSE_MS: u32 = 1000;
/// Always talks to a unit (a probe may not serve the semihosting command line).
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
