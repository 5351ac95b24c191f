//! The three attitude axes and a selection of them.

/// One attitude angle of the NAV440 (Euler angles, aerospace sequence yaw-pitch-roll).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// Roll (phi), deg, wraps at +-180 deg; body x rate p.
    Roll,
    /// Pitch (theta), deg, in [-90, 90] deg (never wraps); body y rate q.
    Pitch,
    /// Yaw (psi), deg, wraps at +-180 deg; body z rate r.
    Yaw,
}

impl Axis {
    /// Every axis, in CSV order (roll, pitch, yaw).
    pub const ALL: [Axis; 3] = [Axis::Roll, Axis::Pitch, Axis::Yaw];

    /// Index 0, 1, 2 for roll, pitch, yaw (the order of the angle and rate arrays).
    pub const fn index(self) -> usize {
        match self {
            Axis::Roll => 0,
            Axis::Pitch => 1,
            Axis::Yaw => 2,
        }
    }

    /// `"roll"`, `"pitch"` or `"yaw"` (CSV column names, `--axis` values).
    pub const fn name(self) -> &'static str {
        match self {
            Axis::Roll => "roll",
            Axis::Pitch => "pitch",
            Axis::Yaw => "yaw",
        }
    }

    /// `true` for an angle that wraps at +-180 deg and is unwrapped before estimation (roll,
    /// yaw); `false` for pitch.
    pub const fn wraps(self) -> bool {
        !matches!(self, Axis::Pitch)
    }

    /// `true` for an angle whose Euler rate is singular at pitch +-90 deg (roll, yaw): its bank
    /// is not fed near gimbal lock ([`crate::euler::near_lock`]) and restarts after it.
    pub const fn singular_near_lock(self) -> bool {
        !matches!(self, Axis::Pitch)
    }
}

/// A non-empty or empty set of axes (a bit per axis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Axes(u8);

impl Axes {
    /// Roll, pitch and yaw.
    pub const ALL: Axes = Axes(0b111);
    /// No axis.
    pub const NONE: Axes = Axes(0);

    /// The set of one axis.
    pub const fn only(axis: Axis) -> Axes {
        Axes(1 << axis.index())
    }

    /// This set with `axis` added.
    pub const fn with(self, axis: Axis) -> Axes {
        Axes(self.0 | (1 << axis.index()))
    }

    /// `true` if `axis` is in the set.
    pub const fn contains(self, axis: Axis) -> bool {
        self.0 & (1 << axis.index()) != 0
    }

    /// Number of axes in the set.
    pub const fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// `true` for the empty set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The axes of the set in CSV order (roll, pitch, yaw).
    pub fn iter(self) -> impl Iterator<Item = Axis> {
        Axis::ALL.into_iter().filter(move |a| self.contains(*a))
    }
}
