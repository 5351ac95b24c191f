//! The firmware part of `cargo xtask ci` (`cargo xtask ci-firmware`): lints, builds and
//! memory-map checks of every image, then under QEMU the firmware/host equivalence on every
//! capture, the unit runs, the failure exits, the bench and the sizes.

use super::build::{
    adaptive_boards, build, build_bins, build_profile, build_small, clippy_firmware, small_boards,
};
use super::captures::{
    bit_fail_capture, bundled_capture, data_captures, false_header_capture, off_rate_capture,
    rate_change_capture, rate_drop_capture, BIT_FAILED_FRAMES, FALSE_HEADER, NOT_PREBUILT,
    OFF_RATE_MS, PERIOD_CHANGE, SPIN_20HZ,
};
use super::equivalence::{equivalence, equivalence_csv, equivalence_full, peak_of, peak_velocity};
use super::nav440_cli::{adaptive_host_args, firmware_host_args, nav440_synth, small_host_args};
use super::qemu_run::counter;
use super::size::{build_noref, euler_symbols, size, soft_float_symbols, NOREF_BOARD};
use super::soak::CI_SOAK;
use super::unit_cases::{short_capture, uart_rows_ci, unit_ci};
use super::{
    read_file, root, work_dir, BankChoice, ADAPTIVE, BENCH_BIN, FIXED_GAINS, FW, FW_BIN,
    NO_REFERENCE, NO_REFERENCE_ARG, ONE_AXIS, PRODUCT, SELF_TUNE, STM32_FEATURE, TUNED,
    TUNED_GAINS, UART_ROWS,
};
use crate::pool::Pool;
use crate::qemu::{self, Board, Output};
use std::path::Path;
use std::time::Duration;

/// The memory-map check of one image (`cargo xtask check-map`), with a line saying so, and
/// the check that it links no float formatting of `core::fmt`.
fn check_map(elf: &Path, board: &str) -> Result<(), String> {
    let r = crate::elf::check_memory_map(elf, Some(board))?;
    let floats = &r.float_symbols;
    if !floats.is_empty() {
        return Err(format!(
            "{} links core::fmt's float formatting ({} symbols, e.g. {}): the firmware must send raw bits and let the host format them",
            elf.display(),
            floats.len(),
            floats[0]
        ));
    }
    eprintln!(
        "xtask: OK: memory map of {}: board {}, {} loadable sections inside its chip's memory, vector table at {:#010x}; no float formatting linked",
        elf.file_name().map(|n| n.to_string_lossy()).unwrap_or_default(),
        r.board,
        r.sections,
        r.vector_table
    );
    Ok(())
}

/// The memory-map check refuses the STM32F405 image with its vector table moved to address 0
/// (where a link with the QEMU map put it) and with its loadable bytes loaded at 0, naming the
/// section or segment and the address.
fn map_check_catches_an_image_at_0(f405: &Path) -> Result<(), String> {
    let data = read_file(f405)?;
    let cases = [
        (
            crate::elf::with_section_address(&data, ".vector_table", 0)?,
            "section .vector_table at 0x00000000",
        ),
        (
            crate::elf::with_load_address(&data, 0)?,
            "is loaded at 0x00000000",
        ),
    ];
    for (i, (bytes, want)) in cases.iter().enumerate() {
        let moved = work_dir()?.join(format!("firmware-stm32f405-moved-{i}.elf"));
        std::fs::write(&moved, bytes)
            .map_err(|e| format!("cannot write {}: {e}", moved.display()))?;
        match crate::elf::check_memory_map(&moved, Some("stm32f405")) {
            Err(e) if e.contains(want) => {
                eprintln!("xtask: OK: the memory-map check refuses a moved image: {e}")
            }
            Err(e) => {
                return Err(format!(
                    "the memory-map check failed otherwise on a moved image: {e}"
                ))
            }
            Ok(_) => {
                return Err(format!(
                    "the memory-map check accepted a moved image ({want})"
                ))
            }
        }
    }
    Ok(())
}

/// Queues the equivalence of `elf` on `board` and `capture` against `nav440 estimate CAPTURE
/// args` as a job of the step `group`; `check` then looks at the firmware's counters.
pub(super) fn spawn_equivalence(
    pool: &Pool,
    group: &'static str,
    board: Board,
    elf: &Path,
    capture: &Path,
    args: &[&str],
    check: impl FnOnce(&[(String, u64)]) -> Result<(), String> + Send + 'static,
) {
    let (elf, capture) = (elf.to_path_buf(), capture.to_path_buf());
    let args: Vec<String> = args.iter().map(|a| (*a).to_owned()).collect();
    let label = format!(
        "{} on {} ({})",
        capture
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        board.name,
        elf.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    pool.spawn(group, label, move || {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let c = equivalence(&board, &elf, &capture, &a)?;
        check(&c)
    });
}

/// A counter check: `want` for `key`, or an error naming the image and the capture.
fn expect_counter(c: &[(String, u64)], key: &str, want: u64, what: &str) -> Result<(), String> {
    match counter(c, key) {
        Some(v) if v == want => Ok(()),
        got => Err(format!(
            "{what}: the firmware reported {key}={got:?}, expected {want}"
        )),
    }
}

/// The steps of the firmware part in `cargo xtask ci`'s table.
const BUILD_STEP: &str = "firmware lints, builds, maps";
const EQUIVALENCE_STEP: &str = "equivalence runs (pool)";
const CHECKS_STEP: &str = "failure exits, bench (pool)";
const SOAK_STEP: &str = "soak (pool)";

/// `cargo xtask ci-firmware`: [`ci_steps`] with its own step table and job pool.
pub fn ci_firmware() -> Result<(), String> {
    let steps = crate::steps::Steps::new(&root());
    let pool = Pool::new(super::POOL_THREADS, steps.clone())?;
    let r = ci_steps(&pool).and_then(|()| steps.run("wait for the QEMU jobs", || pool.wait()));
    let r = r.and_then(|()| steps.run("size", size));
    eprint!("{}", steps.table());
    r
}

/// The firmware part of `cargo xtask ci`: lints, builds and memory maps of every image here;
/// every QEMU run (equivalence, unit cases, soak, failure exits, bench) a job of `pool`, queued
/// as soon as its image is built. The caller waits for the pool.
pub fn ci_steps(pool: &Pool) -> Result<(), String> {
    let steps = pool.steps().clone();
    steps.run(BUILD_STEP, || queue_firmware(pool))
}

/// [`ci_steps`]' work.
fn queue_firmware(pool: &Pool) -> Result<(), String> {
    // QEMU must be there or installable: the test command runs every test. Only an explicit
    // opt-out (XTASK_SKIP_QEMU=1, for a machine where QEMU cannot be installed) skips the QEMU
    // runs, loudly; the lints and cross builds still run.
    let qemu_ok = qemu::ensure_or_skip(
        "the firmware QEMU runs, the firmware/host equivalence check, the bench and the stack measurement",
    )?;
    // The captures: the bundled ones and those CI synthesises.
    let bundled = bundled_capture()?;
    let corrupted = work_dir()?.join("ci-corrupted.bin");
    nav440_synth(
        &corrupted,
        &[
            "--profile",
            "spin",
            "--duration",
            "5",
            "--flip-bits",
            "20",
            "--garbage",
            "10",
            "--drop-packets",
            "5",
            "--seed",
            "7",
        ],
    )?;
    // A capture shorter than the firmware's warm-up (10 packets < 16): the bank starts at the
    // end of the input.
    let short = work_dir()?.join("ci-short.bin");
    let bytes = read_file(&bundled)?;
    std::fs::write(&short, bytes.get(..400).unwrap_or(&bytes))
        .map_err(|e| format!("cannot write {}: {e}", short.display()))?;
    // A capture whose packet rate changes after the warm-up: 20 packets at 100 Hz, then 50 at
    // 50 Hz. Host and firmware both take the bank's period from the first 16 samples
    // (`nav440_pipeline::period`), so they must still agree byte for byte.
    let rate_change = rate_change_capture()?;
    // The bundled capture with 101 packets flagging a BIT failure (masterFail): not estimated,
    // counted in the firmware's summary (`bit_failed`) and dropped alike by `nav440 estimate`.
    let bit_fail = bit_fail_capture(&bundled)?;
    // The bundled capture with a false frame header before its last two frames: at the end of
    // the input both are recovered and the header's bytes reported, by host and firmware alike.
    let false_header = false_header_capture(&bundled)?;
    // Packet rates below the bundled captures' (20-100 Hz), where the shipped preset runs
    // other gains (`BankConfig::NAV440_RATES`: one entry for 10 Hz, one for 2 Hz): the
    // firmware picks the same entry as `nav440 estimate`.
    let mut low_rates = Vec::new();
    for (rate, duration) in [("10", "12"), ("2", "40")] {
        let path = work_dir()?.join(format!("ci-{rate}hz.bin"));
        nav440_synth(
            &path,
            &["--rate", rate, "--duration", duration, "--seed", "4"],
        )?;
        low_rates.push(path);
    }
    // A unit nodding through pitch +-90 deg (15 s, two passes, 45 samples at |pitch| >= 80
    // deg): the roll and yaw banks skip the lock and restart after it, on the board as on the
    // host.
    let tumble = work_dir()?.join("ci-tumble.bin");
    nav440_synth(&tumble, &["--profile", "tumble", "--duration", "15"])?;
    // A capture whose yaw noise switches from 0.01 to 0.5 deg^2 at 10 s (the adaptive
    // firmware's gains follow it).
    let switch = work_dir()?.join("ci-noise-switch.bin");
    nav440_synth(
        &switch,
        &[
            "--duration",
            "20",
            "--seed",
            "2",
            "--yaw-noise",
            "0.01",
            "--yaw-noise",
            "0.5@10",
            "--noise-seed",
            "3",
        ],
    )?;
    // The rate halves after the warm-up, then a reset at a fifth of it: the period is measured
    // again and every estimate stays bounded (checked on the product images below).
    let rate_drop = rate_drop_capture("ci")?;
    // Every bundled capture (all packet types and rates, the week wrap) plus those nine.
    let mut captures = data_captures();
    captures.extend([
        corrupted,
        short,
        rate_change,
        rate_drop.clone(),
        bit_fail.clone(),
        false_header.clone(),
        tumble.clone(),
    ]);
    captures.extend(low_rates);

    // Lints: the FPU build and the no-FPU (fixed-point) builds.
    for target in crate::THUMB_TARGETS {
        clippy_firmware(target, None)?;
    }
    // The paper bank on every QEMU board: the CSV of `nav440 estimate` (`--fixed` without
    // FPU), byte for byte, on every capture; the special captures' counters checked too.
    let mut elfs = Vec::new();
    for (i, board) in qemu::BOARDS.iter().enumerate() {
        // The M4F's bench and panic check images share this cargo run (and its links' cores).
        let bins: &[&str] = if i == 0 {
            &[FW_BIN, BENCH_BIN, "panic_check"]
        } else {
            &[FW_BIN]
        };
        let elf = build_bins(board.target, &[], bins, "release")?
            .into_iter()
            .next()
            .ok_or("no image built")?;
        check_map(&elf, "mps2")?;
        if qemu_ok {
            let host = firmware_host_args(board.target, BankChoice::Paper);
            for capture in &captures {
                let what = format!("{} on {}", capture.display(), board.name);
                let (fh, tb, bf) = (
                    *capture == false_header,
                    *capture == tumble,
                    *capture == bit_fail,
                );
                spawn_equivalence(
                    pool,
                    EQUIVALENCE_STEP,
                    *board,
                    &elf,
                    capture,
                    &host,
                    move |c| {
                        if fh {
                            expect_counter(c, "end_dropped", FALSE_HEADER.len() as u64, &what)?;
                        }
                        if tb {
                            expect_counter(c, "near_lock", 45, &what)?;
                            expect_counter(c, "lock_passes", 2, &what)?;
                        }
                        if bf {
                            expect_counter(
                                c,
                                "bit_failed",
                                BIT_FAILED_FRAMES.clone().count() as u64,
                                &what,
                            )?;
                        }
                        Ok(())
                    },
                );
            }
        }
        elfs.push((*board, elf));
    }
    // The board images: each with its own memory map, checked from the ELF. The STM32F405
    // image also runs on QEMU netduinoplus2 (the unit runs); the others only build.
    clippy_firmware("thumbv7em-none-eabihf", Some(STM32_FEATURE))?;
    let f405 = build("thumbv7em-none-eabihf", &[STM32_FEATURE], FW_BIN)?;
    check_map(&f405, "stm32f405")?;
    map_check_catches_an_image_at_0(&f405)?;
    // The boards no emulator runs (`boards/src/description.rs`: no `qemu`), for their first
    // target, each as its description's `ci_image` (features, profile): linted, and built and
    // map-checked unless the description leaves the image out (`in_ci`).
    for board in nav440_boards::all()
        .iter()
        .filter(|b| b.example && !b.runs_in_qemu())
    {
        let (feature, target, image) = (board.feature(), board.targets[0], board.ci_image);
        let mut features: Vec<&str> = feature.as_deref().into_iter().collect();
        features.extend(image.features);
        // Linted always (clippy does not link); built and map-checked when `in_ci`.
        clippy_firmware(target, Some(&features.join(",")))?;
        if !image.in_ci {
            eprintln!(
                "xtask: SKIPPED: board {}: its image is not built in CI (ci_image.in_ci false in {}): cargo build -p {FW} --target {target} --profile {} --features {} --bin {FW_BIN}",
                board.name,
                nav440_boards::DESCRIPTION_PATH,
                image.profile,
                features.join(",")
            );
            continue;
        }
        let elf = build_profile(target, &features, FW_BIN, image.profile)?;
        check_map(&elf, board.name)?;
        // Its RAM: static RAM from the ELF, the stack measured on its emulated twin.
        if let (Some(twin), true) = (image.stack_twin, qemu_ok) {
            super::twin::stack_twin_ci(pool, board, &elf, image.features, twin)?;
        }
    }
    // The rows also out of a second UART (feature `uart-rows`, the mps2 boards' UART2): linted
    // on the M4F and thumbv6m, the M4F image's map checked; it runs among the unit runs.
    for board in [qemu::BOARDS[0], qemu::BOARDS[2]] {
        clippy_firmware(board.target, Some(UART_ROWS))?;
    }
    check_map(
        &build(qemu::BOARDS[0].target, &[UART_ROWS], FW_BIN)?,
        "mps2",
    )?;
    // The firmware against the simulated unit: boot, configure, stream, estimate, faults
    // (builds the STM32F405 product image too).
    if qemu_ok {
        unit_ci(pool, &data_captures(), &short_capture(), None)?;
        // The rows out of the output UART (feature `uart-rows`): `nav440 rows` on its bytes
        // prints the CSV of `nav440 estimate` (a tumble: rows without roll and yaw too).
        uart_rows_ci(pool, &[short_capture(), tumble.clone()])?;
        // The soak: 10 minutes of stream with 16 faults (`cargo xtask soak --hours H` for
        // long runs by hand).
        let (minutes, window) = CI_SOAK;
        let soak = super::soak::prepare(minutes, window, 1)?;
        pool.spawn(SOAK_STEP, format!("{minutes} min of stream"), soak);
    }
    // The product firmware with the shipped gains fixed (feature `fixed-gains`) prints the CSV
    // of `nav440 estimate --bank product --fixed-gains --axis all` (`--fixed` without FPU),
    // byte for byte, on every capture and board.
    for board in qemu::BOARDS {
        clippy_firmware(board.target, Some(FIXED_GAINS))?;
        // The product bench (thumbv6m) shares its image's cargo run.
        let bins: &[&str] = if board.target == "thumbv6m-none-eabi" {
            &[FW_BIN, BENCH_BIN]
        } else {
            &[FW_BIN]
        };
        let elf = build_bins(
            board.target,
            BankChoice::FixedGains.features(),
            bins,
            "release",
        )?
        .into_iter()
        .next()
        .ok_or("no image built")?;
        check_map(&elf, "mps2")?;
        if qemu_ok {
            let host = firmware_host_args(board.target, BankChoice::FixedGains);
            for capture in captures.iter().filter(|c| **c != rate_drop) {
                spawn_equivalence(pool, EQUIVALENCE_STEP, *board, &elf, capture, &host, |_| {
                    Ok(())
                });
            }
            queue_rate_drop(pool, *board, &elf, &rate_drop, &host);
        }
        if board.name == NOREF_BOARD.name && euler_symbols(&elf)?.is_empty() {
            return Err(format!(
                "{}: no Euler kinematics (euler_rates_deg, sin_cos_deg) found: the check of the no-reference image below would prove nothing",
                elf.display()
            ));
        }
        // The float-free check below sees soft float where it is linked: with the reference.
        if board.name == NOREF_BOARD.name && soft_float_symbols(&elf)?.is_empty() {
            return Err(format!(
                "{}: no soft-float symbol found: the float-free check of the no-reference image below would prove nothing",
                elf.display()
            ));
        }
    }
    // The product firmware with fixed gains without the Euler reference (features
    // `fixed-gains`, `no-reference`; thumbv6m,
    // profile `small`, the image `cargo xtask size` lists as `product-thumbv6m-3axis-small-noref`):
    // it links no Euler kinematics (no `euler_rates_deg`, no sine or cosine; the product image above
    // does) and prints the CSV of `nav440 estimate --bank product --fixed-gains --axis all
    // --fixed --no-reference`, byte for byte, on every capture; on the tumble it pauses near gimbal
    // lock as the images with the reference do.
    let no_reference = format!("{FIXED_GAINS},{NO_REFERENCE}");
    clippy_firmware(NOREF_BOARD.target, Some(&no_reference))?;
    let noref = build_noref()?;
    check_map(&noref, "mps2")?;
    let linked = euler_symbols(&noref)?;
    if !linked.is_empty() {
        return Err(format!(
            "{} (feature `{NO_REFERENCE}`) links the Euler kinematics: {}",
            noref.display(),
            linked.join(", ")
        ));
    }
    eprintln!(
        "xtask: OK: {} links no Euler kinematics (no sine, cosine or euler_rates_deg)",
        noref.display()
    );
    // Nor any floating point: from the packet's integers to the row, integer operations
    // only (the banks read from the table build.rs built on the host).
    let float = soft_float_symbols(&noref)?;
    if !float.is_empty() {
        return Err(format!(
            "{} (features `{FIXED_GAINS}`, `{NO_REFERENCE}`) must be float-free and links {} soft-float or libm symbols: {}",
            noref.display(),
            float.len(),
            float.join(", ")
        ));
    }
    eprintln!(
        "xtask: OK: {} links no soft-float and no libm routine",
        noref.display()
    );
    if qemu_ok {
        let mut host = firmware_host_args(NOREF_BOARD.target, BankChoice::FixedGains);
        host.push(NO_REFERENCE_ARG);
        for capture in captures.iter().filter(|c| **c != rate_drop) {
            let what = format!(
                "{} on {} (no reference)",
                capture.display(),
                NOREF_BOARD.name
            );
            let tb = *capture == tumble;
            spawn_equivalence(
                pool,
                EQUIVALENCE_STEP,
                NOREF_BOARD,
                &noref,
                capture,
                &host,
                move |c| {
                    if tb {
                        expect_counter(c, "near_lock", 45, &what)?;
                        expect_counter(c, "lock_passes", 2, &what)?;
                    }
                    Ok(())
                },
            );
        }
    }
    // Its banks come from the table build.rs built on the host, one per NAV440 packet rate:
    // at a period that is none of them it stops with the error, and never estimates with a
    // bank built for another period.
    if qemu_ok {
        let input = qemu::framed_input(&read_file(&off_rate_capture()?)?)?;
        spawn_expected_failure(
            pool,
            NOREF_BOARD,
            &noref,
            input,
            "offrate",
            NOT_PREBUILT,
            format!(
                "a packet period of {OFF_RATE_MS} ms, for which the product image holds no bank,"
            ),
        );
    }
    // The product firmware with the gains `nav440 tune --bank product --rust` wrote (feature
    // `tuned-gains`), on the M4F board (the feature changes only the preset; the product bank
    // itself runs on every board above): the CSV of the command the gains file names (`nav440
    // estimate FILE --bank product --gains product_fig5.toml --hold H`), byte for byte, on the
    // bundled capture and the tumble.
    let m4f_board = qemu::BOARDS[0];
    clippy_firmware(m4f_board.target, Some(TUNED))?;
    let tuned = build(m4f_board.target, &[PRODUCT, TUNED], FW_BIN)?;
    check_map(&tuned, "mps2")?;
    if qemu_ok {
        let gains = root().join(TUNED_GAINS);
        let gains_text = read_file(&gains).map(|b| String::from_utf8_lossy(&b).into_owned())?;
        let hold = gains_text
            .split_whitespace()
            .skip_while(|w| *w != "--hold")
            .nth(1)
            .ok_or_else(|| format!("{TUNED_GAINS} names no --hold in its header"))?
            .to_owned();
        let gains = gains.display().to_string();
        let mut host = firmware_host_args(m4f_board.target, BankChoice::FixedGains);
        host.extend(["--gains", &gains, "--hold", &hold]);
        for capture in [&bundled, &tumble] {
            spawn_equivalence(
                pool,
                EQUIVALENCE_STEP,
                m4f_board,
                &tuned,
                capture,
                &host,
                |_| Ok(()),
            );
        }
    }
    // The small-MCU firmware (one axis, profile `small`), M4F and thumbv6m: the CSV of
    // `nav440 estimate --axis yaw` (`--fixed` on thumbv6m), byte for byte, on every capture.
    for (board, _label) in small_boards() {
        clippy_firmware(board.target, Some(ONE_AXIS))?;
        let elf = build_small(board.target, FW_BIN)?;
        check_map(&elf, "mps2")?;
        if qemu_ok {
            for capture in &captures {
                spawn_equivalence(
                    pool,
                    EQUIVALENCE_STEP,
                    board,
                    &elf,
                    capture,
                    small_host_args(board.target),
                    |_| Ok(()),
                );
            }
        }
    }
    // The noise-adaptive firmware (M4F and thumbv6m) prints the CSV of `nav440 estimate
    // --gains schedule_fig5.toml`, byte for byte: on the noise switch (the gains follow it:
    // several retunes), on the noise-free bundled capture (the lowest level) and at 20 Hz.
    for board in adaptive_boards() {
        clippy_firmware(board.target, Some(ADAPTIVE))?;
        let elf = build(board.target, &[ADAPTIVE], FW_BIN)?;
        check_map(&elf, "mps2")?;
        if qemu_ok {
            queue_adaptive(pool, board, &elf, &switch, &bundled);
        }
    }
    // The product firmware with its default gains, which follow (M4F, feature `bank-product`
    // alone), prints the CSV of `nav440 estimate --bank product --axis all`, byte for byte: on the noise switch (its gains follow the noise and
    // the motion), on the noise-free bundled capture and through time faults (new epochs: the
    // jerk estimate must not difference the rate across one).
    let mut follow_runs = vec![switch.clone(), bundled.clone()];
    follow_runs.extend(
        data_captures()
            .into_iter()
            .filter(|p| p.to_string_lossy().contains("time_faults")),
    );
    moving_gains_image(
        pool,
        m4f_board,
        BankChoice::Product,
        PRODUCT,
        &follow_runs,
        qemu_ok,
    )?;
    // The self-tuning product firmware (M4F) prints the CSV of `nav440 estimate --bank product
    // --self-tune --axis all`, byte for byte: on every bundled capture (the time faults
    // included), on the noise switch, through gimbal lock (the tumble: no rate, no tuning) and
    // with BIT failures (no sample, no tuning).
    let mut self_tune_runs = data_captures();
    self_tune_runs.extend([switch.clone(), tumble.clone(), bit_fail.clone()]);
    moving_gains_image(
        pool,
        m4f_board,
        BankChoice::SelfTune,
        SELF_TUNE,
        &self_tune_runs,
        qemu_ok,
    )?;
    if !qemu_ok {
        return Ok(());
    }
    queue_failure_exits(pool, m4f_board, &elfs[0].1, &bundled)?;
    // The benches: instruction counts of the paper bank (M4F) and the product bank (thumbv6m).
    for (board, bank) in [
        (qemu::BOARDS[0], BankChoice::Paper),
        (qemu::BOARDS[2], BankChoice::FixedGains),
    ] {
        let run = super::bench::prepare(board, false, bank)?;
        pool.spawn(
            CHECKS_STEP,
            format!("bench {} on {}", bank.name(), board.name),
            run,
        );
    }
    Ok(())
}

/// A product image whose gains move (`bank`, selected by the firmware feature `feature`) on
/// `board`: linted, built and map-checked; with QEMU, its CSV compared byte for byte with
/// `nav440 estimate`'s on each of `captures`.
fn moving_gains_image(
    pool: &Pool,
    board: Board,
    bank: BankChoice,
    feature: &str,
    captures: &[std::path::PathBuf],
    qemu_ok: bool,
) -> Result<(), String> {
    clippy_firmware(board.target, Some(feature))?;
    let elf = build(board.target, bank.features(), FW_BIN)?;
    check_map(&elf, "mps2")?;
    if qemu_ok {
        let host = firmware_host_args(board.target, bank);
        for capture in captures {
            spawn_equivalence(pool, EQUIVALENCE_STEP, board, &elf, capture, &host, |_| {
                Ok(())
            });
        }
    }
    Ok(())
}

/// The product image on the capture whose rate halves and then drops to a fifth after a reset
/// ([`rate_drop_capture`]): the CSV of `nav440 estimate`, byte for byte; the new epoch's
/// period change reported once; the velocities within 10x the motion's 300 deg/s and the
/// accelerations within 10x its 2,000 deg/s^2 on every axis (before the Kalman followed the
/// actual interval, `kf_a` reached 2e38).
fn queue_rate_drop(pool: &Pool, board: Board, elf: &Path, capture: &Path, host: &[&str]) {
    let (elf, capture) = (elf.to_path_buf(), capture.to_path_buf());
    let args: Vec<String> = host.iter().map(|a| (*a).to_owned()).collect();
    pool.spawn(
        EQUIVALENCE_STEP,
        format!("rate drop on {} (product)", board.name),
        move || {
            let a: Vec<&str> = args.iter().map(String::as_str).collect();
            let (c, csv, stderr) = equivalence_full(&board, &elf, &capture, &a)?;
            let what = format!("the product firmware on {} ({})", board.name, capture.display());
            let reports = stderr.matches(PERIOD_CHANGE).count();
            if reports != 1 {
                return Err(format!(
                    "{what}: `{PERIOD_CHANGE}` printed {reports} times, expected once"
                ));
            }
            expect_counter(&c, "backward_jumps", 1, &what)?;
            for axis in ["roll_", "pitch_", "yaw_"] {
                let (v, acc) = (peak_of(&csv, axis, "_v")?, peak_of(&csv, axis, "_a")?);
                if v >= 3_000.0 || acc >= 20_000.0 {
                    return Err(format!(
                        "{what}: {axis}*_v up to {v} deg/s, {axis}*_a up to {acc} deg/s^2 (bounds 3000 and 20000)"
                    ));
                }
            }
            eprintln!(
                "xtask: OK: {what}: the period change reported once, every estimate bounded"
            );
            Ok(())
        },
    );
}

/// The adaptive firmware's runs (see [`queue_firmware`]).
fn queue_adaptive(pool: &Pool, board: Board, elf: &Path, switch: &Path, bundled: &Path) {
    let args = adaptive_host_args(board.target);
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    let (elf2, switch2) = (elf.to_path_buf(), switch.to_path_buf());
    let args2 = args.clone();
    pool.spawn(
        EQUIVALENCE_STEP,
        format!("adaptive noise switch on {}", board.name),
        move || {
            let a: Vec<&str> = args2.iter().map(String::as_str).collect();
            let (c, csv) = equivalence_csv(&board, &elf2, &switch2, &a)?;
            // The gains followed the noise: the initial level, then 0.01 deg^2, then 0.5.
            let retunes = counter(&c, "yaw_retunes").unwrap_or(0);
            if retunes < 2 {
                return Err(format!(
                    "the adaptive firmware on {} retuned its yaw gains {retunes} times on a noise switch (expected at least 2)",
                    board.name
                ));
            }
            // Identical is not enough: gains at the edge of the Euler step saturate the
            // fixed-point AVE at 2.1e9 deg/s on both sides alike (docs/ADAPTIVE-GAINS.md,
            // "Gains at the edge of the Euler step"). The capture's peak rate is 265 deg/s.
            let peak = peak_velocity(&csv, "yaw_")?;
            if peak >= 1000.0 {
                return Err(format!(
                    "the adaptive firmware on {} printed a yaw velocity estimate of {peak} deg/s on the noise switch (peak rate 265 deg/s)",
                    board.name
                ));
            }
            expect_counter(&c, "yaw_schedule_off_rate", 0, "the noise switch")?;
            eprintln!(
                "xtask: OK: adaptive gains on {}: yaw_retunes={retunes}, yaw velocity estimates within {peak:.1} deg/s",
                board.name
            );
            Ok(())
        },
    );
    spawn_equivalence(pool, EQUIVALENCE_STEP, board, elf, bundled, &a, |_| Ok(()));
    // The schedule (tuned at 100 Hz) on the 20 Hz capture: the same CSV as the host, and the
    // firmware says it runs off its rate (only there: 0 on the 100 Hz captures).
    spawn_equivalence(
        pool,
        EQUIVALENCE_STEP,
        board,
        elf,
        &root().join(SPIN_20HZ),
        &a,
        move |c| expect_counter(c, "yaw_schedule_off_rate", 1, SPIN_20HZ),
    );
}

/// Queues a run of `elf` on `board` fed `input` through its UART (replay mode; `tag` names
/// the input file) that must end with a non-zero exit status whose message contains
/// `needle`; `what` names the case in the job's messages.
fn spawn_expected_failure(
    pool: &Pool,
    board: Board,
    elf: &Path,
    input: Vec<u8>,
    tag: &'static str,
    needle: &'static str,
    what: String,
) {
    let elf = elf.to_path_buf();
    pool.spawn(CHECKS_STEP, what.clone(), move || {
        let path = qemu::input_path(&work_dir()?, tag);
        let r = qemu::run_uart(
            &board,
            &elf,
            &path,
            &input,
            Output::Capture,
            Duration::from_secs(60),
        );
        let _ = std::fs::remove_file(&path);
        match r {
            Err(e) if e.contains(needle) => {
                eprintln!("xtask: OK: {what} ends the firmware with exit status 1 ({needle})");
                Ok(())
            }
            Err(e) => Err(format!("unexpected failure with {what}: {e}")),
            Ok(_) => Err(format!("{what} was accepted (exit status 0)")),
        }
    });
}

/// The failure exits, as jobs: input without the length prefix (exit 1, never a hang), a panic
/// (exit 1 with its message), a hard-float image on the FPU-less board (a HardFault exit).
fn queue_failure_exits(
    pool: &Pool,
    m4f_board: Board,
    m4f: &Path,
    bundled: &Path,
) -> Result<(), String> {
    let raw = read_file(bundled)?;
    spawn_expected_failure(
        pool,
        m4f_board,
        m4f,
        raw.get(..4096).unwrap_or(&raw).to_vec(),
        "noprefix",
        "N4LP",
        "input without the length prefix".into(),
    );
    let panic_elf = build(m4f_board.target, &[], "panic_check")?;
    pool.spawn(
        CHECKS_STEP,
        "panic exit".into(),
        move || match qemu::run_plain(&m4f_board, &panic_elf, &[], Duration::from_secs(60)) {
            Err(e) if e.contains("firmware: panic") => {
                eprintln!("xtask: OK: a panic ends the firmware with exit status 1");
                Ok(())
            }
            Err(e) => Err(format!("unexpected failure of the panic check: {e}")),
            Ok(_) => Err("the panic check firmware exited with status 0".into()),
        },
    );
    let (elf, an385) = (m4f.to_path_buf(), qemu::board("an385")?);
    pool.spawn(
        CHECKS_STEP,
        "hard-float image on the FPU-less board".into(),
        move || match qemu::run_plain(&an385, &elf, &[], Duration::from_secs(60)) {
            Err(e) if e.contains("HardFault") => {
                eprintln!(
                    "xtask: OK: hard-float image on the Cortex-M3 board ends with a HardFault exit"
                );
                Ok(())
            }
            Err(e) => Err(format!("unexpected failure of the fault check: {e}")),
            Ok(_) => Err("hard-float image ran on the FPU-less board without a fault".into()),
        },
    );
    Ok(())
}
