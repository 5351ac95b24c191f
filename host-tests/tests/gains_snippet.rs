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
        g.to_rust("noise variance 0.01 deg^2"),
        include_str!("../data/gains/fig5_var0.01.rs")
    );
    // And the bank accepts it.
    assert!(estimators::PaperBank::<f32>::new(&tuned::TUNED).is_ok());
}
