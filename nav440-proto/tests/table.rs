//! The packet table: kinds, units, layouts, and the role-based readers (attitude, body rates,
//! time, BIT) generated from it.
//!
//! Expected values come from docs/NAV440-PROTOCOL.md (scales, payload lengths, the
//! synthetic A2 vector) or are a property against the per-type accessors.

use nav440_proto::*;
use proptest::prelude::*;

/// The synthetic A2 of the protocol document: roll 10 deg, pitch -5, yaw 90, rates 1/2/3
/// deg/s, accel 0/0/1 g, temperatures 25 degC, timeITOW 123456 ms, BIT 0.
const SYNTH_A2: &str = "55 55 41 32 1e 07 1c fc 72 40 00 00 34 00 68 00 9c 00 00 00 00 0c cd 20 00 20 00 20 00 00 01 e2 40 00 00 9d 25";

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

fn decode(t: PacketType, payload: &[u8]) -> Packet<'_> {
    Packet::decode(Frame {
        packet_type: t,
        payload,
    })
    .unwrap()
}

#[test]
fn kinds_scale_by_the_protocol_document() {
    use core::f64::consts::PI;
    // (kind, unit, value of one LSB per the document, computed here in f64).
    let doc: [(Kind, Option<Unit>, Option<f64>); 15] = [
        (Kind::Angle, Some(Unit::Rad), Some(2.0 * PI / 65536.0)),
        (Kind::Rate, Some(Unit::RadPerS), Some(7.0 * PI / 65536.0)),
        (Kind::Accel, Some(Unit::G), Some(20.0 / 65536.0)),
        (Kind::Mag, Some(Unit::Gauss), Some(2.0 / 65536.0)),
        (Kind::Temp, Some(Unit::DegC), Some(200.0 / 65536.0)),
        (Kind::Velocity, Some(Unit::MPerS), Some(512.0 / 65536.0)),
        (
            Kind::LatLon,
            Some(Unit::Rad),
            Some(2.0 * PI / 4_294_967_296.0),
        ),
        (Kind::Altitude, Some(Unit::M), Some(0.25)),
        (
            Kind::DeltaVelocity,
            Some(Unit::MPerS),
            Some(200.0 / 4_294_967_296.0),
        ),
        (
            Kind::DeltaAngle,
            Some(Unit::Rad),
            Some(7.0 * PI / 4_294_967_296.0),
        ),
        (Kind::Itow, Some(Unit::Ms), Some(1.0)),
        (Kind::GpsItow, Some(Unit::Ms), Some(1.0)),
        (Kind::Status, None, None),
        (Kind::Counter, None, None),
        (Kind::Code, None, None),
    ];
    for (kind, unit, lsb) in doc {
        assert_eq!(kind.unit(), unit, "{kind:?}");
        match (kind.lsb(), lsb) {
            (None, None) => {}
            // The f32 scale constants are within one f32 ulp (2^-23) of the exact value.
            (Some(got), Some(want)) => assert!(
                ((got - want) / want).abs() < 1.2e-7,
                "{kind:?}: {got} vs {want}"
            ),
            other => panic!("{kind:?}: {other:?}"),
        }
        assert_eq!(kind.is_flags(), kind == Kind::Status);
    }
}

#[test]
fn units_have_their_symbols() {
    let want = [
        (Unit::Rad, "rad"),
        (Unit::Deg, "deg"),
        (Unit::RadPerS, "rad/s"),
        (Unit::DegPerS, "deg/s"),
        (Unit::G, "g"),
        (Unit::Gauss, "gauss"),
        (Unit::DegC, "degC"),
        (Unit::MPerS, "m/s"),
        (Unit::M, "m"),
        (Unit::Ms, "ms"),
    ];
    assert_eq!(Unit::ALL.len(), want.len());
    for (u, s) in want {
        assert_eq!(u.symbol(), s);
        assert_eq!(u.to_string(), s);
        assert_eq!(Unit::from_symbol(s), Some(u));
    }
    assert_eq!(Unit::from_symbol("furlong"), None);
}

/// Every fixed packet's table line: (type, payload length per the document, fields).
fn tables() -> [(PacketType, usize, &'static [FieldInfo]); 12] {
    [
        (PacketType::S0, 30, S0::FIELDS),
        (PacketType::S1, 24, S1::FIELDS),
        (PacketType::S2, 28, S2::FIELDS),
        (PacketType::A0, 30, A0::FIELDS),
        (PacketType::A1, 32, A1::FIELDS),
        (PacketType::A2, 30, A2::FIELDS),
        (PacketType::N0, 32, N0::FIELDS),
        (PacketType::N1, 42, N1::FIELDS),
        (PacketType::B1, 18, B1::FIELDS),
        (PacketType::T0, 28, T0::FIELDS),
        (PacketType::VR, 5, Vr::FIELDS),
        (PacketType::NAK, 2, Nak::FIELDS),
    ]
}

#[test]
fn table_layouts_tile_the_documented_lengths() {
    for (t, len, fields) in tables() {
        let mut at = 0;
        for f in fields {
            assert_eq!(f.offset, at, "{t} {}", f.name);
            let wire = match f.kind {
                Kind::LatLon | Kind::DeltaVelocity | Kind::DeltaAngle | Kind::Itow => 4,
                Kind::Code => f.size, // U1 (VR) or U2 (NAK)
                _ => 2,
            };
            assert_eq!(f.size, wire, "{t} {}", f.name);
            at += f.size;
        }
        assert_eq!(at, len, "{t}");
        // Streamable output types are exactly S0..T0, with their lengths.
        let stream = !matches!(t, PacketType::VR | PacketType::NAK);
        assert_eq!(t.output_payload_len(), stream.then_some(len), "{t}");
        // The table's line, by type.
        assert_eq!(t.payload_fields(), Some(fields), "{t}");
        // At most one field per role; roles only on fields of the matching kind.
        for f in fields {
            if let Some(r) = f.role {
                assert_eq!(fields.iter().filter(|g| g.role == Some(r)).count(), 1);
                let ok = match r {
                    Role::Roll | Role::Pitch | Role::Yaw => f.kind == Kind::Angle,
                    Role::P | Role::Q | Role::R => f.kind == Kind::Rate,
                    Role::Time => matches!(f.kind, Kind::Itow | Kind::GpsItow),
                    Role::Bit => f.kind == Kind::Status && f.name == "bit",
                };
                assert!(ok, "{t} {} {r:?}", f.name);
            }
        }
    }
    assert_eq!(PacketType::ID.output_payload_len(), None);
    assert_eq!(PacketType::PK.output_payload_len(), None);
    for t in [
        PacketType::ID,
        PacketType::PK,
        PacketType::GF,
        PacketType(*b"zz"),
    ] {
        assert_eq!(t.payload_fields(), None, "{t}");
    }
}

#[test]
fn which_packets_carry_attitude_rates_time_and_bit() {
    // (type, attitude, body rates, yaw sample, time, BIT), per the document's layouts.
    let want = [
        (PacketType::S0, false, true, false, true, true),
        (PacketType::S1, false, true, false, false, true),
        (PacketType::S2, false, false, false, false, true),
        (PacketType::A0, true, true, true, true, true),
        (PacketType::A1, true, true, true, true, true),
        (PacketType::A2, true, true, true, true, true),
        (PacketType::N0, true, true, true, true, true),
        (PacketType::N1, true, true, true, true, true),
        (PacketType::B1, true, false, true, true, true),
        (PacketType::T0, false, false, false, false, true),
        (PacketType::VR, false, false, false, false, false),
        (PacketType::NAK, false, false, false, false, false),
    ];
    for (t, att, rates, yaw, time, bit) in want {
        let len = tables().iter().find(|x| x.0 == t).unwrap().1;
        let payload = vec![0u8; len];
        let p = decode(t, &payload);
        assert_eq!(p.attitude().is_some(), att, "{t}");
        assert_eq!(p.body_rates().is_some(), rates, "{t}");
        assert_eq!(p.yaw_sample().is_some(), yaw, "{t}");
        assert_eq!(p.time() != TimeStamp::None, time, "{t}");
        assert_eq!(p.bit().is_some(), bit, "{t}");
    }
    for p in [Packet::Ping, Packet::Echo(&[1]), Packet::AlgorithmReset] {
        assert_eq!(p.attitude(), None);
        assert_eq!(p.body_rates(), None);
        assert_eq!(p.bit(), None);
    }
}

#[test]
fn attitude_of_the_synthetic_a2_is_the_documented_one() {
    let v = hex(SYNTH_A2);
    let payload = &v[5..v.len() - 2];
    let p = decode(PacketType::A2, payload);
    let lsb_deg = 360.0 / 65536.0;
    let lsb_dps = 1260.0 / 65536.0;
    let a = p.attitude().unwrap();
    assert!((a.roll_deg - 10.0).abs() <= lsb_deg, "{a:?}");
    assert!((a.pitch_deg + 5.0).abs() <= lsb_deg, "{a:?}");
    assert!((a.yaw_deg - 90.0).abs() <= lsb_deg, "{a:?}");
    let w = p.body_rates().unwrap();
    assert!((w.p_deg_s - 1.0).abs() <= lsb_dps, "{w:?}");
    assert!((w.q_deg_s - 2.0).abs() <= lsb_dps, "{w:?}");
    assert!((w.r_deg_s - 3.0).abs() <= lsb_dps, "{w:?}");
    assert_eq!(p.time(), TimeStamp::Itow(123_456));
    assert_eq!(p.bit(), Some(Bit(0)));
}

#[test]
fn field_visitor_reports_each_fields_kind_and_unit() {
    for (t, len, fields) in tables() {
        let payload: Vec<u8> = (0..len as u8).map(|i| i.wrapping_mul(37)).collect();
        let p = decode(t, &payload);
        let mut seen = Vec::new();
        p.for_each_field(|f| seen.push(f));
        assert_eq!(seen.len(), fields.len(), "{t}");
        for (f, info) in seen.iter().zip(fields) {
            assert_eq!((f.name, f.kind), (info.name, info.kind), "{t}");
            assert_eq!(f.si.map(|q| q.unit), info.kind.unit(), "{t} {}", f.name);
            assert_eq!(f.flags, info.kind == Kind::Status);
        }
    }
}

proptest! {
    /// The role readers return exactly the per-type accessors, for any payload.
    #[test]
    fn role_readers_equal_the_typed_accessors(bytes in proptest::collection::vec(any::<u8>(), 42)) {
        macro_rules! check {
            ($t:ident, $yaw:ident) => {{
                let payload = &bytes[..$t::LEN];
                let p = decode(PacketType::$t, payload);
                let Packet::$t(v) = p else { panic!() };
                let a = p.attitude().unwrap();
                prop_assert_eq!(a.roll_deg.to_bits(), v.roll_deg().to_bits());
                prop_assert_eq!(a.pitch_deg.to_bits(), v.pitch_deg().to_bits());
                prop_assert_eq!(a.yaw_deg.to_bits(), v.$yaw().to_bits());
                let s = p.yaw_sample().unwrap();
                prop_assert_eq!(s.yaw_deg.to_bits(), v.$yaw().to_bits());
                prop_assert_eq!(s.yaw_rate_deg_s.to_bits(), v.rate_z_deg_s().to_bits());
                prop_assert_eq!(s.time, p.time());
                prop_assert_eq!(p.bit(), Some(v.bit_flags()));
            }};
        }
        check!(A0, yaw_mag_deg);
        check!(A1, yaw_mag_deg);
        check!(A2, yaw_true_deg);
        check!(N0, yaw_true_deg);
        check!(N1, yaw_true_deg);
        check!(B1, yaw_deg);
        macro_rules! rates {
            ($t:ident) => {{
                let p = decode(PacketType::$t, &bytes[..$t::LEN]);
                let Packet::$t(v) = p else { panic!() };
                let w = p.body_rates().unwrap();
                prop_assert_eq!(w.p_deg_s.to_bits(), v.rate_x_deg_s().to_bits());
                prop_assert_eq!(w.q_deg_s.to_bits(), v.rate_y_deg_s().to_bits());
                prop_assert_eq!(w.r_deg_s.to_bits(), v.rate_z_deg_s().to_bits());
            }};
        }
        rates!(S0);
        rates!(S1);
        rates!(A0);
        rates!(A1);
        rates!(A2);
        rates!(N0);
        rates!(N1);
        // Time stamps: U4 timeITOW or U2 GPSITOW at the table's offset.
        let a1 = decode(PacketType::A1, &bytes[..32]);
        let Packet::A1(v) = a1 else { panic!() };
        prop_assert_eq!(a1.time(), TimeStamp::Itow(v.time_itow()));
        let n0 = decode(PacketType::N0, &bytes[..32]);
        let Packet::N0(v) = n0 else { panic!() };
        prop_assert_eq!(n0.time(), TimeStamp::GpsItow(v.gps_itow()));
    }
}

/// The packet table as docs/PACKETS.md shows it: one markdown table per packet.
fn markdown_table() -> String {
    let mut out = String::new();
    for (t, len, fields) in tables() {
        let stream = if t.output_payload_len().is_some() {
            "stream"
        } else {
            "reply"
        };
        out.push_str(&format!(
            "#### {t} ({len} bytes, {stream})\n\n| field | kind | offset | size | unit | role |\n|---|---|---:|---:|---|---|\n"
        ));
        for f in fields {
            let unit = f.kind.unit().map_or("-", Unit::symbol);
            let role = f.role.map_or("-".to_string(), |r| format!("{r:?}"));
            out.push_str(&format!(
                "| `{}` | {:?} | {} | {} | {unit} | {role} |\n",
                f.name, f.kind, f.offset, f.size
            ));
        }
        out.push('\n');
    }
    out
}

/// docs/PACKETS.md shows the table the code has (regenerate the section with
/// `PRINT_PACKET_TABLE=1 cargo test -p nav440-proto --test table -- --nocapture docs`).
#[test]
fn docs_show_the_table_of_the_code() {
    let table = markdown_table();
    if std::env::var_os("PRINT_PACKET_TABLE").is_some() {
        println!("{table}");
    }
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/PACKETS.md"))
        .expect("docs/PACKETS.md");
    assert!(
        doc.contains(table.trim_end()),
        "docs/PACKETS.md's packet table differs from the code's"
    );
}

#[test]
fn bit_flags_are_named_as_in_the_document() {
    // BIT word per the protocol document: bit 0 masterFail, 1 hardwareError, 2 comError,
    // 3 softwareError, 8 masterStatus, 9 hardwareStatus, 10 comStatus, 11 softwareStatus,
    // 12 sensorStatus.
    let doc = [
        (0, "masterFail"),
        (1, "hardwareError"),
        (2, "comError"),
        (3, "softwareError"),
        (8, "masterStatus"),
        (9, "hardwareStatus"),
        (10, "comStatus"),
        (11, "softwareStatus"),
        (12, "sensorStatus"),
    ];
    for (bit, name) in doc {
        let b = Bit(1 << bit);
        assert_eq!(b.names().collect::<Vec<_>>(), [name]);
        assert_eq!(b.is_fatal(), bit == 0);
    }
    // A healthy unit can show 0x0002 (hardwareError alone).
    assert_eq!(Bit(0x0002).to_string(), "0x0002 (hardwareError)");
    assert_eq!(Bit(0x0101).to_string(), "0x0101 (masterFail, masterStatus)");
    assert_eq!(Bit(0).to_string(), "0x0000");
    // Reserved bits (4-7, 13-15) have no name but show in the hex.
    assert_eq!(Bit(0x00F0).to_string(), "0x00F0");
}

proptest! {
    /// The reply decoder the driver's wait links (`Packet::decode_reply`) gives what the full
    /// decoder gives for the replies (NAK, PK, SF, WF, GF, RF: the packet or the same error),
    /// and leaves every other type undecoded (`Packet::Unknown` of the same frame).
    #[test]
    fn the_reply_decoder_is_the_full_one_for_replies(
        k in 0..PacketType::KNOWN.len() + 1,
        payload in proptest::collection::vec(any::<u8>(), 0..40),
    ) {
        let t = PacketType::KNOWN.get(k).copied().unwrap_or(PacketType(*b"zz"));
        let frame = Frame { packet_type: t, payload: &payload };
        let replies = [
            PacketType::NAK,
            PacketType::PK,
            PacketType::SF,
            PacketType::WF,
            PacketType::GF,
            PacketType::RF,
        ];
        let reply = Packet::decode_reply(frame);
        if replies.contains(&t) {
            prop_assert_eq!(reply, Packet::decode(frame));
        } else {
            prop_assert_eq!(reply, Ok(Packet::Unknown(frame)));
        }
    }
}
