//! Three axes, the Euler reference rate and BIT handling through `nav440 estimate`'s
//! pipeline (`replay::estimate_stream` = `nav440_pipeline::Pipeline`), on A2 captures
//! generated here.
//!
//! The motion is known in closed form (Euler angles and their derivatives); the packets carry
//! the angles and the body rates p, q, r from the inverse kinematics written as the rotation
//! of the Euler rates into the body frame (p = phi' - psi' sin theta, q = theta' cos phi +
//! psi' sin phi cos theta, r = -theta' sin phi + psi' cos phi cos theta), the independent side
//! of the check of the pipeline's forward kinematics (phi', theta', psi' from p, q, r).

use nav440_cli::replay::{self, Axes, Axis, EstimateOptions};
use nav440_proto::A2Fields;

const ANGLE_LSB: f64 = 360.0 / 65536.0; // deg
const RATE_LSB: f64 = 1260.0 / 65536.0; // deg/s

/// Angles (deg) and their derivatives (deg/s) at `t` s: roll turns at 30 deg/s (wrapping
/// every 12 s), pitch swings +-40 deg, yaw turns with a wobble.
fn motion(t: f64) -> ([f64; 3], [f64; 3]) {
    let a = [
        30.0 * t - 170.0,
        40.0 * (0.5 * t).sin(),
        20.0 * t + 30.0 * (0.3 * t).sin(),
    ];
    let d = [30.0, 20.0 * (0.5 * t).cos(), 20.0 + 9.0 * (0.3 * t).cos()];
    (a, d)
}

fn counts(deg: f64) -> i16 {
    ((deg / ANGLE_LSB).round() as i64).rem_euclid(65536) as u16 as i16
}

/// One A2 packet at sample `k` (100 Hz) with BIT word `bit`.
fn a2(k: u32, bit: u16) -> Vec<u8> {
    let t = f64::from(k) * 0.01;
    let (a, d) = motion(t);
    let (phi, theta) = (a[0].to_radians(), a[1].to_radians());
    let p = d[0] - d[2] * theta.sin();
    let q = d[1] * phi.cos() + d[2] * phi.sin() * theta.cos();
    let r = -d[1] * phi.sin() + d[2] * phi.cos() * theta.cos();
    let mut buf = [0u8; 64];
    let n = A2Fields {
        roll: counts(a[0]),
        pitch: counts(a[1]),
        yaw_true: counts(a[2]),
        rate_x: (p / RATE_LSB).round() as i16,
        rate_y: (q / RATE_LSB).round() as i16,
        rate_z: (r / RATE_LSB).round() as i16,
        time_itow: 5000 + 10 * k,
        bit,
        ..Default::default()
    }
    .encode(&mut buf)
    .unwrap();
    buf[..n].to_vec()
}

fn capture(n: u32, bit: impl Fn(u32) -> u16) -> Vec<u8> {
    (0..n).flat_map(|k| a2(k, bit(k))).collect()
}

fn csv(bytes: &[u8], axes: Axes) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let opts = EstimateOptions {
        axes,
        ..Default::default()
    };
    let (text, rejected) = replay::estimate_csv(bytes, &opts).unwrap();
    assert_eq!(rejected, 0);
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().ok()).collect())
        .collect();
    (header, rows)
}

#[test]
fn three_axes_reference_and_estimates_follow_the_known_motion() {
    let bytes = capture(2000, |_| 0x0002); // 20 s; BIT 0x0002: a healthy unit
    let (header, rows) = csv(&bytes, Axes::ALL);
    assert_eq!(header.len(), 49);
    assert_eq!(rows.len(), 2000);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let mut ave_err = [0.0f64; 3];
    let mut n_late = 0.0;
    for (k, row) in rows.iter().enumerate() {
        let t = k as f64 * 0.01;
        assert_eq!(row[0], Some((t * 1e4).round() / 1e4));
        let (a, d) = motion(t);
        for (i, axis) in Axis::ALL.into_iter().enumerate() {
            let name = axis.name();
            // Reference: the Euler rate, within the quantisation of the rates and angles
            // (|pitch| <= 40 deg: amplification 1 / cos 40 = 1.3).
            let reference =
                row[col(&format!("{name}_rate"))].expect("a reference below 80 deg pitch");
            assert!(
                (reference - d[i]).abs() < 4.0 * RATE_LSB + 0.01,
                "t={t} {name}_rate {reference} vs {}",
                d[i]
            );
            // The angle column: roll and yaw unwrapped (continuous, as the motion, which starts
            // at -170 deg and wraps every 12 s), pitch as sent; within one LSB of the motion.
            let angle = row[col(name)].unwrap();
            let want = a[i];
            assert!(
                (angle - want).abs() <= ANGLE_LSB,
                "t={t} {name} {angle} vs {want}"
            );
            if t > 3.0 {
                let v = row[col(&format!("{name}_ave_v"))].unwrap();
                ave_err[i] += (v - d[i]).abs();
            }
        }
        if t > 3.0 {
            n_late += 1.0;
        }
    }
    // The AVE velocity of every axis tracks the known rate (mean error, deg/s).
    for (i, e) in ave_err.iter().enumerate() {
        assert!(
            e / n_late < 1.0,
            "axis {i}: mean |ave_v - rate| = {}",
            e / n_late
        );
    }
}

#[test]
fn one_axis_csv_is_the_axis_block_of_all() {
    let bytes = capture(600, |_| 0);
    let (_, all) = csv(&bytes, Axes::ALL);
    for (i, axis) in Axis::ALL.into_iter().enumerate() {
        let (header, one) = csv(&bytes, Axes::only(axis));
        let name = axis.name();
        assert_eq!(header[1], name);
        assert_eq!(header[2], format!("{name}_rate"));
        assert_eq!(header[3], "ave_v");
        for (a, o) in all.iter().zip(&one) {
            assert_eq!(o[0], a[0]);
            assert_eq!(&o[1..], &a[1 + 16 * i..1 + 16 * (i + 1)]);
        }
    }
    let (header, _) = csv(&bytes, Axes::only(Axis::Yaw));
    assert_eq!(header.join(","), replay::CSV_HEADER);
}

#[test]
fn bit_failures_are_not_estimated_and_are_reported() {
    // Samples 300..=350 flag masterFail + softwareError (0x0009); the rest a healthy 0x0002.
    let bytes = capture(1000, |k| {
        if (300..=350).contains(&k) {
            0x0009
        } else {
            0x0002
        }
    });
    let mut out = Vec::new();
    let report =
        replay::estimate_stream(&bytes[..], &EstimateOptions::default(), &mut out).unwrap();
    assert_eq!(report.bit.failed, 51);
    assert_eq!(report.bit.software_error, 51);
    assert_eq!(report.bit.hardware_error, 0);
    assert_eq!(report.bit.last_word, 0x0009);
    let text = String::from_utf8(out).unwrap();
    assert_eq!(text.lines().count(), 1 + 1000 - 51);
    // No row in the failing stretch (2.99 s < t < 3.51 s).
    assert!(!text.lines().skip(1).any(|l| {
        let t: f64 = l.split(',').next().unwrap().parse().unwrap();
        (3.0..=3.5).contains(&t)
    }));
    let warnings: Vec<String> = report.warnings().collect();
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with("BIT failure: 51 samples not estimated (masterFail")),
        "{warnings:?}"
    );
    // The 0.51 s hole is a gap for the bank (re-initialised, counted).
    assert_eq!(report.summary.gaps, 1);
}

#[test]
fn a_capture_that_only_fails_bit_is_an_error_naming_the_flag() {
    let bytes = capture(50, |_| 0x0001);
    let err = replay::estimate_csv(&bytes, &EstimateOptions::default()).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("BIT failure") && msg.contains("masterFail"),
        "{msg}"
    );
}

#[test]
fn stats_json_names_bit_failures_only_when_present() {
    let bad = capture(100, |k| if k < 10 { 0x0001 } else { 0x0002 });
    let v = replay::stream_stats(&bad).to_json();
    assert_eq!(
        v["bit_failures"],
        serde_json::json!({"flag": "masterFail", "packets": 10, "hardware_error": 0, "com_error": 0, "software_error": 0, "last_word": "0x0001"})
    );
    let good = capture(100, |_| 0x0002);
    assert!(replay::stream_stats(&good)
        .to_json()
        .get("bit_failures")
        .is_none());
}

/// Runs the `nav440` binary; (exit code, stdout, stderr).
fn nav440(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nav440"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cli_axis_option_and_bit_warning() {
    let dir = std::env::temp_dir().join(format!("nav440-three-axes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bit.bin");
    std::fs::write(
        &file,
        capture(300, |k| {
            if (100..110).contains(&k) {
                0x0001
            } else {
                0x0002
            }
        }),
    )
    .unwrap();
    let f = file.to_str().unwrap();
    let (code, out, err) = nav440(&["estimate", f, "--axis", "pitch"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        out.lines().next().unwrap(),
        nav440_pipeline::csv::HEADER.replace("yaw", "pitch")
    );
    assert_eq!(out.lines().count(), 1 + 290);
    assert!(
        err.contains("nav440: warning: BIT failure: 10 samples not estimated (masterFail;"),
        "{err}"
    );
    let (code, out, _) = nav440(&["estimate", f, "--axis", "all"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("t,roll,roll_rate,roll_ave_v,"));
    for cmd in ["paper", "plot"] {
        let mut args = vec![cmd, f, "--axis", "all"];
        if cmd == "plot" {
            args.extend(["-o", "/dev/null"]);
        }
        let (code, _, err) = nav440(&args);
        assert_eq!(code, 2, "{cmd}: {err}");
        assert!(err.contains("one axis at a time"), "{err}");
    }
    let (code, out, err) = nav440(&["paper", f, "--axis", "roll", "--json", "--window", "2"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\"axis\":\"roll\""), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}
