//! `cargo xtask size`: flash and RAM of the firmware images (llvm-size, the stack high-water
//! mark under QEMU), the footprint goals, RAM per estimator, and flash per component.

use super::bench::run_bench;
use super::build::{build, build_profile, build_small, small_boards, SMALL_PROFILE};
use super::qemu_run::{counter, counters, run_capture};
use super::unit_cases::unit_stack_peak;
use super::{root, BankChoice, FIXED_GAINS, FW_BIN, NO_REFERENCE, ONE_AXIS, PRODUCT};
use crate::qemu::{self, Output};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Footprint goals, bytes: (image, flash, RAM if any). The product firmware (boot, driver,
/// pipeline, defmt, three axes) fits a 64 KiB Cortex-M0+ part with room for an application;
/// the paper bank on the M4F fits half of a 96 KiB budget.
const FOOTPRINT_GOALS: &[(&str, u64, Option<u64>)] = &[
    ("product-thumbv6m-3axis-small", 16 * 1024, Some(4 * 1024)),
    (
        "product-thumbv6m-3axis-small-noref",
        16 * 1024,
        Some(4 * 1024),
    ),
    ("product-thumbv6m-3axis", 16 * 1024, Some(4 * 1024)),
    ("product-thumbv7em-3axis-small", 16 * 1024, None),
    ("product-thumbv7em-3axis", 16 * 1024, None),
    ("paper-thumbv7em-3axis", 48 * 1024, None),
];

/// The component (crate, or a group) a demangled symbol name belongs to.
fn component(name: &str) -> String {
    // Symbols llvm-nm leaves in the legacy escaped form (`_$LT$T$u20$as$u20$a..b$GT$::f`):
    // unescape the characters that matter here first.
    let name = name
        .replace("_$LT$", "<")
        .replace("$LT$", "<")
        .replace("$RF$", "&")
        .replace("$u20$", " ")
        .replace("..", "::");
    // `<T as Trait>::f` and `<T>::f` belong to T's crate; `_ZN..` names are already demangled.
    let n = name.trim_start_matches('<').trim_start_matches('&');
    let n = n.strip_prefix("mut ").unwrap_or(n);
    let krate = n
        .split("::")
        .next()
        .unwrap_or(n)
        .split(['<', ' ', '('])
        .next()
        .unwrap_or(n);
    let group = match krate {
        "core" | "alloc" => "core (fmt, panics, slices)",
        "compiler_builtins" => "compiler_builtins (soft float, mem*)",
        k if k.starts_with("__aeabi") || k.starts_with("__") => {
            "compiler_builtins (soft float, mem*)"
        }
        k if k.starts_with("defmt") || k.starts_with("_defmt") => "defmt + transport",
        "firmware_example" | "main" | "Reset" | "HardFault" | "DefaultHandler" => {
            "firmware_example"
        }
        "estimators" => "estimators (bank)",
        "nav440_proto" => "nav440_proto",
        "nav440_pipeline" => "nav440_pipeline",
        "libm" | "micromath" => "libm",
        k if k.starts_with("cortex_m") => "cortex_m, cortex_m_rt",
        "heapless" => "heapless",
        k if k.starts_with("stm32f4") || k == "fugit" => "stm32f4xx_hal",
        k if k.starts_with("embassy") => "embassy",
        k if k.starts_with("semihosting") => "defmt + transport",
        _ => "other",
    };
    group.to_owned()
}

/// `cargo xtask size --components`: flash bytes per component of the release firmware of each
/// target and of the small-MCU builds ([`small_boards`]), from `llvm-nm --print-size -C` (code, read-only data and initialised data symbols;
/// `unattributed` is text + data minus the symbols' sum: alignment, anonymous constants, the
/// vector table).
pub fn size_components() -> Result<(), String> {
    let size_tool = llvm_size()?;
    let nm = size_tool.with_file_name("llvm-nm");
    let mut cols: Vec<(String, std::collections::BTreeMap<String, u64>, u64)> = Vec::new();
    let mut elfs: Vec<(String, PathBuf)> = Vec::new();
    for target in crate::THUMB_TARGETS {
        elfs.push(((*target).to_owned(), build(target, &[], FW_BIN)?));
    }
    for (board, label) in small_boards() {
        elfs.push((label.to_owned(), build_small(board.target, FW_BIN)?));
    }
    for (board, _) in small_boards() {
        elfs.push((
            image_name("product", board.target, 3, "-small"),
            build_profile(
                board.target,
                BankChoice::FixedGains.features(),
                FW_BIN,
                SMALL_PROFILE,
            )?,
        ));
    }
    elfs.push((
        image_name("product", NOREF_BOARD.target, 3, NOREF_SUFFIX),
        build_noref()?,
    ));
    for (target, elf) in elfs {
        let (t, d, _) = sizes(&size_tool, &elf)?;
        let o = Command::new(&nm)
            .args(["--print-size", "-C", "--size-sort"])
            .arg(&elf)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", nm.display()))?;
        let mut per: std::collections::BTreeMap<String, u64> = std::collections::BTreeMap::new();
        let mut sum = 0;
        for l in String::from_utf8_lossy(&o.stdout).lines() {
            // `ADDR SIZE TYPE NAME`
            let mut it = l.splitn(4, ' ');
            let (Some(_), Some(size), Some(ty), Some(name)) =
                (it.next(), it.next(), it.next(), it.next())
            else {
                continue;
            };
            if !matches!(ty, "t" | "T" | "r" | "R" | "d" | "D" | "W" | "w") {
                continue;
            }
            let Ok(size) = u64::from_str_radix(size, 16) else {
                continue;
            };
            *per.entry(component(name)).or_default() += size;
            sum += size;
        }
        per.insert("unattributed".into(), (t + d).saturating_sub(sum));
        cols.push((target, per, t + d));
    }
    println!("== flash per component (llvm-nm symbol sizes, {FW_BIN}: release per target, then the small-MCU builds), bytes ==");
    print!("{:<38}", "component");
    for (t, _, _) in &cols {
        print!(" {t:>24}");
    }
    println!();
    let mut names: Vec<String> = cols
        .iter()
        .flat_map(|(_, p, _)| p.keys().cloned())
        .collect();
    names.sort();
    names.dedup();
    // Largest first (by the first target).
    names.sort_by_key(|n| std::cmp::Reverse(cols[0].1.get(n).copied().unwrap_or(0)));
    for n in &names {
        print!("{n:<38}");
        for (_, p, _) in &cols {
            print!(" {:>24}", p.get(n).copied().unwrap_or(0));
        }
        println!();
    }
    print!("{:<38}", "total flash (text + data)");
    for (_, _, total) in &cols {
        print!(" {total:>24}");
    }
    println!();
    Ok(())
}

fn llvm_size() -> Result<PathBuf, String> {
    llvm_tool("llvm-size")
}

/// The board of the product image without the Euler reference (thumbv6m on the mps2-an385).
pub(super) const NOREF_BOARD: qemu::Board = qemu::BOARDS[2];

/// The image name suffix of the product image without the Euler reference.
const NOREF_SUFFIX: &str = "-small-noref";

/// Builds the product image without the Euler reference (features `fixed-gains`,
/// `no-reference`; thumbv6m, profile `small`): the one `size` lists and `ci` compares with
/// `nav440 estimate --no-reference`.
pub(super) fn build_noref() -> Result<PathBuf, String> {
    build_profile(
        NOREF_BOARD.target,
        &[PRODUCT, FIXED_GAINS, NO_REFERENCE],
        FW_BIN,
        SMALL_PROFILE,
    )
}

/// The Euler kinematics' symbols (`nav440_pipeline::euler`'s `euler_rates_deg` and
/// `sin_cos_deg`, `idsp`'s CORDIC, `libm`'s `sincosf`) among the symbols of `elf`.
pub(super) fn euler_symbols(elf: &Path) -> Result<Vec<String>, String> {
    crate::elf::symbols_containing(elf, &["euler_rates_deg", "sin_cos_deg", "idsp", "sincosf"])
}

/// Parts of the names of the soft-float routines (`compiler_builtins`' `f32`/`f64` arithmetic,
/// comparisons and conversions, by their AEABI names and their own) and of `libm`.
const SOFT_FLOAT: &[&str] = &[
    "__aeabi_f",
    "__aeabi_d",
    "__aeabi_i2f",
    "__aeabi_ui2f",
    "__aeabi_l2f",
    "__aeabi_ul2f",
    "__aeabi_i2d",
    "__aeabi_ui2d",
    "__aeabi_l2d",
    "__aeabi_ul2d",
    "compiler_builtins5float",
    "compiler_builtins::float",
    "libm",
];

/// The soft-float and `libm` symbols among the symbols of `elf` (none in the product image
/// without the Euler reference: its path from the packet's integers to the row is
/// float-free).
pub(super) fn soft_float_symbols(elf: &Path) -> Result<Vec<String>, String> {
    crate::elf::symbols_containing(elf, SOFT_FLOAT)
}

/// A tool of rustup's `llvm-tools` component (pinned in rust-toolchain.toml).
fn llvm_tool(name: &str) -> Result<PathBuf, String> {
    let out = |args: &[&str]| -> Result<String, String> {
        let o = Command::new("rustc")
            .args(args)
            .output()
            .map_err(|e| format!("cannot run rustc: {e}"))?;
        Ok(String::from_utf8_lossy(&o.stdout).into_owned())
    };
    let sysroot = out(&["--print", "sysroot"])?;
    let host = out(&["-vV"])?
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_owned))
        .ok_or("cannot find the host triple in `rustc -vV`")?;
    let p = Path::new(sysroot.trim())
        .join("lib/rustlib")
        .join(host)
        .join("bin")
        .join(name);
    if p.is_file() {
        Ok(p)
    } else {
        Err(format!(
            "{} missing: run `rustup component add llvm-tools`",
            p.display()
        ))
    }
}

/// (flash, static RAM) of an ELF, bytes: text + data, data + bss (`llvm-size`).
pub(super) fn flash_ram(elf: &Path) -> Result<(u64, u64), String> {
    let (t, d, b) = sizes(&llvm_size()?, elf)?;
    Ok((t + d, d + b))
}

/// (text, data, bss) of an ELF from `llvm-size` (Berkeley format).
fn sizes(tool: &Path, elf: &Path) -> Result<(u64, u64, u64), String> {
    let o = Command::new(tool)
        .arg(elf)
        .output()
        .map_err(|e| format!("cannot run llvm-size: {e}"))?;
    let text = String::from_utf8_lossy(&o.stdout);
    let nums: Vec<u64> = text
        .lines()
        .nth(1)
        .ok_or("unexpected llvm-size output")?
        .split_whitespace()
        .take(3)
        .filter_map(|v| v.parse().ok())
        .collect();
    match nums.as_slice() {
        [t, d, b] => Ok((*t, *d, *b)),
        _ => Err(format!("unexpected llvm-size output:\n{text}")),
    }
}

/// `cargo xtask size`.
pub fn size() -> Result<(), String> {
    let tool = llvm_size()?;
    // (image name, board it runs on, ELF, flash, static RAM)
    let mut builds: Vec<(String, qemu::Board, PathBuf, u64, u64)> = Vec::new();
    for board in qemu::BOARDS {
        let elf = build(board.target, &[], FW_BIN)?;
        builds.push((image_name("paper", board.target, 3, ""), *board, elf, 0, 0));
    }
    // One axis (feature `one-axis`) on the Cortex-M0 ISA, release profile.
    builds.push((
        image_name("paper", "thumbv6m-none-eabi", 1, ""),
        qemu::BOARDS[2],
        build("thumbv6m-none-eabi", &[ONE_AXIS], FW_BIN)?,
        0,
        0,
    ));
    // The small-MCU firmware: one axis, cargo profile `small` (opt-level "z").
    for (board, _) in small_boards() {
        builds.push((
            image_name("paper", board.target, 1, "-small"),
            board,
            build_small(board.target, FW_BIN)?,
            0,
            0,
        ));
    }
    // The product firmware (three axes), release and `small`.
    for board in qemu::BOARDS {
        let elf = build(board.target, BankChoice::FixedGains.features(), FW_BIN)?;
        builds.push((
            image_name("product", board.target, 3, ""),
            *board,
            elf,
            0,
            0,
        ));
    }
    for (board, _) in small_boards() {
        let elf = build_profile(
            board.target,
            BankChoice::FixedGains.features(),
            FW_BIN,
            SMALL_PROFILE,
        )?;
        builds.push((
            image_name("product", board.target, 3, "-small"),
            board,
            elf,
            0,
            0,
        ));
    }
    // The product firmware without the Euler reference (feature `no-reference`), thumbv6m,
    // `small`.
    builds.push((
        image_name("product", NOREF_BOARD.target, 3, NOREF_SUFFIX),
        NOREF_BOARD,
        build_noref()?,
        0,
        0,
    ));
    println!("== firmware size (llvm-size, {FW_BIN}; release profile unless `small`; `-noref`: feature `no-reference`) ==");
    println!(
        "{:<34} {:>9} {:>7} {:>7} {:>13} {:>15}",
        "image", "text", "data", "bss", "flash (t+d)", "static RAM (d+b)"
    );
    for (label, _, elf, flash, ram) in &mut builds {
        let (t, d, b) = sizes(&tool, elf)?;
        println!(
            "{label:<34} {t:>9} {d:>7} {b:>7} {:>13} {:>15}",
            t + d,
            d + b
        );
        *flash = t + d;
        *ram = d + b;
    }
    println!(
        "(the bank, parser and buffers live on the stack of `main`: see the stack peak below)"
    );
    let mut peaks: Vec<Option<u64>> = vec![None; builds.len()];
    if qemu::qemu_available() {
        let capture = root().join("host-tests/data/fig5_a2_100hz_corrupt.bin");
        if let Ok(bytes) = std::fs::read(&capture) {
            for ((label, board, elf, _, _), peak) in builds.iter().zip(&mut peaks) {
                let r = run_capture(board, elf, &bytes, Output::Capture)?;
                let c = counters(&r.stderr);
                *peak = counter(&c, "stack_peak");
                if let Some(p) = peak {
                    println!(
                        "stack high-water mark of {label} on {}: {p} B (painted stack, run of {})",
                        board.name,
                        capture.display()
                    );
                }
                // The images with a RAM goal also through a boot and a stream (the simulated
                // unit): the stream loop's frame is deeper than the replay's. The deeper counts.
                let ram_goal = FOOTPRINT_GOALS
                    .iter()
                    .any(|(image, _, ram)| image == label && ram.is_some());
                if ram_goal {
                    let unit = unit_stack_peak(board, elf, &capture)?;
                    println!(
                        "stack high-water mark of {label} on {}: {unit} B (painted stack, boot and stream of {} from `nav440 sim`)",
                        board.name,
                        capture.display()
                    );
                    *peak = Some(peak.map_or(unit, |p| p.max(unit)));
                }
            }
        }
    }
    // One line per image (bytes): flash = text + data, ram = data + bss + stack high-water
    // mark (the deeper of the replay and, for the images with a RAM goal, the boot and stream;
    // `?` without QEMU).
    for ((label, _, _, flash, ram), peak) in builds.iter().zip(&peaks) {
        match peak {
            Some(p) => println!("size: {label} flash={flash} ram={} stack={p}", ram + p),
            None => println!("size: {label} flash={flash} ram=? stack=?"),
        }
    }
    println!();
    println!(
        "== footprint goals (flash = text + data; RAM = data + bss + stack high-water mark) =="
    );
    for (image, flash_goal, ram_goal) in FOOTPRINT_GOALS {
        let Some(((label, _, _, flash, ram), peak)) =
            builds.iter().zip(&peaks).find(|((l, ..), _)| l == image)
        else {
            continue;
        };
        println!(
            "flash <= {flash_goal} B: {label}: {flash} B: {}",
            if flash <= flash_goal {
                "met"
            } else {
                "NOT met"
            }
        );
        if let Some(goal) = ram_goal {
            match peak {
                Some(p) => println!(
                    "RAM <= {goal} B: {label}: {ram} + {p} = {} B: {}",
                    ram + p,
                    if ram + p <= *goal { "met" } else { "NOT met" }
                ),
                None => println!("RAM goal of {label}: no stack measurement (QEMU missing)"),
            }
        }
    }
    // The float-free product image (CI fails it when it links any).
    for (label, _, elf, _, _) in builds.iter().filter(|(l, ..)| l.ends_with(NOREF_SUFFIX)) {
        let float = soft_float_symbols(elf)?;
        println!(
            "no floating point: {label}: {} soft-float or libm symbols: {}",
            float.len(),
            if float.is_empty() { "met" } else { "NOT met" }
        );
    }
    if qemu::qemu_available() {
        let (_, ram_f32) = run_bench(&qemu::BOARDS[0], false, BankChoice::Paper)?;
        let (_, ram_fx) = run_bench(&qemu::BOARDS[1], false, BankChoice::Paper)?;
        println!();
        println!("== RAM per estimator (core::mem::size_of of the state) ==");
        println!("{:<40} {:>14} {:>16}", "", "f32 (v7em)", "Fx Q31.32 (v7m)");
        for (label, n) in &ram_f32 {
            let fx = ram_fx
                .iter()
                .find(|(l, _)| l == label)
                .map_or("?".to_owned(), |(_, v)| format!("{v} B"));
            println!("{label:<40} {:>14} {fx:>16}", format!("{n} B"));
        }
    } else {
        println!("(RAM per estimator needs qemu-system-arm: run `cargo xtask bench` after installing it)");
    }
    println!();
    size_components()?;
    Ok(())
}

/// The name of a firmware image in `cargo xtask size`: bank, target (`thumbv7em`, `thumbv7m`,
/// `thumbv6m`), axes, e.g. `product-thumbv6m-3axis`; `suffix` marks a profile (`-small`).
fn image_name(bank: &str, target: &str, axes: usize, suffix: &str) -> String {
    let isa = target.split('-').next().unwrap_or(target);
    format!("{bank}-{isa}-{axes}axis{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_names_say_bank_target_and_axes() {
        assert_eq!(
            image_name("product", "thumbv6m-none-eabi", 3, ""),
            "product-thumbv6m-3axis"
        );
        assert_eq!(
            image_name("paper", "thumbv7em-none-eabihf", 1, "-small"),
            "paper-thumbv7em-1axis-small"
        );
        assert_eq!(
            image_name("product", NOREF_BOARD.target, 3, NOREF_SUFFIX),
            "product-thumbv6m-3axis-small-noref"
        );
    }
}
