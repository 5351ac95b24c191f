//! Fuzz target: the parser and the decoders never panic, and the parser's invariants hold.
//!
//! Run: `cd nav440-proto/fuzz && cargo +nightly fuzz run parser -- -runs=1000000`
//! (the same checks run on stable in `tests/fuzz_equivalent.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../tests/common/fuzz_check.rs"]
mod fuzz_check;

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
    fuzz_check::check(stream, chunk);
});
