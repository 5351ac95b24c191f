//! `cargo xtask demo`: the firmware against `nav440 sim` streaming a capture, then its
//! estimates and a summary.

use super::build::build;
use super::captures::bundled_capture;
use super::nav440_cli::{nav440_bin, Sim};
use super::qemu_run::{counter, counters, run_unit, unit_timeout};
use super::{read_file, work_dir, FW_BIN};
use crate::qemu::{self, Board};
use std::path::PathBuf;
use std::time::Duration;

/// `cargo xtask demo`: the firmware against `nav440 sim` streaming the bundled capture.
pub fn demo(board: Board, capture: Option<PathBuf>) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let elf = build(board.target, board.features, FW_BIN)?;
    let capture_path = match capture {
        Some(p) => p,
        None => bundled_capture()?,
    };
    let capture = read_file(&capture_path)?;
    let nav440 = nav440_bin()?;
    let record = work_dir()?.join(format!("demo-{}-streamed.bin", board.name));
    let sim = Sim::start(&nav440, &capture_path, Some(&record), &[])?;
    eprintln!(
        "xtask: `nav440 sim` plays a NAV440 at {} with the samples of {} ({} bytes); the firmware on QEMU {} ({}) configures it and estimates",
        sim.addr,
        capture_path.display(),
        capture.len(),
        board.machine,
        board.about
    );
    let r = run_unit(&board, &elf, &sim.addr, false, unit_timeout(capture.len()))?;
    let sim_status = sim.wait(Duration::from_secs(30));
    if r.code() != Some(0) {
        return Err(format!(
            "the firmware ended with status {:?}; its stderr:\n{}",
            r.code(),
            r.stderr
        ));
    }
    let csv_path = work_dir()?.join(format!("demo-{}.csv", board.name));
    std::fs::write(&csv_path, &r.stdout)
        .map_err(|e| format!("cannot write {}: {e}", csv_path.display()))?;
    println!("== boot: the firmware configures the unit ==");
    for l in r
        .stderr
        .lines()
        .filter(|l| l.starts_with("firmware: unit configured") || l.starts_with("firmware: boot"))
    {
        println!("{l}");
    }
    println!();
    print_estimates(&r.stdout)?;
    let c = counters(&r.stderr);
    println!();
    println!("== summary ==");
    println!(
        "board                                    QEMU {} ({}, target {})",
        board.machine, board.about, board.target
    );
    println!(
        "unit                                     nav440 sim, samples of {} ({})",
        capture_path.display(),
        match sim_status {
            Ok(s) if s.success() => "exited 0".to_owned(),
            Ok(s) => format!("exited with {s}"),
            Err(e) => e,
        }
    );
    for (k, label) in [
        ("unit_bytes", "bytes the unit sent (boot + stream)"),
        ("boot_frames", "frames while configuring (counted only)"),
        ("boot_ms", "boot time (SysTick, wall time under QEMU)"),
        ("bytes", "bytes estimated (after the read-back)"),
        ("frames", "frames (CRC ok)"),
        ("crc_errors", "CRC errors"),
        ("skipped", "skipped bytes"),
        ("decode_errors", "decode errors"),
        ("samples", "yaw samples"),
        ("rows", "estimate rows"),
        ("rejected", "rejected samples"),
        ("uart_overruns", "UART overruns"),
        ("uart_stalls", "UART RX stalls (back-pressure, no loss)"),
        ("stack_peak", "stack high-water mark, bytes"),
    ] {
        match counter(&c, k) {
            Some(v) => println!("{label:<40} {v}"),
            None => println!("{label:<40} ?"),
        }
    }
    let secs = r.elapsed.as_secs_f64();
    println!(
        "QEMU run                                 {secs:.1} s wall, {:.1} KB/s through the emulated UART",
        r.unit_bytes as f64 / secs.max(1e-9) / 1e3
    );
    println!(
        "full CSV                                 {}",
        csv_path.display()
    );
    println!(
        "bytes streamed after configuration       {} (`nav440 estimate` on it prints the same CSV)",
        record.display()
    );
    Ok(())
}

/// Prints the CSV one row per second of capture time, plus velocity RMS errors vs the gyro.
fn print_estimates(csv: &str) -> Result<(), String> {
    let mut lines = csv.lines();
    let header = lines.next().ok_or("the firmware printed no CSV header")?;
    let all_cols: Vec<&str> = header.split(',').collect();
    // The yaw block (`t,yaw,yaw_rate,...` or the `yaw,...` columns of a three-axis CSV).
    let base = all_cols.iter().position(|c| *c == "yaw").unwrap_or(1);
    let keep = |i: usize| i == 0 || (base..base + 16).contains(&i);
    // Shown as in a yaw-only CSV (`ave_v`, not `yaw_ave_v`).
    let cols: Vec<&str> = all_cols
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(_, c)| match c.strip_prefix("yaw_") {
            Some(rest) if base > 1 && rest != "rate" => rest,
            _ => *c,
        })
        .collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| keep(*i))
                .map(|(_, v)| v.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    println!("== estimates (one row per second of the capture; deg, deg/s, deg/s^2) ==");
    let line: Vec<String> = cols.iter().map(|c| format!("{c:>9}")).collect();
    println!("{}", line.join(""));
    let mut next_t = 0.0;
    for r in &rows {
        let t = r.first().copied().unwrap_or(f64::NAN);
        if t >= next_t {
            let line: Vec<String> = r.iter().map(|v| format!("{v:>9.2}")).collect();
            println!("{}", line.join(""));
            next_t = t.floor() + 1.0;
        }
    }
    // Velocity estimates against the reference rate (column yaw_rate: the Euler yaw rate).
    if rows.len() > 1 && cols.len() >= 10 {
        println!();
        println!(
            "velocity RMS difference to the reference yaw rate over {} rows (deg/s):",
            rows.len()
        );
        let mut parts = Vec::new();
        for (i, name) in cols.iter().enumerate().take(10).skip(3) {
            let (mut s, mut n) = (0.0, 0usize);
            for r in &rows {
                if let (Some(v), Some(g)) = (r.get(i), r.get(2)) {
                    if v.is_finite() && g.is_finite() {
                        s += (v - g) * (v - g);
                        n += 1;
                    }
                }
            }
            parts.push(format!("{name} {:.3}", (s / n.max(1) as f64).sqrt()));
        }
        println!("  {}", parts.join(", "));
    }
    Ok(())
}
