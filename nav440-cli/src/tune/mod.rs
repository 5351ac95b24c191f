//! `nav440 tune`: per-capture, per-noise-level calibration of each estimator family's gains
//! (the paper: "gains must be re-calibrated to the noise level"). docs/CALIBRATION.md.
//!
//! Method: for each family (AVE; ILO1, ILO2, ILO3 from their presets; AD; ED; KF) and each half
//! of the bank (velocity against the measured rate; series acceleration against the AVE on the
//! measured rate), [`crate::optim::minimise`] over every gain of the family within its valid
//! range ([`search::search_box`]: K1 included) of the MSE over the training time range averaged over
//! `seeds` noise seeds: a global search (coarse log grid, then Nelder-Mead of the `argmin`
//! crate from several starts and from the paper preset) or, with `--exhaustive`, a log grid.
//! Candidates the constructors reject (e.g. `h * L >= 1`) or that diverge count as infinite
//! MSE. Every hold asked for (both by default) is tuned; the one with the smaller geometric
//! mean of the tuned MSEs over the 14 families is kept (the hold is one bank-wide option). The single estimators run behind
//! `estimators::SampleAdapter` (unwrapped noisy yaw, same hold and step as the bank); the
//! "before" and "after" MSE printed are then measured through the whole `PaperBank` with the
//! paper presets and with the tuned gains file, i.e. exactly what `nav440 estimate --gains`
//! computes.

mod preset;
pub use preset::*;
mod schedule;
pub use schedule::*;
mod report;
use report::*;

use crate::error::{Error, Result};
use crate::gains::{FamilyGains, GainsFile};
use crate::optim::{self, Method};
use crate::paper::{ave_on_rate, row_mse, steps_between, REFERENCE_AVE};
use crate::progress::Progress;
use crate::replay::{self, EstimateOptions, Noise, Sample};
use crate::score::Lock;
use crate::search;
use estimators::{
    for_each_family, BankConfig, Channel, Estimator, Family, FamilyVisitor, Gains, Hold, Kalman,
    KalmanConfig, KalmanNoise, Law, LawVisitor, SampleAdapter, Scheduling, Series, Stateful,
    FAMILIES, FAMILY_COUNT,
};
use std::time::Instant;

// Column names in bank order.
use crate::paper::COLUMNS as NAMES;

/// Which families a run tunes, per half (velocity, acceleration; columns in
/// [`crate::paper::COLUMNS`] order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Families(pub [[bool; FAMILY_COUNT]; 2]);

impl Families {
    /// Every family of the paper bank (`nav440 tune`'s default, `--bank paper`).
    pub const ALL: Families = Families([[true; FAMILY_COUNT]; 2]);

    /// The product bank's rows (`--bank product`): ILO1 velocity and Kalman acceleration
    /// (`estimators::ProductBank` runs these two with the paper bank's gains for them).
    pub fn product() -> Families {
        let column = |channels: &[Channel; FAMILY_COUNT], c: Channel| {
            channels.iter().position(|&x| x == c).unwrap_or(0)
        };
        let mut f = [[false; FAMILY_COUNT]; 2];
        f[0][column(&Channel::VELOCITY, Channel::Ilo1V)] = true;
        f[1][column(&Channel::ACCELERATION, Channel::KfA)] = true;
        Families(f)
    }

    /// Whether column `i` of the half `acc` is tuned.
    pub fn tunes(&self, acc: bool, i: usize) -> bool {
        self.0[usize::from(acc)].get(i).copied().unwrap_or(false)
    }

    /// The number of tuned MSEs (the hold's score is their geometric mean).
    pub fn count(&self) -> usize {
        self.0.iter().flatten().filter(|&&t| t).count()
    }
}

/// What to tune and how.
#[derive(Clone, Debug)]
pub struct TuneSpec {
    /// Noise variance added to yaw, deg^2.
    pub noise_var: f64,
    /// Noise seeds averaged per evaluation (1..=seeds).
    pub seeds: u64,
    /// Time range the gains are tuned on (MSE over `from..=to`), s.
    pub train: (f64, f64),
    /// Time range the result is scored on (`None`: the training range), s.
    pub test: Option<(f64, f64)>,
    /// Global search or exhaustive log grid.
    pub method: Method,
    /// Holds tuned (the best is kept); empty: the options' hold only.
    pub holds: Vec<Hold>,
    /// The families tuned (the others keep their gains and are left out of the report and
    /// of the hold's score).
    pub families: Families,
}

/// Cost of the tuning of one hold.
#[derive(Clone, Debug, PartialEq)]
pub struct HoldRun {
    /// The hold.
    pub hold: Hold,
    /// Geometric mean of the tuned MSEs over the 14 families (training range, seeds'
    /// mean): the score the hold is chosen by.
    pub score: f64,
    /// Tuned (training) MSE per family: velocity then acceleration.
    pub cost: [[f64; FAMILY_COUNT]; 2],
    /// Objective evaluations per family.
    pub evals: [[usize; FAMILY_COUNT]; 2],
    /// Wall time per family, s (the two halves run in parallel).
    pub secs: [[f64; FAMILY_COUNT]; 2],
}

/// What the tuner found.
#[derive(Clone, Debug)]
pub struct TuneResult {
    /// Noise variance, deg^2.
    pub noise_var: f64,
    /// Seeds averaged.
    pub seeds: u64,
    /// MSE window end, s (the training range's end).
    pub window_s: f64,
    /// Training range, s.
    pub train: (f64, f64),
    /// Range the before/after MSEs are measured on, s.
    pub test: (f64, f64),
    /// Method used.
    pub method: Method,
    /// The hold kept (the hold the "before" column used is the options').
    pub hold: Hold,
    /// The hold the "before" column (paper presets) was measured with.
    pub hold_before: Hold,
    /// Every hold tuned, with its cost.
    pub runs: Vec<HoldRun>,
    /// Total wall time, s.
    pub elapsed_s: f64,
    /// Tuned gains.
    pub gains: GainsFile,
    /// Paper gains written in the same form (for the "before" column).
    pub paper: GainsFile,
    /// Velocity MSE per column with the paper presets, (deg/s)^2 (through the bank).
    pub vel_before: [f64; FAMILY_COUNT],
    /// Velocity MSE with the tuned gains.
    pub vel_after: [f64; FAMILY_COUNT],
    /// Acceleration MSE with the paper presets, (deg/s^2)^2.
    pub acc_before: [f64; FAMILY_COUNT],
    /// Acceleration MSE with the tuned gains.
    pub acc_after: [f64; FAMILY_COUNT],
    /// Samples scored in the training range.
    pub rows_scored: usize,
    /// Samples of the training range left out near gimbal lock and within
    /// [`crate::score::LOCK_SETTLE_S`] after it.
    pub rows_left_out: usize,
    /// Families with no finite training MSE (their gains are left as they were).
    pub warnings: Vec<String>,
    /// The families tuned ([`TuneSpec::families`]).
    pub families: Families,
}

/// Precomputed inputs of one tuning problem.
struct Problem<'a> {
    samples: &'a [Sample],
    /// Unwrapped noisy yaw, one vector per seed.
    ys: Vec<Vec<f32>>,
    vel_ref: Vec<f32>,
    acc_ref: Vec<f32>,
    opts: &'a EstimateOptions,
    max_gap_s: f32,
    sample_period_s: f32,
    /// MSE range, s.
    range: (f64, f64),
    /// Which samples are fed and scored (gimbal lock, [`crate::score`]).
    lock: Lock,
    /// Told of every evaluation and family fit (`nav440 tune`'s progress bar).
    progress: Option<&'a Progress>,
}

/// MSE of `est` against `reference` over the samples with `from <= t <= to` (s); NaN if none.
pub fn mse_range(t_us: &[u64], est: &[f32], reference: &[f32], range: (f64, f64)) -> f64 {
    mse_scored(t_us, est, reference, range, None)
}

/// [`mse_range`] over the samples `scored` marks (all when `None`; see [`crate::score`]):
/// NaN if none is scored, non-finite if an estimate is.
pub fn mse_scored(
    t_us: &[u64],
    est: &[f32],
    reference: &[f32],
    (from, to): (f64, f64),
    scored: Option<&[bool]>,
) -> f64 {
    let (lo, hi) = ((from * 1e6).round() as u64, (to * 1e6).round() as u64);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (k, ((&t, &e), &r)) in t_us.iter().zip(est).zip(reference).enumerate() {
        let counted = scored.is_none_or(|m| m.get(k).copied().unwrap_or(false));
        if counted && t >= lo && t <= hi {
            let d = f64::from(e) - f64::from(r);
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// What a family's objective is measured on: one [`Problem`] (`nav440 tune`), or a set of
/// them ([`Problems`], the shipped preset's family of motions and noise levels).
trait Eval: Sync {
    /// Observer step h, s.
    fn step_s(&self) -> f32;
    /// The objective of the estimator `law` (velocity half) or of two of it in series
    /// (acceleration half); `i`: the family's column (bank order).
    fn family<L: Law<Num = f32>>(&self, i: usize, law: L, acc: bool) -> f64;
    /// The objective of a Kalman tracker with noise `q`, `r` (its `dt`: each problem's
    /// nominal sample period); `i`: the family's column.
    fn kf(&self, i: usize, q: f32, r: f32, acc: bool) -> f64;
    /// A family's fit is done.
    fn fitted(&self) {}
    /// The largest shortfall on a constant rate the velocity ILOs may have (a fraction; the
    /// search then runs every candidate held to it, [`search::holding_constant_rate`]), or
    /// `None`.
    fn constant_rate(&self) -> Option<f64> {
        None
    }
}

impl Eval for Problem<'_> {
    fn step_s(&self) -> f32 {
        self.opts.step_s
    }
    fn family<L: Law<Num = f32>>(&self, _i: usize, law: L, acc: bool) -> f64 {
        if let Some(p) = self.progress {
            p.evaluation();
        }
        self.eval_family(law, acc)
    }
    fn kf(&self, _i: usize, q: f32, r: f32, acc: bool) -> f64 {
        if let Some(p) = self.progress {
            p.evaluation();
        }
        let dt = self.sample_period_s;
        self.eval_kf(&KalmanConfig { dt, q, r }, acc)
    }
    fn fitted(&self) {
        if let Some(p) = self.progress {
            p.fitted();
        }
    }
}

/// One family's objective in one half ([`Gains::build`] hands it the estimator to score).
struct Objective<'a, E> {
    eval: &'a E,
    column: usize,
    acc: bool,
}

// By hand: a derive would ask `E: Copy`.
impl<E> Clone for Objective<'_, E> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<E> Copy for Objective<'_, E> {}

impl<E: Eval> LawVisitor for Objective<'_, E> {
    type Output = f64;
    fn law<L: Law<Num = f32>>(self, law: L) -> f64 {
        self.eval.family(self.column, law, self.acc)
    }
    fn tracker(self, noise: KalmanNoise) -> f64 {
        self.eval.kf(self.column, noise.q, noise.r, self.acc)
    }
}

/// A set of problems scored together. Without baselines: the geometric mean of their MSEs
/// (each problem weighs the same whatever its MSE's scale). With baselines (per problem, the
/// MSE of each column with the preset to beat): the worst ratio MSE / baseline over the
/// problems, times the geometric mean of the ratios to the power 0.2 (a tie-break that keeps
/// the search moving where the worst case is flat), so that minimising it lowers the worst
/// case relative to the preset first; gains that do not beat the preset in every problem
/// (worst ratio >= 1) cost 1 more (above every gain set that beats it in every problem, which
/// costs below 1), plus, with `hinge`, not that worst ratio but the sum over the problems of
/// `max(0, ln ratio + 0.01)` plus `0.001 ln` of the geometric mean (every case not beaten by
/// 1 % counts, not only the worst: see [`tune_preset`]). Infinite if any problem is.
struct Problems<'a> {
    problems: &'a [Problem<'a>],
    baselines: Option<&'a [[[f64; FAMILY_COUNT]; 2]]>,
    hinge: bool,
    /// [`Eval::constant_rate`].
    constant_rate: Option<f64>,
}

impl Problems<'_> {
    fn combine(&self, i: usize, acc: bool, f: impl Fn(&Problem<'_>) -> f64) -> f64 {
        let mut s = 0.0;
        let mut worst = 0.0f64;
        let mut hinge = 0.0f64;
        for (k, p) in self.problems.iter().enumerate() {
            let mut v = f(p);
            if let Some(b) = self.baselines {
                v /= b[k][usize::from(acc)][i];
            }
            if !(v.is_finite() && v > 0.0) {
                return f64::INFINITY;
            }
            worst = worst.max(v);
            hinge += (v.ln() + 0.01).max(0.0);
            s += v.ln();
        }
        let gm = (s / self.problems.len().max(1) as f64).exp();
        if self.baselines.is_some() {
            if worst < 1.0 {
                worst * gm.powf(0.2)
            } else if self.hinge {
                // hinge >= 0.01 here (some ratio >= 1) and gm >= 1e-4 in practice: above 1.
                1.0 + hinge + 0.001 * gm.ln()
            } else {
                1.0 + worst * gm.powf(0.2)
            }
        } else {
            gm
        }
    }
}

impl Eval for Problems<'_> {
    fn step_s(&self) -> f32 {
        self.problems.first().map_or(1e-4, |p| p.opts.step_s)
    }
    fn family<L: Law<Num = f32>>(&self, i: usize, law: L, acc: bool) -> f64 {
        self.combine(i, acc, |p| p.eval_family(law, acc))
    }
    fn kf(&self, i: usize, q: f32, r: f32, acc: bool) -> f64 {
        self.combine(i, acc, |p| p.kf(i, q, r, acc))
    }
    fn constant_rate(&self) -> Option<f64> {
        self.constant_rate
    }
}

impl Problem<'_> {
    /// Mean over seeds of the MSE of an adapter-driven estimator built by `make`.
    fn eval<E: Estimator<f32>>(&self, make: &dyn Fn() -> Option<E>, acc: bool) -> f64 {
        let reference = if acc { &self.acc_ref } else { &self.vel_ref };
        let t: Vec<u64> = self.samples.iter().map(|s| s.t_us).collect();
        let mut total = 0.0;
        for y in &self.ys {
            let Some(e) = make() else {
                return f64::INFINITY;
            };
            let Ok(mut ad) =
                SampleAdapter::new(e, self.opts.step_s, self.max_gap_s, self.opts.hold)
            else {
                return f64::INFINITY;
            };
            let mut out = Vec::with_capacity(y.len());
            let mut restart = false;
            for ((s, &v), &fed) in self.samples.iter().zip(y).zip(&self.lock.fed) {
                if !fed {
                    restart = true;
                    out.push(f32::NAN);
                    continue;
                }
                if std::mem::take(&mut restart) {
                    ad.restart();
                }
                out.push(ad.update(s.t_us, v).unwrap_or(f32::NAN));
            }
            let m = mse_scored(&t, &out, reference, self.range, Some(&self.lock.scored));
            if !m.is_finite() {
                return f64::INFINITY;
            }
            total += m;
        }
        total / self.ys.len() as f64
    }

    /// [`Self::eval`] of `law` (velocity half) or, for the acceleration half, of two of it
    /// in series (both stages with the same gains, as in the bank).
    fn eval_family<L: Law<Num = f32>>(&self, law: L, acc: bool) -> f64 {
        if acc {
            self.eval(&|| Some(Stateful::from_law(Series::new(law, law))), true)
        } else {
            self.eval(&|| Some(Stateful::from_law(law)), false)
        }
    }

    /// Mean over seeds of the MSE of a Kalman tracker (velocity or acceleration output).
    fn eval_kf(&self, cfg: &KalmanConfig, acc: bool) -> f64 {
        let reference = if acc { &self.acc_ref } else { &self.vel_ref };
        let t: Vec<u64> = self.samples.iter().map(|s| s.t_us).collect();
        let h_s = (f64::from(self.opts.step_s) * 1e6).round() as f32 * 1e-6;
        let h_us = f64::from(h_s) * 1e6;
        let mut total = 0.0;
        for y in &self.ys {
            let Ok(mut kf) = Kalman::<f32>::new(cfg) else {
                return f64::INFINITY;
            };
            let mut out = Vec::with_capacity(y.len());
            let mut prev: Option<u64> = None;
            for ((s, &v), &fed) in self.samples.iter().zip(y).zip(&self.lock.fed) {
                if !fed {
                    // Restarts at the next sample fed, as the bank does after gimbal lock.
                    prev = None;
                    out.push(f32::NAN);
                    continue;
                }
                match prev {
                    None => kf.reset(v),
                    // Like the bank: dt = (number of steps h in the interval) * h.
                    Some(p) => kf.update(v, steps_between(p, s.t_us, h_us) as f32 * h_s),
                }
                prev = Some(s.t_us);
                out.push(if acc {
                    kf.acceleration()
                } else {
                    kf.velocity()
                });
            }
            let m = mse_scored(&t, &out, reference, self.range, Some(&self.lock.scored));
            if !m.is_finite() {
                return f64::INFINITY;
            }
            total += m;
        }
        total / self.ys.len() as f64
    }
}

/// One family's minimisation: result and its cost.
struct Fit {
    x: Vec<f64>,
    cost: f64,
    evals: usize,
    secs: f64,
}

/// Minimises `f` from `x0` within the family's search box ([`search::search_box`]) at the
/// step `h_s` (s).
fn fit<F: Family>(method: Method, h_s: f64, x0: &[f64], f: &dyn Fn(&[f64]) -> f64) -> Fit {
    let t = Instant::now();
    let (lo, hi) = search::search_box::<F>(h_s);
    let o = optim::minimise(method, x0, &lo, &hi, f);
    Fit {
        x: o.x,
        cost: o.cost,
        evals: o.evals,
        secs: t.elapsed().as_secs_f64(),
    }
}

/// Tunes one half of the bank (velocity or acceleration) starting from `start`: each family
/// present there, over every gain it searches ([`search::search_point`], within
/// [`search::search_box`]; candidates its law refuses cost infinity). Returns the gains and,
/// per family, (tuned MSE, evaluations, seconds).
fn tune_family(
    p: &impl Eval,
    start: &FamilyGains,
    acc: bool,
    method: Method,
    families: Families,
) -> (FamilyGains, [(f64, usize, f64); FAMILY_COUNT]) {
    /// Tunes each family in turn.
    struct Tune<'a, E> {
        p: &'a E,
        start: &'a FamilyGains,
        acc: bool,
        method: Method,
        families: Families,
        out: FamilyGains,
        stats: [(f64, usize, f64); FAMILY_COUNT],
    }
    impl<E: Eval> FamilyVisitor for Tune<'_, E> {
        fn family<F: Family>(&mut self, column: usize) {
            if !self.families.tunes(self.acc, column) {
                // Not tuned: no cost (NaN), left out of the score and the report.
                self.stats[column] = (f64::NAN, 0, 0.0);
                return;
            }
            let Some(g0) = self.start.get::<F>() else {
                return;
            };
            let h = self.p.step_s();
            let objective = Objective {
                eval: self.p,
                column,
                acc: self.acc,
            };
            // The gains at a point of the search, held to a constant rate if asked
            // (velocity half).
            let at = |x: &[f64]| {
                let g = search::with_search_point::<F>(&g0, x);
                match (self.acc, self.p.constant_rate()) {
                    (false, Some(s)) => search::holding_constant_rate::<F>(&g, s),
                    _ => g,
                }
            };
            let f = |x: &[f64]| at(x).build(h, objective).unwrap_or(f64::INFINITY);
            let x0 = search::search_point::<F>(&g0);
            let r = fit::<F>(self.method, f64::from(h), &x0, &f);
            self.stats[column] = (r.cost, r.evals, r.secs);
            self.p.fitted();
            // Nothing finite to minimise: the family keeps the gains it started from.
            if r.cost.is_finite() {
                self.out.set::<F>(Some(at(&r.x)));
            }
        }
    }
    let mut tune = Tune {
        p,
        start,
        acc,
        method,
        families,
        out: *start,
        stats: [(f64::INFINITY, 0, 0.0); FAMILY_COUNT],
    };
    for_each_family(&mut tune);
    (tune.out, tune.stats)
}

/// Runs the tuner with the defaults of `nav440 tune`: global search, both holds, MSE over
/// `0..=window_s`.
pub fn tune(
    samples: &[Sample],
    opts: &EstimateOptions,
    noise_var: f64,
    seeds: u64,
    window_s: f64,
) -> Result<TuneResult> {
    tune_with(
        samples,
        opts,
        &TuneSpec {
            noise_var,
            seeds,
            train: (0.0, window_s),
            test: None,
            method: Method::Search,
            holds: vec![Hold::Linear, Hold::ZeroOrder],
            families: Families::ALL,
        },
    )
}

/// Checks a time range, s: finite, `0 <= from < to`.
pub fn check_range(what: &str, (from, to): (f64, f64)) -> Result<()> {
    if from.is_finite() && to.is_finite() && from >= 0.0 && to > from {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "{what} must be a time range T0-T1 in s with 0 <= T0 < T1, got {from}-{to}"
        )))
    }
}

/// Runs the tuner. For each hold, the velocity and acceleration halves run on 2 threads.
pub fn tune_with(
    samples: &[Sample],
    opts: &EstimateOptions,
    spec: &TuneSpec,
) -> Result<TuneResult> {
    tune_with_progress(samples, opts, spec, &Progress::hidden())
}

/// [`tune_with`], telling `progress` of every objective evaluation and family fit.
pub fn tune_with_progress(
    samples: &[Sample],
    opts: &EstimateOptions,
    spec: &TuneSpec,
    progress: &Progress,
) -> Result<TuneResult> {
    tune_on(&[samples], opts, spec, progress)
}

/// [`tune_with_progress`] on several captures at once (`nav440 tune FILE FILE ...`): each
/// family's objective is the geometric mean of its MSE over the captures (each capture weighs
/// the same whatever its MSE's scale), and the before/after MSEs are the means over the
/// captures. The captures must share one packet rate (the bank's nominal period). With one
/// capture it is exactly [`tune_with_progress`].
pub fn tune_on(
    captures: &[&[Sample]],
    opts: &EstimateOptions,
    spec: &TuneSpec,
    progress: &Progress,
) -> Result<TuneResult> {
    let started = Instant::now();
    check_range("--train", spec.train)?;
    let test = spec.test.unwrap_or(spec.train);
    check_range("--test", test)?;
    let Some(&first) = captures.first() else {
        return Err(Error::Usage("no capture to tune on".into()));
    };
    let seeds = spec.seeds.max(1);
    let noise_var = spec.noise_var;
    let opts = &opts.paper_law();
    let axis = opts.axis();
    let holds = if spec.holds.is_empty() {
        vec![opts.hold]
    } else {
        spec.holds.clone()
    };
    let hold_before = opts.hold;
    check_one_rate(captures, opts)?;
    let locks: Vec<Lock> = captures.iter().map(|c| Lock::of(c, axis)).collect();
    let (rows_scored, rows_left_out) = locks
        .iter()
        .zip(captures)
        .map(|(l, c)| l.counts_in(c, spec.train))
        .fold((0, 0), |(a, b), (x, y)| (a + x, b + y));
    if rows_scored == 0 {
        return Err(Error::Usage(format!(
            "nothing to score on the training range {}-{} s: {}",
            spec.train.0,
            spec.train.1,
            match rows_left_out {
                0 => "no sample lies in it".to_string(),
                n => format!(
                    "all its {n} samples are near gimbal lock (|pitch| >= {} deg) or within {} s after it",
                    nav440_pipeline::euler::PITCH_LIMIT_DEG,
                    crate::score::LOCK_SETTLE_S
                ),
            }
        )));
    }
    if rows_scored < crate::score::MIN_ROWS {
        return Err(Error::Usage(format!(
            "only {rows_scored} row(s) to score on the training range {}-{} s: tuning needs at least {} (fewer give an MSE of 0 whatever the gains)",
            spec.train.0,
            spec.train.1,
            crate::score::MIN_ROWS
        )));
    }
    let test_rows: usize = locks
        .iter()
        .zip(captures)
        .map(|(l, c)| l.counts_in(c, test).0)
        .sum();
    if test_rows == 0 {
        let end = captures
            .iter()
            .filter_map(|c| c.last())
            .map(|s| s.t_s())
            .fold(0.0, f64::max);
        return Err(Error::Usage(format!(
            "--test {}-{} s holds no row to score (the data spans 0-{end:.2} s)",
            test.0, test.1
        )));
    }
    let base_before = opts.bank_config_for(first);
    let paper = GainsFile::from_bank(&base_before);
    // Per capture: the noisy inputs, the Euler-kinematics rate (NaN, left out of every MSE,
    // near gimbal lock) and one acceleration reference for every hold: the AVE on the rate with
    // the options' hold (the paper's protocol), so that the holds are compared on one target.
    let mut inputs = Vec::with_capacity(captures.len());
    for (&samples, lock) in captures.iter().zip(&locks) {
        let ys = noisy_inputs(samples, axis, noise_var, 1..=seeds)?;
        let vel_ref: Vec<f32> = samples
            .iter()
            .map(|s| s.reference(axis).unwrap_or(f32::NAN))
            .collect();
        let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, opts)?;
        inputs.push((samples, ys, vel_ref, acc_ref, lock));
    }
    let mut runs = Vec::new();
    let mut best: Option<(f64, GainsFile, Hold)> = None;
    for &hold in &holds {
        let o = EstimateOptions {
            hold,
            ..opts.clone()
        };
        let problems: Vec<Problem<'_>> = inputs
            .iter()
            .map(|(samples, ys, vel_ref, acc_ref, lock)| {
                let base = o.bank_config_for(samples);
                Problem {
                    samples,
                    ys: ys.clone(),
                    vel_ref: vel_ref.clone(),
                    acc_ref: acc_ref.clone(),
                    opts: &o,
                    max_gap_s: base.max_gap_s(),
                    sample_period_s: base.sample_period_s,
                    range: spec.train,
                    lock: (*lock).clone(),
                    progress: Some(progress),
                }
            })
            .collect();
        let (velocity, acceleration) = match problems.as_slice() {
            [one] => tune_halves(one, &paper, spec)?,
            many => tune_halves(
                &Problems {
                    problems: many,
                    baselines: None,
                    hinge: false,
                    constant_rate: None,
                },
                &paper,
                spec,
            )?,
        };
        let mut run = HoldRun {
            hold,
            score: 0.0,
            cost: [[0.0; FAMILY_COUNT]; 2],
            evals: [[0; FAMILY_COUNT]; 2],
            secs: [[0.0; FAMILY_COUNT]; 2],
        };
        let mut log_sum = 0.0;
        for (half, stats) in [&velocity.1, &acceleration.1].into_iter().enumerate() {
            for (i, &(c, e, t)) in stats.iter().enumerate() {
                run.cost[half][i] = c;
                run.evals[half][i] = e;
                run.secs[half][i] = t;
                if spec.families.tunes(half == 1, i) {
                    log_sum += c.ln();
                }
            }
        }
        run.score = (log_sum / spec.families.count().max(1) as f64).exp();
        // The families not tuned are left out of the file (they keep the bank's gains).
        let f = spec.families;
        let gains = GainsFile {
            velocity: velocity.0.only(|i| f.tunes(false, i)),
            acceleration: acceleration.0.only(|i| f.tunes(true, i)),
        };
        if best.as_ref().is_none_or(|b| run.score < b.0) {
            best = Some((run.score, gains, hold));
        }
        runs.push(run);
    }
    let Some((_, gains, hold)) = best else {
        return Err(Error::Other("no hold to tune".into()));
    };
    let mut warnings = Vec::new();
    if let Some(run) = runs.iter().find(|r| r.hold == hold) {
        for (half, what) in ["velocity", "acceleration"].iter().enumerate() {
            for (i, name) in NAMES.iter().enumerate() {
                if spec.families.tunes(half == 1, i) && !run.cost[half][i].is_finite() {
                    warnings.push(format!(
                        "{name} {what}: no finite training MSE on {}-{} s ({rows_scored} rows scored); its gains are left as they were",
                        spec.train.0, spec.train.1
                    ));
                }
            }
        }
        if run.cost.iter().flatten().all(|c| !c.is_finite()) {
            return Err(Error::Other(format!(
                "no family could be scored on the training range {}-{} s ({rows_scored} rows scored): every training MSE is not finite, so nothing was tuned and no file is written",
                spec.train.0, spec.train.1
            )));
        }
    }
    // Before/after through the whole bank, on the test range, against the same references:
    // the mean over the captures.
    let bank_mse = |cfg: BankConfig| -> Result<([f64; FAMILY_COUNT], [f64; FAMILY_COUNT])> {
        let mut sum = ([0.0; FAMILY_COUNT], [0.0; FAMILY_COUNT]);
        for (samples, _, _, acc_ref, _) in &inputs {
            let (v, a) = bank_mse_with(samples, opts, acc_ref, cfg, noise_var, 1..=seeds, test)?;
            for i in 0..FAMILY_COUNT {
                sum.0[i] += v[i];
                sum.1[i] += a[i];
            }
        }
        let n = inputs.len() as f64;
        Ok((sum.0.map(|x| x / n), sum.1.map(|x| x / n)))
    };
    let (vel_before, acc_before) = bank_mse(base_before)?;
    let mut tuned_cfg = gains.apply(base_before);
    tuned_cfg.hold = hold;
    let (vel_after, acc_after) = bank_mse(tuned_cfg)?;
    // A family whose tuned gains score worse than the gains it started from, on the range the
    // report measures: said on stderr, family by family (the hold is chosen by the bank's
    // overall score, so one family can lose what the others gain).
    for (what, before, after, acc) in [
        ("velocity", &vel_before, &vel_after, false),
        ("acceleration", &acc_before, &acc_after, true),
    ] {
        for (i, name) in NAMES.iter().enumerate() {
            let (b, a) = (before[i], after[i]);
            if spec.families.tunes(acc, i) && b.is_finite() && a.is_finite() && a > b {
                warnings.push(format!(
                    "{name} {what}: the tuned gains score worse than the starting gains on {}-{} s (MSE {b:.3} before, {a:.3} after, hold {}); keep the starting [{what}.{}] table if that matters",
                    test.0,
                    test.1,
                    hold_name(hold),
                    name.to_ascii_lowercase()
                ));
            }
        }
    }
    // A tuned leaky ILO that reads a constant rate low (on a zero-mean motion at high noise the
    // search can trade that bias for less noise): said on stderr, because a sustained rotation
    // (a spin) then reads low by as much.
    for (col, name) in NAMES.iter().enumerate() {
        let g = schedule::constant_rate_gain(&gains.velocity, col);
        if spec.families.tunes(false, col) && !schedule::holds(g) {
            warnings.push(format!(
                "{name} velocity: the tuned gains read a constant rate {:.2} % low (K2 / (K2 + L (1 - K1)) = {g:.5}); a sustained rotation reads low by as much",
                100.0 * (1.0 - g)
            ));
        }
    }
    Ok(TuneResult {
        noise_var,
        seeds,
        window_s: spec.train.1,
        train: spec.train,
        test,
        method: spec.method,
        hold,
        hold_before,
        runs,
        elapsed_s: started.elapsed().as_secs_f64(),
        gains,
        paper,
        vel_before,
        vel_after,
        acc_before,
        acc_after,
        rows_scored,
        rows_left_out,
        warnings,
        families: spec.families,
    })
}

/// Tunes both halves of `start` on `eval` (the velocity half on a second thread): the tuned
/// gains and each family's (cost, evaluations, seconds).
#[allow(clippy::type_complexity)]
fn tune_halves(
    eval: &impl Eval,
    start: &GainsFile,
    spec: &TuneSpec,
) -> Result<(
    (FamilyGains, [(f64, usize, f64); FAMILY_COUNT]),
    (FamilyGains, [(f64, usize, f64); FAMILY_COUNT]),
)> {
    let (velocity, acceleration) = std::thread::scope(|s| {
        let v = s.spawn(|| tune_family(eval, &start.velocity, false, spec.method, spec.families));
        let a = tune_family(eval, &start.acceleration, true, spec.method, spec.families);
        (v.join(), a)
    });
    let velocity = velocity.map_err(|_| Error::Other("tuning thread panicked".into()))?;
    Ok((velocity, acceleration))
}

/// Refuses captures at different packet rates (their banks' nominal periods differ): one
/// tuned gain set is for one rate.
pub(crate) fn check_one_rate(captures: &[&[Sample]], opts: &EstimateOptions) -> Result<()> {
    let periods: Vec<f32> = captures
        .iter()
        .map(|c| opts.bank_config_for(c).sample_period_s)
        .collect();
    if periods.windows(2).any(|w| w[0] != w[1]) {
        return Err(Error::Usage(format!(
            "the captures have different packet periods ({}): tune on captures at one packet rate",
            periods
                .iter()
                .map(|p| format!("{p} s"))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(())
}

/// The unwrapped noisy angle of `axis` for each noise seed (the tuner's inputs).
fn noisy_inputs(
    samples: &[Sample],
    axis: replay::Axis,
    noise_var: f64,
    seeds: impl Iterator<Item = u64>,
) -> Result<Vec<Vec<f32>>> {
    seeds
        .map(|seed| {
            let y = replay::noisy_angle(
                samples,
                axis,
                Some(Noise {
                    var: noise_var,
                    seed,
                }),
            )?;
            Ok(if axis.wraps() {
                replay::unwrap_deg(&y)
            } else {
                y
            })
        })
        .collect()
}

/// Per-column MSE of the whole bank with `cfg` (its hold included) over `range` (s), mean of
/// the noise seeds `seeds` at `noise_var` deg^2: velocity against the Euler-kinematics
/// rate, acceleration against `acc_ref` (see [`ave_on_rate`]). What `nav440 tune` prints as
/// "before" and "after" (`nav440 estimate --gains` computes the same rows).
fn bank_mse_with(
    samples: &[Sample],
    opts: &EstimateOptions,
    acc_ref: &[f32],
    cfg: BankConfig,
    noise_var: f64,
    seeds: std::ops::RangeInclusive<u64>,
    range: (f64, f64),
) -> Result<([f64; FAMILY_COUNT], [f64; FAMILY_COUNT])> {
    let axis = opts.axis();
    let mut v = [0.0; FAMILY_COUNT];
    let mut a = [0.0; FAMILY_COUNT];
    let n = seeds.clone().count() as f64;
    for seed in seeds {
        let mut o = opts.clone();
        o.hold = cfg.hold;
        o.config = Some(cfg);
        o.noise = Some(Noise {
            var: noise_var,
            seed,
        });
        let (rows, _) = replay::estimate(samples, &o)?;
        let from = (range.0 * 1e6).round() as u64;
        let rows: Vec<_> = rows.into_iter().filter(|r| r.t_us >= from).collect();
        let (vv, aa) = row_mse(axis, &rows, samples, acc_ref, range.1);
        for i in 0..FAMILY_COUNT {
            v[i] += vv[i] / n;
            a[i] += aa[i] / n;
        }
    }
    Ok((v, a))
}

/// The MSE `nav440 tune` reports for a bank configuration ("before"/"after"): per column
/// (velocity, acceleration), through the whole bank with `cfg` (gains and hold), over `range`
/// (s), mean of the noise seeds `1..=seeds` at `noise_var` deg^2, on the first axis of `opts`
/// (yaw by default); the acceleration reference is the AVE (500, 20000) on the rate with the
/// linear hold, as in `nav440 tune` and `nav440 paper`.
pub fn bank_mse(
    samples: &[Sample],
    cfg: BankConfig,
    noise_var: f64,
    seeds: u64,
    range: (f64, f64),
) -> Result<([f64; FAMILY_COUNT], [f64; FAMILY_COUNT])> {
    let opts = EstimateOptions::default().paper_law();
    let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, &opts)?;
    bank_mse_with(
        samples,
        &opts,
        &acc_ref,
        cfg,
        noise_var,
        1..=seeds.max(1),
        range,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The crossing of the two levels' log-MSE lines in ln(noise), worked by hand: symmetric
    /// lines cross at the geometric midpoint; `[1, 2, 8, 1]` gives `d0 = -ln 8`, `d1 = ln 2`,
    /// so 3/4 of the way; no crossing inside gives the end where the other level already
    /// wins; a non-finite MSE keeps the lower level up to the upper one.
    #[test]
    fn crossover_of_two_levels() {
        let (a, b) = (0.001, 0.01);
        let close = |x: f64, y: f64| (x / y - 1.0).abs() < 1e-12;
        assert!(close(crossover([1.0, 4.0, 4.0, 1.0], a, b), (a * b).sqrt()));
        assert!(close(
            crossover([1.0, 2.0, 8.0, 1.0], a, b),
            a * (b / a).powf(0.75)
        ));
        assert_eq!(crossover([2.0, 4.0, 1.0, 1.0], a, b), a);
        assert_eq!(crossover([1.0, 1.0, 4.0, 2.0], a, b), b);
        assert_eq!(crossover([1.0, f64::NAN, 4.0, 2.0], a, b), b);
        assert_eq!(crossover([1.0, 0.0, 4.0, 2.0], a, b), b);
        // The choice hardly matters (lines within SWITCH_MATTERS = 1.2x at the midpoint:
        // 0.5 % and 4 % apart; identical gains; 4 % apart at both ends): the
        // midpoint, though the lines cross elsewhere.
        assert!(close(
            crossover([1.0, 1.02, 1.01, 1.0], a, b),
            (a * b).sqrt()
        ));
        assert!(close(crossover([1.0, 1.3, 1.2, 1.0], a, b), (a * b).sqrt()));
        assert!(close(crossover([1.0, 2.0, 1.0, 2.0], a, b), (a * b).sqrt()));
        assert!(close(
            crossover([1.0, 1.0, 1.04, 1.04], a, b),
            (a * b).sqrt()
        ));
    }

    #[test]
    fn mse_range_counts_only_the_samples_in_the_range() {
        let t = [0, 1_000_000, 2_000_000, 3_000_000];
        let est = [1.0, 2.0, 3.0, 10.0];
        let r = [0.0; 4];
        // 1 s and 2 s, both ends included: (4 + 9) / 2.
        assert_eq!(mse_range(&t, &est, &r, (1.0, 2.0)), 6.5);
        assert!(mse_range(&t, &est, &r, (3.5, 4.0)).is_nan());
        assert!(check_range("--train", (2.0, 1.0)).is_err());
        assert!(check_range("--train", (-1.0, 1.0)).is_err());
        assert!(check_range("--train", (0.0, f64::NAN)).is_err());
        assert!(check_range("--train", (0.0, 0.5)).is_ok());
    }
}
