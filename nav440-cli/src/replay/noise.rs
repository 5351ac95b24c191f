//! Measurement noise added to an angle before estimation (the paper's protocol).

use super::*;

/// Gaussian noise added to the angles before estimation (the paper's protocol).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// Variance, deg^2.
    pub var: f64,
    /// Seed of the generator (xoshiro256++, one N(0, var) draw per sample in order). Each axis
    /// has its own generator: yaw seeded with `seed` (so the yaw noise does not depend on the
    /// other axes), roll and pitch with [`axis_seed`].
    pub seed: u64,
}

/// The seed of `axis`'s noise generator for the seed `seed`: `seed` for yaw, `seed` XOR a
/// fixed odd constant per axis for roll and pitch.
pub fn axis_seed(seed: u64, axis: Axis) -> u64 {
    match axis {
        Axis::Yaw => seed,
        Axis::Roll => seed ^ 0x9E37_79B9_7F4A_7C15,
        Axis::Pitch => seed ^ 0xD1B5_4A32_D192_ED03,
    }
}

/// The yaw of each sample plus noise (if any), degrees.
pub fn noisy_yaw(samples: &[Sample], noise: Option<Noise>) -> Result<Vec<f32>> {
    noisy_angle(samples, Axis::Yaw, noise)
}

/// The angle of `axis` of each sample plus noise (if any; the axis's generator, see
/// [`Noise::seed`]), degrees.
pub fn noisy_angle(samples: &[Sample], axis: Axis, noise: Option<Noise>) -> Result<Vec<f32>> {
    match noise {
        None => Ok(samples.iter().map(|s| s.angle(axis)).collect()),
        Some(n) => {
            let normal = Normal::new(0.0, n.var.max(0.0).sqrt())
                .map_err(|e| Error::Usage(format!("bad noise variance {}: {e}", n.var)))?;
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(axis_seed(n.seed, axis));
            Ok(samples
                .iter()
                .map(|s| (f64::from(s.angle(axis)) + normal.sample(&mut rng)) as f32)
                .collect())
        }
    }
}
