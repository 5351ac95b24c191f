//! `nav440 sim` end to end: the boot sequence of `nav440_proto::boot` as the host over TCP,
//! every fault flag, the recorded bytes against the capture; and `nav440 config | record |
//! live` against the simulator through a pseudo-terminal.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use nav440_cli::replay;
use nav440_cli::serial::StdDelay;
use nav440_proto::boot::{self, BootError, Options, Report, Target};
use nav440_proto::driver::{IoDriver, Timing};
use nav440_proto::{Baud, FieldId, PacketRate, PacketType, Parser};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-sim-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// Starts `nav440 sim CAPTURE --listen L ARGS`; returns the child and the address it printed.
fn start_sim(capture: &str, listen: &str, args: &[&str]) -> (Child, String) {
    start_sim_at(&data(capture), listen, args)
}

/// [`start_sim`] on a capture anywhere.
fn start_sim_at(capture: &Path, listen: &str, args: &[&str]) -> (Child, String) {
    let mut child = Command::new(BIN)
        .arg("sim")
        .arg(capture)
        .args(["--listen", listen])
        .args(if args.contains(&"--timeout") {
            &[][..]
        } else {
            &["--timeout", "60"][..]
        })
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    (child, line.trim().to_string())
}

fn finish(child: Child) -> (i32, String) {
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[derive(Debug)]
struct TcpError(std::io::Error);

impl std::fmt::Display for TcpError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for TcpError {}

impl embedded_io::Error for TcpError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

/// A TCP connection as an embedded-io serial port (what QEMU's `-serial tcp:` gives the
/// firmware): a UART that ignores baud.
struct TcpIo {
    s: TcpStream,
    buf: Vec<u8>,
    eof: bool,
}

impl TcpIo {
    fn connect(addr: &str) -> Self {
        let s = TcpStream::connect(addr.strip_prefix("tcp:").unwrap()).unwrap();
        s.set_nonblocking(true).unwrap();
        Self {
            s,
            buf: Vec::new(),
            eof: false,
        }
    }

    fn fill(&mut self) -> Result<(), TcpError> {
        let mut b = [0u8; 4096];
        match self.s.read(&mut b) {
            Ok(0) => self.eof = true,
            Ok(n) => self.buf.extend_from_slice(&b[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(TcpError(e)),
        }
        Ok(())
    }

    /// Everything until the unit closes the connection.
    fn read_to_end(mut self) -> Vec<u8> {
        self.s.set_nonblocking(false).unwrap();
        let mut rest = std::mem::take(&mut self.buf);
        self.s.read_to_end(&mut rest).unwrap();
        rest
    }
}

impl embedded_io::ErrorType for TcpIo {
    type Error = TcpError;
}

impl embedded_io::Read for TcpIo {
    fn read(&mut self, out: &mut [u8]) -> Result<usize, TcpError> {
        while self.buf.is_empty() && !self.eof {
            self.fill()?;
            if self.buf.is_empty() {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        let n = out.len().min(self.buf.len());
        out[..n].copy_from_slice(&self.buf[..n]);
        self.buf.drain(..n);
        Ok(n)
    }
}

impl embedded_io::ReadReady for TcpIo {
    fn read_ready(&mut self) -> Result<bool, TcpError> {
        if self.buf.is_empty() {
            self.fill()?;
        }
        Ok(!self.buf.is_empty())
    }
}

impl embedded_io::Write for TcpIo {
    fn write(&mut self, b: &[u8]) -> Result<usize, TcpError> {
        loop {
            match self.s.write(b) {
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(1))
                }
                r => return r.map_err(TcpError),
            }
        }
    }
    fn flush(&mut self) -> Result<(), TcpError> {
        Ok(())
    }
}

/// Boots the unit at `addr` like the firmware (search every baud, 3 pings, short time-outs).
fn boot_tcp(addr: &str, target: Target) -> (Result<Report, BootError<TcpError>>, IoDriver<TcpIo>) {
    boot_tcp_timeout(addr, target, 100)
}

/// [`boot_tcp`] with another reply time-out, ms.
fn boot_tcp_timeout(
    addr: &str,
    target: Target,
    reply_timeout_ms: u32,
) -> (Result<Report, BootError<TcpError>>, IoDriver<TcpIo>) {
    let mut d = IoDriver::new(TcpIo::connect(addr));
    d.set_timing(Timing {
        reply_timeout_ms,
        poll_step_us: 500,
    });
    let r = boot::boot(&mut d, &target, &Options::DEFAULT, &mut StdDelay, |_, _| {
        Ok(())
    });
    (r, d)
}

/// The bytes after the read-back reply: the driver's pending bytes, then the connection.
fn rest_of_stream(d: IoDriver<TcpIo>) -> Vec<u8> {
    let mut rest = d.pending_bytes().to_vec();
    rest.extend(d.release().read_to_end());
    rest
}

fn count(bytes: &[u8], t: PacketType) -> u64 {
    let mut p = Parser::new();
    p.feed(bytes, |_| {});
    p.stats().count(t)
}

#[test]
fn tcp_session_streams_the_capture_after_the_read_back_and_records_exactly_it() {
    let record = tmp("tcp.bin");
    let summary = tmp("tcp.json");
    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &[
            "--fast",
            "--record",
            record.to_str().unwrap(),
            "--summary",
            summary.to_str().unwrap(),
        ],
    );
    let (r, d) = boot_tcp(&addr, Target::DEFAULT);
    let report = r.unwrap();
    // Emulated link: 57600 answers the first ping; the unit says 38400 (its power-up baud).
    assert_eq!(report.found_at, Baud::B57600);
    assert_eq!(report.unit_baud, Baud::B38400);
    assert_eq!(report.initial_packet, PacketType::S1);
    assert_eq!(report.initial_rate_divider, 5);
    assert!(report.switched);
    let rest = rest_of_stream(d);
    let (code, err) = finish(child);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("capture done: closed"), "{err}");
    // --record holds exactly the bytes the host received after its read-back reply.
    assert_eq!(std::fs::read(&record).unwrap(), rest);
    // Re-encoded as A2 at 100 Hz, the samples are the capture's (time, yaw, rate).
    let capture = std::fs::read(data("fig5_a2_100hz.bin")).unwrap();
    assert_eq!(
        replay::samples(&rest).unwrap(),
        replay::samples(&capture).unwrap()
    );
    assert_eq!(
        count(&rest, PacketType::A2),
        count(&capture, PacketType::A2)
    );
}

#[test]
fn capture_is_re_encoded_as_the_commanded_type_and_decimated_to_the_commanded_rate() {
    let record = tmp("n1.bin");
    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &["--fast", "--record", record.to_str().unwrap()],
    );
    // N1 at 50 Hz: 49 x 50 = 2450 B/s, fits 57600 Bd.
    let target = Target {
        packet: PacketType::N1,
        rate: PacketRate::Hz50,
        ..Target::DEFAULT
    };
    let (r, d) = boot_tcp(&addr, target);
    r.unwrap();
    let rest = rest_of_stream(d);
    assert_eq!(finish(child).0, 0);
    let capture = replay::samples(&std::fs::read(data("fig5_a2_100hz.bin")).unwrap()).unwrap();
    let got = replay::samples(&rest).unwrap();
    assert_eq!(count(&rest, PacketType::N1) as usize, got.len());
    // Every other 10 ms sample: 20 ms apart, values of the capture's even samples.
    let even: Vec<_> = capture.iter().step_by(2).copied().collect();
    assert_eq!(got, even);
}

#[test]
fn unit_already_at_57600_is_not_switched() {
    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &["--fast", "--baud", "57600"],
    );
    let (r, d) = boot_tcp(&addr, Target::DEFAULT);
    let report = r.unwrap();
    assert_eq!(report.unit_baud, Baud::B57600);
    assert!(!report.switched);
    rest_of_stream(d);
    assert_eq!(finish(child).0, 0);
}

#[test]
fn fault_no_answer_ends_in_no_answer_at_every_baud() {
    for fault in ["no-answer", "dead"] {
        let (child, addr) = start_sim("fig5_a2_100hz.bin", "tcp:127.0.0.1:0", &["--fault", fault]);
        let (r, d) = boot_tcp_timeout(&addr, Target::DEFAULT, 25);
        let e = r.unwrap_err();
        assert_eq!(
            e.to_string(),
            "no answer from the unit: PK unanswered at 57600, 38400, 19200, 9600 Bd (3 x 25 ms each)"
        );
        drop(d); // the host gives up and closes: the simulator ends too
        let (code, err) = finish(child);
        assert_eq!(code, 0, "{err}");
        assert!(err.contains("host closed the connection"), "{err}");
    }
}

#[test]
fn fault_nak_config_and_wrong_readback() {
    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &["--fault", "nak-config"],
    );
    let (r, d) = boot_tcp(&addr, Target::DEFAULT);
    assert_eq!(
        r.unwrap_err().to_string(),
        "unit rejected (NAK) SF: packet type 0x0003=0x4132 (A2), rate divider 0x0001=1 (100 Hz)"
    );
    drop(d);
    assert_eq!(finish(child).0, 0);

    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &["--fault", "wrong-readback"],
    );
    let (r, d) = boot_tcp(&addr, Target::DEFAULT);
    assert!(matches!(
        r.unwrap_err(),
        BootError::WrongReadBack {
            field: FieldId::PACKET_RATE_DIVIDER,
            expected: 1,
            got: Some(5)
        }
    ));
    drop(d);
    assert_eq!(finish(child).0, 0);
}

#[test]
fn fault_reset_stops_the_stream_and_goes_back_to_power_up() {
    let record = tmp("reset.bin");
    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &[
            "--fast",
            "--fault",
            "reset",
            "--reset-after",
            "40",
            "--record",
            record.to_str().unwrap(),
        ],
    );
    let (r, mut d) = boot_tcp(&addr, Target::DEFAULT);
    r.unwrap();
    // Read until 3 power-up S1 frames (20 Hz: ~0.25 s) have come after the A2 stream.
    let mut seen = d.pending_bytes().to_vec();
    let mut s1 = 0;
    while s1 < 3 {
        d.poll(|p| {
            if p.map(|p| p.packet_type()) == Ok(PacketType::S1) {
                s1 += 1;
            }
        })
        .unwrap();
    }
    let stats = *d.stats();
    seen.clear();
    drop(d);
    let (code, err) = finish(child);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("reset mid-stream"), "{err}");
    // 40 A2 packets after the read-back, recorded; the S1 frames after the reset are not.
    assert_eq!(stats.count(PacketType::A2), 40);
    let rec = std::fs::read(&record).unwrap();
    assert_eq!(count(&rec, PacketType::A2), 40);
    assert_eq!(count(&rec, PacketType::S1), 0);
}

#[test]
fn usage_and_input_errors_are_one_line_with_their_exit_code() {
    let out = Command::new(BIN)
        .args(["sim", "x.bin", "--listen", "udp:1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("expected tcp:HOST:PORT"), "{err}");
    let out = Command::new(BIN)
        .args(["sim", "/nonexistent.bin", "--listen", "tcp:127.0.0.1:0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let out = Command::new(BIN)
        .args(["config", "--port", "/nonexistent-tty"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    // A target over the unit's budget is refused before the port is opened.
    let out = Command::new(BIN)
        .args(["config", "--port", "/nonexistent-tty", "--packet", "N1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("4900 B/s does not fit 57600 Bd"));
}

// --- host tools on a serial port, against the simulator through a pseudo-terminal ---

fn nav440(args: &[&str]) -> std::process::Output {
    Command::new(BIN).args(args).output().unwrap()
}

#[test]
fn live_over_a_pty_prints_what_estimate_prints_on_the_recorded_bytes() {
    let record = tmp("pty-live.bin");
    let (child, path) = start_sim(
        "sin5_a1_50hz.bin",
        "pty",
        &["--fast", "--record", record.to_str().unwrap()],
    );
    let out = nav440(&["live", "--port", &path, "--rate", "50"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(finish(child).0, 0);
    let est = nav440(&["estimate", record.to_str().unwrap()]);
    assert_eq!(est.status.code(), Some(0));
    assert!(!est.stdout.is_empty());
    assert_eq!(out.stdout, est.stdout);
    // And the recorded A2 stream carries the A1 capture's samples.
    let capture = std::fs::read(data("sin5_a1_50hz.bin")).unwrap();
    assert_eq!(
        replay::samples(&std::fs::read(&record).unwrap()).unwrap(),
        replay::samples(&capture).unwrap()
    );
}

#[test]
fn record_over_a_pty_writes_the_bytes_the_simulator_recorded() {
    let record = tmp("pty-sim.bin");
    let out_file = tmp("pty-record.bin");
    let (child, path) = start_sim(
        "fig5_a2_100hz.bin",
        "pty",
        &["--fast", "--record", record.to_str().unwrap()],
    );
    let out = nav440(&["record", "--port", &path, "-o", out_file.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(finish(child).0, 0);
    let got = std::fs::read(&out_file).unwrap();
    assert!(!got.is_empty());
    assert_eq!(got, std::fs::read(&record).unwrap());
}

#[test]
fn config_over_a_pty_reports_the_boot_as_json() {
    let (child, path) = start_sim("fig5_a2_100hz.bin", "pty", &["--timeout", "30"]);
    let out = nav440(&["config", "--port", &path, "--persist"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["found_at"], 57600);
    assert_eq!(v["unit_baud"], 38400);
    assert_eq!(v["switched"], true);
    assert_eq!(v["baud"], 57600);
    assert_eq!(v["packet"], "A2");
    assert_eq!(v["initial_packet"], "S1");
    // The host left; over a pty the simulator would see that only at its --timeout.
    stop(child);
}

/// `nav440 sim` on the fig5 capture through a pty with `--fault FAULT` (30 s time-out).
fn faulty_unit_on_a_pty(fault: &str) -> (Child, String) {
    start_sim(
        "fig5_a2_100hz.bin",
        "pty",
        &["--timeout", "30", "--fault", fault],
    )
}

/// A unit that NAKs the packet type: `config` and `live` stop at the boot with one line, exit
/// 1; `live`'s line also says why (as an IMU440 would NAK every angle packet).
#[test]
fn config_and_live_over_a_pty_report_a_nak_in_one_line() {
    for cmd in ["config", "live"] {
        let (child, path) = faulty_unit_on_a_pty("nak-config");
        let out = nav440(&[cmd, "--port", &path, "--reply-timeout", "100"]);
        assert_eq!(out.status.code(), Some(1), "{cmd}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{cmd}: {err}");
        assert!(
            err.contains("unit rejected (NAK) SF: packet type 0x0003=0x4132 (A2)"),
            "{err}"
        );
        assert!(
            err.contains("(the unit does not stream A2: an IMU440 streams no angle packets;"),
            "{err}"
        );
        assert!(out.stdout.is_empty(), "{cmd}");
        stop(child);
    }
}

fn stop(mut child: Child) {
    let _ = child.kill();
    let _ = child.wait();
}

// --- deadlines that hold, outputs checked before serving, no byte lost at an interrupt ---

/// `--timeout` over TCP ends the session although the host stops reading: the unit streams a
/// 5 MB capture with `--fast` to a host that booted it and then reads nothing (every socket
/// buffer fills and the unit's writes block); it exits 1 within 3x the deadline, with the
/// summary it writes naming the time-out.
#[test]
fn sim_timeout_ends_a_tcp_session_whose_host_stops_reading() {
    let big = tmp("big40.bin");
    let one = std::fs::read(data("fig5_a2_100hz.bin")).unwrap();
    std::fs::write(&big, one.repeat(40)).unwrap();
    let summary = tmp("tcp-stall.json");
    let started = std::time::Instant::now();
    let (child, addr) = start_sim_at(
        &big,
        "tcp:127.0.0.1:0",
        &[
            "--fast",
            "--timeout",
            "3",
            "--summary",
            summary.to_str().unwrap(),
        ],
    );
    let (r, d) = boot_tcp(&addr, Target::DEFAULT);
    r.unwrap();
    // The host keeps the connection open and reads nothing.
    let (code, err) = finish(child);
    let elapsed = started.elapsed();
    drop(d);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("session not over after --timeout 3 s"),
        "{err}"
    );
    assert!(elapsed < Duration::from_secs(9), "ended after {elapsed:?}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&summary).unwrap()).unwrap();
    assert_eq!(v["completed"], false);
    assert_eq!(v["error"], "session not over after --timeout 3 s");
    // It streamed, and less than the capture: the host's buffers filled.
    let packets = v["packets"].as_u64().unwrap();
    assert!(packets > 0 && packets < 40 * 3501, "{v}");
}

/// `--timeout` over a pseudo-terminal ends the session although the host stops reading:
/// `nav440 config` boots the unit (which then streams with `--fast`) and leaves; the pty's
/// buffer fills, and the unit exits 1 within 3x the deadline.
#[test]
fn sim_timeout_ends_a_pty_session_whose_host_stops_reading() {
    let started = std::time::Instant::now();
    let (child, path) = start_sim("fig5_a2_100hz.bin", "pty", &["--fast", "--timeout", "3"]);
    let out = nav440(&["config", "--port", &path]);
    assert_eq!(out.status.code(), Some(0));
    let (code, err) = finish(child);
    let elapsed = started.elapsed();
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("session not over after --timeout 3 s"),
        "{err}"
    );
    assert!(elapsed < Duration::from_secs(9), "ended after {elapsed:?}");
}

/// `--record` and `--summary` are checked before the unit serves: a path that cannot be
/// written is exit 5, the capture itself exit 2, standard output exit 2, each before the
/// address is printed, and no file changes.
#[test]
fn sim_checks_its_output_paths_before_serving() {
    let cap = tmp("sim-out-cap.bin");
    std::fs::copy(data("fig5_a2_100hz.bin"), &cap).unwrap();
    let before = std::fs::read(&cap).unwrap();
    let missing = tmp("no-such-dir").join("r.bin");
    let cap_s = cap.to_str().unwrap();
    for (args, want) in [
        (vec!["--record", missing.to_str().unwrap()], 5),
        (vec!["--summary", missing.to_str().unwrap()], 5),
        (vec!["--record", cap_s], 2),
        (vec!["--summary", cap_s], 2),
        (vec!["--record", "-"], 2),
    ] {
        let out = Command::new(BIN)
            .args([
                "sim",
                cap_s,
                "--listen",
                "tcp:127.0.0.1:0",
                "--timeout",
                "30",
            ])
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(want), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}: served");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(std::fs::read(&cap).unwrap(), before);
    }
}

/// `--address-file F.txt` goes through a temporary file of its own: an existing `F.tmp`
/// is left as it was, and `F.txt` holds the address line.
#[test]
fn sim_address_file_leaves_an_existing_tmp_file_alone() {
    let f = tmp("addr.txt");
    let t = tmp("addr.tmp");
    std::fs::write(&t, "not the simulator's\n").unwrap();
    let (child, addr) = start_sim(
        "fig5_a2_100hz.bin",
        "tcp:127.0.0.1:0",
        &["--timeout", "1", "--address-file", f.to_str().unwrap()],
    );
    let (code, err) = finish(child);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no host connected before --timeout"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&t).unwrap(),
        "not the simulator's\n"
    );
    assert_eq!(std::fs::read_to_string(&f).unwrap(), format!("{addr}\n"));
}

/// `nav440 record` stopped by SIGINT (Ctrl-C) keeps every byte it received: against the
/// simulator at 100 Hz in wall time, the file grows as frames arrive (written chunk by
/// chunk), and after the interrupt it holds at least what it held before, exactly the
/// capture's first bytes (the simulator streams the A2 capture unchanged), and record exits 0
/// saying it was interrupted.
#[test]
fn record_keeps_every_byte_received_before_sigint() {
    let out_file = tmp("sigint.bin");
    let (sim, path) = start_sim("fig5_a2_100hz.bin", "pty", &["--timeout", "30"]);
    let mut rec = Command::new(BIN)
        .args(["record", "--port", &path, "-o", out_file.to_str().unwrap()])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // 100 frames (1 s at 100 Hz) on disk while recording: nothing waits in a buffer.
    let frame = 37u64;
    let mut seen = 0;
    for _ in 0..3000 {
        seen = std::fs::metadata(&out_file).map_or(0, |m| m.len());
        if seen >= 100 * frame {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(seen >= 100 * frame, "the file did not grow: {seen} bytes");
    let st = Command::new("kill")
        .args(["-INT", &rec.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let mut err = String::new();
    rec.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    let code = rec.wait().unwrap().code();
    stop(sim);
    assert_eq!(code, Some(0), "{err}");
    let got = std::fs::read(&out_file).unwrap();
    assert!(got.len() as u64 >= seen, "{} < {seen}", got.len());
    let capture = std::fs::read(data("fig5_a2_100hz.bin")).unwrap();
    assert_eq!(got[..], capture[..got.len()]);
    assert!(
        err.contains(&format!(
            "nav440 record: interrupted: {} bytes written to",
            got.len()
        )),
        "{err}"
    );
}

/// `nav440 record -o -` writes the stream to standard output.
#[test]
fn record_dash_writes_standard_output() {
    let (child, path) = start_sim("fig5_a2_100hz.bin", "pty", &["--fast"]);
    let out = nav440(&["record", "--port", &path, "-o", "-"]);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(finish(child).0, 0);
    assert_eq!(
        out.stdout,
        std::fs::read(data("fig5_a2_100hz.bin")).unwrap()
    );
}

// --- the unit's identity, the ports, `live` with estimate's options and its chart ---

/// `nav440 info` finds the simulated unit, reads its settings and prints the ID and VR the
/// unit model answers (`nav440_proto::unit::SERIAL_NUMBER`, `MODEL`, version 1.0.0), as text
/// and as JSON; it sends no SF, so the unit stays at its power-up output (S1 at 20 Hz, 38400 Bd).
#[test]
fn info_over_a_pty_prints_the_simulated_units_serial_number_and_version() {
    let (child, path) = start_sim("fig5_a2_100hz.bin", "pty", &["--timeout", "30"]);
    let out = nav440(&["info", "--port", &path]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let serial = nav440_proto::unit::SERIAL_NUMBER;
    let model = std::str::from_utf8(nav440_proto::unit::MODEL).unwrap();
    assert_eq!(serial, 4_400_001);
    for line in [
        format!("serial number: {serial}"),
        format!("part number:   {model}"),
        "firmware:      1.0.0 (release candidate, build 0)".to_string(),
        "baud:          38400 Bd (answered at 57600 Bd)".to_string(),
        "output:        S1 at 20 Hz".to_string(),
    ] {
        assert!(text.lines().any(|l| l == line), "{line:?} not in\n{text}");
    }
    assert!(text.contains("angles:        not in S1;"), "{text}");
    let out = nav440(&["info", "--port", &path, "--json"]);
    assert_eq!(out.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["serial_number"], serial);
    assert_eq!(v["model"], model);
    assert_eq!(v["version"], "1.0.0");
    assert_eq!(v["unit_baud"], 38400);
    assert_eq!(
        (v["packet"].as_str(), v["rate_divider"].as_u64()),
        (Some("S1"), Some(5))
    );
    assert_eq!(v["carries_angles"], false);
    stop(child);
}

/// A unit that answers nothing: `info` says so in one line, exit 4, within its time-outs.
#[test]
fn info_of_a_silent_unit_is_no_answer_exit_4() {
    for fault in ["no-answer", "dead"] {
        let (child, path) = faulty_unit_on_a_pty(fault);
        let t0 = std::time::Instant::now();
        let out = nav440(&[
            "info",
            "--port",
            &path,
            "--reply-timeout",
            "50",
            "--pings",
            "1",
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(4), "{fault}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("no answer from the unit: PK unanswered at 57600, 38400, 19200, 9600 Bd (1 x 50 ms each)"),
            "{err}"
        );
        assert!(out.stdout.is_empty());
        assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
        stop(child);
    }
}

/// `nav440 ports` lists the serial ports, one `DEV<TAB>KIND` line each, or says there is
/// none; exit 0 either way.
#[test]
fn ports_lists_the_serial_ports_and_exits_0() {
    let out = nav440(&["ports"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    let err = String::from_utf8_lossy(&out.stderr);
    if text.is_empty() {
        assert!(err.contains("no serial port found"), "{err}");
    }
    for line in text.lines() {
        let (dev, kind) = line.split_once('\t').unwrap_or_else(|| panic!("{line:?}"));
        assert!(dev.starts_with("/dev/") && !kind.is_empty(), "{line:?}");
    }
}

/// `live` takes estimate's options: `--bank product --axis all` over the pty prints what
/// `nav440 estimate --bank product --axis all` prints on the recorded bytes.
#[test]
fn live_with_the_product_bank_on_every_axis_prints_what_estimate_prints() {
    let record = tmp("pty-live-product.bin");
    let (child, path) = start_sim(
        "sin5_a1_50hz.bin",
        "pty",
        &["--fast", "--record", record.to_str().unwrap()],
    );
    let opts = ["--bank", "product", "--axis", "all", "--hold", "zoh"];
    let mut args = vec!["live", "--port", &path, "--rate", "50"];
    args.extend(opts);
    let out = nav440(&args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(finish(child).0, 0);
    let mut args = vec!["estimate", record.to_str().unwrap()];
    args.extend(opts);
    let est = nav440(&args);
    assert_eq!(est.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        text.lines().next(),
        Some("t,roll,roll_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_rate,yaw_ilo1_v,yaw_kf_a")
    );
    assert!(text.lines().count() > 400, "{}", text.lines().count());
    assert_eq!(out.stdout, est.stdout);
}

/// Usage errors of `live`, before the port is opened: a packet without angles, `--plot`
/// without a terminal.
#[test]
fn live_refuses_a_packet_without_angles_and_a_plot_without_a_terminal() {
    let out = nav440(&[
        "live",
        "--port",
        "/nonexistent/tty",
        "--packet",
        "S1",
        "--rate",
        "20",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(
        err.trim(),
        "nav440: --packet S1: it carries no angles, and `nav440 live` estimates from them: use \
         one of A0, A1, A2, N0, N1, B1"
    );
    let out = nav440(&["live", "--port", "/nonexistent/tty", "--plot"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--plot draws on a terminal"), "{err}");
}

/// A private tmux server (its own socket), killed when dropped.
struct Tmux(String);

impl Tmux {
    fn cmd(&self, args: &[&str]) -> std::process::Output {
        Command::new("tmux")
            .args(["-L", &self.0])
            .args(args)
            .output()
            .expect("tmux runs")
    }
    fn capture(&self) -> String {
        String::from_utf8_lossy(&self.cmd(&["capture-pane", "-p"]).stdout).into_owned()
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.cmd(&["kill-server"]);
    }
}

/// The row count on the chart's first line (`... rows N  t ...`).
fn rows_shown(screen: &str) -> Option<u64> {
    let first = screen.lines().next()?;
    let rest = &first[first.find("  rows ")? + 7..];
    rest.split_whitespace().next()?.parse().ok()
}

/// `nav440 live --plot` in a 120 x 40 tmux pane against the simulator streaming the fig5
/// capture in wall time (35 s at 100 Hz): the chart shows its titles and legend, the row count
/// grows between two captures of the pane, `q` quits with exit 0 and restores the screen.
#[test]
fn live_plot_draws_the_chart_in_a_terminal() {
    let have = Command::new("tmux").arg("-V").output();
    assert!(
        have.as_ref().is_ok_and(|o| o.status.success()),
        "tmux is needed for this test (`apt-get install tmux`; `cargo xtask ci` installs it): {have:?}"
    );
    let (child, path) = start_sim("fig5_a2_100hz.bin", "pty", &["--timeout", "60"]);
    let rc = tmp("plot.rc");
    let err = tmp("plot.err");
    let _ = std::fs::remove_file(&rc);
    let shell = format!(
        "'{BIN}' live --port '{path}' --plot 2>'{}'; echo $? >'{}'; sleep 60",
        err.display(),
        rc.display()
    );
    let tmux = Tmux(format!("nav440-test-{}", std::process::id()));
    let started = tmux.cmd(&["new-session", "-d", "-x", "120", "-y", "40", &shell]);
    assert!(started.status.success(), "{started:?}");
    // Wait for the chart with rows (the boot and the 16-sample warm-up come first).
    let wait_for = |pred: &dyn Fn(&str) -> bool| {
        let t0 = std::time::Instant::now();
        loop {
            let s = tmux.capture();
            if pred(&s) || t0.elapsed() > Duration::from_secs(20) {
                return s;
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    };
    let first = wait_for(&|s| rows_shown(s).is_some_and(|n| n >= 100));
    let n1 = rows_shown(&first).unwrap_or_else(|| panic!("no row count on\n{first}"));
    for text in [
        "nav440 live",
        "bank paper",
        "yaw rate, deg/s",
        "yaw acceleration, deg/s^2",
        "rate (reference)",
        "ilo1_v",
        "kf_a",
        "q: quit",
    ] {
        assert!(first.contains(text), "{text:?} not on the screen:\n{first}");
    }
    // Braille dots: the traces are drawn.
    assert!(
        first
            .chars()
            .any(|c| ('\u{2801}'..='\u{28FF}').contains(&c)),
        "{first}"
    );
    let second = wait_for(&|s| rows_shown(s).is_some_and(|n| n >= n1 + 100));
    let n2 = rows_shown(&second).unwrap_or(0);
    assert!(n2 >= n1 + 100, "rows {n1} then {n2}:\n{second}");
    let _ = tmux.cmd(&["send-keys", "q"]);
    let t0 = std::time::Instant::now();
    while !rc.exists() && t0.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(100));
    }
    let code = std::fs::read_to_string(&rc).unwrap_or_default();
    let log = std::fs::read_to_string(&err).unwrap_or_default();
    assert_eq!(code.trim(), "0", "{log}");
    assert!(log.contains("rows plotted"), "{log}");
    // The screen is restored: the chart is gone.
    assert!(!tmux.capture().contains("yaw rate, deg/s"));
    stop(child);
}
