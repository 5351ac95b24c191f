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
use nav440_proto::{Baud, FieldId, PacketType};

use crate::error::{Error, Result};

use crate::sim::{parse_baud, parse_output_type, parse_rate};

/// The serial port and how to find the unit on it, shared by every command that talks to a
/// unit (`config`, `record`, `live`, `info`).
#[derive(Args, Debug, Clone)]
pub struct LinkArgs {
    /// Serial port device (e.g. /dev/ttyUSB0, or the pty path `nav440 sim --listen pty` prints).
    #[arg(long, value_name = "DEV")]
    pub port: String,
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

/// The serial port and the target configuration, shared by the three commands that configure
/// the unit (`config`, `record`, `live`).
#[derive(Args, Debug, Clone)]
pub struct PortArgs {
    /// The port and how to find the unit on it.
    #[command(flatten)]
    pub link: LinkArgs,
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
    /// target (type, rate, baud, budget) and the link's ([`LinkArgs::check`]). Returns the
    /// target.
    pub(crate) fn check(&self) -> Result<Target> {
        let t = target(self)?;
        self.link.check()?;
        Ok(t)
    }
}

impl LinkArgs {
    /// Checks the unit's baud, the reply time-out (1 to 60,000 ms) and the pings per baud (at
    /// least 1) before anything touches the port; returns the unit's baud if given.
    pub(crate) fn check(&self) -> Result<Option<Baud>> {
        let start_baud = self
            .unit_baud
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
        Ok(start_baud)
    }

    /// Opens the port at `baud` (100 ms read time-out) with the driver's reply time-out set.
    pub(crate) fn open(&self, baud: Baud) -> Result<IoDriver<SerialIo>> {
        let port = serialport::new(&self.port, baud.bits_per_second())
            .timeout(Duration::from_millis(100))
            .open()
            .map_err(|e| Error::Input(format!("cannot open serial port {}: {e}", self.port)))?;
        let mut d = IoDriver::new(SerialIo(port));
        d.set_timing(Timing {
            reply_timeout_ms: self.reply_timeout,
            poll_step_us: 500,
        });
        Ok(d)
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

/// Changes the local port's baud (the boot sequence's and `info`'s `set_baud`).
pub(crate) fn set_local_baud(s: &mut SerialIo, b: Baud) -> std::result::Result<(), SerialError> {
    s.0.set_baud_rate(b.bits_per_second())
        .map_err(|e| SerialError(e.into()))
}

/// Opens the port and runs the boot sequence; returns the driver (at the target baud).
pub(crate) fn open_and_boot(a: &PortArgs) -> Result<(IoDriver<SerialIo>, Report, Target)> {
    let t = a.check()?;
    let start_baud = a.link.check()?;
    let mut d = a.link.open(start_baud.unwrap_or(Baud::B57600))?;
    let options = Options {
        start_baud,
        ping_attempts: a.link.pings,
    };
    let r = boot::boot(&mut d, &t, &options, &mut StdDelay, set_local_baud);
    let port = &a.link.port;
    match r {
        Ok(report) => Ok((d, report, t)),
        Err(e @ BootError::NoAnswer { .. }) => Err(Error::NotNav440(format!("{port}: {e}"))),
        Err(e @ BootError::Nak { request, fields })
            if request == PacketType::SF
                && fields.iter().any(|(id, _)| id == FieldId::PACKET_TYPE) =>
        {
            Err(Error::Other(format!(
                "{port}: {e} (the unit does not stream {}: an IMU440 streams no angle packets; \
                 `nav440 info --port {port}` names the unit)",
                t.packet
            )))
        }
        Err(e) => Err(Error::Other(format!("{port}: {e}"))),
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
/// everything the port delivers until `duration`, the end of the stream (the port closed) or
/// `stop` (the port's read time-out, 100 ms, bounds the delay).
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
    let total = pending.len() as u64;
    if !on_bytes(&pending)? {
        return Ok(total);
    }
    Ok(total + read_until(&mut *port, "serial port", end, stop, on_bytes)?)
}

/// Reads `port` until `end`, the end of the stream (the port closed, or hung up) or `stop`,
/// giving every chunk to `on_bytes` (which stops the reading with `Ok(false)`); the bytes
/// read. A read time-out only lets `end` and `stop` be checked; another error is `what`
/// failing.
pub(crate) fn read_until(
    port: &mut dyn Read,
    what: &str,
    end: Option<Instant>,
    stop: Option<&std::sync::atomic::AtomicBool>,
    mut on_bytes: impl FnMut(&[u8]) -> Result<bool>,
) -> Result<u64> {
    let mut total = 0;
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
            Err(e) => return Err(Error::Other(format!("{what} failed: {e}"))),
        }
    }
}

/// True when a packet of type `t` carries the attitude (roll, pitch, yaw) and the rate the
/// pipeline estimates from (A0, A1, A2, N0, N1, B1: read from the packet table, not listed
/// here); false for the sensor packets (S0, S1, S2), T0 and any other type.
pub fn carries_angles(t: PacketType) -> bool {
    let Some(len) = t.output_payload_len() else {
        return false;
    };
    let payload = vec![0u8; len];
    let frame = nav440_proto::Frame {
        packet_type: t,
        payload: &payload,
    };
    nav440_proto::Packet::decode(frame)
        .is_ok_and(|p| p.attitude().is_some() && p.yaw_sample().is_some())
}

/// The output types that carry the angles ([`carries_angles`]), e.g. `A0, A1, A2, N0, N1, B1`.
pub fn angle_types() -> String {
    let names: Vec<&str> = PacketType::KNOWN
        .iter()
        .filter(|t| carries_angles(**t))
        .map(PacketType::name)
        .collect();
    names.join(", ")
}

/// Who the unit is and what it streams: `nav440 info`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Identity {
    /// The local baud at which the unit first answered a ping.
    pub found_at: Baud,
    /// The baud the unit reported (GF of 0x0002; the baud that answered if it reported none).
    pub unit_baud: Baud,
    /// The continuous packet type in force (GF of 0x0003).
    pub packet: PacketType,
    /// The rate divider in force (GF of 0x0001).
    pub rate_divider: u16,
    /// Pings that got no answer before the unit was found.
    pub ping_retries: u32,
    /// The ID packet's serial number.
    pub serial_number: u32,
    /// The ID packet's model string (the part number), invalid UTF-8 replaced.
    pub model: String,
    /// The VR packet: major, minor, patch, stage, build.
    pub version: [u8; 5],
}

impl Identity {
    /// The firmware version as `major.minor.patch` with its stage and build, e.g. `1.0.0
    /// (release candidate, build 0)`.
    pub fn version_text(&self) -> String {
        let [major, minor, patch, stage, build] = self.version;
        let stage = match stage {
            0 => "release candidate".to_string(),
            1 => "development".to_string(),
            2 => "alpha".to_string(),
            3 => "beta".to_string(),
            s => format!("stage {s}"),
        };
        format!("{major}.{minor}.{patch} ({stage}, build {build})")
    }
}

/// Finds the unit on the port as the boot sequence does (a ping at each candidate baud), reads
/// its output settings (GF of fields 1, 2, 3), then asks for its ID and VR packets (GP); sends
/// no SF or WF, so the unit's configuration is left as it was. Errors: exit 3 the port cannot
/// be opened, 4 no answer to the ping, 1 a NAK, no ID or VR reply within the reply time-out,
/// or a port failure.
pub fn identify(a: &LinkArgs) -> Result<Identity> {
    use nav440_proto::driver::Error as DriverError;
    let start = a.check()?;
    let mut d = a.open(start.unwrap_or(Baud::B57600))?;
    let candidates: Vec<Baud> = match start {
        Some(b) => vec![b],
        None => boot::SEARCH_ORDER.to_vec(),
    };
    let port = &a.port;
    let failed = |what: &str, e: DriverError<SerialError>| match e {
        DriverError::NoReply => Error::Other(format!(
            "{port}: no reply to {what} within {} ms (the unit answered the ping)",
            a.reply_timeout
        )),
        e => Error::Other(format!("{port}: {what}: {e}")),
    };
    let (mut found, mut retries, mut tried) = (None, 0u32, boot::Bauds::default());
    'search: for &b in &candidates {
        switch_local(&mut d, b).map_err(|e| failed("the baud switch", e))?;
        tried.insert(b);
        for _ in 0..a.pings {
            match d.ping_wait(&mut StdDelay) {
                Ok(()) => {
                    found = Some(b);
                    break 'search;
                }
                Err(DriverError::NoReply) => retries += 1,
                Err(e) => return Err(failed("PK (ping)", e)),
            }
        }
    }
    let Some(found_at) = found else {
        let e = BootError::<SerialError>::NoAnswer {
            request: PacketType::PK,
            tried,
            attempts: a.pings,
            timeout_ms: a.reply_timeout,
        };
        return Err(Error::NotNav440(format!("{port}: {e}")));
    };
    let [rate, baud, packet, ..] = d
        .get_fields(PacketType::GF, &boot::READ_FIELDS, &mut StdDelay)
        .map_err(|e| failed("GF 1,2,3 (the output settings)", e))?;
    let unit_baud = baud.and_then(Baud::from_code).unwrap_or(found_at);
    if unit_baud != found_at {
        switch_local(&mut d, unit_baud).map_err(|e| failed("the baud switch", e))?;
    }
    let timeout = Duration::from_millis(u64::from(a.reply_timeout));
    let (serial_number, model) = get_packet(&mut d, PacketType::ID, timeout, |p| match p {
        nav440_proto::Packet::Id(id) => Some((
            id.serial(),
            String::from_utf8_lossy(id.model()).into_owned(),
        )),
        _ => None,
    })
    .map_err(|e| failed("GP ID (serial number and model)", e))?;
    let version = get_packet(&mut d, PacketType::VR, timeout, |p| match p {
        nav440_proto::Packet::Vr(v) => {
            let f = v.fields();
            Some([f.major, f.minor, f.patch, f.stage, f.build])
        }
        _ => None,
    })
    .map_err(|e| failed("GP VR (firmware version)", e))?;
    Ok(Identity {
        found_at,
        unit_baud,
        packet: PacketType::from_code(packet.unwrap_or(0)),
        rate_divider: rate.unwrap_or(0),
        ping_retries: retries,
        serial_number,
        model,
        version,
    })
}

/// Switches the local port to `b` and tells the driver (line time, partial frame dropped).
fn switch_local(
    d: &mut IoDriver<SerialIo>,
    b: Baud,
) -> std::result::Result<(), nav440_proto::driver::Error<SerialError>> {
    set_local_baud(d.serial_mut(), b).map_err(nav440_proto::driver::Error::Serial)?;
    d.set_line_baud(b.bits_per_second());
    d.clear_parser();
    Ok(())
}

/// GP of `t`, then the frames that arrive until `take` returns a value for one of them (the
/// reply), a NAK of GP, or `timeout`; the unit's streaming frames in between are skipped.
fn get_packet<T>(
    d: &mut IoDriver<SerialIo>,
    t: PacketType,
    timeout: Duration,
    mut take: impl FnMut(&nav440_proto::Packet<'_>) -> Option<T>,
) -> std::result::Result<T, nav440_proto::driver::Error<SerialError>> {
    use nav440_proto::driver::Error as DriverError;
    d.request_packet(t)?;
    let end = Instant::now() + timeout;
    let (mut got, mut nak) = (None, false);
    while got.is_none() && !nak && Instant::now() < end {
        d.poll_timeout(10_000, &mut StdDelay, |p| match p {
            Ok(nav440_proto::Packet::Nak(n)) if n.failed_type() == PacketType::GP => nak = true,
            Ok(p) if got.is_none() => got = take(&p),
            _ => {}
        })?;
    }
    match got {
        Some(v) => Ok(v),
        None if nak => Err(DriverError::Nak {
            request: PacketType::GP,
        }),
        None => Err(DriverError::NoReply),
    }
}
