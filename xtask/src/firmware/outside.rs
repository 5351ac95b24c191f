//! `cargo xtask outside-firmware`: a firmware outside the workspace (`fixtures/outside-firmware`,
//! its own `[workspace]` and `Cargo.lock`), which depends on the three libraries by version as
//! from crates.io, `[patch.crates-io]` pointing them at this checkout. Linted and built for
//! thumbv7em and thumbv6m, memory map checked from the ELF, and run on QEMU: its CSV (the
//! bundled capture, compiled in, through one product bank) must equal `nav440 estimate --bank
//! product --preset paper --axis yaw` byte for byte.

use super::nav440_cli::host_estimate;
use super::root;
use crate::{cargo, qemu};
use std::time::Duration;

/// The fixture's manifest, relative to the workspace root.
const MANIFEST: &str = "fixtures/outside-firmware/Cargo.toml";

/// The capture the fixture compiles in (`include_bytes!` in its `src/main.rs`).
const CAPTURE: &str = "host-tests/data/fig5_a2_100hz.bin";

/// The emulated boards it runs on: the M4F (thumbv7em, hard float) and a thumbv6m image on
/// the Cortex-M3 board (soft float).
const BOARDS: [&str; 2] = ["an386", "an385-v6m"];

/// Builds, checks and runs the fixture (see the module doc).
pub fn outside_firmware() -> Result<(), String> {
    let manifest = root().join(MANIFEST).display().to_string();
    let target_dir = root().join("target").join("outside-firmware");
    let dir = target_dir.display().to_string();
    let want = host_estimate(
        &root().join(CAPTURE),
        &["--bank", "product", "--preset", "paper", "--axis", "yaw"],
    )?;
    let qemu_ok = qemu::ensure_or_skip("the outside firmware's QEMU runs")?;
    cargo(&["fmt", "--manifest-path", &manifest, "--", "--check"])?;
    for name in BOARDS {
        let board = qemu::board(name)?;
        let common = [
            "--manifest-path",
            &manifest,
            "--target",
            board.target,
            "--target-dir",
            &dir,
        ];
        let mut clippy = vec!["clippy", "--release"];
        clippy.extend(common);
        clippy.extend(["--", "-D", "warnings"]);
        cargo(&clippy)?;
        let mut build = vec!["build", "--release"];
        build.extend(common);
        cargo(&build)?;
        let elf = target_dir
            .join(board.target)
            .join("release")
            .join("outside-firmware");
        let map = crate::elf::check_memory_map_for(&elf, "mps2")?;
        eprintln!(
            "xtask: OK: memory map of the outside firmware ({}): {} loadable sections inside {}'s memory, vector table at {:#010x}",
            board.target, map.sections, map.board, map.vector_table
        );
        if !qemu_ok {
            continue;
        }
        let r = qemu::run_plain(&board, &elf, &[], Duration::from_secs(600))?;
        if r.stdout != want {
            let line = r
                .stdout
                .lines()
                .zip(want.lines())
                .position(|(a, b)| a != b)
                .map_or_else(
                    || {
                        format!(
                            "{} lines against {}",
                            r.stdout.lines().count(),
                            want.lines().count()
                        )
                    },
                    |i| format!("first difference at line {}", i + 1),
                );
            return Err(format!(
                "the outside firmware on {name} printed another CSV than `nav440 estimate`: {line}"
            ));
        }
        eprintln!(
            "xtask: OK: the outside firmware on {name} ({}): {} CSV lines identical to nav440 estimate",
            board.target,
            want.lines().count()
        );
    }
    Ok(())
}
