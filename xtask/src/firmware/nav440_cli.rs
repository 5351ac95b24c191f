//! The host CLI `nav440` as xtask drives it: built and run through cargo (`estimate`,
//! `synth`), the simulated unit (`sim`), and the `nav440 estimate` arguments that print the CSV
//! of each firmware image.

use super::{root, target_dir, BankChoice};
use crate::cargo;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// The cargo profile of the `nav440` binary xtask runs: the one `cargo xtask ci`'s release-mode
/// tests build it with (`Cargo.toml`), so the tests and the checks share one build.
pub const NAV440_PROFILE: &str = "fast-release";

/// `nav440 synth ARGS -o OUT` (the host CLI's capture generator).
pub(super) fn nav440_synth(out: &Path, args: &[&str]) -> Result<(), String> {
    let nav440 = nav440_bin()?;
    let out_s = out.display().to_string();
    let mut all = vec!["synth"];
    all.extend_from_slice(args);
    all.extend(["-o", &out_s]);
    crate::run(&nav440.display().to_string(), &all)
}

/// The `nav440` binary xtask runs, once known ([`nav440_bin`], [`adopt_nav440`]).
static NAV440: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();

/// The `nav440` binary of the host CLI: built once per xtask run ([`NAV440_PROFILE`]) and
/// copied to the work directory, so later cargo builds never replace it under a running job.
pub(super) fn nav440_bin() -> Result<PathBuf, String> {
    NAV440
        .get_or_init(|| {
            cargo(&[
                "build",
                "-q",
                "-p",
                "nav440-cli",
                "--bin",
                "nav440",
                "--profile",
                NAV440_PROFILE,
            ])?;
            copy_nav440()
        })
        .clone()
}

/// Takes the `nav440` that cargo just built in [`NAV440_PROFILE`] as the binary of this run:
/// `cargo xtask ci` calls it right after its release-mode tests, whose build includes the
/// binary (nav440-cli's tests run it), so the tests and the checks share that one build.
pub fn adopt_nav440() -> Result<(), String> {
    let bin = NAV440.get_or_init(copy_nav440).clone()?;
    eprintln!(
        "xtask: the checks run {} (the release-mode tests' build)",
        bin.display()
    );
    Ok(())
}

/// Copies `nav440` from cargo's [`NAV440_PROFILE`] output to the work directory.
fn copy_nav440() -> Result<PathBuf, String> {
    let built = target_dir().join(NAV440_PROFILE).join("nav440");
    // Earlier runs' copies go (a copy still running elsewhere keeps its open inode).
    let dir = super::work_dir()?;
    for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with("nav440-") && name.ends_with(".bin") {
            let _ = std::fs::remove_file(e.path());
        }
    }
    let copy = super::unique_path("nav440", "bin")?;
    std::fs::copy(&built, &copy)
        .map_err(|e| format!("cannot copy {} to {}: {e}", built.display(), copy.display()))?;
    Ok(copy)
}

/// A running `nav440 sim`, killed when dropped.
pub(super) struct Sim {
    child: std::process::Child,
    pub(super) addr: String,
}

impl Sim {
    /// `nav440 sim CAPTURE --listen tcp:127.0.0.1:0 [--record RECORD] EXTRA...`; the address
    /// is the line the simulator prints on stdout once it listens.
    pub(super) fn start(
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
    pub(super) fn wait(mut self, timeout: Duration) -> Result<std::process::ExitStatus, String> {
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

/// `nav440 estimate` arguments that print the small-MCU firmware's CSV on `target`.
pub(super) fn small_host_args(target: &str) -> &'static [&'static str] {
    if target == "thumbv7em-none-eabihf" {
        &["--axis", "yaw"]
    } else {
        &["--fixed", "--axis", "yaw"]
    }
}

/// The schedule the `adaptive-gains` firmware is built with (its `.rs` twin is included by
/// `firmware-example/src/pipeline.rs`), relative to the workspace root.
const ADAPTIVE_SCHEDULE: &str = "host-tests/data/gains/schedule_fig5.toml";

/// `nav440 estimate` arguments that print the `adaptive-gains` firmware's CSV on `target`.
pub(super) fn adaptive_host_args(target: &str) -> Vec<String> {
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

/// The `nav440 estimate --axis` value that prints the firmware's CSV: the firmware estimates
/// the axes of `firmware_example::pipeline::AXES` (all three; keep the two in step).
pub(super) const FIRMWARE_AXIS: &str = "all";

/// The `nav440 estimate` arguments that print the CSV of the three-axis firmware built for
/// `target` with `bank`: `--fixed` where the target has no FPU (the fixed-point bank).
pub(super) fn firmware_host_args(target: &str, bank: BankChoice) -> Vec<&'static str> {
    let mut a = if target == "thumbv7em-none-eabihf" {
        vec!["--axis", FIRMWARE_AXIS]
    } else {
        vec!["--fixed", "--axis", FIRMWARE_AXIS]
    };
    a.extend(bank.host_args());
    a
}

/// `nav440 estimate FILE [extra]` on the host; its CSV.
pub(super) fn host_estimate(file: &Path, extra: &[&str]) -> Result<String, String> {
    let nav440 = nav440_bin()?;
    let f = file.display().to_string();
    let mut args = vec!["estimate", &f];
    args.extend_from_slice(extra);
    eprintln!("+ {} {}", nav440.display(), args.join(" "));
    let o = Command::new(&nav440)
        .args(&args)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", nav440.display()))?;
    if !o.status.success() {
        return Err(format!(
            "`nav440 estimate` failed: {}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    String::from_utf8(o.stdout).map_err(|_| "nav440 printed non-UTF-8".into())
}
