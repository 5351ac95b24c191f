//! Angle unwrapping (+-180 deg) before differentiation.

use crate::Real;

/// Removes the 360 deg jumps of a wrapped angle: each new sample is placed within 180 deg of
/// the previous one by adding a whole number of turns, so the output is continuous across any
/// number of turns.
///
/// The turn count is an `i64` (exact for any number of turns), kept apart from the wrapped
/// angle (in `T`): the unwrapped angle is `360 * turns() + wrapped`, exact at every turn
/// count. Valid when the true change between two samples is below 180 deg (at 100 Hz: below
/// 18000 deg/s). Inputs are expected in `[-180, 180]` deg; others are accepted and unwrapped
/// the same way (at most one turn per sample). Computed in `T` (no floating point for
/// [`crate::Fx`]). RAM: one word of `T`, an `i64` and a flag.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unwrapper<T: Real> {
    prev: T,
    turns: i64,
    started: bool,
}

impl<T: Real> Unwrapper<T> {
    /// A fresh unwrapper (the first sample passes unchanged).
    pub fn new() -> Self {
        Self {
            prev: T::ZERO,
            turns: 0,
            started: false,
        }
    }

    /// Sets the whole-turn count (e.g. to resume an absolute heading after a restart); the
    /// next sample is still unwrapped against the last one.
    pub fn set_turns(&mut self, turns: i64) {
        self.turns = turns;
    }

    /// Takes the next wrapped angle `angle` (deg) and returns the turn count to add to it.
    #[inline]
    pub fn update(&mut self, angle: T) -> i64 {
        if self.started {
            let half = T::from_i32(180);
            let d = angle - self.prev;
            if d.abs() <= half {
                // The common case: no turn (same result as the two tests below).
                self.prev = angle;
                return self.turns;
            }
            if d > half {
                self.turns = self.turns.saturating_sub(1);
            } else if d < -half {
                self.turns = self.turns.saturating_add(1);
            }
        } else {
            self.started = true;
        }
        self.prev = angle;
        self.turns
    }

    /// Returns the unwrapped angle (deg) for the wrapped angle `angle` (deg), in `T`: exact
    /// while `360 * turns` is exact in `T` (f32: 2^27 deg; Fx: saturates at 2^31 deg); use
    /// [`Unwrapper::update`] and [`Unwrapper::turns`] for an exact angle at any turn count.
    #[inline]
    pub fn unwrap(&mut self, angle: T) -> T {
        self.update(angle);
        angle + self.offset()
    }

    /// Whole turns currently added to the wrapped input.
    pub fn turns(&self) -> i64 {
        self.turns
    }

    /// The multiple of 360 deg currently added to the wrapped input (deg), in `T` (rounded
    /// beyond `T`'s exact range, see [`Unwrapper::unwrap`]).
    pub fn offset(&self) -> T {
        T::from_f64(self.turns as f64 * 360.0)
    }

    /// The exact unwrapped value of the last sample, deg, in f64 (exact up to 2^53 deg).
    pub fn last_f64(&self) -> f64 {
        self.turns as f64 * 360.0 + self.prev.to_f64()
    }

    /// The unwrapped value of the last sample, without a new sample.
    pub fn last(&self) -> T {
        self.prev + self.offset()
    }
}
