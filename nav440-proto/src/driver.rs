//! Drivers over `embedded-io` (blocking) and `embedded-hal-nb` (non-blocking) serial ports.
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

fn decode_each(frame: Frame<'_>, on_packet: &mut impl FnMut(Result<Packet<'_>, DecodeError>)) {
    on_packet(Packet::decode(frame));
}

/// Blocking driver over an [`embedded_io::Read`] + [`embedded_io::Write`] serial port.
pub struct IoDriver<S> {
    serial: S,
    parser: Parser,
    rx: [u8; 64],
    reply_budget: usize,
}

impl<S: embedded_io::Read + embedded_io::Write> IoDriver<S> {
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self {
            serial,
            parser: Parser::new(),
            rx: [0; 64],
            reply_budget: DEFAULT_REPLY_BUDGET,
        }
    }

    /// Sets how many received bytes to wait for a reply (default [`DEFAULT_REPLY_BUDGET`]).
    pub fn set_reply_budget(&mut self, bytes: usize) {
        self.reply_budget = bytes;
    }

    /// Gives the serial port back.
    pub fn release(self) -> S {
        self.serial
    }

    /// The parser's counters.
    pub fn stats(&self) -> &Stats {
        self.parser.stats()
    }

    /// One blocking `read`; every complete frame in it is decoded and passed to `on_packet`
    /// (a known type with a wrong length as `Err`). Returns the number of bytes read
    /// (0 = the port reported end of data).
    pub fn poll(
        &mut self,
        mut on_packet: impl FnMut(Result<Packet<'_>, DecodeError>),
    ) -> Result<usize, Error<S::Error>> {
        let n = self.serial.read(&mut self.rx).map_err(Error::Serial)?;
        let bytes = self.rx.get(..n).unwrap_or(&[]);
        self.parser.feed(bytes, |f| decode_each(f, &mut on_packet));
        Ok(n)
    }

    /// Writes a whole pre-encoded frame and flushes.
    pub fn send_raw(&mut self, mut frame: &[u8]) -> Result<(), Error<S::Error>> {
        while !frame.is_empty() {
            match self.serial.write(frame).map_err(Error::Serial)? {
                0 => return Err(Error::WriteZero),
                n => frame = frame.get(n..).unwrap_or(&[]),
            }
        }
        self.serial.flush().map_err(Error::Serial)
    }

    /// Sends a ping (PK).
    pub fn ping(&mut self) -> Result<(), Error<S::Error>> {
        let mut f = [0u8; 8];
        let n = command::ping(&mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// Sends a GP request for one packet of type `t`; the packet comes through [`Self::poll`].
    pub fn request_packet(&mut self, t: PacketType) -> Result<(), Error<S::Error>> {
        let mut f = [0u8; 16];
        let n = command::get_packet(t, &mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// SF: sets fields in RAM and waits for the confirmation (see the module docs).
    pub fn set_fields(&mut self, fields: &[(FieldId, u16)]) -> Result<(), Error<S::Error>> {
        self.configure(PacketType::SF, fields)
    }

    /// WF: writes fields to EEPROM and waits for the confirmation.
    pub fn write_fields(&mut self, fields: &[(FieldId, u16)]) -> Result<(), Error<S::Error>> {
        self.configure(PacketType::WF, fields)
    }

    /// Sets the continuous packet type and rate in one SF (fields 0x0003 and 0x0001).
    pub fn set_packet_type_and_rate(
        &mut self,
        t: PacketType,
        rate: PacketRate,
    ) -> Result<(), Error<S::Error>> {
        self.set_fields(&[
            (FieldId::PACKET_TYPE, t.code()),
            (FieldId::PACKET_RATE_DIVIDER, rate.divider()),
        ])
    }

    fn configure(
        &mut self,
        t: PacketType,
        fields: &[(FieldId, u16)],
    ) -> Result<(), Error<S::Error>> {
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
            let n = self.serial.read(&mut self.rx).map_err(Error::Serial)?;
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

/// Non-blocking driver over [`embedded_hal_nb::serial::Read`] + `Write` (one byte at a time).
pub struct NbDriver<S> {
    serial: S,
    parser: Parser,
    reply_budget: usize,
    idle_polls: u32,
}

impl<S, E> NbDriver<S>
where
    S: embedded_hal_nb::serial::Read<u8, Error = E> + embedded_hal_nb::serial::Write<u8, Error = E>,
{
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self {
            serial,
            parser: Parser::new(),
            reply_budget: DEFAULT_REPLY_BUDGET,
            idle_polls: DEFAULT_IDLE_POLLS,
        }
    }

    /// Sets how many received bytes to wait for a reply (default [`DEFAULT_REPLY_BUDGET`]).
    pub fn set_reply_budget(&mut self, bytes: usize) {
        self.reply_budget = bytes;
    }

    /// Sets how many consecutive `WouldBlock` reads end a wait for a reply
    /// (default [`DEFAULT_IDLE_POLLS`]).
    pub fn set_idle_polls(&mut self, polls: u32) {
        self.idle_polls = polls;
    }

    /// Gives the serial port back.
    pub fn release(self) -> S {
        self.serial
    }

    /// The parser's counters.
    pub fn stats(&self) -> &Stats {
        self.parser.stats()
    }

    /// Reads every byte available now (until `WouldBlock`), passing each decoded packet to
    /// `on_packet`. Returns the number of bytes read; never blocks.
    pub fn poll(
        &mut self,
        mut on_packet: impl FnMut(Result<Packet<'_>, DecodeError>),
    ) -> Result<usize, Error<E>> {
        let mut rx = [0u8; 32];
        let mut total = 0;
        loop {
            let mut n = 0;
            let mut more = true;
            while let Some(slot) = rx.get_mut(n) {
                match self.serial.read() {
                    Ok(b) => {
                        *slot = b;
                        n += 1;
                    }
                    Err(nb::Error::WouldBlock) => {
                        more = false;
                        break;
                    }
                    Err(nb::Error::Other(e)) => return Err(Error::Serial(e)),
                }
            }
            total += n;
            self.parser.feed(rx.get(..n).unwrap_or(&[]), |f| {
                decode_each(f, &mut on_packet)
            });
            if !more {
                return Ok(total);
            }
        }
    }

    /// Writes a whole pre-encoded frame and flushes (spinning on `WouldBlock`).
    pub fn send_raw(&mut self, frame: &[u8]) -> Result<(), Error<E>> {
        for &b in frame {
            nb::block!(self.serial.write(b)).map_err(Error::Serial)?;
        }
        nb::block!(self.serial.flush()).map_err(Error::Serial)
    }

    /// Sends a ping (PK).
    pub fn ping(&mut self) -> Result<(), Error<E>> {
        let mut f = [0u8; 8];
        let n = command::ping(&mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// Sends a GP request for one packet of type `t`; the packet comes through [`Self::poll`].
    pub fn request_packet(&mut self, t: PacketType) -> Result<(), Error<E>> {
        let mut f = [0u8; 16];
        let n = command::get_packet(t, &mut f)?;
        self.send_raw(f.get(..n).unwrap_or(&[]))
    }

    /// SF: sets fields in RAM and waits for the confirmation (see the module docs).
    pub fn set_fields(&mut self, fields: &[(FieldId, u16)]) -> Result<(), Error<E>> {
        self.configure(PacketType::SF, fields)
    }

    /// WF: writes fields to EEPROM and waits for the confirmation.
    pub fn write_fields(&mut self, fields: &[(FieldId, u16)]) -> Result<(), Error<E>> {
        self.configure(PacketType::WF, fields)
    }

    /// Sets the continuous packet type and rate in one SF (fields 0x0003 and 0x0001).
    pub fn set_packet_type_and_rate(
        &mut self,
        t: PacketType,
        rate: PacketRate,
    ) -> Result<(), Error<E>> {
        self.set_fields(&[
            (FieldId::PACKET_TYPE, t.code()),
            (FieldId::PACKET_RATE_DIVIDER, rate.divider()),
        ])
    }

    fn configure(&mut self, t: PacketType, fields: &[(FieldId, u16)]) -> Result<(), Error<E>> {
        let mut f = [0u8; MAX_FRAME];
        let n = if t == PacketType::WF {
            command::write_fields(fields, &mut f)?
        } else {
            command::set_fields(fields, &mut f)?
        };
        self.send_raw(f.get(..n).unwrap_or(&[]))?;
        let mut wait = ReplyWait::new(t, fields);
        let mut budget = self.reply_budget;
        let mut idle = 0u32;
        loop {
            match self.serial.read() {
                Ok(b) => {
                    idle = 0;
                    self.parser.feed(&[b], |f| wait.on_frame(f));
                    if let Some(r) = wait.outcome() {
                        return r;
                    }
                    budget = budget.saturating_sub(1);
                    if budget == 0 {
                        return Err(wait.give_up());
                    }
                }
                Err(nb::Error::WouldBlock) => {
                    idle += 1;
                    if idle >= self.idle_polls {
                        return Err(wait.give_up());
                    }
                }
                Err(nb::Error::Other(e)) => return Err(Error::Serial(e)),
            }
        }
    }
}
