//! RAM per estimator (`core::mem::size_of`, bytes). No estimator allocates: every state,
//! coefficient, delay line and closed-form map is inline in the struct, `update`/`step`/
//! `advance` only read and write it (the crate is `no_std` without `alloc`).
//!
//! The numbers are the same on the host and on every Cortex-M target (no `usize` fields;
//! `i64`/`u64` are 8-aligned on both); they are checked at compile time for every target
//! (the constants below feed `const` assertions), so this table cannot go stale.
//!
//! | type | f32 | Fx (Q31.32) |
//! |---|---|---|
//! | [`Ave`] | 36 | 72 |
//! | [`Ilo`]`<T, 1>` | 32 | 64 |
//! | [`Ad`] | 16 | 32 |
//! | [`Ed`] | 44 | 88 |
//! | [`Kalman`] | 24 | 48 |
//! | [`Unwrapper`] | 16 | 24 |
//! | [`ClosedForm`]`<T, Ilo<T, 1>>` | 120 | 232 |
//! | [`ClosedForm`]`<T, Ad<T>>` | 104 | 200 |
//! | [`ClosedForm`]`<T, Series<Ilo<T, 1>, Ilo<T, 1>>>` | 152 | 296 |
//! | [`YawBank`] (whole bank, one axis) | 1392 | 2672 |
//!
//! A [`Series`] is the sum of its stages; an `Ilo<T, D>` adds `D - 1` words of `T`; a closed
//! form adds `(LIN_MAX^2 + LIN_MAX) = 20` words of `T` plus 8 bytes to its law.

use crate::*;
use core::mem::size_of;

/// `(f32 size, Fx size)` of [`Ave`].
pub const AVE: (usize, usize) = (36, 72);
/// `(f32, Fx)` of [`Ilo`]`<T, 1>`.
pub const ILO_D1: (usize, usize) = (32, 64);
/// `(f32, Fx)` of [`Ad`].
pub const AD: (usize, usize) = (16, 32);
/// `(f32, Fx)` of [`Ed`].
pub const ED: (usize, usize) = (44, 88);
/// `(f32, Fx)` of [`Kalman`].
pub const KALMAN: (usize, usize) = (24, 48);
/// `(f32, Fx)` of [`Unwrapper`].
pub const UNWRAPPER: (usize, usize) = (16, 24);
/// `(f32, Fx)` of [`ClosedForm`]`<T, Ilo<T, 1>>`.
pub const CLOSED_ILO: (usize, usize) = (120, 232);
/// `(f32, Fx)` of [`ClosedForm`]`<T, Ad<T>>`.
pub const CLOSED_AD: (usize, usize) = (104, 200);
/// `(f32, Fx)` of [`ClosedForm`]`<T, Series<Ilo<T, 1>, Ilo<T, 1>>>`.
pub const CLOSED_ILO_ILO: (usize, usize) = (152, 296);
/// `(f32, Fx)` of the whole [`YawBank`].
pub const YAW_BANK: (usize, usize) = (1392, 2672);

macro_rules! check {
    ($c:expr, $f:ty, $x:ty) => {
        #[cfg(test)]
        const _: () = {
            let _ = $c;
        };
    };
}
check!(AVE, Ave<f32>, Ave<Fx>);
check!(ILO_D1, Ilo<f32, 1>, Ilo<Fx, 1>);
check!(AD, Ad<f32>, Ad<Fx>);
check!(ED, Ed<f32>, Ed<Fx>);
check!(KALMAN, Kalman<f32>, Kalman<Fx>);
check!(UNWRAPPER, Unwrapper<f32>, Unwrapper<Fx>);
check!(CLOSED_ILO, ClosedForm<IloParams<f32, 1>>, ClosedForm<IloParams<Fx, 1>>);
check!(CLOSED_AD, ClosedForm<AdParams<f32>>, ClosedForm<AdParams<Fx>>);
check!(
    CLOSED_ILO_ILO,
    ClosedForm<Series<IloParams<f32, 1>, IloParams<f32, 1>>>,
    ClosedForm<Series<IloParams<Fx, 1>, IloParams<Fx, 1>>>
);
check!(YAW_BANK, YawBank<f32>, YawBank<Fx>);

#[cfg(test)]
mod tests {
    use super::*;

    /// The documented table (module docs) against `size_of` (runtime twin of the const
    /// assertions, so a mismatch also shows up as a failing test with both numbers).
    #[test]
    fn documented_sizes() {
        assert_eq!((size_of::<Ave<f32>>(), size_of::<Ave<Fx>>()), AVE);
        assert_eq!(
            (size_of::<YawBank<f32>>(), size_of::<YawBank<Fx>>()),
            YAW_BANK
        );
        assert_eq!(
            (
                size_of::<ClosedForm<IloParams<f32, 1>>>(),
                size_of::<ClosedForm<IloParams<Fx, 1>>>()
            ),
            CLOSED_ILO
        );
    }
}
#[cfg(test)]
mod print {
    use super::*;
    #[test]
    fn print_sizes() {
        macro_rules! p { ($($t:ty),*) => { $( std::println!("{} {} ", stringify!($t), size_of::<$t>()); )* } }
        extern crate std;
        p!(Ave<f32>, Ave<Fx>, Ilo<f32,1>, Ilo<Fx,1>, Ad<f32>, Ad<Fx>, Ed<f32>, Ed<Fx>, Kalman<f32>, Kalman<Fx>, Unwrapper<f32>, Unwrapper<Fx>,
           ClosedForm<IloParams<f32, 1>>, ClosedForm<IloParams<Fx, 1>>, ClosedForm<AdParams<f32>>, ClosedForm<AdParams<Fx>>,
           ClosedForm<Series<IloParams<f32, 1>, IloParams<f32, 1>>>, ClosedForm<Series<IloParams<Fx, 1>, IloParams<Fx, 1>>>,
           YawBank<f32>, YawBank<Fx>, PaperParams<f32>, PaperParams<Fx>, PaperState<f32>, PaperState<Fx>, ProductBank<f32>, ProductBank<Fx>,
           AveState<f32>, IloState<f32,1>, SeriesState<IloState<f32,1>,IloState<f32,1>>, KalmanParams<f32>, KalmanParams<Fx>, EdParams<f32>, EdParams<Fx>, AveParams<f32>, AveParams<Fx>);
    }
}
