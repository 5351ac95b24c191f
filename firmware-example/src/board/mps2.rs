//! QEMU's `mps2-an385` (Cortex-M3) and `mps2-an386` (Cortex-M4F) boards, emulated only: the
//! default board of the firmware (no `board-*` feature). Memory map (from
//! `boards/src/description.rs`): 1 MiB of code memory at 0 and 128 KiB of RAM at
//! `0x2000_0000`, the size of an STM32F405-class part, so an image that fits here fits there.
//! Output: defmt frames on the semihosting stdout.
//!
//! Registers of the CMSDK APB UARTs of the QEMU `mps2-an385`/`mps2-an386` boards: UART0
//! (base `0x4000_4000`, RX interrupt = IRQ 0) carries the NAV440 link, UART1 (base
//! `0x4000_5000`, polled) the harness's control channel, and with the feature `uart-rows`
//! UART2 (base `0x4000_6000`, transmit only, polled) the rows as framed binary messages
//! (docs/UART-ROWS.md); APB clock 25 MHz. QEMU connects its `-serial` options to UART0,
//! UART1, UART2, ... in order.
//!
//! CMSDK APB UART TRM: DATA +0x0, STATE +0x4 (bit0 TX full, bit1 RX full, bit2 TX overrun,
//! bit3 RX overrun; write 1 to clear an overrun bit), CTRL +0x8 (bit0 TX enable, bit1 RX
//! enable, bit3 RX interrupt enable), INTSTATUS/INTCLEAR +0xC (bit1 RX), BAUDDIV +0x10.

/// Reply time-out of each boot request, ms (SysTick follows the host's clock under QEMU).
pub const REPLY_TIMEOUT_MS: u32 = 500;
/// A failed boot or a unit reset ends the run with a status (the harness reads it).
pub const RETRY_FOREVER: bool = false;
/// Pause between two boot attempts, ms (unused: no retry).
pub const RETRY_PAUSE_MS: u32 = 1000;
/// The board runs captures too (`replay` on the semihosting command line).
pub const REPLAY: bool = true;
/// Slots of the NAV440 receive queue ([`crate::uart`], which holds one byte less): 89 ms of
/// stream at 57,600 Bd.
pub const RX_QUEUE_SLOTS: usize = 512;
/// Bytes of the logger's frame buffer ([`crate::log`]): a longer frame is handed on in pieces.
pub const LOG_FRAME_BYTES: usize = 512;
/// No RTT: QEMU has no probe to read it.
pub const RTT: bool = false;

/// QEMU always services semihosting (`-semihosting-config enable=on`).
pub fn host_present() -> bool {
    true
}

const BASE: usize = 0x4000_4000;
/// UART1: the control channel (see [`Control`]).
const CONTROL_BASE: usize = 0x4000_5000;
/// UART2: the rows' output UART (feature `uart-rows`, see [`rows_write`]).
#[cfg(feature = "uart-rows")]
const ROWS_BASE: usize = 0x4000_6000;
/// The line rate of the rows' output UART, Bd: the paper bank's three-axis rows at 100 Hz take
/// about 23,900 B/s, 239,000 Bd with 8N1 (docs/UART-ROWS.md); QEMU's model ignores the rate.
#[cfg(feature = "uart-rows")]
pub const ROWS_BAUD: u32 = 921_600;
const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_RX_OVERRUN: u32 = 1 << 3;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_IE: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;

/// APB clock of the mps2 boards, Hz (also the core clock that SysTick counts).
pub const PCLK_HZ: u32 = 25_000_000;

/// NVIC number of the UART0 receive interrupt.
pub const RX_IRQ: u16 = 0;

fn read_at(base: usize, offset: usize) -> u32 {
    // SAFETY: base is UART0, UART1 or UART2 and offset one of the registers listed above: a valid,
    // aligned MMIO word on the mps2 boards; reading has no side effect besides the documented
    // one (reading DATA pops the received byte), which the callers intend.
    unsafe { core::ptr::read_volatile((base + offset) as *const u32) }
}

fn write_at(base: usize, offset: usize, value: u32) {
    // SAFETY: as in `read_at`; the values written are those the TRM defines for the register.
    unsafe { core::ptr::write_volatile((base + offset) as *mut u32, value) }
}

fn read_reg(offset: usize) -> u32 {
    read_at(BASE, offset)
}

fn write_reg(offset: usize, value: u32) {
    write_at(BASE, offset, value)
}

/// Baud divider for `baud` (the model ignores it; a real CMSDK UART needs at least 16).
fn bauddiv(baud: u32) -> u32 {
    (PCLK_HZ / baud.max(1)).max(16)
}

/// The board's UARTs after [`init`]: the NAV440 UART's transmit side and the control channel.
pub struct Parts {
    /// Transmit side of UART0.
    pub tx: Tx,
    /// UART1, polled.
    pub control: Control,
    /// Core clock (SysTick's clock source), Hz.
    pub core_clock_hz: u32,
}

/// Sets UART0's baud divider, clears stale flags, enables TX, RX and the RX interrupt (in the
/// UART; the NVIC is the caller's business); enables UART1's receiver for the control channel.
/// `None` if called twice.
pub fn init(baud: u32) -> Option<Parts> {
    static TAKEN: critical_section::Mutex<core::cell::Cell<bool>> =
        critical_section::Mutex::new(core::cell::Cell::new(false));
    if critical_section::with(|cs| TAKEN.borrow(cs).replace(true)) {
        return None;
    }
    write_reg(BAUDDIV, bauddiv(baud));
    write_reg(STATE, STATE_RX_OVERRUN);
    write_reg(INTCLEAR, INT_RX);
    write_reg(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_IE);
    write_at(CONTROL_BASE, BAUDDIV, bauddiv(115_200));
    write_at(CONTROL_BASE, CTRL, CTRL_RX_EN);
    #[cfg(feature = "uart-rows")]
    {
        write_at(ROWS_BASE, BAUDDIV, bauddiv(ROWS_BAUD));
        write_at(ROWS_BASE, CTRL, CTRL_TX_EN);
    }
    Some(Parts {
        tx: Tx { _private: () },
        control: Control { _private: () },
        core_clock_hz: PCLK_HZ,
    })
}

/// Transmit side of UART0 (one-byte holding register).
pub struct Tx {
    _private: (),
}

impl Tx {
    /// Puts `byte` into the transmit register if it is free; `false` if it is still full.
    pub fn try_write(&mut self, byte: u8) -> bool {
        if read_reg(STATE) & STATE_TX_FULL != 0 {
            return false;
        }
        write_reg(DATA, u32::from(byte));
        true
    }

    /// The transmit register is empty (the CMSDK UART has no separate shift-register flag).
    pub fn is_idle(&self) -> bool {
        read_reg(STATE) & STATE_TX_FULL == 0
    }

    /// Sets the baud divider for `baud` Bd (QEMU's model ignores the rate; the API is the
    /// STM32 backend's). Never fails here.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), crate::uart::BaudError> {
        if baud == 0 {
            return Err(crate::uart::BaudError { baud });
        }
        write_reg(BAUDDIV, bauddiv(baud));
        Ok(())
    }
}

/// UART1, the control channel from the QEMU harness, read by polling.
pub struct Control {
    _private: (),
}

impl Control {
    /// One received byte, if any.
    pub fn try_read(&mut self) -> Option<u8> {
        if read_at(CONTROL_BASE, STATE) & STATE_RX_FULL != 0 {
            Some((read_at(CONTROL_BASE, DATA) & 0xFF) as u8)
        } else {
            None
        }
    }
}

/// Sends `bytes` out of UART2, the rows' output UART (feature `uart-rows`): polled and
/// blocking, each byte once the transmit register is free. Under QEMU the register empties at
/// once; on a chip a row frame of N bytes takes N x 10 / [`ROWS_BAUD`] s (239 bytes: 2.6 ms).
#[cfg(feature = "uart-rows")]
pub fn rows_write(bytes: &[u8]) {
    for &b in bytes {
        while read_at(ROWS_BASE, STATE) & STATE_TX_FULL != 0 {}
        write_at(ROWS_BASE, DATA, u32::from(b));
    }
}

/// A received byte waits in the data register.
pub fn rx_full() -> bool {
    read_reg(STATE) & STATE_RX_FULL != 0
}

/// Pops the received byte, if any (never `Lost`: the overrun flag is read by [`take_overrun`]).
pub fn poll_rx() -> crate::uart::RxPoll {
    if rx_full() {
        crate::uart::RxPoll::Byte((read_reg(DATA) & 0xFF) as u8)
    } else {
        crate::uart::RxPoll::Empty
    }
}

/// True (once) if the hardware flagged an RX overrun since the last call; clears the flag.
pub fn take_overrun() -> bool {
    if read_reg(STATE) & STATE_RX_OVERRUN != 0 {
        write_reg(STATE, STATE_RX_OVERRUN);
        true
    } else {
        false
    }
}

/// Acknowledges the RX interrupt.
pub fn clear_rx_interrupt() {
    write_reg(INTCLEAR, INT_RX);
}

/// Masks the RX interrupt in the UART (the byte waits in the data register).
pub fn pause_rx() {
    write_reg(CTRL, read_reg(CTRL) & !CTRL_RX_IE);
}

/// Unmasks the RX interrupt in the UART.
pub fn resume_rx() {
    write_reg(CTRL, read_reg(CTRL) | CTRL_RX_IE);
}
