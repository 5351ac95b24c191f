//! `nav440 tune --bank product` end to end, through the real binary: it tunes the product
//! bank's two rows alone (ILO1 velocity, Kalman acceleration), writes a gains file with those
//! two families only, and `nav440 estimate --bank product --gains` on that file reproduces the
//! MSE the report prints. The MSE is recomputed here from the estimate's CSV (its `ilo1_v` and
//! `yaw_rate` columns), independently of the tuner's own scoring.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

fn capture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-tests/data/fig5_a2_100hz.bin")
}

fn ok(args: &[&str]) -> String {
    let o = Command::new(BIN).args(args).output().expect("run nav440");
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

/// MSE of `ilo1_v` against `yaw_rate` over the rows with t <= `window_s`.
fn ilo1_mse(csv: &str, window_s: f64) -> f64 {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header, ["t", "yaw", "yaw_rate", "ilo1_v", "kf_a"]);
    let (mut sum, mut n) = (0.0, 0);
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        let t: f64 = f[0].parse().unwrap();
        if t <= window_s && !f[2].is_empty() {
            let d = f[3].parse::<f64>().unwrap() - f[2].parse::<f64>().unwrap();
            sum += d * d;
            n += 1;
        }
    }
    assert!(n > 0);
    sum / n as f64
}

/// The report's (before, after) of the family `name`.
fn before_after(report: &str, name: &str) -> (f64, f64) {
    let l = report
        .lines()
        .find(|l| l.split_whitespace().next() == Some(name))
        .unwrap_or_else(|| panic!("no {name} row in {report}"));
    let w: Vec<&str> = l.split_whitespace().collect();
    (w[1].parse().unwrap(), w[2].parse().unwrap())
}

#[test]
fn product_tuning_runs_in_estimate_with_the_reported_mse() {
    let d = std::env::temp_dir().join(format!("nav440-tune-product-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let (gains, rust) = (d.join("g.toml"), d.join("g.rs"));
    let cap = capture();
    let report = ok(&[
        "tune",
        p(&cap),
        "--bank",
        "product",
        "--noise-var",
        "0.5",
        "--window",
        "10",
        "--seeds",
        "1",
        "-o",
        p(&gains),
        "--rust",
        p(&rust),
    ]);
    // Two rows tuned, one per table; the hold's score is theirs alone.
    assert!(
        report.contains("geometric mean of the 2 tuned training MSEs"),
        "{report}"
    );
    let families: Vec<&str> = report
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|w| ["AVE", "ILO1", "ILO2", "ILO3", "AD", "ED", "KF"].contains(w))
        .collect();
    assert_eq!(families, ["ILO1", "KF"], "{report}");
    let kept = if report.contains("hold kept: zoh") {
        "zoh"
    } else {
        "linear"
    };
    let toml = std::fs::read_to_string(&gains).unwrap();
    let tables: Vec<&str> = toml.lines().filter(|l| l.starts_with('[')).collect();
    assert_eq!(tables, ["[velocity.ilo1]", "[acceleration.kf]"], "{toml}");
    assert!(toml.contains("--bank product"), "{toml}");
    let snippet = std::fs::read_to_string(&rust).unwrap();
    assert!(snippet.contains("pub const TUNED: BankConfig"), "{snippet}");
    // It names the bank it is for, and no other.
    assert!(snippet.contains("pass to `ProductBank::new`"), "{snippet}");
    assert!(!snippet.contains("PaperBank"), "{snippet}");

    // The report's MSEs, recomputed from the product bank's CSV with the same noise (seed 1).
    let (before, after) = before_after(&report, "ILO1");
    assert!(after < before, "{report}");
    let noise = ["--noise-var", "0.5", "--seed", "1"];
    let run = |extra: &[&str]| {
        let mut args = vec![
            "estimate",
            p(&cap),
            "--bank",
            "product",
            "--preset",
            "paper",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&noise);
        ilo1_mse(&ok(&args), 10.0)
    };
    let tuned = run(&["--gains", p(&gains), "--hold", kept]);
    let paper = run(&["--hold", "linear"]);
    for (ours, printed) in [(tuned, after), (paper, before)] {
        assert!(
            (ours - printed).abs() <= 1e-3 * printed + 1e-3,
            "CSV {ours} against report {printed}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}
