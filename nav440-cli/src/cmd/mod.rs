//! The `nav440` command line: [`Cli`], one module per subcommand (its arguments and its
//! `run`), and the options and output helpers they share.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::error::{Error, Result};
use crate::limits::{noise_var, step};
use crate::{gains, replay};

pub mod completions;
pub mod config;
pub mod decode;
pub mod estimate;
pub mod info;
pub mod live;
pub mod paper;
pub mod plot;
pub mod ports;
pub mod record;
pub mod rows;
pub mod sim;
pub mod stats;
pub mod synth;
pub mod tune;

/// The `nav440` command line.
#[derive(Parser, Debug)]
#[command(
    name = "nav440",
    version,
    about = "Replay, synthesise and analyse Crossbow NAV440 captures (yaw velocity/acceleration estimators of Kawakami et al. 2013)",
    after_help = "Units: s, deg, deg/s, deg/s^2.\nExit codes: 0 ok, 1 other failure, 2 usage, 3 input missing/unreadable/empty, 4 not NAV440 data, 5 output failure."
)]
pub struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

impl Cli {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        match self.cmd {
            Cmd::Stats(a) => stats::run(&a),
            Cmd::Decode(a) => decode::run(&a),
            Cmd::Estimate(a) => estimate::run(a),
            Cmd::Paper(a) => paper::run(&a),
            Cmd::Tune(a) => tune::run(a),
            Cmd::Plot(a) => plot::run(&a),
            Cmd::Synth(a) => synth::run(a),
            Cmd::Sim(a) => sim::run(&a),
            Cmd::Config(a) => config::run(&a),
            Cmd::Record(a) => record::run(&a),
            Cmd::Live(a) => live::run(&a),
            Cmd::Info(a) => info::run(&a),
            Cmd::Ports(a) => ports::run(&a),
            Cmd::Rows(a) => rows::run(&a),
            Cmd::Completions(a) => completions::run(&a),
        }
    }
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Print parser statistics as one JSON object.
    Stats(stats::Args),
    /// Print one CSV row per frame with its fields in SI units.
    Decode(decode::Args),
    /// Run the estimator bank; CSV (t,yaw,yaw_rate, then the bank's channels: the paper
    /// bank's 7 velocities and 7 accelerations, or the product bank's ilo1_v,kf_a) on stdout
    /// (`--axis`: roll/pitch columns, or all three axes with prefixed columns).
    Estimate(estimate::Args),
    /// Reproduce the paper's Tables 1 and 3 (noise 0.01 and 0.5 deg^2, 3 seeds, MSE over 0-30 s).
    Paper(paper::Args),
    /// Calibrate each estimator family's gains to a capture and noise level.
    Tune(tune::Args),
    /// Plot yaw, measured rate, velocity and acceleration estimates (stacked panels, SVG).
    Plot(plot::Args),
    /// Synthesise a capture: motion profile -> NAV440 byte stream (optionally corrupted).
    Synth(synth::Args),
    /// Simulated NAV440 on TCP or a pseudo-terminal: answers commands, streams the capture once configured.
    Sim(sim::Args),
    /// Configure a unit on a serial port (boot sequence: find, baud, packet type and rate, read-back).
    Config(config::Args),
    /// Configure a unit on a serial port, then record its stream to a file.
    Record(record::Args),
    /// Configure a unit on a serial port, then print the estimate CSV while receiving (or,
    /// with --plot, draw a live chart in the terminal).
    Live(live::Args),
    /// Identify the unit on a serial port: serial number, part number, firmware version and
    /// its output settings (changes nothing).
    Info(info::Args),
    /// List the serial ports of this machine.
    Ports(ports::Args),
    /// Print as CSV the rows a `uart-rows` firmware sends out of its output UART (framed
    /// binary, docs/UART-ROWS.md), from a serial port or a saved stream: the CSV `nav440
    /// estimate` prints.
    Rows(rows::Args),
    /// Print the shell completion script for SHELL on stdout (e.g. `nav440 completions bash >
    /// ~/.local/share/bash-completion/completions/nav440`).
    Completions(completions::Args),
}

/// `--hold`: the sample adapter between packets.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum HoldArg {
    /// Linear interpolation between the last two samples (causal, no added latency).
    Linear,
    /// Zero-order hold of the newest sample.
    Zoh,
}

impl From<HoldArg> for estimators::Hold {
    fn from(h: HoldArg) -> Self {
        match h {
            HoldArg::Linear => estimators::Hold::Linear,
            HoldArg::Zoh => estimators::Hold::ZeroOrder,
        }
    }
}

/// `--preset`: the gain preset a gains file is applied over.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// `BankConfig::NAV440`: gains tuned on synthetic motions and noise levels (default of
    /// `estimate` and `plot`).
    Nav440,
    /// `BankConfig::PAPER`: the paper's presets (default of `paper`).
    Paper,
}

impl PresetArg {
    fn config(self) -> estimators::BankConfig {
        match self {
            PresetArg::Nav440 => estimators::BankConfig::NAV440,
            PresetArg::Paper => estimators::BankConfig::PAPER,
        }
    }
}

/// Options shared by every command that runs the estimator bank.
#[derive(Args, Debug, Clone)]
pub struct BankArgs {
    /// Sample adapter: linear interpolation or zero-order hold [default: linear, or a
    /// schedule file's hold].
    #[arg(long, value_enum)]
    pub(crate) hold: Option<HoldArg>,
    /// Observer integration step h, s (1e-7 to 1).
    #[arg(long, default_value_t = 1e-4)]
    pub(crate) step: f32,
    /// Gain preset: nav440 (tuned, default of `estimate` and `plot`) or paper (default of
    /// `paper`). A gains file is applied over it.
    #[arg(long, value_enum)]
    pub(crate) preset: Option<PresetArg>,
    /// Gains file (TOML written by `nav440 tune`), applied over the preset; or a schedule
    /// file (`nav440 tune --schedule`): noise-adaptive gains.
    #[arg(long, value_name = "FILE")]
    pub(crate) gains: Option<PathBuf>,
    /// Where added noise enters: one draw per packet (sample), or one per observer step on the
    /// yaw interpolated to the step grid (step; our reading of the paper's simulation).
    #[arg(long, value_enum, default_value = "sample")]
    pub(crate) noise_at: NoiseAtArg,
    /// Estimated axis: roll, pitch, yaw (default), or all three (`estimate` and `live` only;
    /// CSV columns prefixed with the axis name). See docs/PIPELINE.md.
    #[arg(long, value_enum, default_value = "yaw")]
    pub(crate) axis: AxisArg,
}

/// `--bank`: which estimator bank `estimate` runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BankArg {
    /// `estimators::PaperBank`: the paper's 14 estimators (AVE, ILO1-3, AD, ED, Kalman;
    /// velocity and acceleration).
    Paper,
    /// `estimators::ProductBank`: ILO1 velocity and Kalman acceleration (`ilo1_v`, `kf_a`).
    Product,
}

impl From<BankArg> for replay::BankKind {
    fn from(b: BankArg) -> Self {
        match b {
            BankArg::Paper => replay::BankKind::Paper,
            BankArg::Product => replay::BankKind::Product,
        }
    }
}

/// `--axis`: the estimated axis or axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AxisArg {
    /// Roll (wraps at +-180 deg).
    Roll,
    /// Pitch (not unwrapped).
    Pitch,
    /// Yaw (wraps at +-180 deg).
    Yaw,
    /// Roll, pitch and yaw (`nav440 estimate` and `nav440 live` only).
    All,
}

impl From<AxisArg> for replay::Axes {
    fn from(a: AxisArg) -> Self {
        use replay::{Axes, Axis};
        match a {
            AxisArg::Roll => Axes::only(Axis::Roll),
            AxisArg::Pitch => Axes::only(Axis::Pitch),
            AxisArg::Yaw => Axes::only(Axis::Yaw),
            AxisArg::All => Axes::ALL,
        }
    }
}

/// `paper`, `tune` and `plot` score one axis: `--axis all` is a usage error there.
pub(crate) fn one_axis(opts: &replay::EstimateOptions, cmd: &str) -> Result<()> {
    if opts.axes.len() == 1 {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "`nav440 {cmd}` scores one axis at a time: use --axis roll, pitch or yaw"
        )))
    }
}

/// The options of `nav440 estimate` that choose the bank and its input (`--bank`, the bank
/// options, noise, `--fixed`), shared with `nav440 live`: both run the same
/// [`replay::estimate_stream`] with the options [`EstimateArgs::options`] builds.
#[derive(Args, Debug, Clone)]
pub struct EstimateArgs {
    /// Estimator bank: paper (the paper's 14 estimators) or product (ILO1 velocity and
    /// Kalman acceleration, what the product firmware prints).
    #[arg(
        long = "bank",
        value_enum,
        default_value = "paper",
        value_name = "BANK"
    )]
    pub(crate) bank_kind: BankArg,
    #[command(flatten)]
    pub(crate) bank: BankArgs,
    #[command(flatten)]
    pub(crate) noise: NoiseArgs,
    /// Run the fixed-point (Q31.32) bank, as the no-FPU firmware does, instead of f32.
    #[arg(long)]
    pub(crate) fixed: bool,
    /// No Euler reference: each axis's rate column is the unit's body rate about it (roll p,
    /// pitch q, yaw r, deg/s as sent), named `<axis>_body_rate`, as the firmware built with
    /// the feature `no-reference` prints. Fixed gains' estimates do not change; gains that
    /// follow the motion follow that rate.
    #[arg(long)]
    pub(crate) no_reference: bool,
    /// With `--bank product`: the gains follow the angle's measured noise and the motion's
    /// jerk (from each row's rate about the axis) instead of staying fixed
    /// (`estimators::AdaptiveProductBank`, docs/ADAPTIVE-GAINS.md). The default of `--bank
    /// product` with the shipped gains (no `--preset`, no `--gains`); one sample per packet
    /// (`--noise-at sample`).
    #[arg(long)]
    pub(crate) follow: bool,
    /// With `--bank product`: the shipped preset's gains for the packet rate stay fixed
    /// (`estimators::ProductBank`), as the float-free product images (firmware feature
    /// `fixed-gains`) run them, instead of following the noise and the motion.
    #[arg(long, conflicts_with_all = ["follow", "self_tune"])]
    pub(crate) fixed_gains: bool,
    /// With `--bank product`: ILO1's gains tune themselves online against each row's Euler
    /// reference rate, a step per window towards the lowest error (bounded, bumpless;
    /// `estimators::SelfTuningProductBank`, docs/SELF-TUNE.md), and the gains each axis
    /// settled at are printed on stderr at the end. Not with `--follow` or `--no-reference`.
    #[arg(long)]
    pub(crate) self_tune: bool,
}

impl EstimateArgs {
    /// The options these arguments describe (the NAV440 preset unless `--preset` or a gains
    /// file says otherwise), every number and the gains file checked.
    pub fn options(&self) -> Result<replay::EstimateOptions> {
        let mut opts = bank_options(&self.bank, PresetArg::Nav440)?;
        opts.noise = noise(self.noise.noise_var, self.noise.seed)?;
        opts.fixed = self.fixed;
        opts.bank = self.bank_kind.into();
        if self.no_reference {
            opts.rate_column = replay::RateColumn::Body;
        }
        let product = self.bank_kind == BankArg::Product;
        if self.fixed_gains && !product {
            return Err(Error::Usage(FIXED_GAINS_PAPER.to_string()));
        }
        // The product bank's shipped gains follow the motion unless told otherwise; gains
        // given by `--preset` or `--gains` stay as given.
        let shipped = self.bank.preset.is_none() && self.bank.gains.is_none();
        opts.follow_motion =
            self.follow || (product && shipped && !self.fixed_gains && !self.self_tune);
        opts.self_tune = self.self_tune;
        replay::check_bank_options(&opts)?;
        Ok(opts)
    }
}

/// Why `--fixed-gains` is refused without `--bank product`.
const FIXED_GAINS_PAPER: &str = "--fixed-gains keeps the product bank's shipped gains fixed instead of following the motion: use it with --bank product (the paper bank's gains are fixed, or scheduled by --gains)";

/// Prints the warnings of an estimation on stderr, one line each.
pub(crate) fn print_warnings(report: &replay::StreamReport) {
    for w in report.warnings() {
        eprintln!("nav440: warning: {w}");
    }
}

/// Measurement noise added to yaw before estimation (the paper's protocol).
#[derive(Args, Debug, Clone)]
pub struct NoiseArgs {
    /// Add N(0, V) deg^2 noise to yaw before estimation (0 to 1e15).
    #[arg(long, value_name = "V")]
    pub(crate) noise_var: Option<f64>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
}

/// `--noise-at`: where added noise enters.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum NoiseAtArg {
    /// One N(0, V) draw per packet.
    Sample,
    /// One N(0, V) draw per observer step h (yaw linearly interpolated to the step grid).
    Step,
}

impl From<NoiseAtArg> for replay::NoiseAt {
    fn from(n: NoiseAtArg) -> Self {
        match n {
            NoiseAtArg::Sample => replay::NoiseAt::Sample,
            NoiseAtArg::Step => replay::NoiseAt::Step,
        }
    }
}

pub(crate) fn with_name<T>(name: &str, r: Result<T>) -> Result<T> {
    r.map_err(|e| match e {
        Error::NotNav440(m) => Error::NotNav440(format!("{name}: {m}")),
        other => other,
    })
}

/// The options of `b`; `default_preset` is the command's preset when `--preset` is not given
/// (the base a gains file is applied over; `None` left in `config` means that preset).
pub(crate) fn bank_options(
    b: &BankArgs,
    default_preset: PresetArg,
) -> Result<replay::EstimateOptions> {
    step(b.step)?;
    let preset = b.preset.unwrap_or(default_preset);
    let base = preset.config();
    let (mut config, mut schedule, mut file_hold) = (b.preset.map(PresetArg::config), None, None);
    // The NAV440 preset's gains follow the measured packet rate (a gains file over it is
    // applied over the rate's gains); the paper's and a schedule's do not.
    let mut follow_rate = preset == PresetArg::Nav440;
    let mut overlay = None;
    let loaded = b.gains.as_deref().map(gains::load_any).transpose()?;
    if let (Some(path), Some(l)) = (b.gains.as_deref(), loaded.as_ref()) {
        gains::check_tables(path, l, b.step)?;
    }
    match loaded {
        None => {}
        Some(gains::Loaded::Fixed(g)) => {
            config = Some(g.apply(base));
            overlay = Some(g);
        }
        Some(gains::Loaded::Schedule(f)) => {
            // Validated by `load_any`.
            schedule = Some(f.schedule(&base)?);
            file_hold = Some(f.hold()?);
            config = Some(base);
            follow_rate = false;
        }
    }
    Ok(replay::EstimateOptions {
        hold: b
            .hold
            .map(Into::into)
            .or(file_hold)
            .unwrap_or(estimators::Hold::Linear),
        step_s: b.step,
        noise: None,
        fixed: false,
        config,
        follow_rate,
        overlay,
        noise_at: b.noise_at.into(),
        axes: b.axis.into(),
        schedule,
        bank: replay::BankKind::Paper,
        rate_column: replay::RateColumn::Euler,
        follow_motion: false,
        self_tune: false,
    })
}

pub(crate) fn noise(var: Option<f64>, seed: u64) -> Result<Option<replay::Noise>> {
    match var {
        Some(v) => Ok(Some(replay::Noise {
            var: noise_var("--noise-var", v)?,
            seed,
        })),
        None => Ok(None),
    }
}

/// Writes to standard output (`output` `None`) or to the file `output` through
/// [`crate::output::OutputFile`]; a closed pipe is not an error, a standard output closed at
/// start is.
pub(crate) fn stdout_or_file(
    output: Option<&Path>,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let dest = output.unwrap_or(Path::new(crate::output::STDOUT_NAME));
    let mut w = crate::output::OutputFile::create(dest)?;
    let res = write(&mut w).and_then(|_| w.flush());
    match res {
        // A closed pipe (`nav440 estimate f | head`) is not an error worth reporting.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Error::Output(format!("cannot write output: {e}"))),
        Ok(()) => w.commit(),
    }
}
