//! The end of a finite input: complete frames held behind a false frame header are recovered,
//! and the bytes that did not complete a frame are reported (`estimate`, `decode`, `stats`).
//!
//! The oracle is the bundled capture itself: a false header (`55 55 'A' '2' 200`, announcing
//! 200 payload bytes) inserted before its last two frames adds no frame and removes none, so
//! every output must equal the original capture's, plus one warning naming the 5 bytes.

use std::io::Write;
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");
const FALSE_HEADER: [u8; 5] = [0x55, 0x55, b'A', b'2', 200];
/// Wire length of one A2 frame (30-byte payload + 7).
const A2_FRAME: usize = 37;

fn capture() -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../host-tests/data/fig5_a2_100hz.bin"
    );
    std::fs::read(path).expect("bundled capture")
}

/// The capture with the false header before its last two frames (it ends on a frame boundary:
/// checked by `stats` reporting 0 pending bytes for it).
fn with_false_header(bytes: &[u8]) -> Vec<u8> {
    let at = bytes.len() - 2 * A2_FRAME;
    let mut out = bytes[..at].to_vec();
    out.extend_from_slice(&FALSE_HEADER);
    out.extend_from_slice(&bytes[at..]);
    out
}

fn write_temp(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("nav440-eoi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn run(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run nav440");
    let mut w = child.stdin.take().unwrap();
    if let Some(b) = stdin {
        w.write_all(b).unwrap();
    }
    drop(w);
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const WARNING_5: &str =
    "nav440: warning: the input ends inside a frame: its last 5 bytes did not complete a frame and are dropped";

#[test]
fn estimate_recovers_the_frames_behind_a_false_header_at_the_end() {
    let orig = capture();
    let a = write_temp("orig.bin", &orig);
    let b = write_temp("false-header.bin", &with_false_header(&orig));
    for extra in [&["--axis", "all"][..], &["--bank", "product"][..]] {
        let mut args_a = vec!["estimate", a.to_str().unwrap()];
        args_a.extend_from_slice(extra);
        let mut args_b = vec!["estimate", b.to_str().unwrap()];
        args_b.extend_from_slice(extra);
        let (oa, ob) = (run(&args_a, None), run(&args_b, None));
        assert_eq!(
            oa.stdout, ob.stdout,
            "{extra:?}: the same rows, the last two included"
        );
        assert!(
            !stderr(&oa).contains("ends inside a frame"),
            "{}",
            stderr(&oa)
        );
        assert!(stderr(&ob).contains(WARNING_5), "{}", stderr(&ob));
    }
    // From standard input alike.
    let ob = run(&["estimate", "-"], Some(&with_false_header(&orig)));
    let oa = run(&["estimate", a.to_str().unwrap()], None);
    assert_eq!(oa.stdout, ob.stdout);
    assert!(stderr(&ob).contains(WARNING_5));
}

#[test]
fn decode_and_stats_count_the_recovered_frames() {
    let orig = capture();
    let a = write_temp("orig-d.bin", &orig);
    let b = write_temp("false-header-d.bin", &with_false_header(&orig));
    let (da, db) = (
        run(&["decode", a.to_str().unwrap()], None),
        run(&["decode", b.to_str().unwrap()], None),
    );
    assert_eq!(da.stdout, db.stdout);
    assert!(stderr(&db).contains(WARNING_5), "{}", stderr(&db));
    let dp = run(&["decode", "-"], Some(&with_false_header(&orig)));
    assert_eq!(da.stdout, dp.stdout, "piped input");
    assert!(stderr(&dp).contains(WARNING_5));
    let sa = String::from_utf8(run(&["stats", a.to_str().unwrap()], None).stdout).unwrap();
    let sb = String::from_utf8(run(&["stats", b.to_str().unwrap()], None).stdout).unwrap();
    assert!(sa.contains("\"pending_bytes\":0"), "{sa}");
    // The same frames; the 5 false-header bytes are the pending ones.
    let frames = |s: &str| {
        s[s.find("\"frames\"").unwrap()..]
            .split('}')
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(frames(&sa), frames(&sb));
    assert!(sb.contains("\"pending_bytes\":5"), "{sb}");
}

#[test]
fn a_truncated_last_frame_is_reported() {
    let orig = capture();
    let cut = &orig[..orig.len() - 10];
    let o = run(&["estimate", "-"], Some(cut));
    let want = format!(
        "its last {} bytes did not complete a frame and are dropped",
        A2_FRAME - 10
    );
    assert!(stderr(&o).contains(&want), "{}", stderr(&o));
    // One row fewer than the whole capture.
    let whole = run(&["estimate", "-"], Some(&orig));
    let rows = |o: &Output| o.stdout.iter().filter(|&&b| b == b'\n').count();
    assert_eq!(rows(&o) + 1, rows(&whole));
}
