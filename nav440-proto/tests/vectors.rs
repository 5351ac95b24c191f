//! Every test vector of docs/NAV440-PROTOCOL.md, byte for byte and value for value.

use nav440_proto::*;

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect()
}

fn frames(bytes: &[u8]) -> Vec<(PacketType, Vec<u8>)> {
    let mut p = Parser::new();
    let mut out = Vec::new();
    p.feed(bytes, |f| out.push((f.packet_type, f.payload.to_vec())));
    out
}

fn enc(f: impl FnOnce(&mut [u8]) -> Result<usize, EncodeError>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = f(&mut buf).unwrap();
    buf[..n].to_vec()
}

#[test]
fn crc_catalogue_check_value() {
    // CRC-16/SPI-FUJITSU check("123456789") = 0xE5CC, for every table variant.
    assert_eq!(crc16(b"123456789"), 0xE5CC);
    assert_eq!(
        <crc::Table<0> as Crc16Table>::checksum(b"123456789"),
        0xE5CC
    );
    assert_eq!(
        <crc::Table<1> as Crc16Table>::checksum(b"123456789"),
        0xE5CC
    );
    assert_eq!(
        <crc::Table<16> as Crc16Table>::checksum(b"123456789"),
        0xE5CC
    );
    assert_eq!(crc16::ALGORITHM.init, 0x1D0F);
    assert_eq!(crc16::ALGORITHM.poly, 0x1021);
}

#[test]
fn ping_vector() {
    let v = hex("55 55 50 4B 00 9E F4");
    assert_eq!(enc(command::ping), v);
    assert_eq!(frames(&v), vec![(PacketType::PK, vec![])]);
    let f = Frame {
        packet_type: PacketType::PK,
        payload: &[],
    };
    assert_eq!(Packet::decode(f), Ok(Packet::Ping));
}

#[test]
fn gp_vectors() {
    let a2 = hex("55 55 47 50 02 41 32 B4 C5");
    let n1 = hex("55 55 47 50 02 4E 31 94 98");
    assert_eq!(enc(|o| command::get_packet(PacketType::A2, o)), a2);
    assert_eq!(enc(|o| command::get_packet(PacketType::N1, o)), n1);
    let f = frames(&a2);
    assert_eq!(f, vec![(PacketType::GP, vec![0x41, 0x32])]);
    let fr = Frame {
        packet_type: PacketType::GP,
        payload: &f[0].1,
    };
    assert_eq!(Request::decode(fr), Ok(Request::GetPacket(PacketType::A2)));
    assert_eq!(Packet::decode(fr), Ok(Packet::GetPacket(PacketType::A2)));
}

#[test]
fn sr_ar_ch_vectors() {
    let sr = hex("55 55 53 52 00 7E 4F");
    let ar = hex("55 55 41 52 00 53 4C");
    let ch = hex("55 55 43 48 02 01 02 98 38");
    assert_eq!(enc(command::software_reset), sr);
    assert_eq!(enc(command::algorithm_reset), ar);
    assert_eq!(enc(|o| command::echo(&[1, 2], o)), ch);
    assert_eq!(frames(&sr), vec![(PacketType::SR, vec![])]);
    assert_eq!(frames(&ar), vec![(PacketType::AR, vec![])]);
    assert_eq!(frames(&ch), vec![(PacketType::CH, vec![1, 2])]);
}

#[test]
fn sf_gf_wf_vectors() {
    let sf_rate = hex("55 55 53 46 05 01 00 01 00 01 50 A0");
    let sf_type = hex("55 55 53 46 05 01 00 03 41 32 06 0D");
    let gf = hex("55 55 47 46 07 03 00 01 00 02 00 03 04 80");
    let wf = hex("55 55 57 46 05 01 00 01 00 02 6F AE");
    assert_eq!(
        enc(|o| command::set_fields(
            &[(FieldId::PACKET_RATE_DIVIDER, PacketRate::Hz100.divider())],
            o
        )),
        sf_rate
    );
    assert_eq!(
        enc(|o| command::set_fields(&[(FieldId::PACKET_TYPE, PacketType::A2.code())], o)),
        sf_type
    );
    assert_eq!(
        enc(|o| command::get_fields(
            &[
                FieldId::PACKET_RATE_DIVIDER,
                FieldId::BAUD_RATE,
                FieldId::PACKET_TYPE
            ],
            o
        )),
        gf
    );
    assert_eq!(
        enc(|o| command::write_fields(
            &[(FieldId::PACKET_RATE_DIVIDER, PacketRate::Hz50.divider())],
            o
        )),
        wf
    );
    // The unit side decodes them back.
    let f = frames(&sf_type);
    let req = Request::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap();
    match req {
        Request::SetFields(v) => {
            assert_eq!(v.len(), 1);
            assert_eq!(v.get(FieldId::PACKET_TYPE), Some(0x4132));
        }
        other => panic!("{other:?}"),
    }
    let f = frames(&gf);
    match Request::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap()
    {
        Request::GetFields(ids) => {
            assert_eq!(ids.iter().map(|i| i.0).collect::<Vec<_>>(), vec![1, 2, 3])
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn replies_decode() {
    // SF reply: n=2, IDs 3 and 1; GF reply: n=1, (1, 4).
    let sf = enc(|o| {
        command::fields_accepted_reply(
            PacketType::SF,
            &[FieldId::PACKET_TYPE, FieldId::PACKET_RATE_DIVIDER],
            o,
        )
    });
    assert_eq!(&sf[..10], &[0x55, 0x55, b'S', b'F', 5, 2, 0, 3, 0, 1]);
    let f = frames(&sf);
    match Packet::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap()
    {
        Packet::SetFields(ids) => {
            assert_eq!(ids.len(), 2);
            assert!(ids.contains(FieldId::PACKET_TYPE));
            assert!(!ids.contains(FieldId::BAUD_RATE));
        }
        other => panic!("{other:?}"),
    }
    let gf = enc(|o| command::field_values_reply(PacketType::GF, &[(FieldId(1), 4)], o));
    assert_eq!(&gf[..10], &[0x55, 0x55, b'G', b'F', 5, 1, 0, 1, 0, 4]);
    let f = frames(&gf);
    match Packet::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap()
    {
        Packet::GetFields(v) => assert_eq!(v.get(FieldId(1)), Some(4)),
        other => panic!("{other:?}"),
    }
    let nak = enc(|o| command::nak(PacketType::SF, o));
    assert_eq!(&nak[..7], &[0x55, 0x55, 0x15, 0x15, 2, b'S', b'F']);
    let f = frames(&nak);
    match Packet::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap()
    {
        Packet::Nak(n) => assert_eq!(n.failed_type(), PacketType::SF),
        other => panic!("{other:?}"),
    }
    assert_eq!(PacketType::NAK.name(), "NAK");
}

const SYNTH_A2: &str = "55 55 41 32 1e 07 1c fc 72 40 00 00 34 00 68 00 9c 00 00 00 00 0c cd 20 00 20 00 20 00 00 01 e2 40 00 00 9d 25";

#[test]
fn synthetic_a2_decodes_to_its_physical_values() {
    let v = hex(SYNTH_A2);
    let f = frames(&v);
    assert_eq!(f.len(), 1);
    let p = Packet::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap();
    let Packet::A2(a) = p else { panic!("{p:?}") };
    // One LSB: 360/65536 deg, 1260/65536 deg/s, 20/65536 g, 200/65536 degC.
    let close = |x: f32, want: f32, lsb: f32| assert!((x - want).abs() <= lsb, "{x} vs {want}");
    close(a.roll_deg(), 10.0, 360.0 / 65536.0);
    close(a.pitch_deg(), -5.0, 360.0 / 65536.0);
    close(a.yaw_true_deg(), 90.0, 360.0 / 65536.0);
    close(a.yaw_true_rad(), core::f32::consts::FRAC_PI_2, 1e-4);
    close(a.rate_x_deg_s(), 1.0, 1260.0 / 65536.0);
    close(a.rate_y_deg_s(), 2.0, 1260.0 / 65536.0);
    close(a.rate_z_deg_s(), 3.0, 1260.0 / 65536.0);
    close(
        a.rate_z_rad_s(),
        3.0f32.to_radians(),
        7.0 * core::f32::consts::PI / 65536.0,
    );
    close(a.accel_x_g(), 0.0, 20.0 / 65536.0);
    close(a.accel_y_g(), 0.0, 20.0 / 65536.0);
    close(a.accel_z_g(), 1.0, 20.0 / 65536.0);
    close(a.rate_temp_x_degc(), 25.0, 200.0 / 65536.0);
    close(a.rate_temp_y_degc(), 25.0, 200.0 / 65536.0);
    close(a.rate_temp_z_degc(), 25.0, 200.0 / 65536.0);
    assert_eq!(a.time_itow(), 123_456);
    assert_eq!(a.bit(), 0);
    assert!(!a.bit_flags().master_fail());
    let s = p.yaw_sample().unwrap();
    assert_eq!(s.time, TimeStamp::Itow(123_456));
    close(s.yaw_deg, 90.0, 360.0 / 65536.0);
    close(s.yaw_rate_deg_s, 3.0, 1260.0 / 65536.0);
    // And the fields re-encode to the same bytes.
    assert_eq!(enc(|o| a.fields().encode(o)), v);
}

#[test]
fn real_s1_frame_decodes_to_the_documented_values() {
    let v = hex("55 55 53 31 18 ff e0 00 16 0c c0 ff fe ff f9 ff ff 27 eb 27 eb 27 eb 27 f7 28 f5 00 02 23 bc");
    let f = frames(&v);
    assert_eq!(f.len(), 1, "CRC of the real frame must check");
    let p = Packet::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap();
    let Packet::S1(s) = p else { panic!("{p:?}") };
    // Values as printed in the protocol document, to its precision.
    let round = |x: f32, digits: i32| (x * 10f32.powi(digits)).round() / 10f32.powi(digits);
    assert_eq!(round(s.accel_x_g(), 5), -0.00977);
    assert_eq!(round(s.accel_y_g(), 5), 0.00671);
    assert_eq!(round(s.accel_z_g(), 5), 0.99609);
    assert_eq!(round(s.rate_x_deg_s(), 4), -0.0385);
    assert_eq!(round(s.rate_y_deg_s(), 4), -0.1346);
    assert_eq!(round(s.rate_z_deg_s(), 4), -0.0192);
    assert_eq!(round(s.rate_temp_x_degc(), 2), 31.19);
    assert_eq!(round(s.rate_temp_y_degc(), 2), 31.19);
    assert_eq!(round(s.rate_temp_z_degc(), 2), 31.19);
    assert_eq!(round(s.board_temp_degc(), 2), 31.22);
    assert_eq!(s.counter(), 10485);
    assert_eq!(s.bit(), 0x0002);
    let b = s.bit_flags();
    assert!(b.hardware_error() && !b.master_fail() && !b.is_fatal());
    assert!(p.yaw_sample().is_none());
}

#[test]
fn wrong_length_is_a_typed_error() {
    let payload = [0u8; 29];
    let f = Frame {
        packet_type: PacketType::A2,
        payload: &payload,
    };
    assert_eq!(
        Packet::decode(f),
        Err(DecodeError::Length {
            packet_type: PacketType::A2,
            expected: 30,
            actual: 29
        })
    );
    let f = Frame {
        packet_type: PacketType::SF,
        payload: &[2, 0, 1],
    };
    assert_eq!(
        Packet::decode(f),
        Err(DecodeError::Length {
            packet_type: PacketType::SF,
            expected: 5,
            actual: 3
        })
    );
    let f = Frame {
        packet_type: PacketType::PK,
        payload: &[1],
    };
    assert!(Packet::decode(f).is_err());
    let f = Frame {
        packet_type: PacketType::ID,
        payload: &[1, 2, 3, 4],
    };
    assert!(Packet::decode(f).is_err());
}

#[test]
fn unknown_lowercase_type_passes_through_raw() {
    // An OpenIMU-style "z1" packet with a little-endian payload, then an A2.
    let mut buf = [0u8; 128];
    let n = encode_frame(PacketType(*b"z1"), &[1, 0, 0, 0, 0x55, 0x55], &mut buf).unwrap();
    let m = A2Fields {
        yaw_true: 7,
        ..Default::default()
    }
    .encode(&mut buf[n..])
    .unwrap();
    let f = frames(&buf[..n + m]);
    assert_eq!(f.len(), 2);
    assert_eq!(f[0].0.name(), "z1");
    let p = Packet::decode(Frame {
        packet_type: f[0].0,
        payload: &f[0].1,
    })
    .unwrap();
    assert!(matches!(p, Packet::Unknown(fr) if fr.payload == [1, 0, 0, 0, 0x55, 0x55]));
    assert_eq!(f[1].0, PacketType::A2);
    let mut pr = Parser::new();
    pr.feed(&buf[..n + m], |_| {});
    assert_eq!(pr.stats().other_types, 1);
    assert_eq!(pr.stats().count(PacketType::A2), 1);
    assert_eq!(pr.stats().frames, 2);
}

/// One visited field: (name, raw, (SI value, unit), flags).
type Visited = (&'static str, i64, Option<(f64, &'static str)>, bool);
/// One expected field: (name, raw, (SI value, tolerance, unit), flags).
type Expected<'a> = (&'a str, i64, Option<(f64, f64, &'a str)>, bool);

/// Every field the visitor yields for one packet.
fn visit(p: &Packet<'_>) -> Vec<Visited> {
    let mut out = Vec::new();
    p.for_each_field(|f| {
        out.push((
            f.name,
            f.raw,
            f.si.map(|q| (q.value.to_f64(), q.unit.symbol())),
            f.flags,
        ))
    });
    out
}

fn decode_one(v: &[u8]) -> (PacketType, Vec<u8>) {
    let f = frames(v);
    assert_eq!(f.len(), 1);
    f.into_iter().next().unwrap()
}

/// Checks the visited fields against the expected ones, each SI value within its tolerance.
fn check_fields(got: &[Visited], want: &[Expected<'_>]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert_eq!((g.0, g.1, g.3), (w.0, w.1, w.3), "{g:?} vs {w:?}");
        match (g.2, w.2) {
            (None, None) => {}
            (Some((v, u)), Some((want_v, tol, want_u))) => {
                assert_eq!(u, want_u, "{}", g.0);
                assert!((v - want_v).abs() <= tol, "{}: {v} vs {want_v}", g.0);
            }
            _ => panic!("{g:?} vs {w:?}"),
        }
    }
}

#[test]
fn field_visitor_yields_the_synthetic_a2_values() {
    let (t, payload) = decode_one(&hex(SYNTH_A2));
    let p = Packet::decode(Frame {
        packet_type: t,
        payload: &payload,
    })
    .unwrap();
    // One LSB of each quantity: the document's values are rounded to the nearest LSB.
    let rad = 2.0 * core::f64::consts::PI / 65536.0;
    let rad_s = 7.0 * core::f64::consts::PI / 65536.0;
    let g = 20.0 / 65536.0;
    let degc = 200.0 / 65536.0;
    let d = f64::to_radians;
    check_fields(
        &visit(&p),
        &[
            ("roll", 0x071C, Some((d(10.0), rad, "rad")), false),
            ("pitch", -0x038E, Some((d(-5.0), rad, "rad")), false),
            ("yaw_true", 0x4000, Some((d(90.0), rad, "rad")), false),
            ("rate_x", 0x34, Some((d(1.0), rad_s, "rad/s")), false),
            ("rate_y", 0x68, Some((d(2.0), rad_s, "rad/s")), false),
            ("rate_z", 0x9C, Some((d(3.0), rad_s, "rad/s")), false),
            ("accel_x", 0, Some((0.0, g, "g")), false),
            ("accel_y", 0, Some((0.0, g, "g")), false),
            ("accel_z", 0x0CCD, Some((1.0, g, "g")), false),
            ("rate_temp_x", 0x2000, Some((25.0, degc, "degC")), false),
            ("rate_temp_y", 0x2000, Some((25.0, degc, "degC")), false),
            ("rate_temp_z", 0x2000, Some((25.0, degc, "degC")), false),
            ("time_itow", 123_456, Some((123_456.0, 0.0, "ms")), false),
            ("bit", 0, None, true),
        ],
    );
    // The SI values are exactly the view's accessors.
    let Packet::A2(a) = p else { panic!("{p:?}") };
    let mut yaw = None;
    a.for_each_field(|f| {
        if f.name == "yaw_true" {
            yaw = f.si;
        }
    });
    assert_eq!(
        yaw,
        Some(Quantity {
            value: SiValue::F32(a.yaw_true_rad()),
            unit: Unit::Rad
        })
    );
}

#[test]
fn field_visitor_yields_the_real_s1_values() {
    let v = hex("55 55 53 31 18 ff e0 00 16 0c c0 ff fe ff f9 ff ff 27 eb 27 eb 27 eb 27 f7 28 f5 00 02 23 bc");
    let (t, payload) = decode_one(&v);
    let p = Packet::decode(Frame {
        packet_type: t,
        payload: &payload,
    })
    .unwrap();
    // The document's values, to its printed precision (rates printed in deg/s).
    let dps = |x: f64| x.to_radians();
    check_fields(
        &visit(&p),
        &[
            ("accel_x", -32, Some((-0.00977, 0.5e-5, "g")), false),
            ("accel_y", 22, Some((0.00671, 0.5e-5, "g")), false),
            ("accel_z", 3264, Some((0.99609, 0.5e-5, "g")), false),
            (
                "rate_x",
                -2,
                Some((dps(-0.0385), dps(0.5e-4), "rad/s")),
                false,
            ),
            (
                "rate_y",
                -7,
                Some((dps(-0.1346), dps(0.5e-4), "rad/s")),
                false,
            ),
            (
                "rate_z",
                -1,
                Some((dps(-0.0192), dps(0.5e-4), "rad/s")),
                false,
            ),
            ("rate_temp_x", 0x27EB, Some((31.19, 0.005, "degC")), false),
            ("rate_temp_y", 0x27EB, Some((31.19, 0.005, "degC")), false),
            ("rate_temp_z", 0x27EB, Some((31.19, 0.005, "degC")), false),
            ("board_temp", 0x27F7, Some((31.22, 0.005, "degC")), false),
            ("counter", 10485, None, false),
            ("bit", 0x0002, None, true),
        ],
    );
}

#[test]
fn field_visitor_covers_fixed_packets_only() {
    // T0: fourteen status words; NAK: the failed type code; ID and commands: nothing.
    let t0 = T0Fields {
        com_status: 0x0400,
        ..Default::default()
    }
    .payload();
    let p = Packet::decode(Frame {
        packet_type: PacketType::T0,
        payload: &t0,
    })
    .unwrap();
    let fields = visit(&p);
    assert_eq!(fields.len(), 14);
    assert!(fields.iter().all(|f| f.2.is_none() && f.3));
    assert_eq!(fields[11], ("com_status", 0x0400, None, true));
    let nak = NakFields::for_request(PacketType::SF).payload();
    let p = Packet::decode(Frame {
        packet_type: PacketType::NAK,
        payload: &nak,
    })
    .unwrap();
    assert_eq!(
        visit(&p),
        [("failed_code", i64::from(PacketType::SF.code()), None, false)]
    );
    // N1 latitude / longitude are f64.
    let n1 = N1Fields {
        latitude: 1 << 28,
        ..Default::default()
    }
    .payload();
    let p = Packet::decode(Frame {
        packet_type: PacketType::N1,
        payload: &n1,
    })
    .unwrap();
    let Packet::N1(n) = p else { panic!("{p:?}") };
    let mut lat = None;
    p.for_each_field(|f| {
        if f.name == "latitude" {
            lat = f.si;
        }
    });
    assert_eq!(lat.map(|q| q.value), Some(SiValue::F64(n.latitude_rad())));
    assert!(visit(&Packet::Ping).is_empty());
    assert!(visit(&Packet::Echo(&[1, 2, 3])).is_empty());
}
