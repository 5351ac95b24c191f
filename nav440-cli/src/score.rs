//! Which samples a score counts: what `nav440 paper`, `tune` and `plot` leave out near gimbal
//! lock.
//!
//! At |pitch| >= 80 deg ([`nav440_pipeline::euler::near_lock`]) the roll and yaw reference
//! rates are not given, and the pipeline does not feed the roll and yaw banks; it restarts
//! them from the first sample below the limit. A restarted estimator starts at velocity 0 and
//! needs a moment to follow the motion again, so for roll and yaw every score also leaves out
//! the [`LOCK_SETTLE_S`] after each sample near the lock. Pitch is scored everywhere.
//!
//! The estimators the tuner runs alone (one family, outside the bank) are fed the same way:
//! not near the lock, restarted after it ([`Lock::fed`]).

use crate::replay::{Axis, Sample};

/// Time after the last sample near gimbal lock that the roll and yaw scores leave out, s.
pub const LOCK_SETTLE_S: f64 = 1.0;

/// The samples of one axis that are fed to an estimator and that are scored.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Lock {
    /// Per sample: `false` near gimbal lock for roll and yaw (the bank skips it and restarts
    /// at the next `true`).
    pub fed: Vec<bool>,
    /// Per sample: `false` near gimbal lock and within [`LOCK_SETTLE_S`] after it (roll and
    /// yaw only).
    pub scored: Vec<bool>,
    /// Samples near gimbal lock (roll and yaw only; 0 for pitch).
    pub near_lock: usize,
    /// Samples left out for the settle time after it.
    pub settling: usize,
}

impl Lock {
    /// The lock mask of `axis` over `samples` (in time order).
    pub fn of(samples: &[Sample], axis: Axis) -> Self {
        let singular = axis.singular_near_lock();
        let settle_us = (LOCK_SETTLE_S * 1e6).round() as u64;
        let mut last_lock: Option<u64> = None;
        let (mut fed, mut scored) = (Vec::with_capacity(samples.len()), Vec::new());
        scored.reserve(samples.len());
        let (mut near_lock, mut settling) = (0, 0);
        for s in samples {
            let locked = singular && s.near_lock();
            if locked {
                last_lock = Some(s.t_us);
                near_lock += 1;
            }
            let settles =
                !locked && last_lock.is_some_and(|t| s.t_us.saturating_sub(t) <= settle_us);
            if settles {
                settling += 1;
            }
            fed.push(!locked);
            scored.push(!locked && !settles);
        }
        Self {
            fed,
            scored,
            near_lock,
            settling,
        }
    }

    /// Of the samples with `from <= t <= to` (s): how many are scored, and how many are left
    /// out (near the lock or settling).
    pub fn counts_in(&self, samples: &[Sample], (from, to): (f64, f64)) -> (usize, usize) {
        let (lo, hi) = ((from * 1e6).round() as u64, (to * 1e6).round() as u64);
        samples
            .iter()
            .zip(&self.scored)
            .filter(|(s, _)| s.t_us >= lo && s.t_us <= hi)
            .fold(
                (0, 0),
                |(yes, no), (_, &k)| {
                    if k {
                        (yes + 1, no)
                    } else {
                        (yes, no + 1)
                    }
                },
            )
    }
}

/// The text every report prints about the rows left out, e.g. "54 of 4,000 rows left out
/// near gimbal lock (|pitch| >= 80 deg) and within 1 s after it"; `None` when none were.
pub fn left_out_note(left_out: usize, rows: usize) -> Option<String> {
    (left_out > 0).then(|| {
        format!(
            "{left_out} of {rows} rows left out near gimbal lock (|pitch| >= {} deg) and within {LOCK_SETTLE_S} s after it",
            nav440_pipeline::euler::PITCH_LIMIT_DEG
        )
    })
}

/// The fewest rows `paper` scores and `tune` tunes on: with fewer, every estimator is still at
/// its initial value and the MSEs are zero or meaningless, so both refuse (exit 2).
pub const MIN_ROWS: usize = 3;

#[cfg(test)]
mod tests {
    use super::*;

    fn s(k: u64, pitch: f32) -> Sample {
        Sample::new(k * 100_000, [0.0, pitch, 0.0], [0.0; 3], false)
    }

    /// 10 Hz: samples 3 and 4 near the lock; 5..=14 (the 1 s after sample 4) settle.
    #[test]
    fn the_lock_and_the_second_after_it_are_left_out() {
        let samples: Vec<Sample> = (0..20)
            .map(|k| s(k, if k == 3 || k == 4 { -85.0 } else { 60.0 }))
            .collect();
        let yaw = Lock::of(&samples, Axis::Yaw);
        let fed: Vec<usize> = (0..20).filter(|&k| !yaw.fed[k]).collect();
        assert_eq!(fed, [3, 4]);
        let left: Vec<usize> = (0..20).filter(|&k| !yaw.scored[k]).collect();
        assert_eq!(left, (3..=14).collect::<Vec<_>>());
        assert_eq!((yaw.near_lock, yaw.settling), (2, 10));
        assert_eq!(yaw.counts_in(&samples, (0.0, 1.9)).0, 8);
        assert_eq!(yaw.counts_in(&samples, (0.0, 1.0)).1, 8);
        let pitch = Lock::of(&samples, Axis::Pitch);
        assert!(pitch.fed.iter().chain(&pitch.scored).all(|&k| k));
        assert_eq!((pitch.near_lock, pitch.settling), (0, 0));
        assert_eq!(left_out_note(0, 5), None);
        assert_eq!(
            left_out_note(12, 20).unwrap(),
            "12 of 20 rows left out near gimbal lock (|pitch| >= 80 deg) and within 1 s after it"
        );
    }
}
