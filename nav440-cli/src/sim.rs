//! `nav440 sim`: a simulated NAV440 on a TCP socket or a pseudo-terminal.
//!
//! The command side is [`nav440_proto::unit::Unit`] (PK, CH, GP, SF, WF, GF, RF, AR, SR; NAKs
//! for unknown requests, invalid fields and over-budget combinations at the baud in force).
//! This module adds what a unit streams and when:
//!
//! * **Power-up**: the EEPROM configuration (default S1 at 20 Hz at 38400 Bd) streams in wall
//!   time, interleaved with the replies. By default the stream starts with the first byte the
//!   host sends (so a UART that is enabled late, like QEMU's STM32 USART, loses nothing);
//!   `--stream-at-connect` starts it when the host connects, like a unit powered up already.
//! * **Commanded**: from the SF reply that sets the packet type or rate until the read-back,
//!   the unit streams nothing.
//! * **Configured**: right after the reply to the first GF that follows, the unit streams the
//!   capture's samples, re-encoded as the commanded packet type, at the commanded rate (one
//!   packet per rate period in wall time, or as fast as the host reads with `--fast`), then
//!   closes the connection. A capture denser than the commanded rate is decimated by its time
//!   stamps (a sample is sent when at least one period, less 1 ms, has passed since the last
//!   one sent); time stamps are the capture's.
//!
//! `--record FILE` holds exactly the bytes sent in the configured state: everything after the
//! read-back (GF) reply, up to the close or a reset. A host that starts estimating with the
//! first byte after its read-back reply therefore sees exactly the recorded bytes.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::ValueEnum;
use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::{Baud, PacketRate, PacketType};

use crate::error::{Error, Result};
use crate::output::OutputFile;
pub use crate::raw_sample::{capture_samples, encode_sample, RawSample};
use crate::replay::read_capture;

/// A deliberate fault of the simulated unit (for CI).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Fault {
    /// Ignores every request (no reply, no NAK) but streams its power-up packets.
    NoAnswer,
    /// Sends nothing at all and ignores every request.
    Dead,
    /// NAKs every SF/WF that sets the packet type or rate.
    NakConfig,
    /// Accepts the rate in SF but keeps its old one: the read-back differs.
    WrongReadback,
    /// Resets mid-stream (after `--reset-after` packets): 100 ms of silence, then power-up
    /// behaviour again (EEPROM configuration, power-up stream).
    Reset,
    /// Goes silent mid-stream (after `--reset-after` packets) with the link open: sends
    /// nothing and ignores every request for `--silence` seconds (0: until the host leaves),
    /// then answers requests again but streams only once configured again.
    Silence,
    /// Freezes its time stamps mid-stream: the 50 packets after the first `--reset-after`
    /// repeat the last time stamp (the samples go on).
    Freeze,
    /// Streams at twice the configured rate: time stamps half a period apart.
    DoubleRate,
}

/// Arguments of `nav440 sim`.
#[derive(clap::Args, Debug, Clone)]
pub struct SimArgs {
    /// Capture (raw NAV440 byte stream) whose samples the unit streams once configured.
    pub capture: PathBuf,
    /// Where the unit listens: tcp:HOST:PORT (loopback; port 0 picks a free port) or pty
    /// (a pseudo-terminal pair). The address or the pty's path is printed on stdout.
    #[arg(long, value_name = "ADDR")]
    pub listen: String,
    /// Allow a --listen address that is not loopback (the unit then answers anyone who can
    /// reach the port).
    #[arg(long)]
    pub listen_any: bool,
    /// Write exactly the bytes streamed after configuration (after the read-back reply) here.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Also write the address / pty path (one line) to this file once listening.
    #[arg(long, value_name = "FILE")]
    pub address_file: Option<PathBuf>,
    /// The unit's baud at power-up (EEPROM): 9600, 19200, 38400 or 57600.
    #[arg(long, default_value_t = 38400)]
    pub baud: u32,
    /// Packet type streamed at power-up (S0, S1, S2, A0, A1, A2, N0, N1, B1, T0).
    #[arg(long, default_value = "S1", value_name = "TYPE")]
    pub power_up_packet: String,
    /// Power-up rate, Hz (0 quiet, 2, 4, 5, 10, 20, 25, 50, 100).
    #[arg(long, default_value_t = 20, value_name = "HZ")]
    pub power_up_rate: u32,
    /// Stream the capture as fast as the host reads, instead of at the commanded rate in wall time.
    #[arg(long)]
    pub fast: bool,
    /// Start the power-up stream when the host connects rather than at its first byte.
    #[arg(long)]
    pub stream_at_connect: bool,
    /// Misbehave on purpose.
    #[arg(long, value_enum)]
    pub fault: Option<Fault>,
    /// With --fault reset, silence or freeze: capture packets streamed before the fault.
    #[arg(long, default_value_t = 50, value_name = "N")]
    pub reset_after: u64,
    /// With --fault silence or --inject silence@N: how long the unit stays silent, s (0: until
    /// the host leaves); it then answers requests but streams only once configured again.
    #[arg(long, default_value_t = 0.0, value_name = "S")]
    pub silence: f64,
    /// Inject a fault after N capture packets (repeatable): silence@N, reset@N, freeze@N
    /// (50 packets repeat the last time stamp) or garbage@N (256 bytes with false frame
    /// headers, recorded).
    #[arg(long, value_name = "KIND@N")]
    pub inject: Vec<String>,
    /// Give up (exit 1) when the session has not ended after this many seconds (0: never).
    #[arg(long, default_value_t = 0.0, value_name = "S")]
    pub timeout: f64,
    /// Write the session's summary (JSON: requests, power_up_packets, packets, recorded_bytes,
    /// completed, resets, injected) here at the end.
    #[arg(long, value_name = "FILE")]
    pub summary: Option<PathBuf>,
    /// Log every request and state change on stderr.
    #[arg(long)]
    pub verbose: bool,
}

/// Parses a packet type name (`A2`) that the unit can stream.
pub fn parse_output_type(name: &str) -> Result<PacketType> {
    if let [a, c] = name.as_bytes() {
        let t = PacketType([a.to_ascii_uppercase(), *c]);
        if t.output_payload_len().is_some() {
            return Ok(t);
        }
    }
    let streamed: Vec<&str> = PacketType::KNOWN
        .iter()
        .filter(|t| t.output_payload_len().is_some())
        .map(PacketType::name)
        .collect();
    Err(Error::Usage(format!(
        "`{name}` is not a packet type the unit streams ({})",
        streamed.join(", ")
    )))
}

/// The rate for `hz` (0 = quiet); the usage error names the flag `flag`.
pub fn parse_rate(flag: &str, hz: u32) -> Result<PacketRate> {
    let r = match hz {
        0 => Some(PacketRate::Quiet),
        h if h > 0 && 100 % h == 0 => PacketRate::from_divider((100 / h) as u16),
        _ => None,
    };
    r.ok_or_else(|| {
        Error::Usage(format!(
            "{flag} {hz} Hz is not one of 0, 2, 4, 5, 10, 20, 25, 50, 100"
        ))
    })
}

/// The baud for `bps`; the usage error names the flag `flag`.
pub fn parse_baud(flag: &str, bps: u32) -> Result<Baud> {
    Baud::from_bits_per_second(bps).ok_or_else(|| {
        Error::Usage(format!(
            "{flag} {bps} is not one of 9600, 19200, 38400, 57600"
        ))
    })
}

/// Where the simulator listens.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Listen {
    /// TCP `host:port`.
    Tcp(String),
    /// A new pseudo-terminal pair.
    Pty,
}

/// Parses `tcp:HOST:PORT` or `pty`. A TCP address must resolve to loopback addresses only,
/// unless `any_address` (`--listen-any`): the simulated unit then answers anyone who can reach
/// the port.
pub fn parse_listen(s: &str, any_address: bool) -> Result<Listen> {
    if s == "pty" {
        return Ok(Listen::Pty);
    }
    let bad = || {
        Error::Usage(format!(
            "--listen `{s}`: expected tcp:HOST:PORT (e.g. tcp:127.0.0.1:4440) or pty"
        ))
    };
    let a = s.strip_prefix("tcp:").ok_or_else(bad)?;
    let port_ok = a
        .rsplit_once(':')
        .is_some_and(|(_, p)| p.parse::<u16>().is_ok());
    if !port_ok {
        return Err(bad());
    }
    if !any_address {
        let addrs: Vec<std::net::SocketAddr> = std::net::ToSocketAddrs::to_socket_addrs(a)
            .map_err(|e| Error::Usage(format!("--listen `{s}`: {e}")))?
            .collect();
        if addrs.is_empty() || addrs.iter().any(|x| !x.ip().is_loopback()) {
            return Err(Error::Usage(format!(
                "--listen `{s}` is not a loopback address: the simulated unit would answer the network; use 127.0.0.1 or [::1], or add --listen-any"
            )));
        }
    }
    Ok(Listen::Tcp(a.to_string()))
}

/// A byte stream to the host: a TCP connection or a pty master.
trait Conn: Read + Write + Send {
    /// A second handle for the reader thread.
    fn reader(&self) -> std::io::Result<Box<dyn Read + Send>>;
    /// Ends the session (TCP: shutdown; pty: the master is dropped by the caller).
    fn close(&mut self);
}

impl Conn for TcpStream {
    fn reader(&self) -> std::io::Result<Box<dyn Read + Send>> {
        Ok(Box::new(self.try_clone()?))
    }
    fn close(&mut self) {
        let _ = self.flush();
        let _ = self.shutdown(std::net::Shutdown::Both);
    }
}

impl Conn for serialport::TTYPort {
    fn reader(&self) -> std::io::Result<Box<dyn Read + Send>> {
        Ok(Box::new(self.try_clone_native()?))
    }
    fn close(&mut self) {
        let _ = self.flush();
    }
}

enum Msg {
    Bytes(Vec<u8>),
    Closed,
}

/// An I/O error after which the same read or write is tried again: a time-out that lets the
/// session check its deadline, or an interrupted call.
fn retryable(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::TimedOut
            | std::io::ErrorKind::WouldBlock
            | std::io::ErrorKind::Interrupted
    )
}

fn spawn_reader(mut r: Box<dyn Read + Send>, tx: Sender<Msg>, stop: Arc<AtomicBool>) {
    std::thread::spawn(move || {
        let mut buf = [0u8; 512];
        while !stop.load(Ordering::Relaxed) {
            match r.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    if tx.send(Msg::Bytes(buf[..n].to_vec())).is_err() {
                        return;
                    }
                }
                Err(e) if retryable(&e) => {}
                Err(_) => break,
            }
        }
        let _ = tx.send(Msg::Closed);
    });
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    PowerUp,
    Commanded,
    Configured,
    Resetting(Instant),
    /// `--fault silence`: deaf and mute until then (`None`: for ever), then stalled.
    Silent(Option<Instant>),
    /// After a silence: answers requests but streams nothing until it is configured again.
    Stalled,
}

/// What happened in a session.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Requests answered (or ignored).
    pub requests: u64,
    /// Power-up packets streamed.
    pub power_up_packets: u64,
    /// Capture packets streamed in the configured state.
    pub packets: u64,
    /// Bytes recorded (sent in the configured state).
    pub recorded_bytes: u64,
    /// The whole capture was streamed and the connection closed by the unit.
    pub completed: bool,
    /// Resets done.
    pub resets: u64,
    /// Faults injected (`--fault reset|silence|freeze` and every `--inject`).
    pub injected: u64,
}

/// A fault `nav440 sim` injects mid-stream (`--inject KIND@N`, or `--fault` at
/// `--reset-after`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inject {
    /// Silent and deaf for `--silence` s, then stalled until configured again.
    Silence,
    /// A reset: 100 ms deaf, then power-up behaviour.
    Reset,
    /// [`FREEZE_PACKETS`] packets repeating the last time stamp.
    Freeze,
    /// [`GARBAGE_BYTES`] bytes of garbage with false frame headers (recorded).
    Garbage,
}

impl Inject {
    /// The name used in `--inject`.
    pub fn name(self) -> &'static str {
        match self {
            Inject::Silence => "silence",
            Inject::Reset => "reset",
            Inject::Freeze => "freeze",
            Inject::Garbage => "garbage",
        }
    }
}

/// Packets of a frozen-stamp run.
pub const FREEZE_PACKETS: u64 = 50;
/// Bytes of an injected garbage burst.
pub const GARBAGE_BYTES: usize = 256;
/// The most `--inject` faults one session takes.
pub const MAX_INJECTIONS: usize = 10_000;

/// The garbage burst injected after packet `k`: pseudo-random bytes (seeded by `k`) with a
/// false frame header (`55 55 'A' '2'` and a length) every 32 bytes; no valid frame.
pub fn garbage_burst(k: u64) -> Vec<u8> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(k ^ 0x4741_5242);
    let mut out: Vec<u8> = (0..GARBAGE_BYTES).map(|_| rng.random()).collect();
    for (i, chunk) in out.chunks_mut(32).enumerate() {
        if let Some(h) = chunk.get_mut(..5) {
            h.copy_from_slice(&[0x55, 0x55, b'A', b'2', (i * 37) as u8]);
        }
    }
    out
}

/// The session's injections, sorted: `--fault reset|silence|freeze` at `--reset-after`, then
/// every `--inject KIND@N` (N: capture packets streamed before it).
fn injections(args: &SimArgs) -> Result<Vec<(u64, Inject)>> {
    let mut out = Vec::new();
    match args.fault {
        Some(Fault::Reset) => out.push((args.reset_after, Inject::Reset)),
        Some(Fault::Silence) => out.push((args.reset_after, Inject::Silence)),
        Some(Fault::Freeze) => out.push((args.reset_after, Inject::Freeze)),
        _ => {}
    }
    if args.inject.len() > MAX_INJECTIONS {
        return Err(Error::Usage(format!(
            "--inject given {} times; at most {MAX_INJECTIONS}",
            args.inject.len()
        )));
    }
    for spec in &args.inject {
        let bad = || {
            Error::Usage(format!(
                "--inject {spec}: expected KIND@N with KIND silence, reset, freeze or garbage and N a packet count"
            ))
        };
        let (kind, n) = spec.split_once('@').ok_or_else(bad)?;
        let what = match kind {
            "silence" => Inject::Silence,
            "reset" => Inject::Reset,
            "freeze" => Inject::Freeze,
            "garbage" => Inject::Garbage,
            _ => return Err(bad()),
        };
        let n: u64 = n.parse().map_err(|_| bad())?;
        out.push((n, what));
    }
    out.sort_by_key(|&(n, _)| n);
    Ok(out)
}

struct Session<'a> {
    args: &'a SimArgs,
    unit: Unit,
    samples: Vec<RawSample>,
    next_sample: usize,
    last_sent_itow: Option<u32>,
    phase: Phase,
    started: bool,
    next_due: Instant,
    counter: u16,
    record: Vec<u8>,
    summary: Summary,
    dead: bool,
    /// A freeze in progress: (the packet count where it ends, the stamp repeated).
    freeze: Option<(u64, u32)>,
    /// The last capture stamp sent unchanged.
    last_itow: Option<u32>,
    /// `--fault double-rate`: the first stamp sent.
    first_itow: Option<u32>,
    /// Faults still to inject: (after this many capture packets, what), sorted.
    injections: Vec<(u64, Inject)>,
    /// `--timeout`: when the session ends, whether or not the host reads.
    deadline: Option<Instant>,
}

/// How long one write to the host may block before the deadline is checked again (the
/// connection's write time-out).
const WRITE_SLICE: Duration = Duration::from_millis(200);

/// Without `--timeout`: a host that reads nothing for this long is taken as gone.
const STALLED_HOST: Duration = Duration::from_secs(60);

/// Writes all of `bytes` to the host. Each write blocks at most [`WRITE_SLICE`] (the
/// connection's write time-out); a host that does not read ends the write with `TimedOut`
/// at `deadline` (or after [`STALLED_HOST`] without progress when there is none).
fn write_by(
    conn: &mut dyn Conn,
    mut bytes: &[u8],
    deadline: Option<Instant>,
) -> std::io::Result<()> {
    let mut progress = Instant::now();
    while !bytes.is_empty() {
        match conn.write(bytes) {
            Ok(0) => return Err(std::io::ErrorKind::WriteZero.into()),
            Ok(n) => {
                bytes = bytes.get(n..).unwrap_or_default();
                progress = Instant::now();
            }
            Err(e) if retryable(&e) => {
                let now = Instant::now();
                let over = match deadline {
                    Some(d) => now >= d,
                    None => now.duration_since(progress) >= STALLED_HOST,
                };
                if over {
                    return Err(std::io::ErrorKind::TimedOut.into());
                }
            }
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

impl Session<'_> {
    fn log(&self, msg: std::fmt::Arguments<'_>) {
        if self.args.verbose {
            eprintln!("nav440 sim: {msg}");
        }
    }

    fn period(&self) -> Option<(PacketType, Duration)> {
        let (t, r) = self.unit.ram().stream()?;
        Some((t, Duration::from_millis(10 * u64::from(r.divider()))))
    }

    fn send(&mut self, conn: &mut dyn Conn, bytes: &[u8]) -> std::io::Result<()> {
        if self.phase == Phase::Configured {
            self.record.extend_from_slice(bytes);
        }
        write_by(conn, bytes, self.deadline)
    }

    fn on_bytes(&mut self, conn: &mut dyn Conn, bytes: &[u8]) -> std::io::Result<()> {
        if !self.started {
            self.started = true;
            self.next_due = Instant::now();
        }
        let mut responses = Vec::new();
        self.unit.receive(bytes, |r| {
            responses.push((
                r.request,
                r.frames.to_vec(),
                r.get_packet,
                r.reset,
                r.output_changed,
            ))
        });
        for (request, frames, get_packet, reset, output_changed) in responses {
            self.summary.requests += 1;
            if self.dead {
                continue;
            }
            self.log(format_args!(
                "{request} -> {} bytes ({:?})",
                frames.len(),
                self.phase
            ));
            if matches!(self.phase, Phase::Resetting(_) | Phase::Silent(_)) {
                continue; // rebooting or silent: deaf
            }
            self.send(conn, &frames)?;
            if let Some(t) = get_packet {
                let s = self.current_sample();
                if let Some(f) = encode_sample(t, &s, self.counter) {
                    self.send(conn, &f)?;
                }
            }
            if reset {
                self.power_up("software reset (SR)");
            } else if output_changed && matches!(self.phase, Phase::PowerUp | Phase::Stalled) {
                self.phase = Phase::Commanded;
                self.log(format_args!("output commanded: silent until the read-back"));
            } else if request == PacketType::GF
                && self.phase == Phase::Commanded
                && !frames.is_empty()
            {
                self.phase = Phase::Configured;
                self.next_due = Instant::now();
                let ram = self.unit.ram();
                self.log(format_args!(
                    "configured after the read-back: type 0x{:04X} divider {} baud code {}",
                    ram.packet_type, ram.rate_divider, ram.baud
                ));
            }
        }
        Ok(())
    }

    fn current_sample(&self) -> RawSample {
        match self.phase {
            Phase::Configured => self
                .samples
                .get(self.next_sample.saturating_sub(1))
                .copied()
                .unwrap_or(RawSample::POWER_UP),
            _ => RawSample::POWER_UP,
        }
    }

    fn power_up(&mut self, why: &str) {
        self.unit.reset();
        self.phase = Phase::PowerUp;
        self.next_due = Instant::now();
        self.log(format_args!("power-up behaviour ({why})"));
    }

    /// The time stamp sent for the capture's `itow` (ms): during a freeze (the 50 packets
    /// after a `freeze` injection) the stamp of the last packet before it; with `--fault
    /// double-rate` stamps half a period apart from the first one; else `itow`.
    fn faulty_itow(&mut self, itow: u32, period_ms: u32) -> u32 {
        let k = self.summary.packets;
        if let Some((until, frozen)) = self.freeze {
            if k < until {
                return frozen;
            }
        }
        if self.args.fault == Some(Fault::DoubleRate) {
            let first = *self.first_itow.get_or_insert(itow);
            let step = u64::from(period_ms / 2);
            return first.wrapping_add(u32::try_from(k.saturating_mul(step)).unwrap_or(u32::MAX));
        }
        self.last_itow = Some(itow);
        itow
    }

    /// Injects `what` after the packet just sent.
    fn inject(&mut self, conn: &mut dyn Conn, what: Inject, now: Instant) -> std::io::Result<()> {
        let k = self.summary.packets;
        self.summary.injected += 1;
        self.log(format_args!("{} after {k} capture packets", what.name()));
        match what {
            Inject::Silence => {
                let until = (self.args.silence > 0.0)
                    .then(|| now + Duration::from_secs_f64(self.args.silence));
                self.phase = Phase::Silent(until);
            }
            Inject::Reset => {
                self.summary.resets += 1;
                self.phase = Phase::Resetting(now + Duration::from_millis(100));
            }
            Inject::Freeze => {
                if let Some(last) = self.last_itow {
                    self.freeze = Some((k + FREEZE_PACKETS, last));
                }
            }
            Inject::Garbage => {
                let burst = garbage_burst(k);
                self.send(conn, &burst)?;
            }
        }
        Ok(())
    }

    /// Sends what is due now; `Ok(false)` when the capture is done.
    fn stream(&mut self, conn: &mut dyn Conn) -> std::io::Result<bool> {
        let now = Instant::now();
        match self.phase {
            Phase::Resetting(until) => {
                if now >= until {
                    self.power_up("after the mid-stream reset");
                }
            }
            Phase::Silent(until) => {
                if until.is_some_and(|u| now >= u) {
                    self.phase = Phase::Stalled;
                    self.log(format_args!(
                        "silence over: answering, streaming again once configured"
                    ));
                }
            }
            Phase::Commanded | Phase::Stalled => {}
            Phase::PowerUp => {
                if !self.started || self.dead || now < self.next_due {
                    return Ok(true);
                }
                let Some((t, period)) = self.period() else {
                    return Ok(true);
                };
                self.next_due += period;
                self.counter = self.counter.wrapping_add(1);
                let mut s = RawSample::POWER_UP;
                s.itow = self.counter.into();
                if let Some(f) = encode_sample(t, &s, self.counter) {
                    self.send(conn, &f)?;
                    self.summary.power_up_packets += 1;
                }
            }
            Phase::Configured => {
                if !self.args.fast && now < self.next_due {
                    return Ok(true);
                }
                let Some((t, period)) = self.period() else {
                    return Ok(true);
                };
                let period_ms = period.as_millis() as u32;
                // Next capture sample at least one period (less 1 ms) after the last one sent.
                while let (Some(s), Some(last)) =
                    (self.samples.get(self.next_sample), self.last_sent_itow)
                {
                    if s.itow.wrapping_sub(last).saturating_add(1) >= period_ms {
                        break;
                    }
                    self.next_sample += 1;
                }
                let Some(mut s) = self.samples.get(self.next_sample).copied() else {
                    return Ok(false);
                };
                self.next_sample += 1;
                self.last_sent_itow = Some(s.itow);
                s.itow = self.faulty_itow(s.itow, period_ms);
                self.counter = self.counter.wrapping_add(1);
                self.next_due += match self.args.fault {
                    Some(Fault::DoubleRate) => period / 2,
                    _ => period,
                };
                if let Some(f) = encode_sample(t, &s, self.counter) {
                    self.send(conn, &f)?;
                    self.summary.packets += 1;
                }
                while let Some(&(at, what)) = self.injections.first() {
                    if at > self.summary.packets {
                        break;
                    }
                    self.injections.remove(0);
                    self.inject(conn, what, now)?;
                }
            }
        }
        Ok(true)
    }

    /// Time until something is due (or a long wait).
    fn wait_time(&self) -> Duration {
        let now = Instant::now();
        let due = match self.phase {
            Phase::Resetting(until) | Phase::Silent(Some(until)) => until,
            Phase::Commanded | Phase::Stalled | Phase::Silent(None) => {
                return Duration::from_millis(200)
            }
            Phase::PowerUp if !self.started || self.dead || self.period().is_none() => {
                return Duration::from_millis(200)
            }
            Phase::Configured if self.args.fast => return Duration::ZERO,
            Phase::Configured if self.period().is_none() => return Duration::from_millis(200),
            _ => self.next_due,
        };
        due.saturating_duration_since(now)
    }
}

/// Runs one session of `nav440 sim`: listens, serves one host until the capture was streamed
/// or the host went away, then writes the record.
pub fn run(args: &SimArgs) -> Result<Summary> {
    let listen = parse_listen(&args.listen, args.listen_any)?;
    let baud = parse_baud("--baud", args.baud)?;
    let packet = parse_output_type(&args.power_up_packet)?;
    let rate = parse_rate("--power-up-rate", args.power_up_rate)?;
    crate::limits::seconds("--timeout", args.timeout, true)?;
    crate::limits::seconds("--silence", args.silence, true)?;
    let eeprom = UnitFields {
        rate_divider: rate.divider(),
        baud: baud.code(),
        packet_type: packet.code(),
        orientation: 0,
    };
    if !eeprom.fits_budget() {
        return Err(Error::Usage(format!(
            "power-up {packet} at {} Hz does not fit {} Bd (the unit would not stream it)",
            args.power_up_rate, args.baud
        )));
    }
    // The output files: never the capture, never standard output (it carries the address),
    // created (as temporary files in their directories) before the unit serves, renamed at
    // the end of the session.
    let mut outputs: Vec<(&str, &std::path::Path)> = Vec::new();
    for (flag, p) in [
        ("--record", &args.record),
        ("--summary", &args.summary),
        ("--address-file", &args.address_file),
    ] {
        if let Some(p) = p {
            if crate::output::is_stdout(p) {
                return Err(Error::Usage(format!(
                    "{flag} -: standard output carries the address; name a file"
                )));
            }
            crate::output::check_not_input(flag, p, &[&args.capture])?;
            for &(other, q) in &outputs {
                crate::output::check_distinct((flag, p), (other, q))?;
            }
            outputs.push((flag, p.as_path()));
        }
    }
    let mut record_out = args.record.as_deref().map(OutputFile::create).transpose()?;
    let summary_out = args
        .summary
        .as_deref()
        .map(OutputFile::create)
        .transpose()?;
    let bytes = read_capture(
        &args.capture,
        "`nav440 sim` holds its capture in memory: serve a part of it (e.g. `head -c 500M CAPTURE > part.bin`)",
    )?;
    let samples = capture_samples(&bytes)
        .map_err(|e| Error::NotNav440(format!("{}: {e}", args.capture.display())))?;
    let quirks = Quirks {
        ignore_requests: matches!(args.fault, Some(Fault::NoAnswer | Fault::Dead)),
        nak_output_config: args.fault == Some(Fault::NakConfig),
        keep_rate: args.fault == Some(Fault::WrongReadback),
    };
    let deadline =
        (args.timeout > 0.0).then(|| Instant::now() + Duration::from_secs_f64(args.timeout));
    let mut session = Session {
        args,
        unit: Unit::new(eeprom, quirks),
        samples,
        next_sample: 0,
        last_sent_itow: None,
        phase: Phase::PowerUp,
        started: args.stream_at_connect,
        next_due: Instant::now(),
        counter: 0,
        record: Vec::new(),
        summary: Summary::default(),
        dead: args.fault == Some(Fault::Dead),
        freeze: None,
        last_itow: None,
        first_itow: None,
        injections: injections(args)?,
        deadline,
    };

    // Our handle on the pty's slave end: keeps the pty alive until the host has opened it,
    // and tells when the host has read everything (see `serve`). The host leaving is not
    // seen over a pty while it is open: end such sessions with --timeout.
    let mut _slave: Option<serialport::TTYPort> = None;
    let mut conn: Box<dyn Conn> = match listen {
        Listen::Tcp(addr) => {
            let l = TcpListener::bind(&addr)
                .map_err(|e| Error::Other(format!("cannot listen on tcp:{addr}: {e}")))?;
            let local = l
                .local_addr()
                .map_err(|e| Error::Other(format!("cannot listen on tcp:{addr}: {e}")))?;
            announce(args, &format!("tcp:{local}"))?;
            let (s, _) = accept(&l, deadline)?;
            let _ = s.set_nodelay(true);
            s.set_write_timeout(Some(WRITE_SLICE))
                .map_err(|e| Error::Other(format!("cannot accept a connection: {e}")))?;
            Box::new(s)
        }
        Listen::Pty => {
            let (mut master, slave) = serialport::TTYPort::pair()
                .map_err(|e| Error::Other(format!("cannot open a pseudo-terminal: {e}")))?;
            let path = serialport::SerialPort::name(&slave).unwrap_or_default();
            // The read and write time-out of the master: a write blocks at most this long
            // before the deadline is checked again (`write_by`).
            let _ = serialport::SerialPort::set_timeout(&mut master, WRITE_SLICE);
            announce(args, &path)?;
            _slave = Some(slave);
            Box::new(master)
        }
    };
    let (tx, rx) = mpsc::channel();
    let stop = Arc::new(AtomicBool::new(false));
    let reader = conn
        .reader()
        .map_err(|e| Error::Other(format!("cannot read from the host: {e}")))?;
    spawn_reader(reader, tx, stop.clone());
    let result = serve(&mut session, conn.as_mut(), &rx, deadline, &mut _slave);
    stop.store(true, Ordering::Relaxed);
    conn.close();
    drop(conn);
    if let (Some(p), Some(mut f)) = (&args.record, record_out.take()) {
        f.write_all(&session.record)
            .map_err(|e| Error::Output(format!("cannot write {}: {e}", p.display())))?;
        f.commit()?;
    }
    session.summary.recorded_bytes = session.record.len() as u64;
    if let (Some(p), Some(mut f)) = (&args.summary, summary_out) {
        let s = &session.summary;
        let json = serde_json::json!({
            "requests": s.requests,
            "power_up_packets": s.power_up_packets,
            "packets": s.packets,
            "recorded_bytes": s.recorded_bytes,
            "completed": s.completed,
            "resets": s.resets,
            "injected": s.injected,
            "error": result.as_ref().err().map(ToString::to_string),
        });
        writeln!(f, "{json}")
            .map_err(|e| Error::Output(format!("cannot write {}: {e}", p.display())))?;
        f.commit()?;
    }
    result?;
    Ok(session.summary)
}

/// Prints the address on standard output (a closed pipe is ignored: the host may have read
/// it) and writes `--address-file` through a temporary file of its own renamed over it, so a
/// reader never sees a partial line and no other file is touched.
fn announce(args: &SimArgs, what: &str) -> Result<()> {
    let mut out = std::io::stdout();
    match writeln!(out, "{what}").and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            return Err(Error::Output(format!("cannot write standard output: {e}")))
        }
        _ => {}
    }
    if let Some(p) = &args.address_file {
        crate::output::write_output(p, format!("{what}\n").as_bytes())?;
    }
    Ok(())
}

fn accept(l: &TcpListener, deadline: Option<Instant>) -> Result<(TcpStream, std::net::SocketAddr)> {
    let err = |e: std::io::Error| Error::Other(format!("cannot accept a connection: {e}"));
    let Some(deadline) = deadline else {
        return l.accept().map_err(err);
    };
    l.set_nonblocking(true).map_err(err)?;
    loop {
        match l.accept() {
            Ok((s, a)) => {
                s.set_nonblocking(false).map_err(err)?;
                return Ok((s, a));
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if Instant::now() >= deadline {
                    return Err(Error::Other("no host connected before --timeout".into()));
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(e) => return Err(err(e)),
        }
    }
}

fn serve(
    s: &mut Session<'_>,
    conn: &mut dyn Conn,
    rx: &Receiver<Msg>,
    deadline: Option<Instant>,
    slave: &mut Option<serialport::TTYPort>,
) -> Result<()> {
    let timeout = s.args.timeout;
    let late = || deadline.is_some_and(|d| Instant::now() >= d);
    let timed_out = || {
        Err(Error::Other(format!(
            "session not over after --timeout {timeout} s"
        )))
    };
    let io = |e: std::io::Error| -> Error {
        if matches!(
            e.kind(),
            std::io::ErrorKind::BrokenPipe | std::io::ErrorKind::ConnectionReset
        ) {
            Error::Other("the host closed the connection".into())
        } else {
            Error::Other(format!("connection to the host failed: {e}"))
        }
    };
    loop {
        if late() {
            return timed_out();
        }
        match rx.recv_timeout(s.wait_time()) {
            Ok(Msg::Bytes(b)) => match s.on_bytes(conn, &b) {
                Ok(()) => {}
                // A write the host did not take before the deadline.
                Err(_) if late() => return timed_out(),
                Err(e) => return peer_gone(s, io(e)),
            },
            Ok(Msg::Closed) | Err(RecvTimeoutError::Disconnected) => {
                s.log(format_args!("the host closed the connection"));
                return Ok(());
            }
            Err(RecvTimeoutError::Timeout) => {}
        }
        match s.stream(conn) {
            Ok(true) => {}
            Ok(false) => {
                s.summary.completed = true;
                if let Some(slave) = slave.as_ref() {
                    // Closing the master hangs the pty up, which discards what the host has
                    // not read yet: wait until it has read everything (at most 30 s).
                    // The kernel moves written bytes to the slave's queue asynchronously, so
                    // the queue must stay empty for 200 ms in a row.
                    let mut until = Instant::now() + Duration::from_secs(30);
                    if let Some(d) = deadline {
                        until = until.min(d);
                    }
                    let mut empty_since = None;
                    while Instant::now() < until {
                        let queued = serialport::SerialPort::bytes_to_read(slave).unwrap_or(0);
                        match (queued, empty_since) {
                            (0, None) => empty_since = Some(Instant::now()),
                            (0, Some(t)) if t.elapsed() >= Duration::from_millis(200) => break,
                            (0, Some(_)) => {}
                            _ => empty_since = None,
                        }
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    if late() {
                        return timed_out();
                    }
                }
                s.log(format_args!("capture streamed: closing"));
                return Ok(());
            }
            Err(_) if late() => return timed_out(),
            Err(e) => return peer_gone(s, io(e)),
        }
    }
}

/// A write failed because the host went away: a normal end of session.
fn peer_gone(s: &Session<'_>, e: Error) -> Result<()> {
    s.log(format_args!("{e}"));
    Ok(())
}
