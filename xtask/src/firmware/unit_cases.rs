//! The firmware against `nav440 sim`, each run with the outcome it must end with: every
//! bundled capture and the unit's faults on every board (`cargo xtask ci-unit`), and the
//! embassy example (`cargo xtask embassy`).

use super::build::build;
use super::captures::{data_captures, rate_drop_capture, PERIOD_CHANGE};
use super::equivalence::compare_csv;
use super::nav440_cli::{firmware_host_args, host_estimate, nav440_bin, Sim, FIRMWARE_AXIS};
use super::qemu_run::{counter, counters, run_unit, run_unit_rows, stack_within, unit_timeout};
use super::{root, unique_path, BankChoice, FW, FW_BIN, STM32_FEATURE, UART_ROWS};
use crate::cargo;
use crate::pool::Pool;
use crate::qemu::{self, Board};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// What a unit run in CI must end with.
enum Expect {
    /// Exit 0, and the CSV equals `nav440 estimate` on the simulator's record; `stderr_has`
    /// must appear in the firmware's stderr.
    Csv { stderr_has: &'static str },
    /// This exit status and diagnostic (emulated mps2 boards: a failure ends the run).
    Fails {
        status: i32,
        diagnostic: &'static str,
    },
    /// The real-board profile retries forever: within the time limit at least two attempts,
    /// each with `diagnostic` (the run is then stopped).
    Retries { diagnostic: &'static str },
    /// The firmware reports `report` once, configures the unit again and finishes with
    /// exit 0 (a unit that reset, on the real-board profile; a unit silent for a while).
    Reconfigures { report: &'static str },
    /// As [`Expect::Csv`], and the stack's high-water mark (`stack_peak`) at most
    /// `stack_limit` bytes.
    CsvStack {
        stderr_has: &'static str,
        stack_limit: u64,
    },
}

/// One firmware run against `nav440 sim` (CI).
struct UnitCase {
    name: &'static str,
    capture: PathBuf,
    sim_args: &'static [&'static str],
    expect: Expect,
}

/// The simulator's session limit in CI (it exits 1 if a session lasts longer).
const SIM_TIMEOUT: &str = "120";

/// The unit silent for ever with the link open after 20 packets: reported within 0.5 s, then
/// the boot finds no unit (the run ends by itself with status 2, not by the harness's time
/// limit): the simulator's arguments and the firmware's diagnostic.
const SILENCE: (&[&str], &str) = (
    &["--fast", "--fault", "silence", "--reset-after", "20"],
    "stream silent: no complete frame for",
);

/// Silent for 1 s after 20 packets, at the commanded rate in wall time (with --fast the unit
/// would stream the rest of the capture and close while the firmware still pings it):
/// reported at 0.5 s; the boot's first ping baud (3 x 500 ms) then finds the unit again.
const SILENCE_1S: (&[&str], &str) = (
    &[
        "--fault",
        "silence",
        "--reset-after",
        "20",
        "--silence",
        "1",
    ],
    "firmware: stream silent: no complete frame for",
);

/// Time stamps frozen for 50 packets after 20: reported, and the CSV identical to `nav440
/// estimate` on the record.
const FREEZE: (&[&str], &str) = (
    &["--fast", "--fault", "freeze", "--reset-after", "20"],
    "firmware: time stamps frozen: 25 frames in a row",
);

/// A reset after 20 packets (frames of another type follow): status 5 on the emulated boards.
const RESET: (&[&str], &str) = (
    &["--fast", "--fault", "reset", "--reset-after", "20"],
    "unit reset mid-stream",
);

/// Runs one case on `board`; Ok(description) or Err(what went wrong).
fn unit_case(
    board: &Board,
    elf: &Path,
    nav440: &Path,
    case: &UnitCase,
    host_extra: &[&str],
) -> Result<String, String> {
    let record = unique_path(&format!("ci-unit-{}-{}", board.name, case.name), "bin")?;
    let mut sim_args = case.sim_args.to_vec();
    sim_args.extend(["--timeout", SIM_TIMEOUT]);
    let sim = Sim::start(nav440, &case.capture, Some(&record), &sim_args)?;
    let bytes = std::fs::metadata(&case.capture).map_or(0, |m| m.len() as usize);
    let limit = match case.expect {
        // About 10 attempts (12 pings x 1000 ms nominal = 1.1 s of wall time each) on an idle
        // machine; 2 are required, so the limit leaves room for a 5x slowdown (QEMU starved by
        // parallel builds on a loaded 2-core machine). The silence case first streams, then
        // waits out the silence limit before its first attempt: it gets 8 s more (a CI run
        // saw one attempt in 12 s there).
        Expect::Retries { .. } if case.name == "silence" => Duration::from_secs(20),
        Expect::Retries { .. } => Duration::from_secs(12),
        _ => unit_timeout(bytes),
    };
    let run = run_unit(board, elf, &sim.addr, false, limit);
    let sim_status = sim.wait(Duration::from_secs(30));
    let what = format!("{} on {}", case.name, board.name);
    match (&case.expect, run) {
        (Expect::Retries { diagnostic }, Err(e)) => {
            let attempts = e
                .lines()
                .filter(|l| l.starts_with("firmware: boot attempt") && l.contains(diagnostic))
                .count();
            if attempts >= 2 {
                Ok(format!("{what}: {attempts} boot attempts in {} s, each `{diagnostic}...`, still retrying (stopped)", limit.as_secs()))
            } else {
                Err(format!(
                    "{what}: expected repeated `{diagnostic}` attempts, got:\n{e}"
                ))
            }
        }
        (_, Err(e)) => Err(format!("{what}: {e}")),
        (Expect::Retries { .. }, Ok(r)) => Err(format!(
            "{what}: the real-board profile ended (status {:?}) instead of retrying:\n{}",
            r.code(),
            r.stderr
        )),
        (Expect::Fails { status, diagnostic }, Ok(r)) => {
            let line = r
                .stderr
                .lines()
                .find(|l| l.starts_with("firmware: ") && l.contains(diagnostic));
            match (r.code() == Some(*status), line) {
                (true, Some(l)) => Ok(format!("{what}: exit status {status}, `{l}`")),
                _ => Err(format!(
                    "{what}: expected exit status {status} and `{diagnostic}`, got status {:?}:\n{}",
                    r.code(),
                    r.stderr
                )),
            }
        }
        (Expect::Reconfigures { report }, Ok(r)) => {
            let configured = r.stderr.matches("firmware: unit configured").count();
            let reports = r.stderr.matches(report).count();
            if r.code() == Some(0) && configured == 2 && reports == 1 {
                Ok(format!(
                    "{what}: `{report}` reported, configured again, run completed (exit 0)"
                ))
            } else {
                Err(format!(
                    "{what}: expected one `{report}`, two configurations and exit 0, got status {:?}:\n{}",
                    r.code(),
                    r.stderr
                ))
            }
        }
        (Expect::Csv { stderr_has } | Expect::CsvStack { stderr_has, .. }, Ok(r)) => {
            if r.code() != Some(0) {
                return Err(format!(
                    "{what}: firmware exit status {:?}:\n{}",
                    r.code(),
                    r.stderr
                ));
            }
            if !r.stderr.contains(stderr_has) {
                return Err(format!(
                    "{what}: `{stderr_has}` missing from:\n{}",
                    r.stderr
                ));
            }
            match sim_status {
                Ok(s) if s.success() => {}
                other => return Err(format!("{what}: nav440 sim ended with {other:?}")),
            }
            if counter(&counters(&r.stderr), "uart_overruns").unwrap_or(0) != 0 {
                return Err(format!("{what}: UART overruns reported under QEMU"));
            }
            let stack = match case.expect {
                Expect::CsvStack { stack_limit, .. } => {
                    let p = stack_within(&counters(&r.stderr), stack_limit, &what)?;
                    format!("; stack high-water mark {p} B, at most {stack_limit} B")
                }
                _ => String::new(),
            };
            let host = host_estimate(&record, host_extra)?;
            let lines = compare_csv(&r.stdout, &host).map_err(|d| {
                format!("{what}: firmware CSV differs from `nav440 estimate` on the record: {d}")
            })?;
            // A flashable image: its output read the ways of a real board gives the same CSV.
            let logs = if board.name == qemu::STM32_BOARD.name {
                format!(
                    "; {}",
                    saved_logs_decode(elf, &r).map_err(|e| format!("{what}: {e}"))?
                )
            } else {
                String::new()
            };
            Ok(format!(
                "{what}: IDENTICAL to `nav440 estimate{}` on the {} bytes streamed after configuration ({lines} lines; the unit sent {} bytes in all){logs}{stack}",
                host_extra.iter().map(|a| format!(" {a}")).collect::<String>(),
                std::fs::metadata(&record).map_or(0, |m| m.len()),
                r.unit_bytes
            ))
        }
    }
}

/// The decoders of a flashed board's output fed the exact bytes a QEMU run of the image
/// produced (its defmt frames): `cargo xtask decode` on them as a saved RTT log, and on the
/// text probe-rs prints for them (`cargo xtask flash`'s path; the text is made here by
/// defmt-decoder's rendering of each message, which is what probe-rs prints with `--log-format
/// "{s}"`). Each must give the CSV the run printed, header and rows, and the same other lines.
fn saved_logs_decode(elf: &Path, r: &crate::unit::UnitRun) -> Result<String, String> {
    use crate::defmt_out::{decode_frames, decode_lines, frame_lines, table};
    let raw = r
        .raw
        .as_deref()
        .ok_or("the firmware's output was too long to keep")?;
    let table = table(elf)?.ok_or("the image has no row message")?;
    let frames = decode_frames(&table, raw)?;
    let lines = frame_lines(&table, raw)?;
    let text = decode_lines(&lines)?;
    for (how, t) in [
        ("as a saved RTT log", &frames),
        ("as probe-rs's text", &text),
    ] {
        if t.csv != r.stdout {
            let at = compare_csv(&t.csv, &r.stdout).err().unwrap_or_default();
            return Err(format!(
                "its {} output bytes decoded {how} differ from the run's CSV: {at}",
                raw.len()
            ));
        }
    }
    if frames.diag != text.diag {
        return Err(
            "the diagnostics decoded from the frames and from probe-rs's text differ".into(),
        );
    }
    let saved = unique_path("rtt-log", "defmt")?;
    std::fs::write(&saved, raw).map_err(|e| format!("{}: {e}", saved.display()))?;
    let decoded = xtask_prints(
        &["decode".as_ref(), elf.as_os_str(), saved.as_os_str()],
        None,
    );
    let _ = std::fs::remove_file(&saved);
    if decoded? != r.stdout {
        return Err(
            "`cargo xtask decode` on the saved output printed another CSV than the run".into(),
        );
    }
    let runner = runner_prints(elf, &lines)?;
    if runner != r.stdout {
        let at = compare_csv(&runner, &r.stdout).err().unwrap_or_default();
        return Err(format!(
            "`cargo xtask flash` printed another CSV than the run: {at}"
        ));
    }
    Ok(format!(
        "its {} output bytes give the same CSV as a saved RTT log (`cargo xtask decode`), as probe-rs's text and through `cargo xtask flash` ({} lines)",
        raw.len(),
        lines.lines().count()
    ))
}

/// What `cargo xtask flash ELF` (this program's `flash`) prints on stdout when `probe-rs`
/// prints `lines`: a stand-in `probe-rs` first on `PATH` checks the arguments the runner gives
/// it (`run --chip CHIP --log-format {s} ELF`) and prints the lines.
fn runner_prints(elf: &Path, lines: &str) -> Result<String, String> {
    let dir = unique_path("fake-probe-rs", "d")?;
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    std::fs::write(dir.join("log.txt"), lines).map_err(|e| e.to_string())?;
    let script = dir.join("probe-rs");
    std::fs::write(
        &script,
        "#!/bin/sh\n[ \"$1 $2 $4 $5\" = \"run --chip --log-format {s}\" ] || { echo \"probe-rs stand-in: unexpected arguments: $*\" >&2; exit 9; }\ncat \"$(dirname \"$0\")/log.txt\"\n",
    )
    .map_err(|e| e.to_string())?;
    {
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| e.to_string())?;
    }
    let path = format!(
        "{}:{}",
        dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = xtask_prints(&["flash".as_ref(), elf.as_os_str()], Some(&path));
    let _ = std::fs::remove_dir_all(&dir);
    out
}

/// What this program prints on stdout when run with `args` (and `PATH` set to `path`).
fn xtask_prints(args: &[&std::ffi::OsStr], path: Option<&str>) -> Result<String, String> {
    let me = std::env::current_exe().map_err(|e| e.to_string())?;
    let mut cmd = std::process::Command::new(me);
    cmd.args(args);
    if let Some(p) = path {
        cmd.env("PATH", p);
    }
    let what = format!("`cargo xtask {}`", args[0].to_string_lossy());
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run {what}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{what} ended with {}: {}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    String::from_utf8(out.stdout).map_err(|_| format!("{what} printed no text"))
}

/// Queues `case` on `board` (image `elf`) as a job of the step `group`; the host's CSV comes
/// from `nav440 estimate RECORD host_extra`.
fn spawn_case(
    pool: &Pool,
    group: &'static str,
    board: Board,
    elf: &Path,
    case: UnitCase,
    host_extra: Vec<String>,
) -> Result<(), String> {
    let nav440 = nav440_bin()?;
    let elf = elf.to_path_buf();
    let label = format!(
        "{} ({}) on {}",
        case.name,
        case.capture
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        board.name
    );
    pool.spawn(group, label, move || {
        let t = std::time::Instant::now();
        let extra: Vec<&str> = host_extra.iter().map(String::as_str).collect();
        let ok = unit_case(&board, &elf, &nav440, &case, &extra)?;
        eprintln!(
            "xtask: {group} OK ({:.1} s): {ok}",
            t.elapsed().as_secs_f64()
        );
        Ok(())
    });
    Ok(())
}

/// `elf` on `board` against `nav440 sim` streaming `capture` (boot, configuration, stream), a
/// job of `group` in `pool`: exit 0, `stderr_has` in its stderr, the CSV of `nav440 estimate
/// host_extra` on what the unit streamed, and a stack high-water mark of at most `stack_limit`
/// bytes.
pub(super) fn spawn_stack_case(
    pool: &Pool,
    group: &'static str,
    board: Board,
    elf: &Path,
    capture: &Path,
    host_extra: &[&str],
    (stderr_has, stack_limit): (&'static str, u64),
) -> Result<(), String> {
    let case = UnitCase {
        name: "stack",
        capture: capture.to_path_buf(),
        sim_args: &["--fast"],
        expect: Expect::CsvStack {
            stderr_has,
            stack_limit,
        },
    };
    let extra = host_extra.iter().map(|a| (*a).to_owned()).collect();
    spawn_case(pool, group, board, elf, case, extra)
}

/// The stack high-water mark of `elf` on `board` through a boot, a configuration and the
/// stream of `capture` from `nav440 sim` (exit 0 required), bytes.
pub(super) fn unit_stack_peak(board: &Board, elf: &Path, capture: &Path) -> Result<u64, String> {
    let nav440 = nav440_bin()?;
    let sim_args = ["--fast", "--timeout", SIM_TIMEOUT];
    let sim = Sim::start(&nav440, capture, None, &sim_args)?;
    let bytes = std::fs::metadata(capture).map_or(0, |m| m.len() as usize);
    let run = run_unit(board, elf, &sim.addr, false, unit_timeout(bytes));
    let _ = sim.wait(Duration::from_secs(30));
    let r = run?;
    let what = format!("{} on {} against `nav440 sim`", elf.display(), board.name);
    if r.code() != Some(0) {
        return Err(format!("{what}: exit status {:?}:\n{}", r.code(), r.stderr));
    }
    counter(&counters(&r.stderr), "stack_peak")
        .ok_or_else(|| format!("{what}: no stack_peak counter:\n{}", r.stderr))
}

/// The step of the unit runs in `cargo xtask ci`'s table.
pub(super) const UNIT_STEP: &str = "unit runs (pool)";

/// The firmware against `nav440 sim` on every emulated board and the STM32 profile: every
/// bundled capture (CSV identical to `nav440 estimate` on what the unit streamed after
/// configuration) and the faults, each with its diagnostic and exit status.
/// The images are built here; each run is a job of `pool`.
pub(super) fn unit_ci(
    pool: &Pool,
    captures: &[PathBuf],
    short: &Path,
    only: Option<Board>,
) -> Result<(), String> {
    let short = short.to_path_buf();
    let mut boards: Vec<Board> = qemu::BOARDS.to_vec();
    boards.push(qemu::STM32_BOARD);
    if let Some(b) = only {
        boards.retain(|x| x.name == b.name);
    }
    for board in &boards {
        let elf = build(board.target, board.features, FW_BIN)?;
        let stm32 = board.features.contains(&STM32_FEATURE);
        let host_extra: Vec<String> = firmware_host_args(board.target, BankChoice::Paper)
            .into_iter()
            .map(str::to_owned)
            .collect();
        let mut cases: Vec<UnitCase> = captures
            .iter()
            .map(|c| UnitCase {
                name: "capture",
                capture: c.clone(),
                sim_args: &["--fast"],
                expect: Expect::Csv {
                    stderr_has: "unit was at 38400 Bd",
                },
            })
            .collect();
        cases.push(UnitCase {
            name: "already-57600",
            capture: short.clone(),
            sim_args: &["--fast", "--baud", "57600"],
            expect: Expect::Csv {
                stderr_has: "found at 57600 Bd, unit was at 57600 Bd",
            },
        });
        let faults: [(&'static str, &'static [&'static str], i32, &'static str); 5] = [
            (
                "no-answer",
                &["--fault", "no-answer"],
                2,
                "no answer from the unit",
            ),
            (
                "nak",
                &["--fault", "nak-config"],
                3,
                "unit rejected (NAK) SF",
            ),
            (
                "wrong-readback",
                &["--fault", "wrong-readback"],
                4,
                "wrong read-back (GF)",
            ),
            ("reset", RESET.0, 5, RESET.1),
            ("silence", SILENCE.0, 2, SILENCE.1),
        ];
        for (name, sim_args, status, diagnostic) in faults {
            let expect = match (stm32, name) {
                (true, "reset") => Expect::Reconfigures {
                    report: "firmware: unit reset mid-stream",
                },
                (true, "silence") => Expect::Retries {
                    diagnostic: "no answer",
                },
                (true, _) => Expect::Retries { diagnostic },
                (false, _) => Expect::Fails { status, diagnostic },
            };
            cases.push(UnitCase {
                name,
                capture: short.clone(),
                sim_args,
                expect,
            });
        }
        // Stream faults the firmware reports while it happens and survives: time stamps
        // frozen for 50 packets, a stream at twice the configured rate (CSV identical to
        // `nav440 estimate` on the record), a silence of 1 s (configured again, exit 0).
        for (name, sim_args, stderr_has) in [
            ("freeze", FREEZE.0, FREEZE.1),
            (
                "double-rate",
                &["--fast", "--fault", "double-rate"][..],
                "firmware: packet rate differs from the configuration: a period of 5000 us measured, 10000 us configured",
            ),
        ] {
            cases.push(UnitCase {
                name,
                capture: short.clone(),
                sim_args,
                expect: Expect::Csv { stderr_has },
            });
        }
        cases.push(UnitCase {
            name: "silence-1s",
            capture: short.clone(),
            sim_args: SILENCE_1S.0,
            expect: Expect::Reconfigures {
                report: SILENCE_1S.1,
            },
        });
        for case in cases {
            spawn_case(pool, UNIT_STEP, *board, &elf, case, host_extra.clone())?;
        }
        // The product firmware of a board that cannot replay captures (its board image):
        // every capture through the simulated unit, byte-identical to `nav440 estimate --bank
        // product` (the replay boards are compared on every capture in `ci_steps`).
        if stm32 {
            let mut features = board.features.to_vec();
            features.extend(BankChoice::FixedGains.features());
            let elf = build(board.target, &features, FW_BIN)?;
            let extra: Vec<String> = firmware_host_args(board.target, BankChoice::FixedGains)
                .into_iter()
                .map(str::to_owned)
                .collect();
            for c in captures {
                let case = UnitCase {
                    name: "product-capture",
                    capture: c.clone(),
                    sim_args: &["--fast"],
                    expect: Expect::Csv {
                        stderr_has: "unit was at 38400 Bd",
                    },
                };
                spawn_case(pool, UNIT_STEP, *board, &elf, case, extra.clone())?;
            }
        }
    }
    Ok(())
}

/// The board of the output-UART runs: the M4F (its UART2 is the rows' output UART).
const UART_ROWS_BOARD: &str = "an386";

/// The `uart-rows` image on [`UART_ROWS_BOARD`] against `nav440 sim` on each of `captures`,
/// each run a job of the unit runs' step: its output UART (UART2) written to a file, `nav440
/// rows` on that file must print the CSV of `nav440 estimate` on what the unit streamed after
/// configuration, byte for byte, and so must the image's defmt rows. The image is built here.
pub(super) fn uart_rows_ci(pool: &Pool, captures: &[PathBuf]) -> Result<(), String> {
    let board = qemu::board(UART_ROWS_BOARD)?;
    let elf = build(board.target, &[UART_ROWS], FW_BIN)?;
    let nav440 = nav440_bin()?;
    let host: Vec<String> = firmware_host_args(board.target, BankChoice::Paper)
        .into_iter()
        .map(str::to_owned)
        .collect();
    for capture in captures {
        let (elf, nav440, capture, host) =
            (elf.clone(), nav440.clone(), capture.clone(), host.clone());
        let label = format!(
            "uart-rows ({}) on {}",
            capture
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            board.name
        );
        pool.spawn(UNIT_STEP, label, move || {
            let t = std::time::Instant::now();
            let extra: Vec<&str> = host.iter().map(String::as_str).collect();
            let ok = uart_rows_case(&board, &elf, &nav440, &capture, &extra)?;
            eprintln!(
                "xtask: {UNIT_STEP} OK ({:.1} s): {ok}",
                t.elapsed().as_secs_f64()
            );
            Ok(())
        });
    }
    Ok(())
}

/// One run of [`uart_rows_ci`]; Ok(description) or Err(what went wrong).
fn uart_rows_case(
    board: &Board,
    elf: &Path,
    nav440: &Path,
    capture: &Path,
    host_extra: &[&str],
) -> Result<String, String> {
    let what = format!("uart-rows on {} ({})", board.name, capture.display());
    let record = unique_path(&format!("ci-uart-rows-{}-record", board.name), "bin")?;
    let rows_file = unique_path(&format!("ci-uart-rows-{}-uart2", board.name), "bin")?;
    let sim = Sim::start(
        nav440,
        capture,
        Some(&record),
        &["--fast", "--timeout", SIM_TIMEOUT],
    )?;
    let bytes = std::fs::metadata(capture).map_or(0, |m| m.len() as usize);
    let run = run_unit_rows(board, elf, &sim.addr, unit_timeout(bytes), &rows_file);
    let sim_status = sim.wait(Duration::from_secs(30));
    let r = run.map_err(|e| format!("{what}: {e}"))?;
    if r.code() != Some(0) {
        return Err(format!(
            "{what}: firmware exit status {:?}:\n{}",
            r.code(),
            r.stderr
        ));
    }
    match sim_status {
        Ok(s) if s.success() => {}
        other => return Err(format!("{what}: nav440 sim ended with {other:?}")),
    }
    let host = host_estimate(&record, host_extra)?;
    compare_csv(&r.stdout, &host)
        .map_err(|d| format!("{what}: the defmt rows' CSV differs from `nav440 estimate`: {d}"))?;
    let uart2 = std::fs::metadata(&rows_file).map_or(0, |m| m.len());
    let rows_args = ["rows".to_owned(), rows_file.display().to_string()];
    eprintln!("+ {} {}", nav440.display(), rows_args.join(" "));
    let o = std::process::Command::new(nav440)
        .args(&rows_args)
        .output()
        .map_err(|e| format!("{what}: cannot run {}: {e}", nav440.display()))?;
    let stderr = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() || !stderr.is_empty() {
        return Err(format!(
            "{what}: `nav440 rows` on the {uart2} bytes of UART2 ended with {} and said:\n{stderr}",
            o.status
        ));
    }
    let csv = String::from_utf8(o.stdout)
        .map_err(|_| format!("{what}: `nav440 rows` printed non-UTF-8"))?;
    let lines = compare_csv(&csv, &host).map_err(|d| {
        format!("{what}: `nav440 rows` on UART2 differs from `nav440 estimate` on the record: {d}")
    })?;
    // Every row and header went out as one frame, and none failed to encode.
    let c = counters(&r.stderr);
    let frames = counter(&c, "rows_frames").unwrap_or(0);
    let headers = (lines as u64).saturating_sub(1).div_ceil(100).max(1);
    if counter(&c, "rows_encode_errors") != Some(0) || frames != lines as u64 - 1 + headers {
        return Err(format!(
            "{what}: the firmware counted {frames} frames on UART2 ({lines} CSV lines, {headers} headers expected):\n{}",
            r.stderr
        ));
    }
    let _ = std::fs::remove_file(&rows_file);
    Ok(format!(
        "{what}: `nav440 rows` on the {uart2} bytes of UART2 ({frames} frames) IDENTICAL to `nav440 estimate{}` on the {} bytes streamed after configuration ({lines} lines), and so are the defmt rows",
        host_extra.iter().map(|a| format!(" {a}")).collect::<String>(),
        std::fs::metadata(&record).map_or(0, |m| m.len()),
    ))
}

/// The step of the embassy example's runs in `cargo xtask ci`'s table.
pub(super) const EMBASSY_STEP: &str = "embassy example runs (pool)";

/// `cargo xtask embassy`: the embassy example (`firmware-example/src/bin/embassy.rs`, an
/// embassy-executor task with nav440-proto's async driver) linted, built for thumbv7em and run
/// on QEMU `mps2-an386` against `nav440 sim`: every bundled capture (CSV identical to `nav440
/// estimate` on what the unit streamed after configuration), a unit that never answers, and the
/// stream watchdog's cases of the blocking firmware (silence, frozen stamps, a reset).
pub fn embassy() -> Result<(), String> {
    let start = std::time::Instant::now();
    let pool = Pool::new(super::POOL_THREADS, crate::steps::Steps::new(&root()))?;
    embassy_jobs(&pool)?;
    pool.wait()?;
    eprintln!(
        "xtask: embassy example against nav440 sim: every case passed in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// [`embassy`]'s lint and build; its runs are jobs of `pool`.
pub fn embassy_jobs(pool: &Pool) -> Result<(), String> {
    let board = qemu::BOARDS
        .iter()
        .find(|b| b.name == "an386")
        .ok_or("board an386 missing")?;
    // In the image's profile, as `clippy_firmware`.
    cargo(&[
        "clippy",
        "-p",
        FW,
        "--target",
        board.target,
        "--release",
        "--features",
        "embassy",
        "--bin",
        "embassy",
        "--",
        "-D",
        "warnings",
    ])?;
    let elf = build(board.target, &["embassy"], "embassy")?;
    if !qemu::ensure_or_skip("the embassy example's QEMU runs")? {
        return Ok(());
    }
    let mut cases: Vec<UnitCase> = data_captures()
        .into_iter()
        .map(|capture| UnitCase {
            name: "embassy",
            capture,
            sim_args: &["--fast"],
            expect: Expect::Csv {
                stderr_has: "unit configured (embassy, async driver): A2 at 57600 Bd (unit was at 38400 Bd)",
            },
        })
        .collect();
    // The rate halves after the warm-up, then a reset at a fifth of it: the period change is
    // reported while it happens.
    cases.push(UnitCase {
        name: "embassy-rate-drop",
        capture: rate_drop_capture("embassy")?,
        sim_args: &["--fast"],
        expect: Expect::Csv {
            stderr_has: PERIOD_CHANGE,
        },
    });
    cases.push(UnitCase {
        name: "embassy-no-answer",
        capture: short_capture(),
        sim_args: &["--fault", "no-answer"],
        expect: Expect::Fails {
            status: 2,
            diagnostic: "boot failed: no answer from the unit",
        },
    });
    // The stream watchdog, as on the blocking firmware's emulated boards: a unit silent for
    // ever (reported, then the boot finds no unit: status 2), silent for 1 s (reported,
    // configured again, exit 0), frozen time stamps (reported, CSV = host), a reset (status 5).
    cases.push(UnitCase {
        name: "embassy-silence",
        capture: short_capture(),
        sim_args: SILENCE.0,
        expect: Expect::Fails {
            status: 2,
            diagnostic: SILENCE.1,
        },
    });
    cases.push(UnitCase {
        name: "embassy-silence-1s",
        capture: short_capture(),
        sim_args: SILENCE_1S.0,
        expect: Expect::Reconfigures {
            report: SILENCE_1S.1,
        },
    });
    cases.push(UnitCase {
        name: "embassy-freeze",
        capture: short_capture(),
        sim_args: FREEZE.0,
        expect: Expect::Csv {
            stderr_has: FREEZE.1,
        },
    });
    cases.push(UnitCase {
        name: "embassy-reset",
        capture: short_capture(),
        sim_args: RESET.0,
        expect: Expect::Fails {
            status: 5,
            diagnostic: RESET.1,
        },
    });
    for case in cases {
        // The embassy example runs the firmware's pipeline (`pipeline::AXES`) and defmt rows.
        let extra = vec!["--axis".to_owned(), FIRMWARE_AXIS.to_owned()];
        spawn_case(pool, EMBASSY_STEP, *board, &elf, case, extra)?;
    }
    Ok(())
}

/// `cargo xtask ci-unit`: the unit runs of `ci-firmware` (QEMU required).
pub fn ci_unit(only: Option<Board>) -> Result<(), String> {
    qemu::ensure_qemu()?;
    let start = std::time::Instant::now();
    let pool = Pool::new(super::POOL_THREADS, crate::steps::Steps::new(&root()))?;
    unit_ci(&pool, &data_captures(), &short_capture(), only)?;
    if only.is_none_or(|b| b.name == UART_ROWS_BOARD) {
        uart_rows_ci(&pool, &[short_capture()])?;
    }
    pool.wait()?;
    eprintln!(
        "xtask: firmware against nav440 sim: every case passed in {:.0} s",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The short capture of the unit cases (faults, baud).
pub(super) fn short_capture() -> PathBuf {
    root().join("host-tests/data/sin5_a2_25hz_weekwrap.bin")
}
