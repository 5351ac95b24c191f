//! [`GainSchedule`]: noise level -> gains.

use crate::bank::{BankConfig, BankGains};
use crate::error::positive;
use crate::family::{for_each_family, geometric, Family, FamilyVisitor, Gains, Scheduling};
use crate::FAMILY_COUNT;
use crate::{AveFamily, ConfigError};

/// Most levels a [`GainSchedule`] holds.
pub const MAX_LEVELS: usize = 8;

/// One level of a [`GainSchedule`]: the gains tuned for one noise variance.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScheduleLevel {
    /// Measurement-noise variance of the angle these gains were tuned for, deg^2 (> 0).
    pub noise_var: f32,
    /// Velocity estimators' gains.
    pub velocity: BankGains,
    /// Acceleration series' gains.
    pub acceleration: BankGains,
    /// The AVEs' switching gains `deltahat` these gains were tuned with: their mean over the
    /// tuning run (`nav440 tune --schedule` records them); `None`: not recorded. When an
    /// [`AdaptiveBank`](crate::AdaptiveBank) changes its AVE gains, it sets the AVEs' `deltahat` to these, so that
    /// the new gains do not start from the `deltahat` the old ones left (see [`AveDeltahat`]).
    pub ave_deltahat: Option<AveDeltahat>,
    /// Where each observer family moves on to the next level's gains (with
    /// [`Blend::NearestObservers`]; see [`ObserverSwitch`]); `None`: at the two levels'
    /// geometric midpoint. Ignored on the last level.
    pub switch_up: Option<ObserverSwitch>,
}

/// The noise variances (deg^2) at which each observer family (velocity and acceleration
/// gains alike) leaves a level for the next one: the noise at which the next level's gains
/// become the better of the two. `nav440 tune --schedule` records it from each level's MSE at
/// its neighbour's noise (`[level.switch_up]`).
///
/// Why not the geometric midpoint: two neighbouring levels' tuned observers can be different
/// kinds of observer, and one of them can stay the better one well past the midpoint; a
/// switch at the midpoint then runs the worse set over part of the range
/// (docs/ADAPTIVE-RESULTS.md, "Between the levels", printed by `cargo test --release -p host-tests --test schedule -- --nocapture`).
/// A value outside `[this level, next level]` is clamped into it. Each family finds its own
/// value here through [`crate::Family::switch_up_mut`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct ObserverSwitch {
    /// AVE (velocity AVE and the AVE-AVE series), deg^2.
    pub ave: f32,
    /// ILO1, ILO2, ILO3 (and their ILO-ILO series), deg^2.
    pub ilo: [f32; 3],
    /// ED (and the ED-ED series), deg^2.
    pub ed: f32,
}

impl ObserverSwitch {
    /// Every family's switch point at `x` deg^2 (a starting value to fill family by family,
    /// [`crate::Family::switch_up_mut`]).
    pub const fn all(x: f32) -> Self {
        Self {
            ave: x,
            ilo: [x; 3],
            ed: x,
        }
    }

    /// `Ok` if every value is finite and > 0.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let all = self.points();
        if all.iter().any(|(_, x)| !x.is_finite()) {
            return Err(ConfigError::NotFinite("switch_up"));
        }
        if all.iter().any(|&(_, x)| x <= 0.0) {
            return Err(ConfigError::NotPositive("switch_up"));
        }
        Ok(())
    }

    /// The switch points, deg^2, as `(column, value)` for each family that records one
    /// ([`Family::switch_up_mut`]), in column order ([`crate::FAMILIES`]).
    pub fn points(&self) -> heapless::Vec<(usize, f32), FAMILY_COUNT> {
        /// Collects the families' switch points.
        struct Points<'a>(
            &'a ObserverSwitch,
            heapless::Vec<(usize, f32), FAMILY_COUNT>,
        );
        impl FamilyVisitor for Points<'_> {
            fn family<F: Family>(&mut self, column: usize) {
                if let Some(x) = F::switch_up(self.0) {
                    // One entry per family: never full.
                    let _ = self.1.push((column, x));
                }
            }
        }
        let mut points = Points(self, heapless::Vec::new());
        for_each_family(&mut points);
        points.1
    }
}

/// The switching gains `deltahat` of a bank's AVE rows ([`crate::PaperBank::ave_deltahat`]).
///
/// Why a schedule records them: the tuned AVE gains of different noise levels can be different
/// kinds of observer (a slow AVE tuned at high noise runs with a `deltahat` of several deg/s,
/// a fast one tuned at low noise with a fraction of one). Kept through a gain change,
/// `deltahat` takes the leaky law's time constant (`1 / sigma`, 10 s) to move from the one to
/// the other, and the AVE is worse than either fixed set in the seconds after the change; set
/// to the value the new gains were tuned with, it is not (docs/ADAPTIVE-RESULTS.md, "Forty
/// noise draws", printed by `cargo test --release -p host-tests --test schedule -- --nocapture`). A warm start replays with these
/// values.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AveDeltahat {
    /// The velocity AVE's `deltahat`, deg/s (finite, >= 0).
    pub velocity: f32,
    /// The AVE-AVE acceleration series' first stage's (deg/s) and second stage's (deg/s^2)
    /// (finite, >= 0). The first stage is the velocity AVE itself when both have the same
    /// gains; then its value is the velocity's.
    pub acceleration: [f32; 2],
}

impl AveDeltahat {
    /// `Ok` if every value is finite and >= 0.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let all = [self.velocity, self.acceleration[0], self.acceleration[1]];
        if all.iter().any(|x| !x.is_finite()) {
            return Err(ConfigError::NotFinite("ave_deltahat"));
        }
        if all.iter().any(|&x| x < 0.0) {
            return Err(ConfigError::Negative("ave_deltahat"));
        }
        Ok(())
    }
}

/// A gain schedule: 1 to [`MAX_LEVELS`] levels in increasing noise variance. Between two
/// levels a gain is interpolated geometrically in the noise variance (linear in
/// `ln(noise_var)` and `ln(gain)`: gains span decades), the ILO's `K1` through its leak
/// `1 - K1` (linearly where a leak is 0), or taken from the nearer level, per [`Blend`]
/// (default: geometric for the AD and the tracker, nearer level for the AVE, ILO and ED);
/// below the first level and above the last, the end level's gains are used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GainSchedule {
    levels: [ScheduleLevel; MAX_LEVELS],
    len: usize,
    blend: Blend,
    /// The nominal sample period the levels were tuned at, s (`None`: not recorded).
    period_s: Option<f32>,
    /// The jerk power of the motion the levels were tuned on, (deg/s^3)^2 (`None`: not
    /// recorded).
    jerk: Option<f32>,
    /// Its acceleration power, (deg/s^2)^2 (`None`: not recorded).
    acceleration: Option<f32>,
}

/// A [`GainSchedule`] fits a bank whose nominal sample period is within this factor of the
/// period the schedule was tuned at ([`GainSchedule::fits_period`]). The NAV440's packet rates
/// (1, 2, 4, 5, 10, 20, 25, 50, 100 Hz) differ by at least 1.25x from one to the next, so
/// 1.2 accepts the rate a schedule was tuned at (and the warm-up's measured period of it) and
/// no other.
pub const PERIOD_TOLERANCE: f32 = 1.2;

/// The noise variances (deg^2) a [`GainSchedule`] picks each family's gains for, in column
/// order ([`crate::FAMILIES`]): the noise estimate for every family of a bank that follows the
/// noise alone, and each scaled by the measure of the motion the family follows
/// ([`crate::Follows`]) for one that follows the motion too.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels(pub [f32; FAMILY_COUNT]);

impl Levels {
    /// `noise_var` (deg^2) for every family.
    pub const fn all(noise_var: f32) -> Self {
        Levels([noise_var; FAMILY_COUNT])
    }
}

/// How a [`GainSchedule`] blends two levels' gains between them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Blend {
    /// Every gain geometrically (linear in `ln(noise_var)` and `ln(gain)`).
    Geometric,
    /// The AD's `T` and the tracker's `q`, `r` geometrically; the AVE, ILO and ED take the
    /// gains of the nearer level (in `ln(noise_var)`). Default: the tuned AVE, ILO and ED
    /// gains are often lightly damped observers whose ringing is tuned to the sample period
    /// (a whole number of ringing periods per sample, so the samples do not see it); a blend
    /// of two such sets is no longer in tune and rings in the output. The AD and the tracker
    /// have one smooth gain. Which families are which: [`crate::Family::SCHEDULING`].
    #[default]
    NearestObservers,
}

/// `x` limited to `[lo, hi]` (`lo <= hi`), as `f32::clamp` computes it (a NaN stays NaN), but
/// without its `lo <= hi` assertion, whose message would link `core::fmt`'s float formatting
/// into every firmware that runs a schedule.
fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

impl GainSchedule {
    /// A schedule of `levels` (1 to [`MAX_LEVELS`], noise variances finite, > 0 and strictly
    /// increasing). The gains themselves are validated when a bank is built from them.
    pub fn new(levels: &[ScheduleLevel]) -> Result<Self, ConfigError> {
        if levels.is_empty() || levels.len() > MAX_LEVELS {
            return Err(ConfigError::ScheduleLevels);
        }
        let mut prev = 0.0f32;
        for l in levels {
            if !l.noise_var.is_finite() {
                return Err(ConfigError::NotFinite("noise_var"));
            }
            if l.noise_var <= prev {
                return Err(ConfigError::ScheduleLevels);
            }
            prev = l.noise_var;
            if let Some(d) = &l.ave_deltahat {
                d.validate()?;
            }
            if let Some(w) = &l.switch_up {
                w.validate()?;
            }
        }
        let mut s = GainSchedule {
            levels: [levels[0]; MAX_LEVELS],
            len: levels.len(),
            blend: Blend::default(),
            period_s: None,
            jerk: None,
            acceleration: None,
        };
        s.levels[..levels.len()].copy_from_slice(levels);
        Ok(s)
    }

    /// This schedule with the blend `blend` (default [`Blend::NearestObservers`]).
    pub fn with_blend(self, blend: Blend) -> Self {
        Self { blend, ..self }
    }

    /// How levels are blended.
    pub fn blend(&self) -> Blend {
        self.blend
    }

    /// This schedule, recorded as tuned at the nominal sample period `period_s` (s, finite and
    /// positive; `nav440 tune --schedule` records the capture's). The observers' tuned gains
    /// are tied to the sample period they were tuned at (a tuned ILO can ring at a frequency
    /// the samples at that rate do not see, see [`Blend`]): run at another rate, a schedule's
    /// gains can be worse than the fixed `BankConfig::NAV440` preset's
    /// (docs/ADAPTIVE-RESULTS.md, "Low packet rates"). The
    /// schedule still runs at any rate; [`AdaptiveBank::period_fits`](crate::AdaptiveBank::period_fits) tells whether it was
    /// tuned for its bank's.
    pub fn with_sample_period(self, period_s: f32) -> Result<Self, ConfigError> {
        positive("sample_period_s", f64::from(period_s))?;
        Ok(Self {
            period_s: Some(period_s),
            ..self
        })
    }

    /// This schedule with what a schedule file or its Rust twin records, each when it does:
    /// the sample period tuned at ([`Self::with_sample_period`]), the tuning motion's jerk
    /// power ([`Self::with_tuned_jerk`]) and its acceleration power
    /// ([`Self::with_tuned_acceleration`]).
    pub fn with_records(
        self,
        period_s: Option<f32>,
        tuned_jerk: Option<f32>,
        tuned_acceleration: Option<f32>,
    ) -> Result<Self, ConfigError> {
        let mut s = self;
        if let Some(p) = period_s {
            s = s.with_sample_period(p)?;
        }
        if let Some(j) = tuned_jerk {
            s = s.with_tuned_jerk(j)?;
        }
        match tuned_acceleration {
            Some(a) => s.with_tuned_acceleration(a),
            None => Ok(s),
        }
    }

    /// This schedule, recorded as tuned on a motion of jerk power `jerk` ((deg/s^3)^2, finite
    /// and positive; fig5's is about 3.7e6: [`crate::AdaptiveProductConfig::START_JERK`] over
    /// 1-30 s of the synthetic motion, 3.85e6 over the whole bundled capture).
    /// An [`AdaptiveBank`](crate::AdaptiveBank) given the rate then follows the motion as well
    /// as the noise: on a motion of jerk power `J` more than `m` times above it, it picks a
    /// family's gains for `V x m x jerk / J` instead of the noise estimate `V` (lighter
    /// filtering, less lag); more than `m` times below it, for `V x jerk / (m x J)` (heavier
    /// filtering); in between, the noise's as without (`m`:
    /// [`crate::AdaptiveConfig::jerk_margin`] for the observers,
    /// [`crate::AdaptiveConfig::smooth_jerk_margin`] for the tracker; the AD follows the
    /// acceleration power instead when it is recorded too, [`Self::with_tuned_acceleration`];
    /// docs/MOTION-FAMILY.md, "A schedule that follows the motion").
    pub fn with_tuned_jerk(self, jerk: f32) -> Result<Self, ConfigError> {
        positive("tuned_jerk_power", f64::from(jerk))?;
        Ok(Self {
            jerk: Some(jerk),
            ..self
        })
    }

    /// This schedule, recorded as tuned on a motion of acceleration power `acceleration`
    /// ((deg/s^2)^2, finite and positive; the bundled fig5 capture's is 1.43e5). With a
    /// recorded jerk power ([`Self::with_tuned_jerk`]) too, an
    /// [`AdaptiveBank`](crate::AdaptiveBank) given the rate picks the gains of the families
    /// that follow the acceleration ([`crate::Follows::Acceleration`]: the AD) for
    /// `V x acceleration / A` on a motion of acceleration power `A`, without a margin.
    pub fn with_tuned_acceleration(self, acceleration: f32) -> Result<Self, ConfigError> {
        positive("tuned_acceleration_power", f64::from(acceleration))?;
        Ok(Self {
            acceleration: Some(acceleration),
            ..self
        })
    }

    /// The acceleration power of the motion the schedule was tuned on, (deg/s^2)^2 (`None` if
    /// not recorded).
    pub fn tuned_acceleration(&self) -> Option<f32> {
        self.acceleration
    }

    /// The jerk power of the motion the schedule was tuned on, (deg/s^3)^2 (`None` if not
    /// recorded: the gains follow the noise alone).
    pub fn tuned_jerk(&self) -> Option<f32> {
        self.jerk
    }

    /// The nominal sample period the schedule was tuned at, s (`None` if not recorded).
    pub fn sample_period_s(&self) -> Option<f32> {
        self.period_s
    }

    /// `true` if the schedule was tuned for a nominal sample period of `period_s` (s): within
    /// a factor [`PERIOD_TOLERANCE`] of the recorded one, or none is recorded.
    pub fn fits_period(&self, period_s: f32) -> bool {
        match self.period_s {
            None => true,
            Some(p) => period_s <= p * PERIOD_TOLERANCE && period_s * PERIOD_TOLERANCE >= p,
        }
    }

    /// The levels, in increasing noise variance.
    pub fn levels(&self) -> &[ScheduleLevel] {
        &self.levels[..self.len]
    }

    /// The top level's noise variance, deg^2.
    pub fn top(&self) -> f32 {
        self.levels()[self.len - 1].noise_var
    }

    /// `noise_var` (deg^2) clamped to the schedule's range.
    pub fn clamp(&self, noise_var: f32) -> f32 {
        let l = self.levels();
        let (lo, hi) = (l[0].noise_var, l[l.len() - 1].noise_var);
        if noise_var.is_nan() {
            lo
        } else {
            clamp(noise_var, lo, hi)
        }
    }

    /// The interpolated gains (velocity, acceleration) for `noise_var`, deg^2: each family's
    /// gains between the two levels around it ([`Gains::interpolate`]) with the family's
    /// weight ([`Self::family_weight`]).
    pub fn gains_at(&self, noise_var: f32) -> (BankGains, BankGains) {
        self.gains_for(Levels::all(noise_var))
    }

    /// [`Self::gains_at`] with each family's gains for its own noise variance in `levels`.
    pub fn gains_for(&self, levels: Levels) -> (BankGains, BankGains) {
        /// Interpolates each family's gains into `out` (velocity, acceleration).
        struct Blended<'a> {
            schedule: &'a GainSchedule,
            levels: Levels,
            out: (BankGains, BankGains),
        }
        impl FamilyVisitor for Blended<'_> {
            fn family<F: Family>(&mut self, column: usize) {
                let s = self.schedule;
                let v = self.levels.0[column];
                let (a, upper) = s.bracket(v);
                let (b, w) = match upper {
                    Some((b, w)) => (b, s.family_weight::<F>(a, b, v, w)),
                    None => (a, 0.0),
                };
                let blend = |x: &BankGains, y: &BankGains| F::get(x).interpolate(&F::get(y), w);
                F::set(&mut self.out.0, blend(&a.velocity, &b.velocity));
                F::set(&mut self.out.1, blend(&a.acceleration, &b.acceleration));
            }
        }
        let first = &self.levels()[0];
        let mut blended = Blended {
            schedule: self,
            levels,
            out: (first.velocity, first.acceleration),
        };
        for_each_family(&mut blended);
        blended.out
    }

    /// The weight of the upper level `b` for the family `F` between the levels `a` and `b`
    /// at `noise_var` (deg^2), whose geometric weight is `w` (in `[0, 1]`): `w` for a
    /// [`Scheduling::Smooth`] family and with [`Blend::Geometric`]; for an observer with
    /// [`Blend::NearestObservers`], 1 at or past the family's switch point (`a`'s
    /// [`ScheduleLevel::switch_up`], clamped to `[a, b]`; without one, the geometric
    /// midpoint), else 0.
    pub fn family_weight<F: Family>(
        &self,
        a: &ScheduleLevel,
        b: &ScheduleLevel,
        noise_var: f32,
        w: f32,
    ) -> f32 {
        if F::SCHEDULING == Scheduling::Smooth || self.blend == Blend::Geometric {
            return w;
        }
        let up = match a.switch_up.as_ref().and_then(F::switch_up) {
            Some(t) => self.clamp(noise_var) >= clamp(t, a.noise_var, b.noise_var),
            None => w >= 0.5,
        };
        if up {
            1.0
        } else {
            0.0
        }
    }

    /// The levels around `noise_var` (deg^2, clamped to the schedule): the last level at or
    /// below it, and the next one with the weight of `noise_var` between the two (0 to 1,
    /// linear in `ln(noise_var)`), if there is a next one.
    fn bracket(&self, noise_var: f32) -> (&ScheduleLevel, Option<(&ScheduleLevel, f32)>) {
        let l = self.levels();
        let v = self.clamp(noise_var);
        let i = l.iter().rposition(|x| x.noise_var <= v).unwrap_or(0);
        let a = &l[i];
        let upper = l.get(i + 1).map(|b| {
            let w = libm::logf(v / a.noise_var) / libm::logf(b.noise_var / a.noise_var);
            (b, w)
        });
        (a, upper)
    }

    /// The recorded AVE switching gains for `noise_var` (deg^2): those of the level whose AVE
    /// gains [`Self::gains_at`] takes (the nearer level in `ln(noise_var)` with
    /// [`Blend::NearestObservers`]; interpolated geometrically with [`Blend::Geometric`]).
    /// `None` if the level at or below `noise_var` has none recorded, or the level above it
    /// when that one is taken or interpolated with.
    pub fn ave_deltahat_at(&self, noise_var: f32) -> Option<AveDeltahat> {
        let (a, upper) = self.bracket(noise_var);
        let da = a.ave_deltahat?;
        let Some((b, w)) = upper else {
            return Some(da);
        };
        let w = self.family_weight::<AveFamily>(a, b, noise_var, w);
        if w <= 0.0 {
            return Some(da);
        }
        let db = b.ave_deltahat?;
        Some(AveDeltahat {
            velocity: geometric(da.velocity, db.velocity, w),
            acceleration: [
                geometric(da.acceleration[0], db.acceleration[0], w),
                geometric(da.acceleration[1], db.acceleration[1], w),
            ],
        })
    }

    /// `base` with the gains for `noise_var` (deg^2).
    pub fn config_at(&self, base: &BankConfig, noise_var: f32) -> BankConfig {
        self.config_for(base, Levels::all(noise_var))
    }

    /// `base` with the gains for `levels` ([`Self::gains_for`]).
    pub fn config_for(&self, base: &BankConfig, levels: Levels) -> BankConfig {
        let (velocity, acceleration) = self.gains_for(levels);
        BankConfig {
            velocity,
            acceleration,
            ..*base
        }
    }
}
