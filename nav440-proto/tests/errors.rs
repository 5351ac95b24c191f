//! `Display` and `core::error::Error` of every error type of the crate: the messages, and
//! that each works as a `Box<dyn Error>` with its source chain.

use core::error::Error as _;
use nav440_proto::boot::BootError;
use nav440_proto::driver::Error as DriverError;
use nav440_proto::*;

#[test]
fn decode_error_names_type_and_lengths() {
    // A 29-byte A2 payload (A2 is 30 bytes per the protocol document).
    let e = Packet::decode(Frame {
        packet_type: PacketType::A2,
        payload: &[0; 29],
    })
    .unwrap_err();
    assert_eq!(e.to_string(), "A2 payload of 29 bytes, expected 30");
    // A NAK is two bytes; an SF reply of n=2 IDs is 1 + 2*2 bytes.
    let e = NakFields::default().payload();
    let e = Packet::decode(Frame {
        packet_type: PacketType::NAK,
        payload: &e[..1],
    })
    .unwrap_err();
    assert_eq!(e.to_string(), "NAK payload of 1 bytes, expected 2");
    let e = Packet::decode(Frame {
        packet_type: PacketType::SF,
        payload: &[2, 0, 1],
    })
    .unwrap_err();
    assert_eq!(e.to_string(), "SF payload of 3 bytes, expected 5");
    assert!(e.source().is_none());
}

#[test]
fn encode_error_messages() {
    // The ping frame is 7 bytes.
    let e = command::ping(&mut [0u8; 3]).unwrap_err();
    assert_eq!(e, EncodeError::BufferTooSmall { needed: 7 });
    assert_eq!(
        e.to_string(),
        "output buffer too small: the frame needs 7 bytes"
    );
    let mut out = [0u8; 300];
    let e = encode_frame(PacketType::CH, &[0u8; 256], &mut out).unwrap_err();
    assert_eq!(
        e.to_string(),
        "payload of 256 bytes exceeds the maximum of 255 bytes"
    );
}

#[test]
fn driver_error_messages_and_source() {
    type E = DriverError<&'static str>;
    let cases: [(E, &str); 6] = [
        (DriverError::Serial("EIO"), "serial port error: \"EIO\""),
        (
            DriverError::WriteZero,
            "serial port error: it accepted no byte",
        ),
        (
            DriverError::Encode(EncodeError::BufferTooSmall { needed: 7 }),
            "request could not be encoded: output buffer too small: the frame needs 7 bytes",
        ),
        (
            DriverError::Nak {
                request: PacketType::SF,
            },
            "unit rejected (NAK) SF",
        ),
        (
            DriverError::NotAccepted {
                requested: 3,
                accepted: 2,
            },
            "unit accepted only 2 of the 3 fields requested",
        ),
        (DriverError::NoReply, "no reply within the reply time-out"),
    ];
    for (e, msg) in cases {
        assert_eq!(e.to_string(), msg);
        let has_source = matches!(e, DriverError::Encode(_));
        assert_eq!(e.source().is_some(), has_source, "{msg}");
    }
    let e: E = DriverError::Encode(EncodeError::PayloadTooLong { len: 300 });
    assert_eq!(
        e.source().unwrap().to_string(),
        "payload of 300 bytes exceeds the maximum of 255 bytes"
    );
}

#[test]
fn boot_error_is_an_error_with_source() {
    let e: BootError<&'static str> = BootError::Encode(EncodeError::BufferTooSmall { needed: 9 });
    assert_eq!(
        e.to_string(),
        "request could not be encoded: output buffer too small: the frame needs 9 bytes"
    );
    assert_eq!(
        e.source().map(|s| s.to_string()).as_deref(),
        Some("output buffer too small: the frame needs 9 bytes")
    );
    let e: BootError<&'static str> = BootError::WriteZero;
    assert!(e.source().is_none());
}

/// Every error type converts into `Box<dyn Error>` with `?` (the host CLI's way).
#[test]
fn every_error_boxes() {
    fn run() -> Result<(), Box<dyn std::error::Error>> {
        Packet::decode(Frame {
            packet_type: PacketType::B1,
            payload: &[0; 17],
        })?;
        Ok(())
    }
    assert_eq!(
        run().unwrap_err().to_string(),
        "B1 payload of 17 bytes, expected 18"
    );
    let boxed: [Box<dyn std::error::Error>; 4] = [
        Box::new(EncodeError::PayloadTooLong { len: 256 }),
        Box::new(DriverError::<u8>::NoReply),
        Box::new(BootError::<u8>::WriteZero),
        Box::new(DecodeError::Length {
            packet_type: PacketType::GP,
            expected: 2,
            actual: 0,
        }),
    ];
    let msgs: Vec<String> = boxed.iter().map(|e| e.to_string()).collect();
    assert_eq!(
        msgs,
        [
            "payload of 256 bytes exceeds the maximum of 255 bytes",
            "no reply within the reply time-out",
            "serial port error: it accepted no byte",
            "GP payload of 0 bytes, expected 2",
        ]
    );
}
