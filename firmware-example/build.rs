//! Links the firmware with cortex-m-rt's `link.x` and the workspace's `memory.x`.
//!
//! Only this crate gets the flags (via `cargo:rustc-link-arg-bins`), so no other crate of the
//! workspace is affected. The board profile picks the memory map:
//! * default (QEMU `mps2-an386` / `mps2-an385`): `../memory.x` (1 MiB flash @ 0, 128 KiB RAM @ 0x2000_0000);
//! * feature `board-stm32f405`: `memory-stm32f405.x` of this crate (flash @ 0x0800_0000).

use std::{env, fs, path::PathBuf};

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let target = env::var("TARGET").unwrap_or_default();
    let stm32 = env::var_os("CARGO_FEATURE_BOARD_STM32F405").is_some();
    let src = if stm32 {
        manifest.join("memory-stm32f405.x")
    } else {
        manifest.join("..").join("memory.x")
    };
    println!("cargo:rerun-if-changed={}", src.display());
    println!("cargo:rerun-if-changed=build.rs");
    if !target.starts_with("thumb") {
        // Host builds (e.g. `cargo clippy --workspace` by mistake) get no linker script.
        return;
    }
    // Copy into OUT_DIR so that exactly one `memory.x` is on the search path.
    let memory = fs::read(&src).expect("memory map file exists");
    fs::write(out.join("memory.x"), memory).expect("OUT_DIR writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    // The defmt table (interned format strings) the host decoder reads from the ELF.
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
