//! Self-check of the failure path: panics at once. `cargo xtask ci` runs it under QEMU and
//! expects exit status 1 with the panic message on stderr (a panic must end a run, not hang it).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use firmware_example as _;

#[entry]
fn main() -> ! {
    let items: [u8; 0] = [];
    let i = core::hint::black_box(3usize);
    // An out-of-bounds index, as a library bug would produce.
    let x = items[i];
    panic!("panic_check: unreachable, read {x}");
}
