//! The RAM of a board no emulator runs, from its ELF and an emulated twin
//! (`nav440_boards::Twin`): the board's image links its static RAM (`.data` + `.bss`, read from
//! its ELF); the stack is the high-water mark of the same image built for a QEMU board of the
//! same core, painted and measured through a boot and a stream against `nav440 sim` and
//! through a replay. Static RAM + stack + [`STACK_MARGIN`] must fit the board's RAM, and the
//! board's frames may add at most [`STACK_MARGIN`] to the twin's (compared from the ELFs).

use super::ci::spawn_equivalence;
use super::nav440_cli::firmware_host_args;
use super::qemu_run::stack_within;
use super::size::flash_ram;
use super::unit_cases::{spawn_stack_case, UNIT_STEP};
use super::{
    build::build_profile, root, BankChoice, FIXED_GAINS, FW_BIN, NO_REFERENCE, NO_REFERENCE_ARG,
    PRODUCT,
};
use crate::pool::Pool;
use crate::qemu;
use std::path::Path;

/// Bytes kept free beyond the twin's high-water mark, for the frames in which the board's
/// code and the twin's differ. CI checks it from the two ELFs ([`crate::frames`]): the sum of
/// what each of the board's frames adds (larger than the twin's, or the board's own) must
/// not exceed it. On the NUCLEO-G031K8 that sum is 440 B: the boot's frame 88 B larger,
/// `main`'s 16 B, a stream closure's 96 B, the RTT and interrupt code's own frames.
pub(super) const STACK_MARGIN: u64 = 512;

/// The capture the twin replays and the simulated unit streams: A2 (the type the product
/// firmware configures, and the only one a `small-part` image decodes), with corrupted frames.
const TWIN_CAPTURE: &str = "host-tests/data/fig5_a2_100hz_corrupt.bin";

/// Builds the twin of `board`'s `image` (whose ELF is `elf`, already built and map-checked)
/// and queues its two runs in `pool` (step [`UNIT_STEP`]): each must print the CSV of `nav440
/// estimate` with the image's bank and reference option, and reach at most the stack the
/// board's RAM leaves.
pub(super) fn stack_twin_ci(
    pool: &Pool,
    board: &nav440_boards::Board,
    elf: &Path,
    features: &[&str],
    twin: nav440_boards::Twin,
) -> Result<(), String> {
    let (_, static_ram) = flash_ram(elf)?;
    let ram = board.ram.kib * 1024;
    let limit = ram
        .checked_sub(static_ram + STACK_MARGIN)
        .ok_or_else(|| {
            format!(
                "{}: static RAM {static_ram} B and the {STACK_MARGIN} B margin exceed its {ram} B of RAM",
                board.name
            )
        })?;
    let qboard = qemu::board(twin.qemu_board)?;
    let mut twin_features: Vec<&str> = features.to_vec();
    twin_features.extend(twin.features);
    let twin_elf = build_profile(
        qboard.target,
        &twin_features,
        FW_BIN,
        board.ci_image.profile,
    )?;
    // The board's own frames against the twin's, from the two ELFs (both thumbv6m).
    if board.targets.first() != Some(&"thumbv6m-none-eabi") || qboard.target != "thumbv6m-none-eabi"
    {
        return Err(format!(
            "{}: a stack twin is compared by its ARMv6-M prologues, and {:?} (twin {}: {}) is not thumbv6m",
            board.name, board.targets, qboard.name, qboard.target
        ));
    }
    let (excess, terms) = crate::frames::excess_over(
        &crate::frames::thumb_frames(elf)?,
        &crate::frames::thumb_frames(&twin_elf)?,
    );
    let largest: Vec<String> = terms
        .iter()
        .take(3)
        .map(|(n, f)| format!("{f} +{n} B"))
        .collect();
    if excess > STACK_MARGIN {
        return Err(format!(
            "{}: its frames exceed its twin's by up to {excess} B (largest: {}), more than the {STACK_MARGIN} B kept free",
            board.name,
            largest.join(", ")
        ));
    }
    eprintln!(
        "xtask: OK: {}: its frames exceed its twin's by {excess} B at most (the larger frames and its own functions' summed; largest: {}), within the {STACK_MARGIN} B kept free",
        board.name,
        largest.join(", ")
    );
    let bank = if features.contains(&FIXED_GAINS) {
        BankChoice::FixedGains
    } else if features.contains(&PRODUCT) {
        BankChoice::Product
    } else {
        BankChoice::Paper
    };
    let mut host = firmware_host_args(qboard.target, bank);
    if features.contains(&NO_REFERENCE) {
        host.push(NO_REFERENCE_ARG);
    }
    let capture = root().join(TWIN_CAPTURE);
    eprintln!(
        "xtask: {}: static RAM {static_ram} B (its ELF); its stack may reach {limit} B of its {ram} B ({STACK_MARGIN} B kept free), measured on its twin {} on {} (features {})",
        board.name,
        twin_elf.display(),
        qboard.name,
        twin_features.join(",")
    );
    // Boot, configuration and stream.
    spawn_stack_case(
        pool,
        UNIT_STEP,
        qboard,
        &twin_elf,
        &capture,
        &host,
        ("unit was at 38400 Bd", limit),
    )?;
    // A replay (the banks built at the measured period, every row).
    let what = format!("{}'s twin, replay of {}", board.name, capture.display());
    spawn_equivalence(
        pool,
        UNIT_STEP,
        qboard,
        &twin_elf,
        &capture,
        &host,
        move |c| {
            let p = stack_within(c, limit, &what)?;
            eprintln!("xtask: OK: {what}: stack high-water mark {p} B, at most {limit} B");
            Ok(())
        },
    );
    Ok(())
}
