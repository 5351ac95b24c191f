//! Running the firmware in QEMU: a capture replayed through its UART (`cargo xtask qemu`),
//! a unit on TCP (`cargo xtask unit`), and the counters the firmware prints at the end.

use super::build::{build, build_profile, SMALL_PROFILE};
use super::{read_file, work_dir, BankChoice, ADAPTIVE, FW_BIN, NO_REFERENCE, ONE_AXIS, UART_ROWS};
use crate::qemu::{self, Board, Output};
use crate::unit;
use std::path::Path;
use std::time::Duration;

/// Runs `capture` through the firmware image `elf` on `board`: the CSV on the run's stdout, the
/// counters on its stderr.
pub(super) fn run_capture(
    board: &Board,
    elf: &Path,
    capture: &[u8],
    output: Output,
) -> Result<qemu::RunResult, String> {
    let input = qemu::framed_input(capture)?;
    let path = qemu::input_path(&work_dir()?, board.name);
    let r = qemu::run_uart(
        board,
        elf,
        &path,
        &input,
        output,
        qemu::uart_timeout(input.len()),
    );
    let _ = std::fs::remove_file(&path);
    r
}

/// The `key=value` counters of the firmware's `firmware: ...` stderr lines (the boot line
/// line, the periodic counter lines and the final counters line).
pub(super) fn counters(stderr: &str) -> Vec<(String, u64)> {
    stderr
        .lines()
        .filter_map(|l| l.strip_prefix("firmware: "))
        .flat_map(|rest| {
            rest.split_whitespace()
                .filter_map(|kv| {
                    let (k, v) = kv.split_once('=')?;
                    Some((k.to_owned(), v.parse().ok()?))
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

pub(super) fn counter(c: &[(String, u64)], key: &str) -> Option<u64> {
    // The last: the end-of-run summary comes after the periodic counter lines.
    c.iter().rev().find(|(k, _)| k == key).map(|(_, v)| *v)
}

/// The run's stack high-water mark (`stack_peak`), if it is at most `limit` bytes; an error
/// naming `what` otherwise (or when the run printed none).
pub(super) fn stack_within(c: &[(String, u64)], limit: u64, what: &str) -> Result<u64, String> {
    match counter(c, "stack_peak") {
        Some(p) if p <= limit => Ok(p),
        p => Err(format!(
            "{what}: stack high-water mark {p:?} B, the limit is {limit} B"
        )),
    }
}

/// Time limit of a unit run (the boot's worst case is a few seconds of time-outs; then as a
/// replay of the same size).
pub(super) fn unit_timeout(capture_bytes: usize) -> Duration {
    qemu::uart_timeout(capture_bytes)
}

/// Runs the firmware image `elf` on `board` against the unit at `addr` (`HOST:PORT`).
pub(super) fn run_unit(
    board: &Board,
    elf: &Path,
    addr: &str,
    inherit_stdout: bool,
    timeout: Duration,
) -> Result<unit::UnitRun, String> {
    unit::run(board, elf, addr, &work_dir()?, inherit_stdout, timeout)
}

/// [`run_unit`] with the board's third UART (a `uart-rows` image's output UART) written to
/// the file `rows`.
pub(super) fn run_unit_rows(
    board: &Board,
    elf: &Path,
    addr: &str,
    timeout: Duration,
    rows: &Path,
) -> Result<unit::UnitRun, String> {
    unit::run_with_rows(board, elf, addr, &work_dir()?, false, timeout, Some(rows))
}

/// `cargo xtask unit --connect tcp:HOST:PORT [--board B] [--rows FILE]`: returns the
/// firmware's exit status. With `rows` the image is built with the feature `uart-rows` and its
/// output UART (UART2) is written to that file (`nav440 rows FILE` prints its CSV).
pub fn unit(board: Board, addr: &str, rows: Option<&Path>) -> Result<u8, String> {
    qemu::ensure_qemu()?;
    let mut features = board.features.to_vec();
    if rows.is_some() {
        if board.name == qemu::STM32_BOARD.name {
            return Err(format!(
                "--rows: the {} image has no output UART (the mps2 boards have it: docs/UART-ROWS.md)",
                board.name
            ));
        }
        features.push(UART_ROWS);
    }
    let elf = build(board.target, &features, FW_BIN)?;
    let timeout = std::env::var("XTASK_UNIT_TIMEOUT")
        .ok()
        .and_then(|v| v.parse().ok())
        .map_or(Duration::from_secs(3600), Duration::from_secs);
    let r = unit::run_with_rows(&board, &elf, addr, &work_dir()?, true, timeout, rows)?;
    eprint!("{}", r.stderr);
    match r.code() {
        Some(c) => Ok(u8::try_from(c).unwrap_or(1)),
        None => Err(format!("QEMU ended without an exit status ({})", r.status)),
    }
}

/// `cargo xtask qemu FILE [--board B] [--small | --adaptive] [--bank B] [--no-reference]`.
pub fn qemu(
    board: Board,
    file: &Path,
    small: bool,
    adaptive: bool,
    bank: BankChoice,
    no_reference: bool,
) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let mut features: Vec<&str> = bank.features().to_vec();
    if adaptive {
        features.push(ADAPTIVE);
    }
    if no_reference {
        features.push(NO_REFERENCE);
    }
    let elf = if small {
        features.push(ONE_AXIS);
        build_profile(board.target, &features, FW_BIN, SMALL_PROFILE)?
    } else {
        build(board.target, &features, FW_BIN)?
    };
    let capture = read_file(file)?;
    let r = run_capture(&board, &elf, &capture, Output::Inherit)?;
    eprint!("{}", r.stderr);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_line_is_parsed() {
        let err = "qemu noise\nfirmware: bytes=10 frames=2 crc_errors=1 skipped=3 uart_overruns=0 stack_peak=7000\n";
        let c = counters(err);
        assert_eq!(counter(&c, "bytes"), Some(10));
        assert_eq!(counter(&c, "crc_errors"), Some(1));
        assert_eq!(counter(&c, "stack_peak"), Some(7000));
        assert_eq!(counter(&c, "missing"), None);
    }
}
