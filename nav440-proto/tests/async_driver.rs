//! The async driver and `boot::boot_async` against the unit model: the same bytes on the
//! wire, the same report and the same errors as the blocking driver (one shared
//! implementation), with the reply time-outs spent awaiting an async `DelayNs` that suspends
//! (so the executor really runs the futures in several polls).

use std::collections::VecDeque;
use std::convert::Infallible;
use std::future::Future;
use std::pin::pin;
use std::task::{Context, Poll, Waker};

use nav440_proto::boot::{self, BootError, Options, Report, Target};
use nav440_proto::driver::{AsyncDriver, IoDriver};
use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::{Baud, PacketRate, PacketType};

/// The protocol document's ping frame.
const PING: [u8; 7] = [0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4];

/// A serial line to the unit model, with both the blocking (0.7) and the async traits.
struct Line {
    unit: Unit,
    to_host: VecDeque<u8>,
    written: Vec<u8>,
    baud: Baud,
}

impl Line {
    fn new(quirks: Quirks) -> Self {
        Self {
            unit: Unit::new(UnitFields::POWER_UP, quirks),
            to_host: VecDeque::new(),
            written: Vec::new(),
            baud: Baud::B38400,
        }
    }

    fn take(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.to_host.len());
        for (slot, b) in buf.iter_mut().zip(self.to_host.drain(..n)) {
            *slot = b;
        }
        n
    }

    fn put(&mut self, buf: &[u8]) -> usize {
        self.written.extend_from_slice(buf);
        let to_host = &mut self.to_host;
        self.unit.receive(buf, |r| to_host.extend(r.frames));
        buf.len()
    }
}

impl embedded_io::ErrorType for Line {
    type Error = Infallible;
}

impl embedded_io::ReadReady for Line {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(!self.to_host.is_empty())
    }
}

impl embedded_io::Read for Line {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        Ok(self.take(buf))
    }
}

impl embedded_io::Write for Line {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        Ok(self.put(buf))
    }
    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

impl embedded_io_async::Read for Line {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        Ok(self.take(buf))
    }
}

impl embedded_io_async::Write for Line {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        Ok(self.put(buf))
    }
    async fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

/// Suspends once, then completes (as a timer would, after waking its task).
struct YieldOnce(bool);

impl Future for YieldOnce {
    type Output = ();
    fn poll(mut self: std::pin::Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        if self.0 {
            Poll::Ready(())
        } else {
            self.0 = true;
            cx.waker().wake_by_ref();
            Poll::Pending
        }
    }
}

/// An async delay that adds up the time awaited and suspends every time.
#[derive(Default)]
struct AsyncClock {
    ns: u64,
}

impl embedded_hal_async::delay::DelayNs for AsyncClock {
    async fn delay_ns(&mut self, ns: u32) {
        self.ns += u64::from(ns);
        YieldOnce(false).await;
    }
}

/// A blocking delay that adds up the time asked for.
#[derive(Default)]
struct Clock {
    ns: u64,
}

impl embedded_hal::delay::DelayNs for Clock {
    fn delay_ns(&mut self, ns: u32) {
        self.ns += u64::from(ns);
    }
}

/// Polls `f` to its end; returns its output and how many polls it took.
fn run<F: Future>(f: F) -> (F::Output, u32) {
    let mut f = pin!(f);
    let mut cx = Context::from_waker(Waker::noop());
    let mut polls = 0;
    loop {
        polls += 1;
        if let Poll::Ready(v) = f.as_mut().poll(&mut cx) {
            return (v, polls);
        }
    }
}

type Outcome = (Result<Report, BootError<Infallible>>, Line, u64);

fn boot_blocking(quirks: Quirks) -> Outcome {
    let mut driver = IoDriver::new(Line::new(quirks));
    let mut clock = Clock::default();
    let r = boot::boot(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut clock,
        |l, b| {
            l.baud = b;
            Ok(())
        },
    );
    (r, driver.release(), clock.ns)
}

fn boot_async(quirks: Quirks) -> (Outcome, u32) {
    let mut driver = AsyncDriver::new(Line::new(quirks));
    let mut clock = AsyncClock::default();
    let (r, polls) = run(boot::boot_async(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut clock,
        |l, b| {
            l.baud = b;
            Ok(())
        },
    ));
    ((r, driver.release(), clock.ns), polls)
}

#[test]
fn async_boot_configures_the_unit_like_the_blocking_one() {
    let ((report, line, ns), polls) = boot_async(Quirks::default());
    let report = report.expect("boot_async");
    assert_eq!(report.unit_baud, Baud::B38400, "power-up baud read with GF");
    assert_eq!(report.baud, Baud::B57600);
    assert!(report.switched);
    assert_eq!(
        line.unit.ram().stream(),
        Some((PacketType::A2, PacketRate::Hz100))
    );
    assert_eq!(line.unit.ram().baud(), Baud::B57600);
    assert_eq!(line.baud, Baud::B57600, "the local port followed");
    assert_eq!(line.written.get(..7), Some(&PING[..]));
    assert_eq!((ns, polls), (0, 1), "every reply was there at once");

    let (blocking, blocking_line, _) = boot_blocking(Quirks::default());
    assert_eq!(blocking.expect("boot"), report, "same report");
    assert_eq!(
        blocking_line.written, line.written,
        "same bytes on the wire"
    );
}

#[test]
fn silent_unit_awaits_every_time_out() {
    let quirks = Quirks {
        ignore_requests: true,
        ..Quirks::default()
    };
    let ((r, _, ns), polls) = boot_async(quirks);
    let err = r.unwrap_err();
    // 4 bauds x 3 pings x the default 200 ms reply time-out, in 500 us sleeps.
    assert!(
        matches!(
            err,
            BootError::NoAnswer {
                request: PacketType::PK,
                attempts: 3,
                timeout_ms: 200,
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(ns, 4 * 3 * 200_000_000);
    assert_eq!(
        polls,
        4 * 3 * (200_000 / 500) + 1,
        "one suspension per sleep"
    );
    let (blocking, _, blocking_ns) = boot_blocking(quirks);
    assert_eq!(blocking.unwrap_err(), err);
    assert_eq!(blocking_ns, ns);
}

#[test]
fn nak_is_the_same_error() {
    let quirks = Quirks {
        nak_output_config: true,
        ..Quirks::default()
    };
    let ((r, _, _), _) = boot_async(quirks);
    let err = r.unwrap_err();
    assert!(
        matches!(
            err,
            BootError::Nak {
                request: PacketType::SF,
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(boot_blocking(quirks).0.unwrap_err(), err);
}

#[test]
fn async_ping_and_poll() {
    let mut driver = AsyncDriver::new(Line::new(Quirks::default()));
    let mut clock = AsyncClock::default();
    let (r, _) = run(driver.ping_wait(&mut clock));
    r.expect("ping answered");
    // A GP of the ID packet: the reply comes through poll.
    let mut frame = [0u8; 16];
    let n = nav440_proto::command::get_packet(PacketType::ID, &mut frame).expect("encode");
    run(driver.send_raw(&frame[..n])).0.expect("sent");
    let mut ids = 0;
    let (r, _) = run(driver.poll(|p| {
        if let Ok(nav440_proto::Packet::Id(_)) = p {
            ids += 1;
        }
    }));
    assert!(r.expect("read") > 0);
    assert_eq!(ids, 1);
}
