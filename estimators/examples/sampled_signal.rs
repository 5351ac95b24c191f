//! One estimator on a sampled signal: the AVE (the paper's eq. 4, its gains k = 500,
//! gamma1 = 20000) estimates the rate of `y(t) = 30 sin(2 t)` deg sampled at 100 Hz.
//!
//! The `SampleAdapter` runs the continuous law with explicit Euler steps of h = 1e-4 s between
//! samples (100 steps per 10 ms sample, linear hold). Prints `t, true rate, estimate` in
//! s, deg/s, deg/s every 0.25 s and checks the estimate has converged.
//!
//! `cargo run -p estimators --example sampled_signal`

use estimators::{presets, Ave, Hold, SampleAdapter};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let h = presets::H_PAPER; // s
    let ave = Ave::<f32>::new(&presets::AVE_PAPER, h)?;
    // A gap longer than 0.25 s would re-initialise the law (none here).
    let mut adapter = SampleAdapter::new(ave, h, 0.25, Hold::Linear)?;
    let mut last_error = f32::INFINITY;
    println!("t_s,true_rate_deg_s,ave_deg_s");
    for k in 0..=400u64 {
        let t_us = k * 10_000; // 100 Hz
        let t = t_us as f32 * 1e-6; // s
        let y = 30.0 * (2.0 * t).sin(); // deg
        let rate = 60.0 * (2.0 * t).cos(); // deg/s, the exact derivative
        let v = adapter.update(t_us, y)?; // deg/s
        if k % 25 == 0 {
            println!("{t:.2},{rate:.3},{v:.3}");
        }
        last_error = (v - rate).abs();
    }
    // After 4 s the AVE tracks the rate to within a few deg/s (its lag is about a * k / gamma1).
    assert!(last_error < 5.0, "AVE error {last_error} deg/s");
    Ok(())
}
