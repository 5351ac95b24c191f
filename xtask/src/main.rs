//! `cargo xtask`: the project's automation (cargo-xtask convention).
//!
//! * `cargo xtask ci`    - everything CI checks (the README's test command; `.ci/run` calls it).
//! * `cargo xtask demo`  - builds the firmware, runs it in QEMU fed the bundled capture through
//!   the emulated UART, prints the estimates and a summary.
//! * `cargo xtask qemu FILE [--board B]` - any capture through the firmware, CSV on stdout.
//! * `cargo xtask bench` - instruction counts on the target (QEMU `-icount`, SysTick).
//! * `cargo xtask size`  - flash/RAM of the firmware (llvm-size) and RAM per estimator.

mod firmware;
mod qemu;

use std::process::{Command, ExitCode};

/// The no_std library crates that must cross-compile for every thumb target.
const NO_STD_CRATES: &[&str] = &["nav440-proto", "estimators"];
/// Cortex-M targets pinned in `rust-toolchain.toml`.
const THUMB_TARGETS: &[&str] = &[
    "thumbv7em-none-eabihf",
    "thumbv7m-none-eabi",
    "thumbv6m-none-eabi",
];

const USAGE: &str = "usage: cargo xtask <command>
  ci                          everything CI checks
  ci-firmware                 only the firmware part of ci (QEMU runs, equivalence, cross builds)
  demo [--board B] [--capture FILE]
                              firmware in QEMU fed the bundled capture over UART0: estimates + summary
  qemu FILE [--board B]       FILE through the firmware in QEMU; CSV on stdout, counters on stderr
  bench                       instructions per estimator update / bank update / parsed byte (QEMU -icount)
  size                        flash/RAM of the firmware (llvm-size) and RAM per estimator
boards: an386 (default, Cortex-M4F, f32), an385 (Cortex-M3, thumbv7m, fixed point),
        an385-v6m (thumbv6m image on the Cortex-M3 board, fixed point)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let rest = args.get(1..).unwrap_or_default();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("ci-firmware") => firmware::ci_steps(),
        Some("demo") => firmware::demo(rest),
        Some("qemu") => firmware::qemu(rest),
        Some("bench") => firmware::bench(rest),
        Some("size") => firmware::size(rest),
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        _ => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Runs a command with extra environment variables, echoing it; an error names the command.
fn run_env(program: &str, args: &[&str], env: &[(&str, &str)]) -> Result<(), String> {
    eprintln!("+ {program} {}", args.join(" "));
    let status = Command::new(program)
        .args(args)
        .envs(env.iter().copied())
        .status()
        .map_err(|e| format!("cannot start `{program}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{program} {}` failed ({status})", args.join(" ")))
    }
}

/// Runs a command, echoing it; an error names the command that failed.
fn run(program: &str, args: &[&str]) -> Result<(), String> {
    run_env(program, args, &[])
}

fn cargo(args: &[&str]) -> Result<(), String> {
    run(env!("CARGO"), args)
}

fn ci() -> Result<(), String> {
    let start = std::time::Instant::now();
    cargo(&["fmt", "--all", "--", "--check"])?;
    cargo(&["clippy", "--all-targets", "--", "-D", "warnings"])?;
    for target in THUMB_TARGETS {
        for krate in NO_STD_CRATES {
            cargo(&[
                "clippy", "-p", krate, "--target", target, "--", "-D", "warnings",
            ])?;
            cargo(&["build", "-p", krate, "--target", target, "--release"])?;
            cargo(&[
                "build",
                "-p",
                krate,
                "--target",
                target,
                "--release",
                "--features",
                "defmt",
            ])?;
        }
    }
    cargo(&["test", "--all-targets"])?;
    cargo(&["test", "--doc"])?;
    firmware::ci_steps()?;
    eprintln!(
        "xtask ci: all checks passed in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
