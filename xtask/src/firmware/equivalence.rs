//! Equivalence of the firmware and the host: the CSV the firmware prints for a capture is
//! compared, as text, with what `nav440 estimate` prints for it.

use super::nav440_cli::host_estimate;
use super::qemu_run::{counter, counters, run_capture};
use super::read_file;
use crate::qemu::{Board, Output};
use std::path::Path;

/// Compares two CSV texts; Ok(number of lines) when identical, Err(first difference) otherwise.
pub(super) fn compare_csv(fw: &str, host: &str) -> Result<usize, String> {
    let (a, b): (Vec<&str>, Vec<&str>) = (fw.lines().collect(), host.lines().collect());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        if x != y {
            return Err(format!("line {}: firmware `{x}` != host `{y}`", i + 1));
        }
    }
    if a.len() != b.len() {
        return Err(format!(
            "firmware printed {} lines, host {}",
            a.len(),
            b.len()
        ));
    }
    Ok(a.len())
}

/// The largest |value| in the velocity columns (`PREFIX..._v`) of a `nav440 estimate` CSV,
/// deg/s (NaN counts as infinite).
pub(super) fn peak_velocity(csv: &str, prefix: &str) -> Result<f64, String> {
    peak_of(csv, prefix, "_v")
}

/// The largest |value| in the columns `PREFIX...SUFFIX` of a `nav440 estimate` CSV (NaN counts
/// as infinite).
pub(super) fn peak_of(csv: &str, prefix: &str, suffix: &str) -> Result<f64, String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().ok_or("empty CSV")?.split(',').collect();
    let cols: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with(prefix) && h.ends_with(suffix))
        .map(|(i, _)| i)
        .collect();
    if cols.is_empty() {
        return Err(format!("no {prefix}*{suffix} column in the CSV"));
    }
    let mut peak = 0.0f64;
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        for &i in &cols {
            let v: f64 = fields
                .get(i)
                .ok_or("short CSV line")?
                .parse()
                .map_err(|e| format!("CSV value: {e}"))?;
            peak = if v.is_nan() {
                f64::INFINITY
            } else {
                peak.max(v.abs())
            };
        }
    }
    Ok(peak)
}

/// Largest absolute difference per column between two CSVs of the same shape.
fn max_abs_diff(a: &str, b: &str) -> Result<Vec<(String, f64)>, String> {
    let mut la = a.lines();
    let mut lb = b.lines();
    let header: Vec<String> = la
        .next()
        .ok_or("empty CSV")?
        .split(',')
        .map(str::to_owned)
        .collect();
    lb.next();
    let mut max = vec![0.0f64; header.len()];
    let mut n = 0;
    for (x, y) in la.zip(lb) {
        n += 1;
        for (i, (u, v)) in x.split(',').zip(y.split(',')).enumerate() {
            let (u, v): (f64, f64) = (u.parse().unwrap_or(f64::NAN), v.parse().unwrap_or(f64::NAN));
            let d = (u - v).abs();
            if let Some(m) = max.get_mut(i) {
                if d.is_nan() || d > *m {
                    *m = d;
                }
            }
        }
    }
    if n == 0 {
        return Err("no rows to compare".into());
    }
    Ok(header.into_iter().zip(max).collect())
}

/// Equivalence of the firmware and `nav440 estimate` on one capture, for one board: the
/// firmware's counters.
pub(super) fn equivalence(
    board: &Board,
    elf: &Path,
    capture: &Path,
    host_extra: &[&str],
) -> Result<Vec<(String, u64)>, String> {
    equivalence_csv(board, elf, capture, host_extra).map(|(c, _)| c)
}

/// [`equivalence`], also returning the CSV both printed.
pub(super) fn equivalence_csv(
    board: &Board,
    elf: &Path,
    capture: &Path,
    host_extra: &[&str],
) -> Result<(Vec<(String, u64)>, String), String> {
    equivalence_full(board, elf, capture, host_extra).map(|(c, csv, _)| (c, csv))
}

/// What an equivalence run gives: the firmware's counters, the CSV both printed, the firmware's
/// stderr.
pub(super) type Equivalent = (Vec<(String, u64)>, String, String);

/// [`equivalence`], also returning the CSV both printed and the firmware's stderr.
pub(super) fn equivalence_full(
    board: &Board,
    elf: &Path,
    capture: &Path,
    host_extra: &[&str],
) -> Result<Equivalent, String> {
    let bytes = read_file(capture)?;
    let fw = run_capture(board, elf, &bytes, Output::Capture)?;
    let host = host_estimate(capture, host_extra)?;
    let c = counters(&fw.stderr);
    match compare_csv(&fw.stdout, &host) {
        Ok(lines) => {
            eprintln!(
                "xtask: EQUIVALENT: firmware on {} ({}) and `nav440 estimate{}` print identical CSV for {} ({lines} lines); {}",
                board.machine,
                board.target,
                host_extra.iter().map(|a| format!(" {a}")).collect::<String>(),
                capture.display(),
                fw.stderr.trim()
            );
            if counter(&c, "uart_overruns").unwrap_or(0) != 0 {
                return Err("UART overruns reported under QEMU".into());
            }
            Ok((c, host, fw.stderr))
        }
        Err(diff) => {
            let detail = max_abs_diff(&fw.stdout, &host)
                .map(|v| {
                    v.iter()
                        .map(|(k, d)| format!("{k}:{d:.3e}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_default();
            Err(format!(
                "firmware CSV differs from `nav440 estimate` for {} on {}: {diff}\nmax |diff| per column: {detail}",
                capture.display(),
                board.name
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_velocity_reads_the_velocity_columns_of_one_axis() {
        let csv = "t,yaw,yaw_rate,yaw_ave_v,yaw_ave_a,pitch_ave_v\n0,1,900,-12.5,5000,7000\n0.01,2,0,3,0,0\n";
        // Not the angle, the reference rate, an acceleration or another axis.
        assert_eq!(peak_velocity(csv, "yaw_").unwrap(), 12.5);
        assert_eq!(peak_velocity(csv, "pitch_").unwrap(), 7000.0);
        let nan = "t,yaw_ave_v\n0,NaN\n0.01,1\n";
        assert_eq!(peak_velocity(nan, "yaw_").unwrap(), f64::INFINITY);
        assert!(peak_velocity(csv, "roll_").is_err());
        assert!(peak_velocity("t,yaw_ave_v\n0,x\n", "yaw_").is_err());
    }

    #[test]
    fn csv_comparison_is_textual() {
        let a = "t,yaw\n0.0000,1.5\n0.0100,2\n";
        assert_eq!(compare_csv(a, a), Ok(3));
        // 2 and 2.0 are the same number but not the same text: a difference.
        let b = "t,yaw\n0.0000,1.5\n0.0100,2.0\n";
        assert!(compare_csv(a, b).is_err_and(|e| e.starts_with("line 3")));
        assert!(compare_csv(a, "t,yaw\n0.0000,1.5\n").is_err());
        let d = max_abs_diff(a, b).unwrap_or_default();
        assert_eq!(d, vec![("t".to_owned(), 0.0), ("yaw".to_owned(), 0.0)]);
    }
}
