//! Every `nav440` command on the committed captures and on fresh `synth` captures, through the
//! real binary; error cases with their exit codes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");
/// The paper bank's yaw header (its columns are checked against a literal in
/// `estimators/tests/table.rs`).
const HEADER: &str = nav440_pipeline::csv::HEADER;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
}

/// A fresh scratch directory per test.
fn scratch(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nav440-cli-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run nav440")
}

fn ok(args: &[&str]) -> String {
    let o = run(args);
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

/// Runs a command expected to fail: returns (exit code, stderr); stderr must be one line.
fn fails(args: &[&str]) -> (i32, String) {
    let o = run(args);
    assert!(!o.status.success(), "{args:?} unexpectedly succeeded");
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "{args:?}: not one line: {err:?}"
    );
    assert!(o.stdout.is_empty(), "{args:?} printed to stdout on error");
    (o.status.code().unwrap(), err)
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn stats_on_committed_captures() {
    // (file, type, frames = duration * rate + 1, frame length)
    for (name, ty, n, flen) in [
        ("fig5_a2_100hz.bin", "A2", 3501u64, 37u64),
        ("sin5_a1_50hz.bin", "A1", 501, 39),
        ("spin_n1_20hz.bin", "N1", 401, 49),
        ("sin5_a2_25hz_weekwrap.bin", "A2", 251, 37),
    ] {
        let v = json(&ok(&["stats", p(&data(name))]));
        assert_eq!(
            v,
            serde_json::json!({"bytes": n * flen, "frames": {ty: n}, "crc_errors": 0, "skipped_bytes": 0, "pending_bytes": 0})
        );
    }
    // The documented key order (docs/CLI.md), `pending_bytes` last.
    assert_eq!(
        ok(&["stats", p(&data("fig5_a2_100hz.bin"))]),
        "{\"bytes\":129537,\"frames\":{\"A2\":3501},\"crc_errors\":0,\"skipped_bytes\":0,\"pending_bytes\":0}\n"
    );
    // Corrupted: 501 packets, 5 dropped, 14 damaged (the synth report; see data/README.md).
    let v = json(&ok(&["stats", p(&data("fig5_a2_100hz_corrupt.bin"))]));
    assert_eq!(v["frames"], serde_json::json!({"A2": 482}));
    assert_eq!(v["bytes"], 18470);
    assert!(v["crc_errors"].as_u64().unwrap() >= 1);
}

#[test]
fn synth_then_every_command_on_a_fresh_capture() {
    let d = scratch("fresh");
    let cap = d.join("spin.bin");
    let s = json(&ok(&[
        "synth",
        "--profile",
        "spin",
        "--packet",
        "N1",
        "--rate",
        "10",
        "--duration",
        "3",
        "--bit",
        "0x0002",
        "-o",
        p(&cap),
    ]));
    // 3 s at 10 Hz: 31 packets of 7 + 42 bytes.
    assert_eq!(s["packets"], 31);
    // spin: rate 200 + 100 sin(0.4 pi t): 3 s reach the peak 300 deg/s at t = 1.25 s.
    assert!((s["peak_rate_deg_s"].as_f64().unwrap() - 300.0).abs() < 1e-3);
    assert_eq!(s["bytes"], 31 * 49);
    assert_eq!(std::fs::metadata(&cap).unwrap().len(), 31 * 49);
    assert_eq!(
        json(&ok(&["stats", p(&cap)]))["frames"],
        serde_json::json!({"N1": 31})
    );

    // decode: one row per frame, SI units, values from the spin profile's formulas.
    let csv = ok(&["decode", p(&cap)]);
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 31);
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    };
    for (k, r) in rows.iter().enumerate() {
        let t = k as f64 * 0.1;
        assert_eq!(r[col("type")], "N1");
        assert_eq!(r[col("bit")], "0x0002");
        let w = 2.0 * std::f64::consts::PI * 0.2;
        let yaw = 200.0 * t + 100.0 / w * (1.0 - (w * t).cos());
        let rate = 200.0 + 100.0 * (w * t).sin();
        let yaw_wrapped = ((yaw + 180.0).rem_euclid(360.0) - 180.0).to_radians();
        let got: f64 = r[col("yaw_rad")].parse().unwrap();
        let mut dy = (got - yaw_wrapped).abs();
        dy = dy.min(2.0 * std::f64::consts::PI - dy);
        assert!(dy < 1e-4, "yaw {k}: {got} vs {yaw_wrapped}");
        let rz: f64 = r[col("rate_z_rad_s")].parse().unwrap();
        assert!((rz - rate.to_radians()).abs() < 2e-4, "rate {k}");
        let az: f64 = r[col("accel_z_m_s2")].parse().unwrap();
        assert!((az - 9.80665).abs() < 0.003, "1 g in m/s^2: {az}");
        let lat: f64 = r[col("latitude_rad")].parse().unwrap();
        assert!((lat - 35f64.to_radians()).abs() < 1e-8);
        let itow: f64 = r[col("time_itow_s")].parse().unwrap();
        assert!((itow - (208_800.0 + t)).abs() < 1e-6);
    }
    assert_eq!(
        ok(&["decode", p(&cap), "--type", "A2"]).lines().count(),
        1,
        "header only"
    );

    // estimate: header, one row per packet, t from timeITOW.
    let est = ok(&["estimate", p(&cap)]);
    let mut lines = est.lines();
    assert_eq!(lines.next(), Some(HEADER));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 31);
    for (k, r) in rows.iter().enumerate() {
        assert!(r.starts_with(&format!("{:.4},", k as f64 * 0.1)), "{r}");
    }

    // plot
    let svg = d.join("p.svg");
    ok(&["plot", p(&cap), "-o", p(&svg)]);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") || text.starts_with("<?xml"));
    assert!(text.contains("Velocity: AVE and ILO1-3 vs measured rate"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn synth_corruption_is_recovered_by_the_parser() {
    let d = scratch("corrupt");
    let cap = d.join("c.bin");
    let s = json(&ok(&[
        "synth",
        "--profile",
        "sin5",
        "--packet",
        "A1",
        "--rate",
        "50",
        "--duration",
        "4",
        "--flip-bits",
        "6",
        "--drop-bytes",
        "3",
        "--drop-packets",
        "4",
        "--garbage",
        "5",
        "--corrupt-seed",
        "11",
        "-o",
        p(&cap),
    ]));
    assert_eq!(s["packets"], 201);
    assert_eq!(s["dropped_packets"], 4);
    let intact = s["intact_packets"].as_u64().unwrap();
    assert_eq!(intact, 201 - 4 - s["damaged_packets"].as_u64().unwrap());
    assert!(intact < 197, "some packets damaged");
    let st = json(&ok(&["stats", p(&cap)]));
    assert_eq!(st["frames"]["A1"].as_u64(), Some(intact));
    // estimate still gives one row per surviving packet.
    assert_eq!(
        ok(&["estimate", p(&cap)]).lines().count() as u64,
        intact + 1
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn estimate_options() {
    let f = data("sin5_a1_50hz.bin");
    let f = p(&f);
    let base = ok(&["estimate", f]);
    assert_eq!(base.lines().count(), 502);
    // Noise: reproducible per seed, different across seeds, absent when the variance is 0.
    let n1 = ok(&["estimate", f, "--noise-var", "0.5", "--seed", "2"]);
    assert_eq!(
        n1,
        ok(&["estimate", f, "--noise-var", "0.5", "--seed", "2"])
    );
    assert_ne!(
        n1,
        ok(&["estimate", f, "--noise-var", "0.5", "--seed", "3"])
    );
    assert_ne!(n1, base);
    assert_eq!(ok(&["estimate", f, "--noise-var", "0"]), base);
    // Hold mode and step change the result; the yaw and rate columns do not depend on them.
    let zoh = ok(&["estimate", f, "--hold", "zoh"]);
    assert_ne!(zoh, base);
    let cols = |s: &str| {
        s.lines()
            .map(|l| l.split(',').take(3).collect::<Vec<_>>().join(","))
            .collect::<Vec<_>>()
    };
    assert_eq!(cols(&zoh), cols(&base));
    assert_ne!(ok(&["estimate", f, "--step", "0.0002"]), base);
    // Fixed point: same rows, velocities close to f32.
    let fx = ok(&["estimate", f, "--fixed"]);
    assert_eq!(fx.lines().count(), 502);
    // -o writes the same text to a file.
    let d = scratch("est");
    let out = d.join("e.csv");
    assert!(ok(&["estimate", f, "-o", p(&out)]).is_empty());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), base);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn paper_json_has_both_tables_next_to_the_paper_values() {
    let v = json(&ok(&[
        "paper",
        p(&data("sin5_a1_50hz.bin")),
        "--json",
        "--window",
        "8",
    ]));
    assert_eq!(v["settings"]["hold"], "linear");
    // Compared as f32 (the step's type): serde_json prints an f32 as its shortest f32 text
    // (0.0001) or, with features another workspace member turns on (`arbitrary_precision`
    // through defmt-decoder in xtask), may keep the f64 widening; both are the same f32.
    assert_eq!(v["settings"]["step_s"].as_f64().unwrap() as f32, 1e-4f32);
    assert_eq!(v["settings"]["seeds"], serde_json::json!([1, 2, 3]));
    // The paper's values (Tables 1 and 3 as restated in PAPER.md).
    assert_eq!(v["velocity_mse"]["0.01"]["paper"]["AVE"], 11.1);
    assert_eq!(v["velocity_mse"]["0.5"]["paper"]["AD"], 71.7);
    assert_eq!(v["acceleration_mse"]["0.01"]["paper"]["ILO2"], 212.4);
    assert_eq!(v["acceleration_mse"]["0.5"]["paper"]["ED"], 392.1);
    for table in ["velocity_mse", "acceleration_mse"] {
        for c in ["AVE", "ILO1", "ILO2", "ILO3", "AD", "KF"] {
            let lo = v[table]["0.01"]["ours"][c].as_f64().unwrap();
            let hi = v[table]["0.5"]["ours"][c].as_f64().unwrap();
            // Linear estimators: MSE = signal error + noise gain * variance, so 50x the noise
            // variance can only raise it.
            assert!(lo > 0.0 && hi > lo, "{table} {c}: {lo} {hi}");
        }
    }
    let text = ok(&["paper", p(&data("sin5_a1_50hz.bin")), "--window", "8"]);
    assert!(text.contains("Table 1") && text.contains("Table 3") && text.contains("0.5 paper"));
}

#[test]
fn tune_train_test_and_exhaustive_flags() {
    let d = scratch("tune_flags");
    let cap = d.join("short.bin");
    ok(&[
        "synth",
        "--profile",
        "fig5",
        "--rate",
        "50",
        "--duration",
        "2",
        "-o",
        p(&cap),
    ]);
    let text = ok(&[
        "tune",
        p(&cap),
        "--noise-var",
        "0.1",
        "--seeds",
        "1",
        "--train",
        "0-1",
        "--test",
        "1-2",
        "--exhaustive",
        "3",
    ]);
    assert!(text.contains("trained on 0-1 s, scored on 1-2 s"), "{text}");
    assert!(
        text.contains("exhaustive log grid, 3 points per gain"),
        "{text}"
    );
    // Both holds tuned; 3 points per gain: 9 (AVE) + 3 * 27 (ILO) + 3 + 9 + 3 per half.
    assert!(
        text.contains("hold linear") && text.contains("hold zoh"),
        "{text}"
    );
    assert!(
        text.contains(&format!("{} evaluations", 2 * 2 * (9 + 81 + 3 + 9 + 3))),
        "{text}"
    );
    for bad in [
        vec!["--train", "2-1"],
        vec!["--train", "x"],
        vec!["--test", "-1-2"],
        vec!["--exhaustive", "1"],
        vec!["--train", "0-1", "--window", "5"],
    ] {
        let mut args = vec!["tune", p(&cap), "--noise-var", "0.1"];
        args.extend(bad.iter().copied());
        let (code, _) = fails(&args);
        assert_eq!(code, 2, "{bad:?}");
    }
}

#[test]
fn tune_improves_and_writes_gains_that_estimate_accepts() {
    let d = scratch("tune");
    let cap = d.join("short.bin");
    let s = json(&ok(&[
        "synth",
        "--profile",
        "fig5",
        "--rate",
        "50",
        "--duration",
        "3",
        "-o",
        p(&cap),
    ]));
    // The paper's Fig. 5 bounds.
    assert!(s["peak_yaw_deg"].as_f64().unwrap() <= 100.0);
    assert!(s["peak_rate_deg_s"].as_f64().unwrap() <= 300.0);
    assert!(s["peak_acc_deg_s2"].as_f64().unwrap() <= 2000.0);
    let gains = d.join("g.toml");
    let rust = d.join("g.rs");
    let text = ok(&[
        "tune",
        p(&cap),
        "--noise-var",
        "0.1",
        "--seeds",
        "1",
        "--hold",
        "linear",
        "-o",
        p(&gains),
        "--rust",
        p(&rust),
    ]);
    // Each table line: NAME before after ...; with the hold fixed, the search evaluates the
    // paper gains and keeps the best point, so after <= before (up to the bank's closed-form
    // rounding). (Without `--hold` the kept hold is the better one over all 14 families, not
    // necessarily for each.)
    assert!(
        text.contains("hold kept: linear (before: linear)"),
        "{text}"
    );
    let mut seen = 0;
    for l in text.lines() {
        let w: Vec<&str> = l.split_whitespace().collect();
        if w.len() >= 3 && ["AVE", "ILO1", "ILO2", "ILO3", "AD", "ED", "KF"].contains(&w[0]) {
            let (b, a): (f64, f64) = (w[1].parse().unwrap(), w[2].parse().unwrap());
            assert!(a <= b * 1.01 + 1e-6, "{l}");
            seen += 1;
        }
    }
    assert_eq!(seen, 14);
    let toml = std::fs::read_to_string(&gains).unwrap();
    assert!(toml.contains("[velocity.ave]") && toml.contains("[acceleration.ilo3]"));
    assert!(std::fs::read_to_string(&rust)
        .unwrap()
        .contains("pub const TUNED: BankConfig"));
    let tuned = ok(&["estimate", p(&cap), "--gains", p(&gains)]);
    assert_ne!(tuned, ok(&["estimate", p(&cap)]));
    // A gains file restating the paper's presets over `--preset paper` reproduces that
    // preset's output exactly; the default (NAV440) differs from it.
    let paper = d.join("paper.toml");
    std::fs::write(
        &paper,
        "[velocity.ave]\nk = 500.0\ngamma1 = 20000.0\n[acceleration.ad]\nt = 0.1\n",
    )
    .unwrap();
    let paper_out = ok(&["estimate", p(&cap), "--preset", "paper"]);
    assert_eq!(
        ok(&[
            "estimate",
            p(&cap),
            "--preset",
            "paper",
            "--gains",
            p(&paper)
        ]),
        paper_out
    );
    assert_ne!(ok(&["estimate", p(&cap)]), paper_out);
    assert_eq!(
        ok(&["estimate", p(&cap), "--preset", "nav440"]),
        ok(&["estimate", p(&cap)])
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn errors_are_one_line_with_documented_exit_codes() {
    let d = scratch("errors");
    let missing = d.join("missing.bin");
    let empty = d.join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let text = d.join("text.bin");
    std::fs::write(
        &text,
        "this is not a NAV440 capture, just text\n".repeat(50),
    )
    .unwrap();
    for cmd in ["stats", "decode", "estimate", "paper", "plot"] {
        let mut extra: Vec<&str> = Vec::new();
        if cmd == "plot" {
            extra = vec!["-o", "/dev/null"];
        }
        let args = |f: &Path| {
            let mut a = vec![cmd, p(f)];
            a.extend(extra.iter().copied());
            a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
        };
        let run_args = |f: &Path| {
            let a = args(f);
            fails(&a.iter().map(String::as_str).collect::<Vec<_>>())
        };
        let (code, err) = run_args(&missing);
        assert_eq!(code, 3, "{cmd} missing: {err}");
        assert!(
            err.starts_with("nav440: cannot read") && err.contains("missing.bin"),
            "{err}"
        );
        let (code, err) = run_args(&empty);
        assert_eq!(code, 3, "{cmd} empty: {err}");
        assert!(err.contains("is empty"), "{err}");
        let (code, err) = run_args(&text);
        assert_eq!(code, 4, "{cmd} text: {err}");
        assert!(err.contains("no NAV440 frame"), "{err}");
    }
    let (code, _) = fails(&["tune", p(&missing), "--noise-var", "0.1"]);
    assert_eq!(code, 3);
    // Usage errors: exit 2.
    let f = data("sin5_a1_50hz.bin");
    assert_eq!(fails(&["estimate", p(&f), "--hold", "cubic"]).0, 2);
    assert_eq!(fails(&["estimate", p(&f), "--noise-var", "-1"]).0, 2);
    assert_eq!(
        fails(&["estimate", p(&f), "--step", "1.5e-7"]).0,
        2,
        "not whole microseconds"
    );
    assert_eq!(
        fails(&["synth", "--rate", "3", "-o", p(&d.join("x.bin"))]).0,
        2
    );
    assert_eq!(
        fails(&["synth", "--profile", "zigzag", "-o", p(&d.join("x.bin"))]).0,
        2
    );
    assert_eq!(fails(&["frobnicate"]).0, 2);
    let bad = d.join("bad.toml");
    std::fs::write(&bad, "[velocity.ave]\nk = \"fast\"\n").unwrap();
    let (code, err) = fails(&["estimate", p(&f), "--gains", p(&bad)]);
    assert_eq!(code, 2, "{err}");
    std::fs::write(&bad, "[velocity.ilo1]\nk1 = 2.0\nl = 1.0\nk2 = 1.0\n").unwrap();
    let (code, err) = fails(&["estimate", p(&f), "--gains", p(&bad)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("K1"), "{err}");
    // Output failure: exit 5.
    assert_eq!(
        fails(&[
            "synth",
            "--duration",
            "1",
            "-o",
            p(&d.join("no/such/dir/x.bin"))
        ])
        .0,
        5
    );
    // Help works and exits 0.
    let h = run(&["--help"]);
    assert!(h.status.success());
    assert!(String::from_utf8_lossy(&h.stdout).contains("Exit codes"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn stats_and_decode_name_nak_and_unknown_types() {
    let d = scratch("types");
    let f = d.join("mixed.bin");
    let mut bytes = Vec::new();
    let mut buf = [0u8; nav440_proto::MAX_FRAME];
    // A NAK for a failed GP request, an OpenIMU-style lower-case packet, a ping reply (len 0),
    // and the protocol document's real S1 frame.
    let n = nav440_proto::encode_frame(nav440_proto::PacketType::NAK, b"GP", &mut buf).unwrap();
    bytes.extend_from_slice(&buf[..n]);
    let n = nav440_proto::encode_frame(nav440_proto::PacketType(*b"z1"), &[1, 2, 3, 4], &mut buf)
        .unwrap();
    bytes.extend_from_slice(&buf[..n]);
    bytes.extend_from_slice(&[0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4]);
    let s1 = "55 55 53 31 18 ff e0 00 16 0c c0 ff fe ff f9 ff ff 27 eb 27 eb 27 eb 27 f7 28 f5 00 02 23 bc";
    bytes.extend(s1.split(' ').map(|h| u8::from_str_radix(h, 16).unwrap()));
    std::fs::write(&f, &bytes).unwrap();
    let v = json(&ok(&["stats", p(&f)]));
    assert_eq!(
        v["frames"],
        serde_json::json!({"NAK": 1, "z1": 1, "PK": 1, "S1": 1})
    );
    assert_eq!(v["bytes"], bytes.len());
    let csv = ok(&["decode", p(&f)]);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5);
    let header: Vec<&str> = lines[0].split(',').collect();
    let cell = |row: usize, name: &str| {
        let i = header.iter().position(|h| *h == name).unwrap();
        lines[row].split(',').nth(i).unwrap().to_string()
    };
    assert_eq!(cell(1, "type"), "NAK");
    assert_eq!(cell(1, "failed_type"), "GP");
    assert_eq!(cell(2, "payload_hex"), "01020304");
    assert_eq!(cell(3, "type"), "PK");
    // S1 from the protocol document: accel z 0.99609 g, counter 10485, BIT 0x0002.
    let az: f64 = cell(4, "accel_z_m_s2").parse().unwrap();
    assert!((az - 0.99609 * 9.80665).abs() < 1e-3);
    assert_eq!(cell(4, "counter"), "10485");
    assert_eq!(cell(4, "bit"), "0x0002");
    let t: f64 = cell(4, "board_temp_degc").parse().unwrap();
    assert!((t - 31.22).abs() < 0.01);
    // Only NAK frames.
    assert_eq!(ok(&["decode", p(&f), "--type", "nak"]).lines().count(), 2);
    // No yaw packet: estimate refuses with exit 4.
    let (code, err) = fails(&["estimate", p(&f)]);
    assert_eq!(code, 4);
    assert!(err.contains("none carries yaw"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// The CLI contract cases (docs/CLI.md, exit codes): each exits with the documented code and an
/// accurate one-line message.
#[test]
fn contract_cases_of_issue_8() {
    let d = scratch("contract");
    let out = d.join("x.bin");
    // A duration the in-memory generator cannot hold: usage error naming the limit (was an
    // allocation failure, exit 134, or a hang).
    let (code, err) = fails(&["synth", "--duration", "1e12", "-o", p(&out)]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--duration must be between 0 and 10000 s"),
        "{err}"
    );
    // timeITOW is a time of week: beyond it (or beyond u32) is a usage error (was wrapped).
    for itow in ["4294967296", "604800000"] {
        let (code, err) = fails(&["synth", "--start-itow", itow, "-o", p(&out)]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("--start-itow must be a time of week"), "{err}");
    }
    assert!(!out.exists());
    // `--window` is checked the same way by paper and tune.
    let f = data("sin5_a1_50hz.bin");
    for cmd in [
        vec!["paper", p(&f), "--window=-1"],
        vec!["tune", p(&f), "--noise-var", "0.01", "--window=-1"],
        vec!["tune", p(&f), "--noise-var", "0.01", "--window", "nan"],
    ] {
        let (code, err) = fails(&cmd);
        assert_eq!(code, 2, "{cmd:?}: {err}");
        assert!(
            err.contains("--window must be a number of seconds > 0"),
            "{err}"
        );
    }
    // A gains file that is not text is a bad gains file: exit 2 as the README says (was 3).
    let bad = d.join("bad.toml");
    std::fs::write(&bad, b"[velocity.ave]\nk = \xff\xfe\n").unwrap();
    let (code, err) = fails(&["estimate", p(&f), "--gains", p(&bad)]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad gains file: not UTF-8 text"), "{err}");
    // Noise so large that |yaw| passes 1e6 deg: the warning says so, not "time not
    // increasing".
    let o = run(&["estimate", p(&f), "--noise-var", "1e14"]);
    assert!(o.status.success());
    let err = String::from_utf8(o.stderr).unwrap();
    assert!(err.contains("with |yaw| above 1000000 deg"), "{err}");
    assert!(!err.contains("time not increasing"), "{err}");
    // A first period longer than 10^6 steps h: said as such (was "must be at least h").
    let mut slow = Vec::new();
    for k in 0..20u32 {
        slow.extend(
            nav440_cli::synth::encode_packet(
                nav440_cli::synth::PacketKind::A2,
                f64::from(k),
                0.0,
                k * 200_000,
                0,
            )
            .unwrap(),
        );
    }
    let slow_f = d.join("slow.bin");
    std::fs::write(&slow_f, &slow).unwrap();
    let (code, err) = fails(&["estimate", p(&slow_f)]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("sample period must be at most 1e6 steps h")
            && err.contains("nominal sample period 200 s"),
        "{err}"
    );
    // A truncated final frame: its bytes are reported as pending (frames + skipped + pending
    // = bytes).
    let full = std::fs::read(data("fig5_a2_100hz.bin")).unwrap();
    let mut cut = full.clone();
    cut.extend_from_slice(&full[..20]);
    let cut_f = d.join("cut.bin");
    std::fs::write(&cut_f, &cut).unwrap();
    let v = json(&ok(&["stats", p(&cut_f)]));
    assert_eq!(v["bytes"], 3501 * 37 + 20);
    assert_eq!(v["frames"]["A2"], 3501);
    assert_eq!(v["skipped_bytes"], 0);
    assert_eq!(v["pending_bytes"], 20);
    let _ = std::fs::remove_dir_all(&d);
}

/// `--noise-at step` re-initialises on the same gaps as the default sample mode instead of
/// interpolating across them: the first row after a 1 s hole (100 lost packets, beyond the
/// 25-period gap rule) reports all 14 estimates as 0 in both modes.
#[test]
fn step_noise_restarts_on_gaps_like_sample_mode() {
    let d = scratch("stepgap");
    let full = std::fs::read(data("fig5_a2_100hz.bin")).unwrap();
    let frame = 37;
    let mut holed = full[..1000 * frame].to_vec();
    holed.extend_from_slice(&full[1100 * frame..]);
    let f = d.join("holed.bin");
    std::fs::write(&f, &holed).unwrap();
    for mode in ["sample", "step"] {
        let csv = ok(&["estimate", p(&f), "--noise-at", mode]);
        let rows: Vec<&str> = csv.lines().skip(1).collect();
        assert_eq!(rows.len(), 3401, "{mode}");
        let after: Vec<f64> = rows[1000].split(',').map(|c| c.parse().unwrap()).collect();
        assert!((after[0] - 11.0).abs() < 1e-9, "{mode}: t {}", after[0]);
        assert!(
            after[3..].iter().all(|&v| v == 0.0),
            "{mode}: estimates after the gap {:?}",
            &after[3..]
        );
        // The row before the gap is a running estimate (not a restart).
        let before: Vec<f64> = rows[999].split(',').map(|c| c.parse().unwrap()).collect();
        assert!(before[3..10].iter().any(|&v| v != 0.0), "{mode}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `nav440 estimate FILE --gains schedule.toml` runs the noise-adaptive bank: same rows and
/// columns as the default, other values (its gains follow the estimated noise); a schedule
/// with one level equals the fixed gains of that level (nothing to interpolate).
#[test]
fn estimate_runs_a_schedule_file() {
    let cap = data("sin5_a1_50hz.bin");
    let sched = data("gains/schedule_fig5.toml");
    let default = ok(&["estimate", p(&cap), "--noise-var", "0.5"]);
    let adaptive = ok(&[
        "estimate",
        p(&cap),
        "--noise-var",
        "0.5",
        "--gains",
        p(&sched),
    ]);
    assert_eq!(default.lines().count(), adaptive.lines().count());
    assert_eq!(default.lines().next(), adaptive.lines().next());
    assert_ne!(default, adaptive);
    let d = scratch("schedule");
    let text = std::fs::read_to_string(&sched).unwrap();
    let first = text.split("[[level]]").nth(1).unwrap();
    let one = d.join("one.toml");
    std::fs::write(&one, format!("hold = \"linear\"\n[[level]]{first}")).unwrap();
    let fixed = d.join("fixed.toml");
    // The level's gains, without its recorded AVE switching gains (a schedule key).
    let gains = first.split("[level.ave_deltahat]").next().unwrap();
    assert_ne!(gains, first);
    let body: String = gains
        .lines()
        .filter(|l| !l.starts_with("noise_var"))
        .map(|l| format!("{}\n", l.replace("[level.", "[")))
        .collect();
    std::fs::write(&fixed, body).unwrap();
    assert_eq!(
        ok(&[
            "estimate",
            p(&cap),
            "--noise-var",
            "0.5",
            "--gains",
            p(&one)
        ]),
        ok(&[
            "estimate",
            p(&cap),
            "--noise-var",
            "0.5",
            "--gains",
            p(&fixed)
        ])
    );
    // The recorded switching gains are checked: a usage error (exit 2) naming them.
    let line = first
        .lines()
        .skip_while(|l| !l.starts_with("[level.ave_deltahat]"))
        .find(|l| l.starts_with("velocity = "))
        .unwrap();
    for (bad, why) in [
        ("velocity = -1.0", "parameter `ave_deltahat` must be >= 0"),
        (
            "velocity = nan",
            "[level.ave_deltahat] of level 1 key velocity is NaN",
        ),
        ("speed = 1.0", "unknown field `speed`"),
    ] {
        let f = d.join("bad.toml");
        std::fs::write(&f, text.replacen(line, bad, 1)).unwrap();
        let (code, err) = fails(&["estimate", p(&cap), "--gains", p(&f)]);
        assert_eq!(code, 2, "{bad}");
        assert!(
            err.contains("bad schedule file") && err.contains(why),
            "{bad}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// `nav440 tune --schedule` records the capture's nominal sample period in the schedule file
/// (`sample_period_s`) and the Rust snippet (`SCHEDULE_PERIOD_S`); `nav440 estimate --gains`
/// warns (stderr, one line; the CSV is unchanged) when a capture's period does not fit it
/// (more than 1.2x off, `estimators::GainSchedule::fits_period`), and only then: a 20 Hz
/// schedule on a 20 Hz capture and on a 100 Hz one, the bundled 100 Hz schedule on 100 Hz and
/// 50 Hz captures, and a file without the period (written before it was recorded).
#[test]
fn a_schedule_records_its_rate_and_estimate_warns_off_it() {
    let d = scratch("schedule_rate");
    let cap20 = d.join("fig5_20hz.bin");
    ok(&[
        "synth",
        "--profile",
        "fig5",
        "--rate",
        "20",
        "--duration",
        "3",
        "-o",
        p(&cap20),
    ]);
    let (toml, rs) = (d.join("s20.toml"), d.join("s20.rs"));
    ok(&[
        "tune",
        p(&cap20),
        "--schedule",
        "0.01,0.5",
        "--seeds",
        "1",
        "-o",
        p(&toml),
        "--rust",
        p(&rs),
    ]);
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(text.contains("\nsample_period_s = 0.05"), "{text}");
    let snippet = std::fs::read_to_string(&rs).unwrap();
    assert!(
        snippet.contains("pub const SCHEDULE_PERIOD_S: Option<f32> = Some(0.05);"),
        "{snippet}"
    );
    let estimate = |cap: &Path, sched: &Path| {
        let o = run(&["estimate", p(cap), "--gains", p(sched)]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            String::from_utf8(o.stdout).unwrap(),
            String::from_utf8(o.stderr).unwrap(),
        )
    };
    let warning = |tuned: &str, run: &str| {
        format!("nav440: warning: the gain schedule was tuned at a sample period of {tuned}, the bank runs at {run} on this capture: ")
    };
    let fig5 = data("fig5_a2_100hz.bin");
    let sin5 = data("sin5_a1_50hz.bin");
    let bundled = data("gains/schedule_fig5.toml");
    assert_eq!(estimate(&cap20, &toml).1, "");
    let (_, err) = estimate(&fig5, &toml);
    assert!(
        err.starts_with(&warning("0.05 s (20 Hz)", "0.01 s (100 Hz)")) && err.lines().count() == 1,
        "{err}"
    );
    assert_eq!(estimate(&fig5, &bundled).1, "");
    let (csv, err) = estimate(&sin5, &bundled);
    assert!(
        err.starts_with(&warning("0.01 s (100 Hz)", "0.02 s (50 Hz)")),
        "{err}"
    );
    // Without the period: the same rows, no warning.
    let old = d.join("old.toml");
    let bundled_text = std::fs::read_to_string(&bundled).unwrap();
    assert!(bundled_text.contains("sample_period_s = 0.01\n"));
    std::fs::write(&old, bundled_text.replace("sample_period_s = 0.01\n", "")).unwrap();
    assert_eq!(estimate(&sin5, &old), (csv, String::new()));
    // A bad period is a usage error (exit 2) naming it.
    for (bad, why) in [
        ("-1", "parameter `sample_period_s` must be > 0"),
        ("nan", "the top level key sample_period_s is NaN"),
        ("\"x\"", "invalid type: string"),
    ] {
        let f = d.join("bad.toml");
        let text = bundled_text.replace(
            "sample_period_s = 0.01\n",
            &format!("sample_period_s = {bad}\n"),
        );
        std::fs::write(&f, text).unwrap();
        let (code, err) = fails(&["estimate", p(&sin5), "--gains", p(&f)]);
        assert_eq!(code, 2, "{bad}");
        assert!(
            err.contains("bad schedule file") && err.contains(why),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The shipped preset follows the unit's packet rate (`BankConfig::NAV440_RATES`): on a 10 Hz
/// capture `nav440 estimate` runs the 10 Hz entry's gains - the same CSV as `--preset paper
/// --gains FILE` with those gains written out in full - and not the 100 Hz ones; a gains
/// file that names only the AVE changes only the AVE columns; `--preset paper` runs the
/// paper's gains at every rate.
#[test]
fn estimate_runs_the_preset_of_the_capture_rate() {
    use estimators::BankConfig;
    use nav440_cli::gains::GainsFile;
    let d = scratch("rate-preset");
    let cap = d.join("10hz.bin");
    ok(&[
        "synth",
        "--rate",
        "10",
        "--duration",
        "12",
        "--seed",
        "4",
        "-o",
        p(&cap),
    ]);
    let write = |name: &str, cfg: &BankConfig| {
        let path = d.join(name);
        std::fs::write(&path, GainsFile::from_bank(cfg).to_toml()).unwrap();
        path
    };
    let entry = BankConfig::nav440_rate_gains(0.1);
    assert_eq!(entry.tuned_period_s, [0.1, 0.1]);
    let at_10_hz = BankConfig {
        velocity: entry.velocity,
        acceleration: entry.acceleration,
        ..BankConfig::NAV440
    };
    let g10 = write("g10.toml", &at_10_hz);
    let g100 = write("g100.toml", &BankConfig::NAV440);
    let noisy = ["--noise-var", "0.1", "--seed", "5"];
    let est = |extra: &[&str]| {
        let mut a = vec!["estimate", p(&cap)];
        a.extend_from_slice(&noisy);
        a.extend_from_slice(extra);
        ok(&a)
    };
    let default = est(&[]);
    // 121 packets (0 to 12 s at 10 Hz) and the header.
    assert_eq!(default.lines().count(), 122);
    assert_eq!(default, est(&["--preset", "nav440"]));
    assert_eq!(default, est(&["--preset", "paper", "--gains", p(&g10)]));
    assert_ne!(default, est(&["--preset", "paper", "--gains", p(&g100)]));
    assert_ne!(default, est(&["--preset", "paper"]));
    // A gains file with the AVE alone: the other families keep the 10 Hz entry's gains.
    let ave_only = d.join("ave.toml");
    std::fs::write(
        &ave_only,
        "[velocity.ave]\nk = 100.0\ngamma1 = 5000.0\n\n[acceleration.ave]\nk = 100.0\ngamma1 = 5000.0\n",
    )
    .unwrap();
    let partial = est(&["--gains", p(&ave_only)]);
    let columns = |csv: &str, pick: &dyn Fn(&str) -> bool| -> Vec<String> {
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        csv.lines()
            .map(|l| {
                l.split(',')
                    .zip(&header)
                    .filter(|(_, h)| pick(h))
                    .map(|(v, _)| v)
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect()
    };
    let is_ave = |h: &str| h.starts_with("ave_");
    assert_eq!(
        columns(&partial, &|h| !is_ave(h)),
        columns(&default, &|h| !is_ave(h))
    );
    assert_ne!(columns(&partial, &is_ave), columns(&default, &is_ave));
    // `nav440 paper --preset nav440` scores the rate's entry too, and says so.
    let paper = |extra: &[&str]| {
        let mut a = vec!["paper", p(&cap), "--window", "12", "--json"];
        a.extend_from_slice(extra);
        json(&ok(&a))
    };
    let (by_paper, by_nav440) = (paper(&[]), paper(&["--preset", "nav440"]));
    assert_eq!(
        by_paper["settings"]["gains"],
        "paper presets (Tables 2 and 4)"
    );
    assert_eq!(
        by_nav440["settings"]["gains"],
        "NAV440 preset (its entry for the capture's packet rate)"
    );
    assert_eq!(
        paper(&["--preset", "paper", "--gains", p(&g10)])["velocity_mse"],
        by_nav440["velocity_mse"]
    );
    assert_ne!(by_paper["velocity_mse"], by_nav440["velocity_mse"]);
    let _ = std::fs::remove_dir_all(&d);
}

/// The columns named `names` of a CSV text (header included), each line's fields joined
/// with `,`: the text of those columns exactly as printed.
fn columns(csv: &str, names: &[String]) -> Vec<String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h == n)
                .unwrap_or_else(|| panic!("no column {n} in {header:?}"))
        })
        .collect();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), header.len(), "{l}");
            idx.iter().map(|&i| f[i]).collect::<Vec<_>>().join(",")
        })
        .collect()
}

/// `--bank product` prints the product firmware's CSV: `t`, then per axis the angle, its
/// rate, `ilo1_v` and `kf_a`, and those columns are, as text, the paper bank's columns of the
/// same name (the product bank is the paper bank's ILO1 velocity and Kalman acceleration
/// rows with the same gains): f32 and fixed point, one axis and all three, with noise and a
/// gains file. `--bank paper` is the default, byte for byte.
#[test]
fn estimate_product_bank_prints_the_paper_banks_ilo1_v_and_kf_a() {
    let cap = data("fig5_a2_100hz.bin");
    let gains = data("gains/fig5_var0.01.toml");
    let cap = p(&cap);
    let gains = p(&gains);
    // The product bank's columns (checked against a literal in estimators/tests/table.rs).
    let [v, a] = <estimators::ProductOutput>::NAMES;
    let yaw_header = format!("t,yaw,yaw_rate,{v},{a}");
    let all_header = format!("t,roll,roll_rate,roll_{v},roll_{a},pitch,pitch_rate,pitch_{v},pitch_{a},yaw,yaw_rate,yaw_{v},yaw_{a}");
    let cases: [&[&str]; 7] = [
        &[],
        &["--fixed"],
        &["--axis", "all"],
        &["--axis", "all", "--fixed"],
        &["--noise-var", "0.01", "--seed", "3", "--gains", gains],
        &["--axis", "pitch", "--noise-var", "0.5", "--hold", "zoh"],
        &[
            "--axis",
            "all",
            "--preset",
            "paper",
            "--noise-at",
            "step",
            "--noise-var",
            "0.01",
            "--fixed",
        ],
    ];
    for extra in cases {
        let args = |bank: Option<&'static str>| {
            let mut a = vec!["estimate", cap];
            if let Some(b) = bank {
                a.extend(["--bank", b]);
            }
            a.extend_from_slice(extra);
            a
        };
        let paper = ok(&args(None));
        assert_eq!(ok(&args(Some("paper"))), paper, "{extra:?}");
        // The shipped gains fixed: the paper bank's (the default `--bank product` follows
        // the motion, `follow.rs`).
        let mut fixed = args(Some("product"));
        fixed.push("--fixed-gains");
        let product = ok(&fixed);
        assert_eq!(product.lines().count(), paper.lines().count(), "{extra:?}");
        assert!(product.lines().count() > 3000, "{extra:?}");
        let header = product.lines().next().unwrap();
        let axes: Vec<&str> = if extra.contains(&"all") {
            assert_eq!(header, all_header);
            vec!["roll", "pitch", "yaw"]
        } else if extra.contains(&"pitch") {
            assert_eq!(header, yaw_header.replace("yaw", "pitch"));
            vec!["pitch"]
        } else {
            assert_eq!(header, yaw_header);
            vec!["yaw"]
        };
        let prefixed = axes.len() > 1;
        let mut names = vec!["t".to_string()];
        for a in &axes {
            names.push(a.to_string());
            names.push(format!("{a}_rate"));
            for c in ["ilo1_v", "kf_a"] {
                names.push(if prefixed {
                    format!("{a}_{c}")
                } else {
                    c.to_string()
                });
            }
        }
        assert_eq!(names.join(","), header);
        let want = columns(&paper, &names);
        // The product CSV is exactly those columns of the paper CSV.
        let got: Vec<&str> = product.lines().skip(1).collect();
        assert_eq!(got, want, "{extra:?}");
        // Not a comparison of zeros: a velocity moves (yaw's in the Fig. 5 capture; roll and
        // pitch are level there, and move with the added noise).
        let moving = want
            .iter()
            .filter(|l| {
                let f: Vec<&str> = l.split(',').collect();
                (0..axes.len()).any(|k| f[3 + 4 * k].parse::<f32>().unwrap().abs() > 1.0)
            })
            .count();
        assert!(moving > 1000, "{extra:?}: {moving}");
    }
}

/// `--bank product` runs no gain schedule: a gain schedule is a usage error, named; an unknown
/// bank is refused by the argument parser.
#[test]
fn estimate_product_bank_refuses_a_schedule() {
    let cap = data("sin5_a1_50hz.bin");
    let sched = data("gains/schedule_fig5.toml");
    let (code, err) = fails(&[
        "estimate",
        p(&cap),
        "--bank",
        "product",
        "--gains",
        p(&sched),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--bank product") && err.contains("schedule"),
        "{err}"
    );
    let o = run(&["estimate", p(&cap), "--bank", "tiny"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty());
}

#[test]
fn plot_to_stdout_writes_the_svg_the_file_would_hold() {
    let d = scratch("plot_stdout");
    let file = d.join("p.svg");
    let cap = data("fig5_a2_100hz.bin");
    let cap = cap.to_str().unwrap();
    ok(&["plot", cap, "-o", file.to_str().unwrap(), "--to", "5"]);
    let o = run(&["plot", cap, "-o", "-", "--to", "5"]);
    assert!(o.status.success());
    assert!(o.stdout.starts_with(b"<svg"), "not an SVG on stdout");
    assert_eq!(o.stdout, std::fs::read(&file).unwrap());
    assert!(
        !std::path::Path::new("-").exists(),
        "a file named - was written"
    );
}

/// Every duration and time-out is refused before any side effect when it is not a finite
/// number of seconds within 30 days (a one-line usage error, exit 2): `record` leaves its
/// output uncreated and touches no port (the port does not exist, and the error is not the
/// port's).
#[test]
fn durations_and_time_outs_are_checked_before_any_side_effect() {
    let d = scratch("durations");
    let out = d.join("rec.bin");
    let cap = data("fig5_a2_100hz.bin");
    for v in ["nan", "inf", "-1", "0", "1e20", "1.7976931348623157e308"] {
        for cmd in ["record", "live", "rows"] {
            let duration = format!("--duration={v}");
            let mut args = vec![cmd, "--port", "/dev/nav440-no-such-port", duration.as_str()];
            if cmd == "record" {
                args.extend(["-o", out.to_str().unwrap()]);
            }
            let o = run(&args);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains("--duration"), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
            assert!(!out.exists(), "{args:?} created its output");
        }
        if v == "0" {
            continue; // --timeout 0: no time-out
        }
        let o = run(&[
            "sim",
            cap.to_str().unwrap(),
            "--listen",
            "tcp:127.0.0.1:0",
            &format!("--timeout={v}"),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "sim --timeout {v}: {err}");
        assert!(err.contains("--timeout"), "sim --timeout {v}: {err}");
    }
    for (flag, v) in [
        ("--reply-timeout", "0"),
        ("--reply-timeout", "4294967295"),
        ("--pings", "0"),
    ] {
        let o = run(&["config", "--port", "/dev/nav440-no-such-port", flag, v]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {v}: {err}");
        assert!(err.contains(flag), "{flag} {v}: {err}");
    }
}

#[test]
fn sim_refuses_a_non_loopback_listen_address_unless_told() {
    let cap = data("fig5_a2_100hz.bin");
    let cap = cap.to_str().unwrap();
    for addr in ["tcp:0.0.0.0:0", "tcp:[::]:0"] {
        let o = run(&["sim", cap, "--listen", addr, "--timeout", "0.2"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{addr}: {err}");
        assert!(err.contains("not a loopback address"), "{addr}: {err}");
    }
    // With --listen-any it listens (and gives up at the time-out: nobody connects).
    let o = run(&[
        "sim",
        cap,
        "--listen",
        "tcp:0.0.0.0:0",
        "--listen-any",
        "--timeout",
        "0.2",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no host connected before --timeout"), "{err}");
}

/// The violent profile's packets carry its rate to 600 deg/s (within the protocol's +-630
/// deg/s, LSB 1260/2^16) and its strokes beyond 10,000 deg/s^2: the body-rate column of
/// `estimate --no-reference` is what the packets hold. An unknown profile names the known ones.
#[test]
fn synth_violent_reaches_600_deg_s_in_the_packets() {
    let d = scratch("violent");
    let cap = d.join("violent.bin");
    let s = json(&ok(&[
        "synth",
        "--profile",
        "violent",
        "--duration",
        "5",
        "-o",
        p(&cap),
    ]));
    assert!((s["peak_rate_deg_s"].as_f64().unwrap() - 600.0).abs() < 1.0);
    assert!(s["peak_acc_deg_s2"].as_f64().unwrap() > 10_000.0);
    let csv = ok(&["estimate", p(&cap), "--no-reference"]);
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|c| *c == "yaw_body_rate").unwrap();
    let peak = lines
        .map(|l| l.split(',').nth(col).unwrap().parse::<f64>().unwrap().abs())
        .fold(0.0, f64::max);
    // The first stroke, 600 deg/s over 0.15 s, sampled at 100 Hz: some packet lies within
    // 5 ms of its peak, 600 (1 + cos(2 pi 0.005 / 0.15)) / 2 = 593.4 deg/s (less half an LSB).
    assert!((593.3..=600.0 + 1260.0 / 65536.0).contains(&peak), "{peak}");
    let (code, err) = fails(&["synth", "--profile", "wobble", "-o", p(&cap)]);
    assert_eq!(code, 2);
    assert!(err.contains("hand, fast-sine or violent"), "{err}");
}
