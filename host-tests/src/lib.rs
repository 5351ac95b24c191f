//! The recorded NAV440 captures of `host-tests/data/` and the integration tests (`tests/`)
//! that replay them through the same parser, estimator banks and tuner the firmware and the
//! `nav440` tool run. `cargo test -p host-tests` runs them; the captures are described in
//! `data/README.md`.

#![forbid(unsafe_code)]

use std::path::PathBuf;

/// The folder of the bundled captures (`host-tests/data`).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// The path of the bundled file `name` (relative to `host-tests/data`, e.g.
/// `"fig5_a2_100hz.bin"` or `"gains/schedule_fig5.toml"`).
pub fn data(name: &str) -> PathBuf {
    data_dir().join(name)
}
