//! The firmware part of `cargo xtask ci` (`cargo xtask ci-firmware`): lints, builds and
//! memory-map checks of every image, then under QEMU the firmware/host equivalence on every
//! capture, the unit runs, the failure exits, the bench and the sizes.

use super::bench::bench;
use super::build::{adaptive_boards, build, build_small, clippy_firmware, small_boards};
use super::captures::{
    bit_fail_capture, bundled_capture, data_captures, false_header_capture, rate_change_capture,
    BIT_FAILED_FRAMES, FALSE_HEADER, SPIN_20HZ,
};
use super::equivalence::{equivalence, equivalence_csv, peak_velocity};
use super::nav440_cli::{adaptive_host_args, firmware_host_args, nav440_synth, small_host_args};
use super::qemu_run::counter;
use super::size::size;
use super::unit_cases::ci_unit;
use super::{
    read_file, root, work_dir, BankChoice, ADAPTIVE, FW_BIN, ONE_AXIS, PRODUCT, STM32_FEATURE,
    TUNED, TUNED_GAINS,
};
use crate::qemu::{self, Output};
use std::path::Path;
use std::time::Duration;

/// The board images that only build (no emulator runs them): (feature, target, board name in
/// the ELF).
const BUILT_ONLY_BOARDS: &[(&str, &str, &str)] = &[
    (
        "board-nucleo-f411re",
        "thumbv7em-none-eabihf",
        "nucleo-f411re",
    ),
    ("board-rp-pico", "thumbv6m-none-eabi", "rp-pico"),
];

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

/// Hours of stream time of the soak `ci` runs.
const CI_SOAK_HOURS: f64 = 1.0;

/// The firmware part of `cargo xtask ci`.
pub fn ci_steps() -> Result<(), String> {
    // QEMU must be there or installable: the test command runs every test. Only an explicit
    // opt-out (XTASK_SKIP_QEMU=1, for a machine where QEMU cannot be installed) skips the QEMU
    // runs, loudly; the lints and cross builds still run.
    let qemu_ok = qemu::ensure_or_skip(
        "the firmware QEMU runs, the firmware/host equivalence check, the bench and the stack measurement",
    )?;
    // Lints: the FPU build and the no-FPU (fixed-point) builds.
    for target in crate::THUMB_TARGETS {
        clippy_firmware(target, None)?;
    }
    let mut elfs = Vec::new();
    for board in qemu::BOARDS {
        let elf = build(board.target, &[], FW_BIN)?;
        check_map(&elf, "mps2")?;
        elfs.push((*board, elf));
    }
    // The board images: each with its own memory map, checked from the ELF. The STM32F405
    // image also runs on QEMU netduinoplus2 (`ci_unit`); the others only build.
    clippy_firmware("thumbv7em-none-eabihf", Some(STM32_FEATURE))?;
    let f405 = build("thumbv7em-none-eabihf", &[STM32_FEATURE], FW_BIN)?;
    check_map(&f405, "stm32f405")?;
    map_check_catches_an_image_at_0(&f405)?;
    for (feature, target, board) in BUILT_ONLY_BOARDS {
        clippy_firmware(target, Some(feature))?;
        check_map(&build(target, &[feature], FW_BIN)?, board)?;
    }
    // The small-MCU firmware (one axis, profile `small`): lint and build for M4F and thumbv6m.
    let mut small_elfs = Vec::new();
    for (board, label) in small_boards() {
        clippy_firmware(board.target, Some(ONE_AXIS))?;
        let elf = build_small(board.target, FW_BIN)?;
        check_map(&elf, "mps2")?;
        small_elfs.push((board, label, elf));
    }
    // The product firmware (feature `bank-product`): lint and build for every QEMU board.
    let mut product_elfs = Vec::new();
    for board in qemu::BOARDS {
        clippy_firmware(board.target, Some(PRODUCT))?;
        let elf = build(board.target, BankChoice::Product.features(), FW_BIN)?;
        check_map(&elf, "mps2")?;
        product_elfs.push((*board, elf));
    }
    // The product firmware with the gains `nav440 tune --bank product --rust` wrote (feature
    // `tuned-gains`): lint and build for the M4F board (the feature changes only the preset;
    // the product bank itself runs on every board above).
    let mut tuned_elfs = Vec::new();
    for board in qemu::BOARDS.iter().take(1) {
        clippy_firmware(board.target, Some(TUNED))?;
        let elf = build(board.target, &[PRODUCT, TUNED], FW_BIN)?;
        check_map(&elf, "mps2")?;
        tuned_elfs.push((*board, elf));
    }
    // The firmware with noise-adaptive gains: lint and build for M4F and thumbv6m.
    let mut adaptive_elfs = Vec::new();
    for board in adaptive_boards() {
        clippy_firmware(board.target, Some(ADAPTIVE))?;
        let elf = build(board.target, &[ADAPTIVE], FW_BIN)?;
        check_map(&elf, "mps2")?;
        adaptive_elfs.push((board, elf));
    }
    if !qemu_ok {
        return Ok(());
    }

    // Equivalence: bundled capture, plus a short corrupted capture (CRC errors, garbage,
    // dropped packets) synthesised by the CLI.
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
    // Every bundled capture (all packet types and rates, the week wrap) plus those eight.
    let mut captures = data_captures();
    captures.extend([
        corrupted,
        short,
        rate_change,
        bit_fail.clone(),
        false_header.clone(),
        tumble.clone(),
    ]);
    captures.extend(low_rates);
    for (board, elf) in &elfs {
        let host_extra = &firmware_host_args(board.target, BankChoice::Paper)[..];
        for capture in &captures {
            let c = equivalence(board, elf, capture, host_extra)?;
            let want = BIT_FAILED_FRAMES.clone().count() as u64;
            let dropped = FALSE_HEADER.len() as u64;
            if *capture == false_header && counter(&c, "end_dropped") != Some(dropped) {
                return Err(format!(
                    "the firmware on {} reported end_dropped={:?} for {}, expected {dropped}",
                    board.name,
                    counter(&c, "end_dropped"),
                    capture.display()
                ));
            }
            if *capture == tumble
                && (counter(&c, "near_lock"), counter(&c, "lock_passes")) != (Some(45), Some(2))
            {
                return Err(format!(
                    "the firmware on {} reported near_lock={:?} lock_passes={:?} for {}, expected 45 and 2",
                    board.name,
                    counter(&c, "near_lock"),
                    counter(&c, "lock_passes"),
                    capture.display()
                ));
            }
            if *capture == bit_fail && counter(&c, "bit_failed") != Some(want) {
                return Err(format!(
                    "the firmware on {} reported bit_failed={:?} for {}, expected {want}",
                    board.name,
                    counter(&c, "bit_failed"),
                    capture.display()
                ));
            }
        }
    }
    // The product firmware (feature `bank-product`) prints the CSV of `nav440 estimate --bank
    // product --axis all` (`--fixed` without FPU), byte for byte, on every capture and board.
    for (board, elf) in &product_elfs {
        eprintln!("xtask: product firmware on {}", board.name);
        let extra = firmware_host_args(board.target, BankChoice::Product);
        for capture in &captures {
            equivalence(board, elf, capture, &extra)?;
        }
    }
    // The tuned product firmware prints the CSV of the command the gains file names (`nav440
    // estimate FILE --bank product --gains product_fig5.toml --hold H`), byte for byte, on the
    // bundled capture and the tumble.
    let gains = root().join(TUNED_GAINS);
    let gains_text = read_file(&gains).map(|b| String::from_utf8_lossy(&b).into_owned())?;
    let hold = gains_text
        .split_whitespace()
        .skip_while(|w| *w != "--hold")
        .nth(1)
        .ok_or_else(|| format!("{TUNED_GAINS} names no --hold in its header"))?
        .to_owned();
    let gains = gains.display().to_string();
    for (board, elf) in &tuned_elfs {
        eprintln!("xtask: tuned product firmware on {}", board.name);
        let mut extra = firmware_host_args(board.target, BankChoice::Product);
        extra.extend(["--gains", &gains, "--hold", &hold]);
        for capture in [&bundled, &tumble] {
            equivalence(board, elf, capture, &extra)?;
        }
    }
    // The small-MCU firmware prints the CSV of `nav440 estimate --axis yaw` (`--fixed` on
    // thumbv6m), byte for byte, on every capture.
    for (board, label, elf) in &small_elfs {
        eprintln!("xtask: small-MCU firmware: {label}");
        for capture in &captures {
            equivalence(board, elf, capture, small_host_args(board.target))?;
        }
    }
    // The noise-adaptive firmware prints the CSV of `nav440 estimate --gains
    // schedule_fig5.toml`, byte for byte: on a capture whose yaw noise switches from 0.01 to
    // 0.5 deg^2 at 10 s (the gains follow it: several retunes) and on the noise-free bundled
    // capture (the lowest level).
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
    for (board, elf) in &adaptive_elfs {
        let args = adaptive_host_args(board.target);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (c, csv) = equivalence_csv(board, elf, &switch, &args)?;
        // The gains followed the noise: the initial level, then 0.01 deg^2, then 0.5.
        let retunes = counter(&c, "yaw_retunes").unwrap_or(0);
        if retunes < 2 {
            return Err(format!(
                "the adaptive firmware on {} retuned its yaw gains {retunes} times on a noise switch (expected at least 2)",
                board.name
            ));
        }
        eprintln!(
            "xtask: OK: adaptive gains on {}: yaw_retunes={retunes}",
            board.name
        );
        // Identical is not enough: gains at the edge of the Euler step saturate the
        // fixed-point AVE at 2.1e9 deg/s on both sides alike (docs/ADAPTIVE-GAINS.md, "Gains at
        // the edge of the Euler step"). The capture's peak rate is 265 deg/s.
        let peak = peak_velocity(&csv, "yaw_")?;
        if peak >= 1000.0 {
            return Err(format!(
                "the adaptive firmware on {} printed a yaw velocity estimate of {peak} deg/s on the noise switch (peak rate 265 deg/s)",
                board.name
            ));
        }
        eprintln!(
            "xtask: OK: adaptive gains on {}: yaw velocity estimates within {peak:.1} deg/s",
            board.name
        );
        equivalence(board, elf, &bundled, &args)?;
        // The schedule (tuned at 100 Hz) on the 20 Hz capture: the same CSV as the host, and
        // the firmware says it runs off its rate (only there: 0 on the 100 Hz captures).
        let c20 = equivalence(board, elf, &root().join(SPIN_20HZ), &args)?;
        for (cc, name, off) in [(&c, "the noise switch", 0), (&c20, SPIN_20HZ, 1)] {
            let got = counter(cc, "yaw_schedule_off_rate");
            if got != Some(off) {
                return Err(format!(
                    "the adaptive firmware on {} reported yaw_schedule_off_rate={got:?} on {name} (expected {off})",
                    board.name
                ));
            }
        }
        eprintln!(
            "xtask: OK: adaptive gains on {}: the 100 Hz schedule is reported off its rate on {SPIN_20HZ} only",
            board.name
        );
    }
    // Input without the length prefix is refused with exit status 1 (never a hang).
    let m4f_board = elfs[0].0;
    let raw = read_file(&bundled)?;
    let path = qemu::input_path(&work_dir()?, "noprefix");
    let r = qemu::run_uart(
        &m4f_board,
        &elfs[0].1,
        &path,
        raw.get(..4096).unwrap_or(&raw),
        Output::Capture,
        Duration::from_secs(60),
    );
    let _ = std::fs::remove_file(&path);
    match r {
        Err(e) if e.contains("N4LP") => {
            eprintln!("xtask: OK: input without the length prefix ends with exit status 1")
        }
        Err(e) => return Err(format!("unexpected failure of the no-prefix check: {e}")),
        Ok(_) => return Err("input without the length prefix was accepted".into()),
    }
    // The firmware against the simulated unit: boot, configure, stream, estimate, faults.
    ci_unit(None)?;
    // An hour of stream with one fault of each kind (`cargo xtask soak`; about 11 minutes of
    // emulation here, docs/RELIABILITY.md).
    super::soak::soak(CI_SOAK_HOURS, 1)?;
    // A panic ends the run with exit status 1 and its message.
    let panic_elf = build(m4f_board.target, &[], "panic_check")?;
    match qemu::run_plain(&m4f_board, &panic_elf, &[], Duration::from_secs(60)) {
        Err(e) if e.contains("firmware: panic") => {
            eprintln!("xtask: OK: a panic ends the firmware with exit status 1")
        }
        Err(e) => return Err(format!("unexpected failure of the panic check: {e}")),
        Ok(_) => return Err("the panic check firmware exited with status 0".into()),
    }
    // A hard-float image on the FPU-less board must fault and exit non-zero, not hang.
    let m4f = &elfs[0].1;
    let an385 = qemu::board("an385")?;
    match qemu::run_plain(&an385, m4f, &[], Duration::from_secs(60)) {
        Err(e) if e.contains("HardFault") => {
            eprintln!(
                "xtask: OK: hard-float image on the Cortex-M3 board ends with a HardFault exit"
            )
        }
        Err(e) => return Err(format!("unexpected failure of the fault check: {e}")),
        Ok(_) => return Err("hard-float image ran on the FPU-less board without a fault".into()),
    }
    bench(qemu::BOARDS[0], false, BankChoice::Paper)?;
    bench(qemu::BOARDS[2], false, BankChoice::Product)?;
    size()?;
    Ok(())
}
