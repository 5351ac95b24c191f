//! Cargo builds and lints of the firmware images.

use super::{target_dir, work_dir, FW, ONE_AXIS};
use crate::cargo;
use crate::qemu;
use std::path::PathBuf;

/// Builds the firmware binary `bin` for `target` (release) and returns the path of its copy.
pub(super) fn build(target: &str, features: &[&str], bin: &str) -> Result<PathBuf, String> {
    build_profile(target, features, bin, "release")
}

/// The cargo profile of the small-MCU firmware (`Cargo.toml`: release with `opt-level = "z"`).
pub(super) const SMALL_PROFILE: &str = "small";

/// Builds `bin` as the small-MCU firmware for `target`: yaw only (feature `one-axis`), cargo
/// profile [`SMALL_PROFILE`].
pub(super) fn build_small(target: &str, bin: &str) -> Result<PathBuf, String> {
    build_profile(target, &[ONE_AXIS], bin, SMALL_PROFILE)
}

/// The small-MCU builds `cargo xtask size` and `ci` measure and check: (board, label).
pub(super) fn small_boards() -> [(qemu::Board, &'static str); 2] {
    [
        (qemu::BOARDS[0], "thumbv7em small (yaw, z)"),
        (qemu::BOARDS[2], "thumbv6m small (yaw, z)"),
    ]
}

/// The boards the `adaptive-gains` firmware is checked on: the M4F (f32) and thumbv6m (`Fx`).
pub(super) fn adaptive_boards() -> [qemu::Board; 2] {
    [qemu::BOARDS[0], qemu::BOARDS[2]]
}

/// Builds the firmware binary `bin` for `target` with the cargo `profile` and returns the path of
/// its copy.
pub(super) fn build_profile(
    target: &str,
    features: &[&str],
    bin: &str,
    profile: &str,
) -> Result<PathBuf, String> {
    let mut copies = build_bins(target, features, &[bin], profile)?;
    copies.pop().ok_or_else(|| format!("{bin} not built"))
}

/// Builds the firmware binaries `bins` for `target` with the cargo `profile` in one cargo run
/// (their fat-LTO links then go on in parallel) and returns the paths of their copies, in order.
pub(super) fn build_bins(
    target: &str,
    features: &[&str],
    bins: &[&str],
    profile: &str,
) -> Result<Vec<PathBuf>, String> {
    let feats = features.join(",");
    let mut args = vec!["build", "-p", FW, "--target", target, "--profile", profile];
    // Only the binaries asked for: each one is a fat-LTO link, and the lints
    // (`clippy_firmware`, `--bins`) already check every binary of each configuration.
    for bin in bins {
        args.extend(["--bin", bin]);
    }
    if !feats.is_empty() {
        args.extend(["--features", &feats]);
    }
    cargo(&args)?;
    // Builds with other features overwrite cargo's output: keep a copy per configuration.
    let mut tag = if feats.is_empty() {
        "default".to_owned()
    } else {
        feats.replace(',', "+")
    };
    if profile != "release" {
        tag = format!("{tag}-{profile}");
    }
    bins.iter()
        .map(|bin| {
            let elf = target_dir().join(target).join(profile).join(bin);
            if !elf.is_file() {
                return Err(format!("built firmware not found at {}", elf.display()));
            }
            let copy = work_dir()?.join(format!("{bin}-{target}-{tag}.elf"));
            std::fs::copy(&elf, &copy)
                .map_err(|e| format!("cannot copy {} to {}: {e}", elf.display(), copy.display()))?;
            Ok(copy)
        })
        .collect()
}

/// `cargo clippy -D warnings` on the firmware's binaries for `target`, with `feature`, in the
/// `release` profile of the images: the host-built build scripts and procedural macros are
/// then those of the image builds, compiled once for both.
pub(super) fn clippy_firmware(target: &str, feature: Option<&str>) -> Result<(), String> {
    let mut args = vec![
        "clippy",
        "-p",
        FW,
        "--target",
        target,
        "--bins",
        "--release",
    ];
    if let Some(f) = feature {
        args.extend(["--features", f]);
    }
    args.extend(["--", "-D", "warnings"]);
    cargo(&args)
}
