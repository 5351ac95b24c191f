//! Bounded memory and errors that point at the cause (docs/RELIABILITY-STREAM.md, "Bounded memory"):
//! each case through the real binary, asserting the exit code, the
//! message and, for memory, that the command succeeds (or stops with its own error) under an
//! address-space limit (`prlimit --as`) that a command holding every packet's row exceeds
//! (exit 134, "memory allocation failed"). The big inputs are generated here (nothing large is stored).

use nav440_cli::synth::{encode_packet, PacketKind};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");
const MIB: u64 = 1 << 20;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
}

/// A fresh scratch directory per test.
fn scratch(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-mem-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `nav440 <args>` under `prlimit --as=<limit>` (bytes of address space), standard input from
/// `stdin` (a file) or nothing.
fn run_limited(limit: u64, args: &[&str], stdin: Option<&Path>) -> Output {
    let mut c = Command::new("prlimit");
    c.arg(format!("--as={limit}")).arg(BIN).args(args);
    c.stdin(match stdin {
        Some(p) => Stdio::from(std::fs::File::open(p).unwrap()),
        None => Stdio::null(),
    });
    c.output().expect("run prlimit (util-linux)")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A 100 Hz A2 capture of `n` packets of a steady 30 deg/s turn (37 bytes each).
fn capture(path: &Path, n: u64) {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for k in 0..n {
        let t = k as f64 * 0.01;
        let yaw = (30.0 * t + 180.0).rem_euclid(360.0) - 180.0;
        w.write_all(&encode_packet(PacketKind::A2, yaw, 30.0, (k * 10) as u32, 0).unwrap())
            .unwrap();
    }
    w.flush().unwrap();
}

/// `sim /dev/zero` read without limit (4.2 GB after 13 s): now stopped at 1 GiB, found while
/// reading, exit 3 with the cap and the way out; a file beyond the cap is refused from its
/// size before a byte is read.
#[test]
fn sim_stops_reading_a_capture_at_1_gib() {
    let o = run_limited(
        1400 * MIB,
        &["sim", "/dev/zero", "--listen", "tcp:127.0.0.1:0"],
        None,
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("/dev/zero: holds more than 1073741824 bytes (1 GiB)")
            && err.contains("head -c"),
        "{err}"
    );
    let d = scratch("sparse");
    let big = d.join("big.bin");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len((1 << 30) + 1).unwrap(); // sparse: no disk used
    drop(f);
    let o = run_limited(
        256 * MIB,
        &["sim", big.to_str().unwrap(), "--listen", "tcp:127.0.0.1:0"],
        None,
    );
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("big.bin: holds more than 1073741824 bytes (1 GiB)"));
    let _ = std::fs::remove_dir_all(&d);
}

/// `paper` held about 0.6 KB per packet (586 MB for 10^6 packets) whatever its window; it now
/// keeps the samples up to the window's end and streams each run into its sums: 5 x 10^5
/// packets on standard input (18.5 MB) under 96 MiB of address space (the old code needed
/// 300 MB), with the whole capture's sample count in the report.
#[test]
fn paper_runs_in_bounded_memory() {
    let d = scratch("paper");
    let c = d.join("c.bin");
    capture(&c, 500_000);
    let o = run_limited(96 * MIB, &["paper", "-", "--json"], Some(&c));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["samples"], 500_000, "{v}");
    assert_eq!(v["rows_in_window"], 3001, "{v}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `plot` held about 0.6 KB per packet and drew every row (166 MB of SVG for 10^6 packets);
/// it now streams the rows into bucketed series: 2 x 10^5 packets under 128 MiB (the old code
/// aborted there), and the SVG stays small.
#[test]
fn plot_runs_in_bounded_memory() {
    let d = scratch("plot");
    let c = d.join("c.bin");
    capture(&c, 200_000);
    let svg = d.join("p.svg");
    let o = run_limited(
        128 * MIB,
        &["plot", c.to_str().unwrap(), "-o", svg.to_str().unwrap()],
        None,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let len = std::fs::metadata(&svg).unwrap().len();
    assert!(len < 4 * MIB, "SVG of {len} bytes");
    let _ = std::fs::remove_dir_all(&d);
}

/// A 50 MB gains file peaked at 1.7-4 GB (parsed three times): now refused after reading
/// 1 MiB + 1 byte, exit 3 naming the file and the cap, under 128 MiB.
#[test]
fn a_gains_file_beyond_1_mib_is_refused_without_parsing_it() {
    let d = scratch("gains");
    let g = d.join("big.toml");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&g).unwrap());
    w.write_all(b"[velocity.ilo1]\n").unwrap();
    for i in 0..4_000_000u32 {
        writeln!(w, "x{i} = 1.0").unwrap();
    }
    drop(w);
    assert!(std::fs::metadata(&g).unwrap().len() > 40_000_000);
    let fig5 = data("fig5_a2_100hz.bin");
    let o = run_limited(
        128 * MIB,
        &[
            "estimate",
            fig5.to_str().unwrap(),
            "--gains",
            g.to_str().unwrap(),
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("big.toml is larger than 1048576 bytes (1 MiB)"),
        "{}",
        stderr(&o)
    );
    assert!(o.stdout.is_empty());
    let _ = std::fs::remove_dir_all(&d);
}

/// ED `alpha = 1e30` passed validation and `ed_v` reached 8e28: now a usage error naming the
/// file, the table and the key, before the capture is read.
#[test]
fn an_ed_alpha_beyond_the_stability_limit_names_file_table_and_key() {
    let d = scratch("ed");
    let g = d.join("ed.toml");
    std::fs::write(&g, "[velocity.ed]\nlambda = 700.0\nalpha = 1e30\n").unwrap();
    let fig5 = data("fig5_a2_100hz.bin");
    for cmd in ["estimate", "paper"] {
        let o = Command::new(BIN)
            .args([cmd, fig5.to_str().unwrap(), "--gains", g.to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(
                "ed.toml: bad gains file: [velocity.ed] key alpha: h * `alpha` must be at most 1e6"
            ),
            "{cmd}: {}",
            stderr(&o)
        );
        assert!(o.stdout.is_empty());
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `paper`, `tune` and `plot` never reported time faults (a reversed capture silently became
/// one sample): each now prints `estimate`'s time-fault line (the same code).
#[test]
fn paper_tune_and_plot_report_time_faults_as_estimate_does() {
    let d = scratch("faults");
    let fwd = d.join("fwd.bin");
    capture(&fwd, 200);
    // The same frames in reverse order: every stamp goes back.
    let bytes = std::fs::read(&fwd).unwrap();
    let rev: Vec<u8> = bytes.chunks(37).rev().flatten().copied().collect();
    let r = d.join("rev.bin");
    std::fs::write(&r, rev).unwrap();
    let rs = r.to_str().unwrap();
    let line = |o: &Output| {
        stderr(o)
            .lines()
            .find(|l| l.contains("time faults:"))
            .map(|l| l[l.find("time faults:").unwrap()..].to_string())
    };
    let est = Command::new(BIN).args(["estimate", rs]).output().unwrap();
    let expected = line(&est).expect("estimate warns");
    assert!(expected.contains("bad_backward=199"), "{expected}");
    let svg = d.join("p.svg");
    let toml = d.join("g.toml");
    for (args, code) in [
        (vec!["paper", rs], 2),
        (vec!["plot", rs, "-o", svg.to_str().unwrap()], 0),
        (
            vec![
                "tune",
                rs,
                "--noise-var",
                "0.01",
                "-o",
                toml.to_str().unwrap(),
            ],
            2,
        ),
    ] {
        let o = Command::new(BIN).args(&args).output().unwrap();
        assert_eq!(o.status.code(), Some(code), "{args:?}: {}", stderr(&o));
        assert_eq!(line(&o).as_deref(), Some(expected.as_str()), "{args:?}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
