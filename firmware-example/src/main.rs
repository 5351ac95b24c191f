//! Firmware example: NAV440 bytes on UART0 -> parser -> estimator bank -> CSV rows on the
//! host's stdout (semihosting), counters on its stderr, then exit status 0.
//!
//! End-of-input convention (emulated boards): the byte stream on UART0 starts with the 4 bytes
//! `N4LP` and the capture's length in bytes as u32 little-endian (`cargo xtask qemu/demo`
//! prepend them); the firmware processes exactly that many bytes, prints its counters and exits.
//! QEMU's UART never signals end-of-file, and a length prefix, unlike a trailer or idle
//! detection, cannot be confused with capture content nor depends on timing. On the emulated
//! boards a stream without the prefix is refused (exit 1) so that a wrong input never hangs a
//! run; with the real-board profile (`board-stm32f405`) it is a live NAV440 stream and the
//! firmware runs until reset.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use embedded_io::Read as _;
use firmware_example::{
    host, pipeline, stack,
    uart::{Board, Uart0},
};

/// Magic at the start of a finite input.
const LENGTH_MAGIC: [u8; 4] = *b"N4LP";

/// NAV440 default baud rate (8N1); QEMU ignores the rate.
const BAUD: u32 = 38_400;

/// Reads the length prefix byte by byte through the `embedded_hal_nb::serial::Read` side of
/// the driver (the capture itself goes through `embedded_io::Read`), polling: 8 bytes, once.
fn read_prefix(uart: &mut Uart0, buf: &mut [u8]) {
    for slot in buf.iter_mut() {
        *slot = loop {
            match embedded_hal_nb::serial::Read::read(uart) {
                Ok(b) => break b,
                Err(nb::Error::WouldBlock) => core::hint::spin_loop(),
                Err(nb::Error::Other(_)) => host::exit(false),
            }
        };
    }
}

#[entry]
fn main() -> ! {
    // UART first: on some UART models (QEMU's STM32 USART) bytes arriving before the
    // receiver is enabled are dropped.
    stack::paint();
    let Some(Board { nav: mut uart, .. }) = Board::take(BAUD) else {
        host::stderr(format_args!("firmware: UART0 already taken\n"));
        host::exit(false)
    };
    let mut pipe = match pipeline::Pipeline::new() {
        Ok(p) => p,
        Err(e) => {
            host::stderr(format_args!(
                "firmware: bank configuration rejected: {e:?}\n"
            ));
            host::exit(false)
        }
    };
    let mut prefix = [0u8; 8];
    read_prefix(&mut uart, &mut prefix);
    let (magic, len) = prefix.split_at(4);
    if magic != LENGTH_MAGIC {
        #[cfg(feature = "board-stm32f405")]
        live(&mut uart, &mut pipe, &prefix);
        #[cfg(not(feature = "board-stm32f405"))]
        {
            host::stderr(format_args!(
                "firmware: input does not start with the N4LP length prefix (got {magic:02x?}); use `cargo xtask qemu FILE`\n"
            ));
            host::exit(false)
        }
    }
    let mut remaining = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
    host::stdout(pipeline::CSV_HEADER.as_bytes());
    host::stdout(b"\n");
    let mut buf = [0u8; 64];
    while remaining > 0 {
        let want = remaining.min(buf.len());
        let n = uart.read(&mut buf[..want]).unwrap_or(0);
        if let Err(e) = pipe.feed(&buf[..n], |row| host::stdout(row.as_bytes())) {
            bank_failed(&e);
        }
        remaining -= n;
    }
    if let Err(e) = pipe.finish(|row| host::stdout(row.as_bytes())) {
        bank_failed(&e);
    }
    let mut line: heapless::String<400> = heapless::String::new();
    let _ = pipe.summary(&mut line, uart.overruns(), uart.stalls());
    host::stderr(format_args!(
        "firmware: {line} stack_peak={}\n",
        stack::peak()
    ));
    host::exit(true)
}

/// The bank cannot run at the measured packet period: report and exit with status 1 (as
/// `nav440 estimate` fails on the same capture).
fn bank_failed(e: &pipeline::ConfigError) -> ! {
    host::stderr(format_args!(
        "firmware: bank configuration rejected for this capture's packet period: {e:?}\n"
    ));
    host::exit(false)
}

/// Real board: a live NAV440 stream (no length prefix) is processed until reset; `first` are
/// the bytes already read while looking for a prefix.
#[cfg(feature = "board-stm32f405")]
fn live(uart: &mut Uart0, pipe: &mut pipeline::Pipeline, first: &[u8]) -> ! {
    host::stdout(pipeline::CSV_HEADER.as_bytes());
    host::stdout(b"\n");
    if let Err(e) = pipe.feed(first, |row| host::stdout(row.as_bytes())) {
        bank_failed(&e);
    }
    let mut buf = [0u8; 64];
    loop {
        let n = uart.read(&mut buf).unwrap_or(0);
        if let Err(e) = pipe.feed(&buf[..n], |row| host::stdout(row.as_bytes())) {
            bank_failed(&e);
        }
    }
}
