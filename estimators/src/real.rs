//! The numeric trait every estimator is generic over, implemented for `f32`, `f64` and the
//! saturating fixed-point type [`Fx`].

use core::fmt::{Debug, Display};
use core::ops::{Add, Mul, Neg, Sub};
use fixed::types::I32F32;
use fixed::Saturating;

/// The fixed-point format of the crate: signed Q31.32 (`I32F32`) in 64 bits, wrapped in
/// [`fixed::Saturating`] so that every `+ - *` saturates at the range ends instead of wrapping.
///
/// * Range: `[-2^31, 2^31)` = about +-2.1e9 in the unit of the quantity (deg, deg/s, deg/s^2).
/// * Resolution: `2^-32` = 2.3e-10.
///
/// Why 32 fractional bits: at the paper's step `h = 1e-4 s` the AVE's
/// `deltahat += h * |e|` increment is `1e-4 * |e|`; with 16 fractional bits (resolution 1.5e-5)
/// every increment below 1.5e-5 - that is every `|e| < 0.15 deg` - would truncate to zero and
/// `deltahat` would never learn, and the ILO's `h * L * e` position increments would vanish the
/// same way. With 32 fractional bits the increments are kept down to `|e| ~ 2e-6 deg`, below the
/// NAV440's 0.005 deg yaw resolution. The 31 integer bits hold any yaw unwrapped over millions of
/// turns. Every operation is integer-only (no FPU): a multiply is a 64x64->128-bit product.
pub type Fx = Saturating<I32F32>;

/// A real-number type the estimators compute in: `f32` (Cortex-M4F FPU), `f64` (host
/// reference) or [`Fx`] (fixed point, Cortex-M0/M3 without FPU).
///
/// Where `f32` runs out: its resolution is relative (ulp(100 deg) = 7.6e-6 deg). On an
/// unwrapped yaw after 11 turns (4000 deg, ulp 4.9e-4) the AVE's per-step increments of
/// `0.04 deg` at 400 deg/s rounded to a 0.5 % velocity bias; the [`crate::YawBank`] therefore
/// runs every law on the wrapped yaw in a translated frame ([`crate::Estimator::translate`]).
/// The implicit ED's sliding band `h^2 alpha = 7.7e-6` is below f32's resolution of a
/// 300 deg/s input, so ED-ED differs between `f32` and [`Fx`] (tests/bank.rs).
///
/// Only `+ - *`, comparisons, `abs`, `sqrt` and division by a positive integer are used in the
/// update paths; every coefficient (which may involve division or `exp`) is computed once at
/// construction time in `f64` and converted with [`Real::from_f64`].
pub trait Real:
    Copy
    + PartialOrd
    + Default
    + Debug
    + Display
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Converts from `f64` (rounding for floats, saturating for fixed point; NaN gives 0).
    fn from_f64(x: f64) -> Self;
    /// Converts from `f32` (exact for `f32`/`f64`, saturating for fixed point; NaN gives 0).
    fn from_f32(x: f32) -> Self;
    /// Converts from an integer (saturating for fixed point).
    fn from_i32(x: i32) -> Self;
    /// Converts to `f32` (rounding to nearest for fixed point, via soft-float conversion only).
    fn to_f32(self) -> f32;
    /// Converts to `f64`.
    fn to_f64(self) -> f64;
    /// `|self|` (saturating at the type's maximum for fixed point).
    fn abs(self) -> Self;
    /// Exact square root: IEEE correctly rounded for floats (`libm::sqrtf`/`libm::sqrt`, so
    /// host and MCU agree bit for bit), the `fixed` crate's integer square root for [`Fx`].
    /// Negative arguments give 0.
    fn sqrt(self) -> Self;
    /// `self / n` for an integer `n >= 1` (`n = 0` returns `self`); integer division for fixed
    /// point, so it never needs an FPU.
    fn div_int(self, n: u32) -> Self;
    /// The sign: -1, 0 or +1.
    fn sgn(self) -> Self {
        if self > Self::ZERO {
            Self::ONE
        } else if self < Self::ZERO {
            -Self::ONE
        } else {
            Self::ZERO
        }
    }
    /// The larger of two values.
    fn max(self, other: Self) -> Self {
        if other > self {
            other
        } else {
            self
        }
    }
    /// The smaller of two values.
    fn min(self, other: Self) -> Self {
        if other < self {
            other
        } else {
            self
        }
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn from_f32(x: f32) -> Self {
        x
    }
    #[inline]
    fn from_i32(x: i32) -> Self {
        x as f32
    }
    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        if self > 0.0 {
            libm::sqrtf(self)
        } else {
            0.0
        }
    }
    #[inline]
    fn div_int(self, n: u32) -> Self {
        if n == 0 {
            self
        } else {
            self / n as f32
        }
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn from_f32(x: f32) -> Self {
        f64::from(x)
    }
    #[inline]
    fn from_i32(x: i32) -> Self {
        f64::from(x)
    }
    #[inline]
    fn to_f32(self) -> f32 {
        self as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        if self > 0.0 {
            libm::sqrt(self)
        } else {
            0.0
        }
    }
    #[inline]
    fn div_int(self, n: u32) -> Self {
        if n == 0 {
            self
        } else {
            self / f64::from(n)
        }
    }
}

impl Real for Fx {
    const ZERO: Self = Saturating(I32F32::ZERO);
    const ONE: Self = Saturating(I32F32::ONE);
    #[inline]
    fn from_f64(x: f64) -> Self {
        // `checked_from_num` (not `saturating_from_num`, which panics on NaN) keeps the
        // conversion panic-free; out of range saturates by the sign bit, NaN gives 0.
        match I32F32::checked_from_num(x) {
            Some(v) => Saturating(v),
            None if x.is_nan() => Self::ZERO,
            None if x.is_sign_negative() => Saturating(I32F32::MIN),
            None => Saturating(I32F32::MAX),
        }
    }
    #[inline]
    fn from_f32(x: f32) -> Self {
        match I32F32::checked_from_num(x) {
            Some(v) => Saturating(v),
            None if x.is_nan() => Self::ZERO,
            None if x.is_sign_negative() => Saturating(I32F32::MIN),
            None => Saturating(I32F32::MAX),
        }
    }
    #[inline]
    fn from_i32(x: i32) -> Self {
        Saturating(I32F32::from_num(x))
    }
    #[inline]
    fn to_f32(self) -> f32 {
        self.0.to_num::<f32>()
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self.0.to_num::<f64>()
    }
    #[inline]
    fn abs(self) -> Self {
        Saturating(self.0.saturating_abs())
    }
    #[inline]
    fn sqrt(self) -> Self {
        // Q31.32: sqrt of at most 2^31 is below 2^16, so `checked_sqrt` of a non-negative value
        // never overflows; the fallback arm is unreachable but keeps the path panic-free.
        if self.0 > I32F32::ZERO {
            Saturating(self.0.checked_sqrt().unwrap_or(I32F32::ZERO))
        } else {
            Self::ZERO
        }
    }
    #[inline]
    fn div_int(self, n: u32) -> Self {
        if n == 0 {
            self
        } else {
            Saturating(self.0.saturating_div_int(i64::from(n)))
        }
    }
}

/// The square root the [`crate::Ed`] uses for its `|e|^(1/2)` term (a type parameter, so a
/// firmware can plug in its FPU's square-root instruction without `unsafe` in this crate).
///
/// Contract: `sqrt(x)` for `x >= 0` must return exactly what [`Real::sqrt`] returns (for `f32`:
/// the correctly rounded IEEE 754 root, which the Cortex-M4F `VSQRT.F32` instruction also
/// computes), so that every implementation gives bit-identical estimator outputs.
pub trait SqrtFn<T: Real>: Copy + Default + Debug {
    /// Square root of `x >= 0`.
    fn sqrt(x: T) -> T;
}

/// The portable exact square root, [`Real::sqrt`] (`libm::sqrtf` for `f32`: about 45
/// instructions on a Cortex-M4F, which has no stable Rust path to `VSQRT` without `unsafe`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExactSqrt;

impl<T: Real> SqrtFn<T> for ExactSqrt {
    #[inline]
    fn sqrt(x: T) -> T {
        x.sqrt()
    }
}
