//! No file is lost, no output is lost silently (docs/RELIABILITY-STREAM.md, "No file is lost"): each
//! case through the real binary, asserting the exit code and that no file changed.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
}

/// A fresh scratch directory per test.
fn scratch(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-nfl-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// The files of `dir`, sorted (a temporary file left behind would show here).
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A copy of the fig5 capture in `dir` as `name`.
fn capture_copy(dir: &Path, name: &str) -> PathBuf {
    let c = dir.join(name);
    std::fs::copy(data("fig5_a2_100hz.bin"), &c).unwrap();
    c
}

#[test]
fn an_output_that_is_the_input_is_refused_before_anything_is_written() {
    let d = scratch("same");
    let c = capture_copy(&d, "c.bin");
    let before = std::fs::read(&c).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    std::fs::hard_link(&c, d.join("link.bin")).unwrap();
    let g = d.join("g.toml");
    std::fs::write(&g, "[velocity.ad]\nt = 0.02\n").unwrap();
    let gains_before = std::fs::read(&g).unwrap();
    for args in [
        vec!["estimate", "c.bin", "-o", "c.bin"],
        // Another name of the same file: same device and inode.
        vec!["estimate", "c.bin", "-o", "sub/../c.bin"],
        vec!["estimate", "c.bin", "-o", "link.bin"],
        vec!["estimate", "c.bin", "--gains", "g.toml", "-o", "g.toml"],
        vec!["plot", "c.bin", "-o", "c.bin"],
        vec!["plot", "c.bin", "-o", "link.bin"],
        vec!["tune", "c.bin", "--noise-var", "0.01", "-o", "c.bin"],
        vec!["tune", "c.bin", "--noise-var", "0.01", "--rust", "link.bin"],
    ] {
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
        assert!(o.stdout.is_empty());
        assert_eq!(std::fs::read(&c).unwrap(), before, "{args:?}");
        assert_eq!(std::fs::read(&g).unwrap(), gains_before, "{args:?}");
    }
    assert_eq!(files(&d), ["c.bin", "g.toml", "link.bin", "sub"]);
}

#[test]
fn a_failing_command_leaves_an_existing_output_as_it_was() {
    let d = scratch("fail");
    capture_copy(&d, "c.bin");
    std::fs::write(d.join("notes.txt"), "not a capture\n").unwrap();
    let keep = b"yesterday's results\n";
    for out in ["out.csv", "out.svg", "out.bin", "out.toml"] {
        std::fs::write(d.join(out), keep).unwrap();
    }
    for (args, code) in [
        (vec!["estimate", "notes.txt", "-o", "out.csv"], 4),
        (vec!["estimate", "missing.bin", "-o", "out.csv"], 3),
        (vec!["plot", "notes.txt", "-o", "out.svg"], 4),
        (vec!["synth", "--duration", "1e12", "-o", "out.bin"], 2),
        (
            vec!["tune", "notes.txt", "--noise-var", "0.01", "-o", "out.toml"],
            4,
        ),
    ] {
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {}", stderr(&o));
        for out in ["out.csv", "out.svg", "out.bin", "out.toml"] {
            assert_eq!(std::fs::read(d.join(out)).unwrap(), keep, "{args:?}");
        }
        // No temporary file left behind.
        assert_eq!(
            files(&d),
            [
                "c.bin",
                "notes.txt",
                "out.bin",
                "out.csv",
                "out.svg",
                "out.toml"
            ],
            "{args:?}"
        );
    }
}

#[cfg(unix)]
#[test]
fn an_output_is_replaced_whole_and_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let d = scratch("replace");
    capture_copy(&d, "c.bin");
    let out = d.join("out.csv");
    std::fs::write(&out, "old\n").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
    let o = run_in(&d, &["estimate", "c.bin", "-o", "out.csv"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    let stdout = run_in(&d, &["estimate", "c.bin"]);
    assert_eq!(std::fs::read(&out).unwrap(), stdout.stdout);
    assert_eq!(stdout.stdout.iter().filter(|&&b| b == b'\n').count(), 3502);
    let mode = std::fs::metadata(&out).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
    assert_eq!(files(&d), ["c.bin", "out.csv"]);
    // A symbolic link is followed: its target gets the output, the link stays a link.
    std::os::unix::fs::symlink("out.csv", d.join("via-link.csv")).unwrap();
    std::fs::write(&out, "old\n").unwrap();
    let o = run_in(&d, &["estimate", "c.bin", "-o", "via-link.csv"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(d.join("via-link.csv"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read(&out).unwrap(), stdout.stdout);
}

#[test]
fn dash_means_standard_output_for_every_command_with_an_output() {
    let d = scratch("dash");
    capture_copy(&d, "c.bin");
    // estimate
    let to_stdout = run_in(&d, &["estimate", "c.bin"]);
    let dash = run_in(&d, &["estimate", "c.bin", "-o", "-"]);
    assert_eq!(dash.status.code(), Some(0));
    assert_eq!(dash.stdout, to_stdout.stdout);
    // synth: the capture on stdout, the summary on stderr.
    let dash = run_in(&d, &["synth", "--duration", "2", "-o", "-"]);
    assert_eq!(dash.status.code(), Some(0), "{}", stderr(&dash));
    let file = run_in(&d, &["synth", "--duration", "2", "-o", "s.bin"]);
    assert_eq!(file.status.code(), Some(0));
    assert_eq!(dash.stdout, std::fs::read(d.join("s.bin")).unwrap());
    assert_eq!(dash.stdout.len(), 201 * 37);
    let summary: serde_json::Value = serde_json::from_str(stderr(&dash).trim()).unwrap();
    assert_eq!(summary["file"], "standard output");
    assert_eq!(summary["packets"], 201);
    // tune: the gains file on stdout, the report on stderr.
    let args = [
        "tune",
        "c.bin",
        "--noise-var",
        "0.01",
        "--seeds",
        "1",
        "--exhaustive",
        "2",
        "--hold",
        "linear",
        "--window",
        "3",
    ];
    let mut with_file = args.to_vec();
    with_file.extend(["-o", "g.toml"]);
    let file = run_in(&d, &with_file);
    assert_eq!(file.status.code(), Some(0), "{}", stderr(&file));
    let mut with_dash = args.to_vec();
    with_dash.extend(["-o", "-"]);
    let dash = run_in(&d, &with_dash);
    assert_eq!(dash.status.code(), Some(0), "{}", stderr(&dash));
    assert_eq!(dash.stdout, std::fs::read(d.join("g.toml")).unwrap());
    assert!(stderr(&dash).contains("velocity, MSE (deg/s)^2"));
    // -o - and --rust - together: one standard output for two files.
    let mut both = args.to_vec();
    both.extend(["-o", "-", "--rust", "-"]);
    let o = run_in(&d, &both);
    assert_eq!(o.status.code(), Some(2));
    // plot
    let dash = run_in(&d, &["plot", "c.bin", "-o", "-", "--to", "2"]);
    assert_eq!(dash.status.code(), Some(0));
    assert!(dash.stdout.starts_with(b"<svg"));
    // None of them created a file named `-`.
    assert_eq!(files(&d), ["c.bin", "g.toml", "s.bin"]);
}

/// `>&-`: the command's standard output is closed when it starts.
fn closed_stdout(dir: &Path, args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("exec \"$0\" \"$@\" >&-")
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

#[test]
fn a_closed_or_failing_standard_output_is_an_output_error() {
    let d = scratch("closed");
    capture_copy(&d, "c.bin");
    for args in [
        vec!["stats", "c.bin"],
        vec!["decode", "c.bin"],
        vec!["estimate", "c.bin"],
        vec!["paper", "c.bin"],
        vec!["estimate", "c.bin", "-o", "-"],
        vec!["plot", "c.bin", "-o", "-"],
        vec!["synth", "--duration", "1", "-o", "s.bin"],
        vec!["completions", "bash"],
    ] {
        let o = closed_stdout(&d, &args);
        assert_eq!(o.status.code(), Some(5), "{args:?}: {}", stderr(&o));
        assert_eq!(
            stderr(&o),
            "nav440: cannot write standard output: it is closed (Bad file descriptor)\n"
        );
        // Refused before the work: synth wrote no file.
        assert_eq!(files(&d), ["c.bin"], "{args:?}");
        // A full device: the write fails.
        if Path::new("/dev/full").exists() {
            let full = std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap();
            let o = Command::new(BIN)
                .args(&args)
                .current_dir(&d)
                .stdout(Stdio::from(full))
                .output()
                .unwrap();
            assert_eq!(o.status.code(), Some(5), "{args:?} > /dev/full");
            assert!(
                stderr(&o).contains("No space left on device"),
                "{}",
                stderr(&o)
            );
        }
        let _ = std::fs::remove_file(d.join("s.bin"));
    }
    // An output file is not standard output: `estimate -o F >&-` works.
    let o = closed_stdout(&d, &["estimate", "c.bin", "-o", "out.csv"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(d.join("out.csv")).unwrap(),
        run_in(&d, &["estimate", "c.bin"]).stdout
    );
}

#[test]
fn record_does_not_touch_its_output_when_the_port_does_not_open() {
    let d = scratch("record");
    let c = capture_copy(&d, "c.bin");
    let before = std::fs::read(&c).unwrap();
    let o = run_in(&d, &["record", "--port", "/dev/ttyUSB9", "-o", "c.bin"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("cannot open serial port /dev/ttyUSB9"));
    assert_eq!(std::fs::read(&c).unwrap(), before);
    assert_eq!(files(&d), ["c.bin"]);
    // A path that cannot be written is found before the port is tried.
    let o = run_in(
        &d,
        &["record", "--port", "/dev/ttyUSB9", "-o", "no/such/dir.bin"],
    );
    assert_eq!(o.status.code(), Some(5), "{}", stderr(&o));
}

#[test]
fn decode_refuses_an_unknown_type() {
    let o = Command::new(BIN)
        .args(["decode", p(&data("fig5_a2_100hz.bin")), "--type", "ZZ"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty());
    assert!(
        stderr(&o).starts_with("nav440: --type \"ZZ\" is not a NAV440 packet type (one of S0, S1,"),
        "{}",
        stderr(&o)
    );
    // Known types in any case still work.
    let o = Command::new(BIN)
        .args(["decode", p(&data("fig5_a2_100hz.bin")), "--type", "a2"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(o.stdout.iter().filter(|&&b| b == b'\n').count(), 3502);
}

#[test]
fn gains_file_range_errors_name_file_table_and_key_before_the_capture_is_read() {
    let d = scratch("gains");
    for (text, want) in [
        (
            "[velocity.ilo1]\nk1 = 2.0\nl = 5.0\nk2 = 0.01\n",
            "g.toml: bad gains file: [velocity.ilo1] key k1: K1 must be in (0, 1]",
        ),
        (
            "[acceleration.ave]\nk = -1.0\ngamma1 = 5.0\n",
            "g.toml: bad gains file: [acceleration.ave] key k: parameter `k` must be > 0",
        ),
        (
            "[velocity.ilo1]\nk1 = 1e39\nl = 5.0\nk2 = 0.01\n",
            "g.toml: bad gains file: [velocity.ilo1] key k1 is 1e39: out of range: every number must be at most 3.4e38 in magnitude (an f32)",
        ),
        (
            "hold = \"linear\"\n[[level]]\nnoise_var = 0.01\n[level.velocity]\n[level.acceleration]\n[[level]]\nnoise_var = 0.1\n[level.acceleration]\n[level.velocity.ad]\nt = 0.0\n",
            "g.toml: bad schedule file: [level.velocity.ad] of level 2 key t: parameter `T` must be > 0",
        ),
    ] {
        std::fs::write(d.join("g.toml"), text).unwrap();
        // The capture does not exist: the gains file's error comes first (exit 2, not 3).
        for cmd in ["estimate", "paper", "plot"] {
            let mut args = vec![cmd, "missing.bin", "--gains", "g.toml"];
            if cmd == "plot" {
                args.extend(["-o", "p.svg"]);
            }
            let o = run_in(&d, &args);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
            assert_eq!(stderr(&o), format!("nav440: {want}\n"), "{args:?}");
        }
    }
    // --bank product checks the tables it does not use too.
    std::fs::write(
        d.join("g.toml"),
        "[velocity.ed]\nlambda = 0.0\nalpha = 5.0\n",
    )
    .unwrap();
    let o = run_in(
        &d,
        &[
            "estimate",
            p(&data("fig5_a2_100hz.bin")),
            "--bank",
            "product",
            "--gains",
            "g.toml",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("[velocity.ed] key lambda"),
        "{}",
        stderr(&o)
    );
    assert_eq!(files(&d), ["g.toml"]);
}

#[test]
fn tune_and_paper_refuse_degenerate_scoring_without_writing() {
    let d = scratch("degenerate");
    let all = std::fs::read(data("fig5_a2_100hz.bin")).unwrap();
    std::fs::write(d.join("two.bin"), &all[..2 * 37]).unwrap();
    std::fs::write(d.join("one.bin"), &all[..37]).unwrap();
    std::fs::write(d.join("g.toml"), "kept\n").unwrap();
    let tune = |file: &str, extra: &[&str]| {
        let mut args = vec![
            "tune",
            file,
            "--noise-var",
            "0.01",
            "--seeds",
            "1",
            "--exhaustive",
            "2",
            "-o",
            "g.toml",
            "--rust",
            "g.rs",
        ];
        args.extend(extra);
        run_in(&d, &args)
    };
    let o = tune("two.bin", &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(
        stderr(&o),
        "nav440: only 2 row(s) to score on the training range 0-30 s: tuning needs at least 3 (fewer give an MSE of 0 whatever the gains)\n"
    );
    std::fs::copy(data("sin5_a1_50hz.bin"), d.join("sin5.bin")).unwrap();
    let o = tune("sin5.bin", &["--test", "100-200"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(
        stderr(&o),
        "nav440: --test 100-200 s holds no row to score (the data spans 0-10.00 s)\n"
    );
    let o = run_in(&d, &["paper", "one.bin"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(o.stdout.is_empty());
    assert_eq!(
        stderr(&o),
        "nav440: one.bin: 1 sample(s) carrying the angle: the paper's tables need at least 3 (fewer give all-zero MSEs)\n"
    );
    assert_eq!(std::fs::read(d.join("g.toml")).unwrap(), b"kept\n");
    assert_eq!(files(&d), ["g.toml", "one.bin", "sin5.bin", "two.bin"]);
}

/// Each family whose tuned gains score worse than its starting gains (the report's "before"
/// and "after" columns) gets its own warning, and no other family does. A 2-point grid on
/// 3 s puts most families at the edge of their search box: worse for 12 of the 14 here.
#[test]
fn tune_warns_for_every_family_it_makes_worse() {
    let o = Command::new(BIN)
        .args([
            "tune",
            p(&data("fig5_a2_100hz.bin")),
            "--noise-var",
            "0.01",
            "--seeds",
            "1",
            "--exhaustive",
            "2",
            "--hold",
            "linear",
            "--window",
            "3",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report = String::from_utf8(o.stdout.clone()).unwrap();
    // The report's two tables: (half, family, before, after).
    let mut worse = Vec::new();
    let mut half = "";
    for line in report.lines() {
        if line.starts_with("velocity, MSE") {
            half = "velocity";
        } else if line.starts_with("acceleration (series), MSE") {
            half = "acceleration";
        } else if !half.is_empty() {
            let cols: Vec<&str> = line.split_whitespace().collect();
            if let [name, before, after, ..] = cols[..] {
                if let (Ok(b), Ok(a)) = (before.parse::<f64>(), after.parse::<f64>()) {
                    if a > b {
                        worse.push(format!("{name} {half}"));
                    }
                }
            }
        }
    }
    assert_eq!(worse.len(), 12, "{report}");
    let warned: Vec<String> = stderr(&o)
        .lines()
        .filter(|l| l.contains("the tuned gains score worse than the starting gains"))
        .map(|l| {
            let l = l.strip_prefix("nav440: warning: ").unwrap();
            l.split(':').next().unwrap().to_string()
        })
        .collect();
    assert_eq!(warned, worse);
    assert!(stderr(&o).contains(
        "nav440: warning: AD velocity: the tuned gains score worse than the starting gains on 0-3 s (MSE 66.651 before, 3551.415 after, hold linear); keep the starting [velocity.ad] table if that matters"
    ), "{}", stderr(&o));
}

/// A tuned ILO velocity set that reads a constant rate more than 0.1 % low gets a warning
/// with its shortfall, computed here from the written gains file by the steady state of the
/// law (`v = K2 e / (1 - K1)` and `L e + v = r`: `K2 / (K2 + L (1 - K1))` of the rate), and the
/// file is still written. A 3-point grid at 0.5 deg^2 on 3 s ends at `L` 9,900, `K2` 3.16,
/// `K1` 0.99969: half the rate.
#[test]
fn tune_warns_for_an_ilo_that_reads_a_constant_rate_low() {
    let d = scratch("tune_constant_rate");
    let out = d.join("g.toml");
    let o = Command::new(BIN)
        .args([
            "tune",
            p(&data("fig5_a2_100hz.bin")),
            "--bank",
            "product",
            "--noise-var",
            "0.5",
            "--seeds",
            "1",
            "--exhaustive",
            "3",
            "--hold",
            "linear",
            "--window",
            "3",
            "-o",
            p(&out),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    let ilo = text.split("[velocity.ilo1]").nth(1).unwrap();
    let value = |key: &str| -> f64 {
        let line = ilo
            .lines()
            .find(|l| l.starts_with(&format!("{key} = ")))
            .unwrap();
        f64::from(line[key.len() + 3..].parse::<f32>().unwrap())
    };
    let (k1, l, k2) = (value("k1"), value("l"), value("k2"));
    let gain = k2 / (k2 + l * (1.0 - k1));
    assert!(gain < 0.6, "{k1} {l} {k2}");
    let warned: Vec<String> = stderr(&o)
        .lines()
        .filter(|l| l.contains("constant rate"))
        .map(str::to_owned)
        .collect();
    assert_eq!(
        warned,
        [format!(
            "nav440: warning: ILO1 velocity: the tuned gains read a constant rate {:.2} % low (K2 / (K2 + L (1 - K1)) = {gain:.5}); a sustained rotation reads low by as much",
            100.0 * (1.0 - gain)
        )]
    );
    let _ = std::fs::remove_dir_all(&d);
}
