//! Links the firmware with cortex-m-rt's `link.x`, the chip's memory map and defmt's
//! `defmt.x`. The chip feature (`stm32f405`, `stm32f411`) is a board's `embassy_feature` in
//! `boards/src/description.rs` (crate `nav440-boards`, included here as a module: its `lib.rs`
//! says why); the map is generated from that board's description, the same map as
//! firmware-example's image of the board.
//!
//! The linker runs in the workspace root, whose `memory.x` it finds before the search path;
//! that file only includes `nav440-board-memory.x` (see the root `memory.x`). So this script
//! writes the map into `OUT_DIR` under both names: whichever `memory.x` the linker finds, the
//! image gets its chip's map (flash at 0x0800_0000).

use std::{env, fs, path::PathBuf};

// The crate nav440-boards, of which this script uses a part.
#[allow(dead_code)]
#[path = "../boards/src/lib.rs"]
mod nav440_boards;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let fail = |e: String| -> ! { panic!("firmware-embassy: {e}") };
    let board =
        nav440_boards::board_of_build(nav440_boards::select_embassy).unwrap_or_else(|e| fail(e));
    println!("cargo:rerun-if-changed=../boards/src");
    println!("cargo:rerun-if-changed=build.rs");
    if !env::var("TARGET").unwrap_or_default().starts_with("thumb") {
        // A host build (e.g. `cargo clippy --workspace` by mistake) gets no linker script.
        return;
    }
    let map = board.linker_map();
    for name in ["memory.x", "nav440-board-memory.x"] {
        fs::write(out.join(name), &map).expect("OUT_DIR writable");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
