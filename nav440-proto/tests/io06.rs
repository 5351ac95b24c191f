//! The drivers over an `embedded-io` 0.6 port wrapped in `Compat06` (feature
//! `embedded-io-06`): the boot sequence configures the unit model exactly as over a 0.7
//! port. Run by CI with `cargo test -p nav440-proto --features embedded-io-06 --test io06`.
#![cfg(feature = "embedded-io-06")]

use std::collections::VecDeque;

use embedded_io_06 as eio;
use nav440_proto::boot::{self, Options, Target};
use nav440_proto::driver::{Compat06, Io06Driver, Timing};
use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::{Baud, PacketRate, PacketType};

/// The protocol document's ping frame.
const PING: [u8; 7] = [0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4];

/// A 0.6 port wired to the unit model (baud rates ignored, as under emulation).
struct Line {
    unit: Unit,
    to_host: VecDeque<u8>,
    written: Vec<u8>,
    baud: Baud,
}

#[derive(Debug, PartialEq)]
struct LineError;

impl eio::Error for LineError {
    fn kind(&self) -> eio::ErrorKind {
        eio::ErrorKind::Other
    }
}

impl eio::ErrorType for Line {
    type Error = LineError;
}

impl eio::Read for Line {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LineError> {
        Ok(std::io::Read::read(&mut self.to_host, buf).expect("a VecDeque reads without error"))
    }
}

impl eio::ReadReady for Line {
    fn read_ready(&mut self) -> Result<bool, LineError> {
        Ok(!self.to_host.is_empty())
    }
}

impl eio::Write for Line {
    fn write(&mut self, buf: &[u8]) -> Result<usize, LineError> {
        self.written.extend_from_slice(buf);
        let to_host = &mut self.to_host;
        self.unit.receive(buf, |r| to_host.extend(r.frames));
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), LineError> {
        Ok(())
    }
}

/// Adds up the time asked for (no real sleep).
struct Clock(u64);

impl embedded_hal::delay::DelayNs for Clock {
    fn delay_ns(&mut self, ns: u32) {
        self.0 += u64::from(ns);
    }
}

fn line(quirks: Quirks) -> Line {
    Line {
        unit: Unit::new(UnitFields::POWER_UP, quirks),
        to_host: VecDeque::new(),
        written: Vec::new(),
        baud: Baud::B38400,
    }
}

#[test]
fn boot_over_an_embedded_io_06_port() {
    let mut driver = Io06Driver::new(Compat06(line(Quirks::default())));
    let mut clock = Clock(0);
    let report = boot::boot(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut clock,
        |l, b| {
            l.0.baud = b;
            Ok(())
        },
    )
    .expect("boot");
    assert_eq!(report.unit_baud, Baud::B38400);
    assert_eq!(report.baud, Baud::B57600);
    let l = driver.release().0;
    assert_eq!(
        l.written.get(..7),
        Some(&PING[..]),
        "the sequence starts with a ping"
    );
    assert_eq!(
        l.unit.ram().stream(),
        Some((PacketType::A2, PacketRate::Hz100))
    );
    assert_eq!(l.unit.ram().baud(), Baud::B57600);
    assert_eq!(l.baud, Baud::B57600, "the local port followed");
    assert_eq!(clock.0, 0, "every reply was there at once: no sleep");
}

#[test]
fn silent_unit_times_out_in_time() {
    let mut driver = Io06Driver::new(Compat06(line(Quirks {
        ignore_requests: true,
        ..Quirks::default()
    })));
    driver.set_timing(Timing {
        reply_timeout_ms: 50,
        poll_step_us: 1000,
    });
    let mut clock = Clock(0);
    let err = driver.ping_wait(&mut clock).unwrap_err();
    assert_eq!(err, nav440_proto::driver::Error::NoReply);
    assert_eq!(clock.0, 50_000_000, "50 ms slept in 1 ms steps");
}

impl embedded_io_async_06::Read for Line {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, LineError> {
        eio::Read::read(self, buf)
    }
}

impl embedded_io_async_06::Write for Line {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, LineError> {
        eio::Write::write(self, buf)
    }
}

/// Polls `f` to its end (the line and the delay below never suspend).
fn run<F: std::future::Future>(f: F) -> F::Output {
    let mut f = std::pin::pin!(f);
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    loop {
        if let std::task::Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return v;
        }
    }
}

impl embedded_hal_async::delay::DelayNs for Clock {
    async fn delay_ns(&mut self, ns: u32) {
        self.0 += u64::from(ns);
    }
}

#[test]
fn compat06_port_under_the_async_and_the_blocking_driver() {
    use nav440_proto::driver::{AsyncDriver, IoDriver};
    let set_baud = |l: &mut Compat06<Line>, b: Baud| {
        l.0.baud = b;
        Ok(())
    };
    let mut driver = AsyncDriver::new(Compat06(line(Quirks::default())));
    let mut clock = Clock(0);
    let r = run(boot::boot_async(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut clock,
        set_baud,
    ));
    assert_eq!(r.expect("boot_async").baud, Baud::B57600);
    let async_line = driver.release().0;
    assert_eq!(
        async_line.unit.ram().stream(),
        Some((PacketType::A2, PacketRate::Hz100))
    );

    let mut driver = IoDriver::new(Compat06(line(Quirks::default())));
    let r = boot::boot(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut clock,
        set_baud,
    );
    assert_eq!(r.expect("boot").baud, Baud::B57600);
    assert_eq!(driver.release().0.written, async_line.written);
}

#[test]
fn compat06_errors_keep_their_kind() {
    use embedded_io::Error as _;
    use nav440_proto::driver::Compat06Error;
    let e = Compat06Error(LineError);
    assert_eq!(e.kind(), embedded_io::ErrorKind::Other);
    assert_eq!(e.to_string(), "serial port error: LineError");
}
