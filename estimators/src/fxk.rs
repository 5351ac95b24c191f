//! Integer fast paths of the stepped laws (AVE, ED and their series rows) for [`crate::Fx`].
//!
//! The generic laws compute in [`crate::Fx`] with saturating `+ - *` on Q31.32. The kernels
//! here compute **the same expression trees on the same Q31.32 bits**, but with wrapping
//! (plain) `i64` additions and multiplies specialised to what the operands are:
//!
//! * a coefficient in `[0, 1/2)` (`h`, `h k`, `h sigma`: raw bits below 2^31) times a state:
//!   two 32 x 32-bit products ([`mulf`]);
//! * an error `e = xhat - y` below 1/2 in magnitude (raw bits fit an `i32`, the usual case):
//!   one 32 x 32-bit product per coefficient (`h gamma1` in Q3.28, see `AveFx` in `ave.rs`);
//! * the ED's square root: the fixed-point bank's own root [`sqrt_fast`] (a Newton iteration
//!   in 32-bit words, within a relative 2^-27 of the exact root; the generic [`crate::Fx`] ED
//!   uses the same function through [`crate::Real::ed_sqrt`]);
//! * anything else: the generic `fx_mul` on the raw bits.
//!
//! **Why no saturation is needed (the range guard).** Before the interval and after every step
//! the kernel checks that every state and input is below `2^(B-32)` in magnitude (raw below
//! `2^B`), with `B` derived from the coefficients (`AveFx::of` in `ave.rs`, `ED_B` in `ed.rs`:
//! B = 60 - G where `|h gamma1| < 2^G`, and B = 60 for the ED with
//! `lambda < 2^13`). Under that bound no intermediate of one step can leave the `i64` range
//! (each law's step function states the bound of every intermediate), so every wrapping
//! operation gives the exact integer, which is also what the saturating code gives. When the
//! check fails (never on a physical input: with the paper's gains B = 58, about 6.7e7 deg,
//! deg/s or deg/s^2) the kernel drops its work and the caller runs the generic saturating path
//! on the untouched state. The outputs are therefore **bit for bit those of the generic
//! [`crate::Fx`] code**, on every target: the kernels change the cost, not the results.
//!
//! The check itself is one `EOR` with the sign and one `ORR` per state word, and one compare
//! per stage and step.
//!
//! See docs/FIXED-POINT.md for the measured cost.

use crate::law::Interval;
use crate::real::{smul32u, umul32};
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
    i64::from(xh) * i64::from(c) + (umul32(xl, c as u32) >> 32) as i64
}

/// `floor(c e / 2^32)` for a fraction `c` from [`frac`] and a 32-bit `e`: one product.
#[inline(always)]
pub(crate) fn mulf32(c: i32, e: i32) -> i64 {
    smul(c, e) >> 32
}

/// The signed 32 x 32 -> 64-bit product (`SMULL`; on the Cortex-M0 from unsigned pieces).
#[inline(always)]
pub(crate) fn smul(a: i32, b: i32) -> i64 {
    crate::real::smul32(a, b)
}

/// `|v| < 2^bits` test material: the high word with its sign folded (`h ^ (h >> 31)`), to be
/// OR-ed over several values and compared once.
#[inline(always)]
pub(crate) fn mag(v: i64) -> u32 {
    let h = (v >> 32) as i32;
    (h ^ (h >> 31)) as u32
}

/// A general Q31.32 coefficient `c = hi + lo / 2^32`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coef {
    pub(crate) raw: i64,
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

    /// The smallest `g >= 0` with `|c| < 2^g`.
    pub(crate) fn log2_bound(&self) -> u32 {
        let m = self.raw.unsigned_abs();
        (64 - m.leading_zeros()).saturating_sub(32)
    }

    /// The exact `c * r` (Q31.32) for a raw `r < 2^47` and `|c| < 2^13`:
    /// `hi rh 2^32 + hi rl + lo rh + floor(lo rl / 2^32)` (`r = rh 2^32 + rl`), below 2^61.
    #[inline(always)]
    pub(crate) fn mul_u47(&self, r: u64) -> i64 {
        let (rh, rl) = ((r >> 32) as u32, r as u32);
        let p = ((i64::from(self.hi) * i64::from(rh)) << 32) + smul32u(self.hi, rl);
        if self.lo == 0 {
            p
        } else {
            p + umul32(self.lo, rh) as i64 + (umul32(self.lo, rl) >> 32) as i64
        }
    }

    /// The exact `c * r` (Q31.32) for an unsigned 32-bit raw `r`.
    #[inline(always)]
    pub(crate) fn mul_u32(&self, r: u32) -> i64 {
        let p = smul32u(self.hi, r);
        if self.lo == 0 {
            p
        } else {
            p + (umul32(self.lo, r) >> 32) as i64
        }
    }
}

/// `1 / sqrt(X) / 2` in Q0.16 (the top 16 bits of the Q1.31 value) at the middle of each of
/// 192 steps of `X` in `[1, 4)`, indexed by the top byte `j = 64 .. 255` of `x = X 2^30`
/// (`X = (j + 0.5) / 64`; entries 0 .. 63, below the normalised range, are never used and
/// hold 2^15): the start of [`sqrt_newton`]'s iteration (about 8 bits). Indexed by a byte, so
/// no bounds check. Computed at compile time, by bisection on integers: the largest `y` with
/// `y^2 X <= 2^62`, shifted right by 15.
const RSQRT256: [u16; 256] = {
    let mut t = [1u16 << 15; 256];
    let mut i = 0;
    while i < 192 {
        // X = (2 i + 129) / 128: the largest y with y^2 (2 i + 129) <= 128 2^62.
        let d = (2 * i as u128) + 129;
        let target = 128u128 << 62;
        let (mut lo, mut hi) = (0u128, 1u128 << 33);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if mid * mid * d <= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        t[i + 64] = (lo >> 15) as u16;
        i += 1;
    }
    t
};

/// The Newton iteration of the fixed-point ED's square root: for `x` in
/// `[2^30, 2^32)` (`X = x / 2^30` in `[1, 4)`), `q ~ sqrt(x 2^32) = sqrt(X) 2^31`, from the
/// [`RSQRT256`] seed (8 bits) and two Newton steps of `1 / sqrt(X)` in 32-bit words; `q` is
/// within a few units of `floor(sqrt(x 2^32))` (relative error below 2^-28, checked in the
/// tests), never above `2^32 - 1`.
#[inline(always)]
fn sqrt_newton(x: u32) -> u32 {
    let mut y = u32::from(RSQRT256[(x >> 24) as u8 as usize]) << 15; // Q1.31
    for _ in 0..2 {
        let y2 = (umul32(y, y) >> 31) as u32; // y^2, Q1.31
        let xy2 = (umul32(x, y2) >> 31) as u32; // X y^2 / 2, Q1.31
        let t = (3u32 << 29).wrapping_sub(xy2 >> 1); // (3 - X y^2) / 2, Q2.30
        y = (umul32(y, t) >> 30) as u32; // Q1.31
    }
    // Each Newton step ends at or below 1 / sqrt(X) (`y (3 - X y^2) / 2 <= 1 / sqrt(X)` for
    // every `y >= 0`, and the truncations only lower it), so `x y / 2^30 <= sqrt(X) 2^31 < 2^32`.
    (umul32(x, y) >> 30) as u32
}

/// The fixed-point bank's ED square root ([`crate::Real::ed_sqrt`] of [`crate::Fx`]): the
/// Q31.32 root of a raw `r >= 0`, `sqrt(r 2^32)`, **not** rounded to the last bit: `r` is
/// normalised to `m = r 4^k` in `[2^62, 2^64)`, [`sqrt_newton`] of its top word gives
/// `q ~ sqrt(m)` to about 29 bits, and the root is `q 2^(16 - k)` (shifted right for `k > 16`,
/// which truncates). Relative error below `2^-27` (a few units of 2^-32 of the root, tested
/// against the exact `fx_sqrt`); 0 for `r <= 0`. About a third of the exact root's cost: no
/// correction by whole units, no remainder digits (docs/FIXED-POINT.md, "The ED's square root and the AVE's `h gamma1`").
#[inline(always)]
pub(crate) fn sqrt_fast(r: i64) -> u64 {
    if r <= 0 {
        return 0;
    }
    let r = r as u64;
    if let Ok(r32) = u32::try_from(r) {
        // r < 2^32 (|e| < 1, the usual case): k = 16 + k32, m's top word is r32 4^k32.
        let k32 = r32.leading_zeros() / 2;
        u64::from(sqrt_newton(r32 << (2 * k32)) >> k32)
    } else {
        let k = r.leading_zeros() / 2; // 0 ..= 15
        let q = u64::from(sqrt_newton(((r << (2 * k)) >> 32) as u32));
        q << (16 - k)
    }
}

/// The inputs of the `n` steps of one interval, as [`crate::law::step_n`] presents them:
/// `(first, inc, y_new)` such that steps `1 .. n-1` see `first + j inc` (accumulated with `+`,
/// as the generic loop does) and the last step sees `y_new`. `None` if `T` is not
/// [`crate::Fx`].
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

/// Declares a law's state as raw Q31.32 bits: a struct whose `i64` fields mirror the state's
/// fields (`raw: field`), with `of` (the bits of a state, `None` for the float types) and
/// `store` (writes them back).
macro_rules! fx_state {
    ($(#[$m:meta])* $name:ident for $state:ident { $($raw:ident: $field:ident),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug)]
        struct $name {
            $($raw: i64),+
        }

        impl $name {
            #[inline(always)]
            fn of<T: Real>(s: &$state<T>) -> Option<Self> {
                Some(Self {
                    $($raw: s.$field.fx_bits()?),+
                })
            }

            #[inline(always)]
            fn store<T: Real>(&self, s: &mut $state<T>) {
                $(s.$field = T::from_fx_bits(self.$raw);)+
            }
        }
    };
}
pub(crate) use fx_state;

/// A law's integer kernel over one sample interval (the AVE's, the ED's): `a2` is the
/// series' second stage fed by `self`; the states are written only when it succeeds (else
/// the caller runs the generic code from the same states).
/// `S`: the law's state (`AveState<T>`, `EdState<T>`).
pub(crate) trait Kernel<S> {
    /// The interval of `n >= 1` steps with the inputs `ys` of [`inputs`].
    fn advance(
        &self,
        a2: Option<&Self>,
        sv: &mut S,
        sa: &mut S,
        ys: (i64, i64, i64),
        n: u32,
    ) -> bool;
}

/// `Law::advance` of one law through its kernel `k` (`None`: a float type, or coefficients
/// outside the kernel's classes); `true` when the kernel ran the interval.
#[inline(always)]
pub(crate) fn advance_one<S: Copy, K: Kernel<S>, T: Real>(
    k: Option<K>,
    s: &mut S,
    y_prev: T,
    y_new: T,
    n: u32,
    hold: Hold,
) -> bool {
    if n == 0 {
        return false;
    }
    let (Some(k), Some(ys)) = (k, inputs(y_prev, y_new, n, hold)) else {
        return false;
    };
    let mut unused = *s;
    k.advance(None, s, &mut unused, ys, n)
}

/// `Law::advance_pair` through the kernels of both stages; `true` when they ran the interval.
#[inline(always)]
pub(crate) fn advance_two<S, K: Kernel<S>, T: Real>(
    kv: Option<K>,
    ka: Option<K>,
    sv: &mut S,
    sa: &mut S,
    iv: Interval<T>,
) -> bool {
    match (kv, ka, inputs(iv.y_prev, iv.y_new, iv.n, iv.hold)) {
        (Some(kv), Some(ka), Some(ys)) => kv.advance(Some(&ka), sv, sa, ys, iv.n),
        _ => false,
    }
}

/// One law of a kernel: a step on raw Q31.32 states that is exact (wrapping operations that
/// cannot overflow) while every state and the input are below the law's guard bound.
pub(crate) trait Stage {
    /// The raw state.
    type S: Copy;
    /// One step with input `y`; returns the output (a state word, covered by [`Stage::mag`]).
    fn step(&self, s: &mut Self::S, y: i64) -> i64;
    /// The OR of the states' folded high words ([`mag`]).
    fn mag(s: &Self::S) -> u32;
}

/// Steps per chunk of [`run`]: the first stage's outputs are buffered (256 bytes of stack) so
/// that each stage's loop keeps its own states in registers.
const CHUNK: usize = 32;

/// `n >= 1` steps of `a` with the inputs `(y_prev, inc, y_new)` of [`inputs`] and, when `b`
/// is given, of a second stage fed by `a`'s output of each step (the paper's series), on local
/// copies of the states; every state and input is checked against `bound` (raw high-word
/// bound `2^(B-32)`) before each step. `None` (states untouched) when the guard fails.
#[inline(always)]
pub(crate) fn run<A: Stage>(
    a: &A,
    b: Option<&A>,
    sa: &mut A::S,
    sb: &mut A::S,
    (mut y, inc, y_new): (i64, i64, i64),
    n: u32,
    bound: u32,
) -> Option<()> {
    let mut va = *sa;
    let mut vb = *sb;
    let mb = |v: &A::S| if b.is_some() { A::mag(v) } else { 0 };
    if (mag(y) | mag(y_new) | A::mag(&va) | mb(&vb)) >= bound {
        return None;
    }
    let mut buf = [0i64; CHUNK];
    let mut left = n as usize;
    while left > 0 {
        let m = left.min(CHUNK);
        left -= m;
        let (head, last) = if left == 0 {
            // The interval's last step sees y_new exactly.
            buf.split_at_mut(m - 1)
        } else {
            buf.split_at_mut(m)
        };
        for o in head.iter_mut() {
            y = y.wrapping_add(inc);
            *o = a.step(&mut va, y);
            if A::mag(&va) >= bound {
                return None;
            }
        }
        if left == 0 {
            if let Some(o) = last.first_mut() {
                *o = a.step(&mut va, y_new);
                if A::mag(&va) >= bound {
                    return None;
                }
            }
        }
        if let Some(b) = b {
            for o in buf.iter().take(m) {
                b.step(&mut vb, *o);
                if A::mag(&vb) >= bound {
                    return None;
                }
            }
        }
    }
    *sa = va;
    *sb = vb;
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::real::fx_sqrt;

    /// `sqrt_fast` is within a relative `2^-27` (plus one unit) of the exact `fx_sqrt` on
    /// every magnitude: powers of two and neighbours, a dense sweep below 1, 2 million random
    /// values; never negative, 0 at 0.
    #[test]
    fn sqrt_fast_error_bound() {
        let check = |v: i64| {
            let exact = fx_sqrt(v) as f64;
            let fast = sqrt_fast(v) as f64;
            assert!(
                (fast - exact).abs() <= exact * 2f64.powi(-27) + 1.0,
                "{v}: {fast} vs {exact}"
            );
        };
        assert_eq!(sqrt_fast(0), 0);
        assert_eq!(sqrt_fast(-5), 0);
        for b in 0..63 {
            for d in 0..5i64 {
                check((1i64 << b).wrapping_add(d).max(1));
                check((1i64 << b).wrapping_sub(d).max(1));
            }
        }
        check(i64::MAX);
        let mut r: u64 = 1;
        while r < u64::from(u32::MAX) {
            check(r as i64);
            r = r + (r >> 9) + 1;
        }
        let mut x: u64 = 0x0F1E_2D3C_4B5A_6978;
        for _ in 0..2_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            check(((x >> 1) >> (x % 63)) as i64);
        }
    }

    /// The seed table is `2^31 / sqrt(X)` at the middle of each step (checked in f64).
    #[test]
    fn rsqrt_seed() {
        for (i, y) in RSQRT256.iter().enumerate().skip(64) {
            let x = (2.0 * i as f64 + 1.0) / 128.0;
            let want = 2f64.powi(16) / x.sqrt();
            assert!((f64::from(*y) - want).abs() <= 1.0, "{i}: {y} {want}");
        }
    }

    /// `mulf`, `mulf32` and `Coef::mul_u32` are the exact floor of the
    /// product (computed in i128).
    #[test]
    fn products_exact() {
        let mut x: u64 = 12345;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for _ in 0..1_000_000 {
            let c = (next() >> 33) as i32; // [0, 2^31)
            let v = (next() as i64) >> (next() % 40);
            let want = ((i128::from(c) * i128::from(v)) >> 32) as i64;
            assert_eq!(mulf(c, v), want);
            let e = next() as i32;
            assert_eq!(mulf32(c, e), ((i128::from(c) * i128::from(e)) >> 32) as i64);
            let raw = (next() as i64) >> (next() % 64);
            let k = Coef::of(crate::Fx::from_bits(raw)).unwrap();
            let u = next() as u32;
            assert_eq!(
                k.mul_u32(u),
                ((i128::from(raw) * i128::from(u)) >> 32) as i64
            );
            assert!(raw.unsigned_abs() < 1u64 << (32 + k.log2_bound()).min(63) || raw == i64::MIN);
        }
    }
}
