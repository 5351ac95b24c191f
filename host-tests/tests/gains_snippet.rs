//! The Rust snippet `nav440 tune --rust` writes for the firmware compiles, and builds exactly
//! the configuration its TOML twin gives `--gains`.

use estimators::BankConfig;
use nav440_cli::gains::GainsFile;

mod tuned {
    include!("../data/gains/fig5_var0.01.rs");
}

#[test]
fn committed_snippet_equals_its_toml() {
    let toml = include_str!("../data/gains/fig5_var0.01.toml");
    let g = GainsFile::from_toml(toml).unwrap();
    assert_eq!(tuned::TUNED, g.apply(BankConfig::PAPER));
    assert_ne!(tuned::TUNED, BankConfig::PAPER);
    // The generator still writes exactly this text.
    assert_eq!(
        g.to_rust("noise variance 0.01 deg^2", "PaperBank"),
        include_str!("../data/gains/fig5_var0.01.rs")
    );
    // And the bank accepts it.
    assert!(estimators::PaperBank::<f32>::new(&tuned::TUNED).is_ok());
}

mod product {
    include!("../../firmware-example/src/gains/product_fig5.rs");
}

/// The product snippet (`nav440 tune --bank product --rust`, which the `tuned-gains` firmware
/// includes) holds the gains of its TOML twin for the two rows the product bank runs, and the
/// hold the file's header names; so the firmware (the snippet at every rate) and `nav440
/// estimate --bank product --gains product_fig5.toml --hold zoh` (the file over the NAV440
/// preset at the capture's rate) run the same two estimators. `cargo xtask ci-firmware`
/// compares their CSVs byte for byte.
#[test]
fn product_snippet_runs_what_its_toml_gives_estimate() {
    let toml = include_str!("../data/gains/product_fig5.toml");
    assert!(
        toml.contains("# use: nav440 estimate FILE --bank product --gains THIS_FILE --hold zoh")
    );
    let g = GainsFile::from_toml(toml).unwrap();
    let tables: Vec<&str> = toml.lines().filter(|l| l.starts_with('[')).collect();
    assert_eq!(tables, ["[velocity.ilo1]", "[acceleration.kf]"]);
    let snippet = product::TUNED;
    assert_eq!(snippet.hold, estimators::Hold::ZeroOrder);
    // What `estimate` runs at 100 Hz: the file over the NAV440 preset's gains for that rate.
    let host = g.apply(
        BankConfig {
            sample_period_s: 0.01,
            ..BankConfig::NAV440
        }
        .with_nav440_gains(),
    );
    assert_eq!(snippet.velocity.ilo[0], host.velocity.ilo[0]);
    assert_eq!(snippet.acceleration.kf, host.acceleration.kf);
    let rest = |c: &BankConfig| (c.h, c.max_gap_periods, c.closed_form, c.ed_scheme, c.wrap);
    assert_eq!(rest(&snippet), rest(&host));
    assert!(estimators::ProductBank::<f32>::new(&snippet).is_ok());
}
