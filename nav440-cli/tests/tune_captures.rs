//! `nav440 tune` on several captures (a family of motions), through the real binary: two fig5
//! hand motions of different shapes at 50 Hz. The report's MSEs are the means over the
//! captures, recomputed here from the CSV that `nav440 estimate` prints with the written
//! gains on each capture (independently of the tuner's scoring); captures at different packet
//! rates are refused; a schedule tunes on both.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

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

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// A scratch directory with fig5 captures of shapes 1 and 2 at 50 Hz and shape 2 at 25 Hz
/// (6 s each).
fn captures(test: &str) -> (PathBuf, [PathBuf; 3]) {
    let d = std::env::temp_dir().join(format!(
        "nav440-tune-captures-{}-{test}",
        std::process::id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    let files = [("a", "1", "50"), ("b", "2", "50"), ("c", "2", "25")].map(|(n, seed, rate)| {
        let f = d.join(format!("{n}.bin"));
        ok(&[
            "synth",
            "--profile",
            "fig5",
            "--seed",
            seed,
            "--rate",
            rate,
            "--duration",
            "6",
            "-o",
            p(&f),
        ]);
        f
    });
    (d, files)
}

/// MSE of `ilo1_v` against `yaw_rate` over the rows with t <= 6 s.
fn ilo1_mse(csv: &str) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for l in csv.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        if f[0].parse::<f64>().unwrap() <= 6.0 && !f[2].is_empty() {
            let d = f[3].parse::<f64>().unwrap() - f[2].parse::<f64>().unwrap();
            sum += d * d;
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn two_captures_tune_one_gain_set_scored_on_both() {
    let (d, [a, b, _]) = captures("product");
    let gains = d.join("g.toml");
    let report = ok(&[
        "tune",
        p(&a),
        p(&b),
        "--bank",
        "product",
        "--noise-var",
        "0.1",
        "--seeds",
        "1",
        "--window",
        "6",
        "--hold",
        "linear",
        "-o",
        p(&gains),
    ]);
    // 301 rows per capture in 0-6 s.
    assert!(report.contains("training rows scored: 602\n"), "{report}");
    let row = report
        .lines()
        .find(|l| l.starts_with("ILO1 "))
        .unwrap_or_else(|| panic!("{report}"));
    let w: Vec<f64> = row
        .split_whitespace()
        .skip(1)
        .take(2)
        .map(|x| x.parse().unwrap())
        .collect();
    let (before, after) = (w[0], w[1]);
    assert!(after < before, "{report}");
    // The report's MSEs are the means of the two captures' MSEs, with the same noise (seed 1).
    let mean = |extra: &[&str]| {
        let per: Vec<f64> = [&a, &b]
            .iter()
            .map(|f| {
                let mut args = vec!["estimate", p(f), "--bank", "product", "--preset", "paper"];
                args.extend_from_slice(extra);
                args.extend(["--hold", "linear", "--noise-var", "0.1", "--seed", "1"]);
                ilo1_mse(&ok(&args))
            })
            .collect();
        (per[0] + per[1]) / 2.0
    };
    for (ours, printed) in [(mean(&["--gains", p(&gains)]), after), (mean(&[]), before)] {
        assert!(
            (ours - printed).abs() <= 1e-3 * printed + 1e-3,
            "CSV {ours} against report {printed}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn captures_at_different_rates_are_refused() {
    let (d, [a, _, c]) = captures("rates");
    let o = run(&["tune", p(&a), p(&c), "--noise-var", "0.1"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        String::from_utf8(o.stderr).unwrap(),
        "nav440: the captures have different packet periods (0.02 s, 0.04 s): tune on captures at one packet rate\n"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_schedule_tunes_on_both_captures() {
    let (d, [a, b, _]) = captures("schedule");
    let file = d.join("s.toml");
    let report = ok(&[
        "tune",
        p(&a),
        p(&b),
        "--schedule",
        "0.01,0.5",
        "--seeds",
        "1",
        "--window",
        "6",
        "-o",
        p(&file),
    ]);
    assert_eq!(
        report.matches("training rows scored: 602\n").count(),
        2,
        "{report}"
    );
    let toml = std::fs::read_to_string(&file).unwrap();
    assert_eq!(toml.matches("[[level]]").count(), 2, "{toml}");
    assert!(toml.contains("sample_period_s = 0.02"), "{toml}");
    // The schedule runs on either capture.
    for f in [&a, &b] {
        assert_eq!(
            ok(&["estimate", p(f), "--gains", p(&file)]).lines().count(),
            302
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}
