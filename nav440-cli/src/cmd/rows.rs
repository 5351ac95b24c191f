//! `nav440 rows`: the rows a `uart-rows` firmware sends out of its output UART, read from a
//! serial port or a saved stream, printed as the CSV of `nav440 estimate` ([`crate::rows`]).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::error::{Error, Result};
use crate::replay;
use crate::rows::RowsReader;

/// The line rates `--baud` accepts, Bd.
const BAUD_RANGE: std::ops::RangeInclusive<u32> = 50..=12_000_000;

/// Arguments of `nav440 rows`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// A saved stream of the output UART (e.g. QEMU's `-chardev file`); `-` reads standard
    /// input. Instead of --port.
    #[arg(
        value_name = "FILE",
        required_unless_present = "port",
        conflicts_with = "port"
    )]
    input: Option<PathBuf>,
    /// The serial port the firmware's output UART is wired to (e.g. /dev/ttyUSB1); read until
    /// it closes, --duration, or SIGINT/SIGTERM.
    #[arg(long, value_name = "DEV")]
    port: Option<String>,
    /// Line rate of --port, Bd (the firmware's output UART: 921600).
    #[arg(long, default_value_t = 921_600, value_name = "BAUD")]
    baud: u32,
    /// With --port: stop after this many seconds.
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
}

/// `nav440 rows`: the CSV on stdout, the reports of bad frames and what was skipped on stderr.
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    if !BAUD_RANGE.contains(&a.baud) {
        return Err(Error::Usage(format!(
            "--baud must be {} to {} Bd, got {}",
            BAUD_RANGE.start(),
            BAUD_RANGE.end(),
            a.baud
        )));
    }
    let duration = a
        .duration
        .map(|s| crate::limits::seconds("--duration", s, false))
        .transpose()?;
    let mut reader = RowsReader::new();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut warn = |w: &str| eprintln!("nav440: warning: {w}");
    let mut feed = |bytes: &[u8]| -> Result<bool> {
        reader.feed(bytes, &mut out, &mut warn)?;
        Ok(!reader.output_closed())
    };
    match (&a.port, &a.input) {
        (Some(port), _) => read_port(port, a.baud, duration, &mut feed)?,
        (None, Some(file)) => {
            let mut r = replay::open_capture(file)?;
            r.for_each_chunk(&mut feed)?;
        }
        (None, None) => return Err(Error::Usage("give FILE or --port DEV".into())),
    }
    if reader.output_closed() {
        return Ok(());
    }
    for w in reader.finish()? {
        eprintln!("nav440: warning: {w}");
    }
    Ok(())
}

/// Reads `port` at `baud` until it closes (hang-up), `duration` s or SIGINT/SIGTERM, giving
/// every chunk to `feed` (which stops the reading with `Ok(false)`).
fn read_port(
    port: &str,
    baud: u32,
    duration: Option<f64>,
    feed: &mut dyn FnMut(&[u8]) -> Result<bool>,
) -> Result<()> {
    let mut p = serialport::new(port, baud)
        .timeout(Duration::from_millis(100))
        .open()
        .map_err(|e| Error::Input(format!("cannot open serial port {port}: {e}")))?;
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .map_err(|e| Error::Other(format!("cannot handle SIGINT/SIGTERM: {e}")))?;
    }
    let end = duration.map(|s| Instant::now() + Duration::from_secs_f64(s));
    crate::serial::read_until(
        &mut *p,
        &format!("serial port {port}"),
        end,
        Some(&stop),
        feed,
    )?;
    Ok(())
}
