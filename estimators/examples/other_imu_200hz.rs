//! The estimators with another IMU: a yaw angle sampled at 200 Hz through the product bank.
//!
//! The signal is a known motion, `y(t) = 30 sin(2 pi 0.5 t) + 15 sin(2 pi t)` deg, plus
//! Gaussian noise of 0.1 deg RMS (variance 0.01 deg^2), sampled every 5 ms. Its exact rate
//! and acceleration are known, so the example prints a few rows of
//! `t, true rate, ILO1 velocity, true acceleration, Kalman acceleration` (s, deg/s, deg/s,
//! deg/s^2, deg/s^2) and the RMS errors against the exact derivatives: the velocity's is a
//! few percent of the rate; the acceleration, a second derivative of a noisy angle, is
//! rougher.
//!
//! What another sensor has to set (docs/OTHER-IMU.md):
//!
//! * [`ProductBank`]: two estimators per angle, the ILO1 velocity (`ProductChannel::Ilo1V`,
//!   deg/s) and the Kalman tracker's acceleration (`ProductChannel::KfA`, deg/s^2).
//! * `sample_period_s`: the sensor's nominal sample period in s, here 0.005 (200 Hz). The
//!   default is 0.01 (100 Hz) and nothing warns when it is wrong: it sets the closed-form maps,
//!   the tracker's gains and the gap rule.
//! * `wrap`: [`Wrap::None`] for a signal that does not wrap at +-180 deg (this one, a pitch
//!   angle, any position); [`Wrap::Deg180`] (the default) for a heading reported within
//!   +-180 deg.
//! * The tracker's noise [`KalmanNoise`]: `q` in deg^2/s^5 (the power spectral density of the
//!   white jerk that drives its constant-acceleration model: larger follows faster motion with
//!   more noise), `r` in deg^2 (the angle's measurement-noise variance, here 0.01).
//! * Time stamps in integer microseconds, increasing; angles in deg.
//!
//! Channels of the paper bank ([`estimators::PaperBank`]) not to pick for a product: they are
//! the paper's demonstrations of failure. `Channel::Ilo1A`, the ILO series with `K1 = 1`
//! (Table 4's ILO1; the paper's Fig. 3 shows that series diverging), does no better than
//! outputting 0; `Channel::EdA`, the Euler-stepped ED in series, differentiates the ED's
//! chatter; `Channel::AdA` (two 1.6 Hz low-passes) is too slow for hand motion.
//!
//! `cargo run -p velocity-estimators --example other_imu_200hz`

use estimators::{BankConfig, KalmanNoise, ProductBank, ProductChannel, Wrap};
use std::f64::consts::PI;

/// The motion, deg, and its exact first and second derivatives, deg/s and deg/s^2.
fn motion(t: f64) -> (f64, f64, f64) {
    let (w1, w2) = (2.0 * PI * 0.5, 2.0 * PI);
    let y = 30.0 * (w1 * t).sin() + 15.0 * (w2 * t).sin();
    let v = 30.0 * w1 * (w1 * t).cos() + 15.0 * w2 * (w2 * t).cos();
    let a = -30.0 * w1 * w1 * (w1 * t).sin() - 15.0 * w2 * w2 * (w2 * t).sin();
    (y, v, a)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut cfg = BankConfig {
        sample_period_s: 0.005, // s: 200 Hz, the sensor's sample period
        wrap: Wrap::None,       // the angle stays within +-45 deg and does not wrap
        ..BankConfig::DEFAULT   // the paper's gains (leaky AVE law), h = 1e-4 s
    };
    // The tracker whose acceleration the bank reports: q in deg^2/s^5, r in deg^2.
    cfg.acceleration.kf = KalmanNoise { q: 1.0e6, r: 0.01 };
    let mut bank = ProductBank::<f32>::new(&cfg)?;

    // Gaussian noise of 0.1 deg RMS, reproducible (seed 1).
    let mut rng: rand::rngs::Xoshiro256PlusPlus = rand::SeedableRng::seed_from_u64(1);
    let mut noise =
        || -> f64 { rand_distr::Distribution::sample(&rand_distr::StandardNormal, &mut rng) };

    // Sums of squares over 1-10 s: velocity error, rate, acceleration error, acceleration.
    let mut sums = [0.0f64; 4];
    let mut n = 0u32;
    println!("t_s,true_rate_deg_s,ilo1_v_deg_s,true_acc_deg_s2,kf_a_deg_s2");
    for k in 0..=2_000u64 {
        let t_us = k * 5_000; // 200 Hz, integer microseconds
        let t = t_us as f64 * 1e-6; // s
        let (y, rate, acc) = motion(t);
        let out = bank.update(t_us, (y + 0.1 * noise()) as f32)?;
        let (v, a) = (out[ProductChannel::Ilo1V], out[ProductChannel::KfA]);
        if k % 150 == 0 {
            println!("{t:.2},{rate:.2},{v:.2},{acc:.1},{a:.1}");
        }
        // The error once the estimators have settled (the first second left out).
        if t >= 1.0 {
            let (ev, ea) = (f64::from(v) - rate, f64::from(a) - acc);
            for (s, x) in sums.iter_mut().zip([ev, rate, ea, acc]) {
                *s += x * x;
            }
            n += 1;
        }
    }
    let [rms_err, rms_rate, rms_acc_err, rms_acc] = sums.map(|s| (s / f64::from(n)).sqrt());
    println!(
        "ILO1 velocity over 1-10 s: RMS error {rms_err:.2} deg/s against an RMS rate of \
         {rms_rate:.1} deg/s (relative {:.3})",
        rms_err / rms_rate
    );
    println!(
        "Kalman acceleration over 1-10 s: RMS error {rms_acc_err:.1} deg/s^2 against an RMS \
         acceleration of {rms_acc:.1} deg/s^2 (relative {:.3})",
        rms_acc_err / rms_acc
    );
    assert!(rms_err < 0.1 * rms_rate, "RMS error {rms_err} deg/s");
    Ok(())
}
