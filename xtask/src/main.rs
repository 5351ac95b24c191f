//! `cargo xtask`: the project's automation (cargo-xtask convention).
//!
//! * `cargo xtask ci`   - everything CI checks (the README's test command; `.ci/run` calls it).
//!
//! Further subcommands (demo, qemu, bench, size) come with the firmware issue.

use std::process::{Command, ExitCode};

/// The no_std library crates that must cross-compile for every thumb target.
const NO_STD_CRATES: &[&str] = &["nav440-proto", "estimators"];
/// Cortex-M targets pinned in `rust-toolchain.toml`.
const THUMB_TARGETS: &[&str] = &[
    "thumbv7em-none-eabihf",
    "thumbv7m-none-eabi",
    "thumbv6m-none-eabi",
];

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci(),
        _ => {
            eprintln!("usage: cargo xtask <ci>");
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

/// Runs a command, echoing it; an error names the command that failed.
fn run(program: &str, args: &[&str]) -> Result<(), String> {
    eprintln!("+ {program} {}", args.join(" "));
    let status = Command::new(program)
        .args(args)
        .status()
        .map_err(|e| format!("cannot start `{program}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{program} {}` failed ({status})", args.join(" ")))
    }
}

fn cargo(args: &[&str]) -> Result<(), String> {
    run(env!("CARGO"), args)
}

fn ci() -> Result<(), String> {
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
    eprintln!("xtask ci: all checks passed");
    Ok(())
}
