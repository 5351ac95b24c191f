//! `cargo xtask flash ELF`, the runner of `cargo run` for the firmware.

use std::path::Path;
use std::process::Command;

/// `cargo xtask flash ELF` (the runner of `cargo run`): a board image's memory map is
/// checked, then `probe-rs run --chip CHIP ELF` flashes it and prints its defmt output.
pub fn flash(elf: &Path) -> Result<(), String> {
    let board = crate::elf::board_of(elf)?.ok_or_else(|| {
        format!(
            "{} names no board (no NAV440_BOARD symbol): not a firmware image of this repository",
            elf.display()
        )
    })?;
    let chip = crate::elf::chip(&board)?;
    let Some(probe_chip) = chip.probe_chip else {
        return Err(format!(
            "{} is an image of the emulated board `{board}` ({}), not of a chip: run it with `cargo xtask qemu FILE`, `demo` or `unit`; to flash a board build it with its feature, e.g. `--features board-stm32f405` (docs/PORTING.md)",
            elf.display(),
            chip.part
        ));
    };
    crate::elf::check_memory_map(elf, Some(&board))?;
    eprintln!(
        "xtask: flashing {} ({}) with probe-rs, chip {probe_chip}; NAV440 on {}",
        elf.display(),
        chip.part,
        chip.wiring()
    );
    let status = Command::new("probe-rs")
        .args(["run", "--chip", probe_chip])
        .arg(elf)
        .status()
        .map_err(|e| {
            format!("cannot run probe-rs ({e}): install it (https://probe.rs, `cargo install probe-rs-tools`)")
        })?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("probe-rs run ended with {status}"))
    }
}
