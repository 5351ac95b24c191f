//! `cargo xtask bench`: instruction counts of the bench firmware on QEMU (`-icount`), the
//! estimated cycles and CPU share, and the goals they are checked against.

use super::build::{build, build_profile, SMALL_PROFILE};
use super::{BankChoice, BENCH_BIN, ONE_AXIS};
use crate::qemu::{self, Board};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Clock of the reference real target for the budget (STM32F405-class Cortex-M4F), Hz.
const REF_CLOCK_HZ: f64 = 168e6;
/// NAV440 output rate of the budget, Hz.
const SAMPLE_RATE_HZ: f64 = 100.0;
/// Assumed cycles per instruction of the reference target for the *estimated* cycle column
/// (Cortex-M4F: most ALU/FP ops 1 cycle, loads 2, taken branches 2-4, VDIV/VSQRT 14, zero
/// wait-state flash through the ART accelerator). Only an estimate: QEMU counts instructions.
const ASSUMED_CPI: f64 = 1.5;

/// Instructions per A2 frame of the product firmware's pipeline (three axes) on thumbv6m,
/// with the Euler reference rates.
const PRODUCT_PIPELINE_GOAL: f64 = 20_000.0;
/// The same without the reference (feature `no-reference`: the rows carry the body rates).
const PRODUCT_PIPELINE_NOREF_GOAL: f64 = 8_000.0;

/// The firmware's receive queue, bytes (`firmware_example::uart::RX_QUEUE_BYTES`).
const RX_QUEUE_BYTES: f64 = 511.0;

/// The time the firmware's receive queue covers while the pipeline builds its banks, s: A2
/// frames (30-byte payload and the frame's 7 bytes) at 100 Hz.
fn rx_queue_s() -> f64 {
    let payload = nav440_proto::PacketType::A2
        .output_payload_len()
        .unwrap_or(30);
    RX_QUEUE_BYTES / ((payload + nav440_proto::FRAME_OVERHEAD) as f64 * 100.0)
}
/// A small part's clock, Hz (the 48 MHz of a Cortex-M0+ such as the STM32C0, the G0 runs 64).
const SMALL_PART_HZ: f64 = 48e6;

/// One measurement line of the bench firmware: `instr<TAB>label<TAB>count<TAB>unit`.
pub(super) struct Measure {
    label: String,
    instr: f64,
    unit: String,
    /// `VSQRT.F32` executed per unit (14 cycles each on a Cortex-M4F).
    sqrt: f64,
}

/// Cycles of one `VSQRT.F32` on a Cortex-M4F (ARM Cortex-M4 TRM, FPU instruction timing).
const VSQRT_CYCLES: f64 = 14.0;

impl Measure {
    /// Estimated cycles on a Cortex-M4F: `ASSUMED_CPI` per instruction, `VSQRT_CYCLES` per
    /// square-root instruction.
    fn cycles(&self) -> f64 {
        (self.instr - self.sqrt) * ASSUMED_CPI + self.sqrt * VSQRT_CYCLES
    }
}

/// Measurements and `size_of` lines (label, bytes) printed by the bench firmware.
pub(super) type BenchOutput = (Vec<Measure>, Vec<(String, u64)>);

pub(super) fn run_bench(
    board: &Board,
    small: bool,
    bank: BankChoice,
) -> Result<BenchOutput, String> {
    run_built(board, &build_bench(board, small, bank)?)
}

/// Builds the bench image of `board` with `bank` (`small`: one axis, profile `small`).
fn build_bench(board: &Board, small: bool, bank: BankChoice) -> Result<PathBuf, String> {
    let mut features: Vec<&str> = bank.features().to_vec();
    if small {
        features.push(ONE_AXIS);
        build_profile(board.target, &features, BENCH_BIN, SMALL_PROFILE)
    } else {
        build(board.target, &features, BENCH_BIN)
    }
}

/// Runs a built bench image on `board`: its measurements and RAM lines.
fn run_built(board: &Board, elf: &Path) -> Result<BenchOutput, String> {
    let r = qemu::run_plain(
        board,
        elf,
        &["-icount", "shift=6"],
        Duration::from_secs(600),
    )?;
    let mut m = Vec::new();
    let mut ram = Vec::new();
    let mut sqrt: Vec<(String, f64)> = Vec::new();
    for l in r.stdout.lines() {
        // The bench's text lines share stdout with the binary defmt frames of the row
        // messages it measures: a line starts at its tag.
        let Some(start) = ["instr\t", "sqrt\t", "ram\t"]
            .iter()
            .filter_map(|tag| l.find(tag))
            .min()
        else {
            continue;
        };
        let l = &l[start..];
        let f: Vec<&str> = l.split('\t').collect();
        match f.as_slice() {
            ["instr", label, n, unit] => m.push(Measure {
                label: (*label).to_owned(),
                instr: n.parse().map_err(|_| format!("bad bench line `{l}`"))?,
                unit: (*unit).to_owned(),
                sqrt: 0.0,
            }),
            ["sqrt", label, n, _] => sqrt.push((
                (*label).to_owned(),
                n.parse().map_err(|_| format!("bad bench line `{l}`"))?,
            )),
            ["ram", label, n] => ram.push((
                (*label).to_owned(),
                n.parse().map_err(|_| format!("bad bench line `{l}`"))?,
            )),
            _ => {}
        }
    }
    if m.is_empty() {
        return Err(format!(
            "the bench firmware printed no measurement; stdout:\n{}\nstderr:\n{}",
            r.stdout, r.stderr
        ));
    }
    for x in &mut m {
        x.sqrt = sqrt
            .iter()
            .find(|(l, _)| *l == x.label)
            .map_or(0.0, |(_, n)| *n);
    }
    Ok((m, ram))
}

/// `cargo xtask bench`.
pub fn bench(board: Board, small: bool, bank: BankChoice) -> Result<(), String> {
    qemu::ensure_qemu()?;
    prepare(board, small, bank)?()
}

/// [`bench()`]'s build; the returned run (QEMU, then the report on stdout in one piece) can go
/// to `cargo xtask ci`'s job pool.
pub(super) fn prepare(
    board: Board,
    small: bool,
    bank: BankChoice,
) -> Result<impl FnOnce() -> Result<(), String> + Send + 'static, String> {
    let elf = build_bench(&board, small, bank)?;
    Ok(move || {
        let (m, _) = run_built(&board, &elf)?;
        let report = report(board, small, bank, &m);
        print!("{report}");
        let broken = guards(board, small, bank, &m);
        if broken.is_empty() {
            Ok(())
        } else {
            Err(format!("bench guards broken: {}", broken.join("; ")))
        }
    })
}

/// The speed goals that are met and so are guards: a run past one fails `cargo xtask bench`
/// (and CI, which runs the product bench on thumbv6m). The product pipeline on thumbv6m with
/// the Euler reference (<= [`PRODUCT_PIPELINE_GOAL`] per A2 frame) and without it (<=
/// [`PRODUCT_PIPELINE_NOREF_GOAL`]), and the output stage (<= [`OUTPUT_GOAL`] per sample,
/// every bench that measures it). Returns the broken ones.
fn guards(board: Board, small: bool, bank: BankChoice, m: &[Measure]) -> Vec<String> {
    let mut broken = Vec::new();
    let find = |prefix: &str| m.iter().find(|x| x.label.starts_with(prefix));
    if bank == BankChoice::FixedGains && board.target == "thumbv6m-none-eabi" && !small {
        for (label, what, guard) in [
            (
                "pipeline, A2 frame",
                "with the reference",
                PRODUCT_PIPELINE_GOAL,
            ),
            (
                "pipeline without reference",
                "without the reference",
                PRODUCT_PIPELINE_NOREF_GOAL,
            ),
        ] {
            match find(label) {
                Some(p) if p.instr > guard => broken.push(format!(
                    "product pipeline {what}, thumbv6m: {:.0} instructions per A2 frame, guard {guard:.0}",
                    p.instr
                )),
                Some(_) => {}
                None => broken.push(format!("no measurement of the pipeline {what}")),
            }
        }
    }
    if let Some(o) = find("defmt row message").filter(|o| o.instr > OUTPUT_GOAL) {
        broken.push(format!(
            "output stage: {:.0} instructions per sample, guard {OUTPUT_GOAL:.0}",
            o.instr
        ));
    }
    broken
}

/// The bench's report: its table and goals.
fn report(board: Board, small: bool, bank: BankChoice, m: &[Measure]) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
            out,
        "== instructions on QEMU {} ({}; firmware pipeline with the {} bank{}), counted with -icount shift=6 + SysTick ==",
        board.machine,
        board.about,
        bank.name(),
        if small {
            "; small-MCU build: one axis, opt-level \"z\""
        } else {
            ""
        }
    );
    let _ = writeln!(
            out,
        "cycle column: ESTIMATE = instructions x {ASSUMED_CPI} (assumed average CPI of a Cortex-M4F), VSQRT.F32 counted as {VSQRT_CYCLES} cycles;\nCPU share: estimated cycles x {SAMPLE_RATE_HZ} Hz / {} MHz; last column: instructions x {SAMPLE_RATE_HZ} Hz / {} MHz (CPI 1, a floor)",
        REF_CLOCK_HZ / 1e6,
        REF_CLOCK_HZ / 1e6
    );
    if board.target != "thumbv7em-none-eabihf" {
        let _ = writeln!(
            out,
            "note: fixed-point bank (estimators::Fx, Q31.32, integer multiply and square root of docs/FIXED-POINT.md) without FPU; the share columns still use the M4F budget (168 MHz, 100 Hz) as the yardstick"
        );
    }
    let _ = writeln!(
        out,
        "{:<44} {:>12} {:>14} {:>16} {:>16}",
        "what", "instructions", "cycles (est.)", "CPU share (est.)", "share at CPI 1"
    );
    let pct = |cycles: f64| cycles * SAMPLE_RATE_HZ / REF_CLOCK_HZ * 100.0;
    for x in m {
        let cyc = x.cycles();
        let (share, floor) = if x.unit == "sample" {
            (
                format!("{:.3} %", pct(cyc)),
                format!("{:.3} %", pct(x.instr)),
            )
        } else {
            ("-".to_owned(), "-".to_owned())
        };
        let label = format!("{} (per {})", x.label, x.unit);
        let _ = writeln!(
            out,
            "{label:<44} {:>12.1} {cyc:>14.0} {share:>16} {floor:>16}",
            x.instr
        );
    }
    if let Some(b) = m.iter().find(|x| x.label == "whole bank") {
        let share = pct(b.cycles());
        let _ = writeln!(
            out,
            "goal: whole bank < 2 % of a 168 MHz M4F at 100 Hz -> {share:.3} % estimated ({:.3} % at CPI 1): {}",
            pct(b.instr),
            if share < 2.0 { "met" } else { "NOT met (estimate)" }
        );
    }
    // The product firmware's pipeline on a Cortex-M0+: 20,000 instructions per A2 frame for
    // three axes is 4 % of a 48 MHz core at 100 Hz.
    if bank == BankChoice::FixedGains && board.target == "thumbv6m-none-eabi" && !small {
        for (label, what, goal) in [
            ("pipeline, A2 frame", "", PRODUCT_PIPELINE_GOAL),
            (
                "pipeline without reference",
                " without the Euler reference",
                PRODUCT_PIPELINE_NOREF_GOAL,
            ),
        ] {
            if let Some(p) = m.iter().find(|x| x.label.starts_with(label)) {
                let _ = writeln!(
                    out,
                    "goal: product pipeline{what} per A2 frame, three axes, thumbv6m <= {goal} instructions -> {:.0}: {}",
                    p.instr,
                    if p.instr <= goal { "met" } else { "NOT met" }
                );
            }
        }
    }
    // Building the three axes' banks after the warm-up (or a period change) stops the stream:
    // the receive queue must hold what arrives meanwhile, on a 48 MHz part at CPI 1.
    if bank == BankChoice::FixedGains && board.target == "thumbv6m-none-eabi" && !small {
        if let Some(b) = m.iter().find(|x| x.label.starts_with("bank construction")) {
            let queue_s = rx_queue_s();
            let goal = queue_s * SMALL_PART_HZ;
            let three = 3.0 * b.instr;
            let _ = writeln!(
                out,
                "goal: building the product banks of three axes, thumbv6m, within the {:.0} ms of A2 at 100 Hz that the receive queue holds, at 48 MHz and CPI 1: <= {goal:.0} instructions -> {three:.0}: {}",
                queue_s * 1e3,
                if three <= goal { "met" } else { "NOT met" }
            );
        }
    }
    // What the Euler reference costs: the pipeline with it minus the pipeline without it
    // (feature `no-reference`: the body rates).
    if let (Some(with), Some(without)) = (
        m.iter().find(|x| x.label.starts_with("pipeline, A2 frame")),
        m.iter()
            .find(|x| x.label.starts_with("pipeline without reference")),
    ) {
        let _ = writeln!(
            out,
            "reference: the pipeline per A2 frame takes {:.0} instructions with the Euler reference, {:.0} without (feature `no-reference`): {:.0} for the reference",
            with.instr,
            without.instr,
            with.instr - without.instr
        );
    }
    // The fixed-point bank (no FPU), one axis, per 100 Hz sample: (goal, baseline the goal
    // was set against, core).
    let fixed_goal = match board.target {
        "thumbv6m-none-eabi" => Some((250_000.0, 2_475_970.0, "Cortex-M0 (thumbv6m)")),
        "thumbv7m-none-eabi" => Some((40_000.0, 384_284.0, "Cortex-M3 (thumbv7m)")),
        _ => None,
    };
    if let (Some((goal, baseline, what)), Some(b)) =
        (fixed_goal, m.iter().find(|x| x.label == "whole bank"))
    {
        let _ = writeln!(
            out,
            "goal: whole fixed-point bank, one axis, {what}: <= {goal:.0} instructions per sample (baseline {baseline:.0}) -> {:.0} ({:.1}x fewer): {}",
            b.instr,
            baseline / b.instr,
            if b.instr <= goal { "met" } else { "NOT met" }
        );
    }
    // Three axes (roll, pitch, yaw), counted in instructions (CPI 1).
    for (label, goal, what) in [
        (
            "paper bank, 3 axes",
            33_600.0,
            "full paper bank on three axes <= 2 % of a 168 MHz M4F at CPI 1",
        ),
        (
            "product bank, 3 axes",
            500.0,
            "product bank (one velocity + one acceleration estimator per axis), three axes",
        ),
    ] {
        if let Some(b) = m.iter().find(|x| x.label == label) {
            let _ = writeln!(
                out,
                "goal: {what}: <= {goal:.0} instructions per sample -> {:.0}: {}",
                b.instr,
                if b.instr <= goal { "met" } else { "NOT met" }
            );
        }
    }
    if let Some(b) = m.iter().find(|x| x.label.starts_with("boot sequence")) {
        let _ = writeln!(
            out,
            "boot: {:.0} instructions from power-up configuration to confirmed A2 100 Hz 57600 Bd (ping, GF, SF baud, ping, SF type/rate, GF; replies at once, no waiting): about {:.2} ms of a 168 MHz M4F (estimate), once per start",
            b.instr,
            b.cycles() / REF_CLOCK_HZ * 1e3
        );
    }
    if let Some(t) = m.iter().find(|x| x.label.starts_with("transmit")) {
        let _ = writeln!(
            out,
            "transmit: {:.1} instructions per byte through embedded_io::Write (a 12-byte SF request: {:.0})",
            t.instr,
            t.instr * 12.0
        );
    }
    if let Some(p) = m.iter().find(|x| x.label == "parser") {
        let _ = writeln!(
            out,
            "goal: parser < 30 instructions/byte -> {:.1}: {}",
            p.instr,
            if p.instr < 30.0 { "met" } else { "NOT met" }
        );
    }
    // The output stage (one defmt row message per sample).
    if let Some(o) = m.iter().find(|x| x.label.starts_with("defmt row message")) {
        let _ = writeln!(
            out,
            "goal: output stage <= {OUTPUT_GOAL:.0} instructions per sample -> {:.0}: {}",
            o.instr,
            if o.instr <= OUTPUT_GOAL {
                "met"
            } else {
                "NOT met"
            }
        );
    }
    out
}

/// Goal: instructions of the output stage per sample.
const OUTPUT_GOAL: f64 = 500.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vsqrt_cycles_enter_the_estimate() {
        let m = Measure {
            label: "x".into(),
            instr: 1000.0,
            unit: "sample".into(),
            sqrt: 100.0,
        };
        assert_eq!(m.cycles(), 900.0 * ASSUMED_CPI + 100.0 * VSQRT_CYCLES);
    }
}
