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

/// The textbook filter Riccati recursion with general 3x3 products, `P- = F P F' + Q`,
/// `K = P- H' / (H P- H' + r)`, `P = (I - K H) P-`, iterated 5,000 times from `P = Q`.
fn riccati_by_matrices(dt: f64, q: f64, r: f64) -> [f64; 3] {
    type M = [[f64; 3]; 3];
    let mul = |a: &M, b: &M| -> M {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    };
    let f: M = [[1.0, dt, dt * dt / 2.0], [0.0, 1.0, dt], [0.0, 0.0, 1.0]];
    let mut ft = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            ft[i][j] = f[j][i];
        }
    }
    let d = |p: i32| dt.powi(p);
    let qm: M = [
        [q * d(5) / 20.0, q * d(4) / 8.0, q * d(3) / 6.0],
        [q * d(4) / 8.0, q * d(3) / 3.0, q * d(2) / 2.0],
        [q * d(3) / 6.0, q * d(2) / 2.0, q * dt],
    ];
    let mut p = qm;
    let mut k = [0.0; 3];
    for _ in 0..5000 {
        let mut pp = mul(&mul(&f, &p), &ft);
        for i in 0..3 {
            for j in 0..3 {
                pp[i][j] += qm[i][j];
            }
        }
        let s = pp[0][0] + r;
        k = [pp[0][0] / s, pp[1][0] / s, pp[2][0] / s];
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] = pp[i][j] - k[i] * pp[0][j];
            }
        }
    }
    k
}

/// The tracker's gain (the recursion on the six distinct covariance entries, stopped at a
/// 1e-13 relative change) equals the textbook recursion run to its fixed point to 1e-10
/// relative, at the unit's packet rates (100 Hz to 2 Hz) and
/// with `q / r` from 1e3 to 1e11 around the shipped gains.
#[test]
fn steady_state_gain_equals_the_matrix_recursion() {
    for dt in [0.01f32, 0.02, 0.04, 0.05, 0.1, 0.2, 0.25, 0.5] {
        for q in [1e3f32, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9] {
            for r in [0.01f32, 0.1, 1.0] {
                let fast = Kalman::<f64>::new(&KalmanConfig { dt, q, r })
                    .unwrap()
                    .gain();
                let slow = riccati_by_matrices(f64::from(dt), f64::from(q), f64::from(r));
                for (a, b) in fast.iter().zip(slow) {
                    assert!(
                        (a - b).abs() <= 1e-10 * b.abs(),
                        "dt={dt} q={q} r={r}: {fast:?} vs {slow:?}"
                    );
                }
            }
        }
    }
}
