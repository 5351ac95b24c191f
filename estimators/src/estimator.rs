//! The one trait every time-step law implements, and how a sample interval is fed to it.

use crate::Real;

/// How the input is presented to the law between two samples `y_{k-1}` (at `t_{k-1}`) and
/// `y_k` (at `t_k`) during the `n_k` steps of size `h` run when `y_k` arrives.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Hold {
    /// Step `j = 1..=n_k` sees `y_{k-1} + (y_k - y_{k-1}) * j / n_k`: the sampled signal
    /// joined by straight lines, what a continuous-time law sees of it. Causal (all steps run
    /// when `y_k` arrives), no added latency. The default.
    #[default]
    Linear,
    /// Every step sees `y_k` (a staircase input). Fast estimators settle during the flat part
    /// and their output decays, so the reported value is biased low (see the crate README).
    ZeroOrder,
}

/// One time-step law (AVE, ILO, AD, ED, [`crate::Series`]): fed one input value per step,
/// advances by its fixed step `h` (set at construction) and returns its estimate.
///
/// Units: a velocity estimator fed a position in deg returns deg/s; a series (acceleration)
/// estimator returns deg/s^2.
pub trait Estimator<T: Real> {
    /// Sets the state as if the input had been constant at `y0` forever: position states =
    /// `y0`, every velocity / learning / delay state = 0, output 0. No transient follows.
    fn reset(&mut self, y0: T);

    /// Advances one step `h` with input `y` and returns the new estimate.
    fn step(&mut self, y: T) -> T;

    /// The estimate of the last step (0 after [`Estimator::reset`]).
    fn output(&self) -> T;

    /// Adds `d` (unit of the input) to every position state. Every law here is invariant to a
    /// constant input offset (`y -> y + d` with positions `+ d` gives the same velocities),
    /// so this moves the estimator to a shifted input frame without any transient; the
    /// [`crate::PaperBank`] uses it to keep its `f32` states near the wrapped angle (+-180 deg)
    /// instead of an unwrapped angle that grows by 360 deg per turn and loses `f32` precision.
    fn translate(&mut self, d: T);

    /// Runs the `n >= 1` steps of one sample interval from `y_prev` to `y_new` as
    /// [`Hold`] prescribes and returns the output of the last step. `n = 0` does nothing and
    /// returns the current output.
    ///
    /// The default steps `n` times; linear laws wrapped in [`crate::ClosedForm`] replace this by
    /// their exact precomputed `n`-step map.
    fn advance(&mut self, y_prev: T, y_new: T, n: u32, hold: Hold) -> T {
        advance_by_steps(self, y_prev, y_new, n, hold)
    }
}

/// The stepping implementation of [`Estimator::advance`] (usable by overriding impls as
/// their fallback).
#[inline]
pub fn advance_by_steps<T: Real, E: Estimator<T> + ?Sized>(
    e: &mut E,
    y_prev: T,
    y_new: T,
    n: u32,
    hold: Hold,
) -> T {
    if n == 0 {
        return e.output();
    }
    match hold {
        Hold::ZeroOrder => {
            for _ in 0..n {
                e.step(y_new);
            }
        }
        Hold::Linear => {
            // y_j = y_prev + j * dy / n, computed as y_prev + j * inc; the last step gets y_new
            // exactly so the rounding of `inc` never accumulates into the next interval.
            let inc = (y_new - y_prev).div_int(n);
            let mut y = y_prev;
            for _ in 1..n {
                y = y + inc;
                e.step(y);
            }
            e.step(y_new);
        }
    }
    e.output()
}
