//! `nav440 stats|decode|estimate -` stream: the child's peak resident memory (VmHWM) stays under
//! 64 MiB while several times that many bytes go through its standard input, and rows come out
//! before the input ends. The streams are generated on the fly (nothing is stored).
//!
//! The memory tests are release-only (CI: `cargo test --release -p host-tests --test
//! streaming`); the first-rows tests run in every build.

// The ILO steady-state gain helper shared with the capture-replay tests.
#[path = "../../host-tests/tests/common/mod.rs"]
mod common;

use nav440_cli::replay::EstimateOptions;
use nav440_cli::synth::{encode_packet, PacketKind, ANGLE_LSB_DEG, RATE_LSB_DEG_S};
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_nav440");
/// The memory bound of the issue, KiB.
const LIMIT_KIB: u64 = 64 * 1024;
/// How long a test waits for a row before calling the command stuck (a guard, not a timing).
const STUCK: Duration = Duration::from_secs(120);

/// Multiplies the number of frames of the memory tests (default 1): e.g.
/// `NAV440_STREAM_SCALE=16` for the multi-GB figures of docs/CLI.md (Streaming).
fn scale() -> u64 {
    std::env::var("NAV440_STREAM_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

/// Rotation rate of the generated motion, deg/s.
const RATE: f64 = 30.0;

/// The A2 frame of packet `k` of a steady 100 Hz rotation at [`RATE`]: timeITOW = 10 k ms.
fn frame(k: u64) -> Vec<u8> {
    let t = k as f64 * 0.01;
    encode_packet(PacketKind::A2, RATE * t, RATE, (k * 10) as u32, 0).unwrap()
}

/// Peak resident set of process `pid`, KiB (`VmHWM` of /proc/PID/status).
fn vm_hwm_kib(pid: u32) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let line = s.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
    line.split_whitespace().nth(1).unwrap().parse().unwrap()
}

fn spawn(args: &[&str]) -> Child {
    Command::new(BIN)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run nav440")
}

/// What came out of a streamed run.
struct Outcome {
    /// Bytes written to the child's standard input.
    bytes_in: u64,
    /// The child's peak resident set after all input was written, KiB.
    hwm_kib: u64,
    /// Output lines.
    lines: u64,
    /// First and last output line.
    first: String,
    last: String,
    stderr: String,
}

/// Pipes `frames` generated frames, each followed by `pad` zero bytes (skipped by the parser),
/// into `nav440 <args> -`, reading its output as it comes.
fn pipe_through(args: &[&str], frames: u64, pad: usize) -> Outcome {
    let mut child = spawn(args);
    let pid = child.id();
    let mut stdin = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        let zeros = vec![0u8; pad];
        let mut block = Vec::with_capacity(1 << 20);
        let mut bytes = 0u64;
        for k in 0..frames {
            block.extend_from_slice(&frame(k));
            block.extend_from_slice(&zeros);
            if block.len() >= 1 << 20 || k + 1 == frames {
                stdin.write_all(&block).unwrap();
                bytes += block.len() as u64;
                block.clear();
            }
        }
        // Everything is in the pipe (at most its 64 KiB buffer still unread): the peak so far
        // covers the whole stream.
        let hwm = vm_hwm_kib(pid);
        drop(stdin);
        (bytes, hwm)
    });
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let (mut lines, mut first, mut last, mut line) =
        (0u64, String::new(), String::new(), String::new());
    while out.read_line(&mut line).unwrap() > 0 {
        if lines == 0 {
            first = line.clone();
        }
        lines += 1;
        std::mem::swap(&mut last, &mut line);
        line.clear();
    }
    let (bytes_in, hwm_kib) = writer.join().unwrap();
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    assert!(child.wait().unwrap().success(), "{args:?}: {stderr}");
    Outcome {
        bytes_in,
        hwm_kib,
        lines,
        first: first.trim_end().to_string(),
        last: last.trim_end().to_string(),
        stderr,
    }
}

fn check_memory(what: &str, o: &Outcome) {
    eprintln!(
        "{what}: {} MiB through standard input, {} output lines, peak RSS {} KiB",
        o.bytes_in >> 20,
        o.lines,
        o.hwm_kib
    );
    assert!(
        o.bytes_in > 3 * LIMIT_KIB * 1024,
        "{what}: stream too short"
    );
    assert!(
        o.hwm_kib < LIMIT_KIB,
        "{what}: peak RSS {} KiB >= 64 MiB",
        o.hwm_kib
    );
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test streaming"
)]
fn stats_streams_in_constant_memory() {
    let (n, pad) = (200_000 * scale(), 1024usize);
    let o = pipe_through(&["stats", "-"], n, pad);
    check_memory("stats", &o);
    let v: serde_json::Value = serde_json::from_str(&o.first).unwrap();
    assert_eq!(v["bytes"], o.bytes_in);
    assert_eq!(v["frames"]["A2"], n);
    assert_eq!(v["skipped_bytes"], n * pad as u64);
    assert_eq!(v["pending_bytes"], 0);
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test streaming"
)]
fn decode_streams_in_constant_memory() {
    let (n, pad) = (200_000 * scale(), 1024usize);
    let o = pipe_through(&["decode", "-"], n, pad);
    check_memory("decode", &o);
    assert!(o.stderr.is_empty(), "{}", o.stderr);
    assert_eq!(o.lines, n + 1);
    let header: Vec<&str> = o.first.split(',').collect();
    let last: Vec<&str> = o.last.split(',').collect();
    let cell = |name: &str| last[header.iter().position(|h| *h == name).unwrap()];
    assert_eq!(cell("index"), (n - 1).to_string());
    assert_eq!(cell("type"), "A2");
    // timeITOW of the last packet, s.
    let t: f64 = cell("time_itow_s").parse().unwrap();
    assert!((t - (n - 1) as f64 * 0.01).abs() < 1e-9, "{t}");
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test streaming"
)]
fn estimate_streams_in_constant_memory() {
    // 10^6 samples: kept in memory (16-byte samples and 72-byte rows) they alone would pass
    // 64 MiB.
    let (n, pad) = (1_000_000 * scale(), 200usize);
    let o = pipe_through(&["estimate", "-"], n, pad);
    check_memory("estimate", &o);
    assert!(o.stderr.is_empty(), "{}", o.stderr);
    assert_eq!(o.lines, n + 1, "one row per packet");
    let last: Vec<f64> = o.last.split(',').map(|c| c.parse().unwrap()).collect();
    assert!(
        (last[0] - (n - 1) as f64 * 0.01).abs() < 1e-6,
        "t {}",
        last[0]
    );
    // A steady rotation: the measured rate within an LSB; the velocity estimates within the
    // quantisation (two angle LSBs per 10 ms), the leaky ILOs at their steady-state gain
    // c / (L + c), c = K2 / (1 - K1) (see tests/replay.rs), computed from the gains `nav440
    // estimate` runs by default (`BankConfig::NAV440`); ED (which chatters) only bounded.
    assert!((last[2] - RATE).abs() <= RATE_LSB_DEG_S, "{}", last[2]);
    let ilo = EstimateOptions::default().bank_config().velocity.ilo;
    let gi = |i: usize| common::ilo_dc_gain(&ilo[i]);
    let gains = [1.0, gi(0), gi(1), gi(2), 1.0, 1.0, 1.0];
    for i in [0, 1, 2, 3, 4, 6] {
        let v = last[3 + i];
        assert!(
            (v - RATE * gains[i]).abs() < 2.0 * ANGLE_LSB_DEG / 0.01,
            "velocity {i}: {v} ({})",
            o.last
        );
    }
    assert!(last[8].abs() < 1000.0, "ED {}", last[8]);
}

/// Reads lines of `child`'s stdout on a thread; lines arrive on the channel.
fn line_reader(child: &mut Child) -> mpsc::Receiver<String> {
    let out = BufReader::new(child.stdout.take().unwrap());
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for l in out.lines() {
            if tx.send(l.unwrap()).is_err() {
                break;
            }
        }
    });
    rx
}

/// Writes the first `early` frames, expects `want_early` output lines while the input is still
/// open, then writes `late` more frames, closes the input, and returns every line.
fn rows_before_the_end(args: &[&str], early: u64, late: u64, want_early: usize) -> Vec<String> {
    let mut child = spawn(args);
    let rx = line_reader(&mut child);
    let mut stdin = child.stdin.take().unwrap();
    let bytes: Vec<u8> = (0..early).flat_map(frame).collect();
    stdin.write_all(&bytes).unwrap();
    stdin.flush().unwrap();
    let mut lines = Vec::new();
    for _ in 0..want_early {
        lines.push(
            rx.recv_timeout(STUCK)
                .unwrap_or_else(|_| panic!("{args:?}: no output while the input is open")),
        );
    }
    let bytes: Vec<u8> = (early..early + late).flat_map(frame).collect();
    stdin.write_all(&bytes).unwrap();
    drop(stdin);
    lines.extend(rx.iter());
    assert!(child.wait().unwrap().success());
    lines
}

#[test]
fn estimate_rows_come_out_before_the_input_ends() {
    // 200 packets (2 s): after the 16-sample warm-up every sample gives its row at once.
    let lines = rows_before_the_end(&["estimate", "-"], 200, 300, 2);
    assert!(lines[0].starts_with("t,yaw,yaw_rate,"));
    assert_eq!(lines.len(), 501);
    assert!(lines[1].starts_with("0.0000,"), "{}", lines[1]);
}

#[test]
fn decode_rows_come_out_before_the_input_ends() {
    // 2,000 A2 frames are 74 KB, past decode's 64 KiB look-ahead on standard input.
    let lines = rows_before_the_end(&["decode", "-"], 2000, 1000, 2);
    assert!(lines[0].starts_with("index,type,"));
    assert!(lines[1].starts_with("0,A2,"));
    assert_eq!(lines.len(), 3001);
}
