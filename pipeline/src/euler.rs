//! The reference rate of each angle: its time derivative from the body rates through the
//! Euler kinematics (aerospace sequence yaw psi, pitch theta, roll phi):
//!
//! * roll:  phi'   = p + (q sin phi + r cos phi) tan theta
//! * pitch: theta' = q cos phi - r sin phi
//! * yaw:   psi'   = (q sin phi + r cos phi) / cos theta
//!
//! with the body rates p, q, r (x, y, z) and the angles as the packet sends them. Roll and yaw
//! rates divide by cos theta: near |pitch| = 90 deg (gimbal lock) they are undefined and
//! amplify every error of q, r and the angles by 1 / cos theta. Beyond [`PITCH_LIMIT_DEG`] they
//! are not given (`None`: an empty CSV field, left out of every MSE); the pitch rate is defined
//! at any pitch. The same limit decides where the roll and yaw banks are not fed
//! ([`near_lock`], see `crate::Estimation`). Computed in `f32` with `libm` on every target, so the host and the firmware
//! give the same bits. A level unit (roll = pitch = 0) gives exactly p, q, r.

use crate::Axis;

/// Largest |pitch| (deg) at which the roll and yaw reference rates are given: 80 deg, where
/// 1 / cos theta = 5.76 (a 0.1 deg/s gyro error becomes at most 0.58 deg/s of reference
/// error; one pitch LSB of 0.0055 deg changes tan theta by 0.2 %). At |pitch| >= 80 deg they
/// are `None`.
pub const PITCH_LIMIT_DEG: f32 = 80.0;

/// `true` when `pitch_deg` is a finite pitch (deg) with |pitch| >= [`PITCH_LIMIT_DEG`]: the
/// samples where the roll and yaw angles swing with the heading of the pole rather than with
/// the body's motion. The pipeline does not feed the roll and yaw banks there and restarts them
/// when the pitch returns below the limit.
pub fn near_lock(pitch_deg: f32) -> bool {
    // `|pitch| >= limit` on the bit patterns (ordered like the magnitudes of non-NaN floats):
    // the same answer as the float comparison without a soft-float call on an FPU-less core.
    let a = pitch_deg.to_bits() & 0x7FFF_FFFF;
    a >= PITCH_LIMIT_DEG.to_bits() && a <= f32::INFINITY.to_bits()
}

/// Degrees to radians in `f32`.
const DEG_TO_RAD: f32 = core::f32::consts::PI / 180.0;

/// Euler-angle rates (deg/s) of roll, pitch, yaw (indexed by [`Axis::index`]) from the roll
/// and pitch angles (deg) and the body rates `p, q, r` (deg/s). Roll and yaw rates are `None`
/// when |pitch| >= [`PITCH_LIMIT_DEG`]; any rate is `None` when an input it needs is not
/// finite.
pub fn euler_rates_deg(roll_deg: f32, pitch_deg: f32, pqr_deg_s: [f32; 3]) -> [Option<f32>; 3] {
    let [p, q, r] = pqr_deg_s;
    if !(roll_deg.is_finite() && q.is_finite() && r.is_finite()) {
        return [None; 3];
    }
    let phi = roll_deg * DEG_TO_RAD;
    let (sp, cp) = libm::sincosf(phi);
    let q_sin_r_cos = q * sp + r * cp;
    let pitch_rate = q * cp - r * sp;
    if !pitch_deg.is_finite() || near_lock(pitch_deg) {
        return [None, Some(pitch_rate), None];
    }
    let theta = pitch_deg * DEG_TO_RAD;
    let (st, ct) = libm::sincosf(theta);
    let roll_rate = p.is_finite().then(|| p + q_sin_r_cos * st / ct);
    let yaw_rate = q_sin_r_cos / ct;
    [roll_rate, Some(pitch_rate), Some(yaw_rate)]
}

/// The reference rate of one axis (deg/s), see [`euler_rates_deg`].
pub fn euler_rate_deg(axis: Axis, angles_deg: [f32; 3], pqr_deg_s: [f32; 3]) -> Option<f32> {
    euler_rates_deg(angles_deg[0], angles_deg[1], pqr_deg_s)[axis.index()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Option<f32>, b: f64, tol: f64) -> bool {
        a.is_some_and(|a| (f64::from(a) - b).abs() <= tol)
    }

    /// Level: exactly the body rates.
    /// `sincosf` (one argument reduction for both) returns exactly `sinf` and `cosf`: checked
    /// here on every 64th f32 of +-4 rad (+-229 deg; every f32 of that range was compared
    /// once, 2.16e9 values, none differed), so the reference column is the same text as with
    /// the two calls.
    #[test]
    fn sincosf_is_sinf_and_cosf() {
        for bits in (0u32..=0x4080_0000).step_by(64) {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                let (s, c) = libm::sincosf(x);
                assert_eq!(s.to_bits(), libm::sinf(x).to_bits(), "sin {x}");
                assert_eq!(c.to_bits(), libm::cosf(x).to_bits(), "cos {x}");
            }
        }
    }

    #[test]
    fn level_gives_the_body_rates_exactly() {
        let r = euler_rates_deg(0.0, 0.0, [1.25, -3.5, 42.0]);
        assert_eq!(r, [Some(1.25), Some(-3.5), Some(42.0)]);
    }

    /// phi = 30, theta = 45 deg, p, q, r = 1, 2, 3 deg/s; values by hand with
    /// sin 30 = 1/2, cos 30 = sqrt(3)/2, tan 45 = 1, cos 45 = 1/sqrt(2):
    /// phi' = 1 + (1 + 1.5 sqrt 3) = 4.598076, theta' = sqrt 3 - 1.5 = 0.232051,
    /// psi' = (1 + 1.5 sqrt 3) sqrt 2 = 5.088448.
    #[test]
    fn hand_computed_values() {
        let s3 = 3f64.sqrt();
        let r = euler_rates_deg(30.0, 45.0, [1.0, 2.0, 3.0]);
        assert!(close(r[0], 2.0 + 1.5 * s3, 1e-5), "{r:?}");
        assert!(close(r[1], s3 - 1.5, 1e-5), "{r:?}");
        assert!(close(r[2], (1.0 + 1.5 * s3) * 2f64.sqrt(), 1e-5), "{r:?}");
    }

    /// Rolled upside down (phi = 180 deg), level pitch: psi' = -r, theta' = -q, phi' = p.
    #[test]
    fn upside_down_reverses_yaw_and_pitch() {
        let r = euler_rates_deg(180.0, 0.0, [5.0, 7.0, 11.0]);
        assert!(close(r[0], 5.0, 1e-5));
        assert!(close(r[1], -7.0, 1e-5));
        assert!(close(r[2], -11.0, 1e-5));
    }

    /// `near_lock` on the bit patterns gives the float comparison: every exponent with edge
    /// mantissas, both signs, NaN, the infinities and the limit's neighbours.
    #[test]
    fn near_lock_is_the_float_comparison() {
        let limit = PITCH_LIMIT_DEG.to_bits();
        let check = |b: u32| {
            for x in [f32::from_bits(b), -f32::from_bits(b)] {
                assert_eq!(near_lock(x), x.abs() >= PITCH_LIMIT_DEG, "{x:e}");
            }
        };
        for e in 0..=255u32 {
            for m in [0u32, 1, 0x40_0000, 0x7F_FFFF] {
                check((e << 23) | m);
            }
        }
        for b in [limit - 1, limit, limit + 1] {
            check(b);
        }
    }

    /// Beyond the pitch limit: roll and yaw rates are not given, the pitch rate is.
    #[test]
    fn gimbal_lock_limit() {
        let r = euler_rates_deg(10.0, 80.0, [1.0, 2.0, 3.0]);
        assert_eq!((r[0], r[2]), (None, None));
        assert!(r[1].is_some());
        let r = euler_rates_deg(10.0, -79.99, [1.0, 2.0, 3.0]);
        assert!(r.iter().all(Option::is_some));
        assert_eq!(euler_rates_deg(f32::NAN, 0.0, [1.0, 2.0, 3.0]), [None; 3]);
        assert_eq!(
            euler_rate_deg(Axis::Yaw, [0.0, 0.0, 100.0], [1.0, 2.0, 3.0]),
            Some(3.0)
        );
    }
}
