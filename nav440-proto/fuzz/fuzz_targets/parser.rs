//! Fuzz target: the parser and the decoders never panic, and the parser's invariants hold.
//!
//! Run: `cd nav440-proto/fuzz && cargo +nightly fuzz run parser -- -runs=1000000`
//! (the same checks run on stable in `tests/fuzz_equivalent.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use nav440_proto::{encode_frame, Packet, Parser, Request, MAX_FRAME};

fuzz_target!(|data: &[u8]| {
    // First byte: chunk size for feeding (0 = all at once).
    let Some((&chunk, stream)) = data.split_first() else {
        return;
    };
    let chunk = if chunk == 0 {
        stream.len().max(1)
    } else {
        chunk as usize
    };
    let mut parser = Parser::new();
    let mut frames = 0u64;
    for c in stream.chunks(chunk) {
        parser.feed(c, |f| {
            frames += 1;
            // Every emitted frame is a complete, CRC-valid frame.
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
    let per_type: u64 = s.per_type.iter().sum::<u64>() + s.other_types;
    assert_eq!(per_type, frames);
});
