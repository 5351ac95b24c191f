//! The numeric trait every estimator is generic over, implemented for `f32`, `f64` and the
//! saturating fixed-point type [`Fx`].

use core::fmt::{Debug, Display};
use core::ops::{Add, Mul, Neg, Sub};
use fixed::types::I32F32;

/// The fixed-point format of the crate: signed Q31.32 (`I32F32`) in 64 bits, saturating: every
/// `+ - *` saturates at the range ends instead of wrapping. The values and results are those of
/// [`fixed::Saturating`]`<I32F32>` bit for bit (multiplication rounds toward minus infinity,
/// the square root down); the multiply and the square root are this crate's own integer code,
/// written for 32-bit cores (`fx_mul`, `fx_sqrt`; see docs/FIXED-POINT.md).
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
/// turns. Every operation is integer-only (no FPU).
#[derive(Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Fx(I32F32);

impl Fx {
    /// The value with raw bits `bits` (`bits / 2^32`).
    #[inline]
    pub const fn from_bits(bits: i64) -> Self {
        Self(I32F32::from_bits(bits))
    }

    /// The raw bits (`self * 2^32`).
    #[inline]
    pub const fn to_bits(self) -> i64 {
        self.0.to_bits()
    }
}

impl Debug for Fx {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        Debug::fmt(&self.0, f)
    }
}

impl Display for Fx {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        Display::fmt(&self.0, f)
    }
}

impl Add for Fx {
    type Output = Fx;
    #[inline(always)]
    fn add(self, o: Fx) -> Fx {
        Fx::from_bits(self.to_bits().saturating_add(o.to_bits()))
    }
}

impl Sub for Fx {
    type Output = Fx;
    #[inline(always)]
    fn sub(self, o: Fx) -> Fx {
        Fx::from_bits(self.to_bits().saturating_sub(o.to_bits()))
    }
}

impl Neg for Fx {
    type Output = Fx;
    #[inline(always)]
    fn neg(self) -> Fx {
        Fx::from_bits(self.to_bits().saturating_neg())
    }
}

impl Mul for Fx {
    type Output = Fx;
    #[inline]
    fn mul(self, o: Fx) -> Fx {
        Fx::from_bits(fx_mul(self.to_bits(), o.to_bits()))
    }
}

/// `a * b` of two 32-bit numbers as 64 bits. On Cortex-M0 (thumbv6m: no long multiply; the
/// only 32-bit Arm target without 32-bit atomics) [`umul32_split`] instead of the 64 x 64-bit
/// library multiply; elsewhere the native product (`UMULL`).
#[inline(always)]
pub(crate) fn umul32(a: u32, b: u32) -> u64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        umul32_split(a, b)
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        u64::from(a) * u64::from(b)
    }
}

/// `a * b` from four 16 x 16 -> 32-bit products (`MULS`), carries propagated.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn umul32_split(a: u32, b: u32) -> u64 {
    let (a0, a1) = (a & 0xFFFF, a >> 16);
    let (b0, b1) = (b & 0xFFFF, b >> 16);
    let lo = a0 * b0;
    let (mid, c) = (a1 * b0).overflowing_add(a0 * b1);
    let (low, c2) = lo.overflowing_add(mid << 16);
    let high = a1 * b1 + (mid >> 16) + (u32::from(c) << 16) + u32::from(c2);
    (u64::from(high) << 32) | u64::from(low)
}

/// `a * b` of two signed 32-bit numbers as 64 bits. On Cortex-M0 one `MULS` when both fit in
/// 16 bits (the high words of the bank's values and coefficients: |x| < 32768), else the
/// library multiply; elsewhere the native product (`SMULL`).
#[inline(always)]
pub(crate) fn smul32(a: i32, b: i32) -> i64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        if a as i16 as i32 == a && b as i16 as i32 == b {
            return i64::from(a * b);
        }
    }
    i64::from(a) * i64::from(b)
}

/// `a * b` of a signed and an unsigned 32-bit number (`|a b| < 2^63`), from the unsigned
/// unsigned product (one [`umul32`]).
#[inline(always)]
pub(crate) fn smul32u(a: i32, b: u32) -> i64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        // Cortex-M0: the sign handled apart, so that the compiler keeps `umul32_split` (it
        // turns the two's-complement form below back into a library call).
        let p = umul32(a.unsigned_abs(), b) as i64;
        if a < 0 {
            -p
        } else {
            p
        }
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        // a b = (a mod 2^32) b - [a < 0] b 2^32, wrapping (the true product fits).
        (umul32(a as u32, b) as i64).wrapping_sub(if a < 0 { i64::from(b) << 32 } else { 0 })
    }
}

/// The Q31.32 saturating product of raw values `a`, `b`: `floor(a b / 2^32)`, saturated to
/// the `i64` range (exactly `fixed::Saturating<I32F32>`'s multiply).
///
/// With `a = ah 2^32 + al` (`ah` signed, `al` unsigned 32-bit halves) and `b` alike,
/// `floor(a b / 2^32) = ah bh 2^32 + ah bl + al bh + floor(al bl / 2^32)`: four 32 x 32-bit
/// products (two when `a` or `b` is in `[0, 1)`, [`fx_mul_frac`], or `a` is an integer on
/// the M0, [`fx_mul_int`]). Summed two ways, both exact for every
/// input and chosen by what the target runs faster: [`fx_mul_carry`] (Cortex-M3 and others)
/// or [`fx_mul_checked`] (Cortex-M0).
#[inline(always)]
pub fn fx_mul(a: i64, b: i64) -> i64 {
    if a >> 32 == 0 {
        return fx_mul_frac(a as u32, b);
    }
    if b >> 32 == 0 {
        return fx_mul_frac(b as u32, a);
    }
    // Cortex-M0 only: on the M3 the extra test costs more than it saves (measured).
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    if a as u32 == 0 {
        return fx_mul_int((a >> 32) as i32, b);
    }
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        fx_mul_checked(a, b)
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        fx_mul_carry(a, b)
    }
}

/// [`fx_mul`] for `a` in `[0, 1)` (raw `al` below 2^32: the bank's coefficients `h`, `h k`,
/// `h sigma`, `h alpha`, most map entries, written first in every product): `ah = 0`, so
/// `floor(a b / 2^32) = bh al + floor(al bl / 2^32)`, two products; the sum cannot overflow
/// and is never out of range (`|a b| < |b|`).
#[inline(always)]
fn fx_mul_frac(al: u32, b: i64) -> i64 {
    let (bh, bl) = ((b >> 32) as i32, b as u32);
    smul32u(bh, al) + (umul32(al, bl) >> 32) as i64
}

/// [`fx_mul`] for an integer `a = ah` (raw `al = 0`: the coefficients `h gamma1 = 2`,
/// `lambda = 700`, `1 / T = 100`): `a b = ah bh 2^32 + ah bl` exactly, two products, saturated
/// when the high part leaves 32 signed bits.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn fx_mul_int(ah: i32, b: i64) -> i64 {
    let (bh, bl) = ((b >> 32) as i32, b as u32);
    let m1 = smul32u(ah, bl);
    let high = smul32(ah, bh) + (m1 >> 32);
    if (-(1i64 << 31)..(1i64 << 31)).contains(&high) {
        (high << 32) | i64::from(m1 as u32)
    } else if high > 0 {
        i64::MAX
    } else {
        i64::MIN
    }
}

/// The four partial products of [`fx_mul`]: `(ah bh, ah bl, al bh, floor(al bl / 2^32))`.
#[inline(always)]
fn partial_products(a: i64, b: i64) -> (i64, i64, i64, i64) {
    let (ah, al) = ((a >> 32) as i32, a as u32);
    let (bh, bl) = ((b >> 32) as i32, b as u32);
    let lo = (umul32(al, bl) >> 32) as i64;
    (smul32(ah, bh), smul32u(ah, bl), smul32u(bh, al), lo)
}

/// [`fx_mul`] summed as a low word with its carries and a high part that cannot overflow: the
/// result is in range exactly when the high part fits 32 signed bits, and saturates by its
/// sign otherwise.
#[cfg_attr(
    all(target_arch = "arm", not(target_has_atomic = "32")),
    allow(dead_code)
)]
#[inline(always)]
fn fx_mul_carry(a: i64, b: i64) -> i64 {
    let (hh, m1, m2, lo) = partial_products(a, b);
    // S = hh 2^32 + m1 + m2 + lo = high 2^32 + (low mod 2^32), exactly, with
    // low = (m1 mod 2^32) + (m2 mod 2^32) + lo < 3 2^32 and
    // high = hh + floor(m1 / 2^32) + floor(m2 / 2^32) + floor(low / 2^32) (|high| < 2^63).
    let low = u64::from(m1 as u32) + u64::from(m2 as u32) + lo as u64;
    let high = hh + (m1 >> 32) + (m2 >> 32) + (low >> 32) as i64;
    if (-(1i64 << 31)..(1i64 << 31)).contains(&high) {
        (high << 32) | i64::from(low as u32)
    } else if high > 0 {
        i64::MAX
    } else {
        i64::MIN
    }
}

/// [`fx_mul`] summed with overflow checks; any overflow (a result out of range, or an
/// intermediate one) takes the exact 128-bit fallback [`fx_mul_wide`].
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn fx_mul_checked(a: i64, b: i64) -> i64 {
    let (hh, m1, m2, lo) = partial_products(a, b);
    if (-(1i64 << 31)..(1i64 << 31)).contains(&hh) {
        if let Some(r) = (hh << 32)
            .checked_add(m1)
            .and_then(|x| x.checked_add(m2))
            .and_then(|x| x.checked_add(lo))
        {
            return r;
        }
    }
    fx_mul_wide(a, b)
}

/// The exact 128-bit product of [`fx_mul_checked`], saturated (its rare fallback).
#[cold]
#[inline(never)]
fn fx_mul_wide(a: i64, b: i64) -> i64 {
    let p = (i128::from(a) * i128::from(b)) >> 32;
    if p > i128::from(i64::MAX) {
        i64::MAX
    } else if p < i128::from(i64::MIN) {
        i64::MIN
    } else {
        p as i64
    }
}

/// The raw Q31.32 value of `x`: rounded to the nearest (ties to even), saturated to the
/// range by the sign, NaN to 0 (what `I32F32::checked_from_num` gives where it succeeds, and
/// the saturation [`Real::from_f32`] documents where it fails). Integer operations only: on a
/// core without an FPU it costs a few shifts instead of `fixed`'s generic conversion.
#[inline]
pub(crate) fn fx_from_f32(x: f32) -> i64 {
    match f32_scaled(x) {
        Some((m, e)) => fx_from_scaled(m, e),
        // NaN gives 0, an infinity saturates by its sign.
        None if x.to_bits() & 0x007F_FFFF != 0 => 0,
        None if x.to_bits() >> 31 != 0 => i64::MIN,
        None => i64::MAX,
    }
}

/// A finite `f32` as `(m, e)` with `x = m * 2^e` exactly and `|m| < 2^24` (what
/// [`crate::EstimatorBank::update_scaled`] takes); `None` for NaN and the infinities. Both
/// zeros give `(0, -149)`. Integer operations only.
#[inline]
pub fn f32_scaled(x: f32) -> Option<(i32, i32)> {
    let b = x.to_bits();
    let exp = ((b >> 23) & 0xFF) as i32;
    if exp == 0xFF {
        return None;
    }
    let frac = (b & 0x007F_FFFF) as i32;
    let (m, e) = if exp == 0 {
        (frac, -149)
    } else {
        (frac | 0x0080_0000, exp - 150)
    };
    Some((if b >> 31 == 0 { m } else { -m }, e))
}

/// The raw bits of `raw * 2^exp2` in Q31.32 ([`Real::from_scaled`] for [`Fx`]): `raw` shifted
/// by `exp2 + 32`, saturated when it leaves the range, rounded to nearest (ties to even) when
/// bits fall off.
#[inline(always)]
fn fx_from_scaled(raw: i32, exp2: i32) -> i64 {
    let shift = exp2 + 32;
    // |raw| < 2^31: a shift by at most 32 stays within i64 (the usual case: a sensor's LSB
    // between 2^-32 and 1). Built from 32-bit shifts (a 64-bit shift by a variable is a
    // library call on the Cortex-M0): the low word `raw << shift`, the high word the bits
    // shifted out, sign-extended.
    if (0..32).contains(&shift) {
        let lo = (raw as u32) << shift;
        let hi = if shift == 0 {
            raw >> 31
        } else {
            raw >> (32 - shift)
        };
        return (i64::from(hi) << 32) | i64::from(lo);
    }
    fx_from_scaled_wide(raw, shift)
}

/// [`fx_from_scaled`] for a shift outside `0..=32`.
#[cold]
#[inline(never)]
fn fx_from_scaled_wide(raw: i32, shift: i32) -> i64 {
    let raw = i64::from(raw);
    if shift >= 0 {
        let k = shift.min(63) as u32;
        let v = raw.wrapping_shl(k);
        if v >> k == raw {
            return v;
        }
        return if raw > 0 {
            i64::MAX
        } else if raw < 0 {
            i64::MIN
        } else {
            0
        };
    }
    let k = (-shift).min(40) as u32;
    let q = raw >> k;
    let r = raw - (q << k);
    let half = 1i64 << (k - 1);
    if r > half || (r == half && q & 1 == 1) {
        q + 1
    } else {
        q
    }
}

/// [`Real::unwrapped_angle`] in `f64` (soft-float on Cortex-M: out of line, taken only after
/// a turn).
#[cold]
#[inline(never)]
fn unwrapped_angle_f64<T: Real>(turns: i64, wrapped: T) -> (f32, f64) {
    let exact = turns as f64 * 360.0 + wrapped.to_f64();
    let rounded = exact as f32;
    (rounded, exact - f64::from(rounded))
}

/// [`Real::unwrapped_angle`] for [`Fx`]: integer operations only. Without a turn the angle
/// is the raw value itself; its `f32` rounding is [`fx_to_f32`] and the residual is 0
/// whenever the value is an `f32` (the usual case: the banks' input is an `f32`).
#[inline]
fn fx_unwrapped_angle(turns: i64, wrapped: i64) -> (f32, f64) {
    if turns == 0 {
        let r = fx_to_f32(wrapped);
        if fx_from_f32(r) == wrapped {
            return (r, 0.0);
        }
    }
    fx_unwrapped_angle_wide(turns, wrapped)
}

/// [`fx_unwrapped_angle`] after a turn (or with a residual), in 128-bit integers: the exact
/// angle `(360 turns) 2^32 + wrapped` in units of 2^-32 deg, its nearest `f32` and the
/// nearest `f64` to the residual (exact for any angle below 2^40 deg).
#[cold]
#[inline(never)]
fn fx_unwrapped_angle_wide(turns: i64, wrapped: i64) -> (f32, f64) {
    let exact = i128::from(turns) * (360i128 << 32) + i128::from(wrapped);
    let (rounded, back) = q32_nearest(exact, 24);
    let (residual, _) = q32_nearest(exact - back, 53);
    (f32::from_bits(rounded as u32), f64::from_bits(residual))
}

/// The float with a `precision`-bit significand (24: `f32`, otherwise 53: `f64`) nearest to
/// `x 2^-32` (ties to even): its bits, and its value again in units of 2^-32 (exact: every
/// such float with `|x| >= 1` is a multiple of 2^-32 here, as the ones below are exact).
/// Integer operations only; `x = 0` gives `+0`. One out-of-line copy for both precisions.
#[inline(never)]
fn q32_nearest(x: i128, precision: u32) -> (u64, i128) {
    if x == 0 {
        return (0, 0);
    }
    let (sign, fraction_bits, bias, precision) = if precision == 24 {
        (1u64 << 31, 23u32, 127i32, 24u32)
    } else {
        (1u64 << 63, 52, 1023, 53)
    };
    let neg = x < 0;
    let mag = x.unsigned_abs();
    // The leading one at bit `p`: |x 2^-32| in [2^(p - 32), 2^(p - 31)).
    let mut p = 127 - mag.leading_zeros();
    let mut q = if p < precision {
        mag << (precision - 1 - p)
    } else {
        let k = p + 1 - precision;
        let q = mag >> k;
        let r = mag & ((1u128 << k) - 1);
        let half = if k == 0 { 0 } else { 1u128 << (k - 1) };
        if k > 0 && (r > half || (r == half && q & 1 == 1)) {
            q + 1
        } else {
            q
        }
    };
    if q == 1u128 << precision {
        // Rounded up to the next power of two.
        q >>= 1;
        p += 1;
    }
    // The value q 2^(p + 1 - precision) in units of 2^-32.
    let shift = p as i32 + 1 - precision as i32;
    let back = if shift >= 0 { q << shift } else { q >> -shift };
    let back = if neg { -(back as i128) } else { back as i128 };
    let exponent = (p as i32 - 32 + bias) as u64;
    let bits = (if neg { sign } else { 0 })
        | (exponent << fraction_bits)
        | (q as u64 & ((1u64 << fraction_bits) - 1));
    (bits, back)
}

/// The `f32` nearest to the raw Q31.32 value `raw` (ties to even), as `fixed`'s
/// `to_num::<f32>` gives it. Integer operations only.
#[inline]
pub(crate) fn fx_to_f32(raw: i64) -> f32 {
    if raw == 0 {
        return 0.0;
    }
    let sign = if raw < 0 { 1u32 << 31 } else { 0 };
    let mag = raw.unsigned_abs();
    // The leading one at bit `p`: |x| = mag 2^-32 in [2^(p - 32), 2^(p - 31)), a normal f32.
    let p = 63 - mag.leading_zeros();
    let (mut q, mut p) = if p <= 23 {
        (mag << (23 - p), p)
    } else {
        let k = p - 23;
        let q = mag >> k;
        let r = mag & ((1u64 << k) - 1);
        let half = 1u64 << (k - 1);
        let q = if r > half || (r == half && q & 1 == 1) {
            q + 1
        } else {
            q
        };
        (q, p)
    };
    if q == 1 << 24 {
        // Rounded up to the next power of two.
        q >>= 1;
        p += 1;
    }
    // Biased exponent: (p - 32) + 127.
    f32::from_bits(sign | ((p + 95) << 23) | (q as u32 & 0x7F_FFFF))
}

/// `1 / sqrt(X)` in Q1.31 at the middle of each eighth of `X` in `[1, 4)` (`X = (i + 0.5) / 8`
/// for `i = 8 .. 31`): the start of [`isqrt64`]'s Newton iteration (about 5 bits).
const RSQRT_SEED: [u32; 24] = [
    2_083_365_155,
    1_970_666_148,
    1_874_477_404,
    1_791_125_178,
    1_717_986_918,
    1_653_133_683,
    1_595_110_809,
    1_542_797_797,
    1_495_315_679,
    1_451_963_954,
    1_412_176_548,
    1_375_490_368,
    1_341_522_400,
    1_309_952_745,
    1_280_511_845,
    1_252_970_736,
    1_227_133_513,
    1_202_831_433,
    1_179_918_260,
    1_158_266_544,
    1_137_764_631,
    1_118_314_230,
    1_099_828_424,
    1_082_230_034,
];

/// `floor(sqrt(n))`, exact, with 32-bit multiplies only: `n` is normalised to
/// `m = n 4^k` in `[2^62, 2^64)`, `1/sqrt` of its top 32 bits is refined by three Newton steps
/// `y <- y (3 - X y^2) / 2` from [`RSQRT_SEED`] (about 28 bits), `sqrt(m) ~ X y`, and the
/// estimate is corrected by whole units until `s^2 <= m < (s + 1)^2` (exact whatever the
/// estimate; it is off by a few units). The result is `floor(sqrt(m)) / 2^k`.
#[inline]
pub fn isqrt64(n: u64) -> u32 {
    if n == 0 {
        return 0;
    }
    let e = n.leading_zeros() & !1;
    let m = n << e;
    let x = (m >> 32) as u32; // X = x / 2^30 in [1, 4)
    let idx = ((x >> 27) as usize).saturating_sub(8);
    let mut y = RSQRT_SEED.get(idx).copied().unwrap_or(1 << 30); // Q1.31
    for _ in 0..3 {
        let y2 = (umul32(y, y) >> 31) as u32; // y^2, Q1.31
        let xy2 = (umul32(x, y2) >> 31) as u32; // X y^2 / 2, Q1.31 (about 0.5)
        let t = (3u32 << 29).wrapping_sub(xy2 >> 1); // (3 - X y^2) / 2, Q2.30
        y = (umul32(y, t) >> 30) as u32; // Q1.31
    }
    // sqrt(m) = sqrt(X) 2^31 = X y 2^31: (x / 2^30) (y / 2^31) 2^31 = x y / 2^30.
    let mut s = (umul32(x, y) >> 30).min(u64::from(u32::MAX)) as u32;
    while umul32(s, s) > m {
        s -= 1;
    }
    while s < u32::MAX && umul32(s + 1, s + 1) <= m {
        s += 1;
    }
    s >> (e / 2)
}

/// The Q31.32 square root of raw `r`: `floor(sqrt(r 2^32))` (0 for `r <= 0`), exact.
///
/// `r < 2^32` (values below 1, the ED's usual `|e|`): [`isqrt64`] of `r 2^32`. Larger `r`:
/// [`isqrt64`] of `r 4^j` (`4^j r < 2^64`) gives the root's leading bits and its remainder;
/// the remaining `16 - j` bits come from the binary digit-by-digit method on the remainder.
#[inline]
pub fn fx_sqrt(r: i64) -> i64 {
    if r <= 0 {
        return 0;
    }
    let r = r as u64;
    if r >> 32 == 0 {
        return i64::from(isqrt64(r << 32));
    }
    let e = r.leading_zeros() & !1; // < 32
    let m = r << e;
    let mut root = u64::from(isqrt64(m));
    let mut rem = m - umul32(root as u32, root as u32); // <= 2 root < 2^33
    for _ in 0..(32 - e) / 2 {
        rem <<= 2;
        let t = (root << 2) | 1;
        if rem >= t {
            rem -= t;
            root = (root << 1) | 1;
        } else {
            root <<= 1;
        }
    }
    root as i64
}

/// A real-number type the estimators compute in: `f32` (Cortex-M4F FPU), `f64` (host
/// reference) or [`Fx`] (fixed point, Cortex-M0/M3 without FPU).
///
/// Where `f32` runs out: its resolution is relative (ulp(100 deg) = 7.6e-6 deg). On an
/// unwrapped yaw after 11 turns (4000 deg, ulp 4.9e-4) the AVE's per-step increments of
/// `0.04 deg` at 400 deg/s rounded to a 0.5 % velocity bias; the [`crate::PaperBank`] therefore
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
    /// How many steps `h` the AVE advances in one Euler step inside an interval
    /// (docs/FIXED-POINT.md, "The AVE row at `2 h`"): 1 for `f32` and `f64` (every step is a step `h`); 2 for
    /// [`Fx`], whose AVE and AVE-AVE run `floor(n / 2)` Euler steps of `2 h` per interval of
    /// `n` steps and the remainder (`n` odd) as one step `h`, with coefficients computed for
    /// `2 h` (`AveParams` keeps both sets; see `Law::coarse`). Halves the fixed-point AVE row's
    /// cost on the no-FPU targets; the accuracy bound is the test `fixed_point` of
    /// `tests/bank.rs` (`cargo test --release -p velocity-estimators --test bank fixed_point --
    /// --nocapture` prints the figures).
    const AVE_STEP_FACTOR: u32;
    /// Storage of a law's coarse-step parameters (`Law::coarse`): zero-sized
    /// (`PhantomData`) for the float types, which never use it, so their parameters keep their
    /// size; `Option<X>` for [`Fx`].
    #[doc(hidden)]
    type Coarse<X: Copy + Debug + PartialEq>: Copy + Debug + PartialEq;
    /// Stores `x` (dropped by the float types).
    #[doc(hidden)]
    fn coarse_new<X: Copy + Debug + PartialEq>(x: Option<X>) -> Self::Coarse<X>;
    /// The stored coarse-step parameters (`None` for the float types).
    #[doc(hidden)]
    fn coarse_get<X: Copy + Debug + PartialEq>(c: &Self::Coarse<X>) -> Option<X>;
    /// Converts from `f64` (rounding for floats, saturating for fixed point; NaN gives 0).
    fn from_f64(x: f64) -> Self;
    /// Converts from `f32` (exact for `f32`/`f64`, saturating for fixed point; NaN gives 0).
    fn from_f32(x: f32) -> Self;
    /// Converts a coefficient from `f64` for a 32-bit product: [`Real::from_f64`] for the
    /// float types; for [`Fx`], a value below 8 in magnitude is rounded to a multiple of
    /// 2^-28 (Q3.28, its raw bits / 16 fit an `i32`), others as [`Real::from_f64`]. The
    /// fixed-point AVE's `h gamma1` (so that `h gamma1 e` is one 32 x 32-bit product
    /// in the kernel; relative change of the coefficient below 2^-29 for `h gamma1 >= 1/2`).
    fn from_f64_q28(x: f64) -> Self {
        Self::from_f64(x)
    }
    /// Converts from an integer (saturating for fixed point).
    fn from_i32(x: i32) -> Self;
    /// `raw * 2^exp2` (a sensor's fixed-point reading): exact while the type holds it (the
    /// float types for `|raw| < 2^24` and a normal result; [`Fx`] for `exp2 >= -32`, saturating
    /// beyond its range, and rounded to nearest, ties to even, below 2^-32), and then the same
    /// value as [`Real::from_f32`] of it. No conversion through `f32` for [`Fx`].
    fn from_scaled(raw: i32, exp2: i32) -> Self;
    /// Neither NaN nor infinite (always true for [`Fx`]).
    fn is_finite(self) -> bool;
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
    /// The square root of the ED's `|e|^(1/2)` term ([`NativeSqrt`], the banks' default):
    /// [`Real::sqrt`] for the float types (exact, IEEE correctly rounded); for [`Fx`] a
    /// cheaper root within a relative `2^-27` of the exact one (`fxk::sqrt_fast`: Newton
    /// iteration in 32-bit words without the final correction; docs/FIXED-POINT.md, "The
    /// ED's square root and the AVE's `h gamma1`"). Negative arguments give 0.
    #[inline(always)]
    fn ed_sqrt(self) -> Self {
        self.sqrt()
    }
    /// `self / n` for an integer `n >= 1` (`n = 0` returns `self`); integer division for fixed
    /// point, so it never needs an FPU.
    fn div_int(self, n: u32) -> Self;
    /// The angle `360 turns + wrapped` (deg) as its `f32` rounding (nearest, ties to even) and
    /// the exact residual `exact - rounding` in `f64` (what a bank reports as its unwrapped
    /// angle). The default computes in `f64` (exact while the angle fits its 53 bits: below
    /// 2^21 deg for [`Fx`]'s 32 fractional bits) with a fast path when `turns = 0` and the
    /// wrapped value is an `f32`; [`Fx`] computes it with integer operations only, exactly
    /// at any turn count.
    #[inline]
    fn unwrapped_angle(turns: i64, wrapped: Self) -> (f32, f64) {
        if turns == 0 {
            // Fast path (no f64 on a single-precision core): the wrapped value is exactly an
            // f32 (checked by the round trip), so the residual is 0. `+ 0.0` maps -0 to +0 as
            // the f64 sum below does.
            let r = wrapped.to_f32() + 0.0;
            if Self::from_f32(r) == wrapped {
                return (r, 0.0);
            }
        }
        unwrapped_angle_f64(turns, wrapped)
    }
    /// How a bank's output ([`crate::BankOutput`]) holds a channel's value: `f32` for the
    /// float types (rounded when the bank computes it), the number itself for [`Fx`] (rounded
    /// to `f32` only when it is read, [`Real::output_value_f32`]: a device sends the raw bits
    /// and the host rounds them, with the same result).
    type OutputValue: Copy + Debug + PartialEq + Default;
    /// How a bank's output holds its unwrapped angle: the `f32` rounding and its `f64`
    /// residual for the float types ([`Real::unwrapped_angle`], computed when the bank runs),
    /// the turn count and the wrapped value for [`Fx`] (rounded only when read).
    type OutputAngle: Copy + Debug + PartialEq + Default;
    /// `self` as an output holds it.
    fn output_value(self) -> Self::OutputValue;
    /// An output's value as `f32`, deg/s or deg/s^2 (for [`Fx`]: [`Real::to_f32`], nearest,
    /// ties to even).
    fn output_value_f32(v: Self::OutputValue) -> f32;
    /// The angle `360 turns + wrapped` (deg) as an output holds it.
    fn output_angle(turns: i64, wrapped: Self) -> Self::OutputAngle;
    /// An output's angle as [`Real::unwrapped_angle`] gives it: the `f32` rounding and the
    /// residual, deg.
    fn output_angle_f32(a: Self::OutputAngle) -> (f32, f64);
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
    /// The raw Q31.32 bits when `Self` is [`Fx`] (`None` for the float types): lets a law take
    /// its integer-only fast path (module `fxk`) without specialisation.
    #[doc(hidden)]
    #[inline(always)]
    fn fx_bits(self) -> Option<i64> {
        None
    }
    /// The value with raw Q31.32 bits `b` when `Self` is [`Fx`]; only called after
    /// [`Real::fx_bits`] returned `Some` (0 for the float types).
    #[doc(hidden)]
    #[inline(always)]
    fn from_fx_bits(b: i64) -> Self {
        let _ = b;
        Self::ZERO
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

/// `Real` for a float type `$t`: every law stepped at `h` (no coarse step, nothing stored
/// for it), conversions by `as` (exact where they widen), `libm`'s `$abs` and `$sqrt`, `$pow2`
/// the type's power of two (normal from `2^$min_exp` up).
macro_rules! float_real {
    ($t:ty, $abs:path, $sqrt:path, $pow2:path, $min_exp:expr) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const AVE_STEP_FACTOR: u32 = 1;
            type Coarse<X: Copy + Debug + PartialEq> = core::marker::PhantomData<X>;
            type OutputValue = f32;
            type OutputAngle = (f32, f64);
            #[inline(always)]
            fn output_value(self) -> f32 {
                self.to_f32()
            }
            #[inline(always)]
            fn output_value_f32(v: f32) -> f32 {
                v
            }
            #[inline(always)]
            fn output_angle(turns: i64, wrapped: Self) -> (f32, f64) {
                Self::unwrapped_angle(turns, wrapped)
            }
            #[inline(always)]
            fn output_angle_f32(a: (f32, f64)) -> (f32, f64) {
                a
            }
            #[inline(always)]
            fn coarse_new<X: Copy + Debug + PartialEq>(_x: Option<X>) -> Self::Coarse<X> {
                core::marker::PhantomData
            }
            #[inline(always)]
            fn coarse_get<X: Copy + Debug + PartialEq>(_c: &Self::Coarse<X>) -> Option<X> {
                None
            }
            #[inline]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline]
            fn from_f32(x: f32) -> Self {
                x as $t
            }
            #[inline]
            fn from_i32(x: i32) -> Self {
                x as $t
            }
            #[inline]
            fn from_scaled(raw: i32, exp2: i32) -> Self {
                // Two exact steps when 2^exp2 itself is below the normal range (a subnormal
                // result): `raw 2^e1` is exact and normal, the second product exact when the
                // result is representable.
                let e1 = exp2.max($min_exp);
                (raw as $t) * $pow2(e1) * $pow2(exp2 - e1)
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline]
            fn to_f32(self) -> f32 {
                self as f32
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn abs(self) -> Self {
                $abs(self)
            }
            #[inline]
            fn sqrt(self) -> Self {
                if self > 0.0 {
                    $sqrt(self)
                } else {
                    0.0
                }
            }
            #[inline]
            fn div_int(self, n: u32) -> Self {
                if n == 0 {
                    self
                } else {
                    self / n as $t
                }
            }
        }
    };
}

/// `2^e` for `e` in the normal range (clamped to it), from its bits.
#[inline(always)]
fn pow2_f32(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

/// `2^e` for `e` in the normal range (clamped to it), from its bits.
#[inline(always)]
fn pow2_f64(e: i32) -> f64 {
    f64::from_bits(((e.clamp(-1022, 1023) + 1023) as u64) << 52)
}

float_real!(f32, libm::fabsf, libm::sqrtf, pow2_f32, -126);
float_real!(f64, libm::fabs, libm::sqrt, pow2_f64, -1022);

impl Real for Fx {
    const ZERO: Self = Fx(I32F32::ZERO);
    const ONE: Self = Fx(I32F32::ONE);
    const AVE_STEP_FACTOR: u32 = 2;
    type Coarse<X: Copy + Debug + PartialEq> = Option<X>;
    /// The raw number: an `Fx` bank's output is rounded to `f32` only when read.
    type OutputValue = Fx;
    /// The turn count and the wrapped angle.
    type OutputAngle = (i64, Fx);
    #[inline(always)]
    fn output_value(self) -> Fx {
        self
    }
    #[inline]
    fn output_value_f32(v: Fx) -> f32 {
        v.to_f32()
    }
    #[inline(always)]
    fn output_angle(turns: i64, wrapped: Self) -> (i64, Fx) {
        (turns, wrapped)
    }
    #[inline]
    fn output_angle_f32((turns, wrapped): (i64, Fx)) -> (f32, f64) {
        Self::unwrapped_angle(turns, wrapped)
    }
    #[inline(always)]
    fn coarse_new<X: Copy + Debug + PartialEq>(x: Option<X>) -> Self::Coarse<X> {
        x
    }
    #[inline(always)]
    fn coarse_get<X: Copy + Debug + PartialEq>(c: &Self::Coarse<X>) -> Option<X> {
        *c
    }
    #[inline(always)]
    fn fx_bits(self) -> Option<i64> {
        Some(self.to_bits())
    }
    #[inline(always)]
    fn from_fx_bits(b: i64) -> Self {
        Fx::from_bits(b)
    }
    #[inline]
    fn from_f64(x: f64) -> Self {
        // `checked_from_num` (not `saturating_from_num`, which panics on NaN) keeps the
        // conversion panic-free; out of range saturates by the sign bit, NaN gives 0.
        match I32F32::checked_from_num(x) {
            Some(v) => Fx(v),
            None if x.is_nan() => Self::ZERO,
            None if x.is_sign_negative() => Fx(I32F32::MIN),
            None => Fx(I32F32::MAX),
        }
    }
    /// `fixed`'s `checked_from_num` (nearest, ties to even), saturating by the sign, NaN to 0,
    /// computed with integer operations only.
    #[inline]
    fn from_f32(x: f32) -> Self {
        Fx::from_bits(fx_from_f32(x))
    }
    fn from_f64_q28(x: f64) -> Self {
        if x.abs() < 8.0 {
            // |x 2^28| < 2^31: exact in f64, rounded to nearest; raw bits = 16 times that.
            Fx::from_bits((libm::round(x * (1u64 << 28) as f64) as i64) << 4)
        } else {
            Self::from_f64(x)
        }
    }
    #[inline]
    fn from_i32(x: i32) -> Self {
        Fx(I32F32::from_num(x))
    }
    /// A shift: exact for `exp2 >= -32` (saturating beyond the range), nearest (ties to even)
    /// below.
    #[inline]
    fn from_scaled(raw: i32, exp2: i32) -> Self {
        Fx::from_bits(fx_from_scaled(raw, exp2))
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        true
    }
    /// `fixed`'s `to_num::<f32>` (nearest, ties to even), computed with integer operations
    /// only.
    #[inline]
    fn to_f32(self) -> f32 {
        fx_to_f32(self.to_bits())
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self.0.to_num::<f64>()
    }
    #[inline]
    fn abs(self) -> Self {
        Fx(self.0.saturating_abs())
    }
    /// `floor(sqrt(x))` to the last bit (what `fixed`'s `I32F32::sqrt` returns), by
    /// `fx_sqrt`.
    #[inline]
    fn sqrt(self) -> Self {
        Fx::from_bits(fx_sqrt(self.to_bits()))
    }
    /// `fxk::sqrt_fast`: within a relative `2^-27` of [`Real::sqrt`], not to the last bit.
    #[inline(always)]
    fn ed_sqrt(self) -> Self {
        Fx::from_bits(crate::fxk::sqrt_fast(self.to_bits()) as i64)
    }
    /// Integer operations only (128-bit ones for an angle after a turn): exact at any turn
    /// count, and the same values as the default's `f64` wherever that is exact (below 2^21
    /// deg at least).
    #[inline]
    fn unwrapped_angle(turns: i64, wrapped: Self) -> (f32, f64) {
        fx_unwrapped_angle(turns, wrapped.to_bits())
    }
    #[inline]
    fn div_int(self, n: u32) -> Self {
        if n == 0 {
            self
        } else {
            Fx(self.0.saturating_div_int(i64::from(n)))
        }
    }
}

/// The square root the [`crate::Ed`] uses for its `|e|^(1/2)` term (a type parameter, so a
/// firmware can plug in its FPU's square-root instruction without `unsafe` in this crate).
///
/// Contract: `sqrt(x)` for `x >= 0` must return exactly what [`Real::ed_sqrt`] returns (for
/// `f32`: [`Real::sqrt`], the correctly rounded IEEE 754 root, which the Cortex-M4F
/// `VSQRT.F32` instruction also computes), so that every implementation gives bit-identical
/// estimator outputs.
pub trait SqrtFn<T: Real>: Copy + Default + Debug {
    /// Square root of `x >= 0`.
    fn sqrt(x: T) -> T;
}

/// The ED's default square root: the number type's own ED root, [`Real::ed_sqrt`] (the
/// banks' default `S`). For the float types that is the exact, IEEE correctly rounded
/// [`Real::sqrt`] (`libm::sqrtf` for `f32`: about 45 instructions on a Cortex-M4F, which has
/// no stable Rust path to `VSQRT` without `unsafe`); for [`Fx`] it is a cheaper root within a
/// relative `2^-27` of the exact one (`fxk::sqrt_fast`). Hence the name: the type's native
/// root, exact for the float types but not for [`Fx`]. A [`SqrtFn`] of one's own (an FPU
/// instruction) replaces it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NativeSqrt;

impl<T: Real> SqrtFn<T> for NativeSqrt {
    #[inline]
    fn sqrt(x: T) -> T {
        x.ed_sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fixed::Saturating;

    /// `fixed`'s conversions with the saturation `Real::from_f32` documents: the reference
    /// the integer-only [`fx_from_f32`] must equal.
    fn from_f32_by_fixed(x: f32) -> i64 {
        match I32F32::checked_from_num(x) {
            Some(v) => v.to_bits(),
            None if x.is_nan() => 0,
            None if x.is_sign_negative() => i64::MIN,
            None => i64::MAX,
        }
    }

    /// Every exponent with the mantissas around rounding ties, and random bit patterns: the
    /// integer conversion equals `fixed`'s, both ways.
    #[test]
    fn f32_conversions_equal_fixeds() {
        let check_from = |b: u32| {
            let x = f32::from_bits(b);
            assert_eq!(fx_from_f32(x), from_f32_by_fixed(x), "{x:e} ({b:#010x})");
        };
        let check_to = |r: i64| {
            let want = I32F32::from_bits(r).to_num::<f32>();
            assert_eq!(fx_to_f32(r).to_bits(), want.to_bits(), "{r}");
        };
        for exp in 0..=255u32 {
            for man in [
                0u32, 1, 2, 3, 0x40_0000, 0x7F_FFFF, 0x7F_FFFE, 0x55_5555, 0x2A_AAAA,
            ] {
                for sign in [0u32, 1 << 31] {
                    check_from(sign | (exp << 23) | man);
                }
            }
        }
        for r in [0, 1, -1, i64::MIN, i64::MAX, i64::MIN + 1] {
            check_to(r);
        }
        for p in 0..63 {
            for d in [-1i64, 0, 1] {
                check_to((1i64 << p) + d);
                check_to(-(1i64 << p) + d);
                // Ties: a one in the last kept place's half.
                check_to((1i64 << p) | ((1i64 << p) >> 25) | d);
            }
        }
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
        for _ in 0..2_000_000 {
            check_from(rng.next() as u32);
            check_to(rng.next() as i64 >> (rng.next() % 64));
            check_to(rng.raw());
        }
    }

    /// The integer unwrapped angle equals the `f64` computation (the default of
    /// `Real::unwrapped_angle`, the independent reference) wherever that is exact: every
    /// angle below 2^21 deg. Turn counts up to +-5,000, wrapped values of every magnitude
    /// up to 2^18 deg (so the sum stays below 2^21 deg), ties of the f32 rounding
    /// included; and far beyond, `rounding + residual` is the exact angle to the residual's
    /// own rounding (its relative error below 2^-52).
    #[test]
    fn unwrapped_angle_equals_the_f64_computation() {
        let check = |turns: i64, raw: i64| {
            let want = unwrapped_angle_f64(turns, Fx::from_bits(raw));
            let got = fx_unwrapped_angle(turns, raw);
            assert_eq!(got.0.to_bits(), want.0.to_bits(), "{turns} {raw}");
            assert_eq!(got.1.to_bits(), want.1.to_bits(), "{turns} {raw}");
        };
        let mut rng = Rng(0x2545_F491_4F6C_DD1D);
        // |raw| < 2^50: |wrapped| < 2^18 deg, and 5,000 turns are 1.8e6 deg: below 2^21 deg.
        let wrapped = |rng: &mut Rng| rng.raw() >> 14;
        for turns in [0i64, 1, -1, 2, -3, 17, 2_912, -2_912, 5_000, -5_000] {
            check(turns, 0);
            check(turns, 1);
            check(turns, -1);
            for p in 0..50 {
                for d in [-1i64, 0, 1] {
                    check(turns, (1i64 << p) + d);
                    check(turns, -(1i64 << p) + d);
                    check(turns, (1i64 << p) | ((1i64 << p) >> 25) | d);
                }
            }
            for _ in 0..20_000 {
                check(turns, wrapped(&mut rng));
            }
        }
        for _ in 0..200_000 {
            let turns = (rng.next() % 10_001) as i64 - 5_000;
            // 180 deg at most: what a bank's local frame holds.
            let raw = (rng.next() as i64) >> 23;
            check(turns, raw);
        }
        // A million turns (360 million deg): the f64 sum is no longer exact; the integer one
        // is, so its rounding and residual add up to the angle to within the residual's
        // rounding.
        for turns in [1_000_000i64, -7_654_321, 1 << 40] {
            let raw = 0x0000_0001_2345_6789;
            let (r, res) = fx_unwrapped_angle(turns, raw);
            let exact = i128::from(turns) * (360i128 << 32) + i128::from(raw);
            let r_q32 = (f64::from(r) * 4_294_967_296.0) as i128; // exact: r is a multiple of 2^-32
            let res_q32 = res * 4_294_967_296.0;
            let err = (exact - r_q32) as f64 - res_q32;
            assert!(
                err.abs() <= res_q32.abs() * 2f64.powi(-52),
                "{turns}: {err}"
            );
            assert!(
                (f64::from(r) - exact as f64 / 4_294_967_296.0).abs()
                    <= f64::from(r).abs() * 2f64.powi(-24)
            );
        }
    }

    /// `from_scaled(raw, exp2)` is `from_f32` of the same value wherever `f32` holds it
    /// exactly (`|raw| < 2^24`, a normal result), for `Fx`, `f32` and `f64`: every NAV440
    /// angle field (`45 raw * 2^-13`, all 65,536), and 200,000 random pairs with `exp2` from
    /// -60 to 8 (for `Fx` below 2^-32 that is its nearest-even rounding, beyond its range its
    /// saturation). The `f32` value is built independently, as `raw as f64 * 2^exp2` (exact
    /// in `f64`) rounded to `f32`.
    #[test]
    fn from_scaled_is_from_f32_of_the_exact_value() {
        fn check(raw: i32, exp2: i32) {
            let exact = f64::from(raw) * 2f64.powi(exp2);
            let x = exact as f32;
            if f64::from(x) != exact || (x != 0.0 && !x.is_normal()) {
                return;
            }
            assert_eq!(
                Fx::from_scaled(raw, exp2),
                Fx::from_f32(x),
                "{raw} 2^{exp2}"
            );
            assert_eq!(
                f32::from_scaled(raw, exp2).to_bits(),
                x.to_bits(),
                "{raw} 2^{exp2}"
            );
            assert_eq!(f64::from_scaled(raw, exp2), f64::from(x), "{raw} 2^{exp2}");
        }
        for a in i16::MIN..=i16::MAX {
            check(i32::from(a) * 45, -13);
        }
        // Every f32's decomposition, subnormals and the extremes included: `from_scaled` of
        // it is `from_f32` of it (the zeros as +0).
        let mut g = Rng(0xDEC0_4405_E5CA_1ED0);
        let edges = [
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            1e-40,
            f32::MAX,
            f32::MIN,
            0.0,
            1e6,
            -179.99,
        ];
        for x in edges
            .into_iter()
            .chain((0..200_000).map(|_| f32::from_bits(g.next() as u32)))
        {
            let Some((m, e)) = f32_scaled(x) else {
                assert!(!x.is_finite(), "{x}");
                continue;
            };
            assert_eq!(f64::from(m) * 2f64.powi(e), f64::from(x), "{x}");
            assert_eq!(Fx::from_scaled(m, e), Fx::from_f32(x), "{x}");
            assert_eq!(f32::from_scaled(m, e).to_bits(), (x + 0.0).to_bits(), "{x}");
            assert_eq!(f64::from_scaled(m, e), f64::from(x), "{x}");
        }
        let mut g = Rng(0x5EED_0F5C_A1ED);
        for _ in 0..200_000 {
            let raw = (g.next() >> 40) as i32 - (1 << 23);
            let exp2 = (g.next() % 69) as i32 - 60;
            check(raw, exp2);
        }
    }

    /// xorshift64* values with a random number of significant bits (small and large values).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        fn raw(&mut self) -> i64 {
            let bits = (self.next() % 64) as u32;
            let v = (self.next() >> (63 - bits.min(63))) as i64;
            if self.next() & 1 == 0 {
                v
            } else {
                v.wrapping_neg()
            }
        }
    }

    const EDGES: [i64; 12] = [
        0,
        1,
        -1,
        i64::MAX,
        i64::MIN,
        i64::MIN + 1,
        1 << 32,
        -(1 << 32),
        (1 << 32) - 1,
        1 << 31,
        -(1 << 31) - 1,
        0x7FFF_FFFF_0000_0000,
    ];

    /// The crate's multiply (both summations) is `fixed::Saturating<I32F32>`'s (the independent reference) on
    /// edge values and 2 million random pairs of every magnitude.
    #[test]
    fn mul_matches_fixed_crate() {
        let reference = |a: i64, b: i64| {
            (Saturating(I32F32::from_bits(a)) * Saturating(I32F32::from_bits(b)))
                .0
                .to_bits()
        };
        for a in EDGES {
            for b in EDGES {
                let p = reference(a, b);
                assert_eq!(fx_mul(a, b), p, "{a} * {b}");
                assert_eq!(fx_mul_carry(a, b), p, "{a} * {b}");
                assert_eq!(fx_mul_checked(a, b), p, "{a} * {b}");
            }
        }
        let mut r = Rng(0x1234_5678_9ABC_DEF1);
        for _ in 0..2_000_000 {
            let (a, b) = (r.raw(), r.raw());
            let p = reference(a, b);
            assert_eq!(fx_mul_carry(a, b), p, "{a} * {b}");
            assert_eq!(fx_mul_checked(a, b), p, "{a} * {b}");
            assert_eq!(fx_mul(a, b), p, "{a} * {b}");
            let f = a & 0xFFFF_FFFF;
            assert_eq!(fx_mul(f, b), reference(f, b), "{f} * {b}");
            assert_eq!(fx_mul(b, f), reference(b, f), "{b} * {f}");
            let n = a & !0xFFFF_FFFF;
            assert_eq!(fx_mul(n, b), reference(n, b), "{n} * {b}");
            assert_eq!(
                fx_mul_int((n >> 32) as i32, b),
                reference(n, b),
                "{n} * {b}"
            );
        }
    }

    /// `umul32` and its Cortex-M0 form `umul32_split` are the exact product.
    #[test]
    fn umul32_exact() {
        let mut r = Rng(7);
        for _ in 0..1_000_000 {
            let (a, b) = (r.next() as u32, (r.next() >> 7) as u32);
            assert_eq!(umul32(a, b), u64::from(a) * u64::from(b));
            assert_eq!(umul32_split(a, b), u64::from(a) * u64::from(b));
        }
        let m = u64::from(u32::MAX);
        assert_eq!(umul32_split(u32::MAX, u32::MAX), m * m);
    }

    /// The square root is `fixed`'s `I32F32::sqrt` (the independent reference) bit for bit,
    /// on edge values and 2 million random values of every magnitude; `isqrt64` is the floor
    /// of the root on random `u64` and at perfect squares and their neighbours.
    #[test]
    fn sqrt_matches_fixed_crate() {
        let reference = |a: i64| {
            if a > 0 {
                I32F32::from_bits(a).sqrt().to_bits()
            } else {
                0
            }
        };
        for a in EDGES {
            assert_eq!(fx_sqrt(a), reference(a), "sqrt {a}");
        }
        let mut r = Rng(0xDEAD_BEEF);
        for _ in 0..2_000_000 {
            let a = r.raw();
            assert_eq!(fx_sqrt(a), reference(a), "sqrt {a}");
        }
        for _ in 0..200_000 {
            let n = r.next() >> (r.next() % 64);
            let s = u64::from(isqrt64(n));
            assert!(
                s * s <= n && u128::from(s + 1).pow(2) > u128::from(n),
                "isqrt {n}"
            );
            let q = u64::from(r.next() as u32);
            for n in [q * q, (q * q).wrapping_sub(1), q * q + 1] {
                let s = u64::from(isqrt64(n));
                assert!(
                    s * s <= n && u128::from(s + 1).pow(2) > u128::from(n),
                    "isqrt {n}"
                );
            }
        }
        assert_eq!(isqrt64(u64::MAX), u32::MAX);
    }

    /// Add, subtract and negate saturate as `fixed::Saturating` does.
    #[test]
    fn add_sub_neg_match_fixed_crate() {
        let mut r = Rng(99);
        for _ in 0..200_000 {
            let (a, b) = (r.raw(), r.raw());
            let (x, y) = (
                Saturating(I32F32::from_bits(a)),
                Saturating(I32F32::from_bits(b)),
            );
            let (p, q) = (Fx::from_bits(a), Fx::from_bits(b));
            assert_eq!((p + q).to_bits(), (x + y).0.to_bits());
            assert_eq!((p - q).to_bits(), (x - y).0.to_bits());
            assert_eq!((-p).to_bits(), (-x).0.to_bits());
        }
    }

    /// `from_f64_q28`: for `Fx` below 8 the nearest multiple of 2^-28 (raw bits a multiple of
    /// 16, within 2^-29 of `x`, the raw / 16 an `i32`), otherwise `from_f64`; for the float
    /// types exactly `from_f64`.
    #[test]
    fn from_f64_q28_rounds_to_q3_28() {
        let mut r = Rng(7);
        for _ in 0..100_000 {
            let x = (r.raw() as f64) / 2f64.powi(40);
            let q = Fx::from_f64_q28(x);
            if x.abs() < 8.0 {
                assert_eq!(q.to_bits() & 15, 0, "{x}");
                assert!((q.to_f64() - x).abs() <= 2f64.powi(-29), "{x}");
                assert!(i32::try_from(q.to_bits() >> 4).is_ok(), "{x}");
            } else {
                assert_eq!(q, Fx::from_f64(x));
            }
            assert_eq!(f32::from_f64_q28(x).to_bits(), f32::from_f64(x).to_bits());
            assert_eq!(f64::from_f64_q28(x).to_bits(), x.to_bits());
        }
    }
}
