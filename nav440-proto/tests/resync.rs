//! Explicit resynchronisation cases (one-byte drop, buffered frames behind a bad candidate).

use nav440_proto::*;

fn frames_fed(bytes: &[u8], chunk: usize) -> (Vec<(PacketType, Vec<u8>)>, Stats) {
    let mut p = Parser::new();
    let mut out = Vec::new();
    for c in bytes.chunks(chunk) {
        p.feed(c, |f| out.push((f.packet_type, f.payload.to_vec())));
    }
    (out, *p.stats())
}

const PING: [u8; 7] = [0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4];

#[test]
fn frames_inside_a_bad_candidates_span_are_found_in_every_chunking() {
    // A false header announcing 64 payload bytes, then three pings well inside its span, then
    // filler so the false candidate completes (and fails its CRC).
    let mut s = vec![0x55, 0x55, b'A', b'A', 64];
    for _ in 0..3 {
        s.extend_from_slice(&PING);
    }
    s.extend_from_slice(&[0u8; 80]);
    for chunk in [1, 2, 3, 5, 7, 64, 1000] {
        let (f, st) = frames_fed(&s, chunk);
        assert_eq!(f.len(), 3, "chunk {chunk}");
        assert!(f.iter().all(|(t, p)| *t == PacketType::PK && p.is_empty()));
        assert_eq!(st.crc_errors, 1, "chunk {chunk}");
        assert_eq!(st.count(PacketType::PK), 3);
        // 5 bytes of the false header dropped one at a time, 80 filler bytes skipped.
        assert_eq!(st.skipped_bytes, 85);
        assert_eq!(st.frame_bytes, 21);
    }
}

#[test]
fn a_frame_right_after_garbage_is_found() {
    let mut s = vec![0x00, 0x55, 0x13, 0x55, 0x55, 0x00, 0x55];
    s.extend_from_slice(&PING);
    for chunk in [1, 4, 100] {
        let (f, st) = frames_fed(&s, chunk);
        assert_eq!(f, vec![(PacketType::PK, vec![])], "chunk {chunk}");
        assert_eq!(st.skipped_bytes, 7);
        // Impossible headers, rejected without waiting: `55 55 00` at offset 3 (type byte
        // 0x00) and `55 55 55 50` at offset 6 (type byte 'U').
        assert_eq!(st.header_errors, 2);
        assert_eq!(st.crc_errors, 0);
    }
}

#[test]
fn a_run_of_preamble_bytes_before_a_frame_costs_no_latency() {
    // `55 55 55 50 ..`: the candidate at offset 0 has type byte 'U', which is impossible, so the
    // ping at offset 1 is emitted as soon as its last byte arrives.
    let mut s = vec![0x55];
    s.extend_from_slice(&PING);
    let mut p = Parser::new();
    let mut n = 0;
    for b in &s {
        p.feed(core::slice::from_ref(b), |_| n += 1);
    }
    assert_eq!(n, 1);
    assert_eq!(p.pending(), 0);
}

#[test]
fn a_corrupted_frame_followed_by_a_good_one() {
    let mut bad = [0u8; 64];
    let n = A2Fields {
        roll: 5,
        ..Default::default()
    }
    .encode(&mut bad)
    .unwrap();
    bad[10] ^= 0x40;
    let mut s = bad[..n].to_vec();
    s.extend_from_slice(&PING);
    for chunk in [1, 9, 100] {
        let (f, st) = frames_fed(&s, chunk);
        assert_eq!(f, vec![(PacketType::PK, vec![])]);
        assert_eq!(st.crc_errors, 1);
        assert_eq!(st.skipped_bytes, n as u64);
    }
}

/// Feeds `bytes` in chunks of `chunk`, then ends the input with [`Parser::finish`].
fn frames_finished(bytes: &[u8], chunk: usize) -> (Vec<(PacketType, Vec<u8>)>, Stats, usize) {
    let mut p = Parser::new();
    let mut out = Vec::new();
    for c in bytes.chunks(chunk) {
        p.feed(c, |f| out.push((f.packet_type, f.payload.to_vec())));
    }
    let dropped = p.finish(|f| out.push((f.packet_type, f.payload.to_vec())));
    assert_eq!(p.pending(), 0);
    (out, *p.stats(), dropped)
}

#[test]
fn frames_behind_a_false_header_at_the_end_of_input_are_recovered() {
    // A false header announcing 200 payload bytes, then two pings and nothing more: fed alone,
    // the pings wait behind the candidate for ever; `finish` rejects the candidate and finds
    // them.
    let mut s = vec![0x55, 0x55, b'A', b'2', 200];
    s.extend_from_slice(&PING);
    s.extend_from_slice(&PING);
    for chunk in [1, 2, 3, 5, 7, 64, 1000] {
        let (fed, _) = frames_fed(&s, chunk);
        assert!(
            fed.is_empty(),
            "chunk {chunk}: held while the input may go on"
        );
        let (f, st, dropped) = frames_finished(&s, chunk);
        assert_eq!(f, vec![(PacketType::PK, vec![]); 2], "chunk {chunk}");
        // The 5 bytes of the false header did not complete a frame.
        assert_eq!(dropped, 5, "chunk {chunk}");
        assert_eq!(st.skipped_bytes, 5);
        assert_eq!(st.frame_bytes, 14);
        assert_eq!(st.bytes, st.frame_bytes + st.skipped_bytes);
    }
}

#[test]
fn a_truncated_last_frame_is_reported_as_dropped_bytes() {
    // One ping, then the first 5 bytes of another (its CRC is missing).
    let mut s = PING.to_vec();
    s.extend_from_slice(&PING[..5]);
    for chunk in [1, 4, 100] {
        let (f, st, dropped) = frames_finished(&s, chunk);
        assert_eq!(f.len(), 1, "chunk {chunk}");
        assert_eq!(dropped, 5, "chunk {chunk}");
        assert_eq!(st.pending_bytes(), 0);
        assert_eq!(st.bytes, 12);
    }
    // A clean end drops nothing.
    assert_eq!(frames_finished(&PING, 3).2, 0);
}
