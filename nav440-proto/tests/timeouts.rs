//! `Driver::poll_timeout`: a read that waits at most a time, measured through `DelayNs`
//! (sleeps plus the line time of the bytes received), like the reply waits.

use std::collections::VecDeque;
use std::convert::Infallible;

use nav440_proto::driver::{IoDriver, Timing};
use nav440_proto::{A2Fields, Packet};

/// Bytes queued for the host; writes vanish.
struct Feed(VecDeque<u8>);

impl embedded_io::ErrorType for Feed {
    type Error = Infallible;
}
impl embedded_io::ReadReady for Feed {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(!self.0.is_empty())
    }
}
impl embedded_io::Read for Feed {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        let n = buf.len().min(self.0.len());
        for (slot, b) in buf.iter_mut().zip(self.0.drain(..n)) {
            *slot = b;
        }
        Ok(n)
    }
}
impl embedded_io::Write for Feed {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        Ok(buf.len())
    }
    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

#[derive(Default)]
struct Clock {
    ns: u64,
}
impl embedded_hal::delay::DelayNs for Clock {
    fn delay_ns(&mut self, ns: u32) {
        self.ns += u64::from(ns);
    }
}

#[test]
fn silent_port_returns_after_the_time_out() {
    let mut driver = IoDriver::new(Feed(VecDeque::new()));
    driver.set_timing(Timing {
        reply_timeout_ms: 200,
        poll_step_us: 1000,
    });
    let mut clock = Clock::default();
    let n = driver
        .poll_timeout(25_000, &mut clock, |_| panic!("no frame"))
        .expect("read");
    assert_eq!((n, clock.ns), (0, 25_000_000), "25 ms in 1 ms sleeps");
}

#[test]
fn frames_are_yielded_and_their_line_time_counts() {
    // Three A2 frames (37 bytes each) at 57600 Bd: 111 bytes x 173 us = 19.2 ms of line time.
    let mut bytes = VecDeque::new();
    for k in 0..3u32 {
        let mut f = [0u8; 64];
        let fields = A2Fields {
            time_itow: 1000 + 10 * k,
            ..Default::default()
        };
        let n = fields.encode(&mut f).expect("encode");
        bytes.extend(&f[..n]);
    }
    let mut driver = IoDriver::new(Feed(bytes));
    driver.set_line_baud(57_600);
    let mut clock = Clock::default();
    let mut frames = 0;
    let n = driver
        .poll_timeout(20_000, &mut clock, |p| {
            assert!(matches!(p, Ok(Packet::A2(_))), "{p:?}");
            frames += 1;
        })
        .expect("read");
    assert_eq!((n, frames), (111, 3));
    // 111 bytes x 173 us = 19.203 ms, then 500 us sleeps until 20 ms have passed.
    assert_eq!(clock.ns, 1_000_000);
}
