//! `cargo xtask soak [--hours H]`: the product firmware of the real-board profile (STM32F405
//! image on QEMU `netduinoplus2`, which reconfigures a unit after a reset or a silence instead
//! of exiting) against `nav440 sim` streaming as fast as it is read, for H hours of stream
//! time at 100 Hz, with a silence (1 s), a reset, a frozen-stamp run (50 packets) and a burst
//! of garbage (256 bytes) injected at random packets in every fault window (an hour; `cargo
//! xtask ci` runs 10 minutes of stream with a window of 2.5 minutes, [`CI_SOAK`]). It checks
//! that
//! * the firmware's CSV equals `nav440 estimate` on the bytes the unit streamed while
//!   configured (the simulator's record: what the firmware's pipeline got);
//! * every injected fault is reported (`stream silent`, `unit reset mid-stream`, `time stamps
//!   frozen`, and the garbage in the `skipped` counter);
//! * the periodic counters come every 10 s of stream;
//! * the stack high-water mark is that of a short run of the same image with one fault of
//!   each kind, within [`STACK_JITTER`].

use super::build::build;
use super::equivalence::compare_csv;
use super::nav440_cli::{firmware_host_args, host_estimate, nav440_bin, nav440_synth, Sim};
use super::qemu_run::{counter, counters, run_unit};
use super::{work_dir, BankChoice, FW_BIN};
use crate::qemu;
use std::time::{Duration, Instant};

/// How far the stack high-water mark of the long run may lie above the short run's, B: where
/// an interrupt lands decides how deep its frame stacks on `main`'s (the same short run gave
/// 6,504 and 6,512 B; one exception frame with the FPU state is 104 B), and the long run's 16
/// faults land in orders the short run's 4 do not (measured: up to 160 B above it on a loaded
/// machine, where QEMU's timing moves). A stack that grows with stream time exceeds it within
/// the first hours.
const STACK_JITTER: u64 = 256;

/// Packets per minute of stream at 100 Hz.
const PACKETS_PER_MINUTE: u64 = 6_000;

/// The faults injected once per fault window, and the firmware's line that reports each.
const FAULTS: [(&str, &str); 3] = [
    ("silence", "firmware: stream silent: no complete frame for"),
    ("reset", "firmware: unit reset mid-stream"),
    ("freeze", "firmware: time stamps frozen"),
];

/// Minutes of stream of the soak `cargo xtask ci` runs, and its fault window: 16 faults in 10
/// minutes of stream, the same checks as an hour with 4 (docs/RELIABILITY-STREAM.md).
pub(super) const CI_SOAK: (f64, f64) = (10.0, 2.5);

/// A small deterministic generator (splitmix64) for the injection points.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The `--inject` arguments for `minutes` of stream: in every window of `window_min`
/// minutes, each fault once at a random packet, at least 2,000 packets (20 s) from any other,
/// so each is reported on its own.
fn injections(minutes: f64, window_min: f64, seed: u64) -> Vec<String> {
    let total = (minutes * PACKETS_PER_MINUTE as f64) as u64;
    let window = ((window_min * PACKETS_PER_MINUTE as f64) as u64).min(total);
    let mut state = seed;
    let mut points: Vec<u64> = Vec::new();
    let mut out = Vec::new();
    let mut start = 0;
    while start + 2_000 < total {
        let span = window.min(total - start);
        for kind in FAULTS.iter().map(|f| f.0).chain(["garbage"]) {
            let at = loop {
                let at = start + 1_000 + splitmix(&mut state) % span.saturating_sub(2_000).max(1);
                if points.iter().all(|p| p.abs_diff(at) >= 2_000) {
                    break at;
                }
            };
            points.push(at);
            out.push(format!("{kind}@{at}"));
        }
        start += window;
    }
    out
}

/// `cargo xtask soak --hours H --seed S`: H hours of stream, the four faults once an hour.
pub fn soak(hours: f64, seed: u64) -> Result<(), String> {
    if !(hours.is_finite() && hours > 0.0 && hours <= 48.0) {
        return Err(format!("--hours must be > 0 and <= 48, got {hours}"));
    }
    // Four faults an hour need room: at least 10 minutes of stream.
    if hours * 60.0 < 10.0 {
        return Err(format!(
            "--hours must be at least 0.17 (10 minutes), got {hours}"
        ));
    }
    qemu::ensure_qemu()?;
    prepare(hours * 60.0, 60.0, seed)?()
}

/// The soak of `minutes` of stream with the four faults once every `window_min` minutes: the
/// image built and the stream written here; the returned run (QEMU, then the checks) can go to
/// `cargo xtask ci`'s job pool.
pub(super) fn prepare(
    minutes: f64,
    window_min: f64,
    seed: u64,
) -> Result<impl FnOnce() -> Result<(), String> + Send + 'static, String> {
    let start = Instant::now();
    let board = qemu::STM32_BOARD;
    let mut features = board.features.to_vec();
    features.extend(BankChoice::FixedGains.features());
    let elf = build(board.target, &features, FW_BIN)?;
    let nav440 = nav440_bin()?;
    let dir = work_dir()?;
    // The stream: `nav440 synth` at 100 Hz (generated, not stored).
    let capture = dir.join("soak.bin");
    synth_stream(&capture, minutes * 60.0, seed)?;
    let inject = injections(minutes, window_min, seed);
    Ok(move || run(board, elf, nav440, capture, inject, minutes, start))
}

/// Runs a prepared soak and checks it (see the module doc).
fn run(
    board: qemu::Board,
    elf: std::path::PathBuf,
    nav440: std::path::PathBuf,
    capture: std::path::PathBuf,
    inject: Vec<String>,
    minutes: f64,
    start: Instant,
) -> Result<(), String> {
    let dir = work_dir()?;
    let host_extra = firmware_host_args(board.target, BankChoice::FixedGains);
    // The stack baseline: a short run of the same image with one fault of each kind.
    let short = super::root().join("host-tests/data/fig5_a2_100hz.bin");
    let base = {
        let sim = Sim::start(
            &nav440,
            &short,
            None,
            &[
                "--fast",
                "--silence",
                "1",
                "--timeout",
                "300",
                "--inject",
                "silence@500",
                "--inject",
                "reset@1200",
                "--inject",
                "freeze@2000",
                "--inject",
                "garbage@2800",
            ],
        )?;
        let r = run_unit(&board, &elf, &sim.addr, false, Duration::from_secs(300))?;
        let _ = sim.wait(Duration::from_secs(30));
        write_log(&dir.join("soak-baseline.log"), &r.stderr)?;
        counter(&counters(&r.stderr), "stack_peak")
            .ok_or_else(|| format!("no stack_peak in the baseline run:\n{}", r.stderr))?
    };
    let record = dir.join("soak-record.bin");
    let mut args: Vec<&str> = vec!["--fast", "--silence", "1", "--timeout", "0"];
    for i in &inject {
        args.extend(["--inject", i]);
    }
    let sim = Sim::start(&nav440, &capture, Some(&record), &args)?;
    // A last resort against a hung firmware: stream time itself (QEMU runs faster than that).
    let limit = Duration::from_secs_f64((minutes * 60.0).max(600.0));
    let run_start = Instant::now();
    let r = run_unit(&board, &elf, &sim.addr, false, limit)?;
    let run_s = run_start.elapsed().as_secs_f64();
    let _ = sim.wait(Duration::from_secs(60));
    let log = dir.join("soak-firmware.log");
    write_log(&log, &r.stderr)?;
    let c = counters(&r.stderr);
    let mut problems = Vec::new();
    if r.code() != Some(0) {
        problems.push(format!("firmware exit status {:?}", r.code()));
    }
    // Every fault reported, once per injection.
    for (kind, line) in FAULTS {
        let want = inject.iter().filter(|i| i.starts_with(kind)).count();
        let got = r.stderr.matches(line).count();
        if got < want {
            problems.push(format!("{want} {kind} injected, {got} `{line}` reported"));
        }
    }
    let garbage = inject.iter().filter(|i| i.starts_with("garbage")).count() as u64;
    let skipped = counter(&c, "skipped").unwrap_or(0);
    if skipped < garbage * 256 {
        problems.push(format!(
            "{garbage} garbage bursts of 256 bytes injected, skipped={skipped}"
        ));
    }
    // One periodic report per 10 s of stream.
    let periodic = r.stderr.matches("firmware: counters after").count() as u64;
    let expected = (minutes * 6.0) as u64;
    if periodic < expected * 9 / 10 {
        problems.push(format!(
            "{periodic} periodic counter reports, expected about {expected}"
        ));
    }
    let peak = counter(&c, "stack_peak");
    if peak.is_none_or(|p| p > base + STACK_JITTER) {
        problems.push(format!(
            "stack high-water mark {peak:?} B, {base} B on the short run with the same faults (+{STACK_JITTER} B allowed)"
        ));
    }
    let host = host_estimate(&record, &host_extra)?;
    let lines = match compare_csv(&r.stdout, &host) {
        Ok(n) => n,
        Err(d) => {
            problems.push(format!(
                "firmware CSV differs from `nav440 estimate` on the record: {d}"
            ));
            0
        }
    };
    if !problems.is_empty() {
        return Err(format!(
            "soak of {minutes} min failed:\n  {}\n(the firmware's stderr: {})",
            problems.join("\n  "),
            log.display()
        ));
    }
    let bytes = std::fs::metadata(&record).map_or(0, |m| m.len());
    eprintln!(
        "xtask: SOAK OK: {minutes} min of stream ({} faults injected: silence, reset, freeze, garbage, each once per fault window) through the product firmware on {} in {run_s:.0} s ({:.0} s in all): CSV identical to `nav440 estimate` on the {bytes} bytes streamed while configured ({lines} lines), every fault reported, {periodic} periodic counter reports, stack high-water {} B ({base} B on a short run with the same faults)",
        inject.len(),
        board.machine,
        start.elapsed().as_secs_f64(),
        peak.unwrap_or(0)
    );
    Ok(())
}

/// `nav440 synth`'s longest capture, s (`synth::MAX_DURATION_S`).
const SEGMENT_S: f64 = 10_000.0;

/// `synth`'s first time stamp, ms (its default `--start-itow`: day 2, 10:00).
const START_ITOW_MS: u64 = 2 * 86_400_000 + 10 * 3_600_000;

/// Writes `duration_s` of 100 Hz stream to `out`: one `nav440 synth` capture, or several of at
/// most [`SEGMENT_S`] back to back (seeds `seed`, `seed + 1`, ...; each starts one period after
/// the last packet of the one before, so the time stamps go on; the motion restarts).
fn synth_stream(out: &std::path::Path, duration_s: f64, seed: u64) -> Result<(), String> {
    use std::io::Write as _;
    let mut file =
        std::fs::File::create(out).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    let mut done_s = 0.0;
    let mut k = 0u64;
    while done_s < duration_s {
        let d = (duration_s - done_s).min(SEGMENT_S);
        let part = out.with_extension(format!("part{k}.bin"));
        let itow = START_ITOW_MS + (done_s * 1000.0) as u64 + 10 * k;
        let (secs, seed_s, itow_s) = (format!("{d}"), (seed + k).to_string(), itow.to_string());
        nav440_synth(
            &part,
            &[
                "--duration",
                &secs,
                "--seed",
                &seed_s,
                "--profile",
                "sin5",
                "--start-itow",
                &itow_s,
            ],
        )?;
        let bytes =
            std::fs::read(&part).map_err(|e| format!("cannot read {}: {e}", part.display()))?;
        file.write_all(&bytes)
            .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
        let _ = std::fs::remove_file(&part);
        done_s += d;
        k += 1;
    }
    Ok(())
}

/// Writes a run's stderr to `path`.
fn write_log(path: &std::path::Path, text: &str) -> Result<(), String> {
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The injection points, sorted, each at least 2,000 packets from the next and all before
    /// `minutes` of stream.
    fn assert_spread(injections: &[String], minutes: u64) {
        let mut at: Vec<u64> = injections
            .iter()
            .map(|s| s.split_once('@').unwrap().1.parse().unwrap())
            .collect();
        at.sort();
        assert!(at.windows(2).all(|w| w[1] - w[0] >= 2_000));
        assert!(*at.last().unwrap() < minutes * PACKETS_PER_MINUTE);
    }

    #[test]
    fn injections_are_spread_and_apart() {
        let i = injections(120.0, 60.0, 1);
        assert_eq!(i.len(), 8);
        assert_spread(&i, 120);
        // CI's soak: four faults in each of its four windows.
        let (minutes, window) = CI_SOAK;
        let ci = injections(minutes, window, 1);
        assert_eq!(ci.len(), 16);
        assert_spread(&ci, 10);
    }
}
