//! The ED's stability limit `h * alpha` (without it `alpha = 1e30` drives `ed_v` to 8e28
//! deg/s): refused at configuration with a typed error naming `alpha`, in
//! the law, in both banks' halves and for f32 and Q31.32; at the limit the bank still runs and
//! its ED output stays within the chatter the limit allows.

use estimators::{
    BankConfig, Channel, ConfigError, Ed, EdConfig, Fx, PaperBank, ProductBank, ED_MAX_H_ALPHA,
};

const H: f32 = 1e-4;

fn ed(alpha: f32) -> EdConfig {
    EdConfig {
        lambda: 700.0,
        alpha,
    }
}

#[test]
fn h_alpha_beyond_the_limit_is_refused_naming_alpha() {
    let refused = Some(ConfigError::StepRateTooLarge("alpha"));
    for alpha in [1e30, 1e11, f32::MAX] {
        assert_eq!(
            Ed::<f32>::new(&ed(alpha), H).err(),
            refused,
            "alpha {alpha}"
        );
        assert_eq!(Ed::<Fx>::new(&ed(alpha), H).err(), refused, "alpha {alpha}");
        let mut cfg = BankConfig::default();
        cfg.velocity.ed = ed(alpha);
        assert_eq!(PaperBank::<f32>::new(&cfg).err(), refused);
        assert_eq!(PaperBank::<Fx>::new(&cfg).err(), refused);
        let mut cfg = BankConfig::default();
        cfg.acceleration.ed = ed(alpha);
        assert_eq!(PaperBank::<f32>::new(&cfg).err(), refused);
    }
    // The limit scales with the step: 1e10 is refused at h = 1 ms, accepted at 0.1 ms.
    assert_eq!(Ed::<f32>::new(&ed(1e10), 1e-3).err(), refused);
    assert!(Ed::<f32>::new(&ed(1e10), H).is_ok());
    assert_eq!(
        ConfigError::StepRateTooLarge("alpha").to_string(),
        "h * `alpha` must be at most 1e6 (the change of the output in one step, unit/s)"
    );
    // The product bank builds the same laws through the same check.
    let _ = ProductBank::<f32>::new(&BankConfig::default()).unwrap();
}

/// At the limit (`h alpha` = 1e6 deg/s) the bank runs on a 100 Hz spin and its ED velocity
/// stays within a few steps' chatter of the limit: bounded, not 8e28.
#[test]
fn at_the_limit_the_ed_output_stays_bounded() {
    let alpha = (ED_MAX_H_ALPHA / f64::from(H)) as f32;
    let mut cfg = BankConfig::default();
    cfg.velocity.ed = ed(alpha);
    let mut bank = PaperBank::<f32>::new(&cfg).unwrap();
    let mut peak = 0.0f32;
    for k in 0..2000u64 {
        let yaw = (k as f32 * 0.01 * 100.0) % 360.0 - 180.0;
        let out = bank.update(k * 10_000, yaw).unwrap();
        let v = out[Channel::EdV];
        assert!(v.is_finite());
        peak = peak.max(v.abs());
    }
    assert!(peak < 1e9, "ED velocity peak {peak} deg/s");
}
