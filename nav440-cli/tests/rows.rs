//! `nav440 rows`: the rows of a `uart-rows` firmware's output UART (framed binary messages,
//! `nav440_pipeline::wire`) printed as the CSV of `nav440 estimate`. The streams here are made
//! the way the firmware makes them: the rows of the pipeline `nav440 estimate` runs, each
//! encoded with `wire::encode` (the firmware's own run under QEMU is `cargo xtask ci`'s
//! `uart-rows` job).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use estimators::PaperOutput;
use nav440_cli::replay::{self, Axes, EstimateOptions, SampleReader};
use nav440_pipeline::wire::{self, Header, Message, RowFrame};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-rows-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn nav440(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Written on a thread: the child's output fills its pipe while the input is still going.
    let writer = stdin.map(|bytes| {
        let mut i = child.stdin.take().unwrap();
        let bytes = bytes.to_vec();
        std::thread::spawn(move || {
            let _ = i.write_all(&bytes);
        })
    });
    let out = child.wait_with_output().unwrap();
    if let Some(w) = writer {
        w.join().unwrap();
    }
    out
}

/// The frames of the rows `nav440 estimate --axis all` computes for `capture`: a delimiter,
/// the header, then one frame per row with the header again every 100 rows (as the firmware
/// sends them); returns the frames one by one.
fn frames_of(capture: &Path) -> Vec<Vec<u8>> {
    let bytes = std::fs::read(capture).unwrap();
    let mut samples = Vec::new();
    let mut r = SampleReader::new();
    r.feed(&bytes, |s| samples.push(s));
    r.finish(|s| samples.push(s));
    let opts = EstimateOptions {
        axes: Axes::ALL,
        follow_rate: true,
        ..EstimateOptions::default()
    };
    let (rows, _) = replay::estimate_rows(&samples, &opts).unwrap();
    let columns = <PaperOutput>::CSV_COLUMNS.to_string();
    let header = Message::Header(Header::new(Axes::ALL, &columns));
    let mut buf = [0u8; 1024];
    let mut frames = vec![vec![wire::DELIMITER]];
    frames.push(wire::encode(&header, &mut buf).unwrap().to_vec());
    for (k, row) in rows.iter().enumerate() {
        if k > 0 && k % 100 == 0 {
            frames.push(wire::encode(&header, &mut buf).unwrap().to_vec());
        }
        let m = Message::Row(RowFrame::from_row(row, Axes::ALL));
        frames.push(wire::encode(&m, &mut buf).unwrap().to_vec());
    }
    frames
}

fn estimate_all(capture: &Path) -> String {
    let o = nav440(
        &["estimate", capture.to_str().unwrap(), "--axis", "all"],
        None,
    );
    assert!(o.status.success());
    String::from_utf8(o.stdout).unwrap()
}

/// From a file and from standard input, the CSV is `nav440 estimate --axis all`'s, byte for
/// byte, with nothing on stderr: a bundled capture, and a tumble through gimbal lock (rows
/// without roll and yaw).
#[test]
fn rows_print_the_csv_of_estimate() {
    let d = scratch("same");
    let tumble = d.join("tumble.bin");
    let made = nav440(
        &[
            "synth",
            "--profile",
            "tumble",
            "--duration",
            "12",
            "-o",
            tumble.to_str().unwrap(),
        ],
        None,
    );
    assert!(made.status.success());
    for capture in [data("sin5_a2_25hz_weekwrap.bin"), tumble] {
        let stream: Vec<u8> = frames_of(&capture).concat();
        let file = d.join("rows.bin");
        std::fs::write(&file, &stream).unwrap();
        let expected = estimate_all(&capture);
        let o = nav440(&["rows", file.to_str().unwrap()], None);
        assert_eq!(String::from_utf8_lossy(&o.stderr), "");
        assert!(o.status.success());
        assert_eq!(String::from_utf8(o.stdout).unwrap(), expected);
        let o = nav440(&["rows", "-"], Some(&stream));
        assert!(o.status.success());
        assert_eq!(String::from_utf8(o.stdout).unwrap(), expected);
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Over a serial port (one end of a pseudo-terminal pair, both ends raw): the CSV is
/// `nav440 estimate --axis all`'s, nothing on stderr, and the other end's hang-up ends the run
/// with exit 0, before `--duration` would.
#[test]
fn rows_over_a_port_print_the_csv_and_end_at_the_hang_up() {
    use serialport::SerialPort as _;
    let capture = data("sin5_a2_25hz_weekwrap.bin");
    let expected = estimate_all(&capture);
    let (master, slave) = serialport::TTYPort::pair().unwrap();
    // Copies that close on exec: `pair` leaves its descriptors inheritable, and a copy of the
    // writing end in the child would keep the hang-up from ever coming.
    let (mut writer, reader) = (
        master.try_clone_native().unwrap(),
        slave.try_clone_native().unwrap(),
    );
    drop((master, slave));
    let name = reader.name().unwrap();
    let started = std::time::Instant::now();
    let child = Command::new(BIN)
        .args(["rows", "--port", &name, "--duration", "60"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The port is opened before the first byte comes, as a UART's stream is joined.
    std::thread::sleep(std::time::Duration::from_millis(500));
    writer.write_all(&frames_of(&capture).concat()).unwrap();
    writer.flush().unwrap();
    // Until the pseudo-terminal's buffer is read out; then the hang-up.
    while writer.bytes_to_write().unwrap() > 0 {
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    drop(reader);
    drop(writer);
    let o = child.wait_with_output().unwrap();
    // Ended by the hang-up, not by `--duration`.
    assert!(started.elapsed() < std::time::Duration::from_secs(60));
    assert_eq!(String::from_utf8_lossy(&o.stderr), "");
    assert!(o.status.success());
    assert_eq!(String::from_utf8(o.stdout).unwrap(), expected);
}

/// A stream joined mid-frame, with garbage and a corrupted frame: the rows after each are
/// printed, every bad frame is reported on stderr, what was skipped is counted, exit 0.
#[test]
fn rows_resync_after_garbage_and_report_bad_frames() {
    let capture = data("sin5_a2_25hz_weekwrap.bin");
    let expected = estimate_all(&capture);
    let lines: Vec<&str> = expected.lines().collect();
    let frames = frames_of(&capture);
    // frames: [delimiter, header, row 0, row 1, ...]; row k is frames[2 + k] for k < 100.
    let mut stream = Vec::new();
    stream.extend_from_slice(&[0x31, 0x32, 0x33]); // the tail of an earlier frame
    stream.push(0);
    stream.extend_from_slice(&frames[1]); // header
    stream.extend_from_slice(&frames[2]); // row 0
    stream.extend_from_slice(&[0xFF, 0x10, 0x20, 0]); // garbage: not COBS
    let mut bad = frames[3].clone(); // row 1, corrupted
    bad[0] = 0xFE;
    stream.extend_from_slice(&bad);
    for f in &frames[4..] {
        stream.extend_from_slice(f);
    }
    let o = nav440(&["rows", "-"], Some(&stream));
    assert!(o.status.success());
    let mut want: Vec<&str> = vec![lines[0], lines[1]];
    want.extend_from_slice(&lines[3..]);
    let got = String::from_utf8(o.stdout).unwrap();
    assert_eq!(got.lines().collect::<Vec<_>>(), want);
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(
        err.lines()
            .filter(|l| l.contains("undecodable frame:"))
            .count(),
        2,
        "{err}"
    );
    assert!(
        err.contains("nav440: warning: 2 bad frames or rows skipped"),
        "{err}"
    );
    assert!(
        err.contains("3 bytes before the first frame delimiter skipped"),
        "{err}"
    );
    // Rows before the first header are skipped and counted; a later header starts the CSV.
    let mut late = vec![0u8];
    late.extend(frames[2..5].concat());
    late.extend_from_slice(&frames[1]);
    late.extend(frames[5..].concat());
    let o = nav440(&["rows", "-"], Some(&late));
    assert!(o.status.success());
    let got = String::from_utf8(o.stdout).unwrap();
    assert_eq!(got.lines().next(), Some(lines[0]));
    assert_eq!(got.lines().nth(1), Some(lines[4]));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("3 rows before the first header frame skipped")
    );
}

/// Without a usable header the command fails with exit 4 and says why; a missing file is exit
/// 3; FILE and --port together are a usage error.
#[test]
fn rows_without_a_header_are_an_error() {
    let frames = frames_of(&data("sin5_a2_25hz_weekwrap.bin"));
    // Every frame but the header's copies.
    let rows: Vec<u8> = frames[2..]
        .iter()
        .filter(|f| **f != frames[1])
        .flatten()
        .copied()
        .collect();
    let no_header: Vec<u8> = [&frames[0][..], &rows].concat();
    let o = nav440(&["rows", "-"], Some(&no_header));
    assert_eq!(o.status.code(), Some(4));
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(err.starts_with("nav440: no header frame among"), "{err}");
    assert!(o.stdout.is_empty());
    // A NAV440 capture is not a row stream.
    let o = nav440(
        &["rows", data("sin5_a2_25hz_weekwrap.bin").to_str().unwrap()],
        None,
    );
    assert_eq!(o.status.code(), Some(4));
    // A header of another format version.
    let columns = <PaperOutput>::CSV_COLUMNS.to_string();
    let mut h = Header::new(Axes::ALL, &columns);
    h.version = wire::VERSION + 1;
    let mut buf = [0u8; 256];
    let mut other = vec![0u8];
    other.extend_from_slice(wire::encode(&Message::Header(h), &mut buf).unwrap());
    other.extend_from_slice(&rows);
    let o = nav440(&["rows", "-"], Some(&other));
    assert_eq!(o.status.code(), Some(4));
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(
        err.contains("format version 2; this reader reads version 1"),
        "{err}"
    );
    let o = nav440(&["rows", "/nonexistent/rows.bin"], None);
    assert_eq!(o.status.code(), Some(3));
    let o = nav440(&["rows", "x.bin", "--port", "/dev/null"], None);
    assert_eq!(o.status.code(), Some(2));
    let o = nav440(&["rows"], None);
    assert_eq!(o.status.code(), Some(2));
}
