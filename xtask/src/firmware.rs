//! Firmware subcommands: demo, unit, qemu, bench, size, and the firmware part of `ci`.

use crate::cargo;
use crate::qemu::{self, Board, Output};
use crate::unit;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// The firmware crate.
const FW: &str = "firmware-example";
/// Main firmware binary.
const FW_BIN: &str = "firmware-example";
/// Instruction-count benchmark binary.
const BENCH_BIN: &str = "bench";
/// Feature of the STM32F405 board image (run on QEMU `netduinoplus2` too).
const STM32_FEATURE: &str = "board-stm32f405";

/// The board images that only build (no emulator runs them): (feature, target, board name in
/// the ELF).
const BUILT_ONLY_BOARDS: &[(&str, &str, &str)] = &[
    (
        "board-nucleo-f411re",
        "thumbv7em-none-eabihf",
        "nucleo-f411re",
    ),
    ("board-rp-pico", "thumbv6m-none-eabi", "rp-pico"),
];

/// The memory-map check of one image (`cargo xtask check-map`), with a line saying so, and
/// the check that it links no float formatting of `core::fmt`.
fn check_map(elf: &Path, board: &str) -> Result<(), String> {
    let r = crate::elf::check_memory_map(elf, Some(board))?;
    let floats = &r.float_symbols;
    if !floats.is_empty() {
        return Err(format!(
            "{} links core::fmt's float formatting ({} symbols, e.g. {}): the firmware must send raw bits and let the host format them",
            elf.display(),
            floats.len(),
            floats[0]
        ));
    }
    eprintln!(
        "xtask: OK: memory map of {}: board {}, {} loadable sections inside its chip's memory, vector table at {:#010x}; no float formatting linked",
        elf.file_name().map(|n| n.to_string_lossy()).unwrap_or_default(),
        r.board,
        r.sections,
        r.vector_table
    );
    Ok(())
}

/// The memory-map check refuses the STM32F405 image with its vector table moved to address 0
/// (where a link with the QEMU map put it) and with its loadable bytes loaded at 0, naming the
/// section or segment and the address.
fn map_check_catches_an_image_at_0(f405: &Path) -> Result<(), String> {
    let data = read_file(f405)?;
    let cases = [
        (
            crate::elf::with_section_address(&data, ".vector_table", 0)?,
            "section .vector_table at 0x00000000",
        ),
        (
            crate::elf::with_load_address(&data, 0)?,
            "is loaded at 0x00000000",
        ),
    ];
    for (i, (bytes, want)) in cases.iter().enumerate() {
        let moved = work_dir()?.join(format!("firmware-stm32f405-moved-{i}.elf"));
        std::fs::write(&moved, bytes)
            .map_err(|e| format!("cannot write {}: {e}", moved.display()))?;
        match crate::elf::check_memory_map(&moved, Some("stm32f405")) {
            Err(e) if e.contains(want) => {
                eprintln!("xtask: OK: the memory-map check refuses a moved image: {e}")
            }
            Err(e) => {
                return Err(format!(
                    "the memory-map check failed otherwise on a moved image: {e}"
                ))
            }
            Ok(_) => {
                return Err(format!(
                    "the memory-map check accepted a moved image ({want})"
                ))
            }
        }
    }
    Ok(())
}

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
        "xtask: flashing {} ({}) with probe-rs, chip {probe_chip}",
        elf.display(),
        chip.part
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

/// Clock of the reference real target for the budget (STM32F405-class Cortex-M4F), Hz.
const REF_CLOCK_HZ: f64 = 168e6;
/// NAV440 output rate of the budget, Hz.
const SAMPLE_RATE_HZ: f64 = 100.0;
/// Assumed cycles per instruction of the reference target for the *estimated* cycle column
/// (Cortex-M4F: most ALU/FP ops 1 cycle, loads 2, taken branches 2-4, VDIV/VSQRT 14, zero
/// wait-state flash through the ART accelerator). Only an estimate: QEMU counts instructions.
const ASSUMED_CPI: f64 = 1.5;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) => {
            let d = PathBuf::from(d);
            if d.is_absolute() {
                d
            } else {
                root().join(d)
            }
        }
        None => root().join("target"),
    }
}

fn work_dir() -> Result<PathBuf, String> {
    let d = target_dir().join("xtask");
    std::fs::create_dir_all(&d).map_err(|e| format!("cannot create {}: {e}", d.display()))?;
    Ok(d)
}

/// Builds the firmware binary `bin` for `target` (release) and returns the path of its copy.
fn build(target: &str, features: &[&str], bin: &str) -> Result<PathBuf, String> {
    build_profile(target, features, bin, "release")
}

/// The bank a firmware image runs (`--bank`): the paper's 14 estimators (default) or the
/// product bank (feature `bank-product`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BankChoice {
    /// The paper bank (14 estimators per axis).
    Paper,
    /// The product bank (ILO1 velocity + Kalman acceleration per axis).
    Product,
}

/// Instructions per A2 frame of the product firmware's pipeline (three axes) on thumbv6m.
const PRODUCT_PIPELINE_GOAL: f64 = 20_000.0;

/// The firmware feature of the product bank.
const PRODUCT: &str = "bank-product";

impl BankChoice {
    /// The firmware features that select this bank.
    fn features(self) -> &'static [&'static str] {
        match self {
            BankChoice::Paper => &[],
            BankChoice::Product => &[PRODUCT],
        }
    }

    /// The `nav440 estimate` arguments that select this bank.
    fn host_args(self) -> &'static [&'static str] {
        match self {
            BankChoice::Paper => &[],
            BankChoice::Product => &["--bank", "product"],
        }
    }

    /// Its name in image names and messages.
    fn name(self) -> &'static str {
        match self {
            BankChoice::Paper => "paper",
            BankChoice::Product => "product",
        }
    }
}

/// The cargo profile of the small-MCU firmware (`Cargo.toml`: release with `opt-level = "z"`).
const SMALL_PROFILE: &str = "small";

/// Builds `bin` as the small-MCU firmware for `target`: yaw only (feature `one-axis`), cargo
/// profile [`SMALL_PROFILE`].
fn build_small(target: &str, bin: &str) -> Result<PathBuf, String> {
    build_profile(target, &[ONE_AXIS], bin, SMALL_PROFILE)
}

/// `nav440 estimate` arguments that print the small-MCU firmware's CSV on `target`.
fn small_host_args(target: &str) -> &'static [&'static str] {
    if target == "thumbv7em-none-eabihf" {
        &["--axis", "yaw"]
    } else {
        &["--fixed", "--axis", "yaw"]
    }
}

/// The small-MCU builds `cargo xtask size` and `ci` measure and check: (board, label).
fn small_boards() -> [(qemu::Board, &'static str); 2] {
    [
        (qemu::BOARDS[0], "thumbv7em small (yaw, z)"),
        (qemu::BOARDS[2], "thumbv6m small (yaw, z)"),
    ]
}

/// Builds the firmware binary `bin` for `target` with the cargo `profile` and returns the path of
/// `bin`.
fn build_profile(
    target: &str,
    features: &[&str],
    bin: &str,
    profile: &str,
) -> Result<PathBuf, String> {
    let feats = features.join(",");
    let mut args = vec![
        "build",
        "-p",
        FW,
        "--target",
        target,
        "--profile",
        profile,
        // Only the binary asked for: each one is a fat-LTO link, and the lints
        // (`clippy_firmware`, `--bins`) already check every binary of each configuration.
        "--bin",
        bin,
    ];
    if !feats.is_empty() {
        args.extend(["--features", &feats]);
    }
    cargo(&args)?;
    let elf = target_dir().join(target).join(profile).join(bin);
    if !elf.is_file() {
        return Err(format!("built firmware not found at {}", elf.display()));
    }
    // Builds with other features overwrite cargo's output: keep a copy per configuration.
    let mut tag = if feats.is_empty() {
        "default".to_owned()
    } else {
        feats.replace(',', "+")
    };
    if profile != "release" {
        tag = format!("{tag}-{profile}");
    }
    let copy = work_dir()?.join(format!("{bin}-{target}-{tag}.elf"));
    std::fs::copy(&elf, &copy)
        .map_err(|e| format!("cannot copy {} to {}: {e}", elf.display(), copy.display()))?;
    Ok(copy)
}

/// The `.bin` captures of `host-tests/data`, sorted.
fn data_captures() -> Vec<PathBuf> {
    let data = root().join("host-tests").join("data");
    let mut bins: Vec<PathBuf> = std::fs::read_dir(&data)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "bin"))
                .collect()
        })
        .unwrap_or_default();
    bins.sort();
    bins
}

/// The bundled Fig. 5-like capture: `host-tests/data/*fig5*.bin` (else any `.bin` there);
/// if the data directory has none, one is synthesised with `nav440 synth --profile fig5`.
fn bundled_capture() -> Result<PathBuf, String> {
    let data = root().join("host-tests").join("data");
    let bins = data_captures();
    if let Some(p) = bins
        .iter()
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().contains("fig5"))
        })
        .or(bins.first())
    {
        return Ok(p.clone());
    }
    let out = work_dir()?.join("fig5-synth.bin");
    eprintln!(
        "xtask: no capture in {}, synthesising one with `nav440 synth`",
        data.display()
    );
    nav440_synth(&out, &["--profile", "fig5"])?;
    Ok(out)
}

/// Cargo arguments that run the host CLI `nav440`; its own arguments follow.
const NAV440_RUN: &[&str] = &["run", "-q", "-p", "host-tests", "--bin", "nav440", "--"];

/// `nav440 synth ARGS -o OUT` (the host CLI's capture generator).
fn nav440_synth(out: &Path, args: &[&str]) -> Result<(), String> {
    let out_s = out.display().to_string();
    let mut all = NAV440_RUN.to_vec();
    all.push("synth");
    all.extend_from_slice(args);
    all.extend(["-o", &out_s]);
    cargo(&all)
}

fn read_file(p: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(p).map_err(|e| format!("cannot read {}: {e}", p.display()))
}

/// Runs `capture` through the firmware on `board`; returns (CSV, firmware counters line, run).
fn run_capture(
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
/// and the final counters line).
fn counters(stderr: &str) -> Vec<(String, u64)> {
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

fn counter(c: &[(String, u64)], key: &str) -> Option<u64> {
    c.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
}

/// The `nav440` binary of the host CLI, built once (debug profile, as `NAV440_RUN`).
fn nav440_bin() -> Result<PathBuf, String> {
    cargo(&["build", "-q", "-p", "host-tests", "--bin", "nav440"])?;
    let p = target_dir().join("debug").join("nav440");
    if p.is_file() {
        Ok(p)
    } else {
        Err(format!("built nav440 not found at {}", p.display()))
    }
}

/// A running `nav440 sim`, killed when dropped.
struct Sim {
    child: std::process::Child,
    addr: String,
}

impl Sim {
    /// `nav440 sim CAPTURE --listen tcp:127.0.0.1:0 [--record RECORD] EXTRA...`; the address
    /// is the line the simulator prints on stdout once it listens.
    fn start(
        nav440: &Path,
        capture: &Path,
        record: Option<&Path>,
        extra: &[&str],
    ) -> Result<Self, String> {
        let mut args: Vec<String> = vec![
            "sim".into(),
            capture.display().to_string(),
            "--listen".into(),
            "tcp:127.0.0.1:0".into(),
        ];
        if let Some(r) = record {
            args.extend(["--record".into(), r.display().to_string()]);
        }
        args.extend(extra.iter().map(|s| (*s).to_owned()));
        eprintln!("+ {} {}", nav440.display(), args.join(" "));
        let mut child = Command::new(nav440)
            .args(&args)
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start {}: {e}", nav440.display()))?;
        let mut line = String::new();
        if let Some(out) = child.stdout.take() {
            use std::io::BufRead as _;
            let _ = std::io::BufReader::new(out).read_line(&mut line);
        }
        let Some(addr) = line.trim().strip_prefix("tcp:").map(str::to_owned) else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!(
                "nav440 sim did not report its address (printed `{}`)",
                line.trim()
            ));
        };
        Ok(Self { child, addr })
    }

    /// Waits for the simulator to exit (it does once the connection closed), killing it
    /// after `timeout`; its exit status.
    fn wait(mut self, timeout: Duration) -> Result<std::process::ExitStatus, String> {
        let start = std::time::Instant::now();
        loop {
            match self.child.try_wait() {
                Ok(Some(s)) => return Ok(s),
                Ok(None) if start.elapsed() > timeout => {
                    let _ = self.child.kill();
                    return Err("nav440 sim did not exit after the run (killed)".into());
                }
                Ok(None) => std::thread::sleep(Duration::from_millis(20)),
                Err(e) => return Err(format!("waiting for nav440 sim: {e}")),
            }
        }
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Time limit of a unit run (the boot's worst case is a few seconds of time-outs; then as a
/// replay of the same size).
fn unit_timeout(capture_bytes: usize) -> Duration {
    qemu::uart_timeout(capture_bytes)
}

/// Builds the firmware for `board` and runs it against the unit at `addr`.
fn run_unit(
    board: &Board,
    elf: &Path,
    addr: &str,
    inherit_stdout: bool,
    timeout: Duration,
) -> Result<unit::UnitRun, String> {
    unit::run(board, elf, addr, &work_dir()?, inherit_stdout, timeout)
}

/// `cargo xtask unit --connect tcp:HOST:PORT [--board B]`: returns the firmware's exit status.
pub fn unit(board: Board, addr: &str) -> Result<u8, String> {
    qemu::ensure_qemu()?;
    let elf = build(board.target, board.features, FW_BIN)?;
    let timeout = std::env::var("XTASK_UNIT_TIMEOUT")
        .ok()
        .and_then(|v| v.parse().ok())
        .map_or(Duration::from_secs(3600), Duration::from_secs);
    let r = run_unit(&board, &elf, addr, true, timeout)?;
    eprint!("{}", r.stderr);
    match r.code() {
        Some(c) => Ok(u8::try_from(c).unwrap_or(1)),
        None => Err(format!("QEMU ended without an exit status ({})", r.status)),
    }
}

/// `cargo xtask demo`: the firmware against `nav440 sim` streaming the bundled capture.
pub fn demo(board: Board, capture: Option<PathBuf>) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let elf = build(board.target, board.features, FW_BIN)?;
    let capture_path = match capture {
        Some(p) => p,
        None => bundled_capture()?,
    };
    let capture = read_file(&capture_path)?;
    let nav440 = nav440_bin()?;
    let record = work_dir()?.join(format!("demo-{}-streamed.bin", board.name));
    let sim = Sim::start(&nav440, &capture_path, Some(&record), &[])?;
    eprintln!(
        "xtask: `nav440 sim` plays a NAV440 at {} with the samples of {} ({} bytes); the firmware on QEMU {} ({}) configures it and estimates",
        sim.addr,
        capture_path.display(),
        capture.len(),
        board.machine,
        board.about
    );
    let r = run_unit(&board, &elf, &sim.addr, false, unit_timeout(capture.len()))?;
    let sim_status = sim.wait(Duration::from_secs(30));
    if r.code() != Some(0) {
        return Err(format!(
            "the firmware ended with status {:?}; its stderr:\n{}",
            r.code(),
            r.stderr
        ));
    }
    let csv_path = work_dir()?.join(format!("demo-{}.csv", board.name));
    std::fs::write(&csv_path, &r.stdout)
        .map_err(|e| format!("cannot write {}: {e}", csv_path.display()))?;
    println!("== boot: the firmware configures the unit ==");
    for l in r
        .stderr
        .lines()
        .filter(|l| l.starts_with("firmware: unit configured") || l.starts_with("firmware: boot"))
    {
        println!("{l}");
    }
    println!();
    print_estimates(&r.stdout)?;
    let c = counters(&r.stderr);
    println!();
    println!("== summary ==");
    println!(
        "board                                    QEMU {} ({}, target {})",
        board.machine, board.about, board.target
    );
    println!(
        "unit                                     nav440 sim, samples of {} ({})",
        capture_path.display(),
        match sim_status {
            Ok(s) if s.success() => "exited 0".to_owned(),
            Ok(s) => format!("exited with {s}"),
            Err(e) => e,
        }
    );
    for (k, label) in [
        ("unit_bytes", "bytes the unit sent (boot + stream)"),
        ("boot_frames", "frames while configuring (counted only)"),
        ("boot_ms", "boot time (SysTick, wall time under QEMU)"),
        ("bytes", "bytes estimated (after the read-back)"),
        ("frames", "frames (CRC ok)"),
        ("crc_errors", "CRC errors"),
        ("skipped", "skipped bytes"),
        ("decode_errors", "decode errors"),
        ("samples", "yaw samples"),
        ("rows", "estimate rows"),
        ("rejected", "rejected samples"),
        ("uart_overruns", "UART overruns"),
        ("uart_stalls", "UART RX stalls (back-pressure, no loss)"),
        ("stack_peak", "stack high-water mark, bytes"),
    ] {
        match counter(&c, k) {
            Some(v) => println!("{label:<40} {v}"),
            None => println!("{label:<40} ?"),
        }
    }
    let secs = r.elapsed.as_secs_f64();
    println!(
        "QEMU run                                 {secs:.1} s wall, {:.1} KB/s through the emulated UART",
        r.unit_bytes as f64 / secs.max(1e-9) / 1e3
    );
    println!(
        "full CSV                                 {}",
        csv_path.display()
    );
    println!(
        "bytes streamed after configuration       {} (`nav440 estimate` on it prints the same CSV)",
        record.display()
    );
    Ok(())
}

/// Prints the CSV one row per second of capture time, plus velocity RMS errors vs the gyro.
fn print_estimates(csv: &str) -> Result<(), String> {
    let mut lines = csv.lines();
    let header = lines.next().ok_or("the firmware printed no CSV header")?;
    let all_cols: Vec<&str> = header.split(',').collect();
    // The yaw block (`t,yaw,yaw_rate,...` or the `yaw,...` columns of a three-axis CSV).
    let base = all_cols.iter().position(|c| *c == "yaw").unwrap_or(1);
    let keep = |i: usize| i == 0 || (base..base + 16).contains(&i);
    // Shown as in a yaw-only CSV (`ave_v`, not `yaw_ave_v`).
    let cols: Vec<&str> = all_cols
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(_, c)| match c.strip_prefix("yaw_") {
            Some(rest) if base > 1 && rest != "rate" => rest,
            _ => *c,
        })
        .collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| keep(*i))
                .map(|(_, v)| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    println!("== estimates (one row per second of the capture; deg, deg/s, deg/s^2) ==");
    let line: Vec<String> = cols.iter().map(|c| format!("{c:>9}")).collect();
    println!("{}", line.join(""));
    let mut next_t = 0.0;
    for r in &rows {
        let t = r.first().copied().unwrap_or(f64::NAN);
        if t >= next_t {
            let line: Vec<String> = r.iter().map(|v| format!("{v:>9.2}")).collect();
            println!("{}", line.join(""));
            next_t = t.floor() + 1.0;
        }
    }
    // Velocity estimates against the reference rate (column yaw_rate: the Euler yaw rate).
    if rows.len() > 1 && cols.len() >= 10 {
        println!();
        println!(
            "velocity RMS difference to the reference yaw rate over {} rows (deg/s):",
            rows.len()
        );
        let mut parts = Vec::new();
        for (i, name) in cols.iter().enumerate().take(10).skip(3) {
            let (mut s, mut n) = (0.0, 0usize);
            for r in &rows {
                if let (Some(v), Some(g)) = (r.get(i), r.get(2)) {
                    if v.is_finite() && g.is_finite() {
                        s += (v - g) * (v - g);
                        n += 1;
                    }
                }
            }
            parts.push(format!("{name} {:.3}", (s / n.max(1) as f64).sqrt()));
        }
        println!("  {}", parts.join(", "));
    }
    Ok(())
}

/// `cargo clippy -D warnings` on the firmware's binaries for `target`, with `feature`.
fn clippy_firmware(target: &str, feature: Option<&str>) -> Result<(), String> {
    let mut args = vec!["clippy", "-p", FW, "--target", target, "--bins"];
    if let Some(f) = feature {
        args.extend(["--features", f]);
    }
    args.extend(["--", "-D", "warnings"]);
    cargo(&args)
}

/// `cargo xtask qemu FILE [--board B] [--small | --adaptive]`.
pub fn qemu(
    board: Board,
    file: &Path,
    small: bool,
    adaptive: bool,
    bank: BankChoice,
) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let mut features: Vec<&str> = bank.features().to_vec();
    if adaptive {
        features.push(ADAPTIVE);
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

/// One measurement line of the bench firmware: `instr<TAB>label<TAB>count<TAB>unit`.
struct Measure {
    label: String,
    instr: f64,
    unit: String,
    /// `VSQRT.F32` executed per unit (14 cycles each on a Cortex-M4F).
    sqrt: f64,
}

/// Cycles of one `VSQRT.F32` on a Cortex-M4F (ARM Cortex-M4 TRM, FPU instruction timing).
const VSQRT_CYCLES: f64 = 14.0;

impl Measure {
    /// Estimated cycles on a Cortex-M4F: `ASSUMED_CPI` per instruction, `VSQRT_CYCLES` per
    /// square-root instruction.
    fn cycles(&self) -> f64 {
        (self.instr - self.sqrt) * ASSUMED_CPI + self.sqrt * VSQRT_CYCLES
    }
}

/// Measurements and `size_of` lines (label, bytes) printed by the bench firmware.
type BenchOutput = (Vec<Measure>, Vec<(String, u64)>);

fn run_bench(board: &Board, small: bool, bank: BankChoice) -> Result<BenchOutput, String> {
    let mut features: Vec<&str> = bank.features().to_vec();
    let elf = if small {
        features.push(ONE_AXIS);
        build_profile(board.target, &features, BENCH_BIN, SMALL_PROFILE)?
    } else {
        build(board.target, &features, BENCH_BIN)?
    };
    let r = qemu::run_plain(
        board,
        &elf,
        &["-icount", "shift=6"],
        Duration::from_secs(600),
    )?;
    let mut m = Vec::new();
    let mut ram = Vec::new();
    let mut sqrt: Vec<(String, f64)> = Vec::new();
    for l in r.stdout.lines() {
        // The bench's text lines share stdout with the binary defmt frames of the row
        // messages it measures: a line starts at its tag.
        let Some(start) = ["instr\t", "sqrt\t", "ram\t"]
            .iter()
            .filter_map(|tag| l.find(tag))
            .min()
        else {
            continue;
        };
        let l = &l[start..];
        let f: Vec<&str> = l.split('\t').collect();
        match f.as_slice() {
            ["instr", label, n, unit] => m.push(Measure {
                label: (*label).to_owned(),
                instr: n.parse().map_err(|_| format!("bad bench line `{l}`"))?,
                unit: (*unit).to_owned(),
                sqrt: 0.0,
            }),
            ["sqrt", label, n, _] => sqrt.push((
                (*label).to_owned(),
                n.parse().map_err(|_| format!("bad bench line `{l}`"))?,
            )),
            ["ram", label, n] => ram.push((
                (*label).to_owned(),
                n.parse().map_err(|_| format!("bad bench line `{l}`"))?,
            )),
            _ => {}
        }
    }
    if m.is_empty() {
        return Err(format!(
            "the bench firmware printed no measurement; stdout:\n{}\nstderr:\n{}",
            r.stdout, r.stderr
        ));
    }
    for x in &mut m {
        x.sqrt = sqrt
            .iter()
            .find(|(l, _)| *l == x.label)
            .map_or(0.0, |(_, n)| *n);
    }
    Ok((m, ram))
}

/// `cargo xtask bench`.
pub fn bench(board: Board, small: bool, bank: BankChoice) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let (m, _) = run_bench(&board, small, bank)?;
    println!(
        "== instructions on QEMU {} ({}; firmware pipeline with the {} bank{}), counted with -icount shift=6 + SysTick ==",
        board.machine,
        board.about,
        bank.name(),
        if small {
            "; small-MCU build: one axis, opt-level \"z\""
        } else {
            ""
        }
    );
    println!(
        "cycle column: ESTIMATE = instructions x {ASSUMED_CPI} (assumed average CPI of a Cortex-M4F), VSQRT.F32 counted as {VSQRT_CYCLES} cycles;\nCPU share: estimated cycles x {SAMPLE_RATE_HZ} Hz / {} MHz; last column: instructions x {SAMPLE_RATE_HZ} Hz / {} MHz (CPI 1, a floor)",
        REF_CLOCK_HZ / 1e6,
        REF_CLOCK_HZ / 1e6
    );
    if board.target != "thumbv7em-none-eabihf" {
        println!(
            "note: fixed-point bank (estimators::Fx, Q31.32, integer multiply and square root of docs/FIXED-POINT.md) without FPU; the share columns still use the M4F budget (168 MHz, 100 Hz) as the yardstick"
        );
    }
    println!(
        "{:<44} {:>12} {:>14} {:>16} {:>16}",
        "what", "instructions", "cycles (est.)", "CPU share (est.)", "share at CPI 1"
    );
    let pct = |cycles: f64| cycles * SAMPLE_RATE_HZ / REF_CLOCK_HZ * 100.0;
    for x in &m {
        let cyc = x.cycles();
        let (share, floor) = if x.unit == "sample" {
            (
                format!("{:.3} %", pct(cyc)),
                format!("{:.3} %", pct(x.instr)),
            )
        } else {
            ("-".to_owned(), "-".to_owned())
        };
        let label = format!("{} (per {})", x.label, x.unit);
        println!(
            "{label:<44} {:>12.1} {cyc:>14.0} {share:>16} {floor:>16}",
            x.instr
        );
    }
    if let Some(b) = m.iter().find(|x| x.label == "whole bank") {
        let share = pct(b.cycles());
        println!(
            "goal: whole bank < 2 % of a 168 MHz M4F at 100 Hz -> {share:.3} % estimated ({:.3} % at CPI 1): {}",
            pct(b.instr),
            if share < 2.0 { "met" } else { "NOT met (estimate)" }
        );
    }
    // The product firmware's pipeline on a Cortex-M0+: 20,000 instructions per A2 frame for
    // three axes is 4 % of a 48 MHz core at 100 Hz.
    if bank == BankChoice::Product && board.target == "thumbv6m-none-eabi" && !small {
        if let Some(p) = m.iter().find(|x| x.label.starts_with("pipeline, A2 frame")) {
            println!(
                "goal: product pipeline per A2 frame, three axes, thumbv6m <= {PRODUCT_PIPELINE_GOAL} instructions -> {:.0}: {}",
                p.instr,
                if p.instr <= PRODUCT_PIPELINE_GOAL { "met" } else { "NOT met" }
            );
        }
    }
    // The fixed-point bank (no FPU), one axis, per 100 Hz sample.
    let fixed_goal = match board.target {
        "thumbv6m-none-eabi" => Some((250_000.0, 2_475_970.0, "Cortex-M0 (thumbv6m)")),
        "thumbv7m-none-eabi" => Some((40_000.0, 384_284.0, "Cortex-M3 (thumbv7m)")),
        _ => None,
    };
    if let (Some((goal, issue, what)), Some(b)) =
        (fixed_goal, m.iter().find(|x| x.label == "whole bank"))
    {
        println!(
            "goal (issue 12): whole fixed-point bank, one axis, {what}: <= {goal:.0} instructions per sample (issue baseline {issue:.0}) -> {:.0} ({:.1}x fewer): {}",
            b.instr,
            issue / b.instr,
            if b.instr <= goal { "met" } else { "NOT met" }
        );
    }
    // Issue 10 goals: three axes (roll, pitch, yaw), counted in instructions (CPI 1).
    for (label, goal, what) in [
        (
            "paper bank, 3 axes",
            33_600.0,
            "full paper bank on three axes <= 2 % of a 168 MHz M4F at CPI 1",
        ),
        (
            "product bank, 3 axes",
            500.0,
            "product bank (one velocity + one acceleration estimator per axis), three axes",
        ),
    ] {
        if let Some(b) = m.iter().find(|x| x.label == label) {
            println!(
                "goal: {what}: <= {goal:.0} instructions per sample -> {:.0}: {}",
                b.instr,
                if b.instr <= goal { "met" } else { "NOT met" }
            );
        }
    }
    if let Some(b) = m.iter().find(|x| x.label.starts_with("boot sequence")) {
        println!(
            "boot: {:.0} instructions from power-up configuration to confirmed A2 100 Hz 57600 Bd (ping, GF, SF baud, ping, SF type/rate, GF; replies at once, no waiting): about {:.2} ms of a 168 MHz M4F (estimate), once per start",
            b.instr,
            b.cycles() / REF_CLOCK_HZ * 1e3
        );
    }
    if let Some(t) = m.iter().find(|x| x.label.starts_with("transmit")) {
        println!(
            "transmit: {:.1} instructions per byte through embedded_io::Write (a 12-byte SF request: {:.0})",
            t.instr,
            t.instr * 12.0
        );
    }
    if let Some(p) = m.iter().find(|x| x.label == "parser") {
        println!(
            "goal: parser < 30 instructions/byte -> {:.1}: {}",
            p.instr,
            if p.instr < 30.0 { "met" } else { "NOT met" }
        );
    }
    // Issue 11 goal: the output stage (one defmt row message per sample).
    if let Some(o) = m.iter().find(|x| x.label.starts_with("defmt row message")) {
        println!(
            "goal (issue 11): output stage <= {OUTPUT_GOAL:.0} instructions per sample -> {:.0}: {}",
            o.instr,
            if o.instr <= OUTPUT_GOAL { "met" } else { "NOT met" }
        );
    }
    Ok(())
}

/// Issue 11 goal: instructions of the output stage per sample.
const OUTPUT_GOAL: f64 = 500.0;
/// Footprint goals, bytes: (image, flash, RAM if any). The product firmware (boot, driver,
/// pipeline, defmt, three axes) fits a 64 KiB Cortex-M0+ part with room for an application;
/// the paper bank on the M4F fits half of a 96 KiB budget.
const FOOTPRINT_GOALS: &[(&str, u64, Option<u64>)] = &[
    ("product-thumbv6m-3axis-small", 16 * 1024, Some(4 * 1024)),
    ("product-thumbv6m-3axis", 16 * 1024, Some(4 * 1024)),
    ("product-thumbv7em-3axis-small", 16 * 1024, None),
    ("product-thumbv7em-3axis", 16 * 1024, None),
    ("paper-thumbv7em-3axis", 48 * 1024, None),
];

/// The component (crate, or a group) a demangled symbol name belongs to.
fn component(name: &str) -> String {
    // Symbols llvm-nm leaves in the legacy escaped form (`_$LT$T$u20$as$u20$a..b$GT$::f`):
    // unescape the characters that matter here first.
    let name = name
        .replace("_$LT$", "<")
        .replace("$LT$", "<")
        .replace("$RF$", "&")
        .replace("$u20$", " ")
        .replace("..", "::");
    // `<T as Trait>::f` and `<T>::f` belong to T's crate; `_ZN..` names are already demangled.
    let n = name.trim_start_matches('<').trim_start_matches('&');
    let n = n.strip_prefix("mut ").unwrap_or(n);
    let krate = n
        .split("::")
        .next()
        .unwrap_or(n)
        .split(['<', ' ', '('])
        .next()
        .unwrap_or(n);
    let group = match krate {
        "core" | "alloc" => "core (fmt, panics, slices)",
        "compiler_builtins" => "compiler_builtins (soft float, mem*)",
        k if k.starts_with("__aeabi") || k.starts_with("__") => {
            "compiler_builtins (soft float, mem*)"
        }
        k if k.starts_with("defmt") || k.starts_with("_defmt") => "defmt + transport",
        "firmware_example" | "main" | "Reset" | "HardFault" | "DefaultHandler" => {
            "firmware_example"
        }
        "estimators" => "estimators (bank)",
        "nav440_proto" => "nav440_proto",
        "nav440_pipeline" => "nav440_pipeline",
        "libm" | "micromath" => "libm",
        k if k.starts_with("cortex_m") => "cortex_m, cortex_m_rt",
        "heapless" => "heapless",
        k if k.starts_with("stm32f4") || k == "fugit" => "stm32f4xx_hal",
        k if k.starts_with("embassy") => "embassy",
        k if k.starts_with("semihosting") => "defmt + transport",
        _ => "other",
    };
    group.to_owned()
}

/// `cargo xtask size --components`: flash bytes per component of the release firmware of each
/// target and of the small-MCU builds ([`small_boards`]), from `llvm-nm --print-size -C` (code, read-only data and initialised data symbols;
/// `unattributed` is text + data minus the symbols' sum: alignment, anonymous constants, the
/// vector table).
pub fn size_components() -> Result<(), String> {
    let size_tool = llvm_size()?;
    let nm = size_tool.with_file_name("llvm-nm");
    let mut cols: Vec<(String, std::collections::BTreeMap<String, u64>, u64)> = Vec::new();
    let mut elfs: Vec<(String, PathBuf)> = Vec::new();
    for target in crate::THUMB_TARGETS {
        elfs.push(((*target).to_owned(), build(target, &[], FW_BIN)?));
    }
    for (board, label) in small_boards() {
        elfs.push((label.to_owned(), build_small(board.target, FW_BIN)?));
    }
    for (board, _) in small_boards() {
        elfs.push((
            image_name("product", board.target, 3, "-small"),
            build_profile(
                board.target,
                BankChoice::Product.features(),
                FW_BIN,
                SMALL_PROFILE,
            )?,
        ));
    }
    for (target, elf) in elfs {
        let (t, d, _) = sizes(&size_tool, &elf)?;
        let o = Command::new(&nm)
            .args(["--print-size", "-C", "--size-sort"])
            .arg(&elf)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", nm.display()))?;
        let mut per: std::collections::BTreeMap<String, u64> = std::collections::BTreeMap::new();
        let mut sum = 0;
        for l in String::from_utf8_lossy(&o.stdout).lines() {
            // `ADDR SIZE TYPE NAME`
            let mut it = l.splitn(4, ' ');
            let (Some(_), Some(size), Some(ty), Some(name)) =
                (it.next(), it.next(), it.next(), it.next())
            else {
                continue;
            };
            if !matches!(ty, "t" | "T" | "r" | "R" | "d" | "D" | "W" | "w") {
                continue;
            }
            let Ok(size) = u64::from_str_radix(size, 16) else {
                continue;
            };
            *per.entry(component(name)).or_default() += size;
            sum += size;
        }
        per.insert("unattributed".into(), (t + d).saturating_sub(sum));
        cols.push((target, per, t + d));
    }
    println!("== flash per component (llvm-nm symbol sizes, {FW_BIN}: release per target, then the small-MCU builds), bytes ==");
    print!("{:<38}", "component");
    for (t, _, _) in &cols {
        print!(" {t:>24}");
    }
    println!();
    let mut names: Vec<String> = cols
        .iter()
        .flat_map(|(_, p, _)| p.keys().cloned())
        .collect();
    names.sort();
    names.dedup();
    // Largest first (by the first target).
    names.sort_by_key(|n| std::cmp::Reverse(cols[0].1.get(n).copied().unwrap_or(0)));
    for n in &names {
        print!("{n:<38}");
        for (_, p, _) in &cols {
            print!(" {:>24}", p.get(n).copied().unwrap_or(0));
        }
        println!();
    }
    print!("{:<38}", "total flash (text + data)");
    for (_, _, total) in &cols {
        print!(" {total:>24}");
    }
    println!();
    Ok(())
}

fn llvm_size() -> Result<PathBuf, String> {
    llvm_tool("llvm-size")
}

/// A tool of rustup's `llvm-tools` component (pinned in rust-toolchain.toml).
fn llvm_tool(name: &str) -> Result<PathBuf, String> {
    let out = |args: &[&str]| -> Result<String, String> {
        let o = Command::new("rustc")
            .args(args)
            .output()
            .map_err(|e| format!("cannot run rustc: {e}"))?;
        Ok(String::from_utf8_lossy(&o.stdout).into_owned())
    };
    let sysroot = out(&["--print", "sysroot"])?;
    let host = out(&["-vV"])?
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_owned))
        .ok_or("cannot find the host triple in `rustc -vV`")?;
    let p = Path::new(sysroot.trim())
        .join("lib/rustlib")
        .join(host)
        .join("bin")
        .join(name);
    if p.is_file() {
        Ok(p)
    } else {
        Err(format!(
            "{} missing: run `rustup component add llvm-tools`",
            p.display()
        ))
    }
}

/// (text, data, bss) of an ELF from `llvm-size` (Berkeley format).
fn sizes(tool: &Path, elf: &Path) -> Result<(u64, u64, u64), String> {
    let o = Command::new(tool)
        .arg(elf)
        .output()
        .map_err(|e| format!("cannot run llvm-size: {e}"))?;
    let text = String::from_utf8_lossy(&o.stdout);
    let nums: Vec<u64> = text
        .lines()
        .nth(1)
        .ok_or("unexpected llvm-size output")?
        .split_whitespace()
        .take(3)
        .filter_map(|v| v.parse().ok())
        .collect();
    match nums.as_slice() {
        [t, d, b] => Ok((*t, *d, *b)),
        _ => Err(format!("unexpected llvm-size output:\n{text}")),
    }
}

/// Feature of the one-axis (yaw) firmware.
const ONE_AXIS: &str = "one-axis";

/// Feature of the firmware with noise-adaptive gains (`estimators::AdaptiveBank`).
const ADAPTIVE: &str = "adaptive-gains";

/// The schedule the `adaptive-gains` firmware is built with (its `.rs` twin is included by
/// `firmware-example/src/pipeline.rs`), relative to the workspace root.
const ADAPTIVE_SCHEDULE: &str = "host-tests/data/gains/schedule_fig5.toml";

/// A bundled capture at 20 Hz (the adaptive firmware's schedule is tuned at 100 Hz).
const SPIN_20HZ: &str = "host-tests/data/spin_n1_20hz.bin";

/// `nav440 estimate` arguments that print the `adaptive-gains` firmware's CSV on `target`.
fn adaptive_host_args(target: &str) -> Vec<String> {
    let mut a = vec![
        "--gains".to_owned(),
        root().join(ADAPTIVE_SCHEDULE).display().to_string(),
        "--axis".to_owned(),
        FIRMWARE_AXIS.to_owned(),
    ];
    if target != "thumbv7em-none-eabihf" {
        a.push("--fixed".to_owned());
    }
    a
}

/// The boards the `adaptive-gains` firmware is checked on: the M4F (f32) and thumbv6m (`Fx`).
fn adaptive_boards() -> [qemu::Board; 2] {
    [qemu::BOARDS[0], qemu::BOARDS[2]]
}

/// `cargo xtask size`.
pub fn size() -> Result<(), String> {
    let tool = llvm_size()?;
    // (image name, board it runs on, ELF, flash, static RAM)
    let mut builds: Vec<(String, qemu::Board, PathBuf, u64, u64)> = Vec::new();
    for board in qemu::BOARDS {
        let elf = build(board.target, &[], FW_BIN)?;
        builds.push((image_name("paper", board.target, 3, ""), *board, elf, 0, 0));
    }
    // One axis (feature `one-axis`) on the Cortex-M0 ISA, release profile.
    builds.push((
        image_name("paper", "thumbv6m-none-eabi", 1, ""),
        qemu::BOARDS[2],
        build("thumbv6m-none-eabi", &[ONE_AXIS], FW_BIN)?,
        0,
        0,
    ));
    // The small-MCU firmware: one axis, cargo profile `small` (opt-level "z").
    for (board, _) in small_boards() {
        builds.push((
            image_name("paper", board.target, 1, "-small"),
            board,
            build_small(board.target, FW_BIN)?,
            0,
            0,
        ));
    }
    // The product firmware (three axes), release and `small`.
    for board in qemu::BOARDS {
        let elf = build(board.target, BankChoice::Product.features(), FW_BIN)?;
        builds.push((
            image_name("product", board.target, 3, ""),
            *board,
            elf,
            0,
            0,
        ));
    }
    for (board, _) in small_boards() {
        let elf = build_profile(
            board.target,
            BankChoice::Product.features(),
            FW_BIN,
            SMALL_PROFILE,
        )?;
        builds.push((
            image_name("product", board.target, 3, "-small"),
            board,
            elf,
            0,
            0,
        ));
    }
    println!("== firmware size (llvm-size, {FW_BIN}; release profile unless `small`) ==");
    println!(
        "{:<28} {:>9} {:>7} {:>7} {:>13} {:>15}",
        "image", "text", "data", "bss", "flash (t+d)", "static RAM (d+b)"
    );
    for (label, _, elf, flash, ram) in &mut builds {
        let (t, d, b) = sizes(&tool, elf)?;
        println!(
            "{label:<28} {t:>9} {d:>7} {b:>7} {:>13} {:>15}",
            t + d,
            d + b
        );
        *flash = t + d;
        *ram = d + b;
    }
    println!(
        "(the bank, parser and buffers live on the stack of `main`: see the stack peak below)"
    );
    let mut peaks: Vec<Option<u64>> = vec![None; builds.len()];
    if qemu::qemu_available() {
        let capture = root().join("host-tests/data/fig5_a2_100hz_corrupt.bin");
        if let Ok(bytes) = std::fs::read(&capture) {
            for ((label, board, elf, _, _), peak) in builds.iter().zip(&mut peaks) {
                let r = run_capture(board, elf, &bytes, Output::Capture)?;
                let c = counters(&r.stderr);
                *peak = counter(&c, "stack_peak");
                if let Some(p) = peak {
                    println!(
                        "stack high-water mark of {label} on {}: {p} B (painted stack, run of {})",
                        board.name,
                        capture.display()
                    );
                }
            }
        }
    }
    // One line per image (bytes): flash = text + data, ram = data + bss + stack high-water
    // mark (`?` without QEMU).
    for ((label, _, _, flash, ram), peak) in builds.iter().zip(&peaks) {
        match peak {
            Some(p) => println!("size: {label} flash={flash} ram={} stack={p}", ram + p),
            None => println!("size: {label} flash={flash} ram=? stack=?"),
        }
    }
    println!();
    println!(
        "== footprint goals (flash = text + data; RAM = data + bss + stack high-water mark) =="
    );
    for (image, flash_goal, ram_goal) in FOOTPRINT_GOALS {
        let Some(((label, _, _, flash, ram), peak)) =
            builds.iter().zip(&peaks).find(|((l, ..), _)| l == image)
        else {
            continue;
        };
        println!(
            "flash <= {flash_goal} B: {label}: {flash} B: {}",
            if flash <= flash_goal {
                "met"
            } else {
                "NOT met"
            }
        );
        if let Some(goal) = ram_goal {
            match peak {
                Some(p) => println!(
                    "RAM <= {goal} B: {label}: {ram} + {p} = {} B: {}",
                    ram + p,
                    if ram + p <= *goal { "met" } else { "NOT met" }
                ),
                None => println!("RAM goal of {label}: no stack measurement (QEMU missing)"),
            }
        }
    }
    if qemu::qemu_available() {
        let (_, ram_f32) = run_bench(&qemu::BOARDS[0], false, BankChoice::Paper)?;
        let (_, ram_fx) = run_bench(&qemu::BOARDS[1], false, BankChoice::Paper)?;
        println!();
        println!("== RAM per estimator (core::mem::size_of of the state) ==");
        println!("{:<40} {:>14} {:>16}", "", "f32 (v7em)", "Fx Q31.32 (v7m)");
        for (label, n) in &ram_f32 {
            let fx = ram_fx
                .iter()
                .find(|(l, _)| l == label)
                .map_or("?".to_owned(), |(_, v)| format!("{v} B"));
            println!("{label:<40} {:>14} {fx:>16}", format!("{n} B"));
        }
    } else {
        println!("(RAM per estimator needs qemu-system-arm: run `cargo xtask bench` after installing it)");
    }
    println!();
    size_components()?;
    Ok(())
}

/// The name of a firmware image in `cargo xtask size`: bank, target (`thumbv7em`, `thumbv7m`,
/// `thumbv6m`), axes, e.g. `product-thumbv6m-3axis`; `suffix` marks a profile (`-small`).
fn image_name(bank: &str, target: &str, axes: usize, suffix: &str) -> String {
    let isa = target.split('-').next().unwrap_or(target);
    format!("{bank}-{isa}-{axes}axis{suffix}")
}

/// The `nav440 estimate --axis` value that prints the firmware's CSV: the firmware estimates
/// the axes of `firmware_example::pipeline::AXES` (all three; keep the two in step).
const FIRMWARE_AXIS: &str = "all";

/// The `nav440 estimate` arguments that print the CSV of the three-axis firmware built for
/// `target` with `bank`: `--fixed` where the target has no FPU (the fixed-point bank).
fn firmware_host_args(target: &str, bank: BankChoice) -> Vec<&'static str> {
    let mut a = if target == "thumbv7em-none-eabihf" {
        vec!["--axis", FIRMWARE_AXIS]
    } else {
        vec!["--fixed", "--axis", FIRMWARE_AXIS]
    };
    a.extend(bank.host_args());
    a
}

/// `nav440 estimate FILE [extra]` on the host; its CSV.
fn host_estimate(file: &Path, extra: &[&str]) -> Result<String, String> {
    let f = file.display().to_string();
    let mut args = NAV440_RUN.to_vec();
    args.extend(["estimate", &f]);
    args.extend_from_slice(extra);
    eprintln!("+ cargo {}", args.join(" "));
    let o = Command::new(crate::cargo_bin())
        .args(&args)
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !o.status.success() {
        return Err(format!(
            "`nav440 estimate` failed: {}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    String::from_utf8(o.stdout).map_err(|_| "nav440 printed non-UTF-8".into())
}

/// Compares two CSV texts; Ok(description) when identical, Err(first difference) otherwise.
fn compare_csv(fw: &str, host: &str) -> Result<usize, String> {
    let (a, b): (Vec<&str>, Vec<&str>) = (fw.lines().collect(), host.lines().collect());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        if x != y {
            return Err(format!("line {}: firmware `{x}` != host `{y}`", i + 1));
        }
    }
    if a.len() != b.len() {
        return Err(format!(
            "firmware printed {} lines, host {}",
            a.len(),
            b.len()
        ));
    }
    Ok(a.len())
}

/// Largest absolute difference per column between two CSVs of the same shape.
/// The largest |value| in the velocity columns (`PREFIX..._v`) of a `nav440 estimate` CSV,
/// deg/s (NaN counts as infinite).
fn peak_velocity(csv: &str, prefix: &str) -> Result<f64, String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().ok_or("empty CSV")?.split(',').collect();
    let cols: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with(prefix) && h.ends_with("_v"))
        .map(|(i, _)| i)
        .collect();
    if cols.is_empty() {
        return Err(format!("no {prefix}*_v column in the CSV"));
    }
    let mut peak = 0.0f64;
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        for &i in &cols {
            let v: f64 = fields
                .get(i)
                .ok_or("short CSV line")?
                .parse()
                .map_err(|e| format!("CSV value: {e}"))?;
            peak = if v.is_nan() {
                f64::INFINITY
            } else {
                peak.max(v.abs())
            };
        }
    }
    Ok(peak)
}

fn max_abs_diff(a: &str, b: &str) -> Result<Vec<(String, f64)>, String> {
    let mut la = a.lines();
    let mut lb = b.lines();
    let header: Vec<String> = la
        .next()
        .ok_or("empty CSV")?
        .split(',')
        .map(str::to_owned)
        .collect();
    lb.next();
    let mut max = vec![0.0f64; header.len()];
    let mut n = 0;
    for (x, y) in la.zip(lb) {
        n += 1;
        for (i, (u, v)) in x.split(',').zip(y.split(',')).enumerate() {
            let (u, v): (f64, f64) = (u.parse().unwrap_or(f64::NAN), v.parse().unwrap_or(f64::NAN));
            let d = (u - v).abs();
            if let Some(m) = max.get_mut(i) {
                if d.is_nan() || d > *m {
                    *m = d;
                }
            }
        }
    }
    if n == 0 {
        return Err("no rows to compare".into());
    }
    Ok(header.into_iter().zip(max).collect())
}

/// Equivalence of the firmware and `nav440 estimate` on one capture, for one board: the
/// firmware's counters.
fn equivalence(
    board: &Board,
    elf: &Path,
    capture: &Path,
    host_extra: &[&str],
) -> Result<Vec<(String, u64)>, String> {
    equivalence_csv(board, elf, capture, host_extra).map(|(c, _)| c)
}

/// [`equivalence`], also returning the CSV both printed.
fn equivalence_csv(
    board: &Board,
    elf: &Path,
    capture: &Path,
    host_extra: &[&str],
) -> Result<(Vec<(String, u64)>, String), String> {
    let bytes = read_file(capture)?;
    let fw = run_capture(board, elf, &bytes, Output::Capture)?;
    let host = host_estimate(capture, host_extra)?;
    let c = counters(&fw.stderr);
    match compare_csv(&fw.stdout, &host) {
        Ok(lines) => {
            eprintln!(
                "xtask: EQUIVALENT: firmware on {} ({}) and `nav440 estimate{}` print identical CSV for {} ({lines} lines); {}",
                board.machine,
                board.target,
                host_extra.iter().map(|a| format!(" {a}")).collect::<String>(),
                capture.display(),
                fw.stderr.trim()
            );
            if counter(&c, "uart_overruns").unwrap_or(0) != 0 {
                return Err("UART overruns reported under QEMU".into());
            }
            Ok((c, host))
        }
        Err(diff) => {
            let detail = max_abs_diff(&fw.stdout, &host)
                .map(|v| {
                    v.iter()
                        .map(|(k, d)| format!("{k}:{d:.3e}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_default();
            Err(format!(
                "firmware CSV differs from `nav440 estimate` for {} on {}: {diff}\nmax |diff| per column: {detail}",
                capture.display(),
                board.name
            ))
        }
    }
}

/// Synthesises (with `nav440 synth`) a capture of 20 packets at 100 Hz (0 to 190 ms) followed
/// by 50 packets at 50 Hz (210 to 1190 ms), and returns its path.
fn rate_change_capture() -> Result<PathBuf, String> {
    let dir = work_dir()?;
    let mut bytes = Vec::new();
    // (file, rate Hz, duration s, timeITOW of the first packet ms)
    for (name, rate, duration, itow) in [
        ("ci-rate-100hz.bin", "100", "0.19", "100000"),
        ("ci-rate-50hz.bin", "50", "0.98", "100210"),
    ] {
        let part = dir.join(name);
        nav440_synth(
            &part,
            &[
                "--profile",
                "sin5",
                "--rate",
                rate,
                "--duration",
                duration,
                "--start-itow",
                itow,
            ],
        )?;
        bytes.extend(read_file(&part)?);
    }
    let out = dir.join("ci-rate-change.bin");
    std::fs::write(&out, &bytes).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(out)
}

/// Packets (frame indices) of the bundled A2 capture whose BIT word becomes 0x0009
/// (masterFail + softwareError) in the BIT-failure capture of `ci-firmware`.
const BIT_FAILED_FRAMES: std::ops::RangeInclusive<usize> = 1000..=1100;

/// Writes `ci-bit-fail.bin`: `bundled` (an A2 capture) with the BIT word of the frames
/// [`BIT_FAILED_FRAMES`] set to 0x0009, re-encoded (valid CRC). The firmware must drop and
/// count those samples (`bit_failed=101`) and print the same CSV as `nav440 estimate`.
fn bit_fail_capture(bundled: &Path) -> Result<PathBuf, String> {
    use nav440_proto::{encode_frame, PacketType, Parser, A2};
    let bytes = read_file(bundled)?;
    let mut out = Vec::with_capacity(bytes.len());
    let mut parser = Parser::new();
    let (mut k, mut failed) = (0usize, 0usize);
    let mut err = None;
    parser.feed(&bytes, |f| {
        let mut payload = f.payload.to_vec();
        if BIT_FAILED_FRAMES.contains(&k) && f.packet_type == PacketType::A2 {
            if let Ok(view) = A2::new(f.payload) {
                let mut fields = view.fields();
                fields.bit = 0x0009;
                payload = fields.payload().to_vec();
                failed += 1;
            }
        }
        k += 1;
        let mut buf = [0u8; 512];
        match encode_frame(f.packet_type, &payload, &mut buf) {
            Ok(n) => out.extend_from_slice(buf.get(..n).unwrap_or_default()),
            Err(e) => err = Some(format!("cannot re-encode frame {k}: {e:?}")),
        }
    });
    if let Some(e) = err {
        return Err(e);
    }
    if failed != BIT_FAILED_FRAMES.clone().count() {
        return Err(format!(
            "{} is not an A2 capture of at least {} frames",
            bundled.display(),
            BIT_FAILED_FRAMES.end() + 1
        ));
    }
    let path = work_dir()?.join("ci-bit-fail.bin");
    std::fs::write(&path, &out).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}

/// What a unit run in CI must end with.
enum Expect {
    /// Exit 0, and the CSV equals `nav440 estimate` on the simulator's record; `stderr_has`
    /// must appear in the firmware's stderr.
    Csv { stderr_has: &'static str },
    /// This exit status and diagnostic (emulated mps2 boards: a failure ends the run).
    Fails {
        status: i32,
        diagnostic: &'static str,
    },
    /// The real-board profile retries forever: within the time limit at least two attempts,
    /// each with `diagnostic` (the run is then stopped).
    Retries { diagnostic: &'static str },
    /// The real-board profile re-configures a unit that reset, then finishes with exit 0.
    Reconfigures,
}

/// One firmware run against `nav440 sim` (CI).
struct UnitCase {
    name: &'static str,
    capture: PathBuf,
    sim_args: &'static [&'static str],
    expect: Expect,
}

/// The simulator's session limit in CI (it exits 1 if a session lasts longer).
const SIM_TIMEOUT: &str = "120";

/// Runs one case on `board`; Ok(description) or Err(what went wrong).
fn unit_case(
    board: &Board,
    elf: &Path,
    nav440: &Path,
    case: &UnitCase,
    host_extra: &[&str],
) -> Result<String, String> {
    let record = work_dir()?.join(format!("ci-unit-{}-{}.bin", board.name, case.name));
    let mut sim_args = case.sim_args.to_vec();
    sim_args.extend(["--timeout", SIM_TIMEOUT]);
    let sim = Sim::start(nav440, &case.capture, Some(&record), &sim_args)?;
    let bytes = std::fs::metadata(&case.capture).map_or(0, |m| m.len() as usize);
    let limit = match case.expect {
        // About 10 attempts (12 pings x 1000 ms nominal = 1.1 s of wall time each) on an idle
        // machine; 2 are required. 6 s gave a single attempt on a loaded 2-core machine
        // (QEMU starved by parallel builds), so the limit leaves room for a 5x slowdown.
        Expect::Retries { .. } => Duration::from_secs(12),
        _ => unit_timeout(bytes),
    };
    let run = run_unit(board, elf, &sim.addr, false, limit);
    let sim_status = sim.wait(Duration::from_secs(30));
    let what = format!("{} on {}", case.name, board.name);
    match (&case.expect, run) {
        (Expect::Retries { diagnostic }, Err(e)) => {
            let attempts = e
                .lines()
                .filter(|l| l.starts_with("firmware: boot attempt") && l.contains(diagnostic))
                .count();
            if attempts >= 2 {
                Ok(format!("{what}: {attempts} boot attempts in {} s, each `{diagnostic}...`, still retrying (stopped)", limit.as_secs()))
            } else {
                Err(format!(
                    "{what}: expected repeated `{diagnostic}` attempts, got:\n{e}"
                ))
            }
        }
        (_, Err(e)) => Err(format!("{what}: {e}")),
        (Expect::Retries { .. }, Ok(r)) => Err(format!(
            "{what}: the real-board profile ended (status {:?}) instead of retrying:\n{}",
            r.code(),
            r.stderr
        )),
        (Expect::Fails { status, diagnostic }, Ok(r)) => {
            let line = r
                .stderr
                .lines()
                .find(|l| l.starts_with("firmware: ") && l.contains(diagnostic));
            match (r.code() == Some(*status), line) {
                (true, Some(l)) => Ok(format!("{what}: exit status {status}, `{l}`")),
                _ => Err(format!(
                    "{what}: expected exit status {status} and `{diagnostic}`, got status {:?}:\n{}",
                    r.code(),
                    r.stderr
                )),
            }
        }
        (Expect::Reconfigures, Ok(r)) => {
            let configured = r.stderr.matches("firmware: unit configured").count();
            let resets = r.stderr.matches("firmware: unit reset mid-stream").count();
            if r.code() == Some(0) && configured == 2 && resets == 1 {
                Ok(format!(
                    "{what}: unit reset detected, configured again, run completed (exit 0)"
                ))
            } else {
                Err(format!(
                    "{what}: expected one reset, two configurations and exit 0, got status {:?}:\n{}",
                    r.code(),
                    r.stderr
                ))
            }
        }
        (Expect::Csv { stderr_has }, Ok(r)) => {
            if r.code() != Some(0) {
                return Err(format!(
                    "{what}: firmware exit status {:?}:\n{}",
                    r.code(),
                    r.stderr
                ));
            }
            if !r.stderr.contains(stderr_has) {
                return Err(format!(
                    "{what}: `{stderr_has}` missing from:\n{}",
                    r.stderr
                ));
            }
            match sim_status {
                Ok(s) if s.success() => {}
                other => return Err(format!("{what}: nav440 sim ended with {other:?}")),
            }
            if counter(&counters(&r.stderr), "uart_overruns").unwrap_or(0) != 0 {
                return Err(format!("{what}: UART overruns reported under QEMU"));
            }
            let host = host_estimate(&record, host_extra)?;
            let lines = compare_csv(&r.stdout, &host).map_err(|d| {
                format!("{what}: firmware CSV differs from `nav440 estimate` on the record: {d}")
            })?;
            Ok(format!(
                "{what}: IDENTICAL to `nav440 estimate{}` on the {} bytes streamed after configuration ({lines} lines; the unit sent {} bytes in all)",
                host_extra.iter().map(|a| format!(" {a}")).collect::<String>(),
                std::fs::metadata(&record).map_or(0, |m| m.len()),
                r.unit_bytes
            ))
        }
    }
}

/// The firmware against `nav440 sim` on every emulated board and the STM32 profile: every
/// bundled capture (CSV identical to `nav440 estimate` on what the unit streamed after
/// configuration) and the faults, each with its diagnostic and exit status.
fn unit_ci(captures: &[PathBuf], short: &Path, only: Option<Board>) -> Result<(), String> {
    let nav440 = nav440_bin()?;
    let short = short.to_path_buf();
    let mut boards: Vec<Board> = qemu::BOARDS.to_vec();
    boards.push(qemu::STM32_BOARD);
    if let Some(b) = only {
        boards.retain(|x| x.name == b.name);
    }
    for board in &boards {
        let elf = build(board.target, board.features, FW_BIN)?;
        let stm32 = board.features.contains(&STM32_FEATURE);
        let host_extra = &firmware_host_args(board.target, BankChoice::Paper)[..];
        let mut cases: Vec<UnitCase> = captures
            .iter()
            .map(|c| UnitCase {
                name: "capture",
                capture: c.clone(),
                sim_args: &["--fast"],
                expect: Expect::Csv {
                    stderr_has: "unit was at 38400 Bd",
                },
            })
            .collect();
        cases.push(UnitCase {
            name: "already-57600",
            capture: short.clone(),
            sim_args: &["--fast", "--baud", "57600"],
            expect: Expect::Csv {
                stderr_has: "found at 57600 Bd, unit was at 57600 Bd",
            },
        });
        let faults: [(&'static str, &'static [&'static str], i32, &'static str); 4] = [
            (
                "no-answer",
                &["--fault", "no-answer"],
                2,
                "no answer from the unit",
            ),
            (
                "nak",
                &["--fault", "nak-config"],
                3,
                "unit rejected (NAK) SF",
            ),
            (
                "wrong-readback",
                &["--fault", "wrong-readback"],
                4,
                "wrong read-back (GF)",
            ),
            (
                "reset",
                &["--fast", "--fault", "reset", "--reset-after", "20"],
                5,
                "unit reset mid-stream",
            ),
        ];
        for (name, sim_args, status, diagnostic) in faults {
            let expect = match (stm32, name) {
                (true, "reset") => Expect::Reconfigures,
                (true, _) => Expect::Retries { diagnostic },
                (false, _) => Expect::Fails { status, diagnostic },
            };
            cases.push(UnitCase {
                name,
                capture: short.clone(),
                sim_args,
                expect,
            });
        }
        for case in &cases {
            let t = std::time::Instant::now();
            let ok = unit_case(board, &elf, &nav440, case, host_extra)?;
            eprintln!("xtask: UNIT OK ({:.1} s): {ok}", t.elapsed().as_secs_f64());
        }
        // The product firmware of a board that cannot replay captures (its board image):
        // every capture through the simulated unit, byte-identical to `nav440 estimate --bank
        // product` (the replay boards are compared on every capture in `ci_steps`).
        if stm32 {
            let mut features = board.features.to_vec();
            features.extend(BankChoice::Product.features());
            let elf = build(board.target, &features, FW_BIN)?;
            let extra = firmware_host_args(board.target, BankChoice::Product);
            for c in captures {
                let case = UnitCase {
                    name: "product-capture",
                    capture: c.clone(),
                    sim_args: &["--fast"],
                    expect: Expect::Csv {
                        stderr_has: "unit was at 38400 Bd",
                    },
                };
                let t = std::time::Instant::now();
                let ok = unit_case(board, &elf, &nav440, &case, &extra)?;
                eprintln!("xtask: UNIT OK ({:.1} s): {ok}", t.elapsed().as_secs_f64());
            }
        }
    }
    Ok(())
}

/// `cargo xtask embassy`: the embassy example (`firmware-example/src/bin/embassy.rs`, an
/// embassy-executor task with nav440-proto's async driver) linted, built for thumbv7em and run
/// on QEMU `mps2-an386` against `nav440 sim`: every bundled capture (CSV identical to `nav440
/// estimate` on what the unit streamed after configuration) and a unit that never answers.
pub fn embassy() -> Result<(), String> {
    let start = std::time::Instant::now();
    let board = qemu::BOARDS
        .iter()
        .find(|b| b.name == "an386")
        .ok_or("board an386 missing")?;
    cargo(&[
        "clippy",
        "-p",
        FW,
        "--target",
        board.target,
        "--features",
        "embassy",
        "--bin",
        "embassy",
        "--",
        "-D",
        "warnings",
    ])?;
    let elf = build(board.target, &["embassy"], "embassy")?;
    // As in `ci-firmware`: without QEMU, XTASK_SKIP_QEMU=1 skips the runs, loudly.
    match qemu::ensure_qemu() {
        Ok(()) => {}
        Err(e) if std::env::var("XTASK_SKIP_QEMU").is_ok_and(|v| v == "1") => {
            eprintln!("xtask: XTASK_SKIP_QEMU=1: SKIPPING the embassy example's QEMU runs: {e}");
            return Ok(());
        }
        Err(e) => return Err(e),
    }
    let nav440 = nav440_bin()?;
    let mut cases: Vec<UnitCase> = data_captures()
        .into_iter()
        .map(|capture| UnitCase {
            name: "embassy",
            capture,
            sim_args: &["--fast"],
            expect: Expect::Csv {
                stderr_has: "unit configured (embassy, async driver): A2 at 57600 Bd (unit was at 38400 Bd)",
            },
        })
        .collect();
    cases.push(UnitCase {
        name: "embassy-no-answer",
        capture: root().join("host-tests/data/sin5_a2_25hz_weekwrap.bin"),
        sim_args: &["--fault", "no-answer"],
        expect: Expect::Fails {
            status: 2,
            diagnostic: "boot failed: no answer from the unit",
        },
    });
    for case in &cases {
        let t = std::time::Instant::now();
        // The embassy example runs the firmware's pipeline (`pipeline::AXES`) and defmt rows.
        let ok = unit_case(board, &elf, &nav440, case, &["--axis", FIRMWARE_AXIS])?;
        eprintln!(
            "xtask: EMBASSY OK ({:.1} s): {ok}",
            t.elapsed().as_secs_f64()
        );
    }
    eprintln!(
        "xtask: embassy example against nav440 sim: every case passed in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `cargo xtask ci-unit`: the unit runs of `ci-firmware` (QEMU required).
pub fn ci_unit(only: Option<Board>) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let start = std::time::Instant::now();
    let short = root().join("host-tests/data/sin5_a2_25hz_weekwrap.bin");
    unit_ci(&data_captures(), &short, only)?;
    eprintln!(
        "xtask: firmware against nav440 sim: every case passed in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The firmware part of `cargo xtask ci`.
pub fn ci_steps() -> Result<(), String> {
    // QEMU must be there or installable: the test command runs every test. Only an explicit
    // opt-out (XTASK_SKIP_QEMU=1, for a machine where QEMU cannot be installed) skips the QEMU
    // runs, loudly; the lints and cross builds still run.
    let qemu_ok = match qemu::ensure_qemu() {
        Ok(()) => true,
        Err(e) if std::env::var("XTASK_SKIP_QEMU").is_ok_and(|v| v == "1") => {
            eprintln!("{}", "!".repeat(78));
            eprintln!(
                "xtask: XTASK_SKIP_QEMU=1: SKIPPING the firmware QEMU runs, the firmware/host"
            );
            eprintln!("xtask: equivalence check, the bench and the stack measurement: {e}");
            eprintln!("{}", "!".repeat(78));
            false
        }
        Err(e) => {
            return Err(format!(
                "{e}\n(set XTASK_SKIP_QEMU=1 to run the other checks without the QEMU part)"
            ))
        }
    };
    // Lints: the FPU build and the no-FPU (fixed-point) builds.
    for target in crate::THUMB_TARGETS {
        clippy_firmware(target, None)?;
    }
    let mut elfs = Vec::new();
    for board in qemu::BOARDS {
        let elf = build(board.target, &[], FW_BIN)?;
        check_map(&elf, "mps2")?;
        elfs.push((*board, elf));
    }
    // The board images: each with its own memory map, checked from the ELF. The STM32F405
    // image also runs on QEMU netduinoplus2 (`ci_unit`); the others only build.
    clippy_firmware("thumbv7em-none-eabihf", Some(STM32_FEATURE))?;
    let f405 = build("thumbv7em-none-eabihf", &[STM32_FEATURE], FW_BIN)?;
    check_map(&f405, "stm32f405")?;
    map_check_catches_an_image_at_0(&f405)?;
    for (feature, target, board) in BUILT_ONLY_BOARDS {
        clippy_firmware(target, Some(feature))?;
        check_map(&build(target, &[feature], FW_BIN)?, board)?;
    }
    // The small-MCU firmware (one axis, profile `small`): lint and build for M4F and thumbv6m.
    let mut small_elfs = Vec::new();
    for (board, label) in small_boards() {
        clippy_firmware(board.target, Some(ONE_AXIS))?;
        let elf = build_small(board.target, FW_BIN)?;
        check_map(&elf, "mps2")?;
        small_elfs.push((board, label, elf));
    }
    // The product firmware (feature `bank-product`): lint and build for every QEMU board.
    let mut product_elfs = Vec::new();
    for board in qemu::BOARDS {
        clippy_firmware(board.target, Some(PRODUCT))?;
        let elf = build(board.target, BankChoice::Product.features(), FW_BIN)?;
        check_map(&elf, "mps2")?;
        product_elfs.push((*board, elf));
    }
    // The firmware with noise-adaptive gains: lint and build for M4F and thumbv6m.
    let mut adaptive_elfs = Vec::new();
    for board in adaptive_boards() {
        clippy_firmware(board.target, Some(ADAPTIVE))?;
        let elf = build(board.target, &[ADAPTIVE], FW_BIN)?;
        check_map(&elf, "mps2")?;
        adaptive_elfs.push((board, elf));
    }
    if !qemu_ok {
        return Ok(());
    }

    // Equivalence: bundled capture, plus a short corrupted capture (CRC errors, garbage,
    // dropped packets) synthesised by the CLI.
    let bundled = bundled_capture()?;
    let corrupted = work_dir()?.join("ci-corrupted.bin");
    nav440_synth(
        &corrupted,
        &[
            "--profile",
            "spin",
            "--duration",
            "5",
            "--flip-bits",
            "20",
            "--garbage",
            "10",
            "--drop-packets",
            "5",
            "--seed",
            "7",
        ],
    )?;
    // A capture shorter than the firmware's warm-up (10 packets < 16): the bank starts at the
    // end of the input.
    let short = work_dir()?.join("ci-short.bin");
    let bytes = read_file(&bundled)?;
    std::fs::write(&short, bytes.get(..400).unwrap_or(&bytes))
        .map_err(|e| format!("cannot write {}: {e}", short.display()))?;
    // A capture whose packet rate changes after the warm-up: 20 packets at 100 Hz, then 50 at
    // 50 Hz. Host and firmware both take the bank's period from the first 16 samples
    // (`nav440_pipeline::period`), so they must still agree byte for byte.
    let rate_change = rate_change_capture()?;
    // The bundled capture with 101 packets flagging a BIT failure (masterFail): not estimated,
    // counted in the firmware's summary (`bit_failed`) and dropped alike by `nav440 estimate`.
    let bit_fail = bit_fail_capture(&bundled)?;
    // Packet rates below the bundled captures' (20-100 Hz), where the shipped preset runs
    // other gains (`BankConfig::NAV440_RATES`: one entry for 10 Hz, one for 2 Hz): the
    // firmware picks the same entry as `nav440 estimate`.
    let mut low_rates = Vec::new();
    for (rate, duration) in [("10", "12"), ("2", "40")] {
        let path = work_dir()?.join(format!("ci-{rate}hz.bin"));
        nav440_synth(
            &path,
            &["--rate", rate, "--duration", duration, "--seed", "4"],
        )?;
        low_rates.push(path);
    }
    // Every bundled capture (all packet types and rates, the week wrap) plus those six.
    let mut captures = data_captures();
    captures.extend([corrupted, short, rate_change, bit_fail.clone()]);
    captures.extend(low_rates);
    for (board, elf) in &elfs {
        let host_extra = &firmware_host_args(board.target, BankChoice::Paper)[..];
        for capture in &captures {
            let c = equivalence(board, elf, capture, host_extra)?;
            let want = BIT_FAILED_FRAMES.clone().count() as u64;
            if *capture == bit_fail && counter(&c, "bit_failed") != Some(want) {
                return Err(format!(
                    "the firmware on {} reported bit_failed={:?} for {}, expected {want}",
                    board.name,
                    counter(&c, "bit_failed"),
                    capture.display()
                ));
            }
        }
    }
    // The product firmware (feature `bank-product`) prints the CSV of `nav440 estimate --bank
    // product --axis all` (`--fixed` without FPU), byte for byte, on every capture and board.
    for (board, elf) in &product_elfs {
        eprintln!("xtask: product firmware on {}", board.name);
        let extra = firmware_host_args(board.target, BankChoice::Product);
        for capture in &captures {
            equivalence(board, elf, capture, &extra)?;
        }
    }
    // The small-MCU firmware prints the CSV of `nav440 estimate --axis yaw` (`--fixed` on
    // thumbv6m), byte for byte, on every capture.
    for (board, label, elf) in &small_elfs {
        eprintln!("xtask: small-MCU firmware: {label}");
        for capture in &captures {
            equivalence(board, elf, capture, small_host_args(board.target))?;
        }
    }
    // The noise-adaptive firmware prints the CSV of `nav440 estimate --gains
    // schedule_fig5.toml`, byte for byte: on a capture whose yaw noise switches from 0.01 to
    // 0.5 deg^2 at 10 s (the gains follow it: several retunes) and on the noise-free bundled
    // capture (the lowest level).
    let switch = work_dir()?.join("ci-noise-switch.bin");
    nav440_synth(
        &switch,
        &[
            "--duration",
            "20",
            "--seed",
            "2",
            "--yaw-noise",
            "0.01",
            "--yaw-noise",
            "0.5@10",
            "--noise-seed",
            "3",
        ],
    )?;
    for (board, elf) in &adaptive_elfs {
        let args = adaptive_host_args(board.target);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (c, csv) = equivalence_csv(board, elf, &switch, &args)?;
        // The gains followed the noise: the initial level, then 0.01 deg^2, then 0.5.
        let retunes = counter(&c, "yaw_retunes").unwrap_or(0);
        if retunes < 2 {
            return Err(format!(
                "the adaptive firmware on {} retuned its yaw gains {retunes} times on a noise switch (expected at least 2)",
                board.name
            ));
        }
        eprintln!(
            "xtask: OK: adaptive gains on {}: yaw_retunes={retunes}",
            board.name
        );
        // Identical is not enough: both sides once printed a fixed-point AVE saturated at
        // 2.1e9 deg/s (docs/CALIBRATION.md, "Gains at the edge of the Euler step"). The
        // capture's peak rate is 265 deg/s.
        let peak = peak_velocity(&csv, "yaw_")?;
        if peak >= 1000.0 {
            return Err(format!(
                "the adaptive firmware on {} printed a yaw velocity estimate of {peak} deg/s on the noise switch (peak rate 265 deg/s)",
                board.name
            ));
        }
        eprintln!(
            "xtask: OK: adaptive gains on {}: yaw velocity estimates within {peak:.1} deg/s",
            board.name
        );
        equivalence(board, elf, &bundled, &args)?;
        // The schedule (tuned at 100 Hz) on the 20 Hz capture: the same CSV as the host, and
        // the firmware says it runs off its rate (only there: 0 on the 100 Hz captures).
        let c20 = equivalence(board, elf, &root().join(SPIN_20HZ), &args)?;
        for (cc, name, off) in [(&c, "the noise switch", 0), (&c20, SPIN_20HZ, 1)] {
            let got = counter(cc, "yaw_schedule_off_rate");
            if got != Some(off) {
                return Err(format!(
                    "the adaptive firmware on {} reported yaw_schedule_off_rate={got:?} on {name} (expected {off})",
                    board.name
                ));
            }
        }
        eprintln!(
            "xtask: OK: adaptive gains on {}: the 100 Hz schedule is reported off its rate on {SPIN_20HZ} only",
            board.name
        );
    }
    // Input without the length prefix is refused with exit status 1 (never a hang).
    let m4f_board = elfs[0].0;
    let raw = read_file(&bundled)?;
    let path = qemu::input_path(&work_dir()?, "noprefix");
    let r = qemu::run_uart(
        &m4f_board,
        &elfs[0].1,
        &path,
        raw.get(..4096).unwrap_or(&raw),
        Output::Capture,
        Duration::from_secs(60),
    );
    let _ = std::fs::remove_file(&path);
    match r {
        Err(e) if e.contains("N4LP") => {
            eprintln!("xtask: OK: input without the length prefix ends with exit status 1")
        }
        Err(e) => return Err(format!("unexpected failure of the no-prefix check: {e}")),
        Ok(_) => return Err("input without the length prefix was accepted".into()),
    }
    // The firmware against the simulated unit: boot, configure, stream, estimate, faults.
    ci_unit(None)?;
    // A panic ends the run with exit status 1 and its message.
    let panic_elf = build(m4f_board.target, &[], "panic_check")?;
    match qemu::run_plain(&m4f_board, &panic_elf, &[], Duration::from_secs(60)) {
        Err(e) if e.contains("firmware: panic") => {
            eprintln!("xtask: OK: a panic ends the firmware with exit status 1")
        }
        Err(e) => return Err(format!("unexpected failure of the panic check: {e}")),
        Ok(_) => return Err("the panic check firmware exited with status 0".into()),
    }
    // A hard-float image on the FPU-less board must fault and exit non-zero, not hang.
    let m4f = &elfs[0].1;
    let an385 = qemu::board("an385")?;
    match qemu::run_plain(&an385, m4f, &[], Duration::from_secs(60)) {
        Err(e) if e.contains("HardFault") => {
            eprintln!(
                "xtask: OK: hard-float image on the Cortex-M3 board ends with a HardFault exit"
            )
        }
        Err(e) => return Err(format!("unexpected failure of the fault check: {e}")),
        Ok(_) => return Err("hard-float image ran on the FPU-less board without a fault".into()),
    }
    bench(qemu::BOARDS[0], false, BankChoice::Paper)?;
    bench(qemu::BOARDS[2], false, BankChoice::Product)?;
    size()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_velocity_reads_the_velocity_columns_of_one_axis() {
        let csv = "t,yaw,yaw_rate,yaw_ave_v,yaw_ave_a,pitch_ave_v\n0,1,900,-12.5,5000,7000\n0.01,2,0,3,0,0\n";
        // Not the angle, the reference rate, an acceleration or another axis.
        assert_eq!(peak_velocity(csv, "yaw_").unwrap(), 12.5);
        assert_eq!(peak_velocity(csv, "pitch_").unwrap(), 7000.0);
        let nan = "t,yaw_ave_v\n0,NaN\n0.01,1\n";
        assert_eq!(peak_velocity(nan, "yaw_").unwrap(), f64::INFINITY);
        assert!(peak_velocity(csv, "roll_").is_err());
        assert!(peak_velocity("t,yaw_ave_v\n0,x\n", "yaw_").is_err());
    }

    #[test]
    fn counters_line_is_parsed() {
        let err = "qemu noise\nfirmware: bytes=10 frames=2 crc_errors=1 skipped=3 uart_overruns=0 stack_peak=7000\n";
        let c = counters(err);
        assert_eq!(counter(&c, "bytes"), Some(10));
        assert_eq!(counter(&c, "crc_errors"), Some(1));
        assert_eq!(counter(&c, "stack_peak"), Some(7000));
        assert_eq!(counter(&c, "missing"), None);
    }

    #[test]
    fn csv_comparison_is_textual() {
        let a = "t,yaw\n0.0000,1.5\n0.0100,2\n";
        assert_eq!(compare_csv(a, a), Ok(3));
        // 2 and 2.0 are the same number but not the same text: a difference.
        let b = "t,yaw\n0.0000,1.5\n0.0100,2.0\n";
        assert!(compare_csv(a, b).is_err_and(|e| e.starts_with("line 3")));
        assert!(compare_csv(a, "t,yaw\n0.0000,1.5\n").is_err());
        let d = max_abs_diff(a, b).unwrap_or_default();
        assert_eq!(d, vec![("t".to_owned(), 0.0), ("yaw".to_owned(), 0.0)]);
    }

    #[test]
    fn image_names_say_bank_target_and_axes() {
        assert_eq!(
            image_name("product", "thumbv6m-none-eabi", 3, ""),
            "product-thumbv6m-3axis"
        );
        assert_eq!(
            image_name("paper", "thumbv7em-none-eabihf", 1, "-small"),
            "paper-thumbv7em-1axis-small"
        );
    }

    #[test]
    fn vsqrt_cycles_enter_the_estimate() {
        let m = Measure {
            label: "x".into(),
            instr: 1000.0,
            unit: "sample".into(),
            sqrt: 100.0,
        };
        assert_eq!(m.cycles(), 900.0 * ASSUMED_CPI + 100.0 * VSQRT_CYCLES);
    }
}
