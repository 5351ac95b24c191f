//! [`Port`] adapter for `embedded-io` 0.6 serial ports (feature `embedded-io-06`).
//!
//! HALs such as `embassy-stm32` and `stm32f4xx-hal` implement `embedded-io` 0.6, while this
//! crate's [`IoDriver`](super::IoDriver) takes 0.7 ports. [`Io06Driver`] is the same driver
//! over a 0.6 port: `Read + ReadReady + Write` from `embedded_io` 0.6, used exactly as
//! [`IoPort`](super::IoPort) uses the 0.7 traits.

use embedded_io_06 as eio;

use super::{Driver, Error, Port};

/// [`Port`] adapter for an `embedded-io` 0.6 [`eio::Read`] + [`eio::ReadReady`] +
/// [`eio::Write`] serial port (blocking, chunked reads for [`Driver::poll`]; `read_ready`
/// keeps the reply waits from blocking).
pub struct Io06Port<S> {
    serial: S,
}

/// Blocking driver over an `embedded-io` 0.6 [`eio::Read`] + [`eio::ReadReady`] +
/// [`eio::Write`] serial port (feature `embedded-io-06`).
pub type Io06Driver<S> = Driver<Io06Port<S>>;

impl<S: eio::Read + eio::ReadReady + eio::Write> Port for Io06Port<S> {
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

impl<S: eio::Read + eio::ReadReady + eio::Write> Driver<Io06Port<S>> {
    /// Wraps an `embedded-io` 0.6 serial port (already at the unit's baud rate).
    pub fn new(serial: S) -> Self {
        Self::from_port(Io06Port { serial })
    }
}
