//! Raspberry Pi Pico (RP2040, Cortex-M0+, `thumbv6m-none-eabi`; feature `board-rp-pico`) on
//! `rp2040-hal` 0.12: clocks, pins and UARTs are set up by the HAL. Built, linked and
//! memory-map checked; QEMU has no RP2040 board, so it is not emulated.
//!
//! * Output: defmt frames into the RTT up-channel `defmt`, read by probe-rs (a Debug Probe or
//!   a second Pico running debugprobe on SWD).
//! * Time base: SysTick on the core clock (125 MHz), [`crate::time`].
//! * Memory map: generated from `boards/src/description.rs` (boot2 at `0x1000_0000`, vector
//!   table at `0x1000_0100`, 256 KiB of striped SRAM at `0x2000_0000`).
//! * Probe: `probe-rs run --chip RP2040` (`cargo run`, through `cargo xtask flash`).
//!
//! * Clocks: the HAL's `init_clocks_and_plls` from the Pico's 12 MHz crystal: `clk_sys` =
//!   125 MHz (the core clock, SysTick's clock with CLKSOURCE = processor), `clk_peri` = `clk_sys`
//!   (the UARTs' clock, which the baud dividers are computed from).
//! * NAV440 link: UART0 (PL011), TX GP0, RX GP1 (RX with the pad's pull-up, so an unconnected
//!   line idles high instead of receiving breaks), 8N1, FIFOs on (32 bytes each way), interrupt
//!   = `UART0_IRQ` (IRQ 20). The UART raises it when the RX FIFO holds 4 bytes (RXIM,
//!   watermark 1/8) or when it holds fewer and the line has been quiet for 32 bit times (RTIM);
//!   both clear as the FIFO is drained, so there is nothing to acknowledge.
//! * Control channel (test harness only): UART1, TX GP4, RX GP5, 115200 Bd, polled.
//! * The second-stage bootloader [`BOOT2_FIRMWARE`] (W25Q080 flash of the Pico) sits in
//!   `.boot2`, which the board's memory map places at 0x1000_0000.
//!
//! The run-time baud change goes through the HAL without resetting the UART
//! (`UartPeripheral::disable`, then `enable` with the new rate, inside a critical section):
//! the RX FIFO's contents, the interrupt mask and the FIFO watermark survive it.
//! (`UartPeripheral::new` would reset the block and flush the RX FIFO, so it is not used.)
//!
//! The receive side (the free functions, called by the parent's RX interrupt or inside a
//! critical section) reads UART0's FR/DR/RSR registers directly: the HAL's `Reader` folds the
//! per-byte line errors and the sticky overrun flag into one error type that cannot tell a
//! good byte from a lost one the way [`poll_rx`]/[`take_overrun`] need.

use core::sync::atomic::{AtomicBool, Ordering};
use fugit::{HertzU32, RateExtU32};
use rp2040_hal::{
    clocks::{init_clocks_and_plls, Clock},
    gpio::{
        bank0::{Gpio0, Gpio1, Gpio4, Gpio5},
        FunctionUart, Pin, Pins, PullNone, PullUp,
    },
    pac,
    uart::{DataBits, Enabled, FifoWatermark, StopBits, UartConfig, UartPeripheral},
    Sio, Watchdog,
};

/// Second-stage bootloader for the Pico's W25Q080 QSPI flash: the boot ROM copies these 256
/// bytes from the start of flash into SRAM and runs them to set up execute-in-place. The
/// memory map places `.boot2` at 0x1000_0000 and names this symbol in `EXTERN(...)`, so the
/// linker keeps it although no code refers to it.
// SAFETY (`no_mangle`): no other symbol of the image is named `BOOT2_FIRMWARE`.
#[unsafe(link_section = ".boot2")]
#[unsafe(no_mangle)]
#[used]
pub static BOOT2_FIRMWARE: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

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

/// Never emulated: no semihosting host (a semihosting call without a debugger faults).
pub fn host_present() -> bool {
    false
}

/// NVIC number of the UART0 interrupt (`UART0_IRQ`).
pub const RX_IRQ: u16 = 20;
const _: () = assert!(pac::Interrupt::UART0_IRQ as u16 == RX_IRQ);

/// Frequency of the Pico's crystal oscillator, Hz.
pub const XOSC_CRYSTAL_FREQ: u32 = 12_000_000;

/// Baud rate of the control channel.
const CONTROL_BAUD: u32 = 115_200;

/// Largest deviation (per mille) of the rate the PL011 dividers make from the requested one
/// that [`Tx::set_baud`] and [`init`] accept. The fractional divider (1/64 steps) keeps every
/// rate from 120 Bd to 7.8 MBd well inside it at 125 MHz; the limit only catches the HAL's
/// rounding of a fraction up to 64/64, which its 6-bit register field stores as 0.
const BAUD_TOLERANCE_PERMILLE: u64 = 20;

type NavPins = (
    Pin<Gpio0, FunctionUart, PullNone>,
    Pin<Gpio1, FunctionUart, PullUp>,
);
type ControlPins = (
    Pin<Gpio4, FunctionUart, PullNone>,
    Pin<Gpio5, FunctionUart, PullUp>,
);
type NavUart = UartPeripheral<Enabled, pac::UART0, NavPins>;
type ControlUart = UartPeripheral<Enabled, pac::UART1, ControlPins>;

/// UART0 is out of reset and configured (the free functions touch no register before).
static READY: AtomicBool = AtomicBool::new(false);

/// The board's UARTs after [`init`].
pub struct Parts {
    /// Transmit side of UART0 (and what a baud change needs).
    pub tx: Tx,
    /// UART1, polled.
    pub control: Control,
    /// Core clock (`clk_sys`, SysTick's clock source) from the HAL's clocks, Hz.
    pub core_clock_hz: u32,
}

/// 8N1 at `baud` Bd.
fn uart_config(baud: u32) -> UartConfig {
    UartConfig::new(baud.Hz(), DataBits::Eight, None, StopBits::One)
}

/// The rate (Bd) that the PL011 dividers programmed by `rp2040-hal` 0.12 make for `baud` from
/// a UART clock of `clk_hz`, or `None` if the clock cannot make `baud`: 0 Bd, faster than
/// `clk_hz / 16`, so slow that the integer divider would reach 65535 (the HAL silently clamps
/// both ends), or off by more than [`BAUD_TOLERANCE_PERMILLE`].
///
/// Mirrors the HAL's private `calculate_baudrate_dividers`: divisor = `clk / (16 * baud)` in
/// 16.6 fixed point, i.e. `8 * clk / baud` = integer part << 7 | 7 fraction bits, rounded to
/// 6 bits; the fraction is written to a 6-bit field (a rounded-up 64 becomes 0).
pub const fn achieved_baud(baud: u32, clk_hz: u32) -> Option<u32> {
    if baud == 0 {
        return None;
    }
    let div = (clk_hz as u64) * 8 / (baud as u64);
    let int = div >> 7;
    let frac = (div & 0x7f).div_ceil(2) & 0x3f;
    if int == 0 || int >= 65535 {
        return None;
    }
    let achieved = (4 * clk_hz as u64) / (64 * int + frac);
    if achieved.abs_diff(baud as u64) * 1000 > BAUD_TOLERANCE_PERMILLE * baud as u64 {
        return None;
    }
    Some(achieved as u32)
}

// Compile-time checks of the divider arithmetic at the Pico's 125 MHz UART clock.
const _: () = {
    assert!(achieved_baud(38_400, 125_000_000).is_some());
    assert!(achieved_baud(57_600, 125_000_000).is_some());
    assert!(achieved_baud(115_200, 125_000_000).is_some());
    assert!(achieved_baud(230_400, 125_000_000).is_some());
    assert!(achieved_baud(921_600, 125_000_000).is_some());
    assert!(achieved_baud(7_812_500, 125_000_000).is_some());
    assert!(achieved_baud(7_812_501, 125_000_000).is_none());
    assert!(achieved_baud(119, 125_000_000).is_none());
    assert!(achieved_baud(120, 125_000_000).is_some());
    assert!(achieved_baud(0, 125_000_000).is_none());
};

/// Starts the crystal and PLLs (125 MHz system clock), sets up UART0 for `baud` Bd 8N1 on
/// GP0/GP1 with its RX interrupt enabled in the UART (the NVIC is the caller's business) and
/// UART1 on GP4/GP5 for the control channel. `None` if the peripherals were already taken
/// (a second call), the clocks failed to start, or the clock cannot make a rate.
pub fn init(baud: u32) -> Option<Parts> {
    let mut dp = pac::Peripherals::take()?;
    let mut watchdog = Watchdog::new(dp.WATCHDOG);
    let clocks = init_clocks_and_plls(
        XOSC_CRYSTAL_FREQ,
        dp.XOSC,
        dp.CLOCKS,
        dp.PLL_SYS,
        dp.PLL_USB,
        &mut dp.RESETS,
        &mut watchdog,
    )
    .ok()?;
    let uart_clock: HertzU32 = clocks.peripheral_clock.freq();
    achieved_baud(baud, uart_clock.to_Hz())?;
    achieved_baud(CONTROL_BAUD, uart_clock.to_Hz())?;

    let sio = Sio::new(dp.SIO);
    let pins = Pins::new(dp.IO_BANK0, dp.PADS_BANK0, sio.gpio_bank0, &mut dp.RESETS);
    let nav_pins: NavPins = (pins.gpio0.reconfigure(), pins.gpio1.reconfigure());
    let mut nav = UartPeripheral::new(dp.UART0, nav_pins, &mut dp.RESETS)
        .enable(uart_config(baud), uart_clock)
        .ok()?;
    nav.set_rx_watermark(FifoWatermark::Bytes4);
    nav.enable_rx_interrupt();

    let control_pins: ControlPins = (pins.gpio4.reconfigure(), pins.gpio5.reconfigure());
    let control = UartPeripheral::new(dp.UART1, control_pins, &mut dp.RESETS)
        .enable(uart_config(CONTROL_BAUD), uart_clock)
        .ok()?;

    READY.store(true, Ordering::Release);
    Some(Parts {
        tx: Tx {
            uart: Some(nav),
            uart_clock,
        },
        control: Control { uart: control },
        core_clock_hz: clocks.system_clock.freq().to_Hz(),
    })
}

/// UART0's registers, or `None` before [`init`] configured it (a peripheral still held in
/// reset must not be accessed).
fn nav_regs() -> Option<&'static pac::uart0::RegisterBlock> {
    if !READY.load(Ordering::Acquire) {
        return None;
    }
    // SAFETY: UART0's register block is at a fixed address for the whole program. The HAL's
    // `UartPeripheral` in `Tx` owns it, but through this reference the receive side only
    // reads FR, RSR and DR (a DR read pops the RX FIFO, which only the receive side does) and
    // writes ECR; `Tx` writes DR (the TX FIFO) and, in `set_baud` inside a critical section,
    // CR/IBRD/FBRD/LCR_H/DMACR. The registers are volatile cells, so shared access is sound.
    Some(unsafe { &*pac::UART0::ptr() })
}

/// Transmit side of UART0, plus what a baud change needs.
pub struct Tx {
    /// `None` only inside [`Tx::set_baud`] (or after a failed re-enable, which cannot happen
    /// for a rate that passed [`achieved_baud`]).
    uart: Option<NavUart>,
    /// `clk_peri`, the UARTs' clock.
    uart_clock: HertzU32,
}

impl Tx {
    /// Puts `byte` into the TX FIFO if it has room; `false` if it is full.
    pub fn try_write(&mut self, byte: u8) -> bool {
        match self.uart.as_ref() {
            // `write_raw` returns `Err(WouldBlock)` if the FIFO was full and nothing was written.
            Some(uart) => uart.write_raw(&[byte]).is_ok(),
            None => false,
        }
    }

    /// The transmitter is completely idle: TX FIFO empty and the last stop bit sent (the
    /// PL011's BUSY flag is set from the moment the TX FIFO is non-empty until then).
    pub fn is_idle(&self) -> bool {
        match self.uart.as_ref() {
            Some(uart) => !uart.uart_is_busy(),
            None => true,
        }
    }

    /// Switches UART0 to `baud` Bd: waits for the bytes in flight, then disables and
    /// re-enables the UART through the HAL with the new dividers, in a critical section.
    /// Neither resets the block: bytes waiting in the RX FIFO, the RX interrupt enable and
    /// the FIFO watermark stay. Fails (and leaves the rate unchanged) for a rate the 125 MHz
    /// UART clock cannot make (see [`achieved_baud`]).
    ///
    /// A byte that is being *received* while the dividers change may be garbled (the PL011
    /// has no receive-busy flag to wait for): [`poll_rx`] then reports it as `Lost`.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), crate::uart::BaudError> {
        let err = crate::uart::BaudError { baud };
        achieved_baud(baud, self.uart_clock.to_Hz()).ok_or(err)?;
        while !self.is_idle() {}
        critical_section::with(|_| {
            let uart = self.uart.take().ok_or(err)?;
            // `disable` clears UARTEN/TXE/RXE only; `enable` writes IBRD/FBRD, then LCR_H (8N1,
            // FIFOs on: the write that latches the dividers; FEN stays set, so the FIFOs are
            // not flushed), then CR. IMSC and IFLS are not touched.
            let uart = uart
                .disable()
                .enable(uart_config(baud), self.uart_clock)
                .map_err(|_| err)?;
            self.uart = Some(uart);
            Ok(())
        })
    }
}

/// UART1, the control channel, read by polling.
pub struct Control {
    uart: ControlUart,
}

impl Control {
    /// One received byte, if any (a framing, parity or break error drops the byte; a byte
    /// that carries the overrun flag is itself good and is returned).
    pub fn try_read(&mut self) -> Option<u8> {
        let mut byte = [0u8; 1];
        match self.uart.read_raw(&mut byte) {
            Ok(n) if n > 0 => Some(byte[0]),
            Ok(_) | Err(nb::Error::WouldBlock) => None,
            Err(nb::Error::Other(e)) => e.discarded.first().copied(),
        }
    }
}

/// A received byte waits in UART0's RX FIFO.
pub fn rx_full() -> bool {
    nav_regs().is_some_and(|uart| uart.uartfr().read().rxfe().bit_is_clear())
}

/// Pops one byte from UART0's RX FIFO. A byte received with a framing, parity or break error
/// is `Lost`. The overrun flag that the PL011 attaches to the first byte written after an
/// overflow marks a *good* byte (the lost one never reached the FIFO): that byte is returned,
/// and the loss is reported once by [`take_overrun`].
pub fn poll_rx() -> crate::uart::RxPoll {
    let Some(uart) = nav_regs() else {
        return crate::uart::RxPoll::Empty;
    };
    if uart.uartfr().read().rxfe().bit_is_set() {
        return crate::uart::RxPoll::Empty;
    }
    let dr = uart.uartdr().read();
    if dr.fe().bit_is_set() || dr.pe().bit_is_set() || dr.be().bit_is_set() {
        crate::uart::RxPoll::Lost
    } else {
        crate::uart::RxPoll::Byte(dr.data().bits())
    }
}

/// `true` once per RX overrun flagged by UART0 (the sticky OE bit of its receive status
/// register, set when a byte arrives with the RX FIFO full) since the last call; clears it.
/// Several overruns between two calls report once.
pub fn take_overrun() -> bool {
    let Some(uart) = nav_regs() else {
        return false;
    };
    if uart.uartrsr().read().oe().bit_is_clear() {
        return false;
    }
    // SAFETY: a write of any value to UARTRSR/UARTECR clears its error flags (RP2040
    // datasheet, UARTRSR); no other field of any register is affected.
    unsafe { uart.uartrsr().write_with_zero(|w| w) };
    true
}

/// Nothing to acknowledge: the RX (FIFO level) and RX-timeout interrupts clear as the FIFO is
/// drained below the watermark / emptied, and while bytes wait they keep the line asserted
/// (so a paused byte raises the interrupt again once the NVIC line is unmasked).
pub fn clear_rx_interrupt() {}

/// Masks the UART0 line in the NVIC (the bytes wait in the RX FIFO, 32 deep; the UART keeps
/// its interrupt asserted, so it becomes pending).
pub fn pause_rx() {
    cortex_m::peripheral::NVIC::mask(crate::uart::Irq(RX_IRQ));
}

/// Unmasks the UART0 line in the NVIC.
pub fn resume_rx() {
    // SAFETY: the handler for this IRQ only touches the receive queue's producer (behind a
    // critical section), atomics and UART0's receive registers, so unmasking it breaks no
    // critical section.
    unsafe { cortex_m::peripheral::NVIC::unmask(crate::uart::Irq(RX_IRQ)) };
}
