//! `cargo xtask embassy-stm32`: the embassy-stm32 firmware (`firmware-embassy`) for the
//! STM32F405 and the NUCLEO-F411RE.
//!
//! 1. The async driver's docs show the firmware's boot code: the ```` ```rust,ignore ````
//!    block of `nav440-proto/src/driver/asynch.rs` equals the region between the binary's
//!    `ANCHOR: boot` and `ANCHOR_END: boot` comments, line for line (dedented).
//! 2. Lints (`cargo fmt --check`, `cargo clippy -D warnings`) and builds the release ELF for
//!    `thumbv7em-none-eabihf`, once per chip ([`images`]).
//! 3. Checks each image's memory map from the ELF against its chip (`nucleo-f411re`,
//!    `stm32f405`: vector table at `0x0800_0000`, every section inside flash or RAM) and prints
//!    its flash and RAM.
//! 4. QEMU 7.2's `netduinoplus2` cannot run the STM32F405 image (and QEMU has no F411 board):
//!    the STM32F405 model has no RCC (an unimplemented device that reads 0), and
//!    `embassy_stm32::init` waits for RCC_CR.HSIRDY.
//!    The command runs the ELF there for a bounded time with `-d unimp` and asserts exactly
//!    that (the HSION write, then nothing but reads of RCC_CR), so that the documented failure
//!    mode stays true; when a QEMU models RCC the assertion fails and says so.

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
/// QEMU's STM32F405 board.
const MACHINE: &str = "netduinoplus2";
/// What `-d unimp` logs when the firmware sets RCC_CR.HSION (RCC at 0x4002_3800, CR at 0).
const HSION_WRITE: &str =
    "RCC: unimplemented device write (size 4, offset 0x000, value 0x00000001)";
/// What `-d unimp` logs for each read of RCC_CR (the wait for HSIRDY, bit 1).
const CR_READ: &str = "RCC: unimplemented device read  (size 4, offset 0x000)";
/// Consecutive [`CR_READ`] lines that make the spin certain (QEMU logs about 600,000 a second).
const SPIN_READS: usize = 10_000;
/// Wall-time bound of the QEMU run.
const QEMU_LIMIT: Duration = Duration::from_secs(10);

/// The images, one per board of `boards/src/description.rs` with an `embassy_feature`: (cargo
/// feature arguments, the board's name, which the image carries in `NAV440_BOARD`). The
/// board QEMU runs as [`MACHINE`] (the STM32F405) last, so that the ELF left in the target
/// directory is the one QEMU and `cargo xtask flash` take.
fn images() -> Vec<([&'static str; 3], &'static str)> {
    let mut boards: Vec<_> = nav440_boards::all()
        .iter()
        .filter_map(|b| Some((b.embassy_feature?, b)))
        .collect();
    boards.sort_by_key(|(_, b)| b.qemu.contains(&MACHINE));
    boards
        .into_iter()
        .map(|(f, b)| (["--no-default-features", "--features", f], b.name))
        .collect()
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
    }
    if qemu::ensure_or_skip("the embassy-stm32 QEMU check")? {
        qemu_lacks_rcc(&elf)?;
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

/// Step 4 of the module doc: QEMU `netduinoplus2` with `-d unimp,guest_errors` (logged on
/// QEMU's stderr) until the firmware has set HSION and then read RCC_CR [`SPIN_READS`] times
/// in a row with no other access, or [`QEMU_LIMIT`].
fn qemu_lacks_rcc(elf: &Path) -> Result<(), String> {
    let elf_arg = elf.display().to_string();
    let args = [
        "-M",
        MACHINE,
        "-nographic",
        "-monitor",
        "none",
        "-serial",
        "null",
        "-d",
        "unimp,guest_errors",
        "-kernel",
        &elf_arg,
    ];
    eprintln!("+ qemu-system-arm {}", args.join(" "));
    let mut child = Command::new("qemu-system-arm")
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
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
    let mut hsion_at = None;
    let mut spin = 0usize;
    let mut lines = 0usize;
    let mut last_other = String::new();
    for line in BufReader::new(stderr).lines() {
        let Ok(line) = line else { break };
        lines += 1;
        if line == HSION_WRITE {
            hsion_at = Some(lines);
            spin = 0;
        } else if line == CR_READ && hsion_at.is_some() {
            spin += 1;
            if spin >= SPIN_READS {
                break;
            }
        } else {
            spin = 0;
            last_other = line;
        }
    }
    done.store(true, Ordering::Relaxed);
    let _ = watchdog.join();
    let status = child
        .lock()
        .map_err(|_| "QEMU's handle is poisoned")?
        .wait()
        .map_err(|e| format!("waiting for QEMU: {e}"))?;
    match hsion_at {
        Some(at) if spin >= SPIN_READS => {
            eprintln!(
                "xtask: OK: QEMU {MACHINE} lacks the RCC, as documented: after `{HSION_WRITE}` (log line {at}) the firmware read RCC_CR {SPIN_READS} times in a row waiting for HSIRDY (embassy_stm32::init, {:.1} s; QEMU stopped)",
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        _ => Err(format!(
            "QEMU {MACHINE} did not show the documented failure mode (the HSION write {}, then {SPIN_READS} reads of RCC_CR; {spin} seen) within {} s; QEMU {status}, {lines} log lines, the last other one: `{last_other}`. If this QEMU models the RCC, run the firmware against `nav440 sim` instead and update docs/EMBASSY.md",
            if hsion_at.is_some() { "seen" } else { "not seen" },
            QEMU_LIMIT.as_secs()
        )),
    }
}
