//! Parse a NAV440 capture (the raw bytes of the serial line) and print what it holds: frames
//! per type, CRC errors and skipped bytes, and the first yaw samples (time in ms since the
//! first sample, yaw in deg, z rate in deg/s).
//!
//! `cargo run -p nav440-proto --example parse_capture -- host-tests/data/fig5_a2_100hz.bin`
//! (`-` reads standard input).

use std::collections::BTreeMap;
use std::io::Read;

use nav440_proto::{ItowClock, Packet, Parser};

fn main() -> std::process::ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: parse_capture FILE|-");
        return std::process::ExitCode::from(2);
    };
    let mut input: Box<dyn Read> = if path == "-" {
        Box::new(std::io::stdin())
    } else {
        match std::fs::File::open(&path) {
            Ok(f) => Box::new(f),
            Err(e) => {
                eprintln!("parse_capture: cannot read {path}: {e}");
                return std::process::ExitCode::from(3);
            }
        }
    };
    let (mut parser, mut clock) = (Parser::new(), ItowClock::new());
    let mut per_type: BTreeMap<String, u64> = BTreeMap::new();
    let (mut samples, mut chunk) = (0u64, [0u8; 4096]);
    loop {
        let n = match input.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) => {
                eprintln!("parse_capture: read error: {e}");
                return std::process::ExitCode::from(3);
            }
        };
        // Bytes in any chunking; the closure sees every CRC-checked frame.
        parser.feed(&chunk[..n], |frame| {
            let name = String::from_utf8_lossy(&frame.packet_type.0).into_owned();
            *per_type.entry(name).or_default() += 1;
            let Some(s) = Packet::decode(frame).ok().and_then(|p| p.yaw_sample()) else {
                return;
            };
            if let Some(t_us) = clock.update(s.time) {
                if samples < 5 {
                    println!(
                        "sample {samples}: t = {} ms, yaw = {:.3} deg, z rate = {:.3} deg/s",
                        t_us / 1000,
                        s.yaw_deg,
                        s.yaw_rate_deg_s
                    );
                }
                samples += 1;
            }
        });
    }
    let st = parser.stats();
    println!("frames per type: {per_type:?}");
    println!(
        "yaw samples {samples}, bytes {}, CRC errors {}, skipped bytes {}",
        st.bytes, st.crc_errors, st.skipped_bytes
    );
    if per_type.is_empty() {
        eprintln!("parse_capture: {path}: no NAV440 frame found");
        return std::process::ExitCode::from(4);
    }
    std::process::ExitCode::SUCCESS
}
