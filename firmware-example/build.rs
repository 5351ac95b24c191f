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
    println!("cargo::rustc-check-cfg=cfg(prebuilt_banks)");
    println!("cargo::rustc-check-cfg=cfg(follow_gains)");
    if follow_gains() {
        println!("cargo:rustc-cfg=follow_gains");
    }
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
    // Identical code folding: functions that compile to the same bytes (monomorphisations
    // that differ only in types of one layout) are linked once.
    println!("cargo:rustc-link-arg-bins=--icf=all");
    if let Some(table) = prebuilt_banks() {
        fs::write(out.join("banks.rs"), table).expect("OUT_DIR writable");
        println!("cargo:rustc-cfg=prebuilt_banks");
    }
}

/// Whether the firmware is built with the cargo feature `name` (upper case, `_` for `-`).
fn feature(name: &str) -> bool {
    env::var_os(format!("CARGO_FEATURE_{name}")).is_some()
}

/// Whether the image runs the product bank whose gains follow the noise and the motion
/// (`estimators::AdaptiveProductBank`, cfg `follow_gains`): with the feature `follow`, or
/// `bank-product` alone (neither `fixed-gains`, `tuned-gains` nor `self-tune`).
fn follow_gains() -> bool {
    feature("FOLLOW")
        || (feature("BANK_PRODUCT")
            && !feature("FIXED_GAINS")
            && !feature("TUNED_GAINS")
            && !feature("SELF_TUNE"))
}

/// The product images' banks, built here on the host: `Some(source)` of the table `BANKS`
/// for an image with the feature `fixed-gains` (the product bank with the shipped preset's
/// fixed gains); `None` for every other image, which builds its banks itself. The banks are
/// in the image's number type: `Fx` with the `fixed-point` feature or on a target without an
/// FPU, `f32` otherwise (`src/lib.rs`, `Num`).
///
/// One entry per NAV440 packet rate (`PacketRate`, dividers 1 to 50 of 100 Hz): the key is
/// the nominal period as the pipeline's period rule gives it for that rate
/// (`PeriodEstimator` over a steady stream, an `f32` in s, by its bits), the value the bank
/// `nav440_pipeline::axis_bank` builds for it for an axis that wraps at +-180 deg (yaw), with
/// the preset's gains for that rate (`BankConfig::NAV440.with_nav440_gains()`, what
/// `src/pipeline.rs` builds without the table), as its words (`Bank::put_words`: the input
/// stage and the laws, `estimators::words`), each an `i64` in postcard's form (a zigzag
/// varint: a small or zero word takes one byte). An axis that does not wrap (pitch) reads the same
/// entry back and switches its unwrapping off (`Bank::set_wrap`: the laws do not depend on
/// it). The same `Bank::new` runs in the host tools, in IEEE `f64` as here, so a bank read
/// back equals the one `nav440 estimate --bank product --fixed-gains` (`--fixed`) builds.
fn prebuilt_banks() -> Option<String> {
    if !feature("FIXED_GAINS")
        || feature("TUNED_GAINS")
        || feature("ADAPTIVE_GAINS")
        || feature("FOLLOW")
        || feature("SELF_TUNE")
    {
        return None;
    }
    let fixed =
        feature("FIXED_POINT") || env::var("CARGO_CFG_TARGET_ABI").as_deref() != Ok("eabihf");
    Some(if fixed {
        bank_table::<estimators::Fx>()
    } else {
        bank_table::<f32>()
    })
}

/// The source of the table of [`prebuilt_banks`] for banks in `T`.
fn bank_table<T: estimators::Real + estimators::words::Words>() -> String {
    use estimators::{BankConfig, ProductBank};
    use nav440_pipeline::{period::PeriodEstimator, period::WARMUP_SAMPLES, Axis};
    use std::fmt::Write;

    let mut entries = Vec::new();
    for divider in 1..=50u16 {
        let Some(rate) = nav440_proto::PacketRate::from_divider(divider) else {
            continue;
        };
        // 100 Hz / divider: a period of 10 ms x divider, in us.
        let period_us = 10_000 * u64::from(divider);
        let times = (0..WARMUP_SAMPLES as u64).map(|k| k * period_us);
        let cfg = PeriodEstimator::from_times(times)
            .apply(BankConfig::NAV440)
            .with_nav440_gains();
        let bank: ProductBank<T> = nav440_pipeline::axis_bank(Axis::Yaw, &cfg)
            .unwrap_or_else(|e| panic!("firmware-example: the bank at {rate:?}: {e}"));
        let mut bytes = Vec::new();
        bank.put_words(&mut |w| {
            bytes.extend(postcard::to_stdvec(&w).expect("an i64 serializes"));
        });
        entries.push((cfg.sample_period_s, bytes));
    }
    let mut src = String::from(
        "/// The product banks build.rs built (`prebuilt_banks`): (the nominal period's `f32` \
         /// bits, the words of the bank of an axis that wraps at +-180 deg, as postcard `i64`s).\n",
    );
    let _ = writeln!(
        src,
        "pub static BANKS: [(u32, &[u8]); {}] = [",
        entries.len()
    );
    for (period_s, bytes) in entries {
        let _ = writeln!(
            src,
            "    // {period_s} s\n    ({:#010x}, &{bytes:?}),",
            period_s.to_bits()
        );
    }
    src.push_str("];\n");
    src
}
