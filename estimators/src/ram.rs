//! RAM per estimator (`core::mem::size_of`, bytes). No estimator allocates: every state,
//! coefficient, delay line and closed-form map is inline, `step`/`advance` only read the
//! parameters and write the state (the crate is `no_std` without `alloc`).
//!
//! The numbers are the same on the host and on every Cortex-M target (no `usize` fields;
//! `i64`/`u64` are 8-aligned on both); they are checked at compile time for every target
//! (the constants below feed `const` assertions), so this table cannot go stale.
//!
//! Parameters (validated coefficients, [`crate::Law`]) and state are apart: several axes can
//! share one parameter set, each keeping only its state.
//!
//! | type | f32 | Fx (Q31.32) |
//! |---|---|---|
//! | [`Ave`] (params + state) | 32 | 104 (with the coarse `2 h` step's coefficients, [`AveParams`]) |
//! | [`Ilo`]`<T, 1>` | 32 | 64 |
//! | [`Ad`] | 16 | 32 |
//! | [`Ed`] | 44 | 88 |
//! | [`Kalman`] (gains, nominal period, state, last input, restart count) | 36 | 72 |
//! | [`Unwrapper`] | 16 | 24 |
//! | [`ClosedForm`]`<IloParams<T, 1>>` (params) | 104 | 200 |
//! | [`ClosedForm`]`<AdParams<T>>` (params) | 96 | 184 |
//! | [`ClosedForm`]`<Series<IloParams<T, 1>, IloParams<T, 1>>>` (params) | 120 | 232 |
//! | [`PaperParams`] (all 12 rows' parameters) | 1092 | 2224 |
//! | [`PaperState`] (all 12 rows' state, one axis) | 264 | 528 |
//! | [`PaperBank`] (whole bank, one axis) | 1440 | 2840 |
//! | [`ProductBank`] (ILO1 + Kalman, one axis) | 240 | 392 |
//!
//! A [`Series`] is the sum of its stages; an `Ilo<T, D>` adds `D - 1` words of `T`; a closed
//! form adds `(LIN_MAX^2 + LIN_MAX) = 20` words of `T` plus 8 bytes to its law's parameters.

use crate::*;
use core::mem::size_of;

/// `(f32 size, Fx size)` of [`Ave`].
pub const AVE: (usize, usize) = (32, 104);
/// `(f32, Fx)` of [`Ilo`]`<T, 1>`.
pub const ILO_D1: (usize, usize) = (32, 64);
/// `(f32, Fx)` of [`Ad`].
pub const AD: (usize, usize) = (16, 32);
/// `(f32, Fx)` of [`Ed`].
pub const ED: (usize, usize) = (44, 88);
/// `(f32, Fx)` of [`Kalman`].
pub const KALMAN: (usize, usize) = (36, 72);
/// `(f32, Fx)` of [`Unwrapper`].
pub const UNWRAPPER: (usize, usize) = (16, 24);
/// `(f32, Fx)` of [`ClosedForm`]`<IloParams<T, 1>>`.
pub const CLOSED_ILO: (usize, usize) = (104, 200);
/// `(f32, Fx)` of [`ClosedForm`]`<AdParams<T>>`.
pub const CLOSED_AD: (usize, usize) = (96, 184);
/// `(f32, Fx)` of [`ClosedForm`]`<Series<IloParams<T, 1>, IloParams<T, 1>>>`.
pub const CLOSED_ILO_ILO: (usize, usize) = (120, 232);
/// `(f32, Fx)` of [`PaperParams`].
pub const PAPER_PARAMS: (usize, usize) = (1092, 2224);
/// `(f32, Fx)` of [`PaperState`].
pub const PAPER_STATE: (usize, usize) = (264, 528);
/// `(f32, Fx)` of the whole [`PaperBank`].
pub const PAPER_BANK: (usize, usize) = (1440, 2840);
/// `(f32, Fx)` of the [`ProductBank`].
pub const PRODUCT_BANK: (usize, usize) = (240, 392);

macro_rules! check {
    ($c:expr, $f:ty, $x:ty) => {
        const _: () = assert!(size_of::<$f>() == $c.0 && size_of::<$x>() == $c.1);
    };
}
check!(AVE, Ave<f32>, Ave<Fx>);
check!(ILO_D1, Ilo<f32, 1>, Ilo<Fx, 1>);
check!(AD, Ad<f32>, Ad<Fx>);
check!(ED, Ed<f32>, Ed<Fx>);
check!(KALMAN, Kalman<f32>, Kalman<Fx>);
check!(UNWRAPPER, Unwrapper<f32>, Unwrapper<Fx>);
check!(
    CLOSED_ILO,
    ClosedForm<IloParams<f32, 1>>,
    ClosedForm<IloParams<Fx, 1>>
);
check!(
    CLOSED_AD,
    ClosedForm<AdParams<f32>>,
    ClosedForm<AdParams<Fx>>
);
check!(
    CLOSED_ILO_ILO,
    ClosedForm<Series<IloParams<f32, 1>, IloParams<f32, 1>>>,
    ClosedForm<Series<IloParams<Fx, 1>, IloParams<Fx, 1>>>
);
check!(PAPER_PARAMS, PaperParams<f32>, PaperParams<Fx>);
check!(PAPER_STATE, PaperState<f32>, PaperState<Fx>);
check!(PAPER_BANK, PaperBank<f32>, PaperBank<Fx>);
check!(PRODUCT_BANK, ProductBank<f32>, ProductBank<Fx>);

#[cfg(test)]
mod tests {
    use super::*;

    /// The documented table (module docs) against `size_of` (runtime twin of the const
    /// assertions, so a mismatch also shows up as a failing test with both numbers).
    #[test]
    fn documented_sizes() {
        assert_eq!((size_of::<Ave<f32>>(), size_of::<Ave<Fx>>()), AVE);
        assert_eq!(
            (size_of::<PaperBank<f32>>(), size_of::<PaperBank<Fx>>()),
            PAPER_BANK
        );
        assert_eq!(
            (
                size_of::<ClosedForm<IloParams<f32, 1>>>(),
                size_of::<ClosedForm<IloParams<Fx, 1>>>()
            ),
            CLOSED_ILO
        );
        assert_eq!(
            (size_of::<ProductBank<f32>>(), size_of::<ProductBank<Fx>>()),
            PRODUCT_BANK
        );
    }
}
