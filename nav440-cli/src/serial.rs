//! `nav440 config | record | live`: a unit on a real serial port (the `serialport` crate),
//! configured by the same boot sequence the firmware runs ([`nav440_proto::boot`]).
//!
//! After the boot sequence, `record` writes and `live` estimates exactly the bytes that follow
//! the read-back reply (the driver's [`pending_bytes`](nav440_proto::driver::Driver::pending_bytes)
//! first, then the port): the bytes `nav440 sim --record` records, so `nav440 live` prints the
//! text `nav440 estimate` prints on the recorded file.
//!
//! Exit codes (besides clap's 2): 3 the port cannot be opened; 4 no answer from the unit (no
//! NAV440 on that port at any baud tried); 1 the unit rejected the configuration (NAK), the
//! read-back differs, or the port failed; 5 the output cannot be written.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use clap::Args;
use nav440_proto::boot::{self, BootError, Options, Report, Target};
use nav440_proto::driver::{IoDriver, Timing};
use nav440_proto::Baud;

use crate::error::{Error, Result};

use crate::sim::{parse_baud, parse_output_type, parse_rate};

/// The serial port and the target configuration, shared by the three commands.
#[derive(Args, Debug, Clone)]
pub struct PortArgs {
    /// Serial port device (e.g. /dev/ttyUSB0, or the pty path `nav440 sim --listen pty` prints).
    #[arg(long, value_name = "DEV")]
    pub port: String,
    /// Target link baud: 9600, 19200, 38400 or 57600.
    #[arg(long, default_value_t = 57600)]
    pub baud: u32,
    /// Target continuous packet type.
    #[arg(long, default_value = "A2", value_name = "TYPE")]
    pub packet: String,
    /// Target packet rate, Hz (2, 4, 5, 10, 20, 25, 50, 100).
    #[arg(long, default_value_t = 100, value_name = "HZ")]
    pub rate: u32,
    /// Also write the configuration to the unit's EEPROM (WF).
    #[arg(long)]
    pub persist: bool,
    /// The unit's current baud, if known (otherwise 57600, 38400, 19200, 9600 are tried).
    #[arg(long, value_name = "BAUD")]
    pub unit_baud: Option<u32>,
    /// Reply time-out of each request, ms.
    #[arg(long, default_value_t = 200, value_name = "MS")]
    pub reply_timeout: u32,
    /// Pings per baud before trying the next.
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub pings: u8,
}

/// An I/O error of the serial port.
#[derive(Debug)]
pub struct SerialError(pub std::io::Error);

impl std::fmt::Display for SerialError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for SerialError {}

impl embedded_io::Error for SerialError {
    fn kind(&self) -> embedded_io::ErrorKind {
        match self.0.kind() {
            std::io::ErrorKind::TimedOut => embedded_io::ErrorKind::TimedOut,
            std::io::ErrorKind::Interrupted => embedded_io::ErrorKind::Interrupted,
            _ => embedded_io::ErrorKind::Other,
        }
    }
}

/// A `serialport` port as an `embedded-io` serial port (what the driver takes).
pub struct SerialIo(pub Box<dyn serialport::SerialPort>);

impl embedded_io::ErrorType for SerialIo {
    type Error = SerialError;
}

impl embedded_io::Read for SerialIo {
    /// Blocks until at least one byte arrived (retrying the port's read time-out).
    fn read(&mut self, buf: &mut [u8]) -> std::result::Result<usize, SerialError> {
        loop {
            match self.0.read(buf) {
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                    ) => {}
                r => return r.map_err(SerialError),
            }
        }
    }
}

impl embedded_io::ReadReady for SerialIo {
    fn read_ready(&mut self) -> std::result::Result<bool, SerialError> {
        self.0
            .bytes_to_read()
            .map(|n| n > 0)
            .map_err(|e| SerialError(e.into()))
    }
}

impl embedded_io::Write for SerialIo {
    fn write(&mut self, buf: &[u8]) -> std::result::Result<usize, SerialError> {
        self.0.write(buf).map_err(SerialError)
    }
    fn flush(&mut self) -> std::result::Result<(), SerialError> {
        // Waits until the bytes have left the UART (tcdrain), as a baud switch requires.
        self.0.flush().map_err(SerialError)
    }
}

/// `embedded_hal::delay::DelayNs` on the host: `std::thread::sleep`.
pub struct StdDelay;

impl embedded_hal::delay::DelayNs for StdDelay {
    fn delay_ns(&mut self, ns: u32) {
        std::thread::sleep(Duration::from_nanos(u64::from(ns)));
    }
}

/// The longest reply time-out of a request, ms.
const MAX_REPLY_TIMEOUT_MS: u32 = 60_000;

impl PortArgs {
    /// Checks every number of the port arguments before anything touches the port: the
    /// target (type, rate, baud, budget), the unit's baud, the reply time-out (1 to 60,000 ms)
    /// and the pings per baud (at least 1). Returns the target.
    pub(crate) fn check(&self) -> Result<Target> {
        let t = target(self)?;
        self.unit_baud
            .map(|b| parse_baud("--unit-baud", b))
            .transpose()?;
        if !(1..=MAX_REPLY_TIMEOUT_MS).contains(&self.reply_timeout) {
            return Err(Error::Usage(format!(
                "--reply-timeout must be 1 to {MAX_REPLY_TIMEOUT_MS} ms, got {}",
                self.reply_timeout
            )));
        }
        if self.pings == 0 {
            return Err(Error::Usage("--pings must be at least 1".into()));
        }
        Ok(t)
    }
}

fn target(a: &PortArgs) -> Result<Target> {
    let t = Target {
        packet: parse_output_type(&a.packet)?,
        rate: parse_rate("--rate", a.rate)?,
        baud: parse_baud("--baud", a.baud)?,
        persist: a.persist,
    };
    if a.rate == 0 {
        return Err(Error::Usage("--rate 0 (quiet) streams nothing".into()));
    }
    if !t.fits_budget() {
        return Err(Error::Usage(format!(
            "{} at {} Hz = {} B/s does not fit {} Bd (budget {} B/s): the unit would NAK it",
            t.packet,
            a.rate,
            t.bytes_per_second().unwrap_or(0),
            a.baud,
            boot::budget_bytes_per_second(t.baud)
        )));
    }
    Ok(t)
}

/// Opens the port and runs the boot sequence; returns the driver (at the target baud).
pub(crate) fn open_and_boot(a: &PortArgs) -> Result<(IoDriver<SerialIo>, Report, Target)> {
    let t = a.check()?;
    let start_baud = a
        .unit_baud
        .map(|b| parse_baud("--unit-baud", b))
        .transpose()?;
    let first = start_baud.unwrap_or(Baud::B57600).bits_per_second();
    let port = serialport::new(&a.port, first)
        .timeout(Duration::from_millis(100))
        .open()
        .map_err(|e| Error::Input(format!("cannot open serial port {}: {e}", a.port)))?;
    let mut d = IoDriver::new(SerialIo(port));
    d.set_timing(Timing {
        reply_timeout_ms: a.reply_timeout,
        poll_step_us: 500,
    });
    let options = Options {
        start_baud,
        ping_attempts: a.pings,
    };
    let r = boot::boot(&mut d, &t, &options, &mut StdDelay, |s, b| {
        s.0.set_baud_rate(b.bits_per_second())
            .map_err(|e| SerialError(e.into()))
    });
    match r {
        Ok(report) => Ok((d, report, t)),
        Err(e @ BootError::NoAnswer { .. }) => Err(Error::NotNav440(format!("{}: {e}", a.port))),
        Err(e) => Err(Error::Other(format!("{}: {e}", a.port))),
    }
}

pub(crate) fn report_json(port: &str, r: &Report, t: &Target) -> serde_json::Value {
    serde_json::json!({
        "port": port,
        "found_at": r.found_at.bits_per_second(),
        "unit_baud": r.unit_baud.bits_per_second(),
        "initial_packet": r.initial_packet.to_string(),
        "initial_rate_divider": r.initial_rate_divider,
        "switched": r.switched,
        "baud": r.baud.bits_per_second(),
        "packet": t.packet.to_string(),
        "rate_divider": t.rate.divider(),
        "persist": t.persist,
        "ping_retries": r.ping_retries,
        "unsolicited_frames": r.unsolicited_frames,
        "skipped_bytes": r.skipped_bytes,
    })
}

/// Reads the stream after the boot sequence: `on_bytes` gets the driver's pending bytes, then
/// everything the port delivers until `duration` or the end of the stream (the port closed).
pub(crate) fn stream_after_boot(
    d: IoDriver<SerialIo>,
    duration: Option<f64>,
    on_bytes: impl FnMut(&[u8]) -> Result<bool>,
) -> Result<u64> {
    stream_until(d, duration, None, on_bytes)
}

/// [`stream_after_boot`], also ending (as at the end of the stream) once `stop` is set: the
/// port's read time-out (100 ms) bounds the delay.
pub(crate) fn stream_until(
    d: IoDriver<SerialIo>,
    duration: Option<f64>,
    stop: Option<&std::sync::atomic::AtomicBool>,
    mut on_bytes: impl FnMut(&[u8]) -> Result<bool>,
) -> Result<u64> {
    let duration = duration
        .map(|s| crate::limits::seconds("--duration", s, false))
        .transpose()?;
    let pending = d.pending_bytes().to_vec();
    let SerialIo(mut port) = d.release();
    let end = duration.map(|s| Instant::now() + Duration::from_secs_f64(s));
    let mut total = pending.len() as u64;
    if !on_bytes(&pending)? {
        return Ok(total);
    }
    let mut buf = [0u8; 1024];
    loop {
        if end.is_some_and(|e| Instant::now() >= e)
            || stop.is_some_and(|s| s.load(std::sync::atomic::Ordering::Relaxed))
        {
            return Ok(total);
        }
        match port.read(&mut buf) {
            Ok(0) => return Ok(total),
            Ok(n) => {
                total += n as u64;
                if !on_bytes(&buf[..n])? {
                    return Ok(total);
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                ) => {}
            // Hang-up (EIO, or `serialport`'s BrokenPipe on POLLHUP): the other end of a
            // pseudo-terminal closed, a USB adapter was unplugged.
            Err(e) if e.raw_os_error() == Some(5) || e.kind() == std::io::ErrorKind::BrokenPipe => {
                return Ok(total)
            }
            Err(e) => return Err(Error::Other(format!("serial port failed: {e}"))),
        }
    }
}
