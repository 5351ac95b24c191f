//! Drivers over `embedded-io` (blocking) and `embedded-hal-nb` (non-blocking) serial ports.
//!
//! Both are the one [`Driver`] over a thin [`Port`] adapter ([`IoPort`], [`NbPort`]; with the
//! `embedded-io-06` feature, an `embedded-io` 0.6 port goes through [`IoPort`] wrapped in
//! `Compat06`), so the protocol logic below exists once; only reading and writing bytes differ. Any other serial port can
//! implement [`Port`] itself (see "Bring your own port" there) and use
//! [`Driver::from_port`].
//!
//! Both yield decoded packets through a callback ([`Driver::poll`]) and run the unit's commands
//! that have a reply (PK, SF, WF, GF): the request is sent, then incoming frames are read until
//! the unit answers or the reply time-out expires:
//! * a NAK naming the request -> [`Error::Nak`] (also when it comes after a partial reply);
//! * a SF/WF reply listing every requested ID -> `Ok(())`;
//! * a SF/WF reply missing some IDs -> the driver keeps reading for the NAK that the unit sends
//!   with it and returns [`Error::Nak`]; if the time-out expires first, [`Error::NotAccepted`];
//! * nothing -> [`Error::NoReply`].
//!
//! # Time-outs
//! Waits are measured in time, through an [`embedded_hal::delay::DelayNs`] the caller passes
//! in: the driver reads every byte available now, then sleeps [`Timing::poll_step_us`] and
//! tries again, until [`Timing::reply_timeout_ms`]. The time counted is the sum of the sleeps
//! plus the line time of the bytes received (10 bits per byte at [`Driver::line_baud`]), so a
//! unit that streams without pause cannot keep a wait alive forever, even where a port
//! delivers bytes faster than a real line would (emulators).
//!
//! A `DelayNs` that rounds a sleep up to a coarse tick lengthens every wait by as much: with a
//! 1 kHz monotonic (e.g. rtic-monotonics' SysTick at its default rate, whose delays last one to
//! two ticks) each 500 us step lasts 1-2 ms, and a boot against a silent unit took 2.5 times
//! its nominal time when measured. With such a delay set [`Timing::poll_step_us`] to ten
//! ticks or more (e.g. 10,000 us): the UART's receive buffer holds the bytes meanwhile.
//!
//! # Nothing is read past a reply
//! While waiting, the driver reads one byte at a time and stops parsing right after the reply
//! frame ([`Parser::feed_until`]): bytes after it stay in the serial port, or, in the one case
//! where a corrupted candidate had already buffered them, in the parser
//! ([`Driver::pending_bytes`]). A caller that takes the port back continues the stream exactly
//! at the byte after the reply by first feeding [`Driver::pending_bytes`] (empty in practice).
//!
//! Frames that arrive while waiting (continuous output) are not yielded; they are counted in
//! [`Driver::unsolicited`] and in the parser's [`Stats`].

use core::ops::ControlFlow;

use embedded_hal::delay::DelayNs;

use crate::encode::{command, EncodeError};
use crate::packets::{DecodeError, FieldIds, Packet};
use crate::parser::{Frame, Parser};
use crate::types::{Baud, FieldId, PacketRate, PacketType};
use crate::{Stats, MAX_FRAME};

/// Default reply time-out, ms (a reply of a few bytes plus one interleaved output frame of up
/// to 49 bytes takes about 70 ms at 9600 Bd).
pub const DEFAULT_REPLY_TIMEOUT_MS: u32 = 200;

/// Default sleep between two polls of the port while waiting for a reply, µs.
pub const DEFAULT_POLL_STEP_US: u32 = 500;

/// Most fields one [`Driver::get_fields`] request reads back.
pub const MAX_GET_FIELDS: usize = 8;

/// How long the driver waits for a reply and how it polls meanwhile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Timing {
    /// Time-out of one request's reply, ms.
    pub reply_timeout_ms: u32,
    /// Sleep between two polls of the port when no byte is available, µs (at least 1).
    pub poll_step_us: u32,
}

impl Timing {
    /// [`DEFAULT_REPLY_TIMEOUT_MS`], [`DEFAULT_POLL_STEP_US`].
    pub const DEFAULT: Self = Self {
        reply_timeout_ms: DEFAULT_REPLY_TIMEOUT_MS,
        poll_step_us: DEFAULT_POLL_STEP_US,
    };
}

impl Default for Timing {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Driver errors; `E` is the serial port's error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The serial port failed.
    Serial(E),
    /// The serial port accepted no byte (`write` returned 0).
    WriteZero,
    /// The request could not be encoded (too many fields).
    Encode(EncodeError),
    /// The unit answered the request with a NAK.
    Nak {
        /// The request type named in the NAK.
        request: PacketType,
    },
    /// The reply did not list every requested field ID (and no NAK arrived).
    NotAccepted {
        /// IDs requested.
        requested: u8,
        /// IDs among them that the reply listed.
        accepted: u8,
    },
    /// No reply within the reply time-out ([`Timing::reply_timeout_ms`]).
    NoReply,
}

impl<E> From<EncodeError> for Error<E> {
    fn from(e: EncodeError) -> Self {
        Error::Encode(e)
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Serial(e) => write!(f, "serial port error: {e:?}"),
            Error::WriteZero => f.write_str("serial port error: it accepted no byte"),
            Error::Encode(e) => write!(f, "request could not be encoded: {e}"),
            Error::Nak { request } => write!(f, "unit rejected (NAK) {request}"),
            Error::NotAccepted {
                requested,
                accepted,
            } => write!(
                f,
                "unit accepted only {accepted} of the {requested} fields requested"
            ),
            Error::NoReply => f.write_str("no reply within the reply time-out"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Error::Encode(e) => Some(e),
            _ => None,
        }
    }
}

/// What a wait is looking for.
enum Want<'f> {
    /// PK reply.
    Ping,
    /// SF/WF reply with these fields (and a possible NAK).
    Fields(&'f [(FieldId, u16)]),
    /// GF/RF reply to these IDs.
    Values(&'f [FieldId]),
}

/// The state of one wait for a reply (and possible NAK).
struct ReplyWait<'f> {
    request: PacketType,
    want: Want<'f>,
    nak: bool,
    /// SF/WF: IDs accepted so far; PK/GF: 1 once the reply arrived.
    accepted: Option<u8>,
    /// GF/RF: the values read, in the order of the requested IDs.
    values: [Option<u16>; MAX_GET_FIELDS],
    /// Frames that were neither the reply nor its NAK.
    unsolicited: u32,
}

impl<'f> ReplyWait<'f> {
    fn new(request: PacketType, want: Want<'f>) -> Self {
        Self {
            request,
            want,
            nak: false,
            accepted: None,
            values: [None; MAX_GET_FIELDS],
            unsolicited: 0,
        }
    }

    /// Takes one frame; `Break` once the outcome is known.
    fn on_frame(&mut self, frame: Frame<'_>) -> ControlFlow<()> {
        let mine = frame.packet_type == self.request;
        // Only the replies are decoded: every other frame is unsolicited whatever it holds.
        match (Packet::decode_reply(frame), &self.want) {
            (Ok(Packet::Nak(n)), _) if n.failed_type() == self.request => self.nak = true,
            (Ok(Packet::Ping), Want::Ping) => self.accepted = Some(1),
            (Ok(Packet::SetFields(ids) | Packet::WriteFields(ids)), Want::Fields(f)) if mine => {
                self.accepted = Some(count_accepted(f, ids));
            }
            (Ok(Packet::GetFields(v) | Packet::ReadFields(v)), Want::Values(ids)) if mine => {
                for (slot, id) in self.values.iter_mut().zip(ids.iter()) {
                    *slot = v.get(*id);
                }
                self.accepted = Some(1);
            }
            _ => self.unsolicited = self.unsolicited.saturating_add(1),
        }
        if self.outcome::<()>().is_some() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    fn requested(&self) -> u8 {
        match self.want {
            Want::Fields(f) => f.len() as u8,
            Want::Ping | Want::Values(_) => 1,
        }
    }

    /// `Some` once the outcome is known.
    fn outcome<E>(&self) -> Option<Result<(), Error<E>>> {
        if self.nak {
            return Some(Err(Error::Nak {
                request: self.request,
            }));
        }
        match self.accepted {
            Some(a) if a == self.requested() => Some(Ok(())),
            _ => None, // no reply yet, or partial: wait for the NAK
        }
    }

    /// The outcome when the time-out expired.
    fn give_up<E>(&self) -> Error<E> {
        match self.accepted {
            Some(accepted) => Error::NotAccepted {
                requested: self.requested(),
                accepted,
            },
            None => Error::NoReply,
        }
    }
}

fn count_accepted(fields: &[(FieldId, u16)], ids: FieldIds<'_>) -> u8 {
    fields.iter().filter(|(id, _)| ids.contains(*id)).count() as u8
}

/// A serial port as the driver sees it: byte reads and whole-frame writes.
///
/// Implemented here for [`embedded_io`] 0.7 ports ([`IoPort`]; with the `embedded-io-06`
/// feature also `embedded-io` 0.6 ports wrapped in `Compat06`) and [`embedded_hal_nb`] ports
/// ([`NbPort`]).
///
/// # Bring your own port
/// Any other serial port works too: implement this trait for a wrapper around it and build
/// the driver with [`Driver::from_port`]. The rules the driver relies on:
/// * [`Port::read_byte_now`] never blocks: `Ok(None)` when no byte is available now (the
///   driver then sleeps [`Timing::poll_step_us`] through its `DelayNs` and asks again, so
///   reply time-outs stay in time);
/// * [`Port::read_for_poll`] may block until at least one byte arrives (blocking drivers) or
///   return `(0, false)` (non-blocking ones); `true` asks [`Driver::poll`] to read again at once;
/// * [`Port::write_all`] returns once every byte has left the port (flushed), because a baud
///   change ([`Driver::set_baud`]) follows the request's last byte.
///
/// ```
/// use nav440_proto::driver::{Driver, Error, Port};
///
/// /// A port with nothing connected: every read finds no byte, writes vanish.
/// struct Unplugged {
///     baud: u32,
/// }
///
/// impl Port for Unplugged {
///     type Error = core::convert::Infallible;
///     /// What `serial_mut` exposes (e.g. to change the baud rate): here the baud itself.
///     type Serial = u32;
///     fn read_for_poll(&mut self, _buf: &mut [u8]) -> Result<(usize, bool), Self::Error> {
///         Ok((0, false))
///     }
///     fn read_byte_now(&mut self) -> Result<Option<u8>, Self::Error> {
///         Ok(None)
///     }
///     fn write_all(&mut self, _bytes: &[u8]) -> Result<(), Error<Self::Error>> {
///         Ok(())
///     }
///     fn serial_mut(&mut self) -> &mut u32 {
///         &mut self.baud
///     }
///     fn into_serial(self) -> u32 {
///         self.baud
///     }
/// }
///
/// /// Counts the time asked for instead of sleeping.
/// struct Clock(u64);
/// impl embedded_hal::delay::DelayNs for Clock {
///     fn delay_ns(&mut self, ns: u32) {
///         self.0 += u64::from(ns);
///     }
/// }
///
/// let mut driver = Driver::from_port(Unplugged { baud: 38400 });
/// let mut clock = Clock(0);
/// assert_eq!(driver.ping_wait(&mut clock), Err(Error::NoReply));
/// // The default reply time-out, 200 ms, measured in time.
/// assert_eq!(clock.0, 200_000_000);
/// ```
pub trait Port {
    /// The serial port's error.
    type Error;
    /// The wrapped serial port.
    type Serial;

    /// Reads bytes for [`Driver::poll`] into `buf`; returns how many (`0` = none) and whether
    /// more may be ready at once (`poll` then reads again).
    fn read_for_poll(&mut self, buf: &mut [u8]) -> Result<(usize, bool), Self::Error>;

    /// Reads one byte if one is available now; never blocks.
    fn read_byte_now(&mut self) -> Result<Option<u8>, Self::Error>;

    /// Writes every byte of `bytes`, then flushes (the last byte has left the port).
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Error<Self::Error>>;

    /// The wrapped serial port (e.g. to change its baud rate).
    fn serial_mut(&mut self) -> &mut Self::Serial;

    /// Gives the serial port back.
    fn into_serial(self) -> Self::Serial;
}

/// [`Port`] adapter for an [`embedded_io::Read`] + [`embedded_io::ReadReady`] +
/// [`embedded_io::Write`] serial port (blocking, chunked reads for [`Driver::poll`];
/// `read_ready` keeps the reply waits from blocking).
pub struct IoPort<S> {
    serial: S,
}

impl<S: embedded_io::Read + embedded_io::ReadReady + embedded_io::Write> Port for IoPort<S> {
    type Error = S::Error;
    type Serial = S;

    /// One blocking `read`; never asks for more.
    fn read_for_poll(&mut self, buf: &mut [u8]) -> Result<(usize, bool), S::Error> {
        Ok((self.serial.read(buf)?, false))
    }

    /// `read_ready`, then a one-byte `read`.
    fn read_byte_now(&mut self) -> Result<Option<u8>, S::Error> {
        if !self.serial.read_ready()? {
            return Ok(None);
        }
        let mut b = [0u8; 1];
        Ok(match self.serial.read(&mut b)? {
            0 => None,
            _ => Some(b[0]),
        })
    }

    fn write_all(&mut self, mut bytes: &[u8]) -> Result<(), Error<S::Error>> {
        while !bytes.is_empty() {
            match self.serial.write(bytes).map_err(Error::Serial)? {
                0 => return Err(Error::WriteZero),
                n => bytes = bytes.get(n..).unwrap_or(&[]),
            }
        }
        self.serial.flush().map_err(Error::Serial)
    }

    fn serial_mut(&mut self) -> &mut S {
        &mut self.serial
    }

    fn into_serial(self) -> S {
        self.serial
    }
}

/// [`Port`] adapter for an [`embedded_hal_nb::serial::Read`] + `Write` serial port
/// (one byte at a time).
pub struct NbPort<S> {
    serial: S,
}

impl<S> Port for NbPort<S>
where
    S: embedded_hal_nb::serial::Read<u8> + embedded_hal_nb::serial::Write<u8>,
{
    type Error = S::Error;
    type Serial = S;

    /// Reads until `WouldBlock` or `buf` is full (then more may be ready); never blocks.
    fn read_for_poll(&mut self, buf: &mut [u8]) -> Result<(usize, bool), S::Error> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.serial.read() {
                Ok(b) => {
                    *slot = b;
                    n += 1;
                }
                Err(nb::Error::WouldBlock) => return Ok((n, false)),
                Err(nb::Error::Other(e)) => return Err(e),
            }
        }
        Ok((n, true))
    }

    fn read_byte_now(&mut self) -> Result<Option<u8>, S::Error> {
        match self.serial.read() {
            Ok(b) => Ok(Some(b)),
            Err(nb::Error::WouldBlock) => Ok(None),
            Err(nb::Error::Other(e)) => Err(e),
        }
    }

    /// Spins on `WouldBlock` for every byte and for the flush.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Error<S::Error>> {
        for &b in bytes {
            nb::block!(self.serial.write(b)).map_err(Error::Serial)?;
        }
        nb::block!(self.serial.flush()).map_err(Error::Serial)
    }

    fn serial_mut(&mut self) -> &mut S {
        &mut self.serial
    }

    fn into_serial(self) -> S {
        self.serial
    }
}

/// The driver over a [`Port`]: parser, receive buffer, timing and every command.
/// Use it as [`IoDriver`] or [`NbDriver`], or over your own [`Port`] ([`Driver::from_port`]).
pub struct Driver<P> {
    port: P,
    engine: Engine,
    rx: [u8; RX_CHUNK],
}

/// Receive buffer size, bytes (largest chunk fed to the parser at once).
const RX_CHUNK: usize = 64;

/// Blocking driver over an [`embedded_io::Read`] + [`embedded_io::ReadReady`] +
/// [`embedded_io::Write`] serial port.
pub type IoDriver<S> = Driver<IoPort<S>>;

/// Non-blocking driver over [`embedded_hal_nb::serial::Read`] + `Write` (one byte at a time).
pub type NbDriver<S> = Driver<NbPort<S>>;

#[cfg(feature = "embedded-io-06")]
mod io06;
#[cfg(feature = "embedded-io-06")]
pub use io06::{Compat06, Compat06Error, Io06Driver};

mod asynch;
pub use asynch::AsyncDriver;
pub(crate) use asynch::AsyncLink;

/// The I/O of one driver call that waits: the port and the delay. The protocol logic
/// ([`Engine`]) is written once as `async` code over this trait; the blocking drivers run it
/// through [`BlockingLink`] (whose operations never suspend) with [`block_on`], the async
/// driver awaits it with [`AsyncLink`].
pub(crate) trait Link {
    /// The serial port's error.
    type Error;
    /// The wrapped serial port.
    type Serial;
    /// One byte if one is available now; never waits for one.
    async fn read_byte_now(&mut self) -> Result<Option<u8>, Self::Error>;
    /// Every byte of `bytes`, then a flush.
    async fn write_all(&mut self, bytes: &[u8]) -> Result<(), Error<Self::Error>>;
    /// Sleeps `us` microseconds.
    async fn delay_us(&mut self, us: u32);
    /// The serial port (e.g. to change its baud rate).
    fn serial_mut(&mut self) -> &mut Self::Serial;
}

/// [`Link`] of the blocking drivers: a [`Port`] and an [`embedded_hal::delay::DelayNs`].
pub(crate) struct BlockingLink<'a, P, D> {
    pub(crate) port: &'a mut P,
    pub(crate) delay: &'a mut D,
}

impl<P: Port, D: DelayNs> Link for BlockingLink<'_, P, D> {
    type Error = P::Error;
    type Serial = P::Serial;

    async fn read_byte_now(&mut self) -> Result<Option<u8>, P::Error> {
        self.port.read_byte_now()
    }

    async fn write_all(&mut self, bytes: &[u8]) -> Result<(), Error<P::Error>> {
        self.port.write_all(bytes)
    }

    async fn delay_us(&mut self, us: u32) {
        self.delay.delay_us(us);
    }

    fn serial_mut(&mut self) -> &mut P::Serial {
        self.port.serial_mut()
    }
}

/// Runs a future whose every step completes at once (the [`Engine`] over a
/// [`BlockingLink`]) to its end on the calling thread: `embassy_futures::block_on` (a no-op
/// waker; a blocking link never suspends, so the first poll is the last).
pub(crate) use embassy_futures::block_on;

/// The protocol state and logic every driver shares (blocking, non-blocking and async):
/// requests, reply matching ([`ReplyWait`]), time-outs, the parser and its counters. Its
/// I/O goes through a [`Link`].
pub(crate) struct Engine {
    pub(crate) parser: Parser,
    pub(crate) timing: Timing,
    pub(crate) line_baud: u32,
    pub(crate) unsolicited: u32,
}

impl Engine {
    pub(crate) const fn new() -> Self {
        Self {
            parser: Parser::new(),
            timing: Timing::DEFAULT,
            line_baud: Baud::B38400.bits_per_second(),
            unsolicited: 0,
        }
    }

    /// PK, then its reply.
    pub(crate) async fn ping_wait<L: Link>(&mut self, link: &mut L) -> Result<(), Error<L::Error>> {
        let mut f = [0u8; 8];
        let n = command::ping(&mut f)?;
        link.write_all(f.get(..n).unwrap_or(&[])).await?;
        let mut wait = ReplyWait::new(PacketType::PK, Want::Ping);
        self.wait(link, &mut wait).await
    }

    /// SF (RAM) or WF (EEPROM, `t = PacketType::WF`) of `fields`, then the confirmation.
    pub(crate) async fn configure<L: Link>(
        &mut self,
        link: &mut L,
        t: PacketType,
        fields: &[(FieldId, u16)],
    ) -> Result<(), Error<L::Error>> {
        let mut f = [0u8; MAX_FRAME];
        let n = if t == PacketType::WF {
            command::write_fields(fields, &mut f)?
        } else {
            command::set_fields(fields, &mut f)?
        };
        link.write_all(f.get(..n).unwrap_or(&[])).await?;
        let mut wait = ReplyWait::new(t, Want::Fields(fields));
        self.wait(link, &mut wait).await
    }

    /// SF of the baud field; after the request has left, `switch` changes the local port and
    /// the reply is awaited at the new rate (see [`Driver::set_baud`]).
    pub(crate) async fn set_baud<L: Link>(
        &mut self,
        link: &mut L,
        baud: Baud,
        switch: impl FnOnce(&mut L::Serial, Baud) -> Result<(), L::Error>,
    ) -> Result<(), Error<L::Error>> {
        let fields = [(FieldId::BAUD_RATE, baud.code())];
        let mut f = [0u8; 16];
        let n = command::set_fields(&fields, &mut f)?;
        link.write_all(f.get(..n).unwrap_or(&[])).await?;
        switch(link.serial_mut(), baud).map_err(Error::Serial)?;
        self.parser.clear();
        self.line_baud = baud.bits_per_second();
        let mut wait = ReplyWait::new(PacketType::SF, Want::Fields(&fields));
        self.wait(link, &mut wait).await
    }

    /// GF or RF (`t = PacketType::RF`) of up to [`MAX_GET_FIELDS`] IDs, then the values.
    pub(crate) async fn get_fields<L: Link>(
        &mut self,
        link: &mut L,
        t: PacketType,
        ids: &[FieldId],
    ) -> Result<[Option<u16>; MAX_GET_FIELDS], Error<L::Error>> {
        let ids = ids.get(..ids.len().min(MAX_GET_FIELDS)).unwrap_or(&[]);
        let mut f = [0u8; 32];
        let (n, request) = if t == PacketType::RF {
            (command::read_fields(ids, &mut f)?, PacketType::RF)
        } else {
            (command::get_fields(ids, &mut f)?, PacketType::GF)
        };
        link.write_all(f.get(..n).unwrap_or(&[])).await?;
        let mut wait = ReplyWait::new(request, Want::Values(ids));
        self.wait(link, &mut wait).await?;
        Ok(wait.values)
    }

    /// Feeds bytes read by `poll` and passes every frame, decoded, to `on_packet`.
    pub(crate) fn feed(
        &mut self,
        bytes: &[u8],
        mut on_packet: impl FnMut(Result<Packet<'_>, DecodeError>),
    ) {
        self.parser.feed(bytes, |f| on_packet(Packet::decode(f)));
    }

    /// Reads byte by byte until `wait` knows the outcome or the time-out expires.
    async fn wait<L: Link>(
        &mut self,
        link: &mut L,
        wait: &mut ReplyWait<'_>,
    ) -> Result<(), Error<L::Error>> {
        let limit_us = u64::from(self.timing.reply_timeout_ms) * 1000;
        let step_us = self.timing.poll_step_us.max(1);
        let byte_us = 10_000_000 / u64::from(self.line_baud.max(1));
        let mut elapsed_us = 0u64;
        let result = loop {
            match link.read_byte_now().await {
                Err(e) => break Err(Error::Serial(e)),
                Ok(Some(b)) => {
                    // Frames still buffered behind a corrupted candidate are scanned before
                    // this byte (they were sent before the request: counted as unsolicited).
                    self.parser.feed_until(&[b], |f| wait.on_frame(f));
                    if let Some(r) = wait.outcome() {
                        break r;
                    }
                    elapsed_us += byte_us;
                }
                Ok(None) => {
                    link.delay_us(step_us).await;
                    elapsed_us += u64::from(step_us);
                }
            }
            if elapsed_us >= limit_us {
                break Err(wait.give_up());
            }
        };
        self.unsolicited = self.unsolicited.saturating_add(wait.unsolicited);
        result
    }
}

impl<P> Driver<P> {
    /// A driver over any [`Port`] (see "Bring your own port" there); the port must already
    /// be at the unit's baud rate. [`IoDriver::new`] and [`NbDriver::new`] wrap
    /// `embedded-io` and `embedded-hal-nb` ports.
    pub fn from_port(port: P) -> Self {
        Self {
            port,
            engine: Engine::new(),
            rx: [0; RX_CHUNK],
        }
    }

    /// The port and the protocol state, for [`crate::boot`].
    pub(crate) fn parts_mut(&mut self) -> (&mut P, &mut Engine) {
        (&mut self.port, &mut self.engine)
    }
}

impl<S: embedded_io::Read + embedded_io::ReadReady + embedded_io::Write> Driver<IoPort<S>> {
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self::from_port(IoPort { serial })
    }
}

impl<S> Driver<NbPort<S>>
where
    S: embedded_hal_nb::serial::Read<u8> + embedded_hal_nb::serial::Write<u8>,
{
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self::from_port(NbPort { serial })
    }
}

impl<P: Port> Driver<P> {
    /// Sets the reply time-out and poll step (default [`Timing::DEFAULT`]).
    pub fn set_timing(&mut self, timing: Timing) {
        self.engine.timing = timing;
    }

    /// The reply time-out and poll step.
    pub fn timing(&self) -> Timing {
        self.engine.timing
    }

    /// Sets the line rate used to count received bytes as time in reply waits, bit/s
    /// (default 38400; [`crate::boot::boot`] keeps it equal to the local UART's rate).
    pub fn set_line_baud(&mut self, bits_per_second: u32) {
        self.engine.line_baud = bits_per_second.max(1);
    }

    /// The line rate used to count received bytes as time, bit/s.
    pub fn line_baud(&self) -> u32 {
        self.engine.line_baud
    }

    /// The wrapped serial port (e.g. to change its baud rate).
    pub fn serial_mut(&mut self) -> &mut P::Serial {
        self.port.serial_mut()
    }

    /// Gives the serial port back. Feed [`Self::pending_bytes`] first (copy them before) to
    /// continue the stream exactly; see the module docs.
    pub fn release(self) -> P::Serial {
        self.port.into_serial()
    }

    /// Gives the serial port and the parser back (the parser holds
    /// [`Self::pending_bytes`] and the counters).
    pub fn into_parts(self) -> (P::Serial, Parser) {
        (self.port.into_serial(), self.engine.parser)
    }

    /// Bytes read from the port but not yet part of a frame, in stream order (empty right
    /// after a reply unless a corrupted candidate spanned the reply; see the module docs).
    pub fn pending_bytes(&self) -> &[u8] {
        self.engine.parser.pending_bytes()
    }

    /// The parser's counters.
    pub fn stats(&self) -> &Stats {
        self.engine.parser.stats()
    }

    /// Frames received while waiting for replies that were not the reply (continuous output,
    /// other replies), since the driver was made.
    pub fn unsolicited(&self) -> u32 {
        self.engine.unsolicited
    }

    /// Drops a partial frame held by the parser (counted as skipped), e.g. after the local
    /// baud rate changed.
    pub fn clear_parser(&mut self) {
        self.engine.parser.clear();
    }

    /// Reads from the port and passes every complete frame, decoded, to `on_packet` (a known
    /// type with a wrong length as `Err`). Returns the number of bytes read.
    ///
    /// [`IoDriver`]: one blocking `read` (0 bytes = the port reported end of data).
    /// [`NbDriver`]: every byte available now (until `WouldBlock`); never blocks.
    pub fn poll(
        &mut self,
        mut on_packet: impl FnMut(Result<Packet<'_>, DecodeError>),
    ) -> Result<usize, Error<P::Error>> {
        let mut total = 0usize;
        loop {
            let (n, more) = self
                .port
                .read_for_poll(&mut self.rx)
                .map_err(Error::Serial)?;
            total = total.saturating_add(n);
            let bytes = self.rx.get(..n).unwrap_or(&[]);
            self.engine.feed(bytes, &mut on_packet);
            if !more {
                return Ok(total);
            }
        }
    }

    /// Reads every byte that arrives within `timeout_us` microseconds, sleeping
    /// [`Timing::poll_step_us`] through `delay` while none is available, and passes every
    /// complete frame, decoded, to `on_packet`; never waits longer than the time-out (the
    /// line time of the bytes received counts, as in reply waits). Returns the number of
    /// bytes read (0: nothing arrived in time).
    pub fn poll_timeout(
        &mut self,
        timeout_us: u32,
        delay: &mut impl DelayNs,
        mut on_packet: impl FnMut(Result<Packet<'_>, DecodeError>),
    ) -> Result<usize, Error<P::Error>> {
        let step_us = self.engine.timing.poll_step_us.max(1);
        let byte_us = 10_000_000 / u64::from(self.engine.line_baud.max(1));
        let (mut elapsed_us, mut total, mut n) = (0u64, 0usize, 0usize);
        while elapsed_us < u64::from(timeout_us) {
            match self.port.read_byte_now().map_err(Error::Serial)? {
                Some(b) => {
                    if let Some(slot) = self.rx.get_mut(n) {
                        *slot = b;
                        n += 1;
                    }
                    total = total.saturating_add(1);
                    elapsed_us += byte_us;
                    if n < RX_CHUNK {
                        continue;
                    }
                }
                None => {
                    delay.delay_us(step_us);
                    elapsed_us += u64::from(step_us);
                }
            }
            self.engine
                .feed(self.rx.get(..n).unwrap_or(&[]), &mut on_packet);
            n = 0;
        }
        self.engine
            .feed(self.rx.get(..n).unwrap_or(&[]), &mut on_packet);
        Ok(total)
    }

    /// Writes a whole pre-encoded frame and flushes ([`NbDriver`]: spinning on `WouldBlock`).
    pub fn send_raw(&mut self, frame: &[u8]) -> Result<(), Error<P::Error>> {
        self.port.write_all(frame)
    }

    /// Sends a ping (PK) without waiting (the reply comes through [`Self::poll`]).
    pub fn ping(&mut self) -> Result<(), Error<P::Error>> {
        let mut f = [0u8; 8];
        let n = command::ping(&mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// The blocking link of one call.
    fn link<'a, D: DelayNs>(port: &'a mut P, delay: &'a mut D) -> BlockingLink<'a, P, D> {
        BlockingLink { port, delay }
    }

    /// Sends a ping (PK) and waits for the PK reply ([`Error::NoReply`] after the time-out).
    pub fn ping_wait(&mut self, delay: &mut impl DelayNs) -> Result<(), Error<P::Error>> {
        block_on(
            self.engine
                .ping_wait(&mut Self::link(&mut self.port, delay)),
        )
    }

    /// Sends a GP request for one packet of type `t`; the packet comes through [`Self::poll`].
    pub fn request_packet(&mut self, t: PacketType) -> Result<(), Error<P::Error>> {
        let mut f = [0u8; 16];
        let n = command::get_packet(t, &mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// SF: sets fields in RAM and waits for the confirmation (see the module docs).
    pub fn set_fields(
        &mut self,
        fields: &[(FieldId, u16)],
        delay: &mut impl DelayNs,
    ) -> Result<(), Error<P::Error>> {
        let mut link = Self::link(&mut self.port, delay);
        block_on(self.engine.configure(&mut link, PacketType::SF, fields))
    }

    /// WF: writes fields to EEPROM and waits for the confirmation.
    pub fn write_fields(
        &mut self,
        fields: &[(FieldId, u16)],
        delay: &mut impl DelayNs,
    ) -> Result<(), Error<P::Error>> {
        let mut link = Self::link(&mut self.port, delay);
        block_on(self.engine.configure(&mut link, PacketType::WF, fields))
    }

    /// Sets the continuous packet type and rate in one SF (fields 0x0003 and 0x0001).
    pub fn set_packet_type_and_rate(
        &mut self,
        t: PacketType,
        rate: PacketRate,
        delay: &mut impl DelayNs,
    ) -> Result<(), Error<P::Error>> {
        self.set_fields(
            &[
                (FieldId::PACKET_TYPE, t.code()),
                (FieldId::PACKET_RATE_DIVIDER, rate.divider()),
            ],
            delay,
        )
    }

    /// SF of the baud field (0x0002), which the unit applies at once: after the request has
    /// left the port, `switch` changes the local port to `baud` (the reply comes at the new
    /// rate), the parser drops any partial frame, and the reply is awaited at the new rate.
    pub fn set_baud(
        &mut self,
        baud: Baud,
        delay: &mut impl DelayNs,
        switch: impl FnOnce(&mut P::Serial, Baud) -> Result<(), P::Error>,
    ) -> Result<(), Error<P::Error>> {
        let mut link = Self::link(&mut self.port, delay);
        block_on(self.engine.set_baud(&mut link, baud, switch))
    }

    /// GF (RAM) or RF (EEPROM, `t = PacketType::RF`) of up to [`MAX_GET_FIELDS`] IDs: waits
    /// for the reply and returns the values in the order of `ids` (`None`: not in the reply).
    pub fn get_fields(
        &mut self,
        t: PacketType,
        ids: &[FieldId],
        delay: &mut impl DelayNs,
    ) -> Result<[Option<u16>; MAX_GET_FIELDS], Error<P::Error>> {
        let mut link = Self::link(&mut self.port, delay);
        block_on(self.engine.get_fields(&mut link, t, ids))
    }
}
