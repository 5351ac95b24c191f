//! The Euler reference rates (`nav440_pipeline::euler`) against an independent computation on
//! a tilted rotation: a known Euler-angle trajectory (roll through +-180 deg, pitch to +-70
//! deg, yaw over many degrees) is turned into rotation matrices R(t) = Rz(psi) Ry(theta)
//! Rx(phi) (f64); the body rates come from the matrices alone, omega_body = vee(R^T dR/dt)
//! with dR/dt by a central difference. Those rates and the angles go through
//! `euler_rates_deg` (f32); its output must match the trajectory's analytic angle
//! derivatives. No Euler-kinematics formula is used on the reference side.

use nav440_pipeline::euler::{euler_rates_deg, PITCH_LIMIT_DEG};

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn transpose(a: &M3) -> M3 {
    let mut t = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            t[i][j] = a[j][i];
        }
    }
    t
}

/// R = Rz(psi) Ry(theta) Rx(phi), angles in rad (body to navigation frame).
fn rotation(phi: f64, theta: f64, psi: f64) -> M3 {
    let (sf, cf) = phi.sin_cos();
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    let rx = [[1.0, 0.0, 0.0], [0.0, cf, -sf], [0.0, sf, cf]];
    let ry = [[ct, 0.0, st], [0.0, 1.0, 0.0], [-st, 0.0, ct]];
    let rz = [[cp, -sp, 0.0], [sp, cp, 0.0], [0.0, 0.0, 1.0]];
    mul(&rz, &mul(&ry, &rx))
}

/// The trajectory (deg) and its analytic derivative (deg/s).
fn angles(t: f64) -> ([f64; 3], [f64; 3]) {
    let roll = 150.0 * (0.9 * t).sin() + 40.0 * t; // passes +-180 deg
    let pitch = 70.0 * (0.6 * t + 0.3).sin();
    let yaw = 90.0 * (0.4 * t).cos() - 25.0 * t;
    let d = [
        150.0 * 0.9 * (0.9 * t).cos() + 40.0,
        70.0 * 0.6 * (0.6 * t + 0.3).cos(),
        -90.0 * 0.4 * (0.4 * t).sin() - 25.0,
    ];
    ([roll, pitch, yaw], d)
}

/// Body rates p, q, r (deg/s) from the rotation matrices only.
fn body_rates(t: f64) -> [f64; 3] {
    let h = 1e-6;
    let r_at = |t: f64| {
        let (a, _) = angles(t);
        rotation(a[0].to_radians(), a[1].to_radians(), a[2].to_radians())
    };
    let (rp, rm, r0) = (r_at(t + h), r_at(t - h), r_at(t));
    let mut dr = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            dr[i][j] = (rp[i][j] - rm[i][j]) / (2.0 * h);
        }
    }
    let w = mul(&transpose(&r0), &dr); // skew(omega_body)
    [w[2][1], w[0][2], w[1][0]].map(f64::to_degrees)
}

/// Wraps an angle to [-180, 180) deg, as the packets send it.
fn wrap(deg: f64) -> f64 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

#[test]
fn euler_rates_match_the_rotation_matrices() {
    let mut checked = 0;
    let mut max_err = [0.0f64; 3];
    for k in 0..2000 {
        let t = k as f64 * 0.01;
        let (a, d) = angles(t);
        let pqr = body_rates(t);
        let got = euler_rates_deg(wrap(a[0]) as f32, a[1] as f32, pqr.map(|x| x as f32));
        // |pitch| <= 70 < 80 deg: every rate is given.
        assert!(a[1].abs() < f64::from(PITCH_LIMIT_DEG));
        for i in 0..3 {
            let g = f64::from(got[i].expect("defined below the pitch limit"));
            // f32 arithmetic: relative 1e-5 of the rates involved, amplified by
            // 1 / cos(70 deg) = 2.9 at most.
            let scale = pqr.iter().map(|x| x.abs()).fold(1.0, f64::max);
            let err = (g - d[i]).abs();
            assert!(err < 1e-4 * scale, "t = {t}, axis {i}: {g} vs {}", d[i]);
            max_err[i] = max_err[i].max(err);
        }
        checked += 1;
    }
    assert_eq!(checked, 2000);
    // The test exercises tilt: body z rate differs from the yaw rate by far.
    let (a, d) = angles(3.0);
    let pqr = body_rates(3.0);
    assert!(
        a[1].abs() > 30.0 && (pqr[2] - d[2]).abs() > 10.0,
        "{a:?} {pqr:?} {d:?}"
    );
}

#[test]
fn beyond_the_pitch_limit_roll_and_yaw_rates_are_empty() {
    let pqr = [10.0, 20.0, 30.0];
    for pitch in [80.0f32, 85.0, 89.9, 90.0, -80.0, -90.0] {
        let r = euler_rates_deg(12.0, pitch, pqr);
        assert_eq!((r[0], r[2]), (None, None), "pitch {pitch}");
        assert!(r[1].is_some());
    }
}
