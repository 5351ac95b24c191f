//! Theorem 3.1's condition: satisfied by the scalar ILO with `K2 = Q / (2L)`, impossible for
//! the second-order ILO for acceleration (`C F = 0`); the general ILO equals the scalar one.

use estimators::gilo::{check_theorem_3_1, lyapunov, GeneralIlo, GeneralIloConfig};
use estimators::presets::*;
use estimators::{Estimator, Ilo, IloConfig};

fn scalar(l: f64, k1: f64, k2: f64) -> GeneralIloConfig<1, 1, 1, 1> {
    GeneralIloConfig {
        a: [[0.0]],
        b: [[0.0]],
        c: [[1.0]],
        f: [[1.0]],
        l: [[l]],
        k1: [[k1]],
        k2: [[k2]],
    }
}

/// Scalar velocity ILO (`A = 0, C = F = 1`): `P = Q / (2L)` and the condition holds exactly
/// when `K2 = Q / (2L)`; Table 2's ILO1 (`L = 4, K2 = 0.2`) satisfies it for `Q = 1.6`, not
/// for its listed `Q = 16` (the paper's Q column is not operative); `K1 = 1.05` violates
/// `K1^2 <= 1`.
#[test]
fn scalar_ilo_condition() {
    for (l, q) in [(1.0, 1.0), (4.0, 16.0), (5.0, 7.0), (0.2, 10.0)] {
        let k2 = IloConfig::from_lq(1.0, l as f32, q as f32).k2;
        let r = check_theorem_3_1(&scalar(l, 1.0, f64::from(k2)), &[[q]]);
        let p = r.p.unwrap()[0][0];
        assert!((p - q / (2.0 * l)).abs() < 1e-12, "P = {p}");
        assert!(r.satisfied(1e-6), "{r:?}");
        let wrong = check_theorem_3_1(&scalar(l, 1.0, 2.0 * f64::from(k2)), &[[q]]);
        assert!(!wrong.satisfied(1e-6));
    }
    let c = ILO1_TABLE2;
    let cfg = scalar(f64::from(c.l), f64::from(c.k1), f64::from(c.k2));
    assert!(check_theorem_3_1(&cfg, &[[1.6]]).satisfied(1e-6));
    assert!(!check_theorem_3_1(&cfg, &[[f64::from(Q_TABLE2[0])]]).satisfied(1e-6));
    assert!(!check_theorem_3_1(&scalar(1.0, 1.05, 0.5), &[[1.0]]).k1_ok);
    assert!(check_theorem_3_1(&scalar(1.0, 0.7, 0.5), &[[1.0]]).k1_ok);
}

/// The Lyapunov solver on a 2x2 case with a known solution: `Ac = [[-1, 0], [0, -2]]`,
/// `Q = I` gives `P = diag(1/2, 1/4)`.
#[test]
fn lyapunov_known_solution() {
    let p = lyapunov(&[[-1.0, 0.0], [0.0, -2.0]], &[[1.0, 0.0], [0.0, 1.0]]).unwrap();
    assert!((p[0][0] - 0.5).abs() < 1e-12 && (p[1][1] - 0.25).abs() < 1e-12);
    assert!(p[0][1].abs() < 1e-12 && p[1][0].abs() < 1e-12);
    // a coupled case, verified by substitution
    let ac = [[0.0, 1.0], [-3.0, -2.0]];
    let q = [[2.0, 0.5], [0.5, 1.0]];
    let p = lyapunov(&ac, &q).unwrap();
    for i in 0..2 {
        for j in 0..2 {
            let mut s = 0.0;
            for k in 0..2 {
                s += ac[k][i] * p[k][j] + p[i][k] * ac[k][j];
            }
            assert!((s + q[i][j]).abs() < 1e-12);
        }
    }
}

/// Second-order ILO for acceleration: `A = [[0,1],[0,0]]`, `C = [1 0]`, `F = [0 1]^T`,
/// `C F = 0`. For every stabilising `L` and positive definite `Q` tried, and the best possible
/// `K2` (`K2 = (P F)_0`, the only entry `(K2 C)^T` has), `P F = (K2 C)^T` fails by
/// `(P F)_1 = P_11 > 0`: `P > 0` forces `F^T P F > 0` while `F^T (K2 C)^T = (K2 C F)^T = 0`.
#[test]
fn second_order_ilo_cannot_satisfy_theorem() {
    let mut tried = 0;
    for l0 in [0.5, 1.0, 4.0, 20.0] {
        for l1 in [0.1, 1.0, 10.0, 100.0] {
            for q in [
                [[1.0, 0.0], [0.0, 1.0]],
                [[10.0, 1.0], [1.0, 0.2]],
                [[0.1, 0.0], [0.0, 5.0]],
            ] {
                let a = [[0.0, 1.0], [0.0, 0.0]];
                let c = [[1.0, 0.0]];
                let f = [[0.0], [1.0]];
                let l = [[l0], [l1]];
                // best K2: match the first component of P F
                let ac = [[-l0, 1.0], [-l1, 0.0]];
                let p = lyapunov(&ac, &q).unwrap();
                let k2 = p[0][1];
                let cfg = GeneralIloConfig {
                    a,
                    b: [[0.0], [0.0]],
                    c,
                    f,
                    l,
                    k1: [[0.9]],
                    k2: [[k2]],
                };
                let r = check_theorem_3_1(&cfg, &q);
                assert!(r.p_positive && r.q_positive && r.k1_ok, "{r:?}");
                assert!(!r.satisfied(1e-6));
                assert!((r.spr_residual - p[1][1]).abs() < 1e-9 && p[1][1] > 0.0);
                tried += 1;
            }
        }
    }
    assert_eq!(tried, 48);
}

/// The general ILO with `N = U = P = M = 1`, `A = B = 0`, `C = F = 1` steps exactly like the
/// scalar `Ilo` (same Euler law), here with `D = 3`.
#[test]
fn general_ilo_equals_scalar_ilo() {
    let c = ILO2_TABLE2;
    let mut g = GeneralIlo::<f64, 1, 1, 1, 1, 3>::new(
        &scalar(f64::from(c.l), f64::from(c.k1), f64::from(c.k2)),
        1e-3,
    )
    .unwrap();
    let mut s = Ilo::<f64, 3>::new(&c, 1e-3).unwrap();
    g.reset([0.5]);
    s.reset(0.5);
    for i in 0..5000 {
        let y = 0.5 + (i as f64 * 1e-3 * 3.0).sin();
        let a = g.step(&[0.0], &[y])[0];
        let b = s.step(y);
        assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{a} {b}");
        assert!((g.xhat()[0] - s.xhat()).abs() < 1e-12);
    }
}
