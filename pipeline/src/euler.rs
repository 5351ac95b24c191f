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
//! ([`near_lock`], see `crate::Estimation`).
//!
//! The sine and cosine come from an integer CORDIC (`idsp::cos_sin`, 30 rotations on a 32-bit
//! phase; [`sin_cos_deg`]), the rest is `f32`: the same bits on the host and on every firmware
//! target, and no `f64` on the way (a Cortex-M0+ has no FPU; `libm`'s `sincosf` computes its
//! kernels in soft `f64`). The sine and cosine are within 3.3e-7 of the true values at any
//! angle a packet sends (+-180 deg), 1/290 of what its 16-bit angle LSB (0.0055 deg,
//! 9.6e-5 rad) already leaves open. A level unit (roll = pitch = 0) gives exactly p, q, r.

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

/// Phase units (1/2^31 half-turns, `idsp`'s CORDIC phase) per degree.
const PHASE_PER_DEG: f32 = 2_147_483_648.0 / 180.0;

/// The CORDIC's input amplitude: 2^30 / its gain (1.6468), so that its outputs are the cosine
/// and sine times 2^30 (a cosine of 1 fits `i32` with a factor 2 to spare).
const CORDIC_AMPLITUDE: i32 = ((1u32 << 30) as f64 / idsp::CORDIC_CIRCULAR_GAIN) as i32;

/// 2^-30 in `f32`: the CORDIC's outputs as values in [-1, 1] (exact scaling).
const OUTPUT_SCALE: f32 = 1.0 / 1_073_741_824.0;

/// Sine and cosine of `deg` (degrees, finite), `f32`, without `f64` or `libm`.
///
/// The angle becomes a 32-bit phase (1/2^31 half-turns; one `f32` product, truncated, wrapped
/// to a turn), which `idsp::cos_sin`'s CORDIC rotates in integers; its outputs are scaled
/// exactly into `f32`. Error: at most 5e-8 on each (the CORDIC and the `f32` rounding), plus
/// what the product's rounding moves the angle (at most 9e-8 of it in radians, as `deg * PI /
/// 180` in `f32` moves it), checked against `f64` over every 16-bit packet angle in the
/// tests. Exact at the multiples of 90 deg: sin 0 = 0 and cos 0 = 1.
///
/// Never inlined: one copy serves both angles, and the firmware's ELF checks find the
/// kinematics in an image by this name.
#[inline(never)]
pub fn sin_cos_deg(deg: f32) -> (f32, f32) {
    // A packet's angle is within +-180 deg: the product is within +-2^31, and an `i64` holds
    // any other finite one's turns (saturating beyond 4e11 deg, where `f32` has no turn
    // resolution left anyway). Wrapping to `i32` takes whole turns off.
    let phase = (deg * PHASE_PER_DEG) as i64 as i32;
    match phase {
        0 => return (0.0, 1.0),
        0x4000_0000 => return (1.0, 0.0),
        i32::MIN => return (0.0, -1.0),
        -0x4000_0000 => return (-1.0, 0.0),
        _ => {}
    }
    let (c, s) = idsp::cos_sin(CORDIC_AMPLITUDE, 0, phase);
    (s as f32 * OUTPUT_SCALE, c as f32 * OUTPUT_SCALE)
}

/// Euler-angle rates (deg/s) of roll, pitch, yaw (indexed by [`Axis::index`]) from the roll
/// and pitch angles (deg) and the body rates `p, q, r` (deg/s). Roll and yaw rates are `None`
/// when |pitch| >= [`PITCH_LIMIT_DEG`]; any rate is `None` when an input it needs is not
/// finite.
pub fn euler_rates_deg(roll_deg: f32, pitch_deg: f32, pqr_deg_s: [f32; 3]) -> [Option<f32>; 3] {
    let [p, q, r] = pqr_deg_s;
    if !(roll_deg.is_finite() && q.is_finite() && r.is_finite()) {
        return [None; 3];
    }
    let (sp, cp) = sin_cos_deg(roll_deg);
    let q_sin_r_cos = q * sp + r * cp;
    let pitch_rate = q * cp - r * sp;
    if !pitch_deg.is_finite() || near_lock(pitch_deg) {
        return [None, Some(pitch_rate), None];
    }
    let (st, ct) = sin_cos_deg(pitch_deg);
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
    extern crate std;

    use super::*;

    fn close(a: Option<f32>, b: f64, tol: f64) -> bool {
        a.is_some_and(|a| (f64::from(a) - b).abs() <= tol)
    }

    /// `sin_cos_deg` against `f64` at every angle a packet can send (`raw * 360 / 2^16` deg,
    /// exact in `f32`) and at the `f32` angles of +-720 deg in steps of about 0.01 deg: each
    /// within 5e-8 (the CORDIC and the `f32` result) plus 9e-8 of the angle in radians (the
    /// phase product's rounding). The worst case is 0.84 of that bound.
    #[test]
    fn sin_cos_deg_is_within_its_bound_of_f64() {
        let mut worst = 0.0f64;
        let mut check = |deg: f32| {
            let (s, c) = sin_cos_deg(deg);
            let (es, ec) = (f64::from(deg).to_radians()).sin_cos();
            let bound = 5e-8 + 9e-8 * f64::from(deg).to_radians().abs();
            let err = (f64::from(s) - es).abs().max((f64::from(c) - ec).abs());
            assert!(err <= bound, "{deg} deg: ({s}, {c}) against ({es}, {ec})");
            worst = worst.max(err / bound);
        };
        for raw in i16::MIN..=i16::MAX {
            check(f32::from(raw) * 360.0 / 65_536.0);
        }
        for k in -72_000..=72_000 {
            check(k as f32 * 0.01);
        }
        std::println!("worst error / bound: {worst}");
    }

    /// The multiples of 90 deg give the exact values, any number of turns away.
    #[test]
    fn sin_cos_deg_is_exact_at_the_right_angles() {
        for (deg, want) in [
            (0.0, (0.0, 1.0)),
            (90.0, (1.0, 0.0)),
            (180.0, (0.0, -1.0)),
            (-180.0, (0.0, -1.0)),
            (-90.0, (-1.0, 0.0)),
            (270.0, (-1.0, 0.0)),
            (360.0, (0.0, 1.0)),
            (-720.0, (0.0, 1.0)),
        ] {
            assert_eq!(sin_cos_deg(deg), want, "{deg} deg");
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
