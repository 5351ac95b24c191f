//! The gains the firmware compiles in (`firmware-example/src/gains/`) are the committed
//! `nav440 tune --rust` snippets of `data/gains/` (which the other tests hold to their TOML
//! files and to `nav440 estimate --gains`), byte for byte: a firmware includes nothing from
//! host-tests/, so it keeps its own copy, and a re-tuned snippet is copied there too.

use std::path::Path;

/// `name` in `data/gains/` and in `firmware-example/src/gains/`.
fn both(name: &str) -> (String, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let read =
        |p: &Path| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    (
        read(&root.join("data/gains").join(name)),
        read(&root.join("../firmware-example/src/gains").join(name)),
    )
}

#[test]
fn the_firmware_schedule_is_the_committed_snippet() {
    let (host, firmware) = both("schedule_fig5.rs");
    assert!(host.contains("pub const SCHEDULE: [ScheduleLevel; 5] = ["));
    assert_eq!(
        firmware, host,
        "cp host-tests/data/gains/schedule_fig5.rs firmware-example/src/gains/"
    );
}

#[test]
fn the_firmware_product_gains_are_the_committed_snippet() {
    let (host, firmware) = both("product_fig5.rs");
    assert!(host.contains("pub const TUNED: BankConfig = BankConfig {"));
    assert_eq!(
        firmware, host,
        "cp host-tests/data/gains/product_fig5.rs firmware-example/src/gains/"
    );
}
