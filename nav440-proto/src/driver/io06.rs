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

/// An `embedded-io` 0.6 serial port seen through the 0.7 traits, blocking and async: wrap a
/// HAL's 0.6 UART (e.g. `embassy-stm32`'s `BufferedUart`) to use it with
/// [`IoDriver`](super::IoDriver) or [`AsyncDriver`](super::AsyncDriver)
/// (`AsyncDriver::new(Compat06(uart))`). Each 0.7 trait is implemented when the port
/// implements its 0.6 counterpart (`embedded_io` 0.6 `Read`, `ReadReady`, `Write`;
/// `embedded_io_async` 0.6 `Read`, `Write`); errors come wrapped in [`Compat06Error`].
pub struct Compat06<S>(pub S);

/// An `embedded-io` 0.6 error as a 0.7 one (same [`embedded_io::ErrorKind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Compat06Error<E>(pub E);

impl<E: core::fmt::Debug> core::fmt::Display for Compat06Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "serial port error: {:?}", self.0)
    }
}

impl<E: core::fmt::Debug> core::error::Error for Compat06Error<E> {}

impl<E: eio::Error> embedded_io::Error for Compat06Error<E> {
    fn kind(&self) -> embedded_io::ErrorKind {
        use eio::ErrorKind as K6;
        use embedded_io::ErrorKind as K;
        match self.0.kind() {
            K6::NotFound => K::NotFound,
            K6::PermissionDenied => K::PermissionDenied,
            K6::ConnectionRefused => K::ConnectionRefused,
            K6::ConnectionReset => K::ConnectionReset,
            K6::ConnectionAborted => K::ConnectionAborted,
            K6::NotConnected => K::NotConnected,
            K6::AddrInUse => K::AddrInUse,
            K6::AddrNotAvailable => K::AddrNotAvailable,
            K6::BrokenPipe => K::BrokenPipe,
            K6::AlreadyExists => K::AlreadyExists,
            K6::InvalidInput => K::InvalidInput,
            K6::InvalidData => K::InvalidData,
            K6::TimedOut => K::TimedOut,
            K6::Interrupted => K::Interrupted,
            K6::Unsupported => K::Unsupported,
            K6::OutOfMemory => K::OutOfMemory,
            K6::WriteZero => K::WriteZero,
            _ => K::Other,
        }
    }
}

impl<S: eio::ErrorType> embedded_io::ErrorType for Compat06<S> {
    type Error = Compat06Error<S::Error>;
}

impl<S: eio::Read> embedded_io::Read for Compat06<S> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        self.0.read(buf).map_err(Compat06Error)
    }
}

impl<S: eio::ReadReady> embedded_io::ReadReady for Compat06<S> {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        self.0.read_ready().map_err(Compat06Error)
    }
}

impl<S: eio::Write> embedded_io::Write for Compat06<S> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.write(buf).map_err(Compat06Error)
    }

    fn flush(&mut self) -> Result<(), Self::Error> {
        self.0.flush().map_err(Compat06Error)
    }
}

impl<S: embedded_io_async_06::Read> embedded_io_async::Read for Compat06<S> {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        self.0.read(buf).await.map_err(Compat06Error)
    }
}

impl<S: embedded_io_async_06::Write> embedded_io_async::Write for Compat06<S> {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.write(buf).await.map_err(Compat06Error)
    }

    async fn flush(&mut self) -> Result<(), Self::Error> {
        self.0.flush().await.map_err(Compat06Error)
    }
}
