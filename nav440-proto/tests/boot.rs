//! The boot sequence against the unit model (`nav440_proto::unit`) behind a simulated line:
//! every path, with the bytes on the wire checked against the protocol document's vectors
//! (and CRCs computed independently with the `crc` crate's CRC-16/SPI-FUJITSU).

use std::collections::VecDeque;

use nav440_proto::boot::{self, Bauds, BootError, Options, Report, Target};
use nav440_proto::driver::{IoDriver, NbDriver, Port, Timing};
use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::*;

const PING: [u8; 7] = [0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4];
const GF_123: [u8; 14] = [
    0x55, 0x55, 0x47, 0x46, 0x07, 0x03, 0x00, 0x01, 0x00, 0x02, 0x00, 0x03, 0x04, 0x80,
];
/// The document's synthetic A2 frame.
const A2_DOC: [u8; 37] = [
    0x55, 0x55, 0x41, 0x32, 0x1e, 0x07, 0x1c, 0xfc, 0x72, 0x40, 0x00, 0x00, 0x34, 0x00, 0x68, 0x00,
    0x9c, 0x00, 0x00, 0x00, 0x00, 0x0c, 0xcd, 0x20, 0x00, 0x20, 0x00, 0x20, 0x00, 0x00, 0x01, 0xe2,
    0x40, 0x00, 0x00, 0x9d, 0x25,
];
/// The document's real S1 frame.
const S1_DOC: [u8; 31] = [
    0x55, 0x55, 0x53, 0x31, 0x18, 0xff, 0xe0, 0x00, 0x16, 0x0c, 0xc0, 0xff, 0xfe, 0xff, 0xf9, 0xff,
    0xff, 0x27, 0xeb, 0x27, 0xeb, 0x27, 0xeb, 0x27, 0xf7, 0x28, 0xf5, 0x00, 0x02, 0x23, 0xbc,
];

/// A whole frame with the CRC computed by the `crc` crate (independent of the code under test).
fn frame(t: &[u8; 2], payload: &[u8]) -> Vec<u8> {
    let crc = crc::Crc::<u16>::new(&crc::CRC_16_SPI_FUJITSU);
    let mut body = vec![t[0], t[1], payload.len() as u8];
    body.extend_from_slice(payload);
    let c = crc.checksum(&body);
    let mut f = vec![0x55, 0x55];
    f.extend_from_slice(&body);
    f.extend_from_slice(&c.to_be_bytes());
    f
}

fn sf(pairs: &[(u16, u16)]) -> Vec<u8> {
    let mut p = vec![pairs.len() as u8];
    for (id, v) in pairs {
        p.extend_from_slice(&id.to_be_bytes());
        p.extend_from_slice(&v.to_be_bytes());
    }
    frame(b"SF", &p)
}

/// A delay that adds up the time asked for (no real sleep).
#[derive(Default)]
struct FakeDelay {
    ns: u64,
}

impl embedded_hal::delay::DelayNs for FakeDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.ns += u64::from(ns);
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct LineError;

impl std::fmt::Display for LineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("line error")
    }
}

impl std::error::Error for LineError {}

impl embedded_io::Error for LineError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

impl embedded_hal_nb::serial::Error for LineError {
    fn kind(&self) -> embedded_hal_nb::serial::ErrorKind {
        embedded_hal_nb::serial::ErrorKind::Other
    }
}

/// The host's UART wired to a [`Unit`].
struct Line {
    unit: Unit,
    /// Baud rates are ignored (emulator, pty, TCP); otherwise bytes sent at another baud than
    /// the receiver's arrive garbled / are not understood.
    emulated: bool,
    /// The host UART's baud.
    local: Baud,
    /// Bytes to the host, each with the baud it was sent at.
    to_host: VecDeque<(u8, Baud)>,
    /// Bytes the host has read.
    read_count: usize,
    /// Every byte the unit sent, in order.
    sent: Vec<u8>,
    /// Position in `sent` right after the last GF reply.
    after_last_gf: usize,
    written: Vec<u8>,
    /// Streaming frames queued before each response and after it.
    stream_before: usize,
    stream_after: usize,
    /// Streams without pause whenever the host finds the queue empty.
    endless: bool,
    /// Before the n-th GF reply (1-based), send `55 55 41 32 FF`: a corrupted candidate whose
    /// claimed 262 bytes span the reply.
    corrupt_before_gf: Option<usize>,
    gf_replies: usize,
    /// Local baud changes made by the host.
    baud_changes: Vec<Baud>,
    itow: u32,
}

impl Line {
    fn new(eeprom: UnitFields, quirks: Quirks, emulated: bool) -> Self {
        Self {
            unit: Unit::new(eeprom, quirks),
            emulated,
            local: Baud::B38400,
            to_host: VecDeque::new(),
            read_count: 0,
            sent: Vec::new(),
            after_last_gf: 0,
            written: Vec::new(),
            stream_before: 1,
            stream_after: 1,
            endless: false,
            corrupt_before_gf: None,
            gf_replies: 0,
            baud_changes: Vec::new(),
            itow: 123_456,
        }
    }

    fn send(&mut self, bytes: &[u8], baud: Baud) {
        self.sent.extend_from_slice(bytes);
        self.to_host.extend(bytes.iter().map(|&b| (b, baud)));
    }

    /// One frame of the unit's current continuous output (real values from the document).
    fn stream_frame(&mut self) {
        let baud = self.unit.ram().baud();
        let Some((t, _)) = self.unit.ram().stream() else {
            return;
        };
        let f = match t {
            PacketType::S1 => S1_DOC.to_vec(),
            PacketType::A2 => {
                // The document's A2 with the time advanced by 10 ms per frame.
                self.itow += 10;
                let mut p = A2_DOC[5..35].to_vec();
                p[24..28].copy_from_slice(&self.itow.to_be_bytes());
                frame(b"A2", &p)
            }
            other => frame(&other.0, &vec![0u8; other.output_payload_len().unwrap()]),
        };
        self.send(&f, baud);
    }

    fn on_bytes(&mut self, bytes: &[u8]) {
        self.written.extend_from_slice(bytes);
        if !self.emulated && self.local != self.unit.ram().baud() {
            return; // the unit does not understand bytes at another baud
        }
        let mut responses = Vec::new();
        self.unit.receive(bytes, |r| {
            responses.push((r.request, r.frames.to_vec(), r.baud_after))
        });
        for (t, frames, baud_after) in responses {
            for _ in 0..self.stream_before {
                self.stream_frame();
            }
            let baud = baud_after.unwrap_or(self.unit.ram().baud());
            if t == PacketType::GF && !frames.is_empty() {
                self.gf_replies += 1;
                if self.corrupt_before_gf == Some(self.gf_replies) {
                    self.send(&[0x55, 0x55, 0x41, 0x32, 0xFF], baud);
                }
            }
            self.send(&frames, baud);
            if t == PacketType::GF {
                self.after_last_gf = self.sent.len();
            }
            for _ in 0..self.stream_after {
                self.stream_frame();
            }
        }
    }

    fn next_byte(&mut self) -> Option<u8> {
        if self.to_host.is_empty() && self.endless {
            self.stream_frame();
        }
        let (b, baud) = self.to_host.pop_front()?;
        self.read_count += 1;
        Some(if self.emulated || baud == self.local {
            b
        } else {
            b ^ 0x5A // framing at the wrong rate: garbage
        })
    }
}

impl embedded_io::ErrorType for Line {
    type Error = LineError;
}

impl embedded_io::Read for Line {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LineError> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.next_byte() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        Ok(n)
    }
}

impl embedded_io::ReadReady for Line {
    fn read_ready(&mut self) -> Result<bool, LineError> {
        Ok(!self.to_host.is_empty() || self.endless)
    }
}

impl embedded_io::Write for Line {
    fn write(&mut self, buf: &[u8]) -> Result<usize, LineError> {
        let n = buf.len().min(5);
        self.on_bytes(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> Result<(), LineError> {
        Ok(())
    }
}

impl embedded_hal_nb::serial::ErrorType for Line {
    type Error = LineError;
}

impl embedded_hal_nb::serial::Read<u8> for Line {
    fn read(&mut self) -> nb::Result<u8, LineError> {
        self.next_byte().ok_or(nb::Error::WouldBlock)
    }
}

impl embedded_hal_nb::serial::Write<u8> for Line {
    fn write(&mut self, b: u8) -> nb::Result<(), LineError> {
        self.on_bytes(&[b]);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), LineError> {
        Ok(())
    }
}

fn set_baud(l: &mut Line, b: Baud) -> Result<(), LineError> {
    l.local = b;
    l.baud_changes.push(b);
    Ok(())
}

fn run(
    line: Line,
    target: Target,
    options: Options,
) -> (Result<Report, BootError<LineError>>, Line, Vec<u8>, u64) {
    let mut d = IoDriver::new(line);
    let mut delay = FakeDelay::default();
    let r = boot::boot(&mut d, &target, &options, &mut delay, set_baud);
    let pending = d.pending_bytes().to_vec();
    (r, d.release(), pending, delay.ns)
}

fn at(baud: Baud) -> UnitFields {
    UnitFields {
        baud: baud.code(),
        ..UnitFields::POWER_UP
    }
}

/// After success: the host has read exactly the bytes up to the end of the read-back reply
/// (plus what the parser holds), so the stream continues at the byte after it.
fn assert_hand_over(line: &Line, pending: &[u8]) {
    assert_eq!(line.read_count - pending.len(), line.after_last_gf);
    assert_eq!(pending, &line.sent[line.after_last_gf..line.read_count]);
}

#[test]
fn emulated_unit_found_at_once_then_switched_to_57600_and_configured() {
    let (r, line, pending, _) = run(
        Line::new(UnitFields::POWER_UP, Quirks::default(), true),
        Target::DEFAULT,
        Options::DEFAULT,
    );
    let report = r.unwrap();
    assert_eq!(
        report,
        Report {
            found_at: Baud::B57600,
            unit_baud: Baud::B38400,
            initial_packet: PacketType::S1,
            initial_rate_divider: 5,
            switched: true,
            baud: Baud::B57600,
            ping_retries: 0,
            // 1 S1 frame before and after each of the 6 responses, minus the one after the
            // read-back (not read): 11, all before the read-back reply.
            unsolicited_frames: 11,
            skipped_bytes: 0,
        }
    );
    // The wire: ping, GF 1,2,3 (document vectors), SF baud=57600, ping, SF type+rate, GF.
    let mut expected = PING.to_vec();
    expected.extend_from_slice(&GF_123);
    expected.extend(sf(&[(2, 3)]));
    expected.extend_from_slice(&PING);
    expected.extend(sf(&[(3, 0x4132), (1, 1)]));
    expected.extend_from_slice(&GF_123);
    assert_eq!(line.written, expected);
    // The GF said 38400 although 57600 answered (emulation): the host followed the unit.
    assert_eq!(
        line.baud_changes,
        vec![Baud::B57600, Baud::B38400, Baud::B57600]
    );
    assert_eq!(
        *line.unit.ram(),
        UnitFields {
            rate_divider: 1,
            baud: 3,
            packet_type: 0x4132,
            orientation: 0
        }
    );
    assert_eq!(*line.unit.eeprom(), UnitFields::POWER_UP);
    assert_hand_over(&line, &pending);
    assert!(pending.is_empty());
}

#[test]
fn real_line_baud_search_finds_the_unit_at_19200() {
    let (r, line, pending, slept_ns) = run(
        Line::new(at(Baud::B19200), Quirks::default(), false),
        Target::DEFAULT,
        Options::DEFAULT,
    );
    let report = r.unwrap();
    assert_eq!(report.found_at, Baud::B19200);
    assert_eq!(report.unit_baud, Baud::B19200);
    assert!(report.switched);
    // 3 unanswered pings at 57600 and 3 at 38400.
    assert_eq!(report.ping_retries, 6);
    assert_eq!(
        line.baud_changes,
        vec![Baud::B57600, Baud::B38400, Baud::B19200, Baud::B57600]
    );
    assert_eq!(line.unit.ram().baud, 3);
    // Six silent waits of 200 ms each.
    assert_eq!(slept_ns, 6 * 200_000_000);
    assert_hand_over(&line, &pending);
}

#[test]
fn unit_already_at_the_target_baud_is_not_switched() {
    for emulated in [true, false] {
        let (r, line, pending, _) = run(
            Line::new(at(Baud::B57600), Quirks::default(), emulated),
            Target::DEFAULT,
            Options::DEFAULT,
        );
        let report = r.unwrap();
        assert!(!report.switched);
        assert_eq!((report.found_at, report.baud), (Baud::B57600, Baud::B57600));
        let mut expected = PING.to_vec();
        expected.extend_from_slice(&GF_123);
        expected.extend(sf(&[(3, 0x4132), (1, 1)]));
        expected.extend_from_slice(&GF_123);
        assert_eq!(line.written, expected);
        assert_hand_over(&line, &pending);
    }
}

#[test]
fn known_start_baud_tries_only_that_baud() {
    let opts = Options {
        start_baud: Some(Baud::B38400),
        ping_attempts: 2,
    };
    let (r, line, _, _) = run(
        Line::new(UnitFields::POWER_UP, Quirks::default(), false),
        Target::DEFAULT,
        opts,
    );
    assert_eq!(r.unwrap().found_at, Baud::B38400);
    assert_eq!(line.baud_changes[0], Baud::B38400);
    let (r, _, _, _) = run(
        Line::new(at(Baud::B9600), Quirks::default(), false),
        Target::DEFAULT,
        opts,
    );
    let e = r.unwrap_err();
    assert_eq!(
        e,
        BootError::NoAnswer {
            request: PacketType::PK,
            tried: Bauds::one(Baud::B38400),
            attempts: 2,
            timeout_ms: 200
        }
    );
    assert_eq!(
        e.to_string(),
        "no answer from the unit: PK unanswered at 38400 Bd (2 x 200 ms each)"
    );
}

#[test]
fn nak_of_the_configuration_names_the_request_and_fields() {
    let quirks = Quirks {
        nak_output_config: true,
        ..Quirks::default()
    };
    let (r, _, _, _) = run(
        Line::new(UnitFields::POWER_UP, quirks, true),
        Target::DEFAULT,
        Options::DEFAULT,
    );
    let e = r.unwrap_err();
    assert!(matches!(
        e,
        BootError::Nak {
            request: PacketType::SF,
            ..
        }
    ));
    assert_eq!(
        e.to_string(),
        "unit rejected (NAK) SF: packet type 0x0003=0x4132 (A2), rate divider 0x0001=1 (100 Hz)"
    );
}

#[test]
fn over_budget_target_is_naked_by_the_unit() {
    // N1 at 100 Hz = 4900 B/s > 4665 B/s at 57600 Bd: the const check says no, and so does
    // the unit if asked anyway.
    let target = Target {
        packet: PacketType::N1,
        ..Target::DEFAULT
    };
    assert!(!target.fits_budget());
    let (r, line, _, _) = run(
        Line::new(UnitFields::POWER_UP, Quirks::default(), true),
        target,
        Options::DEFAULT,
    );
    assert_eq!(
        r.unwrap_err().to_string(),
        "unit rejected (NAK) SF: packet type 0x0003=0x4E31 (N1), rate divider 0x0001=1 (100 Hz)"
    );
    // Nothing changed but the baud.
    assert_eq!(line.unit.ram().packet_type, PacketType::S1.code());
}

#[test]
fn wrong_read_back_names_field_expected_and_got() {
    let quirks = Quirks {
        keep_rate: true,
        ..Quirks::default()
    };
    let (r, _, _, _) = run(
        Line::new(UnitFields::POWER_UP, quirks, true),
        Target::DEFAULT,
        Options::DEFAULT,
    );
    let e = r.unwrap_err();
    assert_eq!(
        e,
        BootError::WrongReadBack {
            field: FieldId::PACKET_RATE_DIVIDER,
            expected: 1,
            got: Some(5)
        }
    );
    assert_eq!(
        e.to_string(),
        "wrong read-back (GF): expected rate divider 0x0001=1 (100 Hz), got rate divider 0x0001=5 (20 Hz)"
    );
}

#[test]
fn silent_unit_streaming_without_pause_ends_in_no_answer() {
    let quirks = Quirks {
        ignore_requests: true,
        ..Quirks::default()
    };
    let mut line = Line::new(UnitFields::POWER_UP, quirks, true);
    line.endless = true; // S1 frames with no gap: the waits never sleep
    let (r, line, _, slept_ns) = run(line, Target::DEFAULT, Options::DEFAULT);
    let e = r.unwrap_err();
    let mut all = Bauds::default();
    for b in boot::SEARCH_ORDER {
        all.insert(b);
    }
    assert_eq!(
        e,
        BootError::NoAnswer {
            request: PacketType::PK,
            tried: all,
            attempts: 3,
            timeout_ms: 200
        }
    );
    assert_eq!(
        e.to_string(),
        "no answer from the unit: PK unanswered at 57600, 38400, 19200, 9600 Bd (3 x 200 ms each)"
    );
    // Ended by the line time of the bytes received: 12 waits of 200 ms of line time each.
    assert_eq!(slept_ns, 0);
    let line_time_s: f64 = [57600.0, 38400.0, 19200.0, 9600.0]
        .iter()
        .map(|bd| 3.0 * 0.2 * bd / 10.0)
        .sum();
    let read = line.read_count as f64;
    assert!(
        (read - line_time_s).abs() < 12.0 * 31.0,
        "{read} vs {line_time_s}"
    );
}

#[test]
fn silent_and_quiet_unit_sleeps_the_time_outs() {
    let quirks = Quirks {
        ignore_requests: true,
        ..Quirks::default()
    };
    let mut line = Line::new(UnitFields::POWER_UP, quirks, true);
    line.stream_before = 0;
    line.stream_after = 0;
    let (r, _, _, slept_ns) = run(line, Target::DEFAULT, Options::DEFAULT);
    assert!(matches!(r, Err(BootError::NoAnswer { .. })));
    assert_eq!(slept_ns, 12 * 200_000_000);
}

#[test]
fn replies_are_found_among_streaming_frames() {
    let mut line = Line::new(UnitFields::POWER_UP, Quirks::default(), true);
    line.stream_before = 7;
    line.stream_after = 3;
    line.endless = true;
    let (r, line, pending, _) = run(line, Target::DEFAULT, Options::DEFAULT);
    let report = r.unwrap();
    assert_eq!(report.baud, Baud::B57600);
    // 6 responses with 7 frames before each, 3 after each but the last: 57.
    assert_eq!(report.unsolicited_frames, 57);
    assert_hand_over(&line, &pending);
}

#[test]
fn corrupted_candidate_spanning_the_read_back_leaves_the_rest_in_pending_bytes() {
    let mut line = Line::new(UnitFields::POWER_UP, Quirks::default(), true);
    line.corrupt_before_gf = Some(2);
    line.stream_after = 10; // 370 bytes after the GF reply: the candidate's 262 end in them
    let (r, line, pending, _) = run(line, Target::DEFAULT, Options::DEFAULT);
    r.unwrap();
    assert!(!pending.is_empty());
    assert_hand_over(&line, &pending);
    // pending + the rest of the line = exactly the 10 A2 frames after the reply.
    let mut rest = pending.clone();
    rest.extend(line.to_host.iter().map(|(b, _)| *b));
    assert_eq!(rest, line.sent[line.after_last_gf..]);
    let mut p = Parser::new();
    let mut a2 = 0;
    p.feed(&rest, |f| {
        a2 += usize::from(f.packet_type == PacketType::A2)
    });
    assert_eq!(a2, 10);
}

#[test]
fn lower_target_baud_sets_the_output_first() {
    // The unit streams N1 at 50 Hz at 57600 Bd (2450 B/s): at 19200 Bd (1555 B/s) that is over
    // budget, so the baud must come after the output change (A2 at 25 Hz = 925 B/s).
    let unit = UnitFields {
        rate_divider: 2,
        baud: Baud::B57600.code(),
        packet_type: PacketType::N1.code(),
        orientation: 0,
    };
    let target = Target {
        packet: PacketType::A2,
        rate: PacketRate::Hz25,
        baud: Baud::B19200,
        persist: false,
    };
    assert!(target.fits_budget());
    let (r, line, pending, _) = run(
        Line::new(unit, Quirks::default(), false),
        target,
        Options::DEFAULT,
    );
    let report = r.unwrap();
    assert!(report.switched);
    let mut expected = PING.to_vec();
    expected.extend_from_slice(&GF_123);
    expected.extend(sf(&[(3, 0x4132), (1, 4)]));
    expected.extend(sf(&[(2, 1)]));
    expected.extend_from_slice(&PING);
    expected.extend_from_slice(&GF_123);
    assert_eq!(line.written, expected);
    assert_hand_over(&line, &pending);
}

#[test]
fn persist_writes_the_fields_to_eeprom() {
    let target = Target {
        persist: true,
        ..Target::DEFAULT
    };
    let (r, line, _, _) = run(
        Line::new(at(Baud::B57600), Quirks::default(), true),
        target,
        Options::DEFAULT,
    );
    r.unwrap();
    let mut p = vec![3u8];
    for (id, v) in [(3u16, 0x4132u16), (1, 1), (2, 3)] {
        p.extend_from_slice(&id.to_be_bytes());
        p.extend_from_slice(&v.to_be_bytes());
    }
    let wf = frame(b"WF", &p);
    assert!(line.written.windows(wf.len()).any(|w| w == wf.as_slice()));
    assert_eq!(line.unit.eeprom(), line.unit.ram());
}

#[test]
fn nb_driver_runs_the_same_sequence() {
    let mut d = NbDriver::new(Line::new(UnitFields::POWER_UP, Quirks::default(), false));
    d.set_timing(Timing {
        reply_timeout_ms: 50,
        poll_step_us: 1000,
    });
    let mut delay = FakeDelay::default();
    let r = boot::boot(
        &mut d,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut delay,
        set_baud,
    );
    let report = r.unwrap();
    assert_eq!(report.found_at, Baud::B38400);
    assert_eq!(report.ping_retries, 3);
    let pending = d.pending_bytes().to_vec();
    let line = d.release();
    assert_hand_over(&line, &pending);
    assert_eq!(
        line.unit.ram().stream(),
        Some((PacketType::A2, PacketRate::Hz100))
    );
}

#[test]
fn budget_figures_match_the_protocol_document() {
    assert_eq!(boot::budget_bytes_per_second(Baud::B38400), 3110);
    assert_eq!(boot::budget_bytes_per_second(Baud::B57600), 4665);
    // A2 at 100 Hz: 3700 B/s, over the 38400 budget, under the 57600 one.
    assert!(!boot::fits_budget(
        PacketType::A2,
        PacketRate::Hz100,
        Baud::B38400
    ));
    assert!(boot::fits_budget(
        PacketType::A2,
        PacketRate::Hz100,
        Baud::B57600
    ));
    // N1 at 100 Hz does not fit 57600 (document).
    assert!(!boot::fits_budget(
        PacketType::N1,
        PacketRate::Hz100,
        Baud::B57600
    ));
    assert_eq!(
        boot::stream_bytes_per_second(PacketType::S1, PacketRate::Hz20),
        Some(620)
    );
    assert_eq!(
        boot::stream_bytes_per_second(PacketType::PK, PacketRate::Hz20),
        None
    );
    const _: () = assert!(Target::DEFAULT.fits_budget());
}

/// `Port` is nameable for generic callers (its associated types).
#[allow(dead_code)]
fn generic_caller<P: Port>(d: &mut driver::Driver<P>) -> u32 {
    d.unsolicited()
}

#[test]
fn nak_lines_of_baud_switch_and_read_requests() {
    let baud = BootError::<LineError>::Nak {
        request: PacketType::SF,
        fields: boot::FieldList::new(&[(FieldId::BAUD_RATE, 3)]),
    };
    assert_eq!(
        baud.to_string(),
        "unit rejected (NAK) SF: baud 0x0002=3 (57600 Bd)"
    );
    let gf = BootError::<LineError>::Nak {
        request: PacketType::GF,
        fields: boot::FieldList::ids(&boot::READ_FIELDS),
    };
    assert_eq!(
        gf.to_string(),
        "unit rejected (NAK) GF: fields 0x0001, 0x0002, 0x0003"
    );
    let missing = BootError::<LineError>::WrongReadBack {
        field: FieldId::PACKET_TYPE,
        expected: 0x4132,
        got: None,
    };
    assert_eq!(
        missing.to_string(),
        "wrong read-back (GF): expected packet type 0x0003=0x4132 (A2), got packet type 0x0003=(missing)"
    );
}

#[test]
fn undefined_baud_code_in_the_unit_configuration_is_an_error_naming_field_and_value() {
    // The protocol defines baud codes 0-3 (9600-57600 Bd); 9 is none of them.
    let eeprom = UnitFields {
        baud: 9,
        ..UnitFields::POWER_UP
    };
    let (r, _, _, _) = run(
        Line::new(eeprom, Quirks::default(), true),
        Target::DEFAULT,
        Options::DEFAULT,
    );
    let e = r.unwrap_err();
    assert_eq!(
        e,
        BootError::UndefinedValue {
            field: FieldId::BAUD_RATE,
            value: 9
        }
    );
    assert_eq!(
        e.to_string(),
        "the unit's configuration (GF) holds an undefined value: baud 0x0002=9 (undefined)"
    );
}

#[test]
fn nak_of_a_ping_names_the_request() {
    let e = BootError::<LineError>::Nak {
        request: PacketType::PK,
        fields: boot::FieldList::default(),
    };
    assert_eq!(e.to_string(), "unit rejected (NAK) PK (ping)");
}
