//! Registers of USART1 of an STM32F405/F407 (`board-stm32f405` profile): RX on PA10, TX on
//! PA9 (alternate function 7), interrupt = IRQ 37, clocked from APB2.
//!
//! RM0090: RCC_AHB1ENR (0x4002_3830) bit0 GPIOAEN, RCC_APB2ENR (0x4002_3844) bit4 USART1EN;
//! GPIOA (0x4002_0000) MODER +0x00 (2 bits/pin, 0b10 = alternate), AFRH +0x24 (4 bits/pin
//! from pin 8); USART1 (0x4001_1000) SR +0x00 (bit3 ORE, bit5 RXNE), DR +0x04, BRR +0x08,
//! CR1 +0x0C (bit13 UE, bit5 RXNEIE, bit3 TE, bit2 RE). The clock tree is the reset one
//! (16 MHz HSI, APB2 = 16 MHz); a board that switches to the PLL (168 MHz, APB2 84 MHz)
//! changes [`PCLK2_HZ`].

const RCC_AHB1ENR: usize = 0x4002_3830;
const RCC_APB2ENR: usize = 0x4002_3844;
const GPIOA_MODER: usize = 0x4002_0000;
const GPIOA_AFRH: usize = 0x4002_0024;
const USART1: usize = 0x4001_1000;
const SR: usize = USART1;
const DR: usize = USART1 + 0x04;
const BRR: usize = USART1 + 0x08;
const CR1: usize = USART1 + 0x0C;

const SR_ORE: u32 = 1 << 3;
const SR_RXNE: u32 = 1 << 5;
const CR1_UE: u32 = 1 << 13;
const CR1_RXNEIE: u32 = 1 << 5;
const CR1_TE: u32 = 1 << 3;
const CR1_RE: u32 = 1 << 2;

/// APB2 clock after reset (HSI), Hz.
pub const PCLK2_HZ: u32 = 16_000_000;

/// NVIC number of the USART1 interrupt.
pub const RX_IRQ: u16 = 37;

/// QEMU's USART model keeps the interrupt asserted while RXNE is set, even with RXNEIE masked:
/// the driver drops (and counts) bytes on a full queue instead of holding them.
pub const HOLD_WHEN_FULL: bool = false;

fn read_reg(addr: usize) -> u32 {
    // SAFETY: `addr` is one of the RCC/GPIOA/USART1 registers listed above, valid aligned
    // MMIO words on STM32F405/F407; reading DR pops the received byte, which callers intend.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

fn write_reg(addr: usize, value: u32) {
    // SAFETY: as in `read_reg`; values follow RM0090 for these registers.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

fn modify(addr: usize, clear: u32, set: u32) {
    write_reg(addr, (read_reg(addr) & !clear) | set);
}

/// Clocks GPIOA and USART1, routes PA9/PA10 to USART1, sets `baud` 8N1, enables RX interrupt.
pub fn init(baud: u32) {
    modify(RCC_AHB1ENR, 0, 1 << 0);
    modify(RCC_APB2ENR, 0, 1 << 4);
    // PA9, PA10: alternate function mode (0b10), AF7.
    modify(
        GPIOA_MODER,
        (0b11 << 18) | (0b11 << 20),
        (0b10 << 18) | (0b10 << 20),
    );
    modify(GPIOA_AFRH, (0xF << 4) | (0xF << 8), (7 << 4) | (7 << 8));
    // Oversampling by 16: BRR = f_pclk / baud (mantissa.fraction in 12.4).
    write_reg(BRR, (PCLK2_HZ + baud.max(1) / 2) / baud.max(1));
    write_reg(CR1, CR1_UE | CR1_TE | CR1_RE | CR1_RXNEIE);
}

/// A received byte waits in DR.
pub fn rx_full() -> bool {
    read_reg(SR) & SR_RXNE != 0
}

/// Pops the received byte (also clears ORE after an SR read).
pub fn read_data() -> u8 {
    (read_reg(DR) & 0xFF) as u8
}

/// True if the hardware flagged an overrun (ORE). The flag clears with the next DR read
/// (SR read followed by DR read), which the caller's receive loop performs.
pub fn take_overrun() -> bool {
    read_reg(SR) & SR_ORE != 0
}

/// RXNE clears when DR is read: nothing to acknowledge.
pub fn clear_rx_interrupt() {}

/// Unmasks (`true`) or masks the RXNE interrupt.
pub fn set_rx_interrupt(enabled: bool) {
    if enabled {
        modify(CR1, 0, CR1_RXNEIE);
    } else {
        modify(CR1, CR1_RXNEIE, 0);
    }
}
