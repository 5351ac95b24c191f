//! Instruction-count benchmark (run by `cargo xtask bench` under `qemu -icount shift=6`).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use firmware_example::{cycles::Counter, host};

#[entry]
fn main() -> ! {
    let Some(p) = cortex_m::Peripherals::take() else {
        host::exit(false)
    };
    let counter = Counter::new(p.SYST);
    let overhead = counter.overhead();
    let data = [0x55u8; 4096];
    let crc = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740);
    let (n, c) = counter.measure(|| crc.checksum(core::hint::black_box(&data)));
    host::stderr(format_args!(
        "overhead={overhead} crc {} bytes: {} instr ({}/byte) {c:#x}\n",
        data.len(),
        n - overhead,
        (n - overhead) as f32 / data.len() as f32
    ));
    host::exit(true)
}
