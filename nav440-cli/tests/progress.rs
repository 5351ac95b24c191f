//! The long commands (`tune`, `tune --schedule`, `tune --exhaustive`, `synth`) draw their
//! progress bar only when stderr is a terminal: with stderr piped, as here, they print no
//! progress text at all.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
}

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-progress-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `nav440 ARGS` with stdout and stderr piped; returns stderr (the command must succeed
/// and print something on stdout).
fn stderr_of(args: &[&str]) -> String {
    let out = Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .expect("run nav440");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{args:?} failed: {stderr}");
    assert!(!out.stdout.is_empty(), "{args:?} printed nothing");
    stderr
}

#[test]
fn piped_long_commands_print_no_progress() {
    let short = data("sin5_a2_25hz_weekwrap.bin");
    let short = short.to_str().unwrap();
    let dir = scratch();
    let synth = dir.join("synth.bin");
    let runs: [&[&str]; 4] = [
        &[
            "tune",
            short,
            "--noise-var",
            "0.01",
            "--seeds",
            "1",
            "--exhaustive",
            "3",
        ],
        &[
            "tune",
            short,
            "--noise-var",
            "0.01",
            "--seeds",
            "1",
            "--hold",
            "linear",
        ],
        &[
            "tune",
            short,
            "--schedule",
            "0.5",
            "--seeds",
            "1",
            "--hold",
            "linear",
        ],
        &["synth", "--duration", "60", "-o", synth.to_str().unwrap()],
    ];
    for args in runs {
        // Only warnings (e.g. a family the tuning made worse), one line each: no progress.
        let stderr = stderr_of(args);
        assert!(
            stderr
                .lines()
                .all(|l| l.starts_with("nav440: warning: ") && !l.contains('\r')),
            "{args:?} wrote on a piped stderr: {stderr:?}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}
