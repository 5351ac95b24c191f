//! `nav440 live`: configure a unit, then print the estimate CSV while receiving
//! ([`crate::serial`]), or draw it as a live chart ([`crate::live_plot`]).

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};

use super::{print_warnings, EstimateArgs};
use crate::error::{Error, Result};
use crate::live_plot::{self, ChannelWriter};
use crate::replay::{self, EstimateOptions};
use crate::serial::{
    angle_types, carries_angles, open_and_boot, report_json, stream_until, PortArgs, SerialIo,
};
use nav440_proto::driver::IoDriver;

/// Arguments of `nav440 live`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(flatten)]
    pub(crate) port: PortArgs,
    #[command(flatten)]
    estimate: EstimateArgs,
    /// Stop after this many seconds (default: when the port closes).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Draw the estimates as a live chart in the terminal instead of printing the CSV: per
    /// axis the reference rate and the ILO1 velocity (deg/s), and the Kalman acceleration
    /// (deg/s^2), over the last 10 s; `q`, Esc or Ctrl-C quits.
    #[arg(long)]
    plot: bool,
}

/// `nav440 live`: the boot sequence, then the estimate CSV on stdout while receiving (the
/// text `nav440 estimate` prints on the same bytes with the same options), or the chart.
pub fn run(a: &Args) -> Result<()> {
    if a.plot {
        if !std::io::stdout().is_terminal() {
            return Err(Error::Usage(
                "--plot draws on a terminal, and standard output is not one (without --plot \
                 `nav440 live` prints the CSV)"
                    .into(),
            ));
        }
    } else {
        crate::output::check_stdout()?;
    }
    let t = a.port.check()?;
    if !carries_angles(t.packet) {
        return Err(Error::Usage(format!(
            "--packet {}: it carries no angles, and `nav440 live` estimates from them: use one \
             of {}",
            t.packet,
            angle_types()
        )));
    }
    if let Some(s) = a.duration {
        crate::limits::seconds("--duration", s, false)?;
    }
    let opts = a.estimate.options()?;
    let (d, report, t) = open_and_boot(&a.port)?;
    eprintln!(
        "nav440 live: {}",
        report_json(&a.port.link.port, &report, &t)
    );
    let stop = Arc::new(AtomicBool::new(false));
    if a.plot {
        return plot(a, d, &opts, stop);
    }
    let stdout = std::io::stdout();
    let report = estimate(d, a.duration, &opts, &stop, &mut stdout.lock())?;
    print_warnings(&report);
    Ok(())
}

/// The stream after the boot sequence through the same pipeline as `nav440 estimate` (the
/// warm-up, the bank for the unit's packet rate, the CSV, the warnings), until the port
/// closes, `duration` or `stop`.
fn estimate(
    d: IoDriver<SerialIo>,
    duration: Option<f64>,
    opts: &EstimateOptions,
    stop: &AtomicBool,
    out: &mut dyn std::io::Write,
) -> Result<replay::StreamReport> {
    let source = replay::FnChunks(|f: &mut dyn FnMut(&[u8]) -> Result<bool>| {
        stream_until(d, duration, Some(stop), f).map(|_| ())
    });
    replay::estimate_stream(source, opts, out)
}

/// `--plot`: the estimation runs on a thread and sends its CSV to the chart, which draws on
/// this thread; `q` (or SIGINT/SIGTERM) sets `stop`, which ends the stream within the port's
/// read time-out.
fn plot(
    a: &Args,
    d: IoDriver<SerialIo>,
    opts: &EstimateOptions,
    stop: Arc<AtomicBool>,
) -> Result<()> {
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .map_err(|e| Error::Other(format!("cannot handle SIGINT/SIGTERM: {e}")))?;
    }
    let (tx, rx) = mpsc::channel();
    let worker = {
        let (stop, opts, duration) = (stop.clone(), opts.clone(), a.duration);
        std::thread::spawn(move || estimate(d, duration, &opts, &stop, &mut ChannelWriter(tx)))
    };
    let title = format!(
        "nav440 live  {}  bank {}  {}",
        a.port.link.port,
        match a.estimate.bank_kind {
            super::BankArg::Paper => "paper",
            super::BankArg::Product => "product",
        },
        t_packet(a)
    );
    let drawn = live_plot::run(rx, &stop, &title);
    stop.store(true, Ordering::Relaxed);
    let report = worker
        .join()
        .map_err(|_| Error::Other("the estimation thread panicked".into()))?;
    let rows = drawn.map_err(|e| Error::Output(format!("cannot draw on the terminal: {e}")))?;
    let report = report?;
    eprintln!("nav440 live: {rows} rows plotted");
    print_warnings(&report);
    Ok(())
}

fn t_packet(a: &Args) -> String {
    format!(
        "{} at {} Hz",
        a.port.packet.to_ascii_uppercase(),
        a.port.rate
    )
}
