//! The `tumble` profile: a hand-held unit pointing up that nods through the vertical, so its
//! Euler angles pass gimbal lock.
//!
//! # The attitude
//! The body-to-NED rotation is a product of three elementary rotations,
//!
//! ```text
//! R(t) = Rz(gamma) Ry(alpha) Rz(beta)
//! ```
//!
//! (`Rz`, `Ry`: right-handed rotations about z and y). With `alpha = 90 deg`, `beta = 0` the
//! body x axis points up (pitch +90 deg): `90 deg - alpha` and `beta` are the two components of
//! the tilt of the x axis away from the vertical, `gamma` turns the unit about the vertical.
//! All three angles are smooth closed-form functions of a time `tau` that starts the motion
//! from rest (below), in degrees:
//!
//! ```text
//! x     = 2 pi tau / T_N                                   nod phase, T_N = 10.37 s
//! rho   = (A0 + A1 sin(2 pi tau / T_A)) tanh(k_N cos x) / tanh k_N      (signed tilt, deg)
//! m     = (M / 2)(1 - sin x) + M_S sin(2 pi tau / T_M)     (miss distance, deg)
//! phi   = 2 pi tau / T_PHI                                 (direction of the nod, rad)
//! u     = rho cos phi - m sin phi,   v = rho sin phi + m cos phi
//! F     = tanh(k_F cos(2 pi tau / T_F)) / tanh k_F        (+1 upright, -1 upside down)
//! alpha = 90 F - u,   beta = v
//! gamma = G1 sin(2 pi tau / T_G1) + G2 sin(2 pi tau / T_G2 + 1 rad)
//! ```
//!
//! with A0 = 22 deg, A1 = 5 deg, T_A = 23 s, k_N = 7, M = 12 deg, M_S = 0.4 deg, T_M = 7.3 s,
//! T_PHI = 37 s, T_F = 6 T_N = 62.22 s, k_F = 12, G1 = 60 deg, T_G1 = 17 s, G2 = 25 deg,
//! T_G2 = 7 s.
//!
//! The unit rests at a tilt of |rho| = 17..27 deg (pitch about 62-72 deg) and, every T_N / 2,
//! swings quickly (70 to 115 deg/s through the vertical) to the other side. One swing in two
//! passes the vertical within M_S = 0.4 deg (plus up to 0.4 deg that a nearby turn-over adds),
//! so in most periods T_N the pitch comes within 0.5 deg of +-90 deg; the swing back passes
//! M = 12 deg beside it (pitch about 78 deg). The nod's direction phi turns slowly, so the
//! unit reaches the vertical from every side. Every T_F / 2 = 3 T_N the unit turns over (F from +1 to -1 or back, mid-way between
//! two swings), so the poles at pitch +90 and -90 deg alternate every 31 s. T_N = 10.37 s is
//! no multiple of a packet period: the passes fall between samples at varying offsets.
//!
//! The time `tau` ramps in like the Fig. 5 profile: `tau' = sin^2(pi t / (2 T_R))` for
//! `t < T_R = 1.5 s`, then 1, so every rate is 0 at t = 0 (the unit starts at rest, pitch
//! 67.2 deg).
//!
//! # Body rates
//! The angular velocity in the body frame is each factor's axis rate rotated into the body:
//! `omega = Rz(beta)^T Ry(alpha)^T gamma' e_z + Rz(beta)^T alpha' e_y + beta' e_z`, that is
//!
//! ```text
//! p = alpha' sin beta - gamma' sin alpha cos beta
//! q = alpha' cos beta + gamma' sin alpha sin beta
//! r = beta' + gamma' cos alpha
//! r' = beta'' + gamma'' cos alpha - gamma' alpha' sin alpha
//! ```
//!
//! with the derivatives of the angles by the chain rule through `tau` (forward-mode
//! derivatives: a value carried with its first and second derivatives). |p|, |q|, |r| stay
//! below 120 deg/s (the peaks over 3000 s: 63, 115 and 117 deg/s), |r'| below 400 deg/s^2.
//!
//! # Euler angles
//! Aerospace ZYX sequence, from the entries of R:
//! `pitch = -asin R31 = asin(sin alpha cos beta)` in [-90, 90] deg,
//! `roll = atan2(R32, R33) = atan2(sin alpha sin beta, cos alpha)`,
//! `yaw = atan2(R21, R11)`, both in (-180, 180] deg. Near the pole roll and yaw swing by up to
//! 180 deg within a few milliseconds while p, q, r stay bounded: the kinematics of the Euler
//! angles, not a branch flip.

use std::f64::consts::PI;
use std::ops::{Add, Mul, Sub};

use super::MotionPoint;

/// Period of the nod, s (one pass near the pole per period, one swing 12 deg beside it).
pub const TUMBLE_NOD_PERIOD_S: f64 = 10.37;
/// Mean tilt of the x axis from the vertical while the unit rests between swings, deg.
const TILT_MEAN_DEG: f64 = 22.0;
/// Amplitude of the slow change of that tilt, deg.
const TILT_SWING_DEG: f64 = 5.0;
/// Period of the slow change of the tilt, s.
const TILT_PERIOD_S: f64 = 23.0;
/// Steepness of the nod (tanh of k cos): the larger, the faster the swing through the vertical.
const NOD_STEEPNESS: f64 = 7.0;
/// Distance beside the vertical of the swing back, deg.
const MISS_BACK_DEG: f64 = 12.0;
/// Amplitude of the miss distance of the pass near the pole, deg.
const MISS_NEAR_DEG: f64 = 0.4;
/// Period of that miss distance, s.
const MISS_PERIOD_S: f64 = 7.3;
/// Period of the turn of the nod's direction, s.
const DIRECTION_PERIOD_S: f64 = 37.0;
/// Period of the turn-over (up, down, up), s: six nods, so the unit turns over mid-way
/// between two swings.
const FLIP_PERIOD_S: f64 = 6.0 * TUMBLE_NOD_PERIOD_S;
/// Steepness of the turn-over.
const FLIP_STEEPNESS: f64 = 12.0;
/// Amplitudes (deg), periods (s) and phases (rad) of the turn about the vertical.
const HEADING: [(f64, f64, f64); 2] = [(60.0, 17.0, 0.0), (25.0, 7.0, 1.0)];
/// Length of the start ramp of the time `tau`, s.
const RAMP_S: f64 = 1.5;

/// A value with its first and second time derivatives (units of the value per s and s^2):
/// arithmetic on it applies the product and chain rules.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Jet {
    v: f64,
    d: f64,
    dd: f64,
}

impl Jet {
    /// A constant.
    fn c(v: f64) -> Self {
        Jet { v, d: 0.0, dd: 0.0 }
    }

    fn scale(self, k: f64) -> Self {
        Jet {
            v: k * self.v,
            d: k * self.d,
            dd: k * self.dd,
        }
    }

    fn sin(self) -> Self {
        let (s, c) = self.v.sin_cos();
        Jet {
            v: s,
            d: c * self.d,
            dd: c * self.dd - s * self.d * self.d,
        }
    }

    fn cos(self) -> Self {
        let (s, c) = self.v.sin_cos();
        Jet {
            v: c,
            d: -s * self.d,
            dd: -s * self.dd - c * self.d * self.d,
        }
    }

    fn tanh(self) -> Self {
        let t = self.v.tanh();
        let g = 1.0 - t * t;
        Jet {
            v: t,
            d: g * self.d,
            dd: g * self.dd - 2.0 * t * g * self.d * self.d,
        }
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            d: self.d + o.d,
            dd: self.dd + o.dd,
        }
    }
}

impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        Jet {
            v: self.v - o.v,
            d: self.d - o.d,
            dd: self.dd - o.dd,
        }
    }
}

impl Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet {
            v: self.v * o.v,
            d: self.d * o.v + self.v * o.d,
            dd: self.dd * o.v + 2.0 * self.d * o.d + self.v * o.dd,
        }
    }
}

/// The motion's time `tau` (s) at `t` (s) with its derivatives: starts at rest, `tau' =
/// sin^2(pi t / (2 T_R))` during the ramp, then `tau = t - T_R / 2`.
fn tau(t: f64) -> Jet {
    if t <= 0.0 {
        Jet::c(0.0)
    } else if t < RAMP_S {
        let c = PI / RAMP_S;
        let (s, co) = (c * t).sin_cos();
        Jet {
            v: t / 2.0 - s / (2.0 * c),
            d: (1.0 - co) / 2.0,
            dd: c / 2.0 * s,
        }
    } else {
        Jet {
            v: t - RAMP_S / 2.0,
            d: 1.0,
            dd: 0.0,
        }
    }
}

/// `sin(2 pi tau / period + phase)`.
fn wave(tau: Jet, period_s: f64, phase: f64) -> Jet {
    (tau.scale(2.0 * PI / period_s) + Jet::c(phase)).sin()
}

/// The composing angles `[alpha, beta, gamma]` (rad) at `t` (s), with their derivatives.
fn composing_angles(t: f64) -> [Jet; 3] {
    let tau = tau(t);
    let x = tau.scale(2.0 * PI / TUMBLE_NOD_PERIOD_S);
    let square = |arg: Jet, k: f64| arg.cos().scale(k).tanh().scale(1.0 / k.tanh());
    let tilt = Jet::c(TILT_MEAN_DEG) + wave(tau, TILT_PERIOD_S, 0.0).scale(TILT_SWING_DEG);
    let rho = tilt * square(x, NOD_STEEPNESS);
    let miss = (Jet::c(1.0) - x.sin()).scale(MISS_BACK_DEG / 2.0)
        + wave(tau, MISS_PERIOD_S, 0.0).scale(MISS_NEAR_DEG);
    let phi = tau.scale(2.0 * PI / DIRECTION_PERIOD_S);
    let (cphi, sphi) = (phi.cos(), phi.sin());
    let u = rho * cphi - miss * sphi;
    let v = rho * sphi + miss * cphi;
    let flip = square(tau.scale(2.0 * PI / FLIP_PERIOD_S), FLIP_STEEPNESS);
    let alpha = flip.scale(90.0) - u;
    let gamma = HEADING
        .iter()
        .fold(Jet::c(0.0), |g, &(a, p, ph)| g + wave(tau, p, ph).scale(a));
    let rad = PI / 180.0;
    [alpha.scale(rad), v.scale(rad), gamma.scale(rad)]
}

/// Angle `atan2` (deg) folded into (-180, 180].
fn atan2_deg(y: f64, x: f64) -> f64 {
    let a = y.atan2(x).to_degrees();
    if a <= -180.0 {
        a + 360.0
    } else {
        a
    }
}

/// The tumble's motion at `t` (s): Euler angles, body rates, and `rate_deg_s = r`,
/// `acc_deg_s2 = dr/dt`.
pub(super) fn at(t: f64) -> MotionPoint {
    let [al, be, ga] = composing_angles(t);
    let (sa, ca) = al.v.sin_cos();
    let (sb, cb) = be.v.sin_cos();
    let (sg, cg) = ga.v.sin_cos();
    let p = al.d * sb - ga.d * sa * cb;
    let q = al.d * cb + ga.d * sa * sb;
    let r = be.d + ga.d * ca;
    let dr = be.dd + ga.dd * ca - ga.d * al.d * sa;
    // Entries of R = Rz(gamma) Ry(alpha) Rz(beta) that the ZYX angles need.
    let r11 = cg * ca * cb - sg * sb;
    let r21 = sg * ca * cb + cg * sb;
    let r31 = -sa * cb;
    let (r32, r33) = (sa * sb, ca);
    let k = 180.0 / PI;
    MotionPoint {
        yaw_deg: atan2_deg(r21, r11),
        rate_deg_s: k * r,
        acc_deg_s2: k * dr,
        roll_deg: atan2_deg(r32, r33),
        pitch_deg: (-r31).clamp(-1.0, 1.0).asin().to_degrees(),
        body_rates_deg_s: [k * p, k * q, k * r],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type M3 = [[f64; 3]; 3];

    fn mul(a: &M3, b: &M3) -> M3 {
        let mut c = [[0.0; 3]; 3];
        for (i, row) in c.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    fn rx(a: f64) -> M3 {
        let (s, c) = a.sin_cos();
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
    }

    fn ry(a: f64) -> M3 {
        let (s, c) = a.sin_cos();
        [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    }

    fn rz(a: f64) -> M3 {
        let (s, c) = a.sin_cos();
        [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    }

    /// The attitude from the profile's Euler angles: R = Rz(yaw) Ry(pitch) Rx(roll).
    fn euler_matrix(m: &MotionPoint) -> M3 {
        let r = |d: f64| d.to_radians();
        mul(
            &mul(&rz(r(m.yaw_deg)), &ry(r(m.pitch_deg))),
            &rx(r(m.roll_deg)),
        )
    }

    /// `a - b` wrapped into [-180, 180), deg.
    fn wrap(d: f64) -> f64 {
        (d + 180.0).rem_euclid(360.0) - 180.0
    }

    /// Sample times: every 1 ms over 60 s (60,001 points, every pass near the poles included).
    fn times() -> impl Iterator<Item = f64> {
        (0..=60_000).map(|i| f64::from(i) * 1e-3)
    }

    /// The Euler angles rebuild the composed rotation Rz(gamma) Ry(alpha) Rz(beta) (entries
    /// within 1e-12: near the pole asin loses digits, 1e-16 / cos(pitch), and on this grid
    /// cos(pitch) stays above 2e-3),
    /// and the body rates are the skew part of R^T dR/dt by central differences of that
    /// rotation (h = 1e-5 s): truncation h^2/6 |R'''| with |R'''| below about 1e3 rad/s^3 is
    /// below 2e-8 rad/s, rounding 1e-16 / h = 1e-11 rad/s; tolerance 1e-5 deg/s (1.7e-7
    /// rad/s).
    #[test]
    fn body_rates_match_finite_differences_of_the_attitude() {
        let h = 1e-5;
        let mut worst = 0.0f64;
        for t in times() {
            let m = at(t);
            let [al, be, ga] = composing_angles(t);
            let composed = mul(&mul(&rz(ga.v), &ry(al.v)), &rz(be.v));
            let r = euler_matrix(&m);
            for i in 0..3 {
                for j in 0..3 {
                    let d = (r[i][j] - composed[i][j]).abs();
                    assert!(d < 1e-12, "R{}{} at {t}: {d}", i + 1, j + 1);
                }
            }
            let (a, b) = (euler_matrix(&at(t - h)), euler_matrix(&at(t + h)));
            // Omega = R^T dR/dt: omega_x = Omega[2][1], omega_y = Omega[0][2], omega_z = Omega[1][0].
            let om = |i: usize, j: usize| {
                (0..3)
                    .map(|k| r[k][i] * (b[k][j] - a[k][j]) / (2.0 * h))
                    .sum::<f64>()
                    .to_degrees()
            };
            let fd = [om(2, 1), om(0, 2), om(1, 0)];
            for (ax, (f, w)) in fd.iter().zip(m.body_rates_deg_s).enumerate() {
                let e = (f - w).abs();
                worst = worst.max(e);
                assert!(e < 1e-5, "axis {ax} at {t}: fd {f} vs {w}");
            }
            // Omega is skew-symmetric: its diagonal is ~0 (a check of the differences).
            assert!(om(0, 0).abs() < 1e-5 && om(2, 2).abs() < 1e-5, "{t}");
        }
        assert!(worst > 0.0);
    }

    /// Away from the pole (|pitch| < 80 deg) central differences of roll, pitch and yaw
    /// (differences wrapped to +-180 deg, h = 1e-5 s) agree with the Euler kinematics applied
    /// to the profile's p, q, r: roll' = p + (q sin phi + r cos phi) tan theta,
    /// pitch' = q cos phi - r sin phi, yaw' = (q sin phi + r cos phi) / cos theta. The
    /// tolerance, 1e-4 deg/s, is the truncation h^2/6 times a third derivative of the angles
    /// up to about 1e6 deg/s^3 at 80 deg, and 1e-13 deg of rounding over 2h.
    #[test]
    fn euler_angle_rates_follow_the_kinematics() {
        let h = 1e-5;
        let mut checked = 0;
        for t in times().skip(1) {
            let m = at(t);
            if m.pitch_deg.abs() >= 80.0 {
                continue;
            }
            let (a, b) = (at(t - h), at(t + h));
            let fd = [
                wrap(b.roll_deg - a.roll_deg) / (2.0 * h),
                (b.pitch_deg - a.pitch_deg) / (2.0 * h),
                wrap(b.yaw_deg - a.yaw_deg) / (2.0 * h),
            ];
            let [p, q, r] = m.body_rates_deg_s;
            let (sf, cf) = m.roll_deg.to_radians().sin_cos();
            let (st, ct) = m.pitch_deg.to_radians().sin_cos();
            let want = [
                p + (q * sf + r * cf) * st / ct,
                q * cf - r * sf,
                (q * sf + r * cf) / ct,
            ];
            for (ax, (f, w)) in fd.iter().zip(want).enumerate() {
                assert!((f - w).abs() < 1e-4, "axis {ax} at {t}: fd {f} vs {w}");
            }
            checked += 1;
        }
        assert!(checked > 55_000, "{checked}");
    }

    /// Over the first minute, every 1 ms: |pitch| above 89.5 deg in at least two separate
    /// passes, near +90 and near -90 deg; 0.5 to 5 % of the points at |pitch| >= 80 deg (and
    /// most at 60-80 deg); |p|, |q|, |r| at most 300 deg/s; at rest at t = 0.
    #[test]
    fn pitch_passes_the_poles_with_bounded_rates() {
        let (mut passes, mut up, mut down, mut above, mut near, mut mid) = (0, 0, 0, false, 0, 0);
        let mut peak = [0.0f64; 3];
        let n = times().count();
        for t in times() {
            let m = at(t);
            let a = m.pitch_deg.abs();
            if a > 89.5 && !above {
                passes += 1;
                if m.pitch_deg > 0.0 {
                    up += 1;
                } else {
                    down += 1;
                }
            }
            above = a > 89.5;
            near += usize::from(a >= 80.0);
            mid += usize::from((60.0..80.0).contains(&a));
            for (pk, w) in peak.iter_mut().zip(m.body_rates_deg_s) {
                *pk = pk.max(w.abs());
            }
        }
        let share = near as f64 / n as f64;
        assert!(passes >= 2 && up >= 1 && down >= 1, "{passes} {up} {down}");
        assert!((0.005..=0.05).contains(&share), "{share}");
        assert!(mid as f64 > 0.8 * n as f64, "{mid}");
        assert!(peak.iter().all(|&w| w <= 300.0), "{peak:?}");
        assert_eq!(at(0.0).body_rates_deg_s, [0.0; 3]);
    }

    /// The derivative rules of [`Jet`] against central differences of a composed function.
    #[test]
    fn jet_derivatives_match_finite_differences() {
        let f = |t: Jet| (t.scale(3.0).sin() * t.cos().scale(2.0).tanh()) - t * t;
        let j = |t: f64| Jet {
            v: t,
            d: 1.0,
            dd: 0.0,
        };
        let h = 1e-4;
        for i in 0..50 {
            let t = -2.0 + 0.083 * f64::from(i);
            let (a, b, c) = (f(j(t - h)), f(j(t)), f(j(t + h)));
            assert!(((c.v - a.v) / (2.0 * h) - b.d).abs() < 1e-6, "{t}");
            assert!(
                ((c.v - 2.0 * b.v + a.v) / (h * h) - b.dd).abs() < 1e-4,
                "{t}"
            );
        }
    }
}
