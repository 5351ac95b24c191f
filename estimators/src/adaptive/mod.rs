//! Noise-adaptive gains (docs/ADAPTIVE-GAINS.md): the bank estimates the
//! measurement-noise variance of its angle online ([`NoiseEstimator`]) and interpolates its
//! gains from a [`GainSchedule`] (noise level -> gains, written by
//! `nav440 tune --schedule ... [-o FILE.toml] [--rust FILE.rs]`); [`AdaptiveBank`] is the
//! paper bank driven that way.
//!
//! Everything here is `no_std`, heap-free and bounded: the noise estimate costs a few f32
//! operations per sample (in f32 for every [`Real`]: the input angle is an f32 anyway); the
//! gains are re-interpolated and the laws' coefficients rebuilt at most once every
//! [`AdaptiveConfig::retune_every`] samples (twice for a schedule that follows the motion,
//! when the motion picks up: [`AdaptiveBank`]), and only when the estimate moved by more than
//! the factor [`AdaptiveConfig::retune_ratio`] from the level the current gains were made for.

mod jerk;
mod kalman;
mod noise;
mod product;
mod schedule;
mod selftune;
#[cfg(test)]
mod tests;

pub use jerk::*;
pub use kalman::*;
pub use noise::*;
pub use product::*;
pub use schedule::*;
pub use selftune::*;

use crate::bank::{BankConfig, BankGains, PaperBank, PaperOutput};
use crate::family::{Family, FamilyVisitor, Follows, Scheduling};
use crate::{ConfigError, NativeSqrt, Real, SampleError, SqrtFn};

/// The bandwidth (rad/s) of the observers' gains past a schedule's top level, at the level
/// `v` (deg^2): the jerk index's rule `c (J / (V dt))^(1/6)` ([`SelfTuneConfig::ANCHOR_C`],
/// the first alias) for the schedule's tuning motion (`J` its recorded jerk power `tuned`,
/// (deg/s^3)^2) at the noise `v`, the level being that motion's equivalent noise; at least
/// 2 rad/s and at most 80 % of the Nyquist frequency, the sample period `dt` in s.
fn past_top_wn(tuned: f32, v: f32, dt: f32) -> f64 {
    product::bounded_jerk_index_wn(
        f64::from(SelfTuneConfig::ANCHOR_C),
        f64::from(tuned),
        f64::from(v),
        f64::from(dt),
        f64::from(SelfTuneConfig::ZETA),
    )
}

/// How far past a schedule's top level (as a factor of its noise variance) the families that
/// go on past it ([`crate::Gains::PAST_TOP`]: the ILOs and the ED) leave its gains for their
/// own ([`crate::Gains::past_top`]). Just past the top the ILO rule's per-sample poles lag a
/// unit that starts to move more than the top level's tuned set (fig5 after a minute at rest,
/// first 4 s of motion at 0.01 deg^2: ILO1 1.30x the noise alone from the top level on,
/// 1.15x from 8 times it; docs/MOTION-FAMILY.md, "Past the top level").
pub const PAST_TOP_FACTOR: f32 = 8.0;

/// When a bank that follows its estimates checks its gains: at a tick every `every` samples,
/// and at most once in between, early, when the motion picks up ([`AdaptiveBank`],
/// [`AdaptiveProductBank`]): so at most twice per `every` samples.
#[derive(Clone, Copy, Debug, Default)]
struct Cadence {
    /// Samples since the last tick.
    since: u32,
    /// An early check came since the last tick.
    early: bool,
}

impl Cadence {
    /// Counts a sample: `true` at a tick (every `every` samples), which opens a new interval.
    fn tick(&mut self, every: u32) -> bool {
        self.since = self.since.saturating_add(1);
        let tick = self.since >= every;
        if tick {
            self.since = 0;
            self.early = false;
        }
        tick
    }

    /// Whether this interval still has its early check.
    fn early_open(&self) -> bool {
        !self.early
    }

    /// This interval's early check came.
    fn take_early(&mut self) {
        self.early = true;
    }

    /// The next sample is a tick (of an interval of `every` samples).
    fn tick_next(&mut self, every: u32) {
        self.since = every.saturating_sub(1);
    }
}

/// Sets the columns of `dst` that `mask` marks (bank column order) to `src`'s.
fn copy_columns(dst: &mut BankGains, src: &BankGains, mask: [bool; crate::FAMILY_COUNT]) {
    struct Copy<'a>(
        &'a mut BankGains,
        &'a BankGains,
        [bool; crate::FAMILY_COUNT],
    );
    impl FamilyVisitor for Copy<'_> {
        fn family<F: Family>(&mut self, column: usize) {
            if self.2[column] {
                F::set(self.0, F::get(self.1));
            }
        }
    }
    crate::for_each_family(&mut Copy(dst, src, mask));
}

/// Whether a sample interval `dt` (µs) continues a steady stream whose previous interval was
/// `dt_prev` (µs; 0: none yet): within a quarter of it. A lost packet, a gap, a new epoch or
/// a repeated time (0) is not; the noise and jerk estimators then restart their differences.
fn steady_interval(dt: u64, dt_prev: u64) -> bool {
    dt_prev > 0 && 4 * dt.abs_diff(dt_prev) <= dt_prev
}

/// Samples for an observer restarted from a velocity of 0 at the bandwidth `wn_rad_s` and the
/// damping `zeta` to settle (within 2 % after `4 / (zeta wn)` s), at the sample period
/// `dt_s`: how long a bank that moves ILO1's gains keeps the start's after a restart.
fn settle_samples(wn_rad_s: f64, zeta: f64, dt_s: f32) -> u32 {
    libm::ceil(4.0 / (zeta * wn_rad_s) / f64::from(dt_s)).min(f64::from(u16::MAX)) as u32
}

/// Takes the term `x` into the exponentially weighted mean `mean` of `count` terms so far:
/// weight `1 / count` (a plain mean while it starts), at least `alpha` (`dt / tau`).
fn mean_step(mean: &mut f32, count: &mut u32, alpha: f32, x: f32) {
    *count = count.saturating_add(1);
    let w = (1.0 / *count as f32).max(alpha);
    *mean += w * (x - *mean);
}

/// How an [`AdaptiveBank`] follows the noise.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdaptiveConfig {
    /// Time constant of the noise estimate, s (default 0.5; at least
    /// [`NoiseEstimator::MIN_TAU_SAMPLES`] sample periods: 2.5 s at 20 Hz).
    pub tau_s: f32,
    /// Noise variance the gains start at, deg^2 (default 0.01, the paper's small noise).
    pub initial_noise_var: f32,
    /// The gains are reconsidered every this many samples (default 20: 0.2 s at 100 Hz),
    /// and, with a schedule that follows the motion, once in between when the motion picks
    /// up (see [`AdaptiveBank`], "A motion that picks up").
    pub retune_every: u32,
    /// ... and changed only when the estimate (clamped to the schedule) differs from the level
    /// of the current gains by more than this factor either way (default 1.5, above the
    /// jitter of the estimate at a steady noise level with the default time constant, so that
    /// a steady level does not retune at every chance; a smaller ratio follows the noise more
    /// closely with more gain changes: docs/ADAPTIVE-RESULTS.md, "Gain-change rate").
    pub retune_ratio: f32,
    /// A gain change replays the last this many samples (at most [`REPLAY_CAPACITY`]) through
    /// the new gains (warm start, [`PaperBank::set_gains_replaying`]); 0: the states are moved
    /// to the new gains' equilibrium instead (bumpless, [`PaperBank::set_gains`]).
    pub replay_samples: u32,
    /// With a schedule that records the jerk power of the motion it was tuned on
    /// ([`GainSchedule::tuned_jerk`]), the bank estimates the motion's jerk power `J` from the
    /// rate it is given ([`crate::EstimatorBank::observe_rate`], [`JerkEstimator`] with its
    /// default time constant) and picks the observers' gains (the AVE, the ILOs, the ED) for
    /// the noise estimate `V` scaled by the jerk index beyond this margin `m` (default 8, at
    /// least 1; the smooth families: [`Self::smooth_jerk_margin`] and
    /// [`crate::Follows`]): `V x m x tuned / J` for a
    /// motion that moves more than `m` times as hard as the tuning motion (the gains of a
    /// lower noise: lighter filtering, less lag), `V x tuned / (m x J)` for one that moves
    /// less than `1 / m` times as hard (the gains of a higher noise: heavier filtering, which
    /// a smooth motion such as a steady spin can afford), `V` for any other. The margin keeps
    /// the paper-like motions, whose jerk power moves by a few times from stroke to pause, on
    /// the noise's gains (docs/MOTION-FAMILY.md, "A schedule that follows the motion").
    pub jerk_margin: f32,
    /// The margin of [`Self::jerk_margin`] for the smooth families that follow the jerk
    /// ([`crate::Follows::Jerk`], [`crate::Scheduling::Smooth`]: the tracker; default 4, at
    /// least 1). The tracker's best process noise grows with the jerk power (`q = kappa J`,
    /// [`crate::AdaptiveKalman`]), so it follows a motion from closer than the observers,
    /// whose tuned gains hold over a wider band; a margin of 1 would move it with every
    /// stroke and pause of a hand's motion (docs/MOTION-FAMILY.md, "A schedule that follows
    /// the motion").
    pub smooth_jerk_margin: f32,
}

/// Most samples an [`AdaptiveBank`] keeps for a warm-start gain change.
pub const REPLAY_CAPACITY: usize = 64;

impl AdaptiveConfig {
    /// The defaults (see the fields).
    pub const DEFAULT: Self = Self {
        tau_s: 0.5,
        initial_noise_var: 0.01,
        retune_every: 20,
        retune_ratio: 1.5,
        replay_samples: REPLAY_CAPACITY as u32,
        jerk_margin: 8.0,
        smooth_jerk_margin: 4.0,
    };
}

impl Default for AdaptiveConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The paper bank ([`PaperBank`]) with noise-adaptive gains: every sample also updates a
/// [`NoiseEstimator`]; at most every [`AdaptiveConfig::retune_every`] samples, if the
/// estimate left the band `[level / ratio, level * ratio]` around the level the current
/// gains were interpolated for, the gains for the estimate are interpolated from the
/// schedule and the laws' coefficients rebuilt (see [`AdaptiveBank::retune`]). Generic over
/// [`Real`] like the bank (`AdaptiveBank<Fx>` for FPU-less cores; the noise estimate and the
/// interpolation are f32 there too). A schedule that records the jerk power of its tuning
/// motion ([`GainSchedule::with_tuned_jerk`]) makes the bank follow the motion too, from the
/// rate it is given (see [`AdaptiveConfig::jerk_margin`]).
///
/// **A motion that picks up.** Once its noise estimate has settled
/// ([`NoiseEstimator::settled`]), such a bank also computes the levels at every sample
/// between two retune ticks, and retunes at once, once per interval, when a level falls by
/// more than the jerk margin: a motion that starts, or a sharp turn after a pause (a
/// tumble's pitch that reverses in a few samples as the unit nods through the vertical),
/// takes its lighter gains within a sample or two of its onset, and the warm start replays
/// the samples before it through them. (At the default interval the settled noise estimate
/// alone falls by at most `0.98^20` = 0.67 between two ticks: a fall by the margin is the
/// motion's.) The check costs the levels' arithmetic per sample (no `libm` call); a bank
/// then changes its gains at most twice per [`AdaptiveConfig::retune_every`] samples
/// (docs/MOTION-FAMILY.md, "A schedule that follows the motion").
///
/// **Past the top level.** A motion far gentler than the tuning motion (a steady spin) takes
/// its observers' level past the schedule's top one. More than [`PAST_TOP_FACTOR`] times it,
/// once the jerk estimate has run for its time constant, the ILOs take per-sample poles at the
/// jerk index's bandwidth for that level (`K1 = 1`: they hold a constant rate, where a
/// schedule tuned on a back-and-forth motion may not), and the ED a lower `alpha` for the
/// motion's lower acceleration ([`crate::Gains::past_top`]; the other families keep the top
/// level's). Those gains move bumplessly (their bandwidth is below what a replay settles)
/// unless the level falls by more than the jerk margin, and they follow the acceleration
/// power too (docs/MOTION-FAMILY.md, "Past the top level").
///
/// **Warm start.** The bank keeps what its laws were fed for the last
/// [`AdaptiveConfig::replay_samples`] samples (at most [`REPLAY_CAPACITY`], 64: 0.64 s at
/// 100 Hz, 3.2 s at 20 Hz; `64 * size_of::<Fed<T>>()` bytes: 1,536 for f32, 2,560 for `Fx`),
/// and a gain change replays them through the rows whose gains changed
/// ([`PaperBank::set_gains_warm`]; the ED and the ILO-ILO and AD-AD series change
/// bumplessly): those rows then continue as if they had run the new gains over that history,
/// which also covers most of the noise estimate's delay in noticing a change. The replayed
/// rows start the new gains from where those gains would be, not from the old gains' states,
/// so the estimates settle faster after a change than with a bumpless one (measured on a
/// noise switch and over many noise draws: docs/ADAPTIVE-RESULTS.md, printed by
/// `cargo test --release -p host-tests --test schedule -- --nocapture`). Cost: one sample of the whole bank per replayed sample on top of the
/// coefficients' rebuild (`cargo xtask bench`).
#[derive(Clone, Debug)]
pub struct AdaptiveBank<T: Real, S: SqrtFn<T> = NativeSqrt> {
    bank: PaperBank<T, S>,
    base: BankConfig,
    schedule: GainSchedule,
    noise: NoiseEstimator,
    /// The motion's jerk estimate, for a schedule that records its tuning motion's
    /// ([`GainSchedule::tuned_jerk`]).
    jerk: Option<JerkEstimator>,
    cfg: AdaptiveConfig,
    level: Levels,
    /// The gains (velocity, acceleration) the bank runs.
    gains: (BankGains, BankGains),
    /// The acceleration ratio they were made with ([`Self::acceleration_ratio`]).
    ratio: f32,
    /// The retune ticks and the early retune (see [`Self::update`]).
    cadence: Cadence,
    /// [`Self::past_top_max`] once the jerk estimate has settled.
    past_top_max: Option<f32>,
    retunes: u32,
    history: heapless::HistoryBuf<crate::Fed<T>, REPLAY_CAPACITY>,
}

impl<T: Real, S: SqrtFn<T>> AdaptiveBank<T, S> {
    /// A bank with `base`'s step, hold, period, gap rule and unwrapping, and the gains of
    /// `schedule` at `cfg.initial_noise_var`.
    pub fn new(
        base: &BankConfig,
        schedule: &GainSchedule,
        cfg: &AdaptiveConfig,
    ) -> Result<Self, ConfigError> {
        if !(cfg.retune_ratio.is_finite() && cfg.initial_noise_var.is_finite()) {
            return Err(ConfigError::NotFinite("retune_ratio"));
        }
        // `!(>= 1)`: NaN refused too.
        for (m, name) in [
            (cfg.jerk_margin, "jerk_margin"),
            (cfg.smooth_jerk_margin, "smooth_jerk_margin"),
        ] {
            if !(m >= 1.0 && m.is_finite()) {
                return Err(ConfigError::NotPositive(name));
            }
        }
        if cfg.retune_ratio < 1.0 || cfg.initial_noise_var <= 0.0 {
            return Err(ConfigError::NotPositive("retune_ratio"));
        }
        let jerk = match schedule.tuned_jerk() {
            Some(_) => {
                let j = JerkEstimator::new(JerkEstimator::DEFAULT_TAU_S, base.sample_period_s)?;
                Some(match schedule.tuned_acceleration() {
                    Some(_) => j.with_acceleration(),
                    None => j,
                })
            }
            None => None,
        };
        // Where the ILO rule past the top reaches its lowest bandwidth
        // ([`Self::past_top_max`]).
        let past_top_max = schedule.tuned_jerk().map(|tuned| {
            let c = f64::from(SelfTuneConfig::ANCHOR_C) / product::WN_MIN;
            let dt = f64::from(base.sample_period_s);
            let max = f64::from(tuned) / dt * libm::pow(c, 6.0);
            (max as f32).max(schedule.top() * PAST_TOP_FACTOR)
        });
        let level = Levels::all(schedule.clamp(cfg.initial_noise_var));
        let gains = schedule.gains_for(level);
        let bank = PaperBank::new(&BankConfig {
            velocity: gains.0,
            acceleration: gains.1,
            ..*base
        })?;
        // Every level must build (so that a retune never fails half-way).
        for l in schedule.levels() {
            <crate::PaperRows as crate::Rows<T, S>>::build(
                &schedule.config_at(base, l.noise_var),
                0,
                None,
            )?;
        }
        Ok(AdaptiveBank {
            bank,
            base: *base,
            schedule: *schedule,
            noise: NoiseEstimator::new(cfg.tau_s, base.sample_period_s)?,
            jerk,
            cfg: *cfg,
            level,
            gains,
            ratio: 1.0,
            cadence: Cadence::default(),
            past_top_max,
            retunes: 0,
            history: heapless::HistoryBuf::new(),
        })
    }

    /// Feeds one sample (as [`PaperBank::update`]); the noise estimate is updated with it and
    /// the gains follow it, at the retune ticks and when the motion picks up (see the type).
    pub fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<PaperOutput<T>, SampleError> {
        let (out, fed) = self.bank.update_fed(t_us, angle_deg)?;
        if self.cfg.replay_samples > 0 {
            self.history.write(fed);
        }
        self.noise.update(t_us, angle_deg);
        let tick = self.cadence.tick(self.cfg.retune_every);
        // Between ticks, with a schedule that follows the motion and a settled noise
        // estimate, once: a motion that picks up (a level falls by more than the jerk
        // margin) is retuned at once.
        let early =
            !tick && self.cadence.early_open() && self.jerk.is_some() && self.noise.settled();
        if tick || early {
            if let Some((v, noise)) = self.index() {
                let v = self.clamp(v);
                if early {
                    let m = self.cfg.jerk_margin;
                    if !v.0.iter().zip(self.level.0).any(|(v, l)| *v * m < l) {
                        return Ok(out);
                    }
                    self.cadence.take_early();
                }
                // Each family's level moves when its index leaves the band around it; the
                // others keep theirs.
                let r = self.cfg.retune_ratio;
                let mut next = self.level;
                let mut left = false;
                for (l, v) in next.0.iter_mut().zip(v.0) {
                    if v > *l * r || v * r < *l {
                        *l = v;
                        left = true;
                    }
                }
                // Past the top level the gains follow the acceleration too
                // ([`crate::PastTop::acceleration_ratio`]): they move when it leaves the band
                // around the one they were made with and that changes them.
                let a = self.acceleration_ratio();
                let from = self.past_top_from();
                let past = (self.level.0.iter().zip(crate::FAMILIES))
                    .any(|(l, f)| f.past_top && *l > from);
                if !left && past && (a > self.ratio * r || a * r < self.ratio) {
                    if self.gains(self.level) == self.gains {
                        self.ratio = a;
                    } else {
                        left = true;
                    }
                }
                if left {
                    // The AVEs' switching gains follow the error they switch on, which the
                    // noise sets: those recorded for the noise estimate, whatever level the
                    // jerk index picks.
                    self.retune_with(next, noise);
                }
            }
        }
        Ok(out)
    }

    /// The noise variances each family's gains are picked for, deg^2, and the noise estimate
    /// `V`: `V` for every family, or with a schedule that records its tuning motion's jerk
    /// power ([`GainSchedule::tuned_jerk`]) and a jerk estimate `J`, `V` scaled by the motion
    /// the family follows ([`crate::Follows`]): by the jerk index beyond a margin `m`,
    /// `V x m x tuned / J` when `J > m x tuned` and `V x tuned / (m x J)` when
    /// `J < tuned / m` ([`AdaptiveConfig::jerk_margin`] for the observers,
    /// [`AdaptiveConfig::smooth_jerk_margin`] for the smooth families), or, for a family that
    /// follows the acceleration and a schedule that records its tuning motion's
    /// ([`GainSchedule::tuned_acceleration`]), `V x tuned / A` for an acceleration power `A`.
    fn index(&self) -> Option<(Levels, f32)> {
        let v = self.noise.variance()?;
        let Some(jerk) = self.jerk.as_ref() else {
            return Some((Levels::all(v), v));
        };
        let by = |tuned: Option<f32>, now: Option<f32>, m: f32| match (tuned, now) {
            (Some(tuned), Some(j)) if j > m * tuned && j.is_finite() => v * (m * tuned / j),
            // A motion that does not move at all (`J` = 0) takes the top level.
            (Some(tuned), Some(j)) if j * m < tuned && j >= 0.0 => {
                if j > 0.0 {
                    v * (tuned / (m * j))
                } else {
                    f32::MAX
                }
            }
            _ => v,
        };
        let s = &self.schedule;
        let by_jerk = |m: f32| by(s.tuned_jerk(), jerk.power(), m);
        let (observers, smooth) = (
            by_jerk(self.cfg.jerk_margin),
            by_jerk(self.cfg.smooth_jerk_margin),
        );
        let acceleration = match s.tuned_acceleration() {
            Some(a) => by(Some(a), jerk.acceleration_power(), 1.0),
            None => smooth,
        };
        let mut levels = Levels::all(v);
        for (l, f) in levels.0.iter_mut().zip(crate::FAMILIES) {
            *l = match (f.follows, f.scheduling) {
                (Follows::Acceleration, _) => acceleration,
                (Follows::Jerk, Scheduling::Observer) => observers,
                (Follows::Jerk, Scheduling::Smooth) => smooth,
            };
        }
        Some((levels, v))
    }

    /// `levels` clamped to the schedule's range; with a schedule that records its tuning
    /// motion's jerk power, the levels of the families that go on past the top level
    /// ([`crate::Gains::PAST_TOP`]) only from below, and from above at [`Self::past_top_max`].
    fn clamp(&self, mut levels: Levels) -> Levels {
        let max = self.past_top_max();
        for (l, f) in levels.0.iter_mut().zip(crate::FAMILIES) {
            *l = match max {
                Some(max) if f.past_top && *l > max => max,
                Some(_) if f.past_top && *l > self.past_top_from() => *l,
                _ => self.schedule.clamp(*l),
            };
        }
        levels
    }

    /// The motion's acceleration power over the schedule's tuning motion's
    /// ([`GainSchedule::tuned_acceleration`]); 1 where either is not known.
    fn acceleration_ratio(&self) -> f32 {
        let now = self.jerk.as_ref().and_then(|j| j.acceleration_power());
        match (self.schedule.tuned_acceleration(), now) {
            (Some(tuned), Some(a)) if a.is_finite() && a >= 0.0 => a / tuned,
            _ => 1.0,
        }
    }

    /// The level (deg^2) past which the families that go on past the top level take
    /// [`crate::Gains::past_top`]: [`PAST_TOP_FACTOR`] times the top level's.
    fn past_top_from(&self) -> f32 {
        self.schedule.top() * PAST_TOP_FACTOR
    }

    /// The highest level (deg^2) past the schedule's top one that changes gains: where
    /// [`past_top_wn`] reaches its lowest bandwidth. `None` (no family goes past the top)
    /// without a recorded tuning jerk, or before the jerk estimate has run for its time
    /// constant ([`JerkEstimator::settled`]: a motion that has just started, or a unit that
    /// starts at rest, is not yet known to be gentle).
    fn past_top_max(&self) -> Option<f32> {
        self.past_top_max
            .filter(|_| self.jerk.as_ref().is_some_and(JerkEstimator::settled))
    }

    /// The gains (velocity, acceleration) for `levels`: the schedule's
    /// ([`GainSchedule::gains_for`]); for a family that goes on past the top level
    /// ([`crate::Gains::PAST_TOP`]) at a level more than [`PAST_TOP_FACTOR`] times it,
    /// [`crate::Gains::past_top`] of the top level's velocity gains, at the bandwidth of
    /// [`past_top_wn`] and the motion's acceleration ratio ([`Self::acceleration_ratio`]).
    fn gains(&self, levels: Levels) -> (BankGains, BankGains) {
        let (velocity, acceleration) = self.schedule.gains_for(levels);
        let Some(tuned) = self.schedule.tuned_jerk() else {
            return (velocity, acceleration);
        };
        struct Past {
            levels: Levels,
            top: f32,
            tuned: f32,
            h_s: f32,
            dt_s: f32,
            acceleration_ratio: f32,
            velocity: BankGains,
        }
        impl FamilyVisitor for Past {
            fn family<F: Family>(&mut self, column: usize) {
                let v = self.levels.0[column];
                if <F::Gains as crate::Gains>::PAST_TOP && v > self.top {
                    let rule = crate::PastTop {
                        wn_rad_s: past_top_wn(self.tuned, v, self.dt_s),
                        zeta: f64::from(SelfTuneConfig::ZETA),
                        h_s: f64::from(self.h_s),
                        dt_s: f64::from(self.dt_s),
                        acceleration_ratio: self.acceleration_ratio,
                    };
                    let top = F::get(&self.velocity);
                    F::set(&mut self.velocity, crate::Gains::past_top(&top, &rule));
                }
            }
        }
        let mut past = Past {
            levels,
            top: self.past_top_from(),
            tuned,
            h_s: self.base.h,
            dt_s: self.base.sample_period_s,
            acceleration_ratio: self.acceleration_ratio(),
            velocity,
        };
        crate::for_each_family(&mut past);
        (past.velocity, acceleration)
    }

    /// The rate about the bank's axis at `t_us` (deg/s), from which it estimates the motion's
    /// jerk for a schedule that records its tuning motion's ([`GainSchedule::tuned_jerk`];
    /// ignored without). Give it before
    /// [`Self::update`] of the same sample.
    pub fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        if let (Some(j), true) = (&mut self.jerk, rate_deg_s.is_finite()) {
            j.update(t_us, rate_deg_s);
        }
    }

    /// The motion's jerk power estimate, (deg/s^3)^2 (`None` for a schedule without
    /// [`GainSchedule::tuned_jerk`], or before the first estimate).
    pub fn jerk_power(&self) -> Option<f32> {
        self.jerk.as_ref().and_then(|j| j.power())
    }

    /// Sets the gains for the noise variance `noise_var` (deg^2, clamped to the schedule; past
    /// its top level as the type's "Past the top level" says) now.
    ///
    /// With a history (the default, see the type's warm start): the rows whose gains changed
    /// are replayed over it ([`PaperBank::set_gains_warm`]), the AVEs starting with the
    /// switching gains `deltahat` the schedule records for `noise_var`
    /// ([`ScheduleLevel::ave_deltahat`], [`GainSchedule::ave_deltahat_at`]) or, when it
    /// records none, with their present ones; the ED row and the ILO-ILO and AD-AD series are
    /// moved bumplessly.
    ///
    /// Without one ([`AdaptiveConfig::replay_samples`] 0, or before the first sample): the
    /// laws continue from their states moved bumplessly ([`PaperBank::set_gains`]), and when
    /// the AVE gains change and the schedule records switching gains, the AVEs' `deltahat` are
    /// set to those for `noise_var`; otherwise they are kept.
    pub fn retune(&mut self, noise_var: f32) {
        self.retune_with(Levels::all(noise_var), noise_var);
    }

    /// [`Self::retune`] to the gains for `noise_var` with the AVEs' switching gains recorded
    /// for `deltahat_var` (deg^2; the noise estimate when the jerk index moved the level).
    fn retune_with(&mut self, levels: Levels, deltahat_var: f32) {
        let v = self.clamp(levels);
        let old = self.gains;
        let ratio = self.acceleration_ratio();
        let (velocity, acceleration) = self.gains(v);
        let new = BankConfig {
            velocity,
            acceleration,
            ..self.base
        };
        let keep = (self.cfg.replay_samples as usize).min(self.history.len());
        // Interpolated between levels that all build: a gain change cannot fail but for
        // rounding at a constraint's edge; then the current gains are kept.
        let changed = if keep > 0 {
            // A family that stays past the top level, or goes there, moves bumplessly after
            // the others (its bandwidth is below what the replay settles), unless its level
            // fell by more than the jerk margin: the motion picked up (a unit at rest that
            // starts to move), and the replay rebuilds its state from the history.
            let top = self.past_top_from();
            let m = self.cfg.jerk_margin;
            let mut bumpless = [false; crate::FAMILY_COUNT];
            for (c, f) in crate::FAMILIES.iter().enumerate() {
                let (was, will) = (self.level.0[c], v.0[c]);
                bumpless[c] = f.past_top && will > top && will * m >= was;
            }
            let mut first = new;
            copy_columns(&mut first.velocity, &old.0, bumpless);
            let old = BankConfig {
                velocity: old.0,
                acceleration: old.1,
                ..new
            };
            let d = self.schedule.ave_deltahat_at(deltahat_var);
            let history = self
                .history
                .oldest_ordered()
                .skip(self.history.len() - keep);
            if self.bank.set_gains_warm(&old, &first, history, d).is_err() {
                false
            } else if first == new || self.bank.set_gains(&new).is_ok() {
                true
            } else {
                // The bank runs the first step's gains; the level is tried again.
                self.gains = (first.velocity, first.acceleration);
                false
            }
        } else if self.bank.set_gains(&new).is_ok() {
            if let Some(d) = self.schedule.ave_deltahat_at(deltahat_var) {
                let mut now = self.bank.ave_deltahat();
                if new.velocity.ave != old.0.ave {
                    now.velocity = d.velocity;
                }
                if new.acceleration.ave != old.1.ave {
                    now.acceleration = d.acceleration;
                }
                self.bank.set_ave_deltahat(&now);
            }
            true
        } else {
            false
        };
        if changed {
            self.level = v;
            self.gains = (velocity, acceleration);
            self.ratio = ratio;
            self.retunes = self.retunes.saturating_add(1);
        }
    }

    /// The current noise estimate, deg^2 (`None` before the first one).
    pub fn noise_var(&self) -> Option<f32> {
        self.noise.variance()
    }

    /// The noise variance the current observers' gains were interpolated for, deg^2 (the
    /// AVE's column of [`Self::gain_levels`]; every family's without a schedule that follows
    /// the motion).
    pub fn gain_level(&self) -> f32 {
        self.level.0[0]
    }

    /// The noise variance each family's current gains were interpolated for, deg^2 (above the
    /// schedule's top level for a family past it: the type's "Past the top level").
    pub fn gain_levels(&self) -> Levels {
        self.level
    }

    /// How many times the gains changed.
    pub fn retune_count(&self) -> u32 {
        self.retunes
    }

    /// See [`PaperBank::new_epoch`] (the noise estimator restarts its differences too).
    pub fn new_epoch(&mut self) {
        self.bank.new_epoch();
        self.noise.restart();
        if let Some(j) = &mut self.jerk {
            j.restart();
        }
    }

    /// See [`PaperBank::reinit_count`].
    pub fn reinit_count(&self) -> u32 {
        self.bank.reinit_count()
    }

    /// See [`PaperBank::set_turns`].
    pub fn set_turns(&mut self, turns: i64) {
        self.bank.set_turns(turns);
    }

    /// The bank.
    pub fn bank(&self) -> &PaperBank<T, S> {
        &self.bank
    }

    /// The gain schedule.
    pub fn schedule(&self) -> &GainSchedule {
        &self.schedule
    }

    /// The bank's nominal sample period, s (`BankConfig::sample_period_s`).
    pub fn sample_period_s(&self) -> f32 {
        self.base.sample_period_s
    }

    /// `true` unless the schedule records a tuning period that this bank's nominal sample
    /// period does not fit ([`GainSchedule::fits_period`]). The bank runs the schedule either
    /// way; `nav440 estimate` and the firmware warn when this is `false`.
    pub fn period_fits(&self) -> bool {
        self.schedule.fits_period(self.base.sample_period_s)
    }
}

/// The noise-adaptive bank as a bank: the paper bank's channels and output
/// ([`PaperOutput`]); `update` is [`AdaptiveBank::update`] (the gains follow the noise).
impl<T: Real, S: SqrtFn<T>> crate::EstimatorBank for AdaptiveBank<T, S> {
    type Output = PaperOutput<T>;

    #[inline]
    fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<PaperOutput<T>, SampleError> {
        AdaptiveBank::update(self, t_us, angle_deg)
    }

    fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        AdaptiveBank::observe_rate(self, t_us, rate_deg_s)
    }

    fn new_epoch(&mut self) {
        AdaptiveBank::new_epoch(self)
    }

    fn reinit_count(&self) -> u32 {
        AdaptiveBank::reinit_count(self)
    }

    /// The inner bank's [`EstimatorBank::take_over`](crate::EstimatorBank::take_over)
    /// (unwrapper, re-init count); the noise estimate and the gains start again, as the bank
    /// is new.
    fn take_over(&mut self, old: &Self) {
        self.bank.take_over(&old.bank);
    }
}
