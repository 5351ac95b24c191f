//! Unbounded spin: the unwrapped yaw stays exact, and the estimates unaffected, at any number
//! of turns (10^7 turns here), in f32 and Q31.32.

use estimators::EstimatorOutput as _;
use estimators::{BankConfig, Fx, PaperBank, Real, Unwrapper};

/// NAV440 yaw LSB = 360/2^16 deg = 45/8192 deg (exact in f32 for any 16-bit count).
fn lsb_to_deg(counts: i64) -> f64 {
    counts as f64 * 45.0 / 8192.0
}

/// 10^7 turns in steps of 30947 LSB (170.0 deg): the unwrapper's `360 turns + wrapped` equals
/// the exact angle (integer arithmetic) at every sample checked, in f32 and Q31.32.
fn unwrapper_exact_over_1e7_turns<T: Real>() {
    let step: i64 = 30_947;
    let samples = 10_000_000i64 * 65_536 / step + 2;
    let mut u = Unwrapper::<T>::new();
    for k in 0..samples {
        let counts = k * step; // exact unwrapped angle in LSB
        let wrapped = (counts + 32_768).rem_euclid(65_536) - 32_768; // [-32768, 32768)
        let w = T::from_f32(lsb_to_deg(wrapped) as f32);
        let turns = u.update(w);
        if k % 1_000_003 == 0 || k == samples - 1 {
            let got = turns as f64 * 360.0 + w.to_f64();
            assert_eq!(got, lsb_to_deg(counts), "sample {k}");
        }
    }
    assert!(u.turns() >= 10_000_000);
}

#[test]
fn unwrapper_exact_over_ten_million_turns_f32() {
    unwrapper_exact_over_1e7_turns::<f32>();
}

#[test]
fn unwrapper_exact_over_ten_million_turns_fixed() {
    unwrapper_exact_over_1e7_turns::<Fx>();
}

/// A bank 10^7 turns out gives bit-identical estimates to a bank at turn 0 on the same wrapped
/// samples (a 500 deg/s spin for 20 s, 28 turns), and its yaw column is the exact decimal of
/// 3.6e9 deg + the angle (f64 Display of the exact sum, checked by parsing it back).
fn bank_at_ten_million_turns<T: Real>() {
    let mut a = PaperBank::<T>::new(&BankConfig::default()).unwrap();
    let mut b = PaperBank::<T>::new(&BankConfig::default()).unwrap();
    let turns = 10_000_000i64;
    b.set_turns(turns);
    let step = 910i64; // LSB per 10 ms: 5.0 deg, 500 deg/s
    for k in 0..2000i64 {
        let counts = k * step;
        let wrapped = (counts + 32_768).rem_euclid(65_536) - 32_768;
        let y = lsb_to_deg(wrapped) as f32;
        let t_us = k as u64 * 10_000;
        let oa = a.update(t_us, y).unwrap();
        let ob = b.update(t_us, y).unwrap();
        assert_eq!(
            oa.velocities().map(f32::to_bits),
            ob.velocities().map(f32::to_bits)
        );
        assert_eq!(
            oa.accelerations().map(f32::to_bits),
            ob.accelerations().map(f32::to_bits)
        );
        if k > 1000 {
            // accurate after 10 s: every velocity estimator within 3 deg/s of 500 (ILO2/3 within their
            // leaky DC gain; ED within its Euler chatter lambda^2 h = 49 deg/s).
            for (i, v) in ob.velocities().iter().enumerate() {
                let tol = match i {
                    2 | 3 => 0.06 * 500.0,
                    5 => 50.0,
                    _ => 3.0,
                };
                assert!((v - 500.0).abs() < tol, "col {i}: {v}");
            }
        }
        let exact = turns as f64 * 360.0 + lsb_to_deg(counts);
        // The exact unwrapped yaw (f32 rounding + f64 residual; the CSV's yaw column, whose
        // text is checked in nav440-pipeline's csv tests).
        let got = f64::from(ob.unwrapped_deg()) + ob.residual_deg();
        assert_eq!(got, exact, "row {k}");
        let exact_a = lsb_to_deg(counts);
        assert_eq!(f64::from(oa.unwrapped_deg()) + oa.residual_deg(), exact_a);
        if f64::from(exact_a as f32) == exact_a {
            assert_eq!(oa.residual_deg(), 0.0);
        }
    }
}

#[test]
fn bank_at_ten_million_turns_f32() {
    bank_at_ten_million_turns::<f32>();
}

#[test]
fn bank_at_ten_million_turns_fixed() {
    bank_at_ten_million_turns::<Fx>();
}
