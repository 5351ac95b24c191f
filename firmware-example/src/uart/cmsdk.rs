//! Registers of the CMSDK APB UART0 of the QEMU `mps2-an385`/`mps2-an386` boards
//! (base `0x4000_4000`, RX interrupt = IRQ 0, APB clock 25 MHz).
//!
//! CMSDK APB UART TRM: DATA +0x0, STATE +0x4 (bit0 TX full, bit1 RX full, bit2 TX overrun,
//! bit3 RX overrun; write 1 to clear an overrun bit), CTRL +0x8 (bit0 TX enable, bit1 RX
//! enable, bit3 RX interrupt enable), INTSTATUS/INTCLEAR +0xC (bit1 RX), BAUDDIV +0x10.

const BASE: usize = 0x4000_4000;
const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const STATE_RX_FULL: u32 = 1 << 1;
const STATE_RX_OVERRUN: u32 = 1 << 3;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_IE: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;

/// APB clock of the mps2 boards, Hz.
const PCLK_HZ: u32 = 25_000_000;

/// NVIC number of the UART0 receive interrupt.
pub const RX_IRQ: u16 = 0;

/// A received byte can wait in the data register with the RX interrupt masked.
pub const HOLD_WHEN_FULL: bool = true;

fn read_reg(offset: usize) -> u32 {
    // SAFETY: BASE + offset is one of the UART0 registers listed above, a valid, aligned MMIO
    // word on the mps2 boards; reading has no side effect besides the documented one (reading
    // DATA pops the received byte), which the callers intend.
    unsafe { core::ptr::read_volatile((BASE + offset) as *const u32) }
}

fn write_reg(offset: usize, value: u32) {
    // SAFETY: as in `read_reg`; the values written are those the TRM defines for the register.
    unsafe { core::ptr::write_volatile((BASE + offset) as *mut u32, value) }
}

/// Sets the baud divider, clears stale flags, enables TX, RX and the RX interrupt.
pub fn init(baud: u32) {
    write_reg(BAUDDIV, (PCLK_HZ / baud.max(1)).max(16));
    write_reg(STATE, STATE_RX_OVERRUN);
    write_reg(INTCLEAR, INT_RX);
    write_reg(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_IE);
}

/// A received byte waits in the data register.
pub fn rx_full() -> bool {
    read_reg(STATE) & STATE_RX_FULL != 0
}

/// Pops the received byte.
pub fn read_data() -> u8 {
    (read_reg(DATA) & 0xFF) as u8
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

/// Unmasks (`true`) or masks the RX interrupt in the UART.
pub fn set_rx_interrupt(enabled: bool) {
    let ctrl = read_reg(CTRL);
    write_reg(
        CTRL,
        if enabled {
            ctrl | CTRL_RX_IE
        } else {
            ctrl & !CTRL_RX_IE
        },
    );
}
