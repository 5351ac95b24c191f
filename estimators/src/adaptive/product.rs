//! [`AdaptiveProductBank`]: the product bank whose gains follow the measured noise and the
//! motion's jerk.

use super::kalman::{LAMBDA_RANGE, R_FLOOR};
use super::{JerkEstimator, NoiseEstimator};
use crate::{
    BankConfig, ConfigError, EstimatorOutput, IloConfig, KalmanNoise, NativeSqrt, ProductBank,
    ProductOutput, Real, SampleError, SqrtFn,
};

/// How an [`AdaptiveProductBank`] follows the noise and the motion.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdaptiveProductConfig {
    /// `c` of ILO1's bandwidth `wn = c (J / (V dt))^(1/6)` (rad/s, with `J` in
    /// (deg/s^3)^2, `V` in deg^2 and `dt` in s; finite, > 0). Default
    /// [`Self::ILO1_C_FIG5`].
    pub ilo1_c: f32,
    /// The damping of ILO1's per-sample poles, in (0, 1) (default [`Self::ILO1_ZETA`]).
    pub ilo1_zeta: f32,
    /// The alias ILO1's poles are placed through ([`IloConfig::per_sample_alias`]; >= 1,
    /// default [`Self::ILO1_ALIAS`]) while the sample interval is steady (see
    /// [`Self::ilo1_jitter_max`]); the first alias otherwise.
    pub ilo1_alias: u32,
    /// The largest jitter of the sample interval at which ILO1 runs through
    /// [`Self::ilo1_alias`] (in [0, 1); default [`Self::ILO1_JITTER_MAX`]): the mean over
    /// the intervals seen, at most about the last [`JITTER_SAMPLES`], of each interval's
    /// deviation from the nearest whole number of periods `m >= 1`, `|interval /
    /// sample_period_s - m|` (at most 1). Through the `k`-th alias the observer turns `k`
    /// times per nominal sample within its steps, so an interval off by a fraction `d` turns
    /// its per-sample poles by `k d` of a turn, and one of whole periods (a dropped sample)
    /// by whole turns, nothing: on a real recording whose interval varies by 10 % (10 to 12 ms) the fifth alias
    /// made ILO1 7x worse than the backward difference, the first 2.1x better
    /// (docs/MOTION-FAMILY.md, "ILO1 by the jerk index").
    pub ilo1_jitter_max: f32,
    /// `kappa`, s: the acceleration Kalman's process noise is `q = kappa J` (deg^2/s^5), its
    /// measurement noise `r = V` (finite, > 0). Default [`Self::KAPPA_ACCEL_S`].
    pub kappa_s: f32,
    /// Time constant of the noise estimate, s ([`NoiseEstimator`]; default 0.5).
    pub noise_tau_s: f32,
    /// Time constant of the jerk estimate, s ([`JerkEstimator`]; default
    /// [`JerkEstimator::DEFAULT_TAU_S`]).
    pub jerk_tau_s: f32,
    /// The gains are reconsidered every this many samples (default 20: 0.2 s at 100 Hz), and
    /// once in between when the motion picks up (the jerk estimate rose by more than
    /// `ilo1_ratio^6` since the last check, with a settled noise estimate: a nod through the
    /// vertical, a stroke after a pause) ...
    pub retune_every: u32,
    /// ... and changed when ILO1's `wn` moved by more than this factor either way (default
    /// 1.2) ...
    pub ilo1_ratio: f32,
    /// ... or the Kalman's `q / r` by more than this one (default 1.5; both >= 1).
    pub kalman_ratio: f32,
}

impl AdaptiveProductConfig {
    /// `c` from ILO1 on the synthetic fig5 motion (the paper's Fig. 5) at 0.1 deg^2: the
    /// best `wn` of a grid there (24.5 rad/s, with [`Self::ILO1_ZETA`] and
    /// [`Self::ILO1_ALIAS`]) over fig5's index (`host-tests`
    /// `motion_family::ilo1_by_the_jerk_index`, docs/MOTION-FAMILY.md).
    pub const ILO1_C_FIG5: f32 = 0.6245;
    /// The damping of ILO1's per-sample poles: with [`Self::ILO1_ALIAS`], the one of a grid
    /// (0.1 to 0.45) whose rule holds best on every motion of docs/MOTION-FAMILY.md (the
    /// tuned sets' lie between 0.14 and 0.34).
    pub const ILO1_ZETA: f32 = 0.3;
    /// The alias of ILO1's poles: with [`Self::ILO1_ZETA`], the one of a grid (1 to 10)
    /// whose rule holds best on every motion of docs/MOTION-FAMILY.md.
    pub const ILO1_ALIAS: u32 = 5;
    /// `kappa` for the Kalman's acceleration, s: the product bank's Kalman gives the
    /// acceleration alone, so its `kappa` is picked on that, online. Of a grid from 0.02 to
    /// 0.05 s, the one whose worst ratio of the bank's acceleration MSE to the shipped fixed
    /// gains' over the 15 cells of docs/MOTION-FAMILY.md (five motions at 0.01, 0.1 and
    /// 0.5 deg^2) is least: 1.14x (fig5 at 0.01 deg^2). The velocity's
    /// [`crate::AdaptiveKalmanConfig::KAPPA_FIG5_S`] (0.1146 s) reached 1.93x there (the hand
    /// strokes at 0.01 deg^2).
    pub const KAPPA_ACCEL_S: f32 = 0.035;
    /// The default of [`Self::ilo1_jitter_max`]: 0.2 % (the fifth alias then turns its poles
    /// by at most a hundredth of a turn).
    pub const ILO1_JITTER_MAX: f32 = 0.002;
    /// The jerk power ILO1's rule starts from, until the bank has its own estimates: that of
    /// the synthetic fig5 motion, (deg/s^3)^2 (docs/MOTION-FAMILY.md).
    pub const START_JERK: f32 = 3.68e6;
    /// The noise variance ILO1's rule starts from (and restarts from, after a new epoch or a
    /// gap), deg^2: the lowest level the bundled schedule is tuned at; the start is 52.9 rad/s
    /// at 100 Hz (24.5 at 0.1 deg^2). A start runs from a velocity of 0 to the rate, a step a
    /// high bandwidth settles soonest: yaw ILO1 MSE through the bundled time faults 552.5
    /// (deg/s)^2 at 0.1 deg^2, 299.3 at 0.001, 260.4 at 0.0003 (fixed gains 364.5), with fig5
    /// at 0.5 deg^2 of noise 120.8, 112.1 and 113.0 (docs/MOTION-FAMILY.md, "A restart").
    pub const START_NOISE_VAR: f32 = 0.001;

    /// The defaults (see the fields).
    pub const DEFAULT: Self = Self {
        ilo1_c: Self::ILO1_C_FIG5,
        ilo1_zeta: Self::ILO1_ZETA,
        ilo1_alias: Self::ILO1_ALIAS,
        ilo1_jitter_max: Self::ILO1_JITTER_MAX,
        kappa_s: Self::KAPPA_ACCEL_S,
        noise_tau_s: 0.5,
        jerk_tau_s: JerkEstimator::DEFAULT_TAU_S,
        retune_every: 20,
        ilo1_ratio: 1.2,
        kalman_ratio: 1.5,
    };

    fn validate(&self) -> Result<(), ConfigError> {
        let all = [
            ("ilo1_c", self.ilo1_c),
            ("ilo1_zeta", self.ilo1_zeta),
            ("kappa_s", self.kappa_s),
            ("ilo1_ratio", self.ilo1_ratio),
            ("kalman_ratio", self.kalman_ratio),
        ];
        for (name, v) in all {
            if !v.is_finite() {
                return Err(ConfigError::NotFinite(name));
            }
            if v <= 0.0 {
                return Err(ConfigError::NotPositive(name));
            }
        }
        if !(0.0..1.0).contains(&self.ilo1_jitter_max) {
            return Err(ConfigError::NotPositive("ilo1_jitter_max"));
        }
        if self.ilo1_zeta >= 1.0 || self.ilo1_alias == 0 {
            return Err(ConfigError::ObserverPoles);
        }
        if self.ilo1_ratio < 1.0 {
            return Err(ConfigError::NotPositive("ilo1_ratio"));
        }
        if self.kalman_ratio < 1.0 {
            return Err(ConfigError::NotPositive("kalman_ratio"));
        }
        Ok(())
    }
}

impl Default for AdaptiveProductConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The lowest ILO1 bandwidth taken, rad/s.
pub(super) const WN_MIN: f64 = 2.0;

/// Intervals the jitter of [`AdaptiveProductBank`]'s sample interval is averaged over (the
/// weight of an interval once that many were seen is the inverse).
pub const JITTER_SAMPLES: u32 = 50;

/// ILO1's bandwidth by the jerk index, `c (J / (V dt))^(1/6)` rad/s, for the jerk power `j`
/// ((deg/s^3)^2), the noise variance `v` (deg^2) and the sample period `dt` (s): the rule of
/// [`AdaptiveProductBank`], and the anchor of [`crate::SelfTuningProductBank`]'s search.
pub(super) fn jerk_index_wn(c: f64, j: f64, v: f64, dt: f64) -> f64 {
    c * libm::pow(j / (v * dt), 1.0 / 6.0)
}

/// [`jerk_index_wn`] held to the bandwidths ILO1's per-sample poles take: at least [`WN_MIN`],
/// and a damped frequency `wn sqrt(1 - zeta^2)` at most 80 % of the Nyquist frequency `pi /
/// dt` (`zeta` the damping, `dt` the sample period in s).
pub(super) fn bounded_jerk_index_wn(c: f64, j: f64, v: f64, dt: f64, zeta: f64) -> f64 {
    let wn_max = 0.8 * core::f64::consts::PI / (dt * libm::sqrt(1.0 - zeta * zeta));
    // `max` then `min`, not `clamp`: no panic path (whose message formats floats), and a NaN
    // index gives the lowest bandwidth.
    jerk_index_wn(c, j, v, dt)
        .max(WN_MIN)
        .min(wn_max.max(WN_MIN))
}

/// The product bank ([`ProductBank`]: ILO1 velocity, Kalman acceleration) whose gains follow
/// what it measures: the angle's noise variance `V` ([`NoiseEstimator`], from the unwrapped
/// angle) and the motion's jerk power `J` ([`JerkEstimator`], from the rate a gyro measures
/// about the axis, given with [`Self::observe_rate`]).
///
/// - ILO1 is [`IloConfig::per_sample_alias`] at `wn = c (J / (V dt))^(1/6)`, the damping
///   [`AdaptiveProductConfig::ilo1_zeta`] and the alias [`AdaptiveProductConfig::ilo1_alias`]
///   (`wn` within 2 rad/s and 80 % of the Nyquist frequency).
/// - The Kalman's noise model is `q = kappa J`, `r = V` (`q dt^5 / r` within
///   `[2^-40, 2^30]`), as [`crate::AdaptiveKalman`]'s.
///
/// With `c` from the paper's motion, that rule keeps ILO1 below the backward difference of
/// the angle and within 1.5x of ILO1 tuned on each of five motions, from a slow spin to
/// strokes of 600 deg/s, at noise from 0.01 to 0.5 deg^2 (docs/MOTION-FAMILY.md, "ILO1 by the
/// jerk index"), where fixed gains lose to the backward difference on the fast ones.
///
/// ILO1 starts at the rule's gains for [`AdaptiveProductConfig::START_JERK`] and
/// [`AdaptiveProductConfig::START_NOISE_VAR`] (so that every change is between gains of the
/// same alias), the Kalman at the configuration's. ILO1 goes back to that start whenever its
/// laws restart (a new epoch, a gap the bank re-initialises on) at a lower bandwidth, and
/// keeps it while the start settles (`4 / (zeta wn)`, 0.26 s at 100 Hz: a restart from a
/// velocity of 0 at the lowest bandwidth would take seconds). Every
/// [`AdaptiveProductConfig::retune_every`] samples, once both estimates exist, it moves the
/// gains to the rule's when `wn` or `q / r` moved by more than their ratios
/// ([`ProductBank::set_gains`]: bumpless). Without a rate the gains stay, but for ILO1's alias
/// on an interval that jitters (see [`AdaptiveProductConfig::ilo1_jitter_max`]). Each change
/// rebuilds ILO1's closed-form map and the Kalman's gain in `f64` (about as much as building
/// the bank), so it suits a host or a core with the time for it.
///
/// The output, the channels and the errors are [`ProductBank`]'s.
///
/// ```
/// use estimators::{AdaptiveProductBank, AdaptiveProductConfig, BankConfig};
/// let mut bank =
///     AdaptiveProductBank::<f32>::new(&BankConfig::NAV440, &AdaptiveProductConfig::DEFAULT)
///         .unwrap();
/// // Per sample: the rate about the axis (deg/s), then the angle (deg, wrapped as the
/// // bank's `BankConfig::wrap` says) at the same time (us).
/// bank.observe_rate(0, 30.0);
/// let out = bank.update(0, 12.5).unwrap();
/// let (v, a) = (out.values[0], out.values[1]); // ILO1 deg/s, Kalman deg/s^2
/// assert_eq!((v, a), (0.0, 0.0)); // the first sample initialises the laws
/// ```
#[derive(Clone, Debug)]
pub struct AdaptiveProductBank<T: Real, S: SqrtFn<T> = NativeSqrt> {
    bank: ProductBank<T, S>,
    cfg: BankConfig,
    follow: AdaptiveProductConfig,
    noise: NoiseEstimator,
    jerk: JerkEstimator,
    /// The current rule's ILO1 bandwidth, rad/s (`None`: the initial gains), and `q / r`.
    wn: Option<f64>,
    q_over_r: Option<f32>,
    /// The jerk power the gains were last checked at, (deg/s^3)^2 ([`Self::picked_up`]).
    jerk_at: Option<f32>,
    /// The gain checks' ticks and the early check (see [`Self::after`]).
    cadence: super::Cadence,
    /// Samples ILO1 keeps the start's gains after a restart (a new epoch, a gap) while it
    /// settles.
    settle: u32,
    /// The bank's re-initialisations on gaps seen so far.
    reinits: u32,
    retunes: u32,
    ilo1_retunes: u32,
    /// The alias ILO1's gains are placed through now.
    alias: u32,
    /// The last accepted sample's time (us) in this epoch, the mean fractional deviation of
    /// the interval from the nominal period, and how many intervals it has seen.
    last_t_us: Option<u64>,
    jitter: f32,
    intervals: u32,
}

impl<T: Real, S: SqrtFn<T>> AdaptiveProductBank<T, S> {
    /// A bank built from `cfg` ([`ProductBank::new`]) that follows the noise and the motion
    /// as `follow` says.
    pub fn new(cfg: &BankConfig, follow: &AdaptiveProductConfig) -> Result<Self, ConfigError> {
        follow.validate()?;
        let mut bank = Self {
            bank: ProductBank::new(cfg)?,
            cfg: *cfg,
            follow: *follow,
            noise: NoiseEstimator::new(follow.noise_tau_s, cfg.sample_period_s)?,
            jerk: JerkEstimator::new(follow.jerk_tau_s, cfg.sample_period_s)?,
            wn: None,
            q_over_r: None,
            jerk_at: None,
            cadence: super::Cadence::default(),
            settle: 0,
            reinits: 0,
            retunes: 0,
            ilo1_retunes: 0,
            alias: follow.ilo1_alias,
            last_t_us: None,
            jitter: 0.0,
            intervals: 0,
        };
        bank.start_ilo1(bank.start_wn(), follow.ilo1_alias)?;
        bank.settle_start();
        Ok(bank)
    }

    /// ILO1 back to the start's gains for a restart of the laws (a new epoch, or a gap the
    /// bank re-initialises on), kept while the restart settles ([`Self::settle_start`]);
    /// gains of a higher bandwidth than the start's stay (they settle sooner).
    #[inline(never)]
    fn restart_ilo1(&mut self) {
        let start = self.start_wn();
        if self.wn.is_some_and(|wn| wn >= start) {
            return;
        }
        // Cannot fail: the start's gains built when the bank was made; if they did not, the
        // gains stay.
        let _ = self.start_ilo1(start, self.wanted_alias());
        self.settle_start();
    }

    /// The start's bandwidth, rad/s: the rule's for [`AdaptiveProductConfig::START_JERK`]
    /// and [`AdaptiveProductConfig::START_NOISE_VAR`].
    fn start_wn(&self) -> f64 {
        self.rule(
            AdaptiveProductConfig::START_NOISE_VAR,
            AdaptiveProductConfig::START_JERK,
        )
        .0
    }

    /// The start's gains are kept while the laws' start settles ([`super::settle_samples`]);
    /// the gains are checked right after.
    fn settle_start(&mut self) {
        let (zeta, dt) = (f64::from(self.follow.ilo1_zeta), self.cfg.sample_period_s);
        self.settle = self.wn.map_or(0, |wn| super::settle_samples(wn, zeta, dt));
        self.cadence.tick_next(self.follow.retune_every);
    }

    /// Sets ILO1 to the start's gains (out of line: its `f64` rebuild is large, and three
    /// paths call it): the per-sample poles at the start's bandwidth `wn` (rad/s,
    /// [`Self::start_wn`]), through `alias`.
    #[inline(never)]
    fn start_ilo1(&mut self, wn: f64, alias: u32) -> Result<(), ConfigError> {
        if let Ok(ilo1) = self.ilo1_at(wn, alias) {
            let mut cfg = self.cfg;
            cfg.velocity.ilo[0] = ilo1;
            self.bank.set_gains(&cfg)?;
            self.cfg = cfg;
            self.wn = Some(wn);
            self.alias = alias;
        }
        Ok(())
    }

    /// ILO1's gains with per-sample poles at `wn` rad/s and the configured damping, through
    /// `alias`, or the first alias where the step cannot turn that fast (at most 2 steps per
    /// sample per alias).
    fn ilo1_at(&self, wn: f64, alias: u32) -> Result<IloConfig, ConfigError> {
        let (h, dt) = (f64::from(self.cfg.h), f64::from(self.cfg.sample_period_s));
        let zeta = f64::from(self.follow.ilo1_zeta);
        IloConfig::per_sample_alias(wn, zeta, alias, h, dt)
            .or_else(|_| IloConfig::per_sample(wn, zeta, h, dt))
    }

    /// The alias ILO1 should run through: the configured one while the interval's jitter is
    /// at most [`AdaptiveProductConfig::ilo1_jitter_max`] (and before any interval), else
    /// the first.
    fn wanted_alias(&self) -> u32 {
        if self.intervals == 0 || self.jitter <= self.follow.ilo1_jitter_max {
            self.follow.ilo1_alias
        } else {
            1
        }
    }

    /// The jitter of the interval from the last sample to the one at `t_us` (see
    /// [`AdaptiveProductConfig::ilo1_jitter_max`]): its deviation from the nearest whole
    /// number of periods (at least one), at most 1.
    fn observe_interval(&mut self, t_us: u64) {
        if let Some(prev) = self.last_t_us {
            let dt0 = self.cfg.sample_period_s;
            let d = t_us.saturating_sub(prev) as f32 * 1e-6 / dt0;
            let dev = (d - libm::roundf(d).max(1.0)).abs().min(1.0);
            // The first interval starts the mean.
            let weight = 1.0 / (self.intervals.saturating_add(1)).min(JITTER_SAMPLES) as f32;
            self.jitter += (dev - self.jitter) * weight;
            self.intervals = self.intervals.saturating_add(1);
        }
        self.last_t_us = Some(t_us);
    }

    /// The rate about the bank's axis at `t_us` (deg/s): what the jerk estimate is made of.
    /// Give it before [`Self::update`] of the same sample.
    pub fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        if rate_deg_s.is_finite() {
            self.jerk.update(t_us, rate_deg_s);
        }
    }

    /// Feeds one sample (as [`ProductBank::update`]); the noise estimate is updated with its
    /// unwrapped angle and the gains follow the estimates (see the type).
    pub fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<ProductOutput<T>, SampleError> {
        let out = self.bank.update(t_us, angle_deg)?;
        self.after(t_us, &out);
        Ok(out)
    }

    /// [`Self::update`] with the angle `raw * 2^exp2` deg
    /// ([`EstimatorBank::update_scaled`](crate::EstimatorBank::update_scaled)).
    pub fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> Result<ProductOutput<T>, SampleError> {
        let out = crate::EstimatorBank::update_scaled(&mut self.bank, t_us, raw, exp2)?;
        self.after(t_us, &out);
        Ok(out)
    }

    /// After an accepted sample: the noise estimate, and every `retune_every` samples the
    /// gains, or once in between when the motion picks up ([`Self::picked_up`]).
    fn after(&mut self, t_us: u64, out: &ProductOutput<T>) {
        // A gap the bank re-initialised on at this sample: ILO1 restarts from it as after a
        // new epoch.
        let reinits = self.bank.reinit_count();
        if reinits != self.reinits {
            self.reinits = reinits;
            self.restart_ilo1();
        }
        self.observe_interval(t_us);
        self.noise.update(t_us, out.unwrapped_deg());
        if self.settle > 0 {
            self.settle -= 1;
            return;
        }
        if self.cadence.tick(self.follow.retune_every) {
            self.follow_estimates();
        } else if self.cadence.early_open() && self.picked_up() {
            // Once between ticks: a motion that picks up is followed at once.
            self.cadence.take_early();
            self.follow_estimates();
        }
    }

    /// Whether the jerk estimate has risen, since the gains were last checked, by more than
    /// would move ILO1's bandwidth by its ratio at a steady noise (`ilo1_ratio^6`: the rule's
    /// `wn` goes as `J^(1/6)`), with a settled noise estimate.
    fn picked_up(&self) -> bool {
        let r = self.follow.ilo1_ratio;
        let r3 = r * r * r;
        match (self.jerk.power(), self.jerk_at) {
            (Some(j), Some(at)) => self.noise.settled() && j > at * r3 * r3,
            _ => false,
        }
    }

    /// ILO1's bandwidth (rad/s) and the Kalman's `(q, r)` the rule gives for the noise
    /// variance `v` (deg^2) and the jerk power `j` ((deg/s^3)^2).
    fn rule(&self, v: f32, j: f32) -> (f64, (f32, f32)) {
        let r = v.max(R_FLOOR);
        let dt = self.cfg.sample_period_s;
        let f = &self.follow;
        let wn = bounded_jerk_index_wn(
            f64::from(f.ilo1_c),
            f64::from(j),
            f64::from(r),
            f64::from(dt),
            f64::from(f.ilo1_zeta),
        );
        let dt5 = dt * dt * dt * dt * dt;
        let lambda = (f.kappa_s * j / r * dt5)
            .max(LAMBDA_RANGE.0)
            .min(LAMBDA_RANGE.1);
        (wn, (lambda * r / dt5, r))
    }

    /// Moves ILO1's gains to the rule's when its `wn` moved by more than its ratio, and the
    /// Kalman's when its `q / r` did: each law changes only on its own move (a change of
    /// ILO1's gains costs it a transient, so the Kalman's moves leave it alone).
    fn follow_estimates(&mut self) {
        self.jerk_at = self.jerk.power();
        let rule = match (self.noise.variance(), self.jerk.power()) {
            (Some(v), Some(j)) => Some(self.rule(v, j)),
            _ => None,
        };
        let moved = |now: Option<f64>, want: f64, ratio: f32| {
            let ratio = f64::from(ratio);
            now.is_none_or(|now| want > now * ratio || want * ratio < now)
        };
        let alias = self.wanted_alias();
        // ILO1 moves to the rule's bandwidth when that moved, and stays at its own when only
        // the alias must change (a jittering interval needs no estimate to be seen).
        let wn = match rule {
            Some((wn, _)) if moved(self.wn, wn, self.follow.ilo1_ratio) => Some(wn),
            _ if alias != self.alias => self.wn,
            _ => None,
        };
        let kalman = rule.map(|(_, qr)| qr).filter(|(q, r)| {
            moved(
                self.q_over_r.map(f64::from),
                f64::from(q / r),
                self.follow.kalman_ratio,
            )
        });
        let mut cfg = self.cfg;
        if let Some(wn) = wn {
            match self.ilo1_at(wn, alias) {
                Ok(c) => cfg.velocity.ilo[0] = c,
                Err(_) => return,
            }
        }
        if let Some((q, r)) = kalman {
            cfg.acceleration.kf = KalmanNoise { q, r };
        }
        if (wn.is_none() && kalman.is_none()) || self.bank.set_gains(&cfg).is_err() {
            return;
        }
        self.cfg = cfg;
        if let Some(wn) = wn {
            self.wn = Some(wn);
            self.alias = alias;
            self.ilo1_retunes = self.ilo1_retunes.saturating_add(1);
        }
        if let Some((q, r)) = kalman {
            self.q_over_r = Some(q / r);
        }
        self.retunes = self.retunes.saturating_add(1);
    }

    /// How many times the gains changed (either law's).
    pub fn retune_count(&self) -> u32 {
        self.retunes
    }

    /// The alias ILO1's gains are placed through now: the configured one, or the first
    /// while the interval jitters (see [`AdaptiveProductConfig::ilo1_jitter_max`]).
    pub fn ilo1_alias(&self) -> u32 {
        self.alias
    }

    /// The jitter of the sample interval (see [`AdaptiveProductConfig::ilo1_jitter_max`];
    /// `None` before the first interval).
    pub fn interval_jitter(&self) -> Option<f32> {
        (self.intervals > 0).then_some(self.jitter)
    }

    /// How many times ILO1's gains changed.
    pub fn ilo1_retune_count(&self) -> u32 {
        self.ilo1_retunes
    }

    /// The configuration with the current gains.
    pub fn config(&self) -> &BankConfig {
        &self.cfg
    }

    /// ILO1's current bandwidth by the rule, rad/s: the start's (fig5's jerk power at 0.001 deg^2)
    /// until the estimates move it (`None` when that start could not be placed and the
    /// configuration's ILO1 runs).
    pub fn ilo1_wn(&self) -> Option<f64> {
        self.wn
    }

    /// The noise estimate, deg^2, and the jerk estimate, (deg/s^3)^2 (`None` before the
    /// first of each).
    pub fn estimates(&self) -> (Option<f32>, Option<f32>) {
        (self.noise.variance(), self.jerk.power())
    }

    /// The bank.
    pub fn bank(&self) -> &ProductBank<T, S> {
        &self.bank
    }

    /// See [`ProductBank::new_epoch`] (the noise and jerk estimators restart their
    /// differences too). The laws restart from the next sample, ILO1 from a velocity of 0, so
    /// ILO1 goes back to the start's gains (a new bank's bandwidth, 52.9 rad/s) when it runs
    /// slower: the rule's bandwidth for the motion before the epoch can be its lowest
    /// (2 rad/s on a steady rate), at which the restart takes seconds to converge. It keeps
    /// them while the restart settles (`4 / (zeta wn)`: 0.26 s), then the gains follow the
    /// estimates again, between gains of the same alias (bumpless).
    pub fn new_epoch(&mut self) {
        self.restart_ilo1();
        self.bank.new_epoch();
        self.last_t_us = None;
        self.noise.restart();
        self.jerk.restart();
    }

    /// See [`ProductBank::reinit_count`].
    pub fn reinit_count(&self) -> u32 {
        self.bank.reinit_count()
    }
}

/// The motion-adaptive product bank as a bank: [`ProductBank`]'s channels and output;
/// `update` is [`AdaptiveProductBank::update`], `observe_rate`
/// [`AdaptiveProductBank::observe_rate`].
impl<T: Real, S: SqrtFn<T>> crate::EstimatorBank for AdaptiveProductBank<T, S> {
    type Output = ProductOutput<T>;

    #[inline]
    fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<ProductOutput<T>, SampleError> {
        AdaptiveProductBank::update(self, t_us, angle_deg)
    }

    #[inline]
    fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> Result<ProductOutput<T>, SampleError> {
        AdaptiveProductBank::update_scaled(self, t_us, raw, exp2)
    }

    fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        AdaptiveProductBank::observe_rate(self, t_us, rate_deg_s)
    }

    fn new_epoch(&mut self) {
        AdaptiveProductBank::new_epoch(self)
    }

    fn reinit_count(&self) -> u32 {
        AdaptiveProductBank::reinit_count(self)
    }

    /// The inner bank's take-over (unwrapper, re-init count); the estimates and the gains
    /// start again, as the bank is new.
    fn take_over(&mut self, old: &Self) {
        self.bank.take_over(&old.bank);
        self.reinits = self.bank.reinit_count();
    }
}
