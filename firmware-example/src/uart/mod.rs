//! Interrupt-driven UART receive shared by the boards; the register access lives in
//! [`hw`] (CMSDK APB UART0 of the QEMU `mps2-an385`/`mps2-an386` boards by default,
//! STM32F4 USART1 with the `board-stm32f405` feature).
//!
//! The RX interrupt moves bytes from the UART's one-byte data register into a `heapless`
//! SPSC queue (the interrupt is the single producer, [`Uart0`] the single consumer). When the
//! queue is full:
//! * CMSDK UART ([`hw::HOLD_WHEN_FULL`]): the interrupt handler stops taking bytes and masks
//!   the RX interrupt; the consumer unmasks it once it has made room (back-pressure). The byte
//!   waits in the data register meanwhile. QEMU's emulated line then simply waits (lossless);
//!   on real hardware a following byte sets the UART's RX-overrun flag, which is counted.
//! * STM32 USART: the byte is read and dropped, and counted as an overrun (a real USART would
//!   overrun anyway; QEMU's model keeps its interrupt line high while RXNE is set even with
//!   RXNEIE masked, so holding the byte would livelock there).
//!
//! Every lost byte is counted in [`Uart0::overruns`]: a loss is never silent.

use core::cell::RefCell;
use core::convert::Infallible;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use cortex_m::interrupt::InterruptNumber;
use critical_section::{CriticalSection, Mutex};
use heapless::spsc::{Consumer, Producer, Queue};

#[cfg(not(feature = "board-stm32f405"))]
#[path = "cmsdk.rs"]
pub mod hw;
#[cfg(feature = "board-stm32f405")]
#[path = "stm32f4.rs"]
pub mod hw;

/// NVIC interrupt number of the receive interrupt.
pub const RX_IRQ: u16 = hw::RX_IRQ;

/// Capacity of the receive queue in bytes (the queue holds `N - 1` of its `N` slots).
pub const RX_QUEUE_BYTES: usize = 512 - 1;

/// Producer end of the receive queue, owned by the RX interrupt once [`Uart0::take`] ran.
static PRODUCER: Mutex<RefCell<Option<Producer<'static, u8>>>> = Mutex::new(RefCell::new(None));
/// Bytes lost: hardware RX-overrun events plus bytes dropped on a full queue.
static OVERRUNS: AtomicU32 = AtomicU32::new(0);
/// Times the interrupt stopped on a full queue (back-pressure, no loss).
static STALLS: AtomicU32 = AtomicU32::new(0);
/// The RX interrupt is masked because the queue was full.
static PAUSED: AtomicBool = AtomicBool::new(false);

/// Single-core counter increment that also works on `thumbv6m` (no atomic read-modify-write).
fn bump(counter: &AtomicU32) {
    counter.store(
        counter.load(Ordering::Relaxed).wrapping_add(1),
        Ordering::Relaxed,
    );
}

#[derive(Clone, Copy)]
struct Irq(u16);

// SAFETY: `number` returns the board's UART interrupt number (`hw::RX_IRQ`), a valid
// interrupt of its NVIC.
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// Moves received bytes from the data register into the queue until the register is empty;
/// on a full queue holds the byte and masks the RX interrupt, or drops and counts it (see the
/// module doc). Runs in the interrupt or in a critical section, so it never races itself.
fn service_rx(cs: CriticalSection<'_>) {
    if hw::take_overrun() {
        bump(&OVERRUNS);
    }
    let mut producer = PRODUCER.borrow_ref_mut(cs);
    let Some(producer) = producer.as_mut() else {
        return;
    };
    while hw::rx_full() {
        if !producer.ready() {
            if hw::HOLD_WHEN_FULL {
                hw::set_rx_interrupt(false);
                PAUSED.store(true, Ordering::Release);
                bump(&STALLS);
                return;
            }
            // This UART cannot hold the byte with its interrupt masked: drop it, counted.
            let _ = hw::read_data();
            bump(&OVERRUNS);
            continue;
        }
        let byte = hw::read_data();
        // Cannot fail: `ready()` was checked just above and only this code enqueues.
        let _ = producer.enqueue(byte);
    }
}

/// Body of the RX interrupt (dispatched from `DefaultHandler`, IRQ [`RX_IRQ`]).
pub fn on_rx_interrupt() {
    hw::clear_rx_interrupt();
    critical_section::with(service_rx);
}

/// The board's NAV440 UART with interrupt-driven receive. Created once by [`Uart0::take`].
pub struct Uart0 {
    rx: Consumer<'static, u8>,
}

impl Uart0 {
    /// Configures the board's UART for `baud` Bd 8N1 (QEMU ignores the rate), enables TX,
    /// RX and the RX interrupt, and unmasks it in the NVIC. `None` if called a second time.
    pub fn take(baud: u32) -> Option<Self> {
        let queue: &'static mut Queue<u8, { RX_QUEUE_BYTES + 1 }> =
            cortex_m::singleton!(: Queue<u8, { RX_QUEUE_BYTES + 1 }> = Queue::new())?;
        let (producer, consumer) = queue.split();
        critical_section::with(|cs| PRODUCER.borrow(cs).replace(Some(producer)));
        hw::init(baud);
        // SAFETY: the handler for this IRQ only touches PRODUCER (behind a critical section),
        // the atomics above and the UART's registers, so unmasking it cannot break a critical
        // section of the caller.
        unsafe { cortex_m::peripheral::NVIC::unmask(Irq(RX_IRQ)) };
        Some(Self { rx: consumer })
    }

    /// Bytes lost since start: RX-overrun events flagged by the UART hardware plus bytes
    /// dropped on a full queue (STM32 backend). 0 in the QEMU mps2 runs.
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
        if n > 0 && PAUSED.load(Ordering::Acquire) {
            critical_section::with(|cs| {
                PAUSED.store(false, Ordering::Release);
                hw::set_rx_interrupt(true);
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
    type Error = Infallible;
}

impl embedded_io::Read for Uart0 {
    /// Blocks (in `wfi`) until at least one byte is available, then returns what is queued.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
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

impl embedded_hal_nb::serial::ErrorType for Uart0 {
    type Error = Infallible;
}

impl embedded_hal_nb::serial::Read<u8> for Uart0 {
    /// One byte from the queue, or `WouldBlock` when it is empty.
    fn read(&mut self) -> nb::Result<u8, Infallible> {
        let mut b = [0u8; 1];
        if self.drain(&mut b) == 1 {
            Ok(b[0])
        } else {
            Err(nb::Error::WouldBlock)
        }
    }
}
