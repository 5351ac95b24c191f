//! Firmware example: NAV440 bytes on UART0 -> parser -> estimator bank -> CSV (semihosting).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use embedded_io::Read as _;
use firmware_example::{host, uart::Uart0};

#[entry]
fn main() -> ! {
    let Some(mut uart) = Uart0::take(16) else {
        host::stderr(format_args!("firmware: UART0 already taken\n"));
        host::exit(false)
    };
    let mut hdr = [0u8; 8];
    let mut got = 0;
    while got < 8 {
        let Ok(n) = uart.read(&mut hdr[got..]);
        got += n;
    }
    let len = u32::from_le_bytes([hdr[4], hdr[5], hdr[6], hdr[7]]) as usize;
    let mut remaining = len;
    let mut buf = [0u8; 64];
    let crc = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);
    let mut digest = crc.digest();
    while remaining > 0 {
        let want = remaining.min(buf.len());
        let Ok(n) = uart.read(&mut buf[..want]);
        digest.update(&buf[..n]);
        remaining -= n;
    }
    host::stderr(format_args!(
        "bytes={len} crc={:#06x} overruns={} stalls={}\n",
        digest.finalize(),
        uart.overruns(),
        uart.stalls()
    ));
    host::exit(true)
}
