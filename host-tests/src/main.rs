//! `nav440`: replay, synthesise, estimate, reproduce the paper, tune and plot NAV440 captures.
//!
//! Exit codes: 0 success; 1 other failure (estimator/encoder error); 2 usage error (bad
//! argument); 3 input file missing, unreadable or empty; 4 input holds no NAV440 frame (or no
//! packet carrying yaw); 5 output could not be written. Every error is one line on stderr.

use clap::{Args, Parser, Subcommand, ValueEnum};
use host_tests::error::{Error, Result};
use host_tests::{
    corrupt::Corruption, gains, motion::ProfileKind, optim, paper, plots, replay, synth, tune,
};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "nav440",
    version,
    about = "Replay, synthesise and analyse Crossbow NAV440 captures (yaw velocity/acceleration estimators of Kawakami et al. 2013)",
    after_help = "Units: s, deg, deg/s, deg/s^2.\nExit codes: 0 ok, 1 other failure, 2 usage, 3 input missing/unreadable/empty, 4 not NAV440 data, 5 output failure."
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum HoldArg {
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum PresetArg {
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
struct BankArgs {
    /// Sample adapter: linear interpolation or zero-order hold [default: linear, or a
    /// schedule file's hold].
    #[arg(long, value_enum)]
    hold: Option<HoldArg>,
    /// Observer integration step h, s.
    #[arg(long, default_value_t = 1e-4)]
    step: f32,
    /// Gain preset: nav440 (tuned, default of `estimate` and `plot`) or paper (default of
    /// `paper`). A gains file is applied over it.
    #[arg(long, value_enum)]
    preset: Option<PresetArg>,
    /// Gains file (TOML written by `nav440 tune`), applied over the preset; or a schedule
    /// file (`nav440 tune --schedule`): noise-adaptive gains.
    #[arg(long, value_name = "FILE")]
    gains: Option<PathBuf>,
    /// Where added noise enters: one draw per packet (sample), or one per observer step on the
    /// yaw interpolated to the step grid (step; our reading of the paper's simulation).
    #[arg(long, value_enum, default_value = "sample")]
    noise_at: NoiseAtArg,
    /// Estimated axis: roll, pitch, yaw (default), or all three (`estimate` only; CSV columns
    /// prefixed with the axis name). See docs/PIPELINE.md.
    #[arg(long, value_enum, default_value = "yaw")]
    axis: AxisArg,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum BankArg {
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

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum AxisArg {
    /// Roll (wraps at +-180 deg).
    Roll,
    /// Pitch (not unwrapped).
    Pitch,
    /// Yaw (wraps at +-180 deg).
    Yaw,
    /// Roll, pitch and yaw (`nav440 estimate` only).
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
fn one_axis(opts: &replay::EstimateOptions, cmd: &str) -> Result<()> {
    if opts.axes.len() == 1 {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "`nav440 {cmd}` scores one axis at a time: use --axis roll, pitch or yaw"
        )))
    }
}

/// Measurement noise added to yaw before estimation (the paper's protocol).
#[derive(Args, Debug)]
struct NoiseArgs {
    /// Add N(0, V) deg^2 noise to yaw before estimation.
    #[arg(long, value_name = "V")]
    noise_var: Option<f64>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum NoiseAtArg {
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

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Print parser statistics as one JSON object.
    Stats {
        /// Capture file (raw NAV440 byte stream); `-` reads standard input.
        file: PathBuf,
    },
    /// Print one CSV row per frame with its fields in SI units.
    Decode {
        /// Capture file; `-` reads standard input.
        file: PathBuf,
        /// Only frames of this type (e.g. A2, N1, S1, NAK).
        #[arg(long = "type", value_name = "TYPE")]
        packet_type: Option<String>,
    },
    /// Run the estimator bank; CSV (t,yaw,yaw_rate, then the bank's channels: the paper
    /// bank's 7 velocities and 7 accelerations, or the product bank's ilo1_v,kf_a) on stdout
    /// (`--axis`: roll/pitch columns, or all three axes with prefixed columns).
    Estimate {
        /// Capture file; `-` reads standard input.
        file: PathBuf,
        /// Estimator bank: paper (the paper's 14 estimators) or product (ILO1 velocity and
        /// Kalman acceleration, what the product firmware prints).
        #[arg(
            long = "bank",
            value_enum,
            default_value = "paper",
            value_name = "BANK"
        )]
        bank_kind: BankArg,
        #[command(flatten)]
        bank: BankArgs,
        #[command(flatten)]
        noise: NoiseArgs,
        /// Run the fixed-point (Q31.32) bank, as the no-FPU firmware does, instead of f32.
        #[arg(long)]
        fixed: bool,
        /// Write the CSV here instead of stdout.
        #[arg(short, long, value_name = "FILE")]
        output: Option<PathBuf>,
    },
    /// Reproduce the paper's Tables 1 and 3 (noise 0.01 and 0.5 deg^2, 3 seeds, MSE over 0-30 s).
    Paper {
        /// Capture file; `-` reads standard input.
        file: PathBuf,
        #[command(flatten)]
        bank: BankArgs,
        /// Print JSON instead of tables.
        #[arg(long, conflicts_with = "markdown")]
        json: bool,
        /// Print Markdown tables (for a README) instead of text tables.
        #[arg(long)]
        markdown: bool,
        /// MSE window end, s.
        #[arg(long, default_value_t = 30.0)]
        window: f64,
    },
    /// Calibrate each estimator family's gains to a capture and noise level.
    Tune {
        /// Capture file; `-` reads standard input.
        file: PathBuf,
        /// Noise variance added to yaw, deg^2.
        #[arg(
            long,
            value_name = "V",
            required_unless_present = "schedule",
            conflicts_with = "schedule"
        )]
        noise_var: Option<f64>,
        /// Tune a gain schedule: one level per noise variance (deg^2, comma-separated,
        /// increasing, e.g. 0.001,0.01,0.1,0.5,1); `-o` writes the schedule file that
        /// `--gains` runs as a noise-adaptive bank, `--rust` its `SCHEDULE` array.
        #[arg(
            long,
            value_name = "V1,V2,...",
            value_delimiter = ',',
            conflicts_with = "exhaustive"
        )]
        schedule: Option<Vec<f64>>,
        /// Number of noise seeds averaged per evaluation.
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// MSE window end, s (tune and score on 0-WINDOW s).
        #[arg(long, default_value_t = 30.0, conflicts_with = "train")]
        window: f64,
        /// Tune on the MSE over this time range, s (e.g. 0-15).
        #[arg(long, value_name = "T0-T1", value_parser = parse_range)]
        train: Option<(f64, f64)>,
        /// Report the MSE before/after over this time range, s (default: the training range).
        #[arg(long, value_name = "T2-T3", value_parser = parse_range)]
        test: Option<(f64, f64)>,
        /// Reference mode: an exhaustive log grid of N points per gain instead of the search.
        #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "12")]
        exhaustive: Option<usize>,
        /// Sample adapter; default: tune both and keep the better.
        #[arg(long, value_enum)]
        hold: Option<HoldArg>,
        /// Observer step h, s.
        #[arg(long, default_value_t = 1e-4)]
        step: f32,
        /// Write the tuned gains (TOML, accepted by `--gains`) here.
        #[arg(short, long, value_name = "FILE")]
        output: Option<PathBuf>,
        /// Also write a Rust snippet (BankConfig literal for the firmware) here.
        #[arg(long, value_name = "FILE")]
        rust: Option<PathBuf>,
        /// Tuned axis: roll, pitch or yaw.
        #[arg(long, value_enum, default_value = "yaw")]
        axis: AxisArg,
    },
    /// Plot yaw, measured rate, velocity and acceleration estimates (stacked panels, SVG).
    Plot {
        /// Capture file; `-` reads standard input.
        file: PathBuf,
        /// Output SVG file.
        #[arg(short, long, value_name = "OUT.svg")]
        output: PathBuf,
        #[command(flatten)]
        bank: BankArgs,
        #[command(flatten)]
        noise: NoiseArgs,
        /// Plot from this time, s.
        #[arg(long)]
        from: Option<f64>,
        /// Plot up to this time, s.
        #[arg(long)]
        to: Option<f64>,
    },
    /// Synthesise a capture: motion profile -> NAV440 byte stream (optionally corrupted).
    Synth {
        /// Motion profile: fig5 (paper Fig. 5-like hand rotation), spin (many turns), sin5 (section 3.2).
        #[arg(long, default_value = "fig5")]
        profile: ProfileKind,
        /// Packet type: A1, A2 or N1.
        #[arg(long = "packet", default_value = "A2")]
        packet: synth::PacketKind,
        /// Packet rate, Hz (100, 50, 25, 20, 10, 5, 4 or 2).
        #[arg(long, default_value_t = 100)]
        rate: u32,
        /// Duration, s (0 to 10000: the capture is built in memory).
        #[arg(long, default_value_t = 35.0)]
        duration: f64,
        /// Seed of the motion shape (fig5).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// timeITOW of the first packet, ms: a time of week (0 to 604799999).
        #[arg(long, default_value_t = synth::SynthConfig::default().start_itow_ms)]
        start_itow: u64,
        /// BIT word of every packet (e.g. 0x0002).
        #[arg(long, default_value = "0", value_parser = parse_u16)]
        bit: u16,
        /// Flip this many random bits.
        #[arg(long, default_value_t = 0)]
        flip_bits: usize,
        /// Delete this many random bytes.
        #[arg(long, default_value_t = 0)]
        drop_bytes: usize,
        /// Leave out this many random packets.
        #[arg(long, default_value_t = 0)]
        drop_packets: usize,
        /// Insert this many bursts of random bytes between packets.
        #[arg(long, default_value_t = 0)]
        garbage: usize,
        /// Longest garbage burst, bytes.
        #[arg(long, default_value_t = 32)]
        garbage_max_len: usize,
        /// Seed of the corruption.
        #[arg(long, default_value_t = 1)]
        corrupt_seed: u64,
        /// Gaussian noise added to the yaw angle: VAR (deg^2) from the start, or VAR@T from T s
        /// on; repeat for a noise level that changes (e.g. --yaw-noise 0.01 --yaw-noise 0.5@10).
        #[arg(long = "yaw-noise", value_name = "VAR[@T]")]
        yaw_noise: Vec<synth::NoiseStep>,
        /// Seed of the yaw noise.
        #[arg(long, default_value_t = 1)]
        noise_seed: u64,
        /// Output capture file.
        #[arg(short, long, value_name = "FILE")]
        output: PathBuf,
    },
    /// Simulated NAV440 on TCP or a pseudo-terminal: answers commands, streams the capture once configured.
    Sim(host_tests::sim::SimArgs),
    /// Configure a unit on a serial port (boot sequence: find, baud, packet type and rate, read-back).
    Config(host_tests::serial::ConfigArgs),
    /// Configure a unit on a serial port, then record its stream to a file.
    Record(host_tests::serial::RecordArgs),
    /// Configure a unit on a serial port, then print the estimate CSV while receiving.
    Live(host_tests::serial::LiveArgs),
    /// Print the shell completion script for SHELL on stdout (e.g. `nav440 completions bash >
    /// ~/.local/share/bash-completion/completions/nav440`).
    Completions {
        /// The shell: bash, zsh, fish, elvish or powershell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

fn parse_u16(s: &str) -> std::result::Result<u16, String> {
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u16::from_str_radix(h, 16),
        None => s.parse(),
    };
    r.map_err(|_| format!("`{s}` is not a 16-bit value"))
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // --help / --version print normally and exit 0; usage errors exit 2.
            if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                let _ = e.print();
                return ExitCode::from(2);
            }
            if !e.use_stderr() {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // One line: clap's message without its usage/help trailer.
            let text = e.render().to_string();
            let msg: Vec<&str> = text
                .lines()
                .map(str::trim)
                .filter(|l| {
                    !l.is_empty()
                        && !l.starts_with("Usage:")
                        && !l.starts_with("For more information")
                })
                .map(|l| l.strip_prefix("error: ").unwrap_or(l))
                .collect();
            eprintln!("nav440: {} (see `nav440 --help`)", msg.join(" "));
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("nav440: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

fn with_name<T>(name: &str, r: Result<T>) -> Result<T> {
    r.map_err(|e| match e {
        Error::NotNav440(m) => Error::NotNav440(format!("{name}: {m}")),
        other => other,
    })
}

/// Parses a time range `T0-T1` (s), e.g. `0-15` or `12.5-30`.
fn parse_range(s: &str) -> std::result::Result<(f64, f64), String> {
    let bad = || format!("expected a time range T0-T1 in s (e.g. 0-15), got {s:?}");
    let (a, b) = s.split_once('-').ok_or_else(bad)?;
    let a: f64 = a.trim().parse().map_err(|_| bad())?;
    let b: f64 = b.trim().parse().map_err(|_| bad())?;
    if a.is_finite() && b.is_finite() && a >= 0.0 && b > a {
        Ok((a, b))
    } else {
        Err(format!("time range {s:?}: needs 0 <= T0 < T1"))
    }
}

fn load_samples(file: &Path) -> Result<Vec<replay::Sample>> {
    replay::read_samples(file)
}

/// The options of `b`; `default_preset` is the command's preset when `--preset` is not given
/// (the base a gains file is applied over; `None` left in `config` means that preset).
fn bank_options(b: &BankArgs, default_preset: PresetArg) -> Result<replay::EstimateOptions> {
    if !(b.step.is_finite() && b.step > 0.0) {
        return Err(Error::Usage(format!(
            "--step must be a positive number of seconds, got {}",
            b.step
        )));
    }
    let preset = b.preset.unwrap_or(default_preset);
    let base = preset.config();
    let (mut config, mut schedule, mut file_hold) = (b.preset.map(PresetArg::config), None, None);
    // The NAV440 preset's gains follow the measured packet rate (a gains file over it is
    // applied over the rate's gains); the paper's and a schedule's do not.
    let mut follow_rate = preset == PresetArg::Nav440;
    let mut overlay = None;
    match b.gains.as_deref().map(gains::load_any).transpose()? {
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
    })
}

fn noise(var: Option<f64>, seed: u64) -> Result<Option<replay::Noise>> {
    match var {
        Some(v) if !(v.is_finite() && v >= 0.0) => Err(Error::Usage(format!(
            "--noise-var must be >= 0 deg^2, got {v}"
        ))),
        Some(v) => Ok(Some(replay::Noise { var: v, seed })),
        None => Ok(None),
    }
}

fn stdout_or_file(
    output: Option<&Path>,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let res = match output {
        Some(p) => {
            let f = std::fs::File::create(p)
                .map_err(|e| Error::Output(format!("cannot create {}: {e}", p.display())))?;
            let mut w = std::io::BufWriter::new(f);
            write(&mut w).and_then(|_| w.flush())
        }
        None => {
            let out = std::io::stdout();
            let mut w = std::io::BufWriter::new(out.lock());
            write(&mut w).and_then(|_| w.flush())
        }
    };
    match res {
        // A closed pipe (`nav440 estimate f | head`) is not an error worth reporting.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Error::Output(format!("cannot write output: {e}"))),
        Ok(()) => Ok(()),
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.cmd {
        Cmd::Sim(a) => host_tests::sim::command(&a),
        Cmd::Config(a) => host_tests::serial::config(&a),
        Cmd::Record(a) => host_tests::serial::record(&a),
        Cmd::Live(a) => host_tests::serial::live(&a),
        Cmd::Completions { shell } => {
            // Generated into memory first: clap_complete panics on a write error, and a
            // closed pipe must stay a silent success as for every other command.
            let mut script = Vec::new();
            let mut cmd = <Cli as clap::CommandFactory>::command();
            clap_complete::generate(shell, &mut cmd, "nav440", &mut script);
            stdout_or_file(None, |w| w.write_all(&script))
        }
        Cmd::Stats { file } => {
            let mut r = replay::open_capture(&file)?;
            let mut counter = replay::StatsCounter::new();
            r.for_each_chunk(|b| {
                counter.push(b);
                Ok(true)
            })?;
            let stats = counter.stats();
            if stats.total_frames() == 0 {
                return Err(Error::NotNav440(format!(
                    "{}: no NAV440 frame found (not a NAV440 capture?)",
                    r.name()
                )));
            }
            stdout_or_file(None, |w| writeln!(w, "{}", stats.to_json()))
        }
        Cmd::Decode { file, packet_type } => decode(&file, packet_type.as_deref()),
        Cmd::Estimate {
            file,
            bank_kind,
            bank,
            noise: n,
            fixed,
            output,
        } => {
            let mut opts = bank_options(&bank, PresetArg::Nav440)?;
            opts.noise = noise(n.noise_var, n.seed)?;
            opts.fixed = fixed;
            opts.bank = bank_kind.into();
            replay::check_bank_options(&opts)?;
            let mut r = replay::open_capture(&file)?;
            let name = r.name().to_string();
            let report = match output {
                Some(p) => {
                    let mut w = LazyFile::new(p);
                    let res = replay::estimate_stream(&mut r, &opts, &mut w);
                    w.finish(res)
                }
                None => {
                    let out = std::io::stdout();
                    let mut w = std::io::BufWriter::new(out.lock());
                    replay::estimate_stream(&mut r, &opts, &mut w)
                }
            };
            for w in with_name(&name, report)?.warnings() {
                eprintln!("nav440: warning: {w}");
            }
            Ok(())
        }
        Cmd::Paper {
            file,
            bank,
            json,
            markdown,
            window,
        } => {
            let opts = bank_options(&bank, PresetArg::Paper)?;
            one_axis(&opts, "paper")?;
            paper::check_window(window)?;
            let samples = load_samples(&file)?;
            let res = paper::run(&samples, &opts, window, &replay::capture_name(&file))?;
            let text = if json {
                format!("{}\n", res.to_json())
            } else if markdown {
                res.to_markdown()
            } else {
                res.to_text()
            };
            stdout_or_file(None, |w| w.write_all(text.as_bytes()))
        }
        Cmd::Tune {
            file,
            noise_var,
            schedule,
            seeds,
            window,
            train,
            test,
            exhaustive,
            hold,
            step,
            output,
            rust,
            axis,
        } => {
            if let Some(v) = noise_var {
                noise(Some(v), 0)?;
            }
            for &v in schedule.iter().flatten() {
                noise(Some(v), 0)?;
            }
            paper::check_window(window)?;
            let samples = load_samples(&file)?;
            let opts = replay::EstimateOptions {
                hold: hold.map_or(estimators::Hold::Linear, Into::into),
                step_s: step,
                axes: axis.into(),
                ..Default::default()
            };
            one_axis(&opts, "tune")?;
            let spec = tune::TuneSpec {
                noise_var: noise_var.unwrap_or(0.0),
                seeds: seeds.max(1),
                train: train.unwrap_or((0.0, window)),
                test,
                method: match exhaustive {
                    Some(n) if n < 2 => {
                        return Err(Error::Usage(format!(
                            "--exhaustive needs at least 2 points per gain, got {n}"
                        )))
                    }
                    Some(points) => optim::Method::Exhaustive { points },
                    None => optim::Method::Search,
                },
                holds: match hold {
                    Some(h) => vec![h.into()],
                    None => vec![estimators::Hold::Linear, estimators::Hold::ZeroOrder],
                },
            };
            if let Some(levels) = schedule {
                let spec = tune::TuneSpec {
                    holds: vec![hold.map_or(estimators::Hold::Linear, Into::into)],
                    ..spec
                };
                let (file, text) = tune::tune_schedule(&samples, &opts, &spec, &levels)?;
                stdout_or_file(None, |w| w.write_all(text.as_bytes()))?;
                if let Some(p) = output {
                    write_file(&p, &file.to_toml())?;
                }
                if let Some(p) = rust {
                    let what = format!(
                        "--schedule {}",
                        levels
                            .iter()
                            .map(|v| v.to_string())
                            .collect::<Vec<_>>()
                            .join(",")
                    );
                    write_file(&p, &file.to_rust(&what, &estimators::BankConfig::NAV440))?;
                }
                return Ok(());
            }
            let res = tune::tune_with(&samples, &opts, &spec)?;
            stdout_or_file(None, |w| w.write_all(res.to_text().as_bytes()))?;
            if let Some(p) = output {
                write_file(&p, &res.to_toml())?;
            }
            if let Some(p) = rust {
                write_file(&p, &res.to_rust())?;
            }
            Ok(())
        }
        Cmd::Plot {
            file,
            output,
            bank,
            noise: n,
            from,
            to,
        } => {
            let mut opts = bank_options(&bank, PresetArg::Nav440)?;
            one_axis(&opts, "plot")?;
            opts.noise = noise(n.noise_var, n.seed)?;
            let samples = load_samples(&file)?;
            plots::plot_capture(
                &samples,
                &opts,
                &replay::capture_name(&file),
                &output,
                from,
                to,
            )
        }
        Cmd::Synth {
            profile,
            packet,
            rate,
            duration,
            seed,
            start_itow,
            bit,
            flip_bits,
            drop_bytes,
            drop_packets,
            garbage,
            garbage_max_len,
            corrupt_seed,
            yaw_noise,
            noise_seed,
            output,
        } => {
            let cfg = synth::SynthConfig {
                profile,
                seed,
                duration_s: duration,
                rate_hz: rate,
                packet,
                start_itow_ms: start_itow,
                bit,
                corruption: Corruption {
                    bit_flips: flip_bits,
                    dropped_bytes: drop_bytes,
                    dropped_packets: drop_packets,
                    garbage_bursts: garbage,
                    garbage_max_len,
                    seed: corrupt_seed,
                },
                yaw_noise,
                noise_seed,
            };
            let cap = synth::generate(&cfg)?;
            let motion = host_tests::motion::Profile::new(profile, duration, seed);
            let peaks = motion.peaks(1e-3);
            let rms_acc = motion.rms_acc(1e-3);
            std::fs::write(&output, &cap.bytes)
                .map_err(|e| Error::Output(format!("cannot write {}: {e}", output.display())))?;
            let summary = serde_json::json!({
                "file": output.display().to_string(),
                "bytes": cap.bytes.len(),
                "packets": cap.packets,
                "dropped_packets": cap.report.dropped.len(),
                "damaged_packets": cap.report.damaged.len(),
                "intact_packets": cap.report.intact(),
                "garbage_bytes": cap.report.garbage_bytes,
                "peak_yaw_deg": peaks.0,
                "peak_rate_deg_s": peaks.1,
                "peak_acc_deg_s2": peaks.2,
                "rms_acc_deg_s2": rms_acc,
            });
            stdout_or_file(None, |w| writeln!(w, "{summary}"))
        }
    }
}

fn write_file(p: &Path, text: &str) -> Result<()> {
    std::fs::write(p, text).map_err(|e| Error::Output(format!("cannot write {}: {e}", p.display())))
}

/// `-o FILE` of `estimate`: the file is created at the first write, so a command that fails
/// before its first row leaves no file behind.
struct LazyFile {
    path: PathBuf,
    w: Option<std::io::BufWriter<std::fs::File>>,
}

impl LazyFile {
    fn new(path: PathBuf) -> Self {
        LazyFile { path, w: None }
    }

    fn open(&mut self) -> std::io::Result<&mut std::io::BufWriter<std::fs::File>> {
        if self.w.is_none() {
            let f = std::fs::File::create(&self.path).map_err(|e| {
                std::io::Error::new(
                    e.kind(),
                    format!("cannot create {}: {e}", self.path.display()),
                )
            })?;
            self.w = Some(std::io::BufWriter::new(f));
        }
        self.w
            .as_mut()
            .ok_or_else(|| std::io::Error::other("output file not open"))
    }

    /// The result of the command, with a failed creation reported as an output error.
    fn finish<T>(mut self, res: Result<T>) -> Result<T> {
        let v = res.map_err(|e| match e {
            Error::Output(m) if m.contains("cannot create") => {
                Error::Output(m.trim_start_matches("cannot write output: ").to_string())
            }
            other => other,
        })?;
        if let Some(w) = self.w.as_mut() {
            w.flush()
                .map_err(|e| Error::Output(format!("cannot write {}: {e}", self.path.display())))?;
        }
        Ok(v)
    }
}

impl Write for LazyFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.open()?.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match self.w.as_mut() {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

/// Bytes of standard input (or of a pipe) that `decode` reads before it fixes its header.
const DECODE_LOOKAHEAD: u64 = 64 * 1024;

/// Writes to stdout; a closed pipe stops the command quietly.
struct Stdout<'a> {
    w: std::io::BufWriter<std::io::StdoutLock<'a>>,
    closed: bool,
}

impl Stdout<'_> {
    fn new() -> Self {
        Stdout {
            w: std::io::BufWriter::new(std::io::stdout().lock()),
            closed: false,
        }
    }

    fn io(&mut self, r: std::io::Result<()>) -> Result<()> {
        replay::output_result(r, &mut self.closed)
    }

    /// Writes `text` and flushes.
    fn send(&mut self, text: &str) -> Result<()> {
        if self.closed {
            return Ok(());
        }
        let r = self
            .w
            .write_all(text.as_bytes())
            .and_then(|_| self.w.flush());
        self.io(r)
    }
}

/// `nav440 decode`, streamed. A regular file is read twice: a first pass collects the header
/// (the union of the columns, without formatting any value), the second writes the rows as it
/// reads. Standard input (or any pipe) is read once: the header is the union of the columns
/// of the frames in its first `DECODE_LOOKAHEAD` bytes (the whole input if shorter); a later
/// frame with a column outside it loses that cell and is counted in a warning.
fn decode(file: &Path, only: Option<&str>) -> Result<()> {
    use host_tests::decode::{FrameDecoder, Header};
    let mut r = replay::open_capture(file)?;
    let name = r.name().to_string();
    let regular = !replay::is_stdin(file) && std::fs::metadata(file).is_ok_and(|m| m.is_file());
    let mut out = Stdout::new();
    let mut dec = FrameDecoder::new(only);
    let mut header = Header::new();
    let mut line = String::new();
    if regular {
        let mut parser = nav440_proto::Parser::new();
        let mut frames = 0u64;
        r.for_each_chunk(|b| {
            frames += header.scan(&mut parser, b, only);
            Ok(true)
        })?;
        if frames == 0 {
            return with_name(&name, dec.finish());
        }
        out.send(&header.line())?;
        let mut r = replay::open_capture(file)?;
        r.for_each_chunk(|b| {
            line.clear();
            dec.push(b, |row| {
                header.row_line(&row, &mut line);
            });
            out.send(&line)?;
            Ok(!out.closed)
        })?;
        return Ok(());
    }
    let mut held: Vec<host_tests::decode::DecodedRow> = Vec::new();
    let mut started = false;
    let mut outside = 0u64;
    let mut outside_types: std::collections::BTreeSet<String> = Default::default();
    let mut read = 0u64;
    r.for_each_chunk(|b| {
        line.clear();
        read += b.len() as u64;
        dec.push(b, |row| {
            if started {
                if !header.row_line(&row, &mut line) {
                    outside += 1;
                    outside_types.insert(row.name.clone());
                }
            } else {
                header.add_row(&row);
                held.push(row);
            }
        });
        if !started && read >= DECODE_LOOKAHEAD && !held.is_empty() {
            started = true;
            line.push_str(&header.line());
            for row in held.drain(..) {
                header.row_line(&row, &mut line);
            }
        }
        out.send(&line)?;
        Ok(!out.closed)
    })?;
    if out.closed {
        return Ok(());
    }
    with_name(&name, dec.finish())?;
    if !started {
        line.clear();
        line.push_str(&header.line());
        for row in held.drain(..) {
            header.row_line(&row, &mut line);
        }
        out.send(&line)?;
    }
    if outside > 0 {
        eprintln!(
            "nav440: warning: {outside} frames after the first {} KiB of {name} have columns outside the CSV header (types {}); those cells are left out (decode the capture from a file to get every column)",
            DECODE_LOOKAHEAD / 1024,
            outside_types.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    Ok(())
}
