//! `cargo xtask flash ELF`, the runner of `cargo run` for the firmware, and `cargo xtask
//! decode ELF [LOG]`, which turns a saved log of that firmware into the same text.

use crate::defmt_out::{decode_frames, decode_lines, table, Converter, Text};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Command, Stdio};

/// `cargo xtask flash ELF` (the runner of `cargo run`): a board image's memory map is
/// checked, then `probe-rs run --chip CHIP ELF` flashes it and prints its defmt output. For an
/// image that sends rows (firmware-example's), probe-rs prints each message's text only
/// (`--log-format "{s}"`) and this command turns it into the CSV of `nav440 estimate` for the
/// image's bank and axes on stdout, the other messages (diagnostics, counters) on stderr.
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
    let rows = table(elf)?.is_some();
    let mut probe = Command::new("probe-rs");
    probe.args(["run", "--chip", probe_chip]);
    if rows {
        probe.args(["--log-format", "{s}"]).stdout(Stdio::piped());
    }
    let mut child = probe.arg(elf).spawn().map_err(|e| {
        format!("cannot run probe-rs ({e}): install it (https://probe.rs, `cargo install probe-rs-tools`)")
    })?;
    if let Some(out) = child.stdout.take() {
        to_csv(BufReader::new(out));
    }
    let status = child
        .wait()
        .map_err(|e| format!("waiting for probe-rs: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("probe-rs run ended with {status}"))
    }
}

/// Converts message lines as they come: CSV on stdout, other lines on stderr. A line the
/// converter refuses (a malformed row) is passed on to stderr with the reason.
fn to_csv(from: impl BufRead) {
    let mut conv = Converter::default();
    for line in from.lines() {
        let Ok(line) = line else { break };
        let mut text = Text::default();
        if let Err(e) = conv.message(&line, &mut text) {
            eprintln!("xtask: {e}");
            continue;
        }
        print_text(&text);
    }
}

/// Writes converted text: the CSV to stdout, the other lines to stderr.
fn print_text(text: &Text) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.csv.as_bytes());
    let _ = out.flush();
    eprint!("{}", text.diag);
}

/// `cargo xtask decode ELF [LOG] [--text]`: a saved log of the firmware `elf` (the file `log`,
/// or stdin) turned into what `cargo xtask flash` prints. The log is the defmt frames as the
/// firmware wrote them (RTT's `defmt` channel saved
/// raw, or QEMU's semihosting stdout), or with `text` the lines probe-rs printed with
/// `--log-format "{s}"`.
pub fn decode(elf: &Path, log: Option<&Path>, text: bool) -> Result<(), String> {
    let mut bytes = Vec::new();
    match log {
        Some(p) => bytes = std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()))?,
        None => {
            std::io::stdin()
                .read_to_end(&mut bytes)
                .map_err(|e| format!("reading stdin: {e}"))?;
        }
    }
    let converted = if text {
        let s = String::from_utf8(bytes).map_err(|_| {
            "the log is not text: leave out --text to decode defmt frames".to_owned()
        })?;
        decode_lines(&s)?
    } else {
        let table = table(elf)?.ok_or_else(|| {
            format!(
                "{} sends no row messages (not a firmware-example image)",
                elf.display()
            )
        })?;
        decode_frames(&table, &bytes)?
    };
    print_text(&converted);
    Ok(())
}
