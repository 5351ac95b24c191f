//! Property tests of the parser and the codecs (bounded, deterministic seed).

use nav440_proto::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn cfg(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x4E41_5634_3430),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Any plausible frame type: known types, OpenIMU-style lower-case types, NAK.
fn any_type() -> impl Strategy<Value = PacketType> {
    prop_oneof![
        proptest::sample::select(PacketType::KNOWN.to_vec()),
        (b'a'..=b'z', b'0'..=b'z').prop_map(|(a, b)| PacketType([a, b])),
    ]
}

/// Payloads of mostly small lengths, sometimes up to the maximum, biased towards 0x55.
fn any_payload() -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![3 => any::<u8>(), 1 => Just(0x55u8)];
    prop_oneof![
        4 => proptest::collection::vec(byte.clone(), 0..48),
        1 => proptest::collection::vec(byte, 0..=MAX_PAYLOAD),
    ]
}

fn garbage(max: usize) -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![2 => any::<u8>(), 1 => Just(0x55u8)];
    proptest::collection::vec(byte, 0..max)
}

fn encode(t: PacketType, p: &[u8]) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode_frame(t, p, &mut buf).unwrap();
    buf[..n].to_vec()
}

type Owned = (PacketType, Vec<u8>);

fn parse_chunked(bytes: &[u8], cuts: &[usize]) -> (Vec<Owned>, Stats) {
    let mut p = Parser::new();
    let mut out = Vec::new();
    let mut rest = bytes;
    let mut cuts = cuts.iter().cycle();
    while !rest.is_empty() {
        let n = (*cuts.next().unwrap()).clamp(1, rest.len());
        let (a, b) = rest.split_at(n);
        p.feed(a, |f| out.push((f.packet_type, f.payload.to_vec())));
        rest = b;
    }
    (out, *p.stats())
}

/// Emitted frames with their start offsets in `bytes` (fed in one call: all frames borrow it).
fn parse_spans(bytes: &[u8]) -> (Vec<(usize, usize, Owned)>, Stats) {
    let mut p = Parser::new();
    let base = bytes.as_ptr() as usize;
    let mut out = Vec::new();
    p.feed(bytes, |f| {
        let start = f.payload.as_ptr() as usize - base - 5;
        out.push((start, f.wire_len(), (f.packet_type, f.payload.to_vec())));
    });
    (out, *p.stats())
}

/// Zero bytes after a stream: completes (and fails) any pending candidate.
const FLUSH: [u8; MAX_FRAME] = [0; MAX_FRAME];

proptest! {
    #![proptest_config(cfg(96))]

    /// Feeding a stream in any chunking gives the same frames and the same counters.
    #[test]
    fn any_chunking_gives_the_same_frames(
        parts in proptest::collection::vec((garbage(12), any_type(), any_payload()), 1..8),
        tail in garbage(20),
        cuts in proptest::collection::vec(1usize..300, 1..20),
    ) {
        let mut stream = Vec::new();
        for (g, t, p) in &parts {
            stream.extend_from_slice(g);
            stream.extend(encode(*t, p));
        }
        stream.extend_from_slice(&tail);
        let (whole, s_whole) = parse_chunked(&stream, &[stream.len()]);
        let (chunked, s_chunked) = parse_chunked(&stream, &cuts);
        let (bytewise, s_bytewise) = parse_chunked(&stream, &[1]);
        prop_assert_eq!(&whole, &chunked);
        prop_assert_eq!(&whole, &bytewise);
        prop_assert_eq!(s_whole, s_chunked);
        prop_assert_eq!(s_whole, s_bytewise);
        prop_assert_eq!(s_whole.bytes, stream.len() as u64);
    }

    /// `finish` emits the frames that zero filler after the stream would let the parser find
    /// (the filler completes, and fails, every pending candidate), and counts the bytes that
    /// did not complete a frame as skipped.
    #[test]
    fn finish_resolves_what_filler_would(
        parts in proptest::collection::vec((garbage(12), any_type(), any_payload()), 1..8),
        fake_len in any::<u8>(),
        tail in garbage(20),
        cuts in proptest::collection::vec(1usize..300, 1..20),
    ) {
        let mut stream = Vec::new();
        for (i, (g, t, p)) in parts.iter().enumerate() {
            stream.extend_from_slice(g);
            if i + 2 == parts.len() {
                // A false header before the last frame.
                stream.extend_from_slice(&[0x55, 0x55, b'A', b'2', fake_len]);
            }
            stream.extend(encode(*t, p));
        }
        stream.extend_from_slice(&tail);
        let mut flushed = stream.clone();
        flushed.extend_from_slice(&FLUSH);
        let (want, s_flushed) = parse_chunked(&flushed, &[flushed.len()]);
        let mut p = Parser::new();
        let mut got = Vec::new();
        let mut rest = &stream[..];
        let mut cut = cuts.iter().cycle();
        while !rest.is_empty() {
            let n = (*cut.next().unwrap()).clamp(1, rest.len());
            let (a, b) = rest.split_at(n);
            p.feed(a, |f| got.push((f.packet_type, f.payload.to_vec())));
            rest = b;
        }
        let dropped = p.finish(|f| got.push((f.packet_type, f.payload.to_vec())));
        prop_assert_eq!(&got, &want);
        let s = *p.stats();
        prop_assert_eq!(p.pending(), 0);
        prop_assert_eq!(s.bytes, s.frame_bytes + s.skipped_bytes);
        prop_assert_eq!(s.skipped_bytes + FLUSH.len() as u64, s_flushed.skipped_bytes);
        prop_assert!(dropped < MAX_FRAME);
    }

    /// `feed_until` stopping after every frame, with the untaken input fed again, gives the
    /// frames and counters of `feed`; at every stop, the pending bytes followed by the untaken
    /// input give a fresh parser exactly the frames still to come.
    #[test]
    fn feed_until_stops_after_each_frame_and_continues_exactly(
        parts in proptest::collection::vec((garbage(12), any_type(), any_payload()), 1..8),
        tail in garbage(20),
        cuts in proptest::collection::vec(1usize..300, 1..20),
    ) {
        let mut stream = Vec::new();
        for (g, t, p) in &parts {
            stream.extend_from_slice(g);
            stream.extend(encode(*t, p));
        }
        stream.extend_from_slice(&tail);
        let (whole, s_whole) = parse_chunked(&stream, &[stream.len()]);
        let mut p = Parser::new();
        let mut got: Vec<Owned> = Vec::new();
        let mut offset = 0usize;
        let mut cut = cuts.iter().cycle();
        while offset < stream.len() {
            let end = (offset + *cut.next().unwrap()).min(stream.len());
            let mut chunk = &stream[offset..end];
            while !chunk.is_empty() {
                let mut stopped = false;
                let n = p.feed_until(chunk, |f| {
                    got.push((f.packet_type, f.payload.to_vec()));
                    stopped = true;
                    core::ops::ControlFlow::Break(())
                });
                prop_assert!(n <= chunk.len());
                chunk = &chunk[n..];
                if stopped {
                    // The rest of the stream from here, for a fresh parser.
                    let mut rest = p.pending_bytes().to_vec();
                    rest.extend_from_slice(chunk);
                    rest.extend_from_slice(&stream[end..]);
                    let (after, _) = parse_chunked(&rest, &[rest.len().max(1)]);
                    prop_assert_eq!(&after[..], &whole[got.len()..]);
                }
            }
            offset = end;
        }
        // Frames left buffered behind the last stop come out of an empty feed.
        p.feed(&[], |f| got.push((f.packet_type, f.payload.to_vec())));
        prop_assert_eq!(&got, &whole);
        prop_assert_eq!(p.stats().frames, s_whole.frames);
        prop_assert_eq!(p.stats().bytes, s_whole.bytes);
    }

    /// Frames embedded in random garbage are all recovered; anything else emitted is a
    /// genuine CRC collision lying in garbage.
    #[test]
    fn frames_in_garbage_are_recovered(
        parts in proptest::collection::vec((garbage(40), any_type(), any_payload()), 1..10),
        tail in garbage(40),
    ) {
        let mut stream = Vec::new();
        let mut real = Vec::new(); // (start, len, frame)
        let mut garbage_spans = Vec::new();
        for (g, t, p) in &parts {
            garbage_spans.push((stream.len(), g.len()));
            stream.extend_from_slice(g);
            let f = encode(*t, p);
            real.push((stream.len(), f.len(), (*t, p.clone())));
            stream.extend(f);
        }
        garbage_spans.push((stream.len(), tail.len() + FLUSH.len()));
        stream.extend_from_slice(&tail);
        stream.extend_from_slice(&FLUSH);

        let (emitted, stats) = parse_spans(&stream);
        let overlaps = |a: (usize, usize), b: (usize, usize)| a.0 < b.0 + b.1 && b.0 < a.0 + a.1;
        let mut collisions = Vec::new();
        for e in &emitted {
            if real.contains(e) {
                continue;
            }
            // An extra frame: it must be a complete valid frame at its position ...
            let (start, len, (t, p)) = e;
            prop_assert_eq!(&stream[*start..start + len], &encode(*t, p)[..]);
            // ... that starts in garbage.
            prop_assert!(
                garbage_spans.iter().any(|g| *start >= g.0 && *start < g.0 + g.1),
                "extra frame at {} does not start in garbage", start
            );
            collisions.push((*start, *len));
        }
        for r in &real {
            let found = emitted.contains(r);
            let swallowed = collisions.iter().any(|c| overlaps(*c, (r.0, r.1)));
            prop_assert!(found || swallowed, "real frame at {} lost", r.0);
        }
        // Every byte is accounted for; nothing left pending after the flush.
        prop_assert_eq!(stats.bytes, stream.len() as u64);
        prop_assert_eq!(stats.frame_bytes + stats.skipped_bytes, stats.bytes);
        prop_assert_eq!(stats.frames, emitted.len() as u64);
    }

    /// Every single-bit flip of a frame is rejected: the frame is never emitted, and for
    /// flips outside the length byte no frame is emitted from the frame's start at all
    /// (CRC-16 detects all single-bit errors in a fixed-length codeword). A flipped length
    /// byte changes which bytes are checked; a frame accepted then would be a genuine CRC
    /// collision and must verify as such.
    #[test]
    fn every_single_bit_flip_is_rejected(t in any_type(), p in any_payload()) {
        let frame = encode(t, &p);
        for bit in 0..frame.len() * 8 {
            let mut bytes = frame.clone();
            bytes[bit / 8] ^= 1 << (bit % 8);
            bytes.extend_from_slice(&FLUSH);
            let (emitted, _) = parse_spans(&bytes);
            for (start, len, (et, ep)) in &emitted {
                prop_assert!(!(*et == t && *ep == p), "flip of bit {} accepted", bit);
                if bit / 8 != 4 {
                    prop_assert!(*start != 0, "flip of bit {} accepted at the frame start", bit);
                }
                prop_assert_eq!(&bytes[*start..start + len], &encode(*et, ep)[..]);
            }
        }
    }
}

/// Decodes a frame of type `t` from the parser output of `bytes`, asserting exactly one frame.
fn one_frame(bytes: &[u8]) -> Owned {
    let (out, _) = parse_chunked(bytes, &[bytes.len()]);
    assert_eq!(out.len(), 1);
    out.into_iter().next().unwrap()
}

macro_rules! round_trip {
    ($name:ident, $view:ident, $len:expr, $variant:ident) => {
        proptest! {
            #![proptest_config(cfg(64))]
            /// Random payload -> view -> fields -> encode -> parse -> decode -> same fields.
            #[test]
            fn $name(raw in proptest::collection::vec(any::<u8>(), $len)) {
                let fields = $view::new(&raw).unwrap().fields();
                let mut buf = [0u8; MAX_FRAME];
                let n = fields.encode(&mut buf).unwrap();
                prop_assert_eq!(n, $len + 7);
                // The encoder puts every field back at its offset ...
                prop_assert_eq!(&buf[5..5 + $len], &raw[..]);
                let (t, payload) = one_frame(&buf[..n]);
                prop_assert_eq!(t, $view::TYPE);
                // ... and decoding the parsed frame gives the same fields.
                match Packet::decode(Frame { packet_type: t, payload: &payload }).unwrap() {
                    Packet::$variant(v) => prop_assert_eq!(v.fields(), fields),
                    other => prop_assert!(false, "decoded as {:?}", other),
                }
            }
        }
    };
}

round_trip!(round_trip_s0, S0, 30, S0);
round_trip!(round_trip_s1, S1, 24, S1);
round_trip!(round_trip_s2, S2, 28, S2);
round_trip!(round_trip_a0, A0, 30, A0);
round_trip!(round_trip_a1, A1, 32, A1);
round_trip!(round_trip_a2, A2, 30, A2);
round_trip!(round_trip_n0, N0, 32, N0);
round_trip!(round_trip_n1, N1, 42, N1);
round_trip!(round_trip_b1, B1, 18, B1);
round_trip!(round_trip_t0, T0, 28, T0);
round_trip!(round_trip_vr, Vr, 5, Vr);
round_trip!(round_trip_nak, Nak, 2, Nak);

proptest! {
    #![proptest_config(cfg(64))]

    /// Fields built from independent random values (not from a decoded payload) come back
    /// unchanged, and land at the documented offsets.
    #[test]
    fn round_trip_a2_from_values(
        a in any::<[i16; 12]>(), time in any::<u32>(), bit in any::<u16>()
    ) {
        let f = A2Fields {
            roll: a[0], pitch: a[1], yaw_true: a[2], rate_x: a[3], rate_y: a[4], rate_z: a[5],
            accel_x: a[6], accel_y: a[7], accel_z: a[8], rate_temp_x: a[9], rate_temp_y: a[10],
            rate_temp_z: a[11], time_itow: time, bit,
        };
        let mut buf = [0u8; 64];
        let n = f.encode(&mut buf).unwrap();
        let (t, p) = one_frame(&buf[..n]);
        // Offsets from the protocol document: yaw at 4, z rate at 10, timeITOW at 24, BIT 28.
        prop_assert_eq!(i16::from_be_bytes([p[4], p[5]]), a[2]);
        prop_assert_eq!(i16::from_be_bytes([p[10], p[11]]), a[5]);
        prop_assert_eq!(u32::from_be_bytes([p[24], p[25], p[26], p[27]]), time);
        prop_assert_eq!(u16::from_be_bytes([p[28], p[29]]), bit);
        let Packet::A2(v) = Packet::decode(Frame { packet_type: t, payload: &p }).unwrap() else {
            panic!()
        };
        prop_assert_eq!(v.fields(), f);
        let s = Packet::A2(v).yaw_sample().unwrap();
        prop_assert_eq!(s.time, TimeStamp::Itow(time));
        prop_assert_eq!(s.yaw_deg, a[2] as f32 * 360.0 / 65536.0);
        prop_assert_eq!(s.yaw_rate_deg_s, a[5] as f32 * 1260.0 / 65536.0);
    }

    #[test]
    fn round_trip_n1_from_values(
        a in any::<[i16; 14]>(), lon in any::<i32>(), lat in any::<i32>(), time in any::<u32>(),
        bit in any::<u16>()
    ) {
        let f = N1Fields {
            roll: a[0], pitch: a[1], yaw_true: a[2], rate_x: a[3], rate_y: a[4], rate_z: a[5],
            accel_x: a[6], accel_y: a[7], accel_z: a[8], vel_n: a[9], vel_e: a[10], vel_d: a[11],
            longitude: lon, latitude: lat, altitude: a[12], x_rate_temp: a[13], time_itow: time, bit,
        };
        let mut buf = [0u8; 64];
        let n = f.encode(&mut buf).unwrap();
        let (t, p) = one_frame(&buf[..n]);
        prop_assert_eq!(i32::from_be_bytes([p[24], p[25], p[26], p[27]]), lon);
        prop_assert_eq!(i32::from_be_bytes([p[28], p[29], p[30], p[31]]), lat);
        prop_assert_eq!(u32::from_be_bytes([p[36], p[37], p[38], p[39]]), time);
        let Packet::N1(v) = Packet::decode(Frame { packet_type: t, payload: &p }).unwrap() else {
            panic!()
        };
        prop_assert_eq!(v.fields(), f);
        prop_assert_eq!(v.latitude_deg(), lat as f64 * 360.0 / 4_294_967_296.0);
    }

    #[test]
    fn round_trip_id(serial in any::<u32>(), model in proptest::collection::vec(1u8..=255, 0..200)) {
        let f = IdFields { serial, model: &model };
        let mut buf = [0u8; MAX_FRAME];
        let n = f.encode(&mut buf).unwrap();
        let (t, p) = one_frame(&buf[..n]);
        prop_assert_eq!(p.last(), Some(&0));
        let Packet::Id(v) = Packet::decode(Frame { packet_type: t, payload: &p }).unwrap() else {
            panic!()
        };
        prop_assert_eq!(v.fields(), f);
    }

    #[test]
    fn round_trip_field_commands(
        pairs in proptest::collection::vec((any::<u16>(), any::<u16>()), 0..=63),
    ) {
        let fields: Vec<(FieldId, u16)> = pairs.iter().map(|&(i, v)| (FieldId(i), v)).collect();
        let ids: Vec<FieldId> = fields.iter().map(|f| f.0).collect();
        let mut buf = [0u8; MAX_FRAME];
        for t in [PacketType::SF, PacketType::WF] {
            let n = if t == PacketType::SF {
                command::set_fields(&fields, &mut buf)
            } else {
                command::write_fields(&fields, &mut buf)
            }
            .unwrap();
            let (ft, p) = one_frame(&buf[..n]);
            prop_assert_eq!(ft, t);
            let (Request::SetFields(v) | Request::WriteFields(v)) =
                Request::decode(Frame { packet_type: ft, payload: &p }).unwrap() else { panic!() };
            prop_assert_eq!(v.iter().collect::<Vec<_>>(), fields.clone());
            // The unit's reply lists the accepted IDs.
            let n = command::fields_accepted_reply(t, &ids, &mut buf).unwrap();
            let (ft, p) = one_frame(&buf[..n]);
            let (Packet::SetFields(r) | Packet::WriteFields(r)) =
                Packet::decode(Frame { packet_type: ft, payload: &p }).unwrap() else { panic!() };
            prop_assert_eq!(r.iter().collect::<Vec<_>>(), ids.clone());
        }
        for t in [PacketType::GF, PacketType::RF] {
            let n = if t == PacketType::GF {
                command::get_fields(&ids, &mut buf)
            } else {
                command::read_fields(&ids, &mut buf)
            }
            .unwrap();
            let (ft, p) = one_frame(&buf[..n]);
            let (Request::GetFields(r) | Request::ReadFields(r)) =
                Request::decode(Frame { packet_type: ft, payload: &p }).unwrap() else { panic!() };
            prop_assert_eq!(r.iter().collect::<Vec<_>>(), ids.clone());
            let n = command::field_values_reply(t, &fields, &mut buf).unwrap();
            let (ft, p) = one_frame(&buf[..n]);
            let (Packet::GetFields(v) | Packet::ReadFields(v)) =
                Packet::decode(Frame { packet_type: ft, payload: &p }).unwrap() else { panic!() };
            prop_assert_eq!(v.iter().collect::<Vec<_>>(), fields.clone());
        }
    }

    /// The slice-by-16 padding trick gives the catalogue CRC for every length.
    #[test]
    fn message_crc_matches_plain_crc(data in proptest::collection::vec(any::<u8>(), 0..300)) {
        let plain = <crc::Table<1> as Crc16Table>::checksum(&data);
        prop_assert_eq!(<crc::Table<16> as Crc16Table>::message_crc(&data), plain);
        prop_assert_eq!(<crc::Table<16> as Crc16Table>::checksum(&data), plain);
        prop_assert_eq!(<crc::Table<0> as Crc16Table>::checksum(&data), plain);
    }
}

#[test]
fn encoder_rejects_oversize_and_short_buffers() {
    let mut buf = [0u8; MAX_FRAME + 10];
    assert_eq!(
        encode_frame(PacketType::CH, &[0; 256], &mut buf),
        Err(EncodeError::PayloadTooLong { len: 256 })
    );
    assert_eq!(
        encode_frame(PacketType::CH, &[0; 10], &mut buf[..16]),
        Err(EncodeError::BufferTooSmall { needed: 17 })
    );
    let many = [(FieldId(1), 0u16); 64];
    assert!(command::set_fields(&many, &mut buf).is_err());
    assert!(command::set_fields(&many[..63], &mut buf).is_ok());
}

/// A stop inside the parser's buffer (a corrupted candidate that spanned later frames) leaves
/// the later frames buffered; they come out in order, even from an empty feed.
#[test]
fn frames_buffered_behind_a_stop_come_out_of_an_empty_feed() {
    let a = encode(PacketType::PK, &[]);
    let b = encode(PacketType::CH, &[1, 2]);
    let c = encode(PacketType::AR, &[]);
    // A candidate claiming 40 payload bytes swallows a, b and c; its CRC fails at byte 47.
    let mut stream = vec![0x55, 0x55, b'A', b'2', 40];
    for f in [&a, &b, &c] {
        stream.extend_from_slice(f);
    }
    stream.resize(47, 0);
    let mut p = Parser::new();
    let mut got = Vec::new();
    let mut n_total = 0;
    for byte in &stream {
        n_total += p.feed_until(std::slice::from_ref(byte), |f| {
            got.push(f.packet_type);
            core::ops::ControlFlow::Break(())
        });
    }
    assert_eq!(n_total, stream.len());
    // The byte that completed the bad candidate released `a` and stopped there.
    assert_eq!(got, vec![PacketType::PK]);
    assert_eq!(p.pending_bytes().len(), 47 - 5 - a.len());
    p.feed(&[], |f| got.push(f.packet_type));
    assert_eq!(got, vec![PacketType::PK, PacketType::CH, PacketType::AR]);
}
