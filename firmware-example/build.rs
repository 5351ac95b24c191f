//! Selects the board and links the firmware with cortex-m-rt's `link.x` and the board's memory
//! map, both from the board's description in `boards/src/description.rs` (crate
//! `nav440-boards`, included here as a module: its `lib.rs` says why).
//!
//! * The board: the one of the `board-*` feature, the default board (`mps2`) without one; a
//!   `board-*` feature must name a described board (checked here, as the description itself),
//!   and the target must be one of the board's.
//! * Its module: `board.rs` in `OUT_DIR` defines the macro `board_modules!`, which declares
//!   the modules `src/board/<module>.rs` (and its shared backend module) and the board's
//!   `NAME`; `src/board/mod.rs` includes it and invokes the macro.
//! * Its memory map: cortex-m-rt's `link.x` includes a file named `memory.x`, and the linker
//!   looks for it in its working directory (the workspace root, where the top-level
//!   `memory.x` is) before the search path. So no board map is ever *named* `memory.x`: the
//!   top-level `memory.x` (and a copy of it in `OUT_DIR`, for a build whose working directory
//!   has none) only includes `nav440-board-memory.x`, which this script generates into
//!   `OUT_DIR` from the description. Whatever `memory.x` the linker finds, the image gets its
//!   own board's map.
//!
//! Only this crate gets the flags (via `cargo:rustc-link-arg-bins`), so no other crate of the
//! workspace is affected.

use std::{env, fs, path::PathBuf};

// The crate nav440-boards, of which this script uses a part.
#[allow(dead_code)]
#[path = "../boards/src/lib.rs"]
mod nav440_boards;

/// The name `memory.x` includes (unique to this crate, never in a working directory).
const BOARD_MAP: &str = "nav440-board-memory.x";

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let target = env::var("TARGET").unwrap_or_default();
    let fail = |e: String| -> ! { panic!("firmware-example: {e}") };
    let board = nav440_boards::board_of_build(nav440_boards::select).unwrap_or_else(|e| fail(e));
    let board_dir = manifest.join("src").join("board");
    for m in std::iter::once(board.module()).chain(board.backend.map(str::to_owned)) {
        let path = board_dir.join(format!("{m}.rs"));
        if !path.is_file() {
            fail(format!(
                "board `{}`: no module {}",
                board.name,
                path.display()
            ));
        }
    }
    fs::write(out.join("board.rs"), board.module_decl()).expect("OUT_DIR writable");
    let dispatch = manifest.join("..").join("memory.x");
    println!("cargo:rerun-if-changed={}", dispatch.display());
    println!("cargo:rerun-if-changed=../boards/src");
    println!("cargo:rerun-if-changed=build.rs");
    if !target.starts_with("thumb") {
        // Host builds (e.g. `cargo clippy --workspace` by mistake) get no linker script.
        return;
    }
    if !board.targets.contains(&target.as_str()) {
        fail(format!(
            "board `{}` is built for {}, not {target}",
            board.name,
            board.targets.join(", ")
        ));
    }
    fs::write(out.join(BOARD_MAP), board.linker_map()).expect("OUT_DIR writable");
    let dispatch_text = fs::read_to_string(&dispatch).expect("the top-level memory.x exists");
    assert!(
        dispatch_text.contains(&format!("INCLUDE {BOARD_MAP}")),
        "the top-level memory.x must include {BOARD_MAP}"
    );
    fs::write(out.join("memory.x"), dispatch_text).expect("OUT_DIR writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    // The defmt table (interned format strings) the host decoder reads from the ELF.
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
