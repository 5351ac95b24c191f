//! The embassy example: an `embassy-executor` task configures the NAV440 with the async
//! driver (`nav440_proto::boot::boot_async`), then estimates from its stream, printing the same
//! CSV rows as the blocking firmware (`src/main.rs`). The pipeline's stream watchdog reports
//! with the blocking firmware's messages (`nav440_pipeline::report`): a silence, frozen time
//! stamps, another packet rate or type, the counters every 10 s of stream. After a silence the
//! unit is configured again (a boot that fails exits with status 2); a frame of another type
//! (a unit reset) ends the run with status 5, as on the blocking firmware's emulated boards.
//!
//! Build: `cargo build -p firmware-example --release --target thumbv7em-none-eabihf
//! --features embassy --bin embassy`. Run against the simulated unit on QEMU `mps2-an386`:
//! `cargo xtask embassy` (what CI runs: its CSV must equal `nav440 estimate` on the bytes
//! the unit streamed).
//!
//! On a real board with `embassy-stm32`, the two adapters below are not needed: its
//! `BufferedUart` implements the `embedded-io(-async)` 0.7 traits (embassy-stm32 0.6; a HAL
//! on 0.6 goes through `nav440_proto::driver::Compat06` with nav440-proto's `embedded-io-06`
//! feature) and `embassy_time::Delay` implements `embedded_hal_async::delay::DelayNs`. The
//! workspace's `firmware-embassy` crate is that firmware for the STM32F405 (`cargo xtask
//! embassy-stm32`); its boot code, shown in the docs of `nav440_proto::driver::asynch`, maps
//! `set_baudrate`'s `usart::ConfigError` into the UART's error type.
//!
//! Here the board is the emulated one of the blocking firmware (CMSDK UART0 with its
//! interrupt-fed receive queue, SysTick at 1 kHz), adapted to the async traits by polling:
//! a read with no byte ready and an unfinished delay wake their task at once, so the
//! executor polls again (a real HAL wakes it from the interrupt instead).
#![no_std]
#![no_main]

use core::future::poll_fn;
use core::task::Poll;

use embassy_executor::Spawner;
use firmware_example::uart::{Board, EndMessage, Uart0};
use firmware_example::{board, host, out, pipeline, time};
use nav440_pipeline::report::{self, Flow};
use nav440_proto::boot::{self, Options, Target};
use nav440_proto::driver::{AsyncDriver, Timing};
use nav440_proto::Baud;

/// A2 at 100 Hz at 57600 Bd, checked against the unit's byte budget at compile time.
const TARGET: Target = Target::DEFAULT;
const _: () = assert!(TARGET.fits_budget());

/// The UART as `embedded_io_async` sees it.
struct AsyncUart(Uart0);

impl embedded_io::ErrorType for AsyncUart {
    type Error = firmware_example::uart::Error;
}

impl embedded_io::ReadReady for AsyncUart {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        embedded_io::ReadReady::read_ready(&mut self.0)
    }
}

impl embedded_io_async::Read for AsyncUart {
    /// Waits (yielding to the executor) until a byte is ready, then reads what is there.
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        poll_fn(|cx| match embedded_io::ReadReady::read_ready(&mut self.0) {
            Ok(true) => Poll::Ready(Ok(())),
            Ok(false) => {
                cx.waker().wake_by_ref();
                Poll::Pending
            }
            Err(e) => Poll::Ready(Err(e)),
        })
        .await?;
        embedded_io::Read::read(&mut self.0, buf)
    }
}

impl embedded_io_async::Write for AsyncUart {
    /// The emulated UART takes bytes at once: the blocking write never waits.
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        embedded_io::Write::write(&mut self.0, buf)
    }

    async fn flush(&mut self) -> Result<(), Self::Error> {
        embedded_io::Write::flush(&mut self.0)
    }
}

/// `embedded_hal_async::delay::DelayNs` on the SysTick time base (resolution 1 ms, so a
/// delay lasts until the microsecond clock has passed its end).
struct TickDelay;

impl embedded_hal_async::delay::DelayNs for TickDelay {
    async fn delay_ns(&mut self, ns: u32) {
        let until = time::now_us() + u64::from(ns.div_ceil(1000));
        poll_fn(|cx| {
            if time::now_us() >= until {
                Poll::Ready(())
            } else {
                cx.waker().wake_by_ref();
                Poll::Pending
            }
        })
        .await;
    }
}

fn fail(status: u32, what: core::fmt::Arguments<'_>) -> ! {
    host::stderr(format_args!("firmware: {what}\n"));
    host::exit_code(status)
}

#[embassy_executor::main]
async fn main(_spawner: Spawner) {
    let Some(core) = cortex_m::Peripherals::take() else {
        fail(1, format_args!("core peripherals already taken"))
    };
    let Some(board) = Board::take(38_400) else {
        fail(1, format_args!("UARTs already taken"))
    };
    let Board {
        nav,
        mut control,
        core_clock_hz,
    } = board;
    let _blocking_delay = time::start(core.SYST, core_clock_hz);
    if let Err(e) = pipeline::check() {
        fail(1, format_args!("bank configuration rejected: {e:?}"))
    }
    let mut pipe = pipeline::new();
    let mut uart = AsyncUart(nav);
    let mut end = EndMessage::default();
    let mut total: Option<u64> = None;
    let mut first = true;
    loop {
        // 1. Configure the unit: the async driver, the same sequence as the blocking firmware.
        let mut driver = AsyncDriver::new(uart);
        driver.set_timing(Timing {
            reply_timeout_ms: 500,
            ..Timing::DEFAULT
        });
        let set_baud = |u: &mut AsyncUart, b: Baud| {
            u.0.set_baud(b.bits_per_second())
                .map_err(firmware_example::uart::Error::from)
        };
        let report = match boot::boot_async(
            &mut driver,
            &TARGET,
            &Options::DEFAULT,
            &mut TickDelay,
            set_baud,
        )
        .await
        {
            Ok(r) => r,
            Err(e) => fail(2, format_args!("boot failed: {e}")),
        };
        host::stderr(format_args!(
            "firmware: unit configured (embassy, async driver): {} at {} Bd (unit was at {} Bd); boot_frames={} boot_ms={}\n",
            TARGET.packet,
            report.baud.bits_per_second(),
            report.unit_baud.bits_per_second(),
            report.unsolicited_frames,
            time::now_ms(),
        ));

        // 2. Estimate from the first byte after the read-back until the harness's byte count,
        // or until the watchdog sees a silence (configure again). The rows as defmt messages,
        // like the blocking firmware (`firmware_example::out`), the header once.
        if first {
            out::header();
            first = false;
        }
        pipe.watch(TARGET.packet, TARGET.rate, time::now_ms());
        let mut pending = [0u8; nav440_proto::MAX_FRAME];
        let n = driver.pending_bytes().len().min(pending.len());
        pending[..n].copy_from_slice(&driver.pending_bytes()[..n]);
        uart = driver.release();
        if !process(&mut pipe, &pending[..n], &uart.0) {
            continue;
        }
        let mut buf = [0u8; 64];
        loop {
            let read = uart.0.bytes_read();
            if total.is_some_and(|n| read >= n) {
                finish(&mut pipe, &uart.0, total.unwrap_or(0))
            }
            if embedded_io::ReadReady::read_ready(&mut uart).unwrap_or(false) {
                let room = total.map_or(buf.len() as u64, |n| n - read);
                let want = (buf.len() as u64).min(room) as usize;
                let n = match embedded_io_async::Read::read(&mut uart, &mut buf[..want]).await {
                    Ok(n) => n,
                    Err(e) => fail(1, format_args!("UART error: {e:?}")),
                };
                if !process(&mut pipe, &buf[..n], &uart.0) {
                    break;
                }
            } else if let Some(message) = total.is_none().then(|| end.poll(&mut control)).flatten()
            {
                total = Some(
                    message
                        .unwrap_or_else(|m| fail(1, format_args!("bad control message {m:02x?}"))),
                );
            } else if total.is_none() && report::silence(&mut pipe, time::now_ms()) {
                // The unit went silent with the link open (reported): configure it again.
                break;
            } else {
                embassy_futures::yield_now().await;
            }
        }
    }
}

/// Feeds received bytes through the pipeline and its watch (`nav440_pipeline::report::feed`:
/// rows, and every stream fault as it is seen); prints the counters every 10 s of stream.
/// `false`: the unit reset (another packet type), configure it again (the emulated board ends
/// the run with status 5, as the blocking firmware does).
fn process(pipe: &mut pipeline::Pipeline, bytes: &[u8], uart: &Uart0) -> bool {
    let flow = report::feed(pipe, bytes, time::now_ms(), &mut out::row)
        .unwrap_or_else(|e| fail(1, format_args!("bank: {e:?}")));
    match flow {
        Flow::Go => true,
        Flow::Counters(stream_s) => {
            report::periodic(stream_s);
            out::summary(pipe, uart, uart.bytes_read());
            true
        }
        Flow::Reset if board::RETRY_FOREVER => false,
        Flow::Reset => host::exit_code(5),
    }
}

fn finish(pipe: &mut pipeline::Pipeline, uart: &Uart0, unit_bytes: u64) -> ! {
    if let Err(e) = report::finish(pipe, &mut out::row) {
        fail(1, format_args!("bank: {e:?}"))
    }
    out::summary(pipe, uart, unit_bytes);
    host::exit(true)
}
