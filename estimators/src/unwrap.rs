//! Angle unwrapping (+-180 deg) before differentiation.

use crate::Real;

/// Removes the 360 deg jumps of a wrapped angle: each new sample is placed within 180 deg of
/// the previous one by adding a multiple of 360 deg, so the output is continuous across any
/// number of turns.
///
/// Valid when the true change between two samples is below 180 deg (at 100 Hz: below
/// 18000 deg/s). Inputs are expected in `[-180, 180]` deg; others are accepted and unwrapped
/// the same way (one 360 deg correction per sample). Computed in `T` (no floating point for
/// [`crate::Fx`]). RAM: 2 words of `T` plus a flag.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unwrapper<T: Real> {
    prev: T,
    offset: T,
    started: bool,
}

impl<T: Real> Unwrapper<T> {
    /// A fresh unwrapper (the first sample passes unchanged).
    pub fn new() -> Self {
        Self {
            prev: T::ZERO,
            offset: T::ZERO,
            started: false,
        }
    }

    /// Returns the unwrapped angle (deg) for the wrapped angle `yaw` (deg).
    #[inline]
    pub fn unwrap(&mut self, yaw: T) -> T {
        if self.started {
            let half = T::from_i32(180);
            let full = T::from_i32(360);
            let d = yaw - self.prev;
            if d > half {
                self.offset = self.offset - full;
            } else if d < -half {
                self.offset = self.offset + full;
            }
        } else {
            self.started = true;
        }
        self.prev = yaw;
        yaw + self.offset
    }

    /// The multiple of 360 deg currently added to the wrapped input (deg).
    pub fn offset(&self) -> T {
        self.offset
    }

    /// The unwrapped value of the last sample, without a new sample.
    pub fn last(&self) -> T {
        self.prev + self.offset
    }
}
