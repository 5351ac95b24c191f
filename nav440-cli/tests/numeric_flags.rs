//! Every numeric flag of every subcommand, walked with `nan`, `inf`, `-1`, `0`, `1e20` and the
//! maximum of the flag's type: no value panics; a refused value is a one-line usage error
//! (exit 2) naming the flag, written before any side effect (no output file, an existing file
//! keeps its contents, no byte sent to the serial port, no address printed by `sim`); a valid
//! value does no out-of-bound work.
//!
//! The flags come from clap ([`Cli::command`]): every argument that takes a value is either
//! in [`NUMERIC`] (walked) or in [`NOT_NUMERIC`], and every argument whose value parser yields
//! a number must be in [`NUMERIC`], so a new numeric flag cannot escape the walk.

use std::any::TypeId;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use clap::CommandFactory;
use nav440_cli::cmd::Cli;
use serialport::SerialPort;

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

/// The walked values; `MAX` stands for the maximum of the flag's type.
const VALUES: [&str; 6] = ["nan", "inf", "-1", "0", "1e20", "MAX"];

/// Numeric flags: (command, flag, how the value is written: `{}` is replaced by it).
const NUMERIC: &[(&str, &str, &str)] = &[
    ("estimate", "--step", "{}"),
    ("estimate", "--noise-var", "{}"),
    ("estimate", "--seed", "{}"),
    ("paper", "--step", "{}"),
    ("paper", "--window", "{}"),
    ("tune", "--noise-var", "{}"),
    ("tune", "--schedule", "{}"),
    ("tune", "--schedule", "0.01,{}"),
    ("tune", "--seeds", "{}"),
    ("tune", "--window", "{}"),
    ("tune", "--train", "0-{}"),
    ("tune", "--train", "{}-1"),
    ("tune", "--test", "0-{}"),
    ("tune", "--exhaustive", "{}"),
    ("tune", "--step", "{}"),
    ("plot", "--step", "{}"),
    ("plot", "--noise-var", "{}"),
    ("plot", "--seed", "{}"),
    ("plot", "--from", "{}"),
    ("plot", "--to", "{}"),
    ("synth", "--rate", "{}"),
    ("synth", "--duration", "{}"),
    ("synth", "--seed", "{}"),
    ("synth", "--start-itow", "{}"),
    ("synth", "--bit", "{}"),
    ("synth", "--flip-bits", "{}"),
    ("synth", "--drop-bytes", "{}"),
    ("synth", "--drop-packets", "{}"),
    ("synth", "--garbage", "{}"),
    ("synth", "--garbage-max-len", "{}"),
    ("synth", "--corrupt-seed", "{}"),
    ("synth", "--yaw-noise", "{}"),
    ("synth", "--yaw-noise", "0.01@{}"),
    ("synth", "--noise-seed", "{}"),
    ("sim", "--baud", "{}"),
    ("sim", "--power-up-rate", "{}"),
    ("sim", "--reset-after", "{}"),
    ("sim", "--timeout", "{}"),
    ("sim", "--silence", "{}"),
    ("sim", "--inject", "freeze@{}"),
    ("config", "--baud", "{}"),
    ("config", "--rate", "{}"),
    ("config", "--unit-baud", "{}"),
    ("config", "--reply-timeout", "{}"),
    ("config", "--pings", "{}"),
    ("record", "--baud", "{}"),
    ("record", "--rate", "{}"),
    ("record", "--unit-baud", "{}"),
    ("record", "--reply-timeout", "{}"),
    ("record", "--pings", "{}"),
    ("record", "--duration", "{}"),
    ("live", "--baud", "{}"),
    ("live", "--rate", "{}"),
    ("live", "--unit-baud", "{}"),
    ("live", "--reply-timeout", "{}"),
    ("live", "--pings", "{}"),
    ("live", "--duration", "{}"),
    ("live", "--step", "{}"),
    ("live", "--noise-var", "{}"),
    ("live", "--seed", "{}"),
    ("info", "--unit-baud", "{}"),
    ("info", "--reply-timeout", "{}"),
    ("info", "--pings", "{}"),
    ("rows", "--baud", "{}"),
    ("rows", "--duration", "{}"),
];

/// Arguments that take a value that is not a number (paths, names, enums); positional ones by
/// their clap id.
const NOT_NUMERIC: &[(&str, &str)] = &[
    ("stats", "file"),
    ("decode", "file"),
    ("decode", "--type"),
    ("estimate", "file"),
    ("estimate", "--bank"),
    ("estimate", "--hold"),
    ("estimate", "--preset"),
    ("estimate", "--gains"),
    ("estimate", "--noise-at"),
    ("estimate", "--axis"),
    ("estimate", "--output"),
    ("paper", "file"),
    ("paper", "--hold"),
    ("paper", "--preset"),
    ("paper", "--gains"),
    ("paper", "--noise-at"),
    ("paper", "--axis"),
    ("tune", "files"),
    ("tune", "--hold"),
    ("tune", "--output"),
    ("tune", "--rust"),
    ("tune", "--axis"),
    ("tune", "--bank"),
    ("plot", "file"),
    ("plot", "--output"),
    ("plot", "--hold"),
    ("plot", "--preset"),
    ("plot", "--gains"),
    ("plot", "--noise-at"),
    ("plot", "--axis"),
    ("synth", "--profile"),
    ("synth", "--packet"),
    ("synth", "--output"),
    ("sim", "capture"),
    ("sim", "--listen"),
    ("sim", "--record"),
    ("sim", "--address-file"),
    ("sim", "--power-up-packet"),
    ("sim", "--fault"),
    ("sim", "--summary"),
    ("config", "--port"),
    ("config", "--packet"),
    ("record", "--port"),
    ("record", "--packet"),
    ("record", "--output"),
    ("live", "--port"),
    ("live", "--packet"),
    ("live", "--bank"),
    ("live", "--hold"),
    ("live", "--preset"),
    ("live", "--gains"),
    ("live", "--noise-at"),
    ("live", "--axis"),
    ("info", "--port"),
    ("rows", "input"),
    ("rows", "--port"),
    ("completions", "shell"),
];

/// The values a flag accepts among the walked ones, and why; every other walked value must
/// be refused.
const VALID: &[(&str, &str, &str, &str)] = &[
    ("estimate", "--noise-var", "0", "no added noise"),
    ("estimate", "--seed", "0", "any seed"),
    ("estimate", "--seed", "MAX", "any seed"),
    ("tune", "--noise-var", "0", "tuning without added noise"),
    ("tune", "--train", "0-1", "the first second"),
    ("plot", "--noise-var", "0", "no added noise"),
    ("plot", "--seed", "0", "any seed"),
    ("plot", "--seed", "MAX", "any seed"),
    ("plot", "--from", "0", "the start of the capture"),
    ("plot", "--to", "0", "the first instant"),
    ("synth", "--duration", "0", "one packet"),
    ("synth", "--seed", "0", "any seed"),
    ("synth", "--seed", "MAX", "any seed"),
    ("synth", "--start-itow", "0", "the start of the week"),
    ("synth", "--bit", "0", "any 16-bit BIT word"),
    ("synth", "--bit", "MAX", "any 16-bit BIT word"),
    ("synth", "--flip-bits", "0", "no corruption"),
    ("synth", "--drop-bytes", "0", "no corruption"),
    ("synth", "--drop-packets", "0", "no corruption"),
    ("synth", "--garbage", "0", "no corruption"),
    ("synth", "--corrupt-seed", "0", "any seed"),
    ("synth", "--corrupt-seed", "MAX", "any seed"),
    ("synth", "--yaw-noise", "0", "no noise"),
    ("synth", "--yaw-noise", "0.01@0", "noise from the start"),
    ("synth", "--noise-seed", "0", "any seed"),
    ("synth", "--noise-seed", "MAX", "any seed"),
    ("sim", "--power-up-rate", "0", "a quiet unit at power-up"),
    (
        "sim",
        "--reset-after",
        "0",
        "a reset before the first capture packet",
    ),
    (
        "sim",
        "--reset-after",
        "MAX",
        "a count of packets: never reached",
    ),
    (
        "sim",
        "--timeout",
        "0",
        "no time-out (the session waits for a host)",
    ),
    (
        "sim",
        "--silence",
        "0",
        "silent until the host leaves (with --fault silence only)",
    ),
    (
        "sim",
        "--inject",
        "freeze@0",
        "a freeze from the first capture packet",
    ),
    ("config", "--pings", "MAX", "u8: 255 pings per baud"),
    ("record", "--pings", "MAX", "u8: 255 pings per baud"),
    ("live", "--pings", "MAX", "u8: 255 pings per baud"),
    ("live", "--noise-var", "0", "no added noise"),
    ("live", "--seed", "0", "any seed"),
    ("live", "--seed", "MAX", "any seed"),
    ("info", "--pings", "MAX", "u8: 255 pings per baud"),
];

/// A valid value runs at most this long; one that starts long work (a session waiting for a
/// host, 255 pings per baud at 200 ms, a tuning run) is stopped then, having not panicked.
const VALID_LIMIT: Duration = Duration::from_secs(4);

fn numeric_type(vp: &clap::builder::ValueParser) -> Option<&'static str> {
    let t = vp.type_id();
    let types: [(TypeId, &str); 10] = [
        (TypeId::of::<u8>(), "255"),
        (TypeId::of::<u16>(), "65535"),
        (TypeId::of::<u32>(), "4294967295"),
        (TypeId::of::<u64>(), "18446744073709551615"),
        (TypeId::of::<usize>(), "18446744073709551615"),
        (TypeId::of::<i64>(), "9223372036854775807"),
        (TypeId::of::<i32>(), "2147483647"),
        (TypeId::of::<f32>(), "3.4028235e38"),
        (TypeId::of::<f64>(), "1.7976931348623157e308"),
        (TypeId::of::<(f64, f64)>(), "1.7976931348623157e308"),
    ];
    types.iter().find(|(id, _)| t == *id).map(|(_, m)| *m)
}

/// Every argument that takes a value: (command, `--long` or the positional id, the maximum of
/// its numeric type if it is one).
fn value_args() -> Vec<(String, String, Option<&'static str>)> {
    let mut cmd = Cli::command();
    cmd.build();
    let mut out = Vec::new();
    for sub in cmd.get_subcommands() {
        for a in sub.get_arguments() {
            if !a.get_action().takes_values() {
                continue;
            }
            let name = match a.get_long() {
                Some(l) => format!("--{l}"),
                None => a.get_id().to_string(),
            };
            out.push((
                sub.get_name().to_string(),
                name,
                numeric_type(a.get_value_parser()),
            ));
        }
    }
    out
}

#[test]
fn the_walk_covers_every_value_flag_of_clap() {
    let args = value_args();
    let mut unclassified = Vec::new();
    for (cmd, flag, numeric) in &args {
        let walked = NUMERIC.iter().any(|(c, f, _)| c == cmd && f == flag);
        let other = NOT_NUMERIC.iter().any(|(c, f)| c == cmd && f == flag);
        assert!(!(walked && other), "{cmd} {flag} is in both lists");
        if numeric.is_some() && !walked {
            unclassified.push(format!("{cmd} {flag} (numeric, not walked)"));
        } else if !walked && !other {
            unclassified.push(format!("{cmd} {flag} (in neither list)"));
        }
    }
    assert!(unclassified.is_empty(), "classify: {unclassified:?}");
    // And no stale entry.
    for (c, f, _) in NUMERIC {
        assert!(
            args.iter().any(|(cmd, flag, _)| cmd == c && flag == f),
            "{c} {f} is no flag of clap"
        );
    }
    for (c, f) in NOT_NUMERIC {
        assert!(
            args.iter().any(|(cmd, flag, _)| cmd == c && flag == f),
            "{c} {f} is no flag of clap"
        );
    }
    for (c, f, v, _) in VALID {
        assert!(
            NUMERIC.iter().any(|(cc, ff, t)| cc == c
                && ff == f
                && (VALUES.contains(v) || is_template_of(t, v))),
            "{c} {f} {v}: not a walked case"
        );
    }
}

fn is_template_of(template: &str, v: &str) -> bool {
    VALUES
        .iter()
        .any(|x| template.replace("{}", x) == v && template != "{}")
}

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-numeric-flags-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `args`; a run still going after `limit` is killed (`None` then, with what it wrote on
/// stderr so far).
fn run_limited(args: &[String], limit: Duration) -> (Option<Output>, String) {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            let out = child.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr).into_owned();
            return (Some(out), err);
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            let _ = child.wait();
            let mut err = String::new();
            let _ = child.stderr.take().unwrap().read_to_string(&mut err);
            return (None, err);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// The command line of the case: the command's base arguments, without the walked flag's
/// own entry in them (and without what conflicts with it), then `--flag=value`.
fn command_line(cmd: &str, flag: &str, value: &str, files: &Files) -> Vec<String> {
    let tiny = files.tiny.to_str().unwrap();
    let out = files.out.to_str().unwrap();
    let kept = files.kept.to_str().unwrap();
    let port = files.port.as_str();
    let base: Vec<&str> = match cmd {
        "estimate" => vec!["estimate", tiny, "-o", out],
        "paper" => vec!["paper", tiny],
        "tune" if flag == "--schedule" => {
            vec!["tune", tiny, "--seeds", "1", "-o", out, "--rust", kept]
        }
        "tune" => vec![
            "tune",
            tiny,
            "--noise-var",
            "0.01",
            "--seeds",
            "1",
            "--exhaustive",
            "2",
            "--window",
            "0.5",
            "-o",
            out,
            "--rust",
            kept,
        ],
        "plot" => vec!["plot", tiny, "-o", out],
        "synth" => vec!["synth", "--duration", "0.5", "-o", out],
        "sim" => vec![
            "sim",
            tiny,
            "--listen",
            "tcp:127.0.0.1:0",
            "--timeout",
            "0.5",
            "--record",
            out,
        ],
        "config" => vec!["config", "--port", port],
        "record" => vec!["record", "--port", port, "-o", out],
        "live" => vec!["live", "--port", port],
        "info" => vec!["info", "--port", port],
        "rows" => vec!["rows", "--port", port],
        other => panic!("no base command line for {other}"),
    };
    // `--train` conflicts with `--window`.
    let drop: &[&str] = match flag {
        "--train" => &["--window", "--train"],
        f => &[f][..],
    };
    let mut args = Vec::new();
    let mut i = 0;
    while i < base.len() {
        if drop.contains(&base[i]) {
            i += 2;
            continue;
        }
        args.push(base[i].to_string());
        i += 1;
    }
    args.push(format!("{flag}={value}"));
    args
}

/// Reads and drops what is waiting on the pty master; returns its length.
fn drain(master: &mut serialport::TTYPort) -> usize {
    let n = master.bytes_to_read().unwrap_or(0) as usize;
    if n > 0 {
        let mut junk = vec![0u8; n];
        let _ = master.read(&mut junk);
    }
    n
}

struct Files {
    tiny: PathBuf,
    out: PathBuf,
    /// An existing file given as an output (`tune --rust`): it keeps its contents.
    kept: PathBuf,
    port: String,
}

const KEPT: &str = "an existing file\n";

/// What a walk over some of [`NUMERIC`] found.
#[derive(Default)]
struct Walked {
    cases: usize,
    refused: usize,
    failures: Vec<String>,
}

/// The walk's threads: each case waits mostly on a child process (a valid serial command on
/// its time-out), so the threads share the machine's cores well.
const WALKERS: usize = 4;

#[test]
fn every_numeric_flag_refuses_bad_values_before_any_side_effect() {
    let d = scratch();
    let tiny = d.join("tiny.bin");
    let made = Command::new(BIN)
        .args(["synth", "--duration", "0.5", "-o", tiny.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(made.status.success());
    let args = value_args();
    // Each walker takes every WALKERS-th flag, with its own output files and its own
    // pseudo-terminal pair for the unit.
    let walked: Vec<Walked> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..WALKERS)
            .map(|w| {
                let (d, tiny, args) = (&d, &tiny, &args);
                scope.spawn(move || {
                    let flags = NUMERIC.iter().skip(w).step_by(WALKERS);
                    walk(flags, &d.join(format!("walker{w}")), tiny, args)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let _ = std::fs::remove_dir_all(&d);
    let failures: Vec<&str> = walked
        .iter()
        .flat_map(|w| &w.failures)
        .map(String::as_str)
        .collect();
    let cases: usize = walked.iter().map(|w| w.cases).sum();
    let refused: usize = walked.iter().map(|w| w.refused).sum();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(cases, NUMERIC.len() * VALUES.len());
    assert_eq!(
        refused,
        cases - VALID.len(),
        "every VALID entry is a walked case"
    );
}

/// Walks `flags` with every value of [`VALUES`], writing under `dir`.
fn walk<'a>(
    flags: impl Iterator<Item = &'a (&'static str, &'static str, &'static str)>,
    dir: &Path,
    tiny: &Path,
    args: &[(String, String, Option<&'static str>)],
) -> Walked {
    std::fs::create_dir_all(dir).unwrap();
    // A pseudo-terminal pair stands for the unit: the commands open the slave; a byte on the
    // master is a request that reached the "unit".
    let (mut master, slave) = serialport::TTYPort::pair().expect("pty pair");
    let files = Files {
        tiny: tiny.to_path_buf(),
        out: dir.join("out"),
        kept: dir.join("kept.rs"),
        port: slave.name().expect("pty name"),
    };
    let mut walked = Walked::default();
    for &(cmd, flag, template) in flags {
        let max = args
            .iter()
            .find(|(c, f, _)| c == cmd && f == flag)
            .and_then(|(_, _, m)| *m)
            .unwrap_or("1.7976931348623157e308");
        for raw in VALUES {
            let v = if raw == "MAX" { max } else { raw };
            let value = template.replace("{}", v);
            let key = if template == "{}" {
                raw.to_string()
            } else {
                value.clone()
            };
            let valid = VALID
                .iter()
                .any(|(c, f, vv, _)| *c == cmd && *f == flag && *vv == key);
            let _ = std::fs::remove_file(&files.out);
            std::fs::write(&files.kept, KEPT).unwrap();
            let line = command_line(cmd, flag, &value, &files);
            walked.cases += 1;
            let limit = if valid {
                VALID_LIMIT
            } else {
                Duration::from_secs(20)
            };
            let (out, err) = run_limited(&line, limit);
            let what = format!("nav440 {}", line.join(" "));
            let failures = &mut walked.failures;
            if err.contains("panicked") {
                failures.push(format!("{what}: panicked: {err}"));
                continue;
            }
            if let Some(o) = &out {
                if matches!(o.status.code(), Some(101) | Some(134) | None) {
                    failures.push(format!("{what}: exit {:?}: {err}", o.status.code()));
                    continue;
                }
            }
            if valid {
                // A valid serial command did talk to the "unit": drop what it sent.
                drain(&mut master);
                continue;
            }
            walked.refused += 1;
            let Some(o) = out else {
                failures.push(format!("{what}: still running after 20 s"));
                continue;
            };
            let stdout = String::from_utf8_lossy(&o.stdout);
            if o.status.code() != Some(2)
                || err.lines().count() != 1
                || !err.starts_with("nav440: ")
                || !err.contains(flag)
            {
                failures.push(format!(
                    "{what}: expected one line naming {flag}, exit 2; got exit {:?}: {err}",
                    o.status.code()
                ));
            }
            if !stdout.is_empty() {
                failures.push(format!("{what}: printed {stdout:?}"));
            }
            if files.out.exists() {
                failures.push(format!("{what}: wrote {}", files.out.display()));
            }
            if std::fs::read_to_string(&files.kept).unwrap() != KEPT {
                failures.push(format!("{what}: changed {}", files.kept.display()));
            }
            let sent = drain(&mut master);
            if sent > 0 {
                failures.push(format!("{what}: sent {sent} bytes to the port"));
            }
        }
    }
    drop(slave);
    walked
}

/// `tune -o` and `--rust`: a path that cannot be written is an output error before the input
/// is even read; an existing file keeps its contents when the tuning fails later.
#[test]
fn tune_checks_its_outputs_before_tuning_and_keeps_existing_files() {
    let d = scratch().join("tune-outputs");
    std::fs::create_dir_all(&d).unwrap();
    let missing_input = d.join("missing.bin");
    let m = missing_input.to_str().unwrap();
    for flag in ["-o", "--rust"] {
        let bad = d.join("no-such-dir").join("x");
        let (out, err) = run_limited(
            &[
                "tune".into(),
                m.into(),
                "--noise-var".into(),
                "0.01".into(),
                flag.into(),
                bad.to_str().unwrap().into(),
            ],
            Duration::from_secs(20),
        );
        let out = out.unwrap();
        assert_eq!(out.status.code(), Some(5), "{flag}: {err}");
        assert!(
            err.contains("cannot write") && err.contains("no-such-dir"),
            "{err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
        // A directory.
        let (out, err) = run_limited(
            &[
                "tune".into(),
                m.into(),
                "--noise-var".into(),
                "0.01".into(),
                flag.into(),
                d.to_str().unwrap().into(),
            ],
            Duration::from_secs(20),
        );
        assert_eq!(out.unwrap().status.code(), Some(5), "{flag}: {err}");
    }
    // Writable outputs: the run goes on to the input (missing: exit 3); neither the existing
    // file nor the missing one is changed or left behind.
    let existing = d.join("gains.toml");
    std::fs::write(&existing, KEPT).unwrap();
    let new = d.join("new.rs");
    let (out, err) = run_limited(
        &[
            "tune".into(),
            m.into(),
            "--noise-var".into(),
            "0.01".into(),
            "-o".into(),
            existing.to_str().unwrap().into(),
            "--rust".into(),
            new.to_str().unwrap().into(),
        ],
        Duration::from_secs(20),
    );
    assert_eq!(out.unwrap().status.code(), Some(3), "{err}");
    assert_eq!(std::fs::read_to_string(&existing).unwrap(), KEPT);
    assert!(!new.exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// A gains or schedule file with a number that is not finite (TOML allows `nan` and `inf`):
/// a one-line usage error naming the file, the table and the key.
#[test]
fn a_non_finite_gain_names_the_file_table_and_key() {
    let d = scratch().join("gains");
    std::fs::create_dir_all(&d).unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-tests/data");
    let cap = data.join("sin5_a1_50hz.bin");
    let fixed = d.join("fixed.toml");
    std::fs::write(&fixed, "[velocity.ilo1]\nk1 = 1.0\nl = nan\nk2 = 100.0\n").unwrap();
    let sched_text = std::fs::read_to_string(data.join("gains/schedule_fig5.toml")).unwrap();
    let sched = d.join("schedule.toml");
    let pos = sched_text.find("k2 = 168.8898").unwrap();
    let mut broken = sched_text.clone();
    broken.replace_range(pos..pos + "k2 = 168.8898".len(), "k2 = -inf");
    std::fs::write(&sched, broken).unwrap();
    for (file, table, key) in [
        (&fixed, "bad gains file: [velocity.ilo1]", "key l is NaN"),
        (
            &sched,
            "bad schedule file: [level.velocity.ilo1] of level 1",
            "key k2 is -inf",
        ),
    ] {
        for cmd in ["estimate", "plot"] {
            let out_svg = d.join("x.svg");
            let mut args: Vec<String> = vec![
                cmd.into(),
                cap.to_str().unwrap().into(),
                "--gains".into(),
                file.to_str().unwrap().into(),
            ];
            if cmd == "plot" {
                args.extend(["-o".into(), out_svg.to_str().unwrap().into()]);
            }
            let (out, err) = run_limited(&args, Duration::from_secs(60));
            let out = out.unwrap();
            assert_eq!(out.status.code(), Some(2), "{err}");
            assert_eq!(err.lines().count(), 1, "{err}");
            assert!(
                err.contains(file.to_str().unwrap()) && err.contains(table) && err.contains(key),
                "{err}"
            );
            assert!(!out_svg.exists());
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}
