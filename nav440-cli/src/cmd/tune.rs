//! `nav440 tune`: per-family gain calibration on a capture, or a noise-level gain schedule.

use std::io::Write;
use std::path::PathBuf;

use super::{one_axis, AxisArg, BankArg, HoldArg};
use crate::error::{Error, Result};
use crate::limits::{count, noise_var, parse_range};
use crate::output::{self, OutputFile};
use crate::progress::Progress;
use crate::{optim, paper, replay, tune};

/// Arguments of `nav440 tune`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Capture file; `-` reads standard input. Several captures (at one packet rate) tune one
    /// gain set, or one schedule, on all of them: each family's objective is the geometric mean
    /// of its MSEs over the captures.
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    /// Noise variance added to yaw, deg^2 (0 to 1e15).
    #[arg(
        long,
        value_name = "V",
        required_unless_present = "schedule",
        conflicts_with = "schedule"
    )]
    noise_var: Option<f64>,
    /// Tune a gain schedule: one level per noise variance (deg^2, comma-separated,
    /// increasing, e.g. 0.001,0.01,0.1,0.5,1; each > 0 and <= 1e15, at most 8 levels); `-o`
    /// writes the schedule file that `--gains` runs as a noise-adaptive bank, `--rust` its
    /// `SCHEDULE` array.
    #[arg(
        long,
        value_name = "V1,V2,...",
        value_delimiter = ',',
        conflicts_with = "exhaustive"
    )]
    schedule: Option<Vec<f64>>,
    /// Number of noise seeds averaged per evaluation (1 to 100).
    #[arg(long, default_value_t = 3)]
    seeds: u64,
    /// MSE window end, s (tune and score on 0-WINDOW s; at most 2592000, 30 days).
    #[arg(long, default_value_t = 30.0, conflicts_with = "train")]
    window: f64,
    /// Tune on the MSE over this time range, s (e.g. 0-15; 0 <= T0 < T1 <= 2592000).
    #[arg(long, value_name = "T0-T1", value_parser = parse_range)]
    train: Option<(f64, f64)>,
    /// Report the MSE before/after over this time range, s (default: the training range).
    #[arg(long, value_name = "T2-T3", value_parser = parse_range)]
    test: Option<(f64, f64)>,
    /// Reference mode: an exhaustive log grid of N points per gain instead of the search
    /// (2 to 20).
    #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "12")]
    exhaustive: Option<usize>,
    /// Sample adapter; default: tune both and keep the better.
    #[arg(long, value_enum)]
    hold: Option<HoldArg>,
    /// Observer step h, s (1e-7 to 1).
    #[arg(long, default_value_t = 1e-4)]
    step: f32,
    /// Write the tuned gains (TOML, accepted by `--gains`) here (`-`: standard output; the
    /// report then goes to standard error).
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Also write a Rust snippet (BankConfig literal for the firmware) here (`-`: standard
    /// output; the report then goes to standard error).
    #[arg(long, value_name = "FILE")]
    rust: Option<PathBuf>,
    /// Tuned axis: roll, pitch or yaw.
    #[arg(long, value_enum, default_value = "yaw")]
    axis: AxisArg,
    /// The bank tuned: paper (all 14 estimators) or product (its ILO1 velocity and Kalman
    /// acceleration only; the hold is chosen for these two, and `-o` / `--rust` hold their
    /// gains alone, for `nav440 estimate --bank product --gains` and the product firmware).
    #[arg(
        long,
        value_enum,
        default_value = "paper",
        value_name = "BANK",
        conflicts_with = "schedule"
    )]
    bank: BankArg,
}

/// Tunes the gains (or the schedule), prints the report and writes `-o` / `--rust`.
pub fn run(a: Args) -> Result<()> {
    check_numbers(&a)?;
    output::check_stdout()?;
    // The outputs: neither may be a capture, nor both the same; their temporary files are
    // created now, so a directory that cannot take a file is an output error before the
    // captures are read, and nothing at the paths changes until the tuning succeeded.
    if let (Some(o), Some(r)) = (&a.output, &a.rust) {
        output::check_distinct(("-o", o), ("--rust", r))?;
    }
    let inputs: Vec<&std::path::Path> = a.files.iter().map(PathBuf::as_path).collect();
    for (flag, p) in [("-o", &a.output), ("--rust", &a.rust)] {
        if let Some(p) = p {
            output::check_not_input(flag, p, &inputs)?;
        }
    }
    let out = a.output.as_deref().map(OutputFile::create).transpose()?;
    let rust = a.rust.as_deref().map(OutputFile::create).transpose()?;
    // With `-o -` or `--rust -` the file goes to standard output and the report to stderr.
    let report_to_stderr = [&out, &rust]
        .into_iter()
        .flatten()
        .any(OutputFile::is_stdout);
    let report = |text: &str| -> Result<()> {
        if report_to_stderr {
            eprint!("{text}");
            Ok(())
        } else {
            super::stdout_or_file(None, |w| w.write_all(text.as_bytes()))
        }
    };
    let opts = replay::EstimateOptions {
        hold: a.hold.map_or(estimators::Hold::Linear, Into::into),
        step_s: a.step,
        axes: a.axis.into(),
        ..Default::default()
    };
    one_axis(&opts, "tune")?;
    let mut captures = Vec::with_capacity(a.files.len());
    for f in &a.files {
        let cap = replay::read_samples_until(
            f,
            None,
            "tune on a part of it (e.g. `head -c 500M CAPTURE > part.bin`)",
        )?;
        // The input's warnings as `estimate` prints them (one run of the starting bank).
        let summary = replay::summary_of(&cap.samples, &opts.paper_law()).unwrap_or_default();
        for w in cap.warnings(&summary) {
            eprintln!("nav440: warning: {}: {w}", replay::capture_name(f));
        }
        captures.push(cap.samples);
    }
    let captures: Vec<&[replay::Sample]> = captures.iter().map(Vec::as_slice).collect();
    let spec = tune::TuneSpec {
        noise_var: a.noise_var.unwrap_or(0.0),
        seeds: a.seeds.max(1),
        train: a.train.unwrap_or((0.0, a.window)),
        test: a.test,
        method: match a.exhaustive {
            Some(points) => optim::Method::Exhaustive { points },
            None => optim::Method::Search,
        },
        holds: match a.hold {
            Some(h) => vec![h.into()],
            None => vec![estimators::Hold::Linear, estimators::Hold::ZeroOrder],
        },
        families: match a.bank {
            BankArg::Paper => tune::Families::ALL,
            BankArg::Product => tune::Families::product(),
        },
    };
    let (toml_text, rust_text) = if let Some(levels) = a.schedule {
        let spec = tune::TuneSpec {
            holds: vec![a.hold.map_or(estimators::Hold::Linear, Into::into)],
            ..spec
        };
        let progress = progress(&spec, levels.len() as u64);
        let tuned = tune::tune_schedule_on(&captures, &opts, &spec, &levels, &progress);
        progress.finish();
        let (file, text) = tuned?;
        report(&text)?;
        let what = format!(
            "--schedule {}",
            levels
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",")
        );
        (
            file.to_toml(),
            file.to_rust(&what, &estimators::BankConfig::NAV440),
        )
    } else {
        let progress = progress(&spec, 1);
        let res = tune::tune_on(&captures, &opts, &spec, &progress);
        progress.finish();
        let res = res?;
        for w in &res.warnings {
            eprintln!("nav440: warning: {w}");
        }
        report(&res.to_text())?;
        (res.to_toml(), res.to_rust())
    };
    for (f, text) in [(out, toml_text), (rust, rust_text)] {
        if let Some(mut f) = f {
            match f.write_all(text.as_bytes()) {
                Err(e) if f.is_stdout() && e.kind() == std::io::ErrorKind::BrokenPipe => {}
                r => r.map_err(|e| Error::Output(format!("cannot write output: {e}")))?,
            }
            f.commit()?;
        }
    }
    Ok(())
}

/// The most noise seeds per evaluation (`--seeds`).
pub(crate) const MAX_SEEDS: u64 = 100;
/// The most grid points per gain of `--exhaustive` (`points^4` evaluations for the
/// four-gain family: 160,000 at 20).
pub(crate) const MAX_GRID_POINTS: usize = 20;

/// Checks every number of the arguments before any file is touched or any work starts.
fn check_numbers(a: &Args) -> Result<()> {
    if let Some(v) = a.noise_var {
        noise_var("--noise-var", v)?;
    }
    if let Some(levels) = &a.schedule {
        tune::check_levels(levels)?;
    }
    count("--seeds", a.seeds, 1..=MAX_SEEDS, "")?;
    if let Some(n) = a.exhaustive {
        count("--exhaustive", n, 2..=MAX_GRID_POINTS, " points per gain")?;
    }
    crate::limits::step(a.step)?;
    paper::check_window(a.window)
}

/// The progress bar of `runs` tuner runs of `spec` (on stderr when it is a terminal): each
/// run fits every family of both halves for each hold; an exhaustive grid evaluates
/// `points^gains` times per family, a search an unknown number of times (the bar then counts
/// the fits).
fn progress(spec: &tune::TuneSpec, runs: u64) -> Progress {
    let halves = runs * 2 * spec.holds.len().max(1) as u64;
    let dims = search_dims();
    match spec.method {
        optim::Method::Exhaustive { points } => {
            let per_half: u64 = dims.iter().map(|&d| (points.max(2) as u64).pow(d)).sum();
            Progress::items("tune", halves * per_half, "evaluations")
        }
        optim::Method::Search => Progress::fits("tune", halves * dims.len() as u64),
    }
}

/// The number of gains each family's search covers, in column order.
fn search_dims() -> Vec<u32> {
    struct Dims(Vec<u32>);
    impl estimators::FamilyVisitor for Dims {
        fn family<F: estimators::Family>(&mut self, _column: usize) {
            let (lo, _) = crate::search::search_box::<F>(1.0);
            self.0.push(lo.len() as u32);
        }
    }
    let mut d = Dims(Vec::new());
    estimators::for_each_family(&mut d);
    d.0
}
