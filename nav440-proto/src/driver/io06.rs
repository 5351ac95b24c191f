//! `embedded-io` 0.6 serial ports (feature `embedded-io-06`).
//!
//! Some HALs implement `embedded-io` 0.6 (e.g. `stm32f4xx-hal` 0.23), while this crate's
//! drivers take 0.7 ports (which `embassy-stm32` 0.6 and `rp2040-hal` 0.12 implement).
//! [`Compat06`] shows a 0.6 port through the 0.7 traits, so the same drivers run over it:
//! `IoDriver::new(Compat06(uart))` (blocking, also named [`Io06Driver`]) or
//! `AsyncDriver::new(Compat06(uart))`.

use embedded_io_06 as eio;

/// The blocking driver over an `embedded-io` 0.6 [`eio::Read`] + [`eio::ReadReady`] +
/// [`eio::Write`] port: `Io06Driver::new(Compat06(uart))`.
pub type Io06Driver<S> = super::IoDriver<Compat06<S>>;

/// An `embedded-io` 0.6 serial port seen through the 0.7 traits, blocking and async: wrap a
/// HAL's 0.6 UART (e.g. `stm32f4xx-hal` 0.23's serial port) to use it with
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
