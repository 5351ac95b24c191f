//! Drivers over `embedded-io` (blocking) and `embedded-hal-nb` (non-blocking) serial ports.
//!
//! Both are the one [`Driver`] over a thin [`Port`] adapter ([`IoPort`], [`NbPort`]), so the
//! protocol logic below exists once; only reading and writing bytes differ.
//!
//! Both yield decoded packets through a callback and can configure the unit with SF/WF:
//! the request is sent, then incoming frames are read until the unit answers:
//! * a NAK naming the request -> [`Error::Nak`] (also when it comes after a partial reply);
//! * a reply listing every requested ID -> `Ok(())`;
//! * a reply missing some IDs -> the driver keeps reading for the NAK that the unit sends
//!   with it and returns [`Error::Nak`]; if the byte budget runs out or the line goes quiet
//!   first, [`Error::NotAccepted`].
//!
//! Frames that arrive while waiting (continuous output) are dropped; they are still counted
//! in the parser's [`Stats`]. The wait is bounded by a byte budget
//! ([`DEFAULT_REPLY_BUDGET`] bytes), not by time: the crate has no clock.

use crate::encode::{command, EncodeError};
use crate::packets::{DecodeError, FieldIds, Packet};
use crate::parser::{Frame, Parser};
use crate::types::{FieldId, PacketRate, PacketType};
use crate::{Stats, MAX_FRAME};

/// Default number of received bytes to wait for a command's reply (about 0.7 s at 57600 baud).
pub const DEFAULT_REPLY_BUDGET: usize = 4096;

/// Default number of consecutive `WouldBlock` polls the nb driver waits for a reply byte.
pub const DEFAULT_IDLE_POLLS: u32 = 1_000_000;

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
    /// No reply within the byte budget, or the port reported end of data / stayed idle.
    NoReply,
}

impl<E> From<EncodeError> for Error<E> {
    fn from(e: EncodeError) -> Self {
        Error::Encode(e)
    }
}

/// Waits for the reply (and possible NAK) to one SF/WF request.
struct ReplyWait<'f> {
    request: PacketType,
    fields: &'f [(FieldId, u16)],
    nak: bool,
    accepted: Option<u8>,
}

impl<'f> ReplyWait<'f> {
    fn new(request: PacketType, fields: &'f [(FieldId, u16)]) -> Self {
        Self {
            request,
            fields,
            nak: false,
            accepted: None,
        }
    }

    fn on_frame(&mut self, frame: Frame<'_>) {
        match Packet::decode(frame) {
            Ok(Packet::Nak(n)) if n.failed_type() == self.request => self.nak = true,
            Ok(Packet::SetFields(ids) | Packet::WriteFields(ids))
                if frame.packet_type == self.request =>
            {
                self.accepted = Some(self.count_accepted(ids));
            }
            _ => {}
        }
    }

    fn count_accepted(&self, ids: FieldIds<'_>) -> u8 {
        self.fields
            .iter()
            .filter(|(id, _)| ids.contains(*id))
            .count() as u8
    }

    fn requested(&self) -> u8 {
        self.fields.len() as u8
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

    /// The outcome when no more bytes will be waited for.
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

mod sealed {
    /// Keeps [`super::Port`] implemented by this module's adapters only.
    pub trait Sealed {}
}

/// A serial port as the driver sees it: byte reads and whole-frame writes.
///
/// Sealed: implemented by [`IoPort`] and [`NbPort`] only. It is public because it bounds
/// [`Driver`]; callers use [`IoDriver`] and [`NbDriver`] and need not name it.
pub trait Port: sealed::Sealed {
    /// The serial port's error.
    type Error;
    /// The wrapped serial port.
    type Serial;

    /// Reads bytes for [`Driver::poll`] into `buf`; returns how many (`0` = none) and whether
    /// more may be ready at once (`poll` then reads again).
    fn read_for_poll(&mut self, buf: &mut [u8]) -> Result<(usize, bool), Self::Error>;

    /// Reads reply bytes into `buf`; returns how many, `0` meaning stop waiting
    /// (end of data, or the port stayed idle).
    fn read_for_reply(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;

    /// Writes every byte of `bytes`, then flushes.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Error<Self::Error>>;

    /// Gives the serial port back.
    fn into_serial(self) -> Self::Serial;
}

/// [`Port`] adapter for an [`embedded_io::Read`] + [`embedded_io::Write`] serial port
/// (blocking, chunked reads).
pub struct IoPort<S> {
    serial: S,
}

impl<S> sealed::Sealed for IoPort<S> {}

impl<S: embedded_io::Read + embedded_io::Write> Port for IoPort<S> {
    type Error = S::Error;
    type Serial = S;

    /// One blocking `read`; never asks for more.
    fn read_for_poll(&mut self, buf: &mut [u8]) -> Result<(usize, bool), S::Error> {
        Ok((self.serial.read(buf)?, false))
    }

    /// One blocking `read`; `0` when the port reports end of data.
    fn read_for_reply(&mut self, buf: &mut [u8]) -> Result<usize, S::Error> {
        self.serial.read(buf)
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

    fn into_serial(self) -> S {
        self.serial
    }
}

/// [`Port`] adapter for an [`embedded_hal_nb::serial::Read`] + `Write` serial port
/// (one byte at a time).
pub struct NbPort<S> {
    serial: S,
    idle_polls: u32,
}

impl<S> sealed::Sealed for NbPort<S> {}

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

    /// Reads one byte, giving up (`0`) after `idle_polls` consecutive `WouldBlock`s; one byte
    /// at a time so that bytes after the reply stay in the port for [`Driver::poll`].
    fn read_for_reply(&mut self, buf: &mut [u8]) -> Result<usize, S::Error> {
        let Some(slot) = buf.first_mut() else {
            return Ok(0);
        };
        let mut idle = 0u32;
        loop {
            match self.serial.read() {
                Ok(b) => {
                    *slot = b;
                    return Ok(1);
                }
                Err(nb::Error::WouldBlock) => {
                    idle = idle.saturating_add(1);
                    if idle >= self.idle_polls {
                        return Ok(0);
                    }
                }
                Err(nb::Error::Other(e)) => return Err(e),
            }
        }
    }

    /// Spins on `WouldBlock` for every byte and for the flush.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Error<S::Error>> {
        for &b in bytes {
            nb::block!(self.serial.write(b)).map_err(Error::Serial)?;
        }
        nb::block!(self.serial.flush()).map_err(Error::Serial)
    }

    fn into_serial(self) -> S {
        self.serial
    }
}

/// The driver over a [`Port`]: parser, receive buffer, reply budget and every command.
/// Use it as [`IoDriver`] or [`NbDriver`].
pub struct Driver<P> {
    port: P,
    parser: Parser,
    rx: [u8; RX_CHUNK],
    reply_budget: usize,
}

/// Receive buffer size, bytes (largest chunk fed to the parser at once).
const RX_CHUNK: usize = 64;

/// Blocking driver over an [`embedded_io::Read`] + [`embedded_io::Write`] serial port.
pub type IoDriver<S> = Driver<IoPort<S>>;

/// Non-blocking driver over [`embedded_hal_nb::serial::Read`] + `Write` (one byte at a time).
pub type NbDriver<S> = Driver<NbPort<S>>;

impl<P> Driver<P> {
    fn with_port(port: P) -> Self {
        Self {
            port,
            parser: Parser::new(),
            rx: [0; RX_CHUNK],
            reply_budget: DEFAULT_REPLY_BUDGET,
        }
    }
}

impl<S: embedded_io::Read + embedded_io::Write> Driver<IoPort<S>> {
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self::with_port(IoPort { serial })
    }
}

impl<S> Driver<NbPort<S>>
where
    S: embedded_hal_nb::serial::Read<u8> + embedded_hal_nb::serial::Write<u8>,
{
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self::with_port(NbPort {
            serial,
            idle_polls: DEFAULT_IDLE_POLLS,
        })
    }

    /// Sets how many consecutive `WouldBlock` reads end a wait for a reply
    /// (default [`DEFAULT_IDLE_POLLS`]).
    pub fn set_idle_polls(&mut self, polls: u32) {
        self.port.idle_polls = polls;
    }
}

impl<P: Port> Driver<P> {
    /// Sets how many received bytes to wait for a reply (default [`DEFAULT_REPLY_BUDGET`]).
    pub fn set_reply_budget(&mut self, bytes: usize) {
        self.reply_budget = bytes;
    }

    /// Gives the serial port back.
    pub fn release(self) -> P::Serial {
        self.port.into_serial()
    }

    /// The parser's counters.
    pub fn stats(&self) -> &Stats {
        self.parser.stats()
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
            self.parser.feed(bytes, |f| on_packet(Packet::decode(f)));
            if !more {
                return Ok(total);
            }
        }
    }

    /// Writes a whole pre-encoded frame and flushes ([`NbDriver`]: spinning on `WouldBlock`).
    pub fn send_raw(&mut self, frame: &[u8]) -> Result<(), Error<P::Error>> {
        self.port.write_all(frame)
    }

    /// Sends a ping (PK).
    pub fn ping(&mut self) -> Result<(), Error<P::Error>> {
        let mut f = [0u8; 8];
        let n = command::ping(&mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// Sends a GP request for one packet of type `t`; the packet comes through [`Self::poll`].
    pub fn request_packet(&mut self, t: PacketType) -> Result<(), Error<P::Error>> {
        let mut f = [0u8; 16];
        let n = command::get_packet(t, &mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// SF: sets fields in RAM and waits for the confirmation (see the module docs).
    pub fn set_fields(&mut self, fields: &[(FieldId, u16)]) -> Result<(), Error<P::Error>> {
        self.configure(PacketType::SF, fields)
    }

    /// WF: writes fields to EEPROM and waits for the confirmation.
    pub fn write_fields(&mut self, fields: &[(FieldId, u16)]) -> Result<(), Error<P::Error>> {
        self.configure(PacketType::WF, fields)
    }

    /// Sets the continuous packet type and rate in one SF (fields 0x0003 and 0x0001).
    pub fn set_packet_type_and_rate(
        &mut self,
        t: PacketType,
        rate: PacketRate,
    ) -> Result<(), Error<P::Error>> {
        self.set_fields(&[
            (FieldId::PACKET_TYPE, t.code()),
            (FieldId::PACKET_RATE_DIVIDER, rate.divider()),
        ])
    }

    fn configure(
        &mut self,
        t: PacketType,
        fields: &[(FieldId, u16)],
    ) -> Result<(), Error<P::Error>> {
        let mut f = [0u8; MAX_FRAME];
        let n = if t == PacketType::WF {
            command::write_fields(fields, &mut f)?
        } else {
            command::set_fields(fields, &mut f)?
        };
        self.send_raw(f.get(..n).unwrap_or(&[]))?;
        let mut wait = ReplyWait::new(t, fields);
        let mut budget = self.reply_budget;
        loop {
            let n = self
                .port
                .read_for_reply(&mut self.rx)
                .map_err(Error::Serial)?;
            if n == 0 {
                return Err(wait.give_up());
            }
            let bytes = self.rx.get(..n).unwrap_or(&[]);
            self.parser.feed(bytes, |f| wait.on_frame(f));
            if let Some(r) = wait.outcome() {
                return r;
            }
            budget = budget.saturating_sub(n);
            if budget == 0 {
                return Err(wait.give_up());
            }
        }
    }
}
