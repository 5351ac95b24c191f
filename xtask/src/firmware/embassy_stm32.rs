//! `cargo xtask embassy-stm32`: the embassy-stm32 firmware (`firmware-embassy`) for the
//! STM32F405, the NUCLEO-F411RE and the B-L475E-IOT01A (STM32L475VG).
//!
//! 1. The async driver's docs show the firmware's boot code: the ```` ```rust,ignore ````
//!    block of `nav440-proto/src/driver/asynch.rs` equals the region between the binary's
//!    `ANCHOR: boot` and `ANCHOR_END: boot` comments, line for line (dedented).
//! 2. Lints (`cargo fmt --check`, `cargo clippy -D warnings`) and builds the release ELF for
//!    `thumbv7em-none-eabihf`, once per chip ([`images`]).
//! 3. Checks each image's memory map from the ELF against its chip (vector table at
//!    `0x0800_0000`, every section inside flash or RAM) and prints its flash and RAM.
//! 4. Runs the images of the boards QEMU has a machine of ([`STALLS`], QEMU 10) for a
//!    bounded time, logging the device accesses, and asserts where `embassy_stm32::init`
//!    stops there: QEMU does not model a ready flag the HAL writes for and then waits on. On
//!    `netduinoplus2` (STM32F405) the RCC keeps clock enables and resets only (the wait for
//!    RCC_CR.HSIRDY); on `b-l475e-iot01a` (RCC, PLLs, GPIO and USARTs modelled) the PWR is
//!    unimplemented (the wait for PWR_CR1.DBP, which `rcc::init` sets before it touches a
//!    clock). When a QEMU models the device the assertion fails and says so: the image then
//!    runs further, and the check is to become a run against `nav440 sim`.

use super::{read_file, root, target_dir};
use crate::cargo;
use crate::qemu;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The firmware crate (and its binary).
const CRATE: &str = "firmware-embassy";
/// Its target (both chips are Cortex-M4F).
const TARGET: &str = "thumbv7em-none-eabihf";
/// The binary with the anchored boot code, relative to the workspace root.
const MAIN: &str = "firmware-embassy/src/main.rs";
/// The docs that show it, relative to the workspace root.
const DOC: &str = "nav440-proto/src/driver/asynch.rs";
/// The heading in [`DOC`] the shown block follows.
const DOC_HEADING: &str = "//! # On embassy-stm32";
/// An image QEMU runs until `embassy_stm32::init` waits on a device QEMU does not model.
struct Stall {
    /// The board (`boards/src/description.rs`), whose image is run.
    board: &'static str,
    /// Its QEMU machine.
    machine: &'static str,
    /// QEMU's `-d` items.
    log: &'static str,
    /// What QEMU logs for the write after which the HAL waits.
    write: &'static str,
    /// What it logs for each read of the wait.
    read: &'static str,
    /// What the wait is, for messages.
    wait: &'static str,
}

/// The boards QEMU has a machine of, and where the HAL stops there.
const STALLS: &[Stall] = &[
    Stall {
        board: "stm32f405",
        machine: "netduinoplus2",
        // QEMU 10's STM32F4 RCC keeps what is written (RCC at 0x4002_3800) and sets no ready
        // flag; its trace events log the accesses (QEMU prints the value after `addr:` and the
        // offset after `val:`). CR.HSION set, then CR read until HSIRDY (bit 1).
        log: "unimp,guest_errors,trace:stm32_rcc_read,trace:stm32_rcc_write",
        write: "stm32_rcc_write reg write: addr: 0x1 val: 0x0",
        read: "stm32_rcc_read reg read: addr: 0x0 val: 0x1",
        wait: "RCC_CR.HSIRDY (QEMU's STM32F4 RCC models clock enables and resets, no oscillator)",
    },
    Stall {
        board: "b-l475e-iot01a",
        machine: "b-l475e-iot01a",
        log: "unimp,guest_errors",
        // PWR at 0x4000_7000: CR1.DBP (bit 8) set, then CR1 read until DBP reads back.
        write: "PWR: unimplemented device write (size 4, offset 0x000, value 0x00000100)",
        read: "PWR: unimplemented device read  (size 4, offset 0x000)",
        wait: "PWR_CR1.DBP (QEMU's STM32L4x5 has no PWR)",
    },
];

/// Consecutive wait reads that make the spin certain (QEMU logs about 250,000 a second).
const SPIN_READS: usize = 10_000;
/// Wall-time bound of the QEMU run.
const QEMU_LIMIT: Duration = Duration::from_secs(10);

/// The images, one per board of `boards/src/description.rs` with an `embassy_feature`: (cargo
/// feature arguments, the board's name, which the image carries in `NAV440_BOARD`). The
/// STM32F405's last, so that the ELF left in the target directory is the one `cargo xtask
/// flash` takes by default; each image is also kept as `firmware-embassy-<board>`.
fn images() -> Vec<([&'static str; 3], &'static str)> {
    let mut boards: Vec<_> = nav440_boards::all()
        .iter()
        .filter_map(|b| Some((b.embassy_feature?, b)))
        .collect();
    boards.sort_by_key(|(_, b)| b.name == "stm32f405");
    boards
        .into_iter()
        .map(|(f, b)| (["--no-default-features", "--features", f], b.name))
        .collect()
}

/// Where the image of `board` is kept.
fn kept(elf: &Path, board: &str) -> std::path::PathBuf {
    elf.with_file_name(format!("{CRATE}-{board}"))
}

/// Runs the steps of the module doc.
pub fn embassy_stm32() -> Result<(), String> {
    let start = Instant::now();
    check_doc_block()?;
    cargo(&["fmt", "-p", CRATE, "--", "--check"])?;
    let elf = target_dir().join(TARGET).join("release").join(CRATE);
    for (features, chip) in images() {
        let mut clippy = vec!["clippy", "-p", CRATE, "--target", TARGET, "--release"];
        clippy.extend(features);
        clippy.extend(["--", "-D", "warnings"]);
        cargo(&clippy)?;
        let t = Instant::now();
        let mut build = vec!["build", "-p", CRATE, "--target", TARGET, "--release"];
        build.extend(features);
        cargo(&build)?;
        eprintln!(
            "xtask: built {CRATE} for {chip} in {:.1} s",
            t.elapsed().as_secs_f64()
        );
        let map = crate::elf::check_memory_map(&elf, Some(chip))?;
        let (flash, ram) = super::size::flash_ram(&elf)?;
        eprintln!(
            "xtask: OK: memory map of {CRATE}: board {}, {} loadable sections inside its chip's memory, vector table at {:#010x}; flash {flash} B, static RAM {ram} B",
            map.board, map.sections, map.vector_table
        );
        std::fs::copy(&elf, kept(&elf, chip))
            .map_err(|e| format!("cannot keep {}: {e}", elf.display()))?;
    }
    match qemu::qemu10(&target_dir().join("qemu10")) {
        Ok((qemu, version)) => {
            eprintln!(
                "xtask: the embassy-stm32 QEMU checks use {version} ({})",
                qemu.display()
            );
            for stall in STALLS {
                stalls_in_init(&qemu, stall, &kept(&elf, stall.board))?;
            }
        }
        Err(e) if std::env::var("XTASK_SKIP_QEMU").is_ok_and(|v| v == "1") => {
            let bar = "!".repeat(78);
            eprintln!("{bar}\nxtask: XTASK_SKIP_QEMU=1: SKIPPING the embassy-stm32 QEMU checks: {e}\n{bar}");
        }
        Err(e) => return Err(e),
    }
    eprintln!(
        "xtask: embassy-stm32: all checks passed in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The lines strictly between `// ANCHOR: boot` and `// ANCHOR_END: boot` of [`MAIN`],
/// without their common indentation.
fn anchored_region(text: &str) -> Result<Vec<String>, String> {
    let lines: Vec<&str> = text.lines().collect();
    let find = |marker: &str| {
        lines
            .iter()
            .position(|l| l.trim() == marker)
            .ok_or_else(|| format!("{MAIN} has no `{marker}` line"))
    };
    let (a, b) = (find("// ANCHOR: boot")?, find("// ANCHOR_END: boot")?);
    if b <= a + 1 {
        return Err(format!("{MAIN}: the boot anchors enclose nothing"));
    }
    let region = &lines[a + 1..b];
    let indent = region
        .iter()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.len() - l.trim_start().len())
        .min()
        .unwrap_or(0);
    Ok(region
        .iter()
        .map(|l| l.get(indent..).unwrap_or("").trim_end().to_owned())
        .collect())
}

/// The ```` ```rust,ignore ```` block after [`DOC_HEADING`] in [`DOC`], without the `//! `
/// prefixes.
fn doc_block(text: &str) -> Result<Vec<String>, String> {
    let mut lines = text
        .lines()
        .skip_while(|l| l.trim_end() != DOC_HEADING)
        .skip(1)
        .skip_while(|l| l.trim_end() != "//! ```rust,ignore");
    if lines.next().is_none() {
        return Err(format!(
            "{DOC} has no ```rust,ignore block after `{DOC_HEADING}`"
        ));
    }
    let mut block = Vec::new();
    for l in lines {
        let body = l
            .strip_prefix("//!")
            .ok_or_else(|| format!("{DOC}: the block after `{DOC_HEADING}` is not closed"))?;
        let body = body.strip_prefix(' ').unwrap_or(body);
        if body.trim_end() == "```" {
            return Ok(block);
        }
        block.push(body.trim_end().to_owned());
    }
    Err(format!(
        "{DOC}: the block after `{DOC_HEADING}` is not closed"
    ))
}

/// Checks that the docs show the compiled boot code (step 1 of the module doc).
fn check_doc_block() -> Result<(), String> {
    let text =
        |p: &str| String::from_utf8(read_file(&root().join(p))?).map_err(|e| format!("{p}: {e}"));
    let code = anchored_region(&text(MAIN)?)?;
    let shown = doc_block(&text(DOC)?)?;
    if let Some(i) = (0..code.len().max(shown.len())).find(|&i| code.get(i) != shown.get(i)) {
        return Err(format!(
            "the boot code shown in {DOC} differs from {MAIN}'s anchored region at its line {}:\n  docs: {}\n  code: {}\ncopy the region between the ANCHOR comments into the doc block",
            i + 1,
            shown.get(i).map_or("(end of block)", String::as_str),
            code.get(i).map_or("(end of region)", String::as_str),
        ));
    }
    eprintln!(
        "xtask: OK: {DOC} shows {MAIN}'s boot code ({} lines, equal line for line)",
        code.len()
    );
    Ok(())
}

/// A QEMU log line without the `PID@SECONDS:` that starts a trace event's line.
fn without_trace_prefix(line: &str) -> &str {
    match line.split_once(':') {
        Some((head, rest))
            if head.contains('@')
                && head
                    .chars()
                    .all(|c| c.is_ascii_digit() || c == '@' || c == '.') =>
        {
            rest
        }
        _ => line,
    }
}

/// Step 4 of the module doc for one board: its QEMU machine with the stall's `-d` items
/// (logged on QEMU's stderr) until the firmware has made the stall's write and then the
/// stall's read [`SPIN_READS`] times in a row with no other access, or [`QEMU_LIMIT`].
fn stalls_in_init(qemu: &Path, stall: &Stall, elf: &Path) -> Result<(), String> {
    let machine = stall.machine;
    let elf_arg = elf.display().to_string();
    let mut args = qemu::QEMU10_ARGS.to_vec();
    args.extend([
        "-M",
        machine,
        "-nographic",
        "-monitor",
        "none",
        "-serial",
        "null",
        "-d",
        stall.log,
        "-kernel",
        &elf_arg,
    ]);
    eprintln!("+ {} {}", qemu.display(), args.join(" "));
    let mut child = Command::new(qemu)
        .args(&args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start {}: {e}", qemu.display()))?;
    let stderr = child.stderr.take().ok_or("QEMU's stderr is not piped")?;
    let child = Arc::new(Mutex::new(child));
    let done = Arc::new(AtomicBool::new(false));
    let watchdog = {
        let (child, done) = (Arc::clone(&child), Arc::clone(&done));
        std::thread::spawn(move || {
            let t = Instant::now();
            while t.elapsed() < QEMU_LIMIT && !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(50));
            }
            if let Ok(mut c) = child.lock() {
                // Already exited when the firmware ended QEMU itself: nothing to kill.
                let _ = c.kill();
            }
        })
    };
    let t = Instant::now();
    let mut write_at = None;
    let mut spin = 0usize;
    let mut lines = 0usize;
    let mut last_other = String::new();
    for line in BufReader::new(stderr).lines() {
        let Ok(line) = line else { break };
        lines += 1;
        let line = without_trace_prefix(&line);
        if line == stall.write {
            write_at = Some(lines);
            spin = 0;
        } else if line == stall.read && write_at.is_some() {
            spin += 1;
            if spin >= SPIN_READS {
                break;
            }
        } else {
            spin = 0;
            last_other = line.to_owned();
        }
    }
    done.store(true, Ordering::Relaxed);
    let _ = watchdog.join();
    let status = child
        .lock()
        .map_err(|_| "QEMU's handle is poisoned")?
        .wait()
        .map_err(|e| format!("waiting for QEMU: {e}"))?;
    match write_at {
        Some(at) if spin >= SPIN_READS => {
            eprintln!(
                "xtask: OK: {} image on QEMU {machine}: embassy_stm32::init waits for {}, as documented: after `{}` (log line {at}) {SPIN_READS} reads in a row ({:.1} s; QEMU stopped)",
                stall.board,
                stall.wait,
                stall.write,
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        _ => Err(format!(
            "the {} image on QEMU {machine} did not stop as documented (waiting for {}: the write {}, then {SPIN_READS} reads; {spin} seen) within {} s; QEMU {status}, {lines} log lines, the last other one: `{last_other}`. If this QEMU models the device, run the firmware against `nav440 sim` instead and update docs/EMBASSY.md",
            stall.board,
            stall.wait,
            if write_at.is_some() { "seen" } else { "not seen" },
            QEMU_LIMIT.as_secs()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_lines_lose_their_prefix() {
        assert_eq!(
            without_trace_prefix(
                "24506@1764380000.123456:stm32_rcc_read reg read: addr: 0x0 val: 0x1"
            ),
            STALLS[0].read
        );
        assert_eq!(without_trace_prefix(STALLS[1].read), STALLS[1].read);
    }
}
