//! Links the firmware with cortex-m-rt's `link.x`, the chip's map (`memory.x` for the
//! STM32F405, `memory-f411.x` with feature `stm32f411`) and defmt's `defmt.x`.
//!
//! The linker runs in the workspace root, whose `memory.x` it finds before the search path;
//! that file only includes `nav440-board-memory.x` (see the root `memory.x`). So this script
//! writes this crate's map into `OUT_DIR` under both names: whichever `memory.x` the linker
//! finds, the image gets its chip's map (flash at 0x0800_0000).

use std::{env, fs, path::PathBuf};

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let f405 = env::var_os("CARGO_FEATURE_STM32F405").is_some();
    let f411 = env::var_os("CARGO_FEATURE_STM32F411").is_some();
    if f405 == f411 {
        panic!("firmware-embassy: enable exactly one chip feature: stm32f405 or stm32f411");
    }
    let map = manifest.join(if f411 { "memory-f411.x" } else { "memory.x" });
    println!("cargo:rerun-if-changed={}", map.display());
    println!("cargo:rerun-if-changed=build.rs");
    if !env::var("TARGET").unwrap_or_default().starts_with("thumb") {
        // A host build (e.g. `cargo clippy --workspace` by mistake) gets no linker script.
        return;
    }
    let text = fs::read(&map).expect("the chip's map exists in firmware-embassy/");
    for name in ["memory.x", "nav440-board-memory.x"] {
        fs::write(out.join(name), &text).expect("OUT_DIR writable");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
