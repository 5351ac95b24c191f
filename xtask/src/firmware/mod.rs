//! Firmware subcommands: demo, unit, qemu, bench, size, and the firmware part of `ci`.
//!
//! * [`build`]: cargo builds and lints of the firmware images;
//! * [`nav440_cli`]: the host CLI `nav440` (estimate, synth, sim) and the arguments that print
//!   each image's CSV;
//! * [`captures`]: the bundled captures and the ones CI synthesises;
//! * [`qemu_run`]: a capture or a unit through the firmware in QEMU (`cargo xtask qemu`,
//!   `unit`), the firmware's counters;
//! * [`demo`](mod@demo), [`bench`](mod@bench), [`size`](mod@size), [`flash`](mod@flash),
//!   [`embassy_stm32`](mod@embassy_stm32): those commands;
//! * [`equivalence`]: firmware CSV against `nav440 estimate`;
//! * [`unit_cases`]: the firmware against `nav440 sim` with an expected outcome per case
//!   (`ci-unit`, `embassy`);
//! * [`ci`]: the firmware part of `cargo xtask ci` (`ci-firmware`).

mod bench;
mod build;
mod captures;
mod ci;
mod demo;
mod embassy_stm32;
mod equivalence;
mod flash;
mod nav440_cli;
mod outside;
mod qemu_run;
mod size;
mod soak;
mod twin;
mod unit_cases;

pub use bench::bench;
pub use ci::{ci_firmware, ci_steps};
pub use demo::demo;
pub use embassy_stm32::embassy_stm32;
pub use flash::{decode, flash};
pub use nav440_cli::{adopt_nav440, NAV440_PROFILE};
pub use outside::outside_firmware;
pub use qemu_run::{qemu, unit};
pub use size::{size, size_components};
pub use soak::soak;
pub use unit_cases::{ci_unit, embassy, embassy_jobs};

use std::path::{Path, PathBuf};

/// Threads of the QEMU job pool: a run spends much of its time waiting on its emulated UART or
/// on wall-clock time-outs, so three share two cores with the builds that go on beside them.
pub const POOL_THREADS: usize = 3;

/// The firmware crate.
const FW: &str = "firmware-example";
/// Main firmware binary.
const FW_BIN: &str = "firmware-example";
/// Instruction-count benchmark binary.
const BENCH_BIN: &str = "bench";
/// Feature of the STM32F405 board image (run on QEMU `netduinoplus2` too).
const STM32_FEATURE: &str = "board-stm32f405";

/// The firmware feature of the product bank (its gains follow the noise and the motion
/// unless [`FIXED_GAINS`] or another gains feature says otherwise).
const PRODUCT: &str = "bank-product";

/// The firmware feature of the product bank with the shipped preset's gains fixed, built on
/// the host (float-free).
const FIXED_GAINS: &str = "fixed-gains";

/// Feature of the firmware without the Euler reference (rows with the body rates, no
/// trigonometry linked; `nav440 estimate --no-reference` prints its CSV).
const NO_REFERENCE: &str = "no-reference";

/// The `nav440 estimate` flag that prints the CSV of a [`NO_REFERENCE`] image.
const NO_REFERENCE_ARG: &str = "--no-reference";

/// Feature of the one-axis (yaw) firmware.
const ONE_AXIS: &str = "one-axis";

/// Feature of the firmware that also sends the rows out of a second UART as framed binary
/// messages (`nav440_pipeline::wire`; `nav440 rows` reads them).
const UART_ROWS: &str = "uart-rows";

/// Feature of the firmware with noise-adaptive gains (`estimators::AdaptiveBank`).
const ADAPTIVE: &str = "adaptive-gains";
/// The firmware feature of the product bank with the tuned gains of
/// [`TUNED_GAINS`] (`firmware-example/src/pipeline.rs`).
const TUNED: &str = "tuned-gains";
/// The gains file `nav440 tune --bank product` wrote beside the snippet the `tuned-gains`
/// firmware includes (relative to the workspace root).
const TUNED_GAINS: &str = "host-tests/data/gains/product_fig5.toml";

/// Feature of the firmware whose product bank tunes ILO1 online against the Euler reference
/// rate (`estimators::SelfTuningProductBank`).
const SELF_TUNE: &str = "self-tune";

/// The bank a firmware image runs (`--bank`): the paper's 14 estimators (default), the
/// product bank whose gains follow the noise and the motion (feature `bank-product` alone),
/// the product bank with the shipped gains fixed (feature `fixed-gains`) or the one that tunes
/// ILO1 against the rate (`self-tune`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BankChoice {
    /// The paper bank (14 estimators per axis).
    Paper,
    /// The product bank (ILO1 velocity + Kalman acceleration per axis) whose gains follow the
    /// measured noise and the motion's jerk: the product default (feature `bank-product`;
    /// `nav440 estimate --bank product`).
    #[value(alias = "follow")]
    Product,
    /// The product bank with the shipped preset's gains fixed, float-free (feature
    /// `fixed-gains`; `nav440 estimate --bank product --fixed-gains`): the image of the small
    /// parts.
    FixedGains,
    /// The product bank that tunes ILO1 online against each row's Euler reference rate
    /// (feature `self-tune`; `nav440 estimate --bank product --self-tune`).
    SelfTune,
}

impl BankChoice {
    /// The firmware features that select this bank.
    fn features(self) -> &'static [&'static str] {
        match self {
            BankChoice::Paper => &[],
            BankChoice::FixedGains => &[PRODUCT, FIXED_GAINS],
            BankChoice::Product => &[PRODUCT],
            BankChoice::SelfTune => &[PRODUCT, SELF_TUNE],
        }
    }

    /// The `nav440 estimate` arguments that select this bank.
    fn host_args(self) -> &'static [&'static str] {
        match self {
            BankChoice::Paper => &[],
            BankChoice::FixedGains => &["--bank", "product", "--fixed-gains"],
            BankChoice::Product => &["--bank", "product"],
            BankChoice::SelfTune => &["--bank", "product", "--self-tune"],
        }
    }

    /// Its name in image names and messages.
    fn name(self) -> &'static str {
        match self {
            BankChoice::Paper => "paper",
            BankChoice::FixedGains => "fixed-gains",
            BankChoice::Product => "product",
            BankChoice::SelfTune => "self-tune",
        }
    }
}

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

/// Cargo's target directory: `CARGO_TARGET_DIR` (relative to the workspace root) or
/// `target`.
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

/// xtask's scratch directory, `xtask` in the target directory (created if missing).
fn work_dir() -> Result<PathBuf, String> {
    let d = target_dir().join("xtask");
    std::fs::create_dir_all(&d).map_err(|e| format!("cannot create {}: {e}", d.display()))?;
    Ok(d)
}

/// A file name in [`work_dir`] that no other run of this process uses (runs go on in
/// parallel in `cargo xtask ci`'s job pool).
fn unique_path(prefix: &str, ext: &str) -> Result<PathBuf, String> {
    let n = crate::qemu::run_number();
    Ok(work_dir()?.join(format!("{prefix}-{}-{n}.{ext}", std::process::id())))
}

fn read_file(p: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(p).map_err(|e| format!("cannot read {}: {e}", p.display()))
}
