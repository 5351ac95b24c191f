//! Links the firmware with cortex-m-rt's `link.x` and the selected board's memory map.
//!
//! cortex-m-rt's `link.x` includes a file named `memory.x`, and the linker looks for it in
//! its working directory (the workspace root, where the top-level `memory.x` is) before the
//! search path. So no board map is ever *named* `memory.x`: the top-level `memory.x` (and a
//! copy of it in `OUT_DIR`, for a build whose working directory has none) only includes
//! `nav440-board-memory.x`, which this script writes into `OUT_DIR` from the board's map,
//! `src/board/<board>.x` (the board of the `board-*` feature; `mps2` without one). Whatever
//! `memory.x` the linker finds, the image gets its own board's map.
//!
//! Only this crate gets the flags (via `cargo:rustc-link-arg-bins`), so no other crate of the
//! workspace is affected.

use std::{env, fs, path::PathBuf};

/// `board-*` feature (as cargo's environment spells it) -> board module / memory map name,
/// and the shared backend module the board uses, if any (set as `cfg(board_<backend>)`).
const BOARDS: &[(&str, &str, Option<&str>)] = &[
    (
        "CARGO_FEATURE_BOARD_STM32F405",
        "stm32f405",
        Some("stm32f4_hal"),
    ),
    (
        "CARGO_FEATURE_BOARD_NUCLEO_F411RE",
        "nucleo_f411re",
        Some("stm32f4_hal"),
    ),
    ("CARGO_FEATURE_BOARD_RP_PICO", "rp_pico", None),
];

/// The backends of [`BOARDS`], and `mps2` (the QEMU boards, selected by no `board-*`).
const CFGS: &[&str] = &["mps2", "stm32f4_hal"];

/// The name `memory.x` includes (unique to this crate, never in a working directory).
const BOARD_MAP: &str = "nav440-board-memory.x";

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let target = env::var("TARGET").unwrap_or_default();
    let selected: Vec<_> = BOARDS
        .iter()
        .filter(|(var, _, _)| env::var_os(var).is_some())
        .collect();
    let (board, cfg) = match selected.as_slice() {
        [] => ("mps2", Some("mps2")),
        [(_, name, backend)] => (*name, *backend),
        many => panic!(
            "select at most one board-* feature (got {})",
            many.iter().map(|b| b.1).collect::<Vec<_>>().join(", ")
        ),
    };
    for c in CFGS {
        println!("cargo::rustc-check-cfg=cfg(board_{c})");
    }
    if let Some(c) = cfg {
        println!("cargo::rustc-cfg=board_{c}");
    }
    let map = manifest
        .join("src")
        .join("board")
        .join(format!("{board}.x"));
    let dispatch = manifest.join("..").join("memory.x");
    println!("cargo:rerun-if-changed={}", map.display());
    println!("cargo:rerun-if-changed={}", dispatch.display());
    println!("cargo:rerun-if-changed=build.rs");
    if !target.starts_with("thumb") {
        // Host builds (e.g. `cargo clippy --workspace` by mistake) get no linker script.
        return;
    }
    let map_text = fs::read(&map).expect("the board's memory map exists");
    fs::write(out.join(BOARD_MAP), map_text).expect("OUT_DIR writable");
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
