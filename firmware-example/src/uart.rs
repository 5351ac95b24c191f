//! The NAV440 UART shared by the boards: interrupt-driven receive, polled transmit, a
//! run-time baud change, and the harness's control channel. The hardware access lives in
//! the board module ([`crate::board`]: CMSDK APB UART0/UART1 of the QEMU `mps2` boards, the
//! STM32F4 USART1/USART2 through `stm32f4xx-hal`, the RP2040's UART0/UART1 through
//! `rp2040-hal`).
//!
//! [`Uart0`] implements `embedded_io::{Read, ReadReady, Write, WriteReady}` (0.7) and
//! `embedded_hal_nb::serial::{Read, Write}`; [`Uart0::set_baud`] changes the line rate
//! (the CMSDK model ignores the rate but keeps the API).
//!
//! The RX interrupt moves bytes from the UART's data register into a `heapless` SPSC queue
//! (the interrupt is the single producer, [`Uart0`] the single consumer). When the queue is
//! full the interrupt handler leaves the byte in the data register and masks the receive
//! interrupt (`hw::pause_rx`: in the UART on CMSDK, in the NVIC on the STM32, whose USART
//! model keeps its line asserted while a byte waits, so masking RXNEIE there livelocked); the
//! consumer unmasks it once it has made room and takes the waiting byte itself
//! (back-pressure). QEMU's emulated lines then simply wait (lossless); on real hardware a
//! following byte sets the UART's overrun flag, which is counted.
//!
//! Every lost byte is counted in [`Uart0::overruns`]: a loss is never silent.

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use cortex_m::interrupt::InterruptNumber;
use critical_section::{CriticalSection, Mutex};
use heapless::spsc::{Consumer, Producer, Queue};

use crate::board as hw;

pub use hw::Control;

/// NVIC interrupt number of the receive interrupt.
pub const RX_IRQ: u16 = hw::RX_IRQ;

/// What one poll of the receive data register gave.
pub enum RxPoll {
    /// Nothing received.
    Empty,
    /// One byte.
    Byte(u8),
    /// A byte was lost to a line error (overrun, framing, noise, parity).
    Lost,
}

/// The UART cannot run at this rate (with the board's clocks).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct BaudError {
    /// The rejected rate, Bd.
    pub baud: u32,
}

/// Error of the [`Uart0`] traits: only a baud change can fail (reads and writes cannot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Error {
    /// See [`BaudError`].
    Baud(BaudError),
}

impl From<BaudError> for Error {
    fn from(e: BaudError) -> Self {
        Error::Baud(e)
    }
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Baud(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for Error {}

impl embedded_io::Error for Error {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::InvalidInput
    }
}

impl embedded_hal_nb::serial::Error for Error {
    fn kind(&self) -> embedded_hal_nb::serial::ErrorKind {
        embedded_hal_nb::serial::ErrorKind::Other
    }
}

impl core::fmt::Display for BaudError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "the UART cannot run at {} Bd", self.baud)
    }
}

/// Capacity of the receive queue in bytes (the queue holds `N - 1` of its `N` slots, the
/// board's).
pub const RX_QUEUE_BYTES: usize = crate::board::RX_QUEUE_SLOTS - 1;

/// Producer end of the receive queue, owned by the RX interrupt once [`Board::take`] ran.
static PRODUCER: Mutex<RefCell<Option<Producer<'static, u8>>>> = Mutex::new(RefCell::new(None));
/// Bytes lost: RX line errors (overrun, framing, noise, parity) flagged by the hardware.
static OVERRUNS: AtomicU32 = AtomicU32::new(0);
/// Times the interrupt stopped on a full queue (back-pressure, no loss).
static STALLS: AtomicU32 = AtomicU32::new(0);
/// The RX interrupt is masked in the NVIC because the queue was full.
static PAUSED: AtomicBool = AtomicBool::new(false);

/// Single-core counter increment that also works on `thumbv6m` (no atomic read-modify-write).
fn bump(counter: &AtomicU32) {
    counter.store(
        counter.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

/// The receive interrupt's NVIC line.
#[derive(Clone, Copy)]
pub struct Irq(pub u16);

// SAFETY: `number` returns the board's UART interrupt number (`hw::RX_IRQ`), a valid
// interrupt of its NVIC.
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// Moves received bytes from the data register into the queue until the register is empty;
/// on a full queue holds the byte and masks the RX interrupt in the NVIC (see the
/// module doc). Runs in the interrupt or in a critical section, so it never races itself.
fn service_rx(cs: CriticalSection<'_>) {
    if hw::take_overrun() {
        bump(&OVERRUNS);
    }
    // Never borrowed twice (one critical section at a time); `try_borrow_mut` keeps the
    // `BorrowMutError` text, which nothing prints, out of the image.
    let Ok(mut producer) = PRODUCER.borrow(cs).try_borrow_mut() else {
        return;
    };
    let Some(producer) = producer.as_mut() else {
        return;
    };
    loop {
        if !producer.ready() {
            // Queue full: never read the data register now (a byte arriving between a check
            // and the read would have nowhere to go). Hold it and pause if one waits; if none
            // waits yet, the next one raises the interrupt again and lands here.
            if hw::rx_full() {
                hw::pause_rx();
                PAUSED.store(true, Ordering::Release);
                bump(&STALLS);
            }
            return;
        }
        match hw::poll_rx() {
            RxPoll::Empty => return,
            RxPoll::Lost => bump(&OVERRUNS),
            RxPoll::Byte(byte) => {
                // Cannot fail: the queue had room (checked above) and only this code enqueues;
                // counted as lost all the same, should it ever.
                if producer.enqueue(byte).is_err() {
                    bump(&OVERRUNS);
                }
            }
        }
    }
}

/// The harness's end message on the control channel: `N4EN` + the number of bytes the unit
/// sent (u32 LE), taken byte by byte as it arrives (the end of a run under QEMU: see the
/// firmware's `src/main.rs`).
#[derive(Default)]
pub struct EndMessage {
    buf: [u8; 8],
    len: usize,
}

impl EndMessage {
    /// The first four bytes of an end message.
    pub const MAGIC: [u8; 4] = *b"N4EN";

    /// Takes the bytes the control channel has. `None` until all 8 bytes have arrived; then
    /// `Ok(count)`, or `Err(bytes)` when they do not start with [`Self::MAGIC`].
    pub fn poll(&mut self, control: &mut Control) -> Option<Result<u64, [u8; 8]>> {
        while self.len < self.buf.len() {
            self.buf[self.len] = control.try_read()?;
            self.len += 1;
        }
        let [m0, m1, m2, m3, n0, n1, n2, n3] = self.buf;
        Some(if [m0, m1, m2, m3] == Self::MAGIC {
            Ok(u64::from(u32::from_le_bytes([n0, n1, n2, n3])))
        } else {
            Err(self.buf)
        })
    }
}

/// Body of the RX interrupt (dispatched from `DefaultHandler`, IRQ [`RX_IRQ`]).
pub fn on_rx_interrupt() {
    hw::clear_rx_interrupt();
    critical_section::with(service_rx);
}

/// The board's UARTs, from [`Board::take`].
pub struct Board {
    /// The NAV440 link.
    pub nav: Uart0,
    /// The harness's control channel (UART1 on mps2, USART2 on the STM32 profile), polled.
    pub control: Control,
    /// Core clock, Hz (from the HAL's frozen clocks on the STM32 profile).
    pub core_clock_hz: u32,
}

impl Board {
    /// Sets up the board's clocks and UARTs: the NAV440 UART at `baud` Bd 8N1 with TX, RX and
    /// the RX interrupt enabled and unmasked in the NVIC, and the control channel. This is the
    /// first interrupt the firmware enables. `None` if called twice.
    pub fn take(baud: u32) -> Option<Self> {
        let queue: &'static mut Queue<u8, { RX_QUEUE_BYTES + 1 }> =
            cortex_m::singleton!(: Queue<u8, { RX_QUEUE_BYTES + 1 }> = Queue::new())?;
        let (producer, consumer) = queue.split();
        critical_section::with(|cs| {
            // Not borrowed: the interrupt that borrows it is not enabled yet.
            if let Ok(mut slot) = PRODUCER.borrow(cs).try_borrow_mut() {
                *slot = Some(producer);
            }
        });
        let parts = hw::init(baud)?;
        // SAFETY: the handler for this IRQ only touches PRODUCER (behind a critical section),
        // the atomics above and the UART's registers, so unmasking it cannot break a critical
        // section of the caller.
        unsafe { cortex_m::peripheral::NVIC::unmask(Irq(RX_IRQ)) };
        Some(Self {
            nav: Uart0 {
                rx: consumer,
                tx: parts.tx,
                received: 0,
                baud,
            },
            control: parts.control,
            core_clock_hz: parts.core_clock_hz,
        })
    }
}

/// The board's NAV440 UART: interrupt-driven receive, polled transmit. From [`Board::take`].
pub struct Uart0 {
    rx: Consumer<'static, u8>,
    tx: hw::Tx,
    /// Bytes handed to readers since start.
    received: u64,
    /// Line rate in force, Bd.
    baud: u32,
}

impl Uart0 {
    /// Bytes handed to readers (through any read trait) since start.
    pub fn bytes_read(&self) -> u64 {
        self.received
    }

    /// Line rate in force, Bd.
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Changes the line rate to `baud` Bd 8N1 after the byte in flight has been sent. Bytes
    /// already queued are kept. The CMSDK model ignores the rate (the call still succeeds).
    pub fn set_baud(&mut self, baud: u32) -> Result<(), BaudError> {
        self.tx.set_baud(baud)?;
        self.baud = baud;
        Ok(())
    }

    /// Writes one byte, spinning while the transmit register is full.
    fn write_byte(&mut self, byte: u8) {
        while !self.tx.try_write(byte) {
            core::hint::spin_loop();
        }
    }

    /// Bytes lost since start: RX line errors flagged by the UART hardware. 0 under QEMU.
    pub fn overruns(&self) -> u32 {
        OVERRUNS.load(Ordering::Relaxed)
    }

    /// Times the receive queue was full and reception was paused (back-pressure, no loss).
    pub fn stalls(&self) -> u32 {
        STALLS.load(Ordering::Relaxed)
    }

    /// Copies queued bytes into `buf`; resumes reception if it was paused. Returns the count.
    fn drain(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.rx.dequeue() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        self.received += n as u64;
        if n > 0 && PAUSED.load(Ordering::Acquire) {
            critical_section::with(|cs| {
                PAUSED.store(false, Ordering::Release);
                hw::resume_rx();
                // The byte left in the data register raised no new interrupt: take it now.
                service_rx(cs);
            });
        }
        n
    }

    /// Sleeps until an interrupt arrives if the queue is empty (race-free: the check and the
    /// `wfi` run with interrupts masked; a pending interrupt still wakes the core).
    fn wait_for_data(&mut self) {
        cortex_m::interrupt::disable();
        if !self.rx.ready() {
            cortex_m::asm::wfi();
        }
        // SAFETY: re-enables interrupts disabled 3 lines above; no critical section of the
        // caller is open here (this function is never called from one).
        unsafe { cortex_m::interrupt::enable() };
    }
}

impl embedded_io::ErrorType for Uart0 {
    type Error = Error;
}

impl embedded_io::Read for Uart0 {
    /// Blocks (in `wfi`) until at least one byte is available, then returns what is queued.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            let n = self.drain(buf);
            if n > 0 {
                return Ok(n);
            }
            self.wait_for_data();
        }
    }
}

impl embedded_io::ReadReady for Uart0 {
    /// A byte is queued (a `read` would not block).
    fn read_ready(&mut self) -> Result<bool, Error> {
        Ok(self.rx.ready())
    }
}

impl embedded_io::Write for Uart0 {
    /// Blocks until the first byte is in the transmit register, then writes as many more as
    /// the register takes without waiting. Returns the count (0 only for an empty `buf`).
    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        let Some((&first, rest)) = buf.split_first() else {
            return Ok(0);
        };
        self.write_byte(first);
        let mut n = 1;
        for &b in rest {
            if !self.tx.try_write(b) {
                break;
            }
            n += 1;
        }
        Ok(n)
    }

    /// Waits until the transmitter is idle.
    fn flush(&mut self) -> Result<(), Error> {
        while !self.tx.is_idle() {
            core::hint::spin_loop();
        }
        Ok(())
    }
}

impl embedded_io::WriteReady for Uart0 {
    /// The transmit register can take a byte.
    fn write_ready(&mut self) -> Result<bool, Error> {
        Ok(self.tx.is_idle())
    }
}

impl embedded_hal_nb::serial::ErrorType for Uart0 {
    type Error = Error;
}

impl embedded_hal_nb::serial::Write<u8> for Uart0 {
    /// Puts the byte into the transmit register, or `WouldBlock` while it is full.
    fn write(&mut self, byte: u8) -> nb::Result<(), Error> {
        if self.tx.try_write(byte) {
            Ok(())
        } else {
            Err(nb::Error::WouldBlock)
        }
    }

    /// `WouldBlock` until the transmitter is idle.
    fn flush(&mut self) -> nb::Result<(), Error> {
        if self.tx.is_idle() {
            Ok(())
        } else {
            Err(nb::Error::WouldBlock)
        }
    }
}

impl embedded_hal_nb::serial::Read<u8> for Uart0 {
    /// One byte from the queue, or `WouldBlock` when it is empty.
    fn read(&mut self) -> nb::Result<u8, Error> {
        let mut b = [0u8; 1];
        if self.drain(&mut b) == 1 {
            Ok(b[0])
        } else {
            Err(nb::Error::WouldBlock)
        }
    }
}
