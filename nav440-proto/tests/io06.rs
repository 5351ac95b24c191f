//! The driver over an `embedded-io` 0.6 port (feature `embedded-io-06`): the boot sequence
//! configures the unit model exactly as over a 0.7 port. Run by CI with
//! `cargo test -p nav440-proto --features embedded-io-06 --test io06`.
#![cfg(feature = "embedded-io-06")]

use std::collections::VecDeque;

use embedded_io_06 as eio;
use nav440_proto::boot::{self, Options, Target};
use nav440_proto::driver::{Io06Driver, Timing};
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
        let n = buf.len().min(self.to_host.len());
        for (slot, b) in buf.iter_mut().zip(self.to_host.drain(..n)) {
            *slot = b;
        }
        Ok(n)
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
    let mut driver = Io06Driver::new(line(Quirks::default()));
    let mut clock = Clock(0);
    let report = boot::boot(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut clock,
        |l, b| {
            l.baud = b;
            Ok(())
        },
    )
    .expect("boot");
    assert_eq!(report.unit_baud, Baud::B38400);
    assert_eq!(report.baud, Baud::B57600);
    let l = driver.release();
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
    let mut driver = Io06Driver::new(line(Quirks {
        ignore_requests: true,
        ..Quirks::default()
    }));
    driver.set_timing(Timing {
        reply_timeout_ms: 50,
        poll_step_us: 1000,
    });
    let mut clock = Clock(0);
    let err = driver.ping_wait(&mut clock).unwrap_err();
    assert_eq!(err, nav440_proto::driver::Error::NoReply);
    assert_eq!(clock.0, 50_000_000, "50 ms slept in 1 ms steps");
}
