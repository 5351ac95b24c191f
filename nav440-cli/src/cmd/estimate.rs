//! `nav440 estimate`: the estimator bank on a capture, one CSV row per packet, streamed.

use std::io::Write;
use std::path::PathBuf;

use super::{bank_options, noise, with_name, BankArg, BankArgs, NoiseArgs, PresetArg};
use crate::error::{Error, Result};
use crate::replay;

/// Arguments of `nav440 estimate`.
#[derive(clap::Args, Debug)]
pub struct Args {
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
}

/// Streams the capture through the bank; the CSV goes to stdout or `-o`, warnings to stderr.
pub fn run(a: Args) -> Result<()> {
    let mut opts = bank_options(&a.bank, PresetArg::Nav440)?;
    opts.noise = noise(a.noise.noise_var, a.noise.seed)?;
    opts.fixed = a.fixed;
    opts.bank = a.bank_kind.into();
    replay::check_bank_options(&opts)?;
    let mut r = replay::open_capture(&a.file)?;
    let name = r.name().to_string();
    let report = match a.output {
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
