//! Integer fast paths of the stepped laws (AVE, ED and their series rows) for [`crate::Fx`].
//!
//! The generic laws compute in [`crate::Fx`] with saturating `+ - *`. The kernels here compute
//! the **same expression trees** on the raw Q31.32 `i64` bits with *checked* operations and
//! multiplies specialised to the kind of each coefficient (a fraction in `[0, 1/2)`: two
//! 32 x 32-bit products, no overflow possible; an `i32`-sized operand: one product). Whenever
//! no operation of an interval would saturate, every intermediate is the exact integer the
//! saturating code computes, so the results are bit for bit those of the generic path. When
//! any operation would leave the `i64` range (never on a physical input: the states stay
//! within a few thousand deg, deg/s, deg/s^2 and the range is +-2^31), the kernel gives up and
//! the caller runs the generic saturating path on the untouched state. Either way the output
//! is a deterministic function of the inputs, the same on every target.
//!
//! See docs/FIXED-POINT.md for the measured cost.

use crate::real::{fx_mul, fx_mul_frac, smul32u};
use crate::{Hold, Real};

/// A coefficient in `[0, 1/2)` as raw Q0.32 bits below 2^31 (so it is also a positive `i32`).
pub(crate) fn frac<T: Real>(c: T) -> Option<i32> {
    let b = c.fx_bits()?;
    i32::try_from(b).ok().filter(|x| *x >= 0)
}

/// `floor(c x / 2^32)` for a fraction `c` from [`frac`]: the exact Q31.32 product `c * x`
/// (what `fx_mul` returns), never out of range (`|c x| < |x| / 2`).
#[inline(always)]
pub(crate) fn mulf(c: i32, x: i64) -> i64 {
    // x = xh 2^32 + xl: c x / 2^32 = xh c + c xl / 2^32, the first term an integer.
    let xh = (x >> 32) as i32;
    let xl = x as u32;
    i64::from(xh) * i64::from(c) + ((u64::from(xl) * u64::from(c as u32)) >> 32) as i64
}

/// A general Q31.32 coefficient `c = hi + lo / 2^32`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coef {
    raw: i64,
    hi: i32,
    lo: u32,
}

impl Coef {
    pub(crate) fn of<T: Real>(c: T) -> Option<Self> {
        let raw = c.fx_bits()?;
        Some(Self {
            raw,
            hi: (raw >> 32) as i32,
            lo: raw as u32,
        })
    }

    /// The exact `c * x` (Q31.32) for `x` a 32-bit raw value: `hi x + floor(lo x / 2^32)`;
    /// `|hi x| < 2^62`, so it cannot overflow.
    #[inline(always)]
    pub(crate) fn mul_i32(&self, x: i32) -> i64 {
        let p = i64::from(self.hi) * i64::from(x);
        if self.lo == 0 {
            p
        } else {
            p + (smul32u(x, self.lo) >> 32)
        }
    }

    /// The Q31.32 product `c * x`, `None` when it would saturate (or is exactly at an end of
    /// the range: the caller then takes the generic path, which gives the same value).
    #[inline(always)]
    pub(crate) fn mul(&self, x: i64) -> Option<i64> {
        if let Ok(x32) = i32::try_from(x) {
            return Some(self.mul_i32(x32));
        }
        mul_checked(self.raw, x)
    }
}

/// `fx_mul(a, b)` or `None` at the range ends (possible saturation).
#[cold]
#[inline(never)]
pub(crate) fn mul_checked(a: i64, b: i64) -> Option<i64> {
    let r = fx_mul(a, b);
    if r == i64::MAX || r == i64::MIN {
        None
    } else {
        Some(r)
    }
}

/// `floor(c x / 2^32)` for any raw fraction `c < 2^32` (see `fx_mul_frac`).
#[allow(dead_code)]
#[inline(always)]
pub(crate) fn mulf_u(c: u32, x: i64) -> i64 {
    fx_mul_frac(c, x)
}

/// The inputs of the `n` steps of one interval, as [`crate::law::step_n`] presents them:
/// `(first, inc)` such that steps `1 .. n-1` see `first + j inc` (accumulated with `+`, as the
/// generic loop does) and the last step sees `y_new`. `None` if `T` is not [`crate::Fx`].
#[inline(always)]
pub(crate) fn inputs<T: Real>(y_prev: T, y_new: T, n: u32, hold: Hold) -> Option<(i64, i64, i64)> {
    match hold {
        // Every step sees y_new: start there and add 0.
        Hold::ZeroOrder => Some((y_new.fx_bits()?, 0, y_new.fx_bits()?)),
        Hold::Linear => {
            let inc = (y_new - y_prev).div_int(n);
            Some((y_prev.fx_bits()?, inc.fx_bits()?, y_new.fx_bits()?))
        }
    }
}
