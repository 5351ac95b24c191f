//! Both drivers against mock serial devices that answer like the unit.

use std::collections::VecDeque;

use nav440_proto::driver::{Error, IoDriver, NbDriver, Timing};
use nav440_proto::*;

/// A delay that only adds up the time asked for (no real sleep).
#[derive(Default)]
struct FakeDelay {
    ns: u64,
}

impl embedded_hal::delay::DelayNs for FakeDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.ns += u64::from(ns);
    }
}

/// How the mock answers SF/WF requests.
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    /// Accept every field: reply listing all IDs.
    AcceptAll,
    /// Reject everything: NAK only.
    NakOnly,
    /// Accept all but the packet-rate field: reply listing the others, then a NAK.
    ReplyThenNak,
    /// Same, NAK first.
    NakThenReply,
    /// Partial reply, no NAK.
    PartialNoNak,
    /// Never answer.
    Silent,
}

/// A NAV440 stand-in: parses requests written to it and queues the unit's answers,
/// with continuous A2 output frames interleaved before the answer.
struct MockUnit {
    mode: Mode,
    rx_parser: Parser,
    to_host: VecDeque<u8>,
    /// Largest chunk returned by one embedded-io `read` (1 = byte by byte).
    chunk: usize,
    written: Vec<u8>,
    requests: Vec<PacketType>,
    a2_time: u32,
}

impl MockUnit {
    fn new(mode: Mode, chunk: usize) -> Self {
        Self {
            mode,
            rx_parser: Parser::new(),
            to_host: VecDeque::new(),
            chunk,
            written: Vec::new(),
            requests: Vec::new(),
            a2_time: 1000,
        }
    }

    fn push_frame(&mut self, f: impl FnOnce(&mut [u8]) -> Result<usize, EncodeError>) {
        let mut buf = [0u8; MAX_FRAME];
        let n = f(&mut buf).unwrap();
        self.to_host.extend(&buf[..n]);
    }

    fn push_a2(&mut self) {
        self.a2_time += 10;
        let a2 = A2Fields {
            yaw_true: 0x2000,
            time_itow: self.a2_time,
            ..Default::default()
        };
        self.push_frame(|o| a2.encode(o));
    }

    fn on_bytes(&mut self, bytes: &[u8]) {
        self.written.extend_from_slice(bytes);
        let mut reqs: Vec<(PacketType, Vec<u8>)> = Vec::new();
        self.rx_parser
            .feed(bytes, |f| reqs.push((f.packet_type, f.payload.to_vec())));
        for (t, p) in reqs {
            self.requests.push(t);
            let req = Request::decode(Frame {
                packet_type: t,
                payload: &p,
            })
            .unwrap();
            // Continuous output keeps flowing before the answer.
            self.push_a2();
            self.push_a2();
            match req {
                Request::SetFields(v) | Request::WriteFields(v) => {
                    let all: Vec<FieldId> = v.iter().map(|(id, _)| id).collect();
                    let some: Vec<FieldId> = all
                        .iter()
                        .copied()
                        .filter(|id| *id != FieldId::PACKET_RATE_DIVIDER)
                        .collect();
                    match self.mode {
                        Mode::AcceptAll => {
                            self.push_frame(|o| command::fields_accepted_reply(t, &all, o))
                        }
                        Mode::NakOnly => self.push_frame(|o| command::nak(t, o)),
                        Mode::ReplyThenNak => {
                            self.push_frame(|o| command::fields_accepted_reply(t, &some, o));
                            self.push_a2();
                            self.push_frame(|o| command::nak(t, o));
                        }
                        Mode::NakThenReply => {
                            self.push_frame(|o| command::nak(t, o));
                            self.push_frame(|o| command::fields_accepted_reply(t, &some, o));
                        }
                        Mode::PartialNoNak => {
                            self.push_frame(|o| command::fields_accepted_reply(t, &some, o))
                        }
                        Mode::Silent => {}
                    }
                }
                Request::Ping => self.push_frame(command::ping),
                Request::GetPacket(PacketType::A2) => self.push_a2(),
                _ => self.push_frame(|o| command::nak(t, o)),
            }
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct MockError;

impl std::fmt::Display for MockError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("mock serial error")
    }
}

impl std::error::Error for MockError {}

impl embedded_io::Error for MockError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

impl embedded_hal_nb::serial::Error for MockError {
    fn kind(&self) -> embedded_hal_nb::serial::ErrorKind {
        embedded_hal_nb::serial::ErrorKind::Other
    }
}

impl embedded_io::ErrorType for MockUnit {
    type Error = MockError;
}

impl embedded_io::Read for MockUnit {
    /// Returns up to `chunk` queued bytes; 0 when nothing is queued (end of data).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, MockError> {
        let n = buf.len().min(self.chunk).min(self.to_host.len());
        for b in buf.iter_mut().take(n) {
            *b = self.to_host.pop_front().unwrap();
        }
        Ok(n)
    }
}

impl embedded_io::ReadReady for MockUnit {
    fn read_ready(&mut self) -> Result<bool, MockError> {
        Ok(!self.to_host.is_empty())
    }
}

impl embedded_io::Write for MockUnit {
    fn write(&mut self, buf: &[u8]) -> Result<usize, MockError> {
        // Accept at most 5 bytes per call to exercise the write loop.
        let n = buf.len().min(5);
        self.on_bytes(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> Result<(), MockError> {
        Ok(())
    }
}

impl embedded_hal_nb::serial::ErrorType for MockUnit {
    type Error = MockError;
}

impl embedded_hal_nb::serial::Read<u8> for MockUnit {
    fn read(&mut self) -> nb::Result<u8, MockError> {
        self.to_host.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

impl embedded_hal_nb::serial::Write<u8> for MockUnit {
    fn write(&mut self, b: u8) -> nb::Result<(), MockError> {
        self.on_bytes(&[b]);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), MockError> {
        Ok(())
    }
}

fn expected_sf() -> Vec<u8> {
    let mut buf = [0u8; 32];
    let n = command::set_fields(
        &[
            (FieldId::PACKET_TYPE, 0x4132),
            (FieldId::PACKET_RATE_DIVIDER, 1),
        ],
        &mut buf,
    )
    .unwrap();
    buf[..n].to_vec()
}

fn io_configure(mode: Mode, chunk: usize) -> (Result<(), Error<MockError>>, MockUnit) {
    let mut d = IoDriver::new(MockUnit::new(mode, chunk));
    let r =
        d.set_packet_type_and_rate(PacketType::A2, PacketRate::Hz100, &mut FakeDelay::default());
    (r, d.release())
}

fn nb_configure(mode: Mode) -> (Result<(), Error<MockError>>, MockUnit) {
    let mut d = NbDriver::new(MockUnit::new(mode, 1));
    let r =
        d.set_packet_type_and_rate(PacketType::A2, PacketRate::Hz100, &mut FakeDelay::default());
    (r, d.release())
}

#[test]
fn io_driver_sets_type_and_rate_confirmed_by_reply() {
    for chunk in [1, 7, 64] {
        let (r, unit) = io_configure(Mode::AcceptAll, chunk);
        assert_eq!(r, Ok(()));
        assert_eq!(unit.written, expected_sf());
        assert_eq!(unit.requests, vec![PacketType::SF]);
    }
}

#[test]
fn io_driver_reports_nak() {
    for chunk in [1, 64] {
        let (r, _) = io_configure(Mode::NakOnly, chunk);
        assert_eq!(
            r,
            Err(Error::Nak {
                request: PacketType::SF
            })
        );
    }
}

#[test]
fn io_driver_reports_nak_that_comes_with_a_reply() {
    for chunk in [1, 7, 64] {
        for mode in [Mode::ReplyThenNak, Mode::NakThenReply] {
            let (r, _) = io_configure(mode, chunk);
            assert_eq!(
                r,
                Err(Error::Nak {
                    request: PacketType::SF
                }),
                "chunk {chunk}"
            );
        }
    }
}

#[test]
fn io_driver_partial_reply_without_nak_and_silence() {
    let (r, _) = io_configure(Mode::PartialNoNak, 64);
    assert_eq!(
        r,
        Err(Error::NotAccepted {
            requested: 2,
            accepted: 1
        })
    );
    let (r, _) = io_configure(Mode::Silent, 64);
    assert_eq!(r, Err(Error::NoReply));
}

#[test]
fn io_driver_yields_packets() {
    let mut d = IoDriver::new(MockUnit::new(Mode::AcceptAll, 13));
    d.request_packet(PacketType::A2).unwrap();
    let mut yaws = Vec::new();
    while d
        .poll(|p| {
            if let Ok(p) = p {
                if let Some(s) = p.yaw_sample() {
                    yaws.push(s);
                }
            }
        })
        .unwrap()
        > 0
    {}
    // GP answered by two continuous A2 frames plus the requested one.
    assert_eq!(yaws.len(), 3);
    assert!(yaws.iter().all(|s| s.yaw_deg == 45.0));
    assert_eq!(yaws[0].time, TimeStamp::Itow(1010));
    assert_eq!(d.stats().count(PacketType::A2), 3);
}

#[test]
fn nb_driver_sets_type_and_rate_confirmed_by_reply() {
    let (r, unit) = nb_configure(Mode::AcceptAll);
    assert_eq!(r, Ok(()));
    assert_eq!(unit.written, expected_sf());
}

#[test]
fn nb_driver_reports_nak_alone_and_with_a_reply() {
    for mode in [Mode::NakOnly, Mode::ReplyThenNak, Mode::NakThenReply] {
        let (r, _) = nb_configure(mode);
        assert_eq!(
            r,
            Err(Error::Nak {
                request: PacketType::SF
            })
        );
    }
    let (r, _) = nb_configure(Mode::PartialNoNak);
    assert_eq!(
        r,
        Err(Error::NotAccepted {
            requested: 2,
            accepted: 1
        })
    );
    let (r, _) = nb_configure(Mode::Silent);
    assert_eq!(r, Err(Error::NoReply));
}

#[test]
fn nb_driver_yields_packets_without_blocking() {
    let mut d = NbDriver::new(MockUnit::new(Mode::AcceptAll, 1));
    d.ping().unwrap();
    let mut seen = Vec::new();
    let n = d.poll(|p| seen.push(p.map(|p| p.packet_type()))).unwrap();
    assert!(n > 0);
    assert_eq!(
        seen,
        vec![Ok(PacketType::A2), Ok(PacketType::A2), Ok(PacketType::PK)]
    );
    // Nothing more queued: returns at once with 0 bytes.
    assert_eq!(d.poll(|_| panic!("no packet expected")).unwrap(), 0);
}

#[test]
fn write_fields_uses_wf() {
    let mut d = IoDriver::new(MockUnit::new(Mode::AcceptAll, 64));
    d.write_fields(
        &[(FieldId::PACKET_RATE_DIVIDER, 2)],
        &mut FakeDelay::default(),
    )
    .unwrap();
    let unit = d.release();
    let mut buf = [0u8; 16];
    let n = command::write_fields(&[(FieldId::PACKET_RATE_DIVIDER, 2)], &mut buf).unwrap();
    // The protocol document's "WF rate=50Hz" vector.
    assert_eq!(
        &buf[..n],
        &[0x55, 0x55, 0x57, 0x46, 0x05, 0x01, 0x00, 0x01, 0x00, 0x02, 0x6F, 0xAE]
    );
    assert_eq!(unit.written, buf[..n].to_vec());
    assert_eq!(unit.requests, vec![PacketType::WF]);
}

#[test]
fn silent_unit_times_out_after_the_reply_timeout_in_delay_time() {
    // 200 ms in 500 us steps: the wait sleeps 400 steps, then gives up.
    for timing in [
        Timing::DEFAULT,
        Timing {
            reply_timeout_ms: 30,
            poll_step_us: 1000,
        },
    ] {
        let mut d = NbDriver::new(MockUnit::new(Mode::Silent, 1));
        d.set_timing(timing);
        let mut delay = FakeDelay::default();
        // The mock queues two A2 frames (74 B) before its (absent) answer.
        let r = d.set_packet_type_and_rate(PacketType::A2, PacketRate::Hz100, &mut delay);
        assert_eq!(r, Err(Error::NoReply));
        // Slept time + line time of the 74 bytes (74 x 260 us at 38400 Bd) reach the time-out.
        let line_us = 74 * (10_000_000 / 38_400);
        let slept_us = delay.ns / 1000;
        let limit = u64::from(timing.reply_timeout_ms) * 1000;
        assert!(
            slept_us + line_us >= limit,
            "{slept_us} + {line_us} < {limit}"
        );
        assert!(slept_us + line_us < limit + u64::from(timing.poll_step_us));
        assert_eq!(d.unsolicited(), 2);
    }
}
