//! The steady-state constant-acceleration Kalman tracker.

use estimators::{Kalman, KalmanConfig, KF_DEFAULT};

fn tracker() -> Kalman<f64> {
    Kalman::new(&KalmanConfig {
        dt: 0.01,
        q: KF_DEFAULT.q,
        r: KF_DEFAULT.r,
    })
    .unwrap()
}

/// A constant-acceleration model driven by white jerk is tracked without bias: on the
/// noise-free parabola `y = 3 + 40 t + 250 t^2 / 2` the position, velocity and acceleration
/// errors decay to rounding (a type-3 loop: the model contains the signal).
#[test]
fn tracks_a_parabola_exactly() {
    let mut kf = tracker();
    kf.reset(3.0);
    let y = |t: f64| 3.0 + 40.0 * t + 125.0 * t * t;
    for k in 1..=500 {
        let t = k as f64 * 0.01;
        kf.update(y(t), 0.01);
    }
    let t = 5.0;
    assert!((kf.position() - y(t)).abs() < 1e-9);
    assert!((kf.velocity() - (40.0 + 250.0 * t)).abs() < 1e-7);
    assert!((kf.acceleration() - 250.0).abs() < 1e-6);
}

/// The gains are those of a stable filter: 0 < K0 < 1, K1 > 0, K2 > 0, and an initial error
/// state decays (error recursion `(I - K H) F`), here by more than 1e6 within 1 s.
#[test]
fn steady_state_gain_is_stabilising() {
    let kf = tracker();
    let [k0, k1, k2] = kf.gain();
    println!("steady-state gain: {k0:.4}, {k1:.3} 1/s, {k2:.1} 1/s^2");
    assert!(k0 > 0.0 && k0 < 1.0 && k1 > 0.0 && k2 > 0.0);
    // excite the error state with one 0.01 deg step, then measure a zero signal
    let mut f = tracker();
    f.reset(0.0);
    f.update(0.01, 0.01);
    let start = f.velocity().abs();
    for _ in 0..100 {
        f.update(0.0, 0.01);
    }
    assert!(
        f.velocity().abs() < start * 1e-6 + 1e-12,
        "{} vs {start}",
        f.velocity()
    );
}
