//! `nav440 estimate --no-reference`: the rate column of each axis is the unit's body rate
//! (`<axis>_body_rate`: roll p, pitch q, yaw r, deg/s as sent) instead of the Euler reference
//! rate; every other column is the default run's, byte for byte. Checked through the real
//! binary on a bundled capture (level, so the body rates are also the Euler rates there) and
//! on a tilted synthetic capture (where the two differ), the body rates against the packets'
//! rates as `nav440 decode` prints them (rad/s).

use std::path::PathBuf;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

fn ok(args: &[&str]) -> String {
    let o = Command::new(BIN).args(args).output().expect("run nav440");
    assert!(
        o.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

fn data(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../host-tests/data")
        .join(name)
        .display()
        .to_string()
}

/// The CSV's header and rows split into fields.
fn table(csv: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = csv.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect();
    (header, rows)
}

/// `nav440 decode`'s body rates of every attitude frame, deg/s (from its `rate_*_rad_s`
/// columns), in stream order.
fn decoded_rates(capture: &str) -> Vec<[f64; 3]> {
    let (header, rows) = table(&ok(&["decode", capture]));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let cols = [
        col("rate_x_rad_s"),
        col("rate_y_rad_s"),
        col("rate_z_rad_s"),
    ];
    rows.iter()
        .map(|r| cols.map(|c| r[c].parse::<f64>().unwrap().to_degrees()))
        .collect()
}

/// The product bank on every axis with the shipped gains fixed, in fixed point: the
/// estimates `--no-reference` must leave alone (gains that follow the motion follow the rate
/// column they are given).
const PRODUCT_FIXED: &[&str] = &[
    "--axis",
    "all",
    "--bank",
    "product",
    "--fixed-gains",
    "--fixed",
];

const ALL_BODY: &str = "t,roll,roll_body_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_body_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_body_rate,yaw_ilo1_v,yaw_kf_a";

/// Runs `estimate CAPTURE extra` with and without `--no-reference` and checks the contract:
/// the header renames each `<axis>_rate` to `<axis>_body_rate`, every other column is the
/// same text, and the body-rate columns are the decoded packet rates (within the f32 rounding
/// of the conversions). Returns (rows, rows whose rate columns differ).
fn check(capture: &str, extra: &[&str]) -> (usize, usize) {
    let mut args = vec!["estimate", capture];
    args.extend_from_slice(extra);
    let euler = ok(&args);
    args.push("--no-reference");
    let body = ok(&args);
    let (eh, er) = table(&euler);
    let (bh, br) = table(&body);
    let renamed: Vec<String> = eh
        .iter()
        .map(|h| match h.strip_suffix("_rate") {
            Some(axis) if ["roll", "pitch", "yaw"].contains(&axis) => format!("{axis}_body_rate"),
            _ => h.clone(),
        })
        .collect();
    assert_eq!(bh, renamed, "{extra:?}");
    assert_eq!(br.len(), er.len(), "{extra:?}");
    let rate_cols: Vec<(usize, usize)> = bh
        .iter()
        .enumerate()
        .filter_map(|(i, h)| {
            let axis = h.strip_suffix("_body_rate")?;
            Some((i, ["roll", "pitch", "yaw"].iter().position(|a| *a == axis)?))
        })
        .collect();
    assert!(!rate_cols.is_empty());
    let rates = decoded_rates(capture);
    assert_eq!(rates.len(), br.len(), "one row per frame on {capture}");
    let mut differ = 0;
    for (k, (b, e)) in br.iter().zip(&er).enumerate() {
        for (i, (bf, ef)) in b.iter().zip(e).enumerate() {
            if !rate_cols.iter().any(|(c, _)| *c == i) {
                assert_eq!(bf, ef, "row {k} column {} ({extra:?})", bh[i]);
            }
        }
        if rate_cols.iter().any(|(c, _)| b[*c] != e[*c]) {
            differ += 1;
        }
        for (c, axis) in &rate_cols {
            // An axis with no estimate (near gimbal lock) has empty fields in both runs.
            if b[*c].is_empty() {
                assert!(b[c - 1].is_empty(), "row {k}: a body rate is always sent");
                continue;
            }
            let got: f64 = b[*c].parse().unwrap();
            let want = rates[k][*axis];
            assert!(
                (got - want).abs() <= 1e-5 * want.abs().max(1.0),
                "row {k} {}: {got} against decoded {want}",
                bh[*c]
            );
        }
    }
    (br.len(), differ)
}

/// The bundled Fig. 5 capture (level: roll = pitch = 0, so the Euler rates are p, q, r): the
/// documented headers, and the same rows as the default run but for the header.
#[test]
fn a_bundled_capture_gives_the_same_estimates_and_the_body_rate_header() {
    let cap = data("fig5_a2_100hz.bin");
    let body = ok(&[
        "estimate",
        &cap,
        "--axis",
        "all",
        "--bank",
        "product",
        "--no-reference",
    ]);
    assert_eq!(body.lines().next(), Some(ALL_BODY));
    let yaw = ok(&["estimate", &cap, "--no-reference"]);
    assert_eq!(
        yaw.lines().next().unwrap(),
        nav440_pipeline::csv::HEADER.replace("yaw_rate", "yaw_body_rate")
    );
    for extra in [PRODUCT_FIXED, &[][..], &["--axis", "pitch"][..]] {
        let (rows, differ) = check(&cap, extra);
        assert!(rows > 3000, "{rows}");
        // Level: the Euler reference is exactly the body rates.
        assert_eq!(differ, 0, "{extra:?}");
    }
    // The yaw rate moves on this capture: not a comparison of zeros.
    let turning = yaw
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(2).unwrap().parse::<f32>().unwrap().abs() > 10.0)
        .count();
    assert!(turning > 500, "{turning}");
}

/// A tilted capture (the tumble: pitch through +-90 deg): the body rates are not the Euler
/// rates, the estimates are unchanged, and the pause near gimbal lock (empty roll and yaw
/// fields) is the same.
#[test]
fn a_tilted_capture_changes_only_the_rate_columns() {
    let dir = std::env::temp_dir().join(format!("nav440-noref-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cap = dir.join("tumble.bin").display().to_string();
    ok(&[
        "synth",
        "--profile",
        "tumble",
        "--duration",
        "8",
        "-o",
        &cap,
    ]);
    let (rows, differ) = check(&cap, PRODUCT_FIXED);
    assert!(differ > rows / 2, "{differ} of {rows} rows differ");
    let body = ok(&[
        "estimate",
        &cap,
        "--axis",
        "all",
        "--bank",
        "product",
        "--no-reference",
    ]);
    let paused = body.lines().filter(|l| l.contains(",,,,,")).count();
    assert!(paused > 0, "the tumble passes the gimbal lock");
    let _ = std::fs::remove_dir_all(&dir);
}
