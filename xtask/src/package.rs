//! The libraries as users get them: their examples run, their declared minimum supported Rust
//! version checked with that very toolchain, and `cargo publish --dry-run` of each.

use crate::firmware::NAV440_PROFILE;
use crate::{cargo, run};
use std::path::Path;
use std::process::Command;

/// Runs from the workspace root (relative paths below), wherever `cargo xtask` was called.
fn to_root() -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("xtask lives in the workspace")?;
    std::env::set_current_dir(root).map_err(|e| format!("cannot enter {}: {e}", root.display()))
}

/// The publishable libraries: (directory of the `Cargo.toml`, package name). The estimators'
/// package is `velocity-estimators` (`estimators` is taken on crates.io); its library keeps
/// the name `estimators`.
pub const LIBRARIES: &[(&str, &str)] = &[
    ("nav440-proto", "nav440-proto"),
    ("estimators", "velocity-estimators"),
    ("pipeline", "nav440-pipeline"),
];

/// `cargo run --example example -p package -- args`, in the profile of the host tests, whose
/// build it shares.
fn run_example(package: &str, example: &str, args: &[&str]) -> Result<(), String> {
    let mut all = vec![
        "run",
        "-q",
        "--profile",
        NAV440_PROFILE,
        "-p",
        package,
        "--example",
        example,
        "--",
    ];
    all.extend(args);
    cargo(&all)
}

/// Runs every example of the libraries (each checks its own result and exits non-zero on a
/// failure), then `cargo publish --dry-run` of the three libraries together (`--allow-dirty`:
/// CI's checkout may hold build products; the dry run packages, verifies that each package
/// builds on its own with its registry dependencies, and uploads nothing).
pub fn package() -> Result<(), String> {
    to_root()?;
    const CAPTURE: &str = "host-tests/data/fig5_a2_100hz.bin";
    run_example("velocity-estimators", "sampled_signal", &[])?;
    run_example("nav440-proto", "configure_unit", &[])?;
    run_example("nav440-proto", "parse_capture", &[CAPTURE])?;
    // The driver over embedded-io 0.6 ports (feature `embedded-io-06`), on the host and,
    // linted, on the Cortex-M4F target.
    cargo(&[
        "test",
        "--profile",
        NAV440_PROFILE,
        "-p",
        "nav440-proto",
        "--features",
        "embedded-io-06",
        "--test",
        "io06",
    ])?;
    cargo(&[
        "clippy",
        "-p",
        "nav440-proto",
        "--features",
        "embedded-io-06",
        "--target",
        "thumbv7em-none-eabihf",
        "--",
        "-D",
        "warnings",
    ])?;
    run_example("nav440-pipeline", "estimate_capture", &[CAPTURE])?;
    // All three in one dry run: `nav440-pipeline` depends on the other two by version, which
    // cargo resolves against the packages it has just made (not against crates.io).
    forget_unpacked_packages()?;
    forget_verified_builds()?;
    let mut args = vec![
        "publish",
        "--dry-run",
        "--allow-dirty",
        "--target-dir",
        VERIFY_TARGET_DIR,
    ];
    for (_, lib) in LIBRARIES {
        args.extend(["-p", lib]);
    }
    cargo(&args)
}

/// Removes the sources cargo unpacked from earlier dry runs' local registries
/// (`$CARGO_HOME/registry/src/-<hash>/<library>-<version>`). Cargo names that directory after
/// the path of the target directory and does not unpack a package again where the directory
/// exists, so a second dry run from the same checkout path would verify `nav440-pipeline`
/// against the other libraries as they were at the first one.
fn forget_unpacked_packages() -> Result<(), String> {
    let home = std::env::var_os("CARGO_HOME")
        .map(std::path::PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")))
        .ok_or("neither CARGO_HOME nor HOME is set")?;
    let Ok(registries) = std::fs::read_dir(home.join("registry").join("src")) else {
        return Ok(());
    };
    for registry in registries.flatten() {
        // A local registry's directory has no name before its hash; crates.io's has one.
        if !registry.file_name().to_string_lossy().starts_with('-') {
            continue;
        }
        let Ok(packages) = std::fs::read_dir(registry.path()) else {
            continue;
        };
        for package in packages.flatten() {
            let name = package.file_name().to_string_lossy().into_owned();
            if LIBRARIES.iter().any(|(_, lib)| is_version_of(&name, lib)) {
                std::fs::remove_dir_all(package.path())
                    .map_err(|e| format!("cannot remove {}: {e}", package.path().display()))?;
            }
        }
    }
    Ok(())
}

/// Where the dry run builds the packages it verifies: apart from the workspace's builds, so
/// that [`forget_verified_builds`] touches nothing else.
const VERIFY_TARGET_DIR: &str = "target/publish-verify";

/// Removes the fingerprints of the libraries built by earlier dry runs. Cargo takes a
/// registry package as unchanged while its name and version are, so without this it would
/// link the libraries as an earlier dry run packaged them.
fn forget_verified_builds() -> Result<(), String> {
    let Ok(dir) = std::fs::read_dir(Path::new(VERIFY_TARGET_DIR).join("debug/.fingerprint")) else {
        return Ok(());
    };
    for entry in dir.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let ours = LIBRARIES.iter().any(|(_, lib)| {
            name.strip_prefix(lib)
                .and_then(|rest| rest.strip_prefix('-'))
                .is_some_and(|hash| hash.chars().all(|c| c.is_ascii_hexdigit()))
        });
        if ours {
            std::fs::remove_dir_all(entry.path())
                .map_err(|e| format!("cannot remove {}: {e}", entry.path().display()))?;
        }
    }
    Ok(())
}

/// Whether a directory name is `<package>-<version>` for this package (`nav440-proto-0.1.0`
/// is one of `nav440-proto`, `nav440-pipeline-0.1.0` is not).
fn is_version_of(dir: &str, package: &str) -> bool {
    dir.strip_prefix(package)
        .and_then(|rest| rest.strip_prefix('-'))
        .is_some_and(|v| v.starts_with(|c: char| c.is_ascii_digit()))
}

/// The `rust-version` of `[package]` (or `[workspace.package]`) in a manifest's text, if set
/// as a plain string.
pub fn rust_version(manifest: &str) -> Option<String> {
    manifest.lines().find_map(|line| {
        let (key, value) = line.split_once('=')?;
        (key.trim() == "rust-version").then(|| value.trim().trim_matches('"').to_owned())
    })
}

/// The toolchain channel pinned in `rust-toolchain.toml`.
fn pinned_channel() -> Result<String, String> {
    let text = std::fs::read_to_string("rust-toolchain.toml")
        .map_err(|e| format!("cannot read rust-toolchain.toml: {e}"))?;
    text.lines()
        .find_map(|line| {
            let (key, value) = line.split_once('=')?;
            (key.trim() == "channel").then(|| value.trim().trim_matches('"').to_owned())
        })
        .ok_or_else(|| "rust-toolchain.toml names no channel".to_owned())
}

/// `major.minor` of a version or channel (`1.95.0` -> `1.95`).
fn major_minor(v: &str) -> String {
    v.split('.').take(2).collect::<Vec<_>>().join(".")
}

/// Checks each library (`--lib`, with no and with all features) with the toolchain of
/// its declared `rust-version`, installing it with rustup (minimal profile) when missing, and
/// checks that the workspace's `rust-version` (inherited by the host crates, xtask and the
/// firmware, which are built only with the pinned toolchain) equals the pinned toolchain.
pub fn msrv() -> Result<(), String> {
    to_root()?;
    let pinned = pinned_channel()?;
    let root = std::fs::read_to_string("Cargo.toml")
        .map_err(|e| format!("cannot read Cargo.toml: {e}"))?;
    let workspace = rust_version(&root).ok_or("Cargo.toml declares no rust-version")?;
    if major_minor(&workspace) != major_minor(&pinned) {
        return Err(format!(
            "the workspace's rust-version {workspace} is not the pinned toolchain {pinned} \
             (rust-toolchain.toml), the only one its crates are checked with"
        ));
    }
    eprintln!("xtask msrv: workspace rust-version {workspace} = pinned toolchain {pinned}");
    // The libraries by declared version: one `cargo check` per toolchain and feature set.
    let mut by_version: Vec<(String, Vec<&str>)> = Vec::new();
    for (dir, lib) in LIBRARIES {
        let manifest = std::fs::read_to_string(format!("{dir}/Cargo.toml"))
            .map_err(|e| format!("cannot read {dir}/Cargo.toml: {e}"))?;
        let version = rust_version(&manifest)
            .ok_or_else(|| format!("{dir}/Cargo.toml declares no rust-version of its own"))?;
        match by_version.iter_mut().find(|(v, _)| *v == version) {
            Some((_, libs)) => libs.push(lib),
            None => by_version.push((version, vec![lib])),
        }
    }
    for (version, libs) in &by_version {
        let installed = Command::new("rustup")
            .args(["run", version, "rustc", "--version"])
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false);
        if !installed {
            run(
                "rustup",
                &["toolchain", "install", version, "--profile", "minimal"],
            )?;
        }
        for features in [&[][..], &["--all-features"][..]] {
            let mut args = vec!["run", version, "cargo", "check", "-q", "--lib"];
            for lib in libs {
                args.extend(["-p", lib]);
            }
            args.extend_from_slice(features);
            run("rustup", &args)?;
        }
        eprintln!(
            "xtask msrv: {} compile with their declared rust-version {version}",
            libs.join(" and ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_rust_version_and_channel() {
        let m = "[package]\nname = \"x\"\n# note\nrust-version = \"1.85\"\nlicense = \"MIT\"\n";
        assert_eq!(rust_version(m).as_deref(), Some("1.85"));
        assert_eq!(
            rust_version("[package]\nrust-version.workspace = true\n"),
            None
        );
        assert_eq!(major_minor("1.95.0"), "1.95");
        assert_eq!(major_minor("1.95"), "1.95");
        assert!(is_version_of("nav440-proto-0.1.0", "nav440-proto"));
        assert!(!is_version_of("nav440-proto-extra-0.1.0", "nav440-proto"));
        assert!(!is_version_of("nav440-pipeline-0.1.0", "nav440-proto"));
    }
}
