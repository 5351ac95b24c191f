//! The checks shared by the cargo-fuzz target (`fuzz/fuzz_targets/parser.rs`) and its stable
//! equivalent (`tests/fuzz_equivalent.rs`): feeding `stream` in chunks of `chunk` bytes never
//! panics, every emitted frame is complete and CRC-valid, decoding it never panics, and the
//! counters add up.

use nav440_proto::{encode_frame, Packet, Parser, Request, MAX_FRAME};

/// Feeds `stream` in chunks of `chunk` bytes (0 counts as 1) and checks the invariants.
pub fn check(stream: &[u8], chunk: usize) {
    let mut parser = Parser::new();
    let mut frames = 0u64;
    for c in stream.chunks(chunk.max(1)) {
        parser.feed(c, |f| {
            frames += 1;
            let mut buf = [0u8; MAX_FRAME];
            let n = encode_frame(f.packet_type, f.payload, &mut buf).expect("payload <= 255");
            assert_eq!(n, f.wire_len());
            let _ = Packet::decode(f).map(|p| (p.yaw_sample(), p.bit(), p.time()));
            let _ = Request::decode(f);
        });
    }
    let s = parser.stats();
    assert_eq!(s.bytes, stream.len() as u64);
    assert_eq!(s.frames, frames);
    assert_eq!(
        s.frame_bytes + s.skipped_bytes + parser.pending() as u64,
        s.bytes
    );
    assert!(parser.pending() < MAX_FRAME);
    assert_eq!(s.per_type.iter().sum::<u64>() + s.other_types, frames);
}
