//! The unit model against the protocol document's command vectors; expected replies are built
//! with the `crc` crate's CRC-16/SPI-FUJITSU (independent of the encoder under test).

use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::{Baud, PacketType};

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

fn nak(t: &[u8; 2]) -> Vec<u8> {
    frame(&[0x15, 0x15], t)
}

#[derive(Debug, Default)]
struct Answer {
    frames: Vec<u8>,
    baud_after: Option<Baud>,
    get_packet: Option<PacketType>,
    reset: bool,
    output_changed: bool,
}

fn ask(unit: &mut Unit, request: &[u8]) -> Answer {
    let mut answers = Vec::new();
    unit.receive(request, |r| {
        answers.push(Answer {
            frames: r.frames.to_vec(),
            baud_after: r.baud_after,
            get_packet: r.get_packet,
            reset: r.reset,
            output_changed: r.output_changed,
        })
    });
    assert_eq!(answers.len(), 1, "one request, one response");
    answers.pop().unwrap()
}

fn power_up() -> Unit {
    Unit::new(UnitFields::POWER_UP, Quirks::default())
}

const PING: [u8; 7] = [0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4];
const GP_A2: [u8; 9] = [0x55, 0x55, 0x47, 0x50, 0x02, 0x41, 0x32, 0xB4, 0xC5];
const GP_N1: [u8; 9] = [0x55, 0x55, 0x47, 0x50, 0x02, 0x4E, 0x31, 0x94, 0x98];
const SR: [u8; 7] = [0x55, 0x55, 0x53, 0x52, 0x00, 0x7E, 0x4F];
const AR: [u8; 7] = [0x55, 0x55, 0x41, 0x52, 0x00, 0x53, 0x4C];
const CH: [u8; 9] = [0x55, 0x55, 0x43, 0x48, 0x02, 0x01, 0x02, 0x98, 0x38];
const SF_RATE_100: [u8; 12] = [
    0x55, 0x55, 0x53, 0x46, 0x05, 0x01, 0x00, 0x01, 0x00, 0x01, 0x50, 0xA0,
];
const SF_TYPE_A2: [u8; 12] = [
    0x55, 0x55, 0x53, 0x46, 0x05, 0x01, 0x00, 0x03, 0x41, 0x32, 0x06, 0x0D,
];
const GF_123: [u8; 14] = [
    0x55, 0x55, 0x47, 0x46, 0x07, 0x03, 0x00, 0x01, 0x00, 0x02, 0x00, 0x03, 0x04, 0x80,
];
const WF_RATE_50: [u8; 12] = [
    0x55, 0x55, 0x57, 0x46, 0x05, 0x01, 0x00, 0x01, 0x00, 0x02, 0x6F, 0xAE,
];

#[test]
fn ping_echo_and_resets_answer_with_the_same_bytes() {
    let mut u = power_up();
    assert_eq!(ask(&mut u, &PING).frames, PING);
    assert_eq!(ask(&mut u, &CH).frames, CH);
    assert_eq!(ask(&mut u, &AR).frames, AR);
    let sr = ask(&mut u, &SR);
    assert_eq!(sr.frames, SR);
    assert!(sr.reset);
}

#[test]
fn bare_ascii_ping_is_not_a_frame_and_gets_nothing() {
    // The bare `UUPK` has no length/CRC; the model answers framed requests only.
    let mut u = power_up();
    let mut n = 0;
    u.receive(b"UUPK", |_| n += 1);
    assert_eq!(n, 0);
}

#[test]
fn get_fields_reports_the_power_up_configuration() {
    let mut u = power_up();
    // S1 at 20 Hz (divider 5) at 38400 Bd (code 2).
    let expected = frame(
        b"GF",
        &[
            3, 0x00, 0x01, 0x00, 0x05, 0x00, 0x02, 0x00, 0x02, 0x00, 0x03, 0x53, 0x31,
        ],
    );
    assert_eq!(ask(&mut u, &GF_123).frames, expected);
}

#[test]
fn set_fields_within_budget_is_accepted_and_applied() {
    let mut u = power_up();
    // S1 at 100 Hz = 31 x 100 = 3100 B/s <= 3110 B/s at 38400 Bd.
    let a = ask(&mut u, &SF_RATE_100);
    assert_eq!(a.frames, frame(b"SF", &[1, 0x00, 0x01]));
    assert!(a.output_changed);
    assert_eq!(u.ram().rate_divider, 1);
    assert_eq!(u.eeprom().rate_divider, 5);
}

#[test]
fn over_budget_combination_at_the_baud_in_force_is_naked_whole() {
    let mut u = power_up();
    ask(&mut u, &SF_RATE_100);
    // A2 at 100 Hz = 3700 B/s > 3110 B/s at 38400 Bd: NAK, nothing changes.
    let a = ask(&mut u, &SF_TYPE_A2);
    assert_eq!(a.frames, nak(b"SF"));
    assert!(!a.output_changed);
    assert_eq!(u.ram().packet_type, PacketType::S1.code());
    // At 57600 Bd (budget 4665 B/s) it fits; the baud reply comes at the new baud.
    let baud = ask(&mut u, &frame(b"SF", &[1, 0x00, 0x02, 0x00, 0x03]));
    assert_eq!(baud.frames, frame(b"SF", &[1, 0x00, 0x02]));
    assert_eq!(baud.baud_after, Some(Baud::B57600));
    assert_eq!(
        ask(&mut u, &SF_TYPE_A2).frames,
        frame(b"SF", &[1, 0x00, 0x03])
    );
    assert_eq!(
        u.ram().stream(),
        Some((PacketType::A2, nav440_proto::PacketRate::Hz100))
    );
    // Back down to 38400 with A2 at 100 Hz streaming: over budget, NAK.
    let down = ask(&mut u, &frame(b"SF", &[1, 0x00, 0x02, 0x00, 0x02]));
    assert_eq!(down.frames, nak(b"SF"));
    assert_eq!(down.baud_after, None);
}

#[test]
fn write_fields_changes_eeprom_only_and_read_fields_shows_it() {
    let mut u = power_up();
    assert_eq!(
        ask(&mut u, &WF_RATE_50).frames,
        frame(b"WF", &[1, 0x00, 0x01])
    );
    assert_eq!(u.eeprom().rate_divider, 2);
    assert_eq!(u.ram().rate_divider, 5);
    let rf = frame(b"RF", &[1, 0x00, 0x01]);
    assert_eq!(ask(&mut u, &rf).frames, frame(b"RF", &[1, 0, 1, 0, 2]));
    // A software reset loads RAM from EEPROM.
    ask(&mut u, &SR);
    assert_eq!(u.ram().rate_divider, 2);
}

#[test]
fn invalid_values_and_unknown_fields_get_a_nak_with_the_partial_reply() {
    let mut u = power_up();
    // Divider 3 is undefined: NAK alone.
    let a = ask(&mut u, &frame(b"SF", &[1, 0x00, 0x01, 0x00, 0x03]));
    assert_eq!(a.frames, nak(b"SF"));
    // Baud code 4 undefined, type "PK" not a continuous type, field 0x0042 unknown.
    for bad in [
        [0x00, 0x02, 0x00, 0x04],
        [0x00, 0x03, 0x50, 0x4B],
        [0x00, 0x42, 0, 1],
    ] {
        let mut p = vec![1u8];
        p.extend_from_slice(&bad);
        assert_eq!(ask(&mut u, &frame(b"SF", &p)).frames, nak(b"SF"));
    }
    // One good field (rate 50 Hz) with one unknown: reply listing the good one, then NAK.
    let a = ask(
        &mut u,
        &frame(b"SF", &[2, 0x00, 0x01, 0x00, 0x02, 0x00, 0x42, 0x00, 0x01]),
    );
    let mut expected = frame(b"SF", &[1, 0x00, 0x01]);
    expected.extend(nak(b"SF"));
    assert_eq!(a.frames, expected);
    assert_eq!(u.ram().rate_divider, 2);
    // GF of a known and an unknown ID: values of the known, then NAK.
    let a = ask(&mut u, &frame(b"GF", &[2, 0x00, 0x02, 0x00, 0x42]));
    let mut expected = frame(b"GF", &[1, 0x00, 0x02, 0x00, 0x02]);
    expected.extend(nak(b"GF"));
    assert_eq!(a.frames, expected);
}

#[test]
fn unknown_requests_and_malformed_payloads_are_naked() {
    let mut u = power_up();
    assert_eq!(ask(&mut u, &frame(b"ZZ", &[])).frames, nak(b"ZZ"));
    // A ping with a payload, a SF whose count does not match its length.
    assert_eq!(ask(&mut u, &frame(b"PK", &[1])).frames, nak(b"PK"));
    assert_eq!(
        ask(&mut u, &frame(b"SF", &[2, 0, 1, 0, 1])).frames,
        nak(b"SF")
    );
    // GP of a type that is not a packet.
    assert_eq!(ask(&mut u, &frame(b"GP", b"PK")).frames, nak(b"GP"));
}

#[test]
fn get_packet_of_output_types_is_left_to_the_caller() {
    let mut u = power_up();
    let a = ask(&mut u, &GP_A2);
    assert!(a.frames.is_empty());
    assert_eq!(a.get_packet, Some(PacketType::A2));
    assert_eq!(ask(&mut u, &GP_N1).get_packet, Some(PacketType::N1));
    // VR is answered by the model: 1.0.0 stage 0 build 0.
    let vr = ask(&mut u, &frame(b"GP", b"VR"));
    assert_eq!(vr.frames, frame(b"VR", &[1, 0, 0, 0, 0]));
}

#[test]
fn requests_split_anywhere_and_back_to_back_get_answers_in_order() {
    let mut u = power_up();
    let mut stream = PING.to_vec();
    stream.extend_from_slice(&GF_123);
    stream.extend_from_slice(&CH);
    let mut types = Vec::new();
    for chunk in stream.chunks(3) {
        u.receive(chunk, |r| types.push(r.request));
    }
    assert_eq!(types, vec![PacketType::PK, PacketType::GF, PacketType::CH]);
    let mut types = Vec::new();
    u.receive(&stream, |r| types.push(r.request));
    assert_eq!(types, vec![PacketType::PK, PacketType::GF, PacketType::CH]);
}

#[test]
fn quirks_ignore_nak_and_keep_rate() {
    let mut u = Unit::new(
        UnitFields::POWER_UP,
        Quirks {
            ignore_requests: true,
            ..Quirks::default()
        },
    );
    assert!(ask(&mut u, &PING).frames.is_empty());
    let mut u = Unit::new(
        UnitFields::POWER_UP,
        Quirks {
            nak_output_config: true,
            ..Quirks::default()
        },
    );
    assert_eq!(ask(&mut u, &SF_RATE_100).frames, nak(b"SF"));
    let mut u = Unit::new(
        UnitFields::POWER_UP,
        Quirks {
            keep_rate: true,
            ..Quirks::default()
        },
    );
    assert_eq!(
        ask(&mut u, &SF_RATE_100).frames,
        frame(b"SF", &[1, 0x00, 0x01])
    );
    assert_eq!(u.ram().rate_divider, 5);
}
