//! `nav440 sim`: a simulated NAV440 on TCP or a pseudo-terminal ([`crate::sim`]).

use std::path::PathBuf;

use clap::ValueEnum;

use crate::error::Result;

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
pub struct Args {
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

/// `nav440 sim`: [`sim::run`](crate::sim::run), then one summary line on stderr.
pub fn run(args: &Args) -> Result<()> {
    let s = crate::sim::run(args)?;
    eprintln!(
        "nav440 sim: {} requests, {} power-up packets, {} capture packets ({} bytes recorded){}{}",
        s.requests,
        s.power_up_packets,
        s.packets,
        s.recorded_bytes,
        if s.resets > 0 {
            ", reset mid-stream"
        } else {
            ""
        },
        if s.completed {
            ", capture done: closed"
        } else {
            ", host closed the connection"
        }
    );
    Ok(())
}
