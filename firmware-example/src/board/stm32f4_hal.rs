//! The STM32F4 boards on `stm32f4xx-hal` (`stm32f405`, `nucleo_f411re`; the chip is the HAL's
//! feature, which the board feature selects): clocks, pins and USARTs are set up by the HAL,
//! not by register constants of this crate.
//!
//! * Clocks: `rcc::Config::hsi()`, the internal 16 MHz RC oscillator, no PLL: `freeze` then
//!   waits on nothing (QEMU 7.2's `netduinoplus2` leaves RCC unimplemented, so a wait for
//!   HSERDY/PLLRDY would never end there), and a real board runs it as well (HSI is +-1 %,
//!   inside a UART's tolerance at 57600 Bd). The USART baud divider and SysTick's rate come
//!   from the HAL's frozen `Clocks`.
//! * NAV440 link: USART1, TX PA9, RX PA10 (AF7), interrupt = IRQ 37; receive is interrupt
//!   driven (the HAL's `Rx` lives in a `critical_section::Mutex` that the ISR reads from).
//! * Control channel (test harness only): USART2, TX PA2, RX PA3, polled.
//!
//! The run-time baud change rebuilds the USART through the HAL (`Serial::release`, then
//! `Serial::new` with the new rate) inside a critical section.

use core::cell::RefCell;
use critical_section::Mutex;
use stm32f4xx_hal::{
    pac,
    prelude::*,
    rcc::{Config as RccConfig, Rcc},
    serial::{Config, Rx, RxISR, RxListen, Serial, Tx as HalTx},
};

type Nav = pac::USART1;

/// The HAL's receive half of USART1, read by the RX interrupt.
static RX: Mutex<RefCell<Option<Rx<Nav>>>> = Mutex::new(RefCell::new(None));

/// NVIC number of the USART1 interrupt.
pub const RX_IRQ: u16 = 37;

/// True when the image runs under QEMU (`netduinoplus2`), not on a chip: QEMU does not model
/// the RCC (its registers read 0), while on a chip `RCC_CR` always has HSION and HSIRDY set
/// once `init` has frozen the clocks on the HSI (reset value `0x0000_xx83`). Decides whether a
/// semihosting host is there (output, exit status); reading it has no side effect.
pub fn emulated() -> bool {
    // SAFETY: a read of RCC_CR, a valid MMIO register of every STM32F4; no side effect.
    let cr = unsafe { (*pac::RCC::ptr()).cr().read().bits() };
    cr == 0
}

/// A semihosting host is there: only under QEMU ([`emulated`]); on a chip a semihosting call
/// without a debugger faults.
pub fn host_present() -> bool {
    emulated()
}

/// Baud rate of the control channel (the model ignores it).
const CONTROL_BAUD: u32 = 115_200;

/// The board's UARTs after [`init`].
pub struct Parts {
    /// Transmit side of USART1 (and what a baud change needs).
    pub tx: Tx,
    /// USART2, polled.
    pub control: Control,
    /// Core clock (HCLK, SysTick's clock source) from the HAL's `Clocks`, Hz.
    pub core_clock_hz: u32,
}

/// Freezes the clocks (HSI, see the module doc), sets up USART1 for `baud` Bd 8N1 with its
/// RXNE interrupt enabled in the USART (the NVIC is the caller's business) and USART2 for the
/// control channel. `None` if the peripherals were already taken or a USART rejects its
/// configuration.
pub fn init(baud: u32) -> Option<Parts> {
    let dp = pac::Peripherals::take()?;
    let mut rcc = dp.RCC.freeze(RccConfig::hsi());
    let gpioa = dp.GPIOA.split(&mut rcc);
    let nav: Serial<Nav> = Serial::new(
        dp.USART1,
        (gpioa.pa9, gpioa.pa10),
        Config::default().baudrate(baud.bps()),
        &mut rcc,
    )
    .ok()?;
    let (tx, mut rx) = nav.split();
    rx.listen();
    critical_section::with(|cs| RX.borrow(cs).replace(Some(rx)));
    let control: Serial<pac::USART2> = Serial::new(
        dp.USART2,
        (gpioa.pa2, gpioa.pa3),
        Config::default().baudrate(CONTROL_BAUD.bps()),
        &mut rcc,
    )
    .ok()?;
    let core_clock_hz = rcc.clocks.hclk().raw();
    Some(Parts {
        tx: Tx { tx: Some(tx), rcc },
        control: Control { serial: control },
        core_clock_hz,
    })
}

/// Transmit side of USART1, plus the HAL's RCC handle for a baud change.
pub struct Tx {
    /// `None` only inside [`Tx::set_baud`].
    tx: Option<HalTx<Nav>>,
    rcc: Rcc,
}

impl Tx {
    /// Puts `byte` into the data register if TXE is set; `false` if it is still full.
    pub fn try_write(&mut self, byte: u8) -> bool {
        match self.tx.as_mut() {
            Some(tx) => embedded_hal_nb::serial::Write::write(tx, byte).is_ok(),
            None => false,
        }
    }

    /// The last byte has left the shift register (TC).
    pub fn is_idle(&self) -> bool {
        // `flush` of the HAL's Tx only reads SR; it needs `&mut` by the trait's signature.
        let p = pac::USART1::ptr();
        // SAFETY: a read of USART1's SR, which has no side effect (TC is cleared only by a
        // following DR write); the HAL's `Tx` owns the peripheral but reads SR the same way.
        unsafe { (*p).sr().read().tc().bit_is_set() }
    }

    /// Switches USART1 to `baud` Bd: waits for the byte in flight, then rebuilds the USART
    /// through the HAL with interrupts masked. Fails (and leaves the rate unchanged) for a
    /// rate the APB2 clock cannot produce with 16x oversampling.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), crate::uart::BaudError> {
        let err = crate::uart::BaudError { baud };
        let pclk2 = self.rcc.clocks.pclk2().raw();
        if baud == 0 || baud > pclk2 / 16 {
            return Err(err);
        }
        while !self.is_idle() {}
        critical_section::with(|cs| {
            let rx = RX.borrow(cs).take().ok_or(err)?;
            let tx = self.tx.take().ok_or(err)?;
            let (usart, (tx_pin, rx_pin)) = rx.join(tx).release();
            let (Some(tx_pin), Some(rx_pin)) = (tx_pin, rx_pin) else {
                return Err(err);
            };
            let serial: Serial<Nav> = Serial::new(
                usart,
                (tx_pin, rx_pin),
                Config::default().baudrate(baud.bps()),
                &mut self.rcc,
            )
            .map_err(|_| err)?;
            let (tx, mut rx) = serial.split();
            rx.listen();
            RX.borrow(cs).replace(Some(rx));
            self.tx = Some(tx);
            Ok(())
        })
    }
}

/// USART2, the control channel from the QEMU harness, read by polling.
pub struct Control {
    serial: Serial<pac::USART2>,
}

impl Control {
    /// One received byte, if any (a line error drops the byte).
    pub fn try_read(&mut self) -> Option<u8> {
        embedded_hal_nb::serial::Read::read(&mut self.serial).ok()
    }
}

/// A received byte waits in DR.
pub fn rx_full() -> bool {
    critical_section::with(|cs| {
        RX.borrow_ref(cs)
            .as_ref()
            .is_some_and(RxISR::is_rx_not_empty)
    })
}

/// Pops the received byte through the HAL; a line error (overrun, framing, noise, parity)
/// has already cost the byte: `Lost`.
pub fn poll_rx() -> crate::uart::RxPoll {
    critical_section::with(|cs| {
        let mut rx = RX.borrow_ref_mut(cs);
        let Some(rx) = rx.as_mut() else {
            return crate::uart::RxPoll::Empty;
        };
        match embedded_hal_nb::serial::Read::read(rx) {
            Ok(b) => crate::uart::RxPoll::Byte(b),
            Err(nb::Error::WouldBlock) => crate::uart::RxPoll::Empty,
            Err(nb::Error::Other(_)) => crate::uart::RxPoll::Lost,
        }
    })
}

/// Overruns are reported by [`poll_rx`] on this backend.
pub fn take_overrun() -> bool {
    false
}

/// RXNE clears when DR is read: nothing to acknowledge.
pub fn clear_rx_interrupt() {}

/// Masks the USART1 line in the NVIC (not RXNEIE: QEMU's USART model keeps its line asserted
/// while RXNE is set, which livelocks an RXNEIE mask).
pub fn pause_rx() {
    cortex_m::peripheral::NVIC::mask(crate::uart::Irq(RX_IRQ));
}

/// Unmasks the USART1 line in the NVIC.
pub fn resume_rx() {
    // SAFETY: the handler for this IRQ only touches the receive queue's producer (behind a
    // critical section), atomics and USART1, so unmasking it breaks no critical section.
    unsafe { cortex_m::peripheral::NVIC::unmask(crate::uart::Irq(RX_IRQ)) };
}
