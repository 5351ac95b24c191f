//! [`SelfTuningProductBank`]: the product bank that tunes its velocity gains online against
//! the rate a gyro measures.

use super::product::{jerk_index_wn, WN_MIN};
use super::{steady_interval, AdaptiveProductConfig, JerkEstimator, NoiseEstimator};
use crate::{
    BankConfig, ConfigError, EstimatorOutput, IloConfig, NativeSqrt, ProductBank, ProductOutput,
    Real, SampleError, SqrtFn,
};

/// How a [`SelfTuningProductBank`] tunes ILO1.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SelfTuneConfig {
    /// ILO1's bandwidth at the start, rad/s (finite, > 0; default [`Self::WN0_FIG5`]),
    /// brought within the validated range (see [`SelfTuningProductBank`]).
    pub wn0_rad_s: f32,
    /// The damping of ILO1's per-sample poles (first alias, [`IloConfig::per_sample`]), in
    /// (0, 1) (default [`Self::ZETA`]).
    pub zeta: f32,
    /// The first step of each gain: the candidates run at `wn / step` and `wn * step` (or the
    /// damping's), and a move changes it by that factor (> 1; default 1.5). A gain's step
    /// becomes its square root each time its moves change direction, and its square (up to
    /// this one) on two moves the same way ...
    pub step: f32,
    /// ... down to this one (> 1, at most `step`; default 1.05).
    pub min_step: f32,
    /// A candidate takes over only when its squared error is below the running bank's by more
    /// than this fraction of it (in [0, 1); default 0.05): against the window's noise, and
    /// against moves whose transient costs more than they gain.
    pub margin: f32,
    /// Samples compared with the rate per decision (>= 1; default 200: 2 s at 100 Hz).
    pub window: u32,
    /// Samples not compared after a gain change, a re-initialisation or a new epoch: the
    /// candidates' transients (default 50).
    pub settle: u32,
    /// Windows without a move after which the gains count as settled (>= 1; default 2).
    pub settled_after: u32,
    /// Once the bank has its own noise and jerk estimates, `wn` stays within this factor
    /// either way of the bandwidth the jerk index gives them
    /// ([`AdaptiveProductBank`](crate::AdaptiveProductBank)'s rule, `c (J / (V dt))^(1/6)`)
    /// (>= 1; default 4): the search does not leave the region where ILO1 follows the motion.
    pub span: f32,
}

impl SelfTuneConfig {
    /// ILO1's best bandwidth on the synthetic fig5 motion (the paper's Fig. 5) at 0.1 deg^2
    /// with the damping [`Self::ZETA`], rad/s (docs/MOTION-FAMILY.md, "ILO1 by the jerk
    /// index").
    pub const WN0_FIG5: f32 = 25.5;
    /// The damping the search starts from, with the first alias.
    pub const ZETA: f32 = 0.25;
    /// `c` of the jerk index's bandwidth `c (J / (V dt))^(1/6)` that anchors the search: for
    /// [`Self::ZETA`] and the first alias, the best `wn` on fig5 at 0.1 deg^2 over fig5's
    /// index there.
    pub const ANCHOR_C: f32 = 0.649;

    /// The defaults (see the fields).
    pub const DEFAULT: Self = Self {
        wn0_rad_s: Self::WN0_FIG5,
        zeta: Self::ZETA,
        step: 1.5,
        min_step: 1.05,
        margin: 0.05,
        window: 200,
        settle: 50,
        settled_after: 2,
        span: 4.0,
    };

    fn validate(&self) -> Result<(), ConfigError> {
        for (name, v) in [("wn0_rad_s", self.wn0_rad_s), ("zeta", self.zeta)] {
            if !v.is_finite() {
                return Err(ConfigError::NotFinite(name));
            }
            if v <= 0.0 {
                return Err(ConfigError::NotPositive(name));
            }
        }
        if self.zeta >= 1.0 {
            return Err(ConfigError::ObserverPoles);
        }
        for (name, v) in [("step", self.step), ("min_step", self.min_step)] {
            if !v.is_finite() {
                return Err(ConfigError::NotFinite(name));
            }
            if v <= 1.0 {
                return Err(ConfigError::NotPositive(name));
            }
        }
        if self.min_step > self.step {
            return Err(ConfigError::NotPositive("step - min_step"));
        }
        if self.margin.is_nan() {
            return Err(ConfigError::NotFinite("margin"));
        }
        if self.margin < 0.0 {
            return Err(ConfigError::Negative("margin"));
        }
        if self.margin >= 1.0 {
            return Err(ConfigError::NotPositive("1 - margin"));
        }
        if self.window == 0 {
            return Err(ConfigError::NotPositive("window"));
        }
        if self.settled_after == 0 {
            return Err(ConfigError::NotPositive("settled_after"));
        }
        if !self.span.is_finite() {
            return Err(ConfigError::NotFinite("span"));
        }
        if self.span < 1.0 {
            return Err(ConfigError::NotPositive("span - 1"));
        }
        Ok(())
    }
}

impl Default for SelfTuneConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The range of the damping taken.
const ZETA_RANGE: (f64, f64) = (0.05, 0.9);

/// The candidates: the bank that runs, and the two that run one step below and above it in
/// one gain.
const CANDIDATES: usize = 3;

/// The gains tuned: ILO1's bandwidth and damping, one at a time.
const GAINS: usize = 2;

/// `gains` (`wn` rad/s, `zeta`) with gain `i` brought within its range and then within the
/// damped frequency's limit `wd_max` (rad/s) given the other gain, which stays. `wn`'s
/// projection lowers it, no lower than `wd_max >= WN_MIN`; `zeta`'s raises it, and stays
/// within its range only when `wn` is within its own (at most `wd_max / sqrt(1 - 0.05^2)`), so
/// [`fit_both`] fits `wn` first.
fn fit(
    mut gains: [f64; GAINS],
    i: usize,
    ranges: &[(f64, f64); GAINS],
    wd_max: f64,
) -> [f64; GAINS] {
    // `max` then `min`, not `clamp`: no panic path (whose message formats floats).
    gains[i] = gains[i].max(ranges[i].0).min(ranges[i].1);
    let [wn, zeta] = gains;
    if wn * libm::sqrt(1.0 - zeta * zeta) > wd_max {
        if i == 0 {
            gains[0] = wd_max / libm::sqrt(1.0 - zeta * zeta);
        } else {
            let r = wd_max / wn;
            gains[1] = libm::sqrt(1.0 - r * r);
        }
    }
    gains
}

/// [`fit`] of the bandwidth, then of the damping given it: both within their ranges and the
/// damped frequency's limit.
fn fit_both(gains: [f64; GAINS], ranges: &[(f64, f64); GAINS], wd_max: f64) -> [f64; GAINS] {
    fit(fit(gains, 0, ranges, wd_max), 1, ranges, wd_max)
}

/// ILO1's gains where a [`SelfTuningProductBank`] settled.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settled {
    /// The bandwidth of ILO1's per-sample poles, rad/s.
    pub wn_rad_s: f32,
    /// Their damping.
    pub zeta: f32,
    /// The ILO1 gains of those poles ([`IloConfig::per_sample`]).
    pub ilo1: IloConfig,
    /// The velocity MSE of the last window against the rate, (deg/s)^2.
    pub mse: f32,
    /// How many times the gains moved before settling.
    pub moves: u32,
}

/// The product bank ([`ProductBank`]: ILO1 velocity, Kalman acceleration) that tunes ILO1
/// online against the rate a gyro measures about its axis ([`Self::observe_rate`]: the
/// NAV440's body rates, or the Euler rates `nav440_pipeline` builds from them).
///
/// ILO1 runs with per-sample poles ([`IloConfig::per_sample`]) of bandwidth `wn` and damping
/// `zeta`. Beside the bank that runs, two candidates run the same samples with one of the two
/// gains one step below and above (`wn` in one window, `zeta` in the next). Each compares its
/// ILO1 velocity with the rate of the same sample; after [`SelfTuneConfig::window`] compared
/// samples the bank takes the candidate with the lowest squared error if it beats the bank's
/// by more than [`SelfTuneConfig::margin`], or stays. A gain whose moves change direction
/// halves its step in ratio (its square root), down to [`SelfTuneConfig::min_step`]; two
/// moves the same way double it, up to [`SelfTuneConfig::step`]. The search closes in on the
/// gains whose error against the rate is lowest and stays there, and follows them at the
/// first step's pace when the motion changes.
///
/// - **Bounded:** one step per window; `wn` at least 2 rad/s, `zeta` within 0.05 and 0.9, and
///   the damped frequency `wn sqrt(1 - zeta^2)` within 80 % of the Nyquist frequency (where
///   `IloConfig::per_sample` is valid). Once the bank has its own noise estimate `V` (from its
///   unwrapped angle) and jerk estimate `J` (from the valid rates), `wn` stays within
///   [`SelfTuneConfig::span`] of the jerk index's bandwidth `c (J / (V dt))^(1/6)`
///   ([`SelfTuneConfig::ANCHOR_C`]): far below a fast motion's bandwidth ILO1 lags
///   so much that a lower bandwidth, nearer a zero output, errs less, and the search alone
///   would descend there.
/// - **Only against a valid rate:** a sample is compared only when a finite rate was given for
///   its very time and it continues a steady stream (its interval within a quarter of the
///   last one). The first [`SelfTuneConfig::settle`] samples of each window, and after a
///   re-initialisation or a new epoch, are not compared. A caller without a valid rate (a BIT
///   failure, gimbal lock) gives none: `nav440_pipeline` passes only the rows' valid rates,
///   and a sample it drops is not fed at all.
/// - **Bumpless:** a move is [`ProductBank::set_gains`].
/// - **A restart** (a new epoch, a gap the bank re-initialises on) starts ILO1 from a velocity
///   of 0: below the start's bandwidth, the running bank takes the start's gains until the
///   restart settles, then the tuned ones again.
/// - **Settled:** after [`SelfTuneConfig::settled_after`] windows without a move,
///   [`Self::settled`] holds the gains (and [`Self::settle_count`] counts up: a caller reports
///   each new settling once); a later move starts again.
///
/// The Kalman keeps the gains of the configuration it is built with. Each window rebuilds two
/// or three ILO1 maps in `f64` (as building as many banks), and each compared sample costs two
/// more bank updates and a few `f32` operations: it suits a core with an FPU, or a host. RAM:
/// three [`ProductBank`]s. The output, the channels and the errors are [`ProductBank`]'s.
///
/// ```
/// use estimators::{BankConfig, SelfTuneConfig, SelfTuningProductBank};
/// let mut bank =
///     SelfTuningProductBank::<f32>::new(&BankConfig::NAV440, &SelfTuneConfig::DEFAULT).unwrap();
/// // Per sample: the rate about the axis (deg/s), then the angle (deg) at the same time (us).
/// bank.observe_rate(0, 30.0);
/// let out = bank.update(0, 12.5).unwrap();
/// assert_eq!(out.values, [0.0, 0.0]); // the first sample initialises the laws
/// assert_eq!(bank.gains(), (25.5, 0.25));
/// assert!(bank.settled().is_none());
/// ```
#[derive(Clone, Debug)]
pub struct SelfTuningProductBank<T: Real, S: SqrtFn<T> = NativeSqrt> {
    /// The bank that runs, then the candidates below and above it.
    banks: [ProductBank<T, S>; CANDIDATES],
    cfg: BankConfig,
    tune: SelfTuneConfig,
    /// The running bank's gains (`wn` rad/s, `zeta`), their ranges, their steps (ratios) and
    /// the direction of their last moves (-1, 0, 1).
    gains: [f64; GAINS],
    ranges: [(f64, f64); GAINS],
    /// The limit on the damped frequency `wn sqrt(1 - zeta^2)`, rad/s: 80 % of the Nyquist
    /// frequency.
    wd_max: f64,
    steps: [f64; GAINS],
    last_move: [i8; GAINS],
    /// The gain the candidates differ in.
    tuning: usize,
    /// `wn`'s range without the bank's estimates.
    wn_range: (f64, f64),
    /// The noise estimate (from the unwrapped angle) and the jerk estimate (from the valid
    /// rates) that anchor `wn`'s range.
    noise: NoiseEstimator,
    jerk: JerkEstimator,
    /// The rate given for the next sample: (time, deg/s).
    rate: Option<(u64, f32)>,
    /// The sum of each candidate's squared velocity error in this window, (deg/s)^2.
    sums: [f32; CANDIDATES],
    compared: u32,
    /// Samples still not compared.
    skip: u32,
    t_prev: Option<u64>,
    dt_prev: u64,
    reinits: u32,
    /// Samples the running bank keeps the start's ILO1 after a restart, while it settles.
    hold: u32,
    quiet_windows: u32,
    moves: u32,
    settled: Option<Settled>,
    settles: u32,
}

impl<T: Real, S: SqrtFn<T>> SelfTuningProductBank<T, S> {
    /// A bank built from `cfg` ([`ProductBank::new`], its ILO1 replaced by the per-sample
    /// poles at [`SelfTuneConfig::wn0_rad_s`] and [`SelfTuneConfig::zeta`]) that tunes ILO1 as
    /// `tune` says.
    pub fn new(cfg: &BankConfig, tune: &SelfTuneConfig) -> Result<Self, ConfigError> {
        tune.validate()?;
        let dt = f64::from(cfg.sample_period_s);
        let wd_max = (0.8 * core::f64::consts::PI / dt).max(WN_MIN);
        // The lowest damping gives the highest `wn` within the damped frequency's limit.
        let z = ZETA_RANGE.0;
        let ranges = [(WN_MIN, wd_max / libm::sqrt(1.0 - z * z)), ZETA_RANGE];
        let start = [f64::from(tune.wn0_rad_s), f64::from(tune.zeta)];
        let gains = fit_both(start, &ranges, wd_max);
        let step = f64::from(tune.step);
        let bank = ProductBank::new(cfg)?;
        let mut this = Self {
            banks: [bank; CANDIDATES],
            cfg: *cfg,
            tune: *tune,
            gains,
            ranges,
            wd_max,
            steps: [step; GAINS],
            last_move: [0; GAINS],
            tuning: 0,
            wn_range: ranges[0],
            noise: NoiseEstimator::new(
                AdaptiveProductConfig::DEFAULT.noise_tau_s,
                cfg.sample_period_s,
            )?,
            jerk: JerkEstimator::new(JerkEstimator::DEFAULT_TAU_S, cfg.sample_period_s)?,
            rate: None,
            sums: [0.0; CANDIDATES],
            compared: 0,
            skip: tune.settle,
            t_prev: None,
            dt_prev: 0,
            reinits: 0,
            hold: 0,
            quiet_windows: 0,
            moves: 0,
            settled: None,
            settles: 0,
        };
        this.retune(gains, true)?;
        Ok(this)
    }

    /// The rate about the bank's axis at `t_us` (deg/s), measured by a gyro: what ILO1's
    /// velocity is compared with. Give it before [`Self::update`] of the same sample, and only
    /// when it is valid.
    pub fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        self.rate = rate_deg_s.is_finite().then_some((t_us, rate_deg_s));
    }

    /// Feeds one sample (as [`ProductBank::update`]) to the bank and its candidates, compares
    /// their velocities with the rate given for it, and moves the gains after a window (see
    /// the type).
    pub fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<ProductOutput<T>, SampleError> {
        self.feed(t_us, |b| b.update(t_us, angle_deg))
    }

    /// [`Self::update`] with the angle `raw * 2^exp2` deg
    /// ([`EstimatorBank::update_scaled`](crate::EstimatorBank::update_scaled)).
    pub fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> Result<ProductOutput<T>, SampleError> {
        self.feed(t_us, |b| {
            crate::EstimatorBank::update_scaled(b, t_us, raw, exp2)
        })
    }

    fn feed(
        &mut self,
        t_us: u64,
        mut update: impl FnMut(&mut ProductBank<T, S>) -> Result<ProductOutput<T>, SampleError>,
    ) -> Result<ProductOutput<T>, SampleError> {
        let rate = self.rate.take().filter(|(t, _)| *t == t_us).map(|r| r.1);
        let out = update(&mut self.banks[0])?;
        let mut v = [out.channel(crate::ProductChannel::Ilo1V); CANDIDATES];
        for (bank, v) in self.banks[1..].iter_mut().zip(&mut v[1..]) {
            // The candidates differ from the bank in ILO1's gains only, so they accept what
            // the bank accepts.
            if let Ok(o) = update(bank) {
                *v = o.channel(crate::ProductChannel::Ilo1V);
            }
        }
        self.noise.update(t_us, out.unwrapped_deg());
        if let Some(r) = rate {
            self.jerk.update(t_us, r);
        }
        let dt = self.t_prev.map_or(0, |p| t_us.saturating_sub(p));
        let steady = steady_interval(dt, self.dt_prev);
        (self.t_prev, self.dt_prev) = (Some(t_us), dt);
        if self.hold > 0 {
            self.hold -= 1;
            if self.hold == 0 {
                // Settled: the tuned gains again (bumpless).
                let _ = self.retune(self.gains, true);
            }
        }
        let reinits = self.banks[0].reinit_count();
        if reinits != self.reinits {
            self.reinits = reinits;
            self.restart_at_start();
            self.restart_window();
        }
        if let (Some(rate), true) = (rate, steady) {
            if self.skip > 0 {
                self.skip -= 1;
            } else {
                for (sum, v) in self.sums.iter_mut().zip(v) {
                    let e = v - rate;
                    *sum += e * e;
                }
                self.compared += 1;
                if self.compared >= self.tune.window {
                    self.decide();
                }
            }
        }
        Ok(out)
    }

    /// At the end of a window: one step towards the better candidate or stay; then the
    /// candidates of the other gain.
    fn decide(&mut self) {
        let i = self.tuning;
        let best = if self.sums[1] < self.sums[2] { 1 } else { 2 };
        let mse = self.sums[0] / self.compared as f32;
        let wins = self.sums[best] < self.sums[0] * (1.0 - self.tune.margin);
        let dir: i8 = if best == 1 { -1 } else { 1 };
        let mut gains = self.gains;
        if wins {
            gains[i] = self.candidate(i, dir);
        }
        // The range of `wn` around the jerk index's bandwidth, and `wn` within it.
        self.ranges[0] = self.anchored_range();
        gains = fit(gains, 0, &self.ranges, self.wd_max);
        let moved = gains[i] != self.gains[i];
        if moved {
            // A reversal halves the step (in ratio); a second move the same way doubles it
            // again, up to the first step: a motion that changes hours later is followed at
            // the first step's pace.
            if self.last_move[i] == -dir {
                let min = f64::from(self.tune.min_step);
                self.steps[i] = libm::sqrt(self.steps[i]).max(min);
            } else if self.last_move[i] == dir {
                let max = f64::from(self.tune.step);
                self.steps[i] = (self.steps[i] * self.steps[i]).min(max);
            }
            self.last_move[i] = dir;
        }
        self.tuning = (i + 1) % GAINS;
        if self.retune(gains, moved).is_err() {
            // Gains the validated ranges allow always build; should one not, the bank keeps
            // its gains and the candidates stay as they were.
            self.tuning = i;
        }
        self.restart_window();
        if moved {
            self.moves = self.moves.saturating_add(1);
            self.quiet_windows = 0;
            self.settled = None;
            return;
        }
        self.quiet_windows = self.quiet_windows.saturating_add(1);
        if self.quiet_windows == self.tune.settled_after {
            if let Ok(ilo1) = self.ilo1(self.gains) {
                self.settled = Some(Settled {
                    wn_rad_s: self.gains[0] as f32,
                    zeta: self.gains[1] as f32,
                    ilo1,
                    mse,
                    moves: self.moves,
                });
                self.settles = self.settles.saturating_add(1);
            }
        }
    }

    /// `wn`'s range: within [`SelfTuneConfig::span`] of the jerk index's bandwidth for the
    /// bank's noise and jerk estimates, inside the range without them (that range until both
    /// estimates exist).
    fn anchored_range(&self) -> (f64, f64) {
        let (lo, hi) = self.wn_range;
        let (Some(v), Some(j)) = (self.noise.variance(), self.jerk.power()) else {
            return (lo, hi);
        };
        let anchor = jerk_index_wn(
            f64::from(SelfTuneConfig::ANCHOR_C),
            f64::from(j),
            f64::from(v).max(1e-12),
            f64::from(self.cfg.sample_period_s),
        );
        let span = f64::from(self.tune.span);
        // A NaN anchor keeps the whole range (`max` and `min` return the other operand).
        let lo2 = (anchor / span).max(lo).min(hi);
        let hi2 = (anchor * span).min(hi).max(lo2);
        (lo2, hi2)
    }

    /// Gain `i` one step in direction `dir`, within its range and the damped frequency's limit.
    fn candidate(&self, i: usize, dir: i8) -> f64 {
        let mut gains = self.gains;
        if dir < 0 {
            gains[i] /= self.steps[i];
        } else {
            gains[i] *= self.steps[i];
        }
        fit(gains, i, &self.ranges, self.wd_max)[i]
    }

    /// The bank to `gains` (when `bank`), the candidates a step either side of them in the
    /// gain [`Self::tuning`] says (all bumpless).
    fn retune(&mut self, gains: [f64; GAINS], bank: bool) -> Result<(), ConfigError> {
        let old = core::mem::replace(&mut self.gains, gains);
        let i = self.tuning;
        let cfgs = [
            self.ilo1(gains),
            self.ilo1_with(i, self.candidate(i, -1)),
            self.ilo1_with(i, self.candidate(i, 1)),
        ];
        let mut done = Ok(());
        for (k, (bank_k, c)) in self.banks.iter_mut().zip(cfgs).enumerate() {
            if k == 0 && !bank {
                continue;
            }
            let mut cfg = self.cfg;
            cfg.velocity.ilo[0] = match c {
                Ok(c) => c,
                Err(e) => {
                    done = Err(e);
                    continue;
                }
            };
            if let Err(e) = bank_k.set_gains(&cfg) {
                done = Err(e);
            }
        }
        if done.is_err() {
            self.gains = old;
        }
        done
    }

    /// ILO1 with gain `i` at `g` and the other as the bank runs it.
    fn ilo1_with(&self, i: usize, g: f64) -> Result<IloConfig, ConfigError> {
        let mut gains = self.gains;
        gains[i] = g;
        self.ilo1(gains)
    }

    /// ILO1's per-sample poles at `gains` (`wn` rad/s, `zeta`) for the bank's step and sample
    /// period.
    fn ilo1(&self, gains: [f64; GAINS]) -> Result<IloConfig, ConfigError> {
        IloConfig::per_sample(
            gains[0],
            gains[1],
            f64::from(self.cfg.h),
            f64::from(self.cfg.sample_period_s),
        )
    }

    fn restart_window(&mut self) {
        self.sums = [0.0; CANDIDATES];
        self.compared = 0;
        self.skip = self.tune.settle.max(self.hold);
    }

    /// A restart of the laws (a new epoch, a gap the bank re-initialises on) starts ILO1 from
    /// a velocity of 0: when the tuned bandwidth is below the start's
    /// ([`SelfTuneConfig::wn0_rad_s`]; on a steady rate the search can reach 2 rad/s, at which
    /// the restart takes seconds to converge), the running bank takes the start's gains while
    /// the restart settles (`4 / (zeta wn)`: 0.63 s), then the tuned ones again. No sample is
    /// compared meanwhile.
    #[inline(never)]
    fn restart_at_start(&mut self) {
        let start = [f64::from(self.tune.wn0_rad_s), f64::from(self.tune.zeta)];
        if self.gains[0] >= start[0] {
            return;
        }
        let mut cfg = self.cfg;
        let Ok(c) = self.ilo1(start) else {
            return;
        };
        cfg.velocity.ilo[0] = c;
        if self.banks[0].set_gains(&cfg).is_ok() {
            self.hold = super::settle_samples(start[0], start[1], self.cfg.sample_period_s);
        }
    }

    /// ILO1's gains now: the bandwidth of its per-sample poles (rad/s) and their damping.
    pub fn gains(&self) -> (f64, f64) {
        (self.gains[0], self.gains[1])
    }

    /// The gains where the bank settled (`None` before it did, and after a later move).
    pub fn settled(&self) -> Option<&Settled> {
        self.settled.as_ref()
    }

    /// How many times the bank settled.
    pub fn settle_count(&self) -> u32 {
        self.settles
    }

    /// How many times the gains moved.
    pub fn move_count(&self) -> u32 {
        self.moves
    }

    /// The configuration the bank was built with, ILO1's gains the ones it runs.
    pub fn config(&self) -> BankConfig {
        let mut cfg = self.cfg;
        if let Ok(c) = self.ilo1(self.gains) {
            cfg.velocity.ilo[0] = c;
        }
        cfg
    }

    /// The bank that runs.
    pub fn bank(&self) -> &ProductBank<T, S> {
        &self.banks[0]
    }

    /// See [`ProductBank::new_epoch`] (no sample is compared until the settling samples passed;
    /// a tuned ILO1 slower than the start's restarts at the start's gains, see the type).
    pub fn new_epoch(&mut self) {
        self.restart_at_start();
        for bank in &mut self.banks {
            bank.new_epoch();
        }
        self.t_prev = None;
        self.dt_prev = 0;
        self.noise.restart();
        self.jerk.restart();
        self.restart_window();
    }

    /// See [`ProductBank::reinit_count`].
    pub fn reinit_count(&self) -> u32 {
        self.banks[0].reinit_count()
    }
}

/// The self-tuning product bank as a bank: [`ProductBank`]'s channels and output; `update` is
/// [`SelfTuningProductBank::update`], `observe_rate` [`SelfTuningProductBank::observe_rate`].
impl<T: Real, S: SqrtFn<T>> crate::EstimatorBank for SelfTuningProductBank<T, S> {
    type Output = ProductOutput<T>;

    #[inline]
    fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<ProductOutput<T>, SampleError> {
        SelfTuningProductBank::update(self, t_us, angle_deg)
    }

    #[inline]
    fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> Result<ProductOutput<T>, SampleError> {
        SelfTuningProductBank::update_scaled(self, t_us, raw, exp2)
    }

    fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        SelfTuningProductBank::observe_rate(self, t_us, rate_deg_s)
    }

    fn new_epoch(&mut self) {
        SelfTuningProductBank::new_epoch(self)
    }

    fn reinit_count(&self) -> u32 {
        SelfTuningProductBank::reinit_count(self)
    }

    /// The banks' take-over (unwrapper, re-init count) and `old`'s gains (within this bank's
    /// ranges): the tuning goes on from there at the new sample period.
    fn take_over(&mut self, old: &Self) {
        for (bank, old) in self.banks.iter_mut().zip(&old.banks) {
            bank.take_over(old);
        }
        self.reinits = self.banks[0].reinit_count();
        let gains = fit_both(old.gains, &self.ranges, self.wd_max);
        self.steps = old.steps;
        self.last_move = old.last_move;
        self.moves = old.moves;
        let _ = self.retune(gains, true);
    }
}
