//! Finding or installing `qemu-system-arm`, the emulated boards, and running firmware in QEMU.

use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

/// An emulated board the firmware runs on, and the Rust target built for it.
#[derive(Clone, Copy, Debug)]
pub struct Board {
    /// Name used on the command line (`--board`).
    pub name: &'static str,
    /// QEMU `-machine`.
    pub machine: &'static str,
    /// QEMU `-cpu`.
    pub cpu: &'static str,
    /// Rust target triple of the image.
    pub target: &'static str,
    /// What it is, for help texts.
    pub about: &'static str,
    /// Cargo features of the firmware image for this board.
    pub features: &'static [&'static str],
}

/// Boards `cargo xtask qemu/demo --board` accepts; the first is the default.
pub const BOARDS: &[Board] = &[
    Board {
        name: "an386",
        machine: "mps2-an386",
        cpu: "cortex-m4",
        target: "thumbv7em-none-eabihf",
        about: "Cortex-M4F, f32 bank (default)",
        features: &[],
    },
    Board {
        name: "an385",
        machine: "mps2-an385",
        cpu: "cortex-m3",
        target: "thumbv7m-none-eabi",
        about: "Cortex-M3, no FPU, fixed-point bank",
        features: &[],
    },
    Board {
        name: "an385-v6m",
        machine: "mps2-an385",
        cpu: "cortex-m3",
        target: "thumbv6m-none-eabi",
        about: "thumbv6m (Cortex-M0 instruction set) image run on the Cortex-M3 board, fixed-point bank",
        features: &[],
    },
];

/// The STM32F405 board image (`board-stm32f405` on stm32f4xx-hal, linked at the chip's flash,
/// `0x0800_0000`) on QEMU's STM32F405 board: the very ELF `cargo run --features
/// board-stm32f405` flashes; `cargo xtask unit --board netduinoplus2` (its firmware retries a
/// failed boot forever).
pub const STM32_BOARD: Board = Board {
    name: "netduinoplus2",
    machine: "netduinoplus2",
    cpu: "cortex-m4",
    target: "thumbv7em-none-eabihf",
    about: "STM32F405 (board image board-stm32f405 on stm32f4xx-hal), f32 bank",
    // The image writes its defmt frames to RTT and, when it finds itself emulated, also to the
    // semihosting stdout (firmware-example/src/log.rs).
    features: &["board-stm32f405"],
};

/// Looks a board up by name among [`BOARDS`] and [`STM32_BOARD`] (`cargo xtask unit`).
pub fn unit_board(name: &str) -> Result<Board, String> {
    if name == STM32_BOARD.name {
        return Ok(STM32_BOARD);
    }
    board(name).map_err(|e| format!("{e}, {}", STM32_BOARD.name))
}

/// Looks a board up by name.
pub fn board(name: &str) -> Result<Board, String> {
    BOARDS
        .iter()
        .copied()
        .find(|b| b.name == name)
        .ok_or_else(|| {
            let names: Vec<_> = BOARDS.iter().map(|b| b.name).collect();
            format!("unknown board `{name}` (known: {})", names.join(", "))
        })
}

const QEMU: &str = "qemu-system-arm";

fn qemu_version() -> Option<String> {
    let out = Command::new(QEMU).arg("--version").output().ok()?;
    if !out.status.success() {
        return None;
    }
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .next()
        .map(str::to_owned)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

fn have(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program}")])
        .stdout(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// The major version in QEMU's `--version` line (`QEMU emulator version 10.0.2 (...)` -> 10).
fn major_of(line: &str) -> Option<u32> {
    let v = line.split("version ").nth(1)?;
    v.split('.').next()?.trim().parse().ok()
}

/// Makes sure `qemu-system-arm` is runnable: installs it with apt-get (as root, or through
/// `sudo -n`) when missing; otherwise fails with the exact command to run.
pub fn ensure_qemu() -> Result<(), String> {
    if let Some(v) = qemu_version() {
        eprintln!("xtask: using {v}");
        return Ok(());
    }
    let hint = "install it with `sudo apt-get install qemu-system-arm` (Debian/Ubuntu), \
                `sudo dnf install qemu-system-arm` (Fedora) or `brew install qemu` (macOS)";
    let sudo = apt_sudo().map_err(|e| format!("`{QEMU}` not found and {e}: {hint}"))?;
    eprintln!("xtask: `{QEMU}` not found, installing it with apt-get");
    apt(sudo, &["update"])
        .and_then(|()| apt(sudo, &["install", "-y", "--no-install-recommends", QEMU]))
        .map_err(|e| format!("installing QEMU failed ({e}); {hint}"))?;
    match qemu_version() {
        Some(v) => {
            eprintln!("xtask: installed {v}");
            Ok(())
        }
        None => Err(format!("`{QEMU}` still not runnable after apt-get; {hint}")),
    }
}

/// Makes sure `tmux` runs (the test of `nav440 live --plot` draws its chart in a tmux pane):
/// installs it with apt-get, as [`ensure_qemu`] installs QEMU, when missing.
pub fn ensure_tmux() -> Result<(), String> {
    let hint = "install it with `sudo apt-get install tmux` (Debian/Ubuntu), \
                `sudo dnf install tmux` (Fedora) or `brew install tmux` (macOS)";
    if !have("tmux") {
        let sudo = apt_sudo().map_err(|e| format!("`tmux` not found and {e}: {hint}"))?;
        eprintln!("xtask: `tmux` not found, installing it with apt-get");
        apt(sudo, &["update"])
            .and_then(|()| apt(sudo, &["install", "-y", "--no-install-recommends", "tmux"]))
            .map_err(|e| format!("installing tmux failed ({e}); {hint}"))?;
    }
    let out = Command::new("tmux")
        .arg("-V")
        .output()
        .map_err(|e| format!("`tmux -V` failed ({e}); {hint}"))?;
    eprintln!(
        "xtask: using {}",
        String::from_utf8_lossy(&out.stdout).trim()
    );
    Ok(())
}

/// How apt-get runs here: `Ok(&[])` as root, `Ok(["sudo", "-n"])` with sudo; the reason
/// otherwise.
fn apt_sudo() -> Result<&'static [&'static str], String> {
    if !have("apt-get") {
        Err("apt-get is not available".to_owned())
    } else if is_root() {
        Ok(&[])
    } else if have("sudo") {
        Ok(&["sudo", "-n"])
    } else {
        Err("not root (no sudo)".to_owned())
    }
}

/// Runs apt-get with `args` (through `sudo`), its output on stderr.
fn apt(sudo: &[&str], args: &[&str]) -> Result<(), String> {
    let mut all: Vec<&str> = sudo.to_vec();
    all.push("apt-get");
    all.extend_from_slice(args);
    let (prog, rest) = all.split_first().expect("non-empty");
    crate::run_to_stderr(prog, rest, &[("DEBIAN_FRONTEND", "noninteractive")])
}

/// The oldest QEMU whose STM32 machines [`qemu10`] gives: QEMU 10 has the `b-l475e-iot01a`
/// machine with the STM32L4x5's RCC, and a `netduinoplus2` whose RCC keeps clock enables.
pub const QEMU10_MAJOR: u32 = 10;

/// The suite Debian 12 (bookworm) has QEMU 10 in.
const BACKPORTS: &str = "bookworm-backports";

/// Where [`qemu10`] adds [`BACKPORTS`] to apt's sources when none names it.
const BACKPORTS_LIST: &str = "/etc/apt/sources.list.d/bookworm-backports.list";

/// Whether a file of apt's sources already names [`BACKPORTS`].
fn backports_listed() -> bool {
    let mut files = vec![PathBuf::from("/etc/apt/sources.list")];
    if let Ok(dir) = std::fs::read_dir("/etc/apt/sources.list.d") {
        files.extend(dir.flatten().map(|e| e.path()));
    }
    files.iter().any(|f| {
        std::fs::read_to_string(f).is_ok_and(|t| {
            t.lines()
                .filter(|l| !l.trim_start().starts_with('#'))
                .any(|l| l.contains(BACKPORTS))
        })
    })
}

/// A `qemu-system-arm` of QEMU 10 or later, and its `--version` line: the system's when it is
/// one, else a copy of Debian 12's bookworm-backports package unpacked under `dir` (fetched
/// with `apt-get download` the first time, the suite added to apt's sources when none names
/// it; the system's QEMU stays as it is). The copy runs with `-audio none` (see
/// [`QEMU10_ARGS`]). Fails, saying what to install, elsewhere.
pub fn qemu10(dir: &Path) -> Result<(PathBuf, String), String> {
    if let Some(v) = qemu_version().filter(|v| major_of(v) >= Some(QEMU10_MAJOR)) {
        return Ok((PathBuf::from(QEMU), v));
    }
    let bin = dir.join("usr/bin").join(QEMU);
    let version = |bin: &Path| {
        let out = Command::new(bin).arg("--version").output().ok()?;
        let line = String::from_utf8_lossy(&out.stdout)
            .lines()
            .next()?
            .to_owned();
        (major_of(&line) >= Some(QEMU10_MAJOR)).then_some(line)
    };
    if let Some(v) = version(&bin) {
        return Ok((bin, v));
    }
    let have_v = qemu_version().unwrap_or_else(|| "no qemu-system-arm".to_owned());
    let refuse = |why: String| {
        format!(
            "the STM32 machines need QEMU {QEMU10_MAJOR} or later; this machine has {have_v}, and {why}: install qemu-system-arm {QEMU10_MAJOR}.0 or later (Debian 12: from {BACKPORTS})"
        )
    };
    let debian12 = std::fs::read_to_string("/etc/os-release")
        .is_ok_and(|t| t.lines().any(|l| l.trim() == "VERSION_CODENAME=bookworm"));
    if !debian12 {
        return Err(refuse("this is not Debian 12".to_owned()));
    }
    let sudo = apt_sudo().map_err(refuse)?;
    if !backports_listed() {
        eprintln!("xtask: adding {BACKPORTS} to apt's sources ({BACKPORTS_LIST})");
        let line = format!("deb http://deb.debian.org/debian {BACKPORTS} main\n");
        let mut tee: Vec<&str> = sudo.to_vec();
        tee.extend(["tee", BACKPORTS_LIST]);
        let (prog, rest) = tee.split_first().expect("non-empty");
        let mut child = Command::new(prog)
            .args(rest)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .map_err(|e| refuse(format!("tee cannot run: {e}")))?;
        child
            .stdin
            .take()
            .ok_or("tee's stdin is not piped")?
            .write_all(line.as_bytes())
            .map_err(|e| refuse(format!("{BACKPORTS_LIST} cannot be written: {e}")))?;
        if !child.wait().map_err(|e| e.to_string())?.success() {
            return Err(refuse(format!("{BACKPORTS_LIST} cannot be written")));
        }
    }
    apt(sudo, &["update"]).map_err(refuse)?;
    let download = dir.join("download");
    std::fs::create_dir_all(&download)
        .map_err(|e| format!("cannot create {}: {e}", download.display()))?;
    let pkg = format!("{QEMU}/{BACKPORTS}");
    eprintln!("+ apt-get download {pkg} (in {})", download.display());
    let got = Command::new("apt-get")
        .args(["download", &pkg])
        .current_dir(&download)
        .stdout(Stdio::from(std::io::stderr()))
        .status()
        .map_err(|e| refuse(format!("apt-get cannot run: {e}")))?;
    if !got.success() {
        return Err(refuse(format!("`apt-get download {pkg}` failed ({got})")));
    }
    let deb = std::fs::read_dir(&download)
        .map_err(|e| e.to_string())?
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "deb"))
        .ok_or_else(|| refuse("apt-get download left no .deb".to_owned()))?;
    crate::run_to_stderr(
        "dpkg-deb",
        &["-x", &deb.display().to_string(), &dir.display().to_string()],
        &[],
    )
    .map_err(refuse)?;
    let _ = std::fs::remove_dir_all(&download);
    let v = version(&bin).ok_or_else(|| refuse(format!("{} does not run", bin.display())))?;
    eprintln!("xtask: unpacked {v} into {}", dir.display());
    Ok((bin, v))
}

/// Arguments every run of [`qemu10`]'s binary takes: no audio back-end (a copy unpacked beside
/// the system's QEMU 7.2 would otherwise try the system's audio modules, of another build, and
/// warn).
pub const QEMU10_ARGS: &[&str] = &["-audio", "none"];

/// [`ensure_qemu`] for a step that runs `what` on QEMU: `Ok(true)` when QEMU is there (or
/// installed); `Ok(false)`, said loudly, when it is not and `XTASK_SKIP_QEMU=1` (a machine where
/// QEMU cannot be installed: the step's lints and builds still run); the error otherwise.
pub fn ensure_or_skip(what: &str) -> Result<bool, String> {
    match ensure_qemu() {
        Ok(()) => Ok(true),
        Err(e) if std::env::var("XTASK_SKIP_QEMU").is_ok_and(|v| v == "1") => {
            let bar = "!".repeat(78);
            eprintln!("{bar}\nxtask: XTASK_SKIP_QEMU=1: SKIPPING {what}: {e}\n{bar}");
            Ok(false)
        }
        Err(e) => Err(format!(
            "{e}\n(set XTASK_SKIP_QEMU=1 to run the other checks without the QEMU part)"
        )),
    }
}

/// True when `qemu-system-arm` runs (no install attempt).
pub fn qemu_available() -> bool {
    qemu_version().is_some()
}

/// Magic of the length prefix that announces a finite capture to the firmware.
pub const LENGTH_MAGIC: &[u8; 4] = b"N4LP";

/// The byte stream sent through the emulated UART: `"N4LP"`, the capture's length as u32
/// little-endian, then the capture itself (see the firmware's end-of-input convention).
pub fn framed_input(capture: &[u8]) -> Result<Vec<u8>, String> {
    let len = u32::try_from(capture.len()).map_err(|_| "capture larger than 4 GiB".to_owned())?;
    let mut v = Vec::with_capacity(capture.len() + 8);
    v.extend_from_slice(LENGTH_MAGIC);
    v.extend_from_slice(&len.to_le_bytes());
    v.extend_from_slice(capture);
    Ok(v)
}

/// Where the firmware's standard output goes.
pub enum Output {
    /// Straight to this process's stdout (streaming).
    Inherit,
    /// Collected and returned.
    Capture,
}

/// What one QEMU run produced.
pub struct RunResult {
    /// The firmware's semihosting stdout (empty with [`Output::Inherit`]).
    pub stdout: String,
    /// The firmware's semihosting stderr (counters, diagnostics) and QEMU's own messages.
    pub stderr: String,
}

/// Common QEMU arguments for `board` running `elf`, with `semihosting_args` as the
/// program's command line (`arg=` items).
pub fn base_args(board: &Board, elf: &Path, semihosting_args: &[&str]) -> Vec<String> {
    let mut semihosting = "enable=on,target=native".to_owned();
    if !semihosting_args.is_empty() {
        semihosting.push_str(",arg=firmware");
        for a in semihosting_args {
            semihosting.push_str(",arg=");
            semihosting.push_str(a);
        }
    }
    [
        "-machine",
        board.machine,
        "-cpu",
        board.cpu,
        "-display",
        "none",
        "-monitor",
        "none",
        "-semihosting-config",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .chain([semihosting, "-kernel".to_owned(), elf.display().to_string()])
    .collect()
}

/// Runs `elf` on `board`, feeding `input` (already framed) through UART0 via QEMU's stdio
/// chardev (`mux=off` so no byte is taken as an escape). Fails on a non-zero exit status or
/// when the run exceeds `timeout` (then QEMU is killed: a hung firmware never hangs CI).
pub fn run_uart(
    board: &Board,
    elf: &Path,
    input_file: &Path,
    input: &[u8],
    output: Output,
    timeout: Duration,
) -> Result<RunResult, String> {
    File::create(input_file)
        .and_then(|mut f| f.write_all(input))
        .map_err(|e| format!("cannot write {}: {e}", input_file.display()))?;
    let stdin = File::open(input_file).map_err(|e| format!("{}: {e}", input_file.display()))?;
    // `replay`: the firmware reads an N4LP-prefixed capture instead of configuring a unit.
    let mut args = base_args(board, elf, &["replay"]);
    args.extend(
        [
            "-chardev",
            "stdio,id=u0,mux=off,signal=off",
            "-serial",
            "chardev:u0",
        ]
        .map(str::to_owned),
    );
    let table = crate::defmt_out::table(elf)?;
    run(&args, Stdio::from(stdin), output, table, timeout)
}

/// Runs `elf` on `board` without UART input; `extra` QEMU arguments (e.g. `-icount`).
pub fn run_plain(
    board: &Board,
    elf: &Path,
    extra: &[&str],
    timeout: Duration,
) -> Result<RunResult, String> {
    let mut args = base_args(board, elf, &[]);
    args.extend(["-serial", "none"].map(str::to_owned));
    args.extend(extra.iter().map(|s| (*s).to_owned()));
    run(&args, Stdio::null(), Output::Capture, None, timeout)
}

fn run(
    args: &[String],
    stdin: Stdio,
    output: Output,
    table: Option<defmt_decoder::Table>,
    timeout: Duration,
) -> Result<RunResult, String> {
    eprintln!("+ {QEMU} {}", args.join(" "));
    let start = Instant::now();
    let mut child = Command::new(QEMU)
        .args(args)
        .stdin(stdin)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start {QEMU}: {e} (run `cargo xtask ci` or install it)"))?;
    // The firmware's stdout: defmt frames decoded into CSV + diagnostics (`table`), or text.
    let inherit = matches!(output, Output::Inherit);
    let out_reader = child
        .stdout
        .take()
        .map(|s| crate::defmt_out::spawn_reader(s, table, inherit));
    let mut err_pipe = child.stderr.take().expect("piped");
    let err_reader = thread::spawn(move || {
        // Echo stderr lines live as well as keeping them.
        let mut all = Vec::new();
        let mut chunk = [0u8; 4096];
        loop {
            match err_pipe.read(&mut chunk) {
                Ok(0) | Err(_) => break,
                Ok(n) => all.extend_from_slice(&chunk[..n]),
            }
        }
        String::from_utf8_lossy(&all).into_owned()
    });
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "QEMU did not finish within {} s (killed)",
                    timeout.as_secs()
                ));
            }
            Ok(None) => thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(format!("waiting for QEMU: {e}")),
        }
    };
    let crate::defmt_out::Read { stdout, diag, .. } = out_reader
        .map(|h| h.join().unwrap_or_default())
        .unwrap_or_default();
    // The decoded diagnostics first, then QEMU's own stderr (and text-firmware stderr).
    let stderr = diag + &err_reader.join().unwrap_or_default();
    if !status.success() {
        return Err(format!(
            "firmware run failed ({status}); its stderr:\n{stderr}"
        ));
    }
    Ok(RunResult { stdout, stderr })
}

/// Time limit for a UART run of `bytes` bytes: a last resort against a hung firmware, so
/// generous (QEMU's UART moves 10-40 KB/s, but the fixed-point thumbv6m bank needs about
/// 0.7 ms of host CPU per byte, and CI machines are shared).
pub fn uart_timeout(bytes: usize) -> Duration {
    Duration::from_secs(120 + (bytes / 200) as u64)
}

/// A number no other call in this process returns: runs go on in parallel (`cargo xtask ci`'s
/// job pool), so each names its files with one.
pub fn run_number() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Path of an input file for a run, inside the target directory (unique to the run).
pub fn input_path(dir: &Path, tag: &str) -> PathBuf {
    dir.join(format!(
        "uart-input-{tag}-{}-{}.bin",
        std::process::id(),
        run_number()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_major_version() {
        let v10 = "QEMU emulator version 10.0.2 (Debian 1:10.0.2+ds-2+deb13u1~bpo12+1)";
        assert_eq!(major_of(v10), Some(10));
        assert_eq!(
            major_of("QEMU emulator version 7.2.22 (Debian 1:7.2+dfsg-7+deb12u18+b3)"),
            Some(7)
        );
        assert_eq!(major_of("qemu-system-arm: no version"), None);
    }

    #[test]
    fn framed_input_has_magic_and_le_length() {
        let v = framed_input(&[0x55, 0x55, 0x41]).unwrap_or_default();
        assert_eq!(v, [b'N', b'4', b'L', b'P', 3, 0, 0, 0, 0x55, 0x55, 0x41]);
    }

    #[test]
    fn boards_are_found_by_name() {
        assert_eq!(board("an386").map(|b| b.machine), Ok("mps2-an386"));
        assert_eq!(
            board("an385-v6m").map(|b| b.target),
            Ok("thumbv6m-none-eabi")
        );
        assert!(board("stm32").is_err());
    }

    /// Each QEMU run is of a machine and a target of the board its features select in
    /// `boards/src/description.rs`, and each machine described there is run.
    #[test]
    fn the_emulated_boards_are_the_described_ones() {
        let runs: Vec<Board> = BOARDS.iter().copied().chain([STM32_BOARD]).collect();
        let described = |r: &Board| {
            let vars: Vec<String> = r
                .features
                .iter()
                .map(|f| nav440_boards::feature_env(f))
                .collect();
            nav440_boards::select(&vars).expect("a described board")
        };
        for r in &runs {
            let d = described(r);
            assert!(d.qemu.contains(&r.machine), "{}", r.name);
            assert!(d.targets.contains(&r.target), "{}", r.name);
        }
        // firmware-example's runs (firmware-embassy's QEMU run is `cargo xtask embassy-stm32`).
        for d in nav440_boards::all().iter().filter(|d| d.example) {
            for m in d.qemu {
                assert!(
                    runs.iter()
                        .any(|r| r.machine == *m && described(r).name == d.name),
                    "{} on {m}",
                    d.name
                );
            }
        }
    }
}
