//! `cargo xtask`: the project's automation (cargo-xtask convention).
//!
//! * `cargo xtask ci`    - everything CI checks (the README's test command; `.ci/run` calls it).
//! * `cargo xtask demo`  - builds the firmware, runs it in QEMU against `nav440 sim` streaming
//!   the bundled capture: boot -> configure -> stream -> estimate, then a summary.
//! * `cargo xtask unit --connect tcp:HOST:PORT [--board B]` - the firmware against any unit
//!   listening on TCP; CSV on stdout, exit status = the firmware's.
//! * `cargo xtask qemu FILE [--board B]` - any capture replayed through the firmware (no
//!   unit, N4LP length prefix), CSV on stdout.
//! * `cargo xtask bench` - instruction counts on the target (QEMU `-icount`, SysTick).
//! * `cargo xtask size`  - flash/RAM of the firmware (llvm-size) and RAM per estimator.
//! * `cargo xtask msrv`  - the libraries' declared `rust-version` checked with that toolchain.
//! * `cargo xtask package` - the libraries' examples run and `cargo publish --dry-run`.
//! * `cargo xtask embassy` - the embassy example (async driver) under QEMU against `nav440 sim`.
//! * `cargo xtask embassy-stm32` - the embassy-stm32 firmware for the STM32F405 and the
//!   NUCLEO-F411RE: doc block check, lints, builds, memory maps, and the QEMU run that shows
//!   what the emulator lacks.
//! * `cargo xtask outside-firmware` - a firmware outside the workspace on the libraries by
//!   version: built for thumbv7em and thumbv6m, map-checked, run on QEMU.
//! * `cargo xtask flash ELF` - the runner of `cargo run` for the firmware: checks a board
//!   image's memory map and flashes it with `probe-rs run --chip` of its board; refuses an
//!   image of the emulated boards.
//! * `cargo xtask check-map ELF...` - the memory-map check of `ci` on any images.

mod defmt_out;
mod elf;
mod firmware;
mod frames;
mod package;
mod pool;
mod qemu;
mod steps;
mod unit;

use clap::{Parser, Subcommand};
use qemu::Board;
use std::path::PathBuf;
use std::process::{Command, ExitCode, Stdio};

/// The no_std library crates that must cross-compile for every thumb target.
const NO_STD_CRATES: &[&str] = &["nav440-proto", "velocity-estimators", "nav440-pipeline"];
/// Cortex-M targets pinned in `rust-toolchain.toml`.
const THUMB_TARGETS: &[&str] = &[
    "thumbv7em-none-eabihf",
    "thumbv7m-none-eabi",
    "thumbv6m-none-eabi",
];

/// The project's automation: CI checks, the firmware under QEMU, benches and sizes.
#[derive(Parser)]
#[command(name = "cargo xtask", bin_name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Everything CI checks (the README's test command; `.ci/run` calls it).
    Ci,
    /// Only the firmware part of `ci` (cross builds, QEMU runs, equivalence with the host).
    CiFirmware,
    /// Only the firmware-against-`nav440 sim` runs of `ci-firmware` (every board, captures
    /// and faults).
    CiUnit {
        /// Only this board (see `unit --help`).
        #[arg(long, value_parser = qemu::unit_board)]
        board: Option<Board>,
    },
    /// The product firmware (STM32F405 image on QEMU netduinoplus2) against `nav440 sim`
    /// streaming at full speed for H hours of stream time, with a silence, a reset, a
    /// frozen-stamp run and a garbage burst injected in every hour: CSV equal to the host's,
    /// every fault reported, stack high-water mark unchanged.
    Soak {
        /// Hours of stream time at 100 Hz (10 minutes to 48 hours).
        #[arg(long, default_value_t = 1.0, value_name = "H")]
        hours: f64,
        /// Seed of the motion and of the injection points.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// The firmware in QEMU against `nav440 sim` streaming the bundled capture: boot,
    /// configuration, stream, estimates and a summary.
    Demo {
        /// Emulated board: an386 (Cortex-M4F, f32), an385 (Cortex-M3, fixed point),
        /// an385-v6m (thumbv6m image on the Cortex-M3 board, fixed point).
        #[arg(long, default_value = "an386", value_parser = qemu::board)]
        board: Board,
        /// Capture the simulated unit streams instead of the bundled
        /// `host-tests/data/fig5_a2_100hz.bin`.
        #[arg(long, value_name = "FILE")]
        capture: Option<PathBuf>,
    },
    /// The firmware in QEMU with its NAV440 UART connected to a unit listening on TCP (e.g.
    /// `nav440 sim`): estimate CSV on stdout, diagnostics and counters on stderr; exit status
    /// = the firmware's (0 once every byte the unit sent before closing was processed).
    Unit {
        /// Address of the unit, `tcp:HOST:PORT`.
        #[arg(long, value_name = "tcp:HOST:PORT", value_parser = unit::parse_connect)]
        connect: String,
        /// Emulated board: an386, an385, an385-v6m (see `demo --help`) or netduinoplus2
        /// (STM32F405, the real-board profile `board-stm32f405`).
        #[arg(long, default_value = "an386", value_parser = qemu::unit_board)]
        board: Board,
        /// Build the image with the feature `uart-rows` and write its output UART (UART2: the
        /// rows as framed binary messages) to FILE; `nav440 rows FILE` prints their CSV (mps2
        /// boards).
        #[arg(long, value_name = "FILE")]
        rows: Option<PathBuf>,
    },
    /// FILE replayed through the firmware in QEMU (no unit; N4LP length prefix): CSV on
    /// stdout, counters on stderr.
    Qemu {
        /// NAV440 capture (raw serial bytes).
        file: PathBuf,
        /// Emulated board (see `demo --help`).
        #[arg(long, default_value = "an386", value_parser = qemu::board)]
        board: Board,
        /// The small-MCU firmware (yaw only, feature `one-axis`, cargo profile `small`):
        /// prints the CSV of `nav440 estimate --axis yaw` (`--fixed` without FPU).
        #[arg(long, conflicts_with = "adaptive")]
        small: bool,
        /// The firmware with noise-adaptive gains (feature `adaptive-gains`): prints the CSV
        /// of `nav440 estimate --gains host-tests/data/gains/schedule_fig5.toml --axis all`
        /// (`--fixed` without FPU).
        #[arg(long, conflicts_with = "bank")]
        adaptive: bool,
        /// The bank the firmware runs: `paper` (the paper's 14 estimators, the default),
        /// `product` (feature `bank-product`: ILO1 velocity + Kalman acceleration, the gains
        /// following the noise and the motion; `nav440 estimate --bank product`; alias
        /// `follow`), `fixed-gains` (feature `fixed-gains`: the same bank with the shipped
        /// gains fixed, float-free; `nav440 estimate --bank product --fixed-gains`) or
        /// `self-tune`, printing the CSV of the `nav440 estimate` arguments named.
        #[arg(long, value_enum, default_value = "paper")]
        bank: firmware::BankChoice,
        /// The firmware without the Euler reference (feature `no-reference`: each axis's
        /// rate column is the unit's body rate, `<axis>_body_rate`), printing the CSV of
        /// `nav440 estimate --no-reference`.
        #[arg(long)]
        no_reference: bool,
    },
    /// Instructions per estimator update, bank update, parsed byte, transmitted byte and boot
    /// sequence (QEMU -icount + SysTick).
    Bench {
        /// Emulated board (see `demo --help`).
        #[arg(long, default_value = "an386", value_parser = qemu::board)]
        board: Board,
        /// The bench built like the small-MCU firmware (feature `one-axis`, cargo profile
        /// `small`, opt-level "z"): what optimising for size costs in instructions.
        #[arg(long)]
        small: bool,
        /// The bank of the firmware pipeline measured (see `qemu --help`).
        #[arg(long, value_enum, default_value = "paper")]
        bank: firmware::BankChoice,
    },
    /// Flash/RAM of the firmware (llvm-size) and RAM per estimator.
    Size {
        /// Instead: the flash per component (crate) of each target's firmware, from the
        /// sizes of the ELF's symbols (llvm-nm).
        #[arg(long)]
        components: bool,
    },
    /// Checks each library with the toolchain of its declared `rust-version` (installed with
    /// rustup when missing), and that the workspace's `rust-version` is the pinned toolchain.
    Msrv,
    /// Runs the libraries' examples and one `cargo publish --dry-run` of the three (needs
    /// crates.io).
    Package,
    /// The embassy example (async driver on embassy-executor) built for thumbv7em and run on
    /// QEMU `mps2-an386` against `nav440 sim`.
    Embassy,
    /// The embassy-stm32 firmware (`firmware-embassy`) for the STM32F405 and the NUCLEO-F411RE:
    /// checks that the async driver's docs show its boot code, lints and builds both images
    /// for thumbv7em, checks their memory maps, and runs the STM32F405 image on QEMU
    /// `netduinoplus2` for a bounded time to assert the documented failure there (no RCC
    /// model: `embassy_stm32::init` waits for HSIRDY).
    EmbassyStm32,
    /// The firmware outside the workspace (`fixtures/outside-firmware`: the three libraries by
    /// version, patched to this checkout) built for thumbv7em and thumbv6m, map-checked and
    /// run on QEMU against `nav440 estimate`.
    OutsideFirmware,
    /// Flashes a board image with probe-rs and prints its defmt output (the runner of `cargo
    /// run` for the firmware, `.cargo/config.toml`): reads the board from the ELF, checks its
    /// memory map, then runs `probe-rs run --chip CHIP ELF`. An image of the emulated `mps2`
    /// boards is refused (run it with `cargo xtask qemu`, `demo` or `unit`).
    Flash {
        /// The firmware ELF (cargo passes it).
        elf: PathBuf,
        /// Further arguments (passed on to the firmware by cargo; not used).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        rest: Vec<String>,
    },
    /// Turns a saved log of a firmware-example image into what `cargo xtask flash` prints:
    /// the CSV of `nav440 estimate` for the image's bank and axes on stdout, diagnostics and
    /// counters on stderr. The log holds the defmt frames as the firmware wrote them (RTT's
    /// `defmt` channel saved raw, or QEMU's semihosting stdout), or with `--text` the lines
    /// `probe-rs run --log-format "{s}"` printed.
    Decode {
        /// The firmware ELF that wrote the log (its defmt table).
        elf: PathBuf,
        /// The log (default: stdin).
        log: Option<PathBuf>,
        /// The log is probe-rs's text, one message per line.
        #[arg(long)]
        text: bool,
    },
    /// Checks firmware images' memory maps against their boards' chips (what `ci` checks for
    /// every image it builds): every loadable section inside flash or RAM, the vector table at
    /// the boot address.
    CheckMap {
        /// Firmware ELF files.
        #[arg(required = true)]
        elfs: Vec<PathBuf>,
    },
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Cmd::Unit {
            connect,
            board,
            rows,
        } => {
            return match firmware::unit(board, &connect, rows.as_deref()) {
                Ok(code) => ExitCode::from(code),
                Err(e) => {
                    eprintln!("xtask: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        Cmd::Ci => ci(),
        Cmd::Flash { elf, rest: _ } => firmware::flash(&elf),
        Cmd::Decode { elf, log, text } => firmware::decode(&elf, log.as_deref(), text),
        Cmd::CheckMap { elfs } => elfs.iter().try_for_each(|e| {
            let r = elf::check_memory_map(e, None)?;
            eprintln!(
                "xtask: OK: {}: board {}, {} loadable sections inside its chip's memory, vector table at {:#010x}",
                e.display(),
                r.board,
                r.sections,
                r.vector_table
            );
            Ok(())
        }),
        Cmd::CiFirmware => firmware::ci_firmware(),
        Cmd::CiUnit { board } => firmware::ci_unit(board),
        Cmd::Soak { hours, seed } => firmware::soak(hours, seed),
        Cmd::Demo { board, capture } => firmware::demo(board, capture),
        Cmd::Qemu {
            file,
            board,
            small,
            adaptive,
            bank,
            no_reference,
        } => firmware::qemu(board, &file, small, adaptive, bank, no_reference),
        Cmd::Bench { board, small, bank } => firmware::bench(board, small, bank),
        Cmd::Size { components: false } => firmware::size(),
        Cmd::Size { components: true } => firmware::size_components(),
        Cmd::Msrv => package::msrv(),
        Cmd::Package => package::package(),
        Cmd::Embassy => firmware::embassy(),
        Cmd::EmbassyStm32 => firmware::embassy_stm32(),
        Cmd::OutsideFirmware => firmware::outside_firmware(),
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
    run_with(program, args, env, Stdio::inherit())
}

/// [`run_env`] with the command's standard output sent to this process's standard error: an
/// installer's log never mixes with what a command prints on stdout (`cargo xtask qemu FILE >
/// out.csv` on a machine without QEMU).
fn run_to_stderr(program: &str, args: &[&str], env: &[(&str, &str)]) -> Result<(), String> {
    run_with(program, args, env, Stdio::from(std::io::stderr()))
}

fn run_with(
    program: &str,
    args: &[&str],
    env: &[(&str, &str)],
    stdout: Stdio,
) -> Result<(), String> {
    eprintln!("+ {program} {}", args.join(" "));
    let started = std::time::Instant::now();
    let status = Command::new(program)
        .args(args)
        .envs(env.iter().copied())
        .stdout(stdout)
        .status()
        .map_err(|e| format!("cannot start `{program}`: {e}"))?;
    // The commands' times, for finding where CI's time goes (`grep '^xtask: took'`).
    let took = started.elapsed().as_secs_f64();
    if took >= 1.0 {
        eprintln!("xtask: took {took:.0} s: {program} {}", args.join(" "));
    }
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

/// The cargo that runs this xtask (`cargo run` sets `CARGO`), so nested builds use the
/// toolchain pinned by `rust-toolchain.toml`.
pub fn cargo_bin() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned())
}

fn cargo(args: &[&str]) -> Result<(), String> {
    run(&cargo_bin(), args)
}

/// The environment `cargo xtask ci` runs every cargo with (see [`ci`]).
const CI_ENV: [(&str, &str); 3] = [
    ("CARGO_INCREMENTAL", "0"),
    ("CARGO_PROFILE_DEV_DEBUG", "line-tables-only"),
    ("CARGO_PROFILE_RELEASE_DEBUG", "line-tables-only"),
];

fn ci() -> Result<(), String> {
    // CI machines have little free disk (a few GB). Every cargo below inherits these: no
    // incremental caches, and line tables instead of full debug info in the dev and release
    // profiles (backtraces keep their file and line; the firmware images' loaded sections and
    // their defmt tables are unchanged).
    for (key, value) in CI_ENV {
        std::env::set_var(key, value);
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("xtask lives in the workspace")?;
    let steps = steps::Steps::new(root);
    let r = ci_steps(&steps);
    eprint!("{}", steps.table());
    match &r {
        Ok(()) => eprintln!("xtask ci: all checks passed"),
        Err(e) => eprintln!("xtask ci: FAILED: {e}"),
    }
    r
}

/// `cargo fmt --check`, and `rustfmt --check` of the firmware's board modules, which `cargo
/// fmt` does not reach: firmware-example's build script declares them (`include!`), from
/// `boards/src/description.rs`.
fn fmt_check() -> Result<(), String> {
    cargo(&["fmt", "--all", "--", "--check"])?;
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware-example/src/board");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .map_err(|e| format!("cannot list {}: {e}", dir.display()))?
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .map(|p| p.display().to_string())
        .collect();
    files.sort();
    let mut args = vec!["--check", "--edition", "2021"];
    args.extend(files.iter().map(String::as_str));
    run("rustfmt", &args)
}

/// The steps of `cargo xtask ci`, in order (docs/TESTS.md lists them with their budgets).
fn ci_steps(steps: &steps::Steps) -> Result<(), String> {
    steps.run("fmt", fmt_check)?;
    steps.run("clippy host", || {
        cargo(&["clippy", "--all-targets", "--", "-D", "warnings"])
    })?;
    steps.run("clippy thumb libraries", thumb_libraries)?;
    steps.run("tmux", qemu::ensure_tmux)?;
    steps.run("host tests", host_tests)?;
    steps.run("doc tests", || {
        cargo(&["test", "--profile", firmware::NAV440_PROFILE, "--doc"])
    })?;
    // From here on every QEMU run is a job of the pool, queued as soon as its image is built,
    // while this thread goes on building.
    let pool = pool::Pool::new(firmware::POOL_THREADS, steps.clone())?;
    let built = build_beside_the_pool(steps, &pool);
    if built.is_err() {
        pool.cancel();
    }
    let waited = steps.run("wait for the QEMU jobs", || pool.wait());
    built.and(waited)
}

/// The steps that build while the pool runs the QEMU jobs.
fn build_beside_the_pool(steps: &steps::Steps, pool: &pool::Pool) -> Result<(), String> {
    firmware::ci_steps(pool)?;
    steps.run("embassy example build", || firmware::embassy_jobs(pool))?;
    steps.run("embassy-stm32", firmware::embassy_stm32)?;
    steps.run("outside firmware", firmware::outside_firmware)?;
    // Rustdoc of the host crates: broken intra-doc links and bad HTML fail the build.
    steps.run("rustdoc", || {
        run_env(
            &cargo_bin(),
            &["doc", "--no-deps"],
            &[("RUSTDOCFLAGS", "-D warnings")],
        )
    })?;
    // The libraries as users get them: examples, publishable packages, declared MSRV.
    steps.run("package", package::package)?;
    steps.run("msrv", package::msrv)?;
    steps.run("size", firmware::size)
}

/// Clippy `-D warnings` of the no_std libraries on every thumb target, without and with their
/// `defmt` feature (and the pipeline's `wire`): type-checking them for a target without `std`
/// proves they are `no_std` (the firmware images, built for the same three targets, compile
/// them to code).
fn thumb_libraries() -> Result<(), String> {
    let mut defmt: Vec<String> = NO_STD_CRATES.iter().map(|k| format!("{k}/defmt")).collect();
    defmt.push("nav440-pipeline/wire".to_owned());
    let defmt = defmt.join(",");
    for target in THUMB_TARGETS {
        for features in [None, Some(defmt.as_str())] {
            let mut args = vec!["clippy", "--target", target];
            for krate in NO_STD_CRATES {
                args.extend(["-p", krate]);
            }
            if let Some(f) = features {
                args.extend(["--features", f]);
            }
            args.extend(["--", "-D", "warnings"]);
            cargo(&args)?;
        }
    }
    Ok(())
}

/// Every host test in one build, in the profile of the `nav440` binary the firmware checks run
/// (`fast-release`: optimised, integer overflow checked): the tests and the checks share that
/// build, and the release-only tests run with the others (they skip in a debug build, which
/// has `debug_assertions`): 10^6 random parser streams, constant-memory streaming of 200+ MiB,
/// the 24 h run of the whole bank (f32 and fixed point, 8.64 M samples each), the tuner's
/// search against its exhaustive grid, the NAV440 preset against the paper's, and the
/// noise-adaptive bank on a noise switch.
fn host_tests() -> Result<(), String> {
    cargo(&[
        "test",
        "--profile",
        firmware::NAV440_PROFILE,
        "--all-targets",
    ])?;
    firmware::adopt_nav440()
}
