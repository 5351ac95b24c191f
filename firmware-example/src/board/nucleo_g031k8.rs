//! NUCLEO-G031K8 (STM32G031K8, Cortex-M0+ at up to 64 MHz, `thumbv6m-none-eabi`; feature
//! `board-nucleo-g031k8`) on `stm32g0xx-hal` 0.2 (feature `stm32g031`): clocks, pins and the
//! USART are set up by the HAL. Built, linked and memory-map checked; QEMU has no STM32G0
//! machine, so it is not emulated.
//!
//! The board stands for the part the small image is made for: its chip has 64 KiB of flash
//! and 8 KiB of SRAM, and the memory map gives the linker 32 KiB of flash, the STM32G031K6's
//! (`boards/src/description.rs`). Its image is the product bank at the cargo profile `small`
//! (`--profile small --features bank-product,board-nucleo-g031k8`).
//!
//! * Clocks: the 16 MHz HSI16, not divided, no PLL: the core clock (HCLK, SysTick's clock
//!   with CLKSOURCE = processor, [`crate::time`]) and the USART's (PCLK) are both 16 MHz. The
//!   HSI16 is within +-1 % over temperature, inside a UART's tolerance.
//! * NAV440 link: USART1, TX PB6 (Arduino D1), RX PB7 (Arduino D0), AF0, 8N1 with its 8-byte
//!   FIFOs on; interrupt = IRQ 27 (USART1), raised while the RX FIFO is not empty (RXFNEIE),
//!   which clears as the FIFO is drained: nothing to acknowledge. Receive is interrupt driven
//!   (the HAL's `Rx` lives in a `critical_section::Mutex` that the ISR reads from).
//! * Control channel: none. It carries the QEMU harness's end message, and no emulator runs
//!   this board; USART2 (PA2/PA3, the ST-LINK virtual COM port) stays free.
//! * Output: defmt frames into the RTT up-channel `defmt` ([`RTT_BUFFER`] bytes: the part has
//!   8 KiB of RAM), read by probe-rs through the on-board ST-LINK.
//! * Probe: `probe-rs run --chip STM32G031K8Tx` (`cargo run`, through `cargo xtask flash`).
//!
//! The run-time baud change rewrites the divider (BRR) with the USART disabled, which is the
//! only way the reference manual allows (RM0444, USART_BRR: writable when UE = 0); stm32g0xx-hal
//! 0.2 has no call for it (its `Serial` cannot be released and rebuilt).

use core::cell::Cell;
use critical_section::Mutex;
use stm32g0xx_hal::{
    pac,
    prelude::*,
    rcc::{Config as RccConfig, Prescaler},
    serial::{FullConfig, Rx, Serial, Tx as HalTx},
};

type Nav = pac::USART1;

/// The HAL's receive half of USART1, read by the RX interrupt. A `Cell` (taken and put back
/// inside one critical section) rather than a `RefCell`: no borrow can fail, so the image
/// links no borrow-error text that nothing would print.
static RX: Mutex<Cell<Option<Rx<Nav, FullConfig>>>> = Mutex::new(Cell::new(None));

/// Reply time-out of each boot request, ms.
pub const REPLY_TIMEOUT_MS: u32 = 1000;
/// A failed boot or a unit reset is retried for ever (one diagnostic line per attempt).
pub const RETRY_FOREVER: bool = true;
/// Pause between two boot attempts, ms.
pub const RETRY_PAUSE_MS: u32 = 1000;
/// Always talks to a unit.
pub const REPLAY: bool = false;
/// Slots of the NAV440 receive queue ([`crate::uart`], which holds one byte less), a quarter of
/// the SRAM saved against the other boards' 512: 44 ms of stream at 57,600 Bd. The longest
/// stretch without reading is a bank rebuild at a new packet period (three banks read back and
/// 16 held samples run again: about 130,000 instructions, some 10 ms at 16 MHz).
pub const RX_QUEUE_SLOTS: usize = 256;
/// Bytes of the logger's frame buffer ([`crate::log`]), half the other boards': rows go out
/// in place (not through it), and this image's other frames (boot report, boot errors with
/// interned texts, counters) are under 100 bytes. A longer frame is handed on in pieces.
pub const LOG_FRAME_BYTES: usize = 256;
/// defmt frames go to RTT.
pub const RTT: bool = true;
/// Bytes of the RTT up-channel's buffer: a quarter of the other boards', for 8 KiB of SRAM;
/// four of the largest pieces the logger writes at once ([`LOG_FRAME_BYTES`]).
pub const RTT_BUFFER: usize = 1024;

/// Never emulated: no semihosting host (a semihosting call without a debugger faults).
pub fn host_present() -> bool {
    false
}

/// NVIC number of the USART1 interrupt.
pub const RX_IRQ: u16 = 27;
const _: () = assert!(pac::Interrupt::USART1 as u16 == RX_IRQ);

/// The USART1 divider (BRR) for `baud` Bd from a USART clock of `clk_hz`, 16x oversampling
/// (BRR = clock / rate, at least 16: RM0444, USART_BRR), or `None` for 0 Bd or a rate the clock
/// cannot make (faster than `clk_hz / 16`, or a divider past 16 bits).
pub const fn divider(baud: u32, clk_hz: u32) -> Option<u32> {
    if baud == 0 {
        return None;
    }
    let div = clk_hz / baud;
    if div < 16 || div > 0xffff {
        return None;
    }
    Some(div)
}

// The divider at the board's 16 MHz: every NAV440 rate, none past 1 MBd or below 245 Bd.
const _: () = {
    assert!(divider(9_600, 16_000_000).is_some());
    assert!(divider(57_600, 16_000_000).is_some());
    assert!(divider(230_400, 16_000_000).is_some());
    assert!(divider(1_000_000, 16_000_000).is_some());
    assert!(divider(1_000_001, 16_000_000).is_none());
    assert!(divider(244, 16_000_000).is_none());
    assert!(divider(0, 16_000_000).is_none());
};

/// The board's UARTs after [`init`].
pub struct Parts {
    /// Transmit side of USART1 (and what a baud change needs).
    pub tx: Tx,
    /// No control channel on this board.
    pub control: Control,
    /// Core clock (HCLK, SysTick's clock source) from the HAL's clocks, Hz.
    pub core_clock_hz: u32,
}

/// Sets the clocks (HSI16, see the module doc), sets up USART1 for `baud` Bd 8N1 on PB6/PB7
/// with its FIFOs on and its RX FIFO interrupt enabled in the USART (the NVIC is the caller's
/// business). `None` if the peripherals were already taken or the clock cannot make `baud`.
pub fn init(baud: u32) -> Option<Parts> {
    let dp = pac::Peripherals::take()?;
    let mut rcc = dp.RCC.freeze(RccConfig::hsi(Prescaler::NotDivided));
    let usart_clock = rcc.clocks.apb_clk.raw();
    divider(baud, usart_clock)?;
    let gpiob = dp.GPIOB.split(&mut rcc);
    let nav: Serial<Nav, FullConfig> = dp
        .USART1
        .usart(
            (gpiob.pb6, gpiob.pb7),
            FullConfig::default().baudrate(baud.bps()).fifo_enable(),
            &mut rcc,
        )
        .ok()?;
    let (tx, mut rx) = nav.split();
    rx.listen();
    critical_section::with(|cs| RX.borrow(cs).set(Some(rx)));
    Some(Parts {
        tx: Tx { tx, usart_clock },
        control: Control,
        core_clock_hz: rcc.clocks.ahb_clk.raw(),
    })
}

/// USART1's registers.
fn nav_regs() -> &'static pac::usart1::RegisterBlock {
    // SAFETY: USART1's register block is at a fixed address for the whole program. The HAL's
    // `Tx` and `Rx` own it; through this reference only ISR is read (no side effect) and, in
    // `Tx::set_baud` inside a critical section with the transmitter idle, CR1.UE and BRR are
    // written, and in `poll_rx` RDR is read by the receive side, which alone pops the RX FIFO.
    unsafe { &*pac::USART1::ptr() }
}

/// Transmit side of USART1, plus the USART clock for a baud change.
pub struct Tx {
    tx: HalTx<Nav, FullConfig>,
    /// PCLK, the USART's clock, Hz.
    usart_clock: u32,
}

impl Tx {
    /// Puts `byte` into the TX FIFO if it has room; `false` if it is full.
    pub fn try_write(&mut self, byte: u8) -> bool {
        self.tx.write(byte).is_ok()
    }

    /// The last byte has left the shift register (TC).
    pub fn is_idle(&self) -> bool {
        nav_regs().isr.read().tc().bit_is_set()
    }

    /// Switches USART1 to `baud` Bd: waits for the bytes in flight, then, in a critical
    /// section, disables the USART, writes the divider and enables it again. The other
    /// configuration (8N1, FIFOs, RXFNEIE) stays; bytes waiting in the RX FIFO and a byte being
    /// received are lost (UE = 0 stops the receiver; [`poll_rx`] then finds the FIFO empty).
    /// Fails (and leaves the rate unchanged) for a rate the clock cannot make ([`divider`]).
    pub fn set_baud(&mut self, baud: u32) -> Result<(), crate::uart::BaudError> {
        let div = divider(baud, self.usart_clock).ok_or(crate::uart::BaudError { baud })?;
        while !self.is_idle() {}
        critical_section::with(|_| {
            let usart = nav_regs();
            usart.cr1.modify(|_, w| w.ue().clear_bit());
            // SAFETY: `divider` keeps the value within BRR's 16 bits, at least 16.
            usart.brr.write(|w| unsafe { w.bits(div) });
            usart.cr1.modify(|_, w| w.ue().set_bit());
        });
        Ok(())
    }
}

/// No control channel on this board (see the module doc).
pub struct Control;

impl Control {
    /// Never a byte.
    pub fn try_read(&mut self) -> Option<u8> {
        None
    }
}

/// A received byte waits in the RX FIFO (RXFNE).
pub fn rx_full() -> bool {
    critical_section::with(|cs| {
        let slot = RX.borrow(cs);
        let rx = slot.take();
        let full = rx.as_ref().is_some_and(|rx| rx.is_rxne());
        slot.set(rx);
        full
    })
}

/// Pops one received byte through the HAL. An overrun (a byte arrived with the FIFO full) is
/// `Lost` once, and the bytes in the FIFO are good. A byte received with a framing or parity
/// error, or noise, is `Lost`: the HAL clears the flag and leaves the byte, which is dropped
/// here.
pub fn poll_rx() -> crate::uart::RxPoll {
    critical_section::with(|cs| {
        let slot = RX.borrow(cs);
        let Some(mut rx) = slot.take() else {
            return crate::uart::RxPoll::Empty;
        };
        let got = match rx.read() {
            Ok(b) => crate::uart::RxPoll::Byte(b),
            Err(nb::Error::WouldBlock) => crate::uart::RxPoll::Empty,
            Err(nb::Error::Other(stm32g0xx_hal::serial::Error::Overrun)) => {
                crate::uart::RxPoll::Lost
            }
            Err(nb::Error::Other(_)) => {
                if rx.is_rxne() {
                    let _ = nav_regs().rdr.read();
                }
                crate::uart::RxPoll::Lost
            }
        };
        slot.set(Some(rx));
        got
    })
}

/// Overruns are reported by [`poll_rx`] on this board.
pub fn take_overrun() -> bool {
    false
}

/// RXFNE clears as the FIFO is drained: nothing to acknowledge.
pub fn clear_rx_interrupt() {}

/// Masks the USART1 line in the NVIC (the bytes wait in the 8-byte RX FIFO; the USART keeps
/// its line asserted, so it becomes pending).
pub fn pause_rx() {
    cortex_m::peripheral::NVIC::mask(crate::uart::Irq(RX_IRQ));
}

/// Unmasks the USART1 line in the NVIC.
pub fn resume_rx() {
    // SAFETY: the handler for this IRQ only touches the receive queue's producer (behind a
    // critical section), atomics and USART1's receive registers, so unmasking it breaks no
    // critical section.
    unsafe { cortex_m::peripheral::NVIC::unmask(crate::uart::Irq(RX_IRQ)) };
}
