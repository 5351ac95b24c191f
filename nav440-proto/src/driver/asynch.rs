//! The async driver: the same protocol logic as the blocking drivers ([`Engine`]), awaited
//! over an [`embedded_io_async`] serial port with time-outs from
//! [`embedded_hal_async::delay::DelayNs`].
//!
//! # On embassy-stm32
//!
//! The boot of the workspace's embassy-stm32 firmware (`firmware-embassy/src/main.rs`,
//! STM32F405, NAV440 on USART1 as a `BufferedUart`): `embassy_time::Delay` times the replies
//! out, and the baud switch maps `set_baudrate`'s `usart::ConfigError`, which is not the UART's
//! error type, into a `usart::Error`. A failed boot is retried every second. This block is the
//! code between the binary's `ANCHOR: boot` and `ANCHOR_END: boot` comments, line for line
//! (dedented); `cargo xtask embassy-stm32` checks that the two are equal and builds the binary.
//!
//! ```rust,ignore
//! let mut driver = AsyncDriver::new(uart);
//! let report = loop {
//!     // The local UART follows the unit; `ConfigError` is not the UART's error type.
//!     let set_baud = |u: &mut BufferedUart<'_>, b: Baud| {
//!         u.set_baudrate(b.bits_per_second()).map_err(|e| {
//!             defmt::error!("set_baudrate({=u32}): {}", b.bits_per_second(), e);
//!             usart::Error::Framing
//!         })
//!     };
//!     match boot::boot_async(
//!         &mut driver,
//!         &TARGET,
//!         &Options::DEFAULT,
//!         &mut Delay,
//!         set_baud,
//!     )
//!     .await
//!     {
//!         Ok(report) => break report,
//!         Err(e) => defmt::println!("firmware: boot failed: {}", e),
//!     }
//!     Timer::after_secs(1).await;
//! };
//! ```

use embedded_hal_async::delay::DelayNs;

use crate::packets::{DecodeError, Packet};
use crate::parser::Parser;
use crate::types::{Baud, FieldId, PacketRate, PacketType};
use crate::Stats;

use super::{Engine, Error, Link, Timing, MAX_GET_FIELDS, RX_CHUNK};

/// Async driver over an [`embedded_io_async::Read`] + [`embedded_io_async::Write`] +
/// [`embedded_io::ReadReady`] serial port (e.g. `embassy-stm32`'s `BufferedUart`), with reply
/// time-outs in time through an [`embedded_hal_async::delay::DelayNs`] (e.g. `embassy_time::Delay`).
///
/// The requests, the reply matching, the time-out rule and the counters are those of the
/// blocking [`super::Driver`] (one shared implementation; see the [module docs](super)):
/// while waiting for a reply the driver reads the bytes that are ready and otherwise awaits
/// [`Timing::poll_step_us`] on the delay, so other tasks run meanwhile. Configure a unit with
/// [`crate::boot::boot_async`].
pub struct AsyncDriver<S> {
    serial: S,
    engine: Engine,
    rx: [u8; RX_CHUNK],
}

/// [`Link`] of the async driver: the serial port and an async delay.
pub(crate) struct AsyncLink<'a, S, D> {
    pub(crate) serial: &'a mut S,
    pub(crate) delay: &'a mut D,
}

impl<S, D> Link for AsyncLink<'_, S, D>
where
    S: embedded_io_async::Read + embedded_io_async::Write + embedded_io::ReadReady,
    D: DelayNs,
{
    type Error = S::Error;
    type Serial = S;

    /// `read_ready`, then a one-byte `read` (which then completes at once).
    async fn read_byte_now(&mut self) -> Result<Option<u8>, S::Error> {
        if !self.serial.read_ready()? {
            return Ok(None);
        }
        let mut b = [0u8; 1];
        Ok(match self.serial.read(&mut b).await? {
            0 => None,
            _ => Some(b[0]),
        })
    }

    async fn write_all(&mut self, mut bytes: &[u8]) -> Result<(), Error<S::Error>> {
        while !bytes.is_empty() {
            match self.serial.write(bytes).await.map_err(Error::Serial)? {
                0 => return Err(Error::WriteZero),
                n => bytes = bytes.get(n..).unwrap_or(&[]),
            }
        }
        self.serial.flush().await.map_err(Error::Serial)
    }

    async fn delay_us(&mut self, us: u32) {
        self.delay.delay_us(us).await;
    }

    fn serial_mut(&mut self) -> &mut S {
        self.serial
    }
}

impl<S> AsyncDriver<S>
where
    S: embedded_io_async::Read + embedded_io_async::Write + embedded_io::ReadReady,
{
    /// Wraps a serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self {
            serial,
            engine: Engine::new(),
            rx: [0; RX_CHUNK],
        }
    }

    /// The serial port and the protocol state, for [`crate::boot::boot_async`].
    pub(crate) fn parts_mut(&mut self) -> (&mut S, &mut Engine) {
        (&mut self.serial, &mut self.engine)
    }

    fn link<'a, D: DelayNs>(serial: &'a mut S, delay: &'a mut D) -> AsyncLink<'a, S, D> {
        AsyncLink { serial, delay }
    }

    /// Sets the reply time-out and poll step (default [`Timing::DEFAULT`]).
    pub fn set_timing(&mut self, timing: Timing) {
        self.engine.timing = timing;
    }

    /// The reply time-out and poll step.
    pub fn timing(&self) -> Timing {
        self.engine.timing
    }

    /// Sets the line rate used to count received bytes as time in reply waits, bit/s
    /// (default 38400; [`crate::boot::boot_async`] keeps it equal to the local UART's rate).
    pub fn set_line_baud(&mut self, bits_per_second: u32) {
        self.engine.line_baud = bits_per_second.max(1);
    }

    /// The line rate used to count received bytes as time, bit/s.
    pub fn line_baud(&self) -> u32 {
        self.engine.line_baud
    }

    /// The wrapped serial port (e.g. to change its baud rate).
    pub fn serial_mut(&mut self) -> &mut S {
        &mut self.serial
    }

    /// Gives the serial port back (feed [`Self::pending_bytes`] first to continue the stream
    /// exactly).
    pub fn release(self) -> S {
        self.serial
    }

    /// Gives the serial port and the parser back.
    pub fn into_parts(self) -> (S, Parser) {
        (self.serial, self.engine.parser)
    }

    /// Bytes read from the port but not yet part of a frame, in stream order.
    pub fn pending_bytes(&self) -> &[u8] {
        self.engine.parser.pending_bytes()
    }

    /// The parser's counters.
    pub fn stats(&self) -> &Stats {
        self.engine.parser.stats()
    }

    /// Frames received while waiting for replies that were not the reply.
    pub fn unsolicited(&self) -> u32 {
        self.engine.unsolicited
    }

    /// Drops a partial frame held by the parser (counted as skipped).
    pub fn clear_parser(&mut self) {
        self.engine.parser.clear();
    }

    /// Awaits one `read` (at least one byte, or 0 = end of data) and passes every complete
    /// frame, decoded, to `on_packet`. Returns the number of bytes read. Bound it in time with
    /// your executor's time-out (e.g. `embassy_time::with_timeout`).
    pub async fn poll(
        &mut self,
        on_packet: impl FnMut(Result<Packet<'_>, DecodeError>),
    ) -> Result<usize, Error<S::Error>> {
        let n = self
            .serial
            .read(&mut self.rx)
            .await
            .map_err(Error::Serial)?;
        self.engine.feed(self.rx.get(..n).unwrap_or(&[]), on_packet);
        Ok(n)
    }

    /// Writes a whole pre-encoded frame and flushes.
    pub async fn send_raw(&mut self, frame: &[u8]) -> Result<(), Error<S::Error>> {
        let mut no_delay = NoDelay;
        let mut link = Self::link(&mut self.serial, &mut no_delay);
        link.write_all(frame).await
    }

    /// Sends a ping (PK) and awaits the PK reply ([`Error::NoReply`] after the time-out).
    pub async fn ping_wait(&mut self, delay: &mut impl DelayNs) -> Result<(), Error<S::Error>> {
        let mut link = Self::link(&mut self.serial, delay);
        self.engine.ping_wait(&mut link).await
    }

    /// SF: sets fields in RAM and awaits the confirmation.
    pub async fn set_fields(
        &mut self,
        fields: &[(FieldId, u16)],
        delay: &mut impl DelayNs,
    ) -> Result<(), Error<S::Error>> {
        let mut link = Self::link(&mut self.serial, delay);
        self.engine
            .configure(&mut link, PacketType::SF, fields)
            .await
    }

    /// WF: writes fields to EEPROM and awaits the confirmation.
    pub async fn write_fields(
        &mut self,
        fields: &[(FieldId, u16)],
        delay: &mut impl DelayNs,
    ) -> Result<(), Error<S::Error>> {
        let mut link = Self::link(&mut self.serial, delay);
        self.engine
            .configure(&mut link, PacketType::WF, fields)
            .await
    }

    /// Sets the continuous packet type and rate in one SF (fields 0x0003 and 0x0001).
    pub async fn set_packet_type_and_rate(
        &mut self,
        t: PacketType,
        rate: PacketRate,
        delay: &mut impl DelayNs,
    ) -> Result<(), Error<S::Error>> {
        let fields = [
            (FieldId::PACKET_TYPE, t.code()),
            (FieldId::PACKET_RATE_DIVIDER, rate.divider()),
        ];
        self.set_fields(&fields, delay).await
    }

    /// SF of the baud field; after the request has left, `switch` changes the local port to
    /// `baud` and the reply is awaited at the new rate.
    pub async fn set_baud(
        &mut self,
        baud: Baud,
        delay: &mut impl DelayNs,
        switch: impl FnOnce(&mut S, Baud) -> Result<(), S::Error>,
    ) -> Result<(), Error<S::Error>> {
        let mut link = Self::link(&mut self.serial, delay);
        self.engine.set_baud(&mut link, baud, switch).await
    }

    /// GF (RAM) or RF (EEPROM, `t = PacketType::RF`) of up to [`MAX_GET_FIELDS`] IDs: awaits
    /// the reply and returns the values in the order of `ids`.
    pub async fn get_fields(
        &mut self,
        t: PacketType,
        ids: &[FieldId],
        delay: &mut impl DelayNs,
    ) -> Result<[Option<u16>; MAX_GET_FIELDS], Error<S::Error>> {
        let mut link = Self::link(&mut self.serial, delay);
        self.engine.get_fields(&mut link, t, ids).await
    }
}

/// The delay of calls that never wait (`send_raw`).
struct NoDelay;

impl DelayNs for NoDelay {
    async fn delay_ns(&mut self, _ns: u32) {}
}
