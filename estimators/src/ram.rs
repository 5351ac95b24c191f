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
//! | [`IloMap`] = [`ClosedForm`]`<IloParams<T, 1>, 2>` (params) | 48 | 88 |
//! | [`AdMap`] = [`ClosedForm`]`<AdParams<T>, 2>` (params) | 40 | 72 |
//! | [`ClosedForm`]`<Series<IloParams<T, 1>, IloParams<T, 1>>>` (params) | 120 | 232 |
//! | [`PaperParams`] (all 12 rows' parameters) | 868 | 1776 |
//! | [`PaperState`] (all 12 rows' state, one axis) | 264 | 528 |
//! | [`PaperBank`] (whole bank, one axis) | 1216 | 2392 |
//! | [`ProductBank`] (ILO1 + Kalman, one axis) | 184 | 280 |
//!
//! A [`Series`] is the sum of its stages; an `Ilo<T, D>` adds `D - 1` words of `T`; a closed
//! form `ClosedForm<E, M>` adds `(M^2 + M)` words of `T` plus 8 bytes to its law's parameters:
//! 6 words for the banks' ILO and AD rows (`M = 2`, their state's dimension), 20 for the
//! default `M = LIN_MAX` (the ILO-ILO and AD-AD series, 4 states).

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
/// `(f32, Fx)` of [`IloMap`] (`ClosedForm<IloParams<T, 1>, 2>`).
pub const CLOSED_ILO: (usize, usize) = (48, 88);
/// `(f32, Fx)` of [`AdMap`] (`ClosedForm<AdParams<T>, 2>`).
pub const CLOSED_AD: (usize, usize) = (40, 72);
/// `(f32, Fx)` of [`ClosedForm`]`<Series<IloParams<T, 1>, IloParams<T, 1>>>`.
pub const CLOSED_ILO_ILO: (usize, usize) = (120, 232);
/// `(f32, Fx)` of [`PaperParams`].
pub const PAPER_PARAMS: (usize, usize) = (868, 1776);
/// `(f32, Fx)` of [`PaperState`].
pub const PAPER_STATE: (usize, usize) = (264, 528);
/// `(f32, Fx)` of the whole [`PaperBank`].
pub const PAPER_BANK: (usize, usize) = (1216, 2392);
/// `(f32, Fx)` of the [`ProductBank`].
pub const PRODUCT_BANK: (usize, usize) = (184, 280);

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
check!(CLOSED_ILO, IloMap<f32>, IloMap<Fx>);
check!(CLOSED_AD, AdMap<f32>, AdMap<Fx>);
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
            (size_of::<IloMap<f32>>(), size_of::<IloMap<Fx>>()),
            CLOSED_ILO
        );
        assert_eq!(
            (size_of::<ProductBank<f32>>(), size_of::<ProductBank<Fx>>()),
            PRODUCT_BANK
        );
    }
}
