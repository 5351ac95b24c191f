//! `nav440 tune`: per-capture, per-noise-level calibration of each estimator family's gains
//! (the paper: "gains must be re-calibrated to the noise level"). docs/CALIBRATION.md.
//!
//! Method: for each family (AVE; ILO1, ILO2, ILO3 from their presets; AD; ED; KF) and each half
//! of the bank (velocity against the measured rate; series acceleration against the AVE on the
//! measured rate), [`crate::optim::minimise`] over every gain of the family within its valid
//! range ([`ranges`]: K1 included) of the MSE over the training time range averaged over
//! `seeds` noise seeds: a global search (coarse log grid, then Nelder-Mead of the `argmin`
//! crate from several starts and from the paper preset) or, with `--exhaustive`, a log grid.
//! Candidates the constructors reject (e.g. `h * L >= 1`) or that diverge count as infinite
//! MSE. Every hold asked for (both by default) is tuned; the one with the smaller geometric
//! mean of the tuned MSEs over the 14 families is kept (the hold is one bank-wide option). The single estimators run behind
//! `estimators::SampleAdapter` (unwrapped noisy yaw, same hold and step as the bank); the
//! "before" and "after" MSE printed are then measured through the whole `PaperBank` with the
//! paper presets and with the tuned gains file, i.e. exactly what `nav440 estimate --gains`
//! computes.

use crate::error::{Error, Result};
use crate::gains::{FamilyGains, GainsFile};
use crate::optim::{self, Method};
use crate::paper::{ave_on_rate, row_mse, steps_between, REFERENCE_AVE};
use crate::progress::Progress;
use crate::replay::{self, EstimateOptions, Noise, Sample};
use estimators::{
    for_each_family, BankConfig, Estimator, Family, FamilyVisitor, Gains, Hold, Kalman,
    KalmanConfig, KalmanNoise, Law, SampleAdapter, Scheduling, Scorer, Series, Stateful, FAMILIES,
    FAMILY_COUNT,
};
use std::time::Instant;

// Column names in bank order.
use crate::paper::COLUMNS as NAMES;

/// The number of tuned MSEs (every family, velocity and acceleration).
const TUNED_MSES: usize = 2 * FAMILY_COUNT;

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
    /// Told of every evaluation and family fit (`nav440 tune`'s progress bar).
    progress: Option<&'a Progress>,
}

/// MSE of `est` against `reference` over the samples with `from <= t <= to` (s); NaN if none.
pub fn mse_range(t_us: &[u64], est: &[f32], reference: &[f32], (from, to): (f64, f64)) -> f64 {
    let (lo, hi) = ((from * 1e6).round() as u64, (to * 1e6).round() as u64);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for ((&t, &e), &r) in t_us.iter().zip(est).zip(reference) {
        if t >= lo && t <= hi {
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

/// One family's objective in one half ([`Gains::score`] hands it the estimator to score).
struct Objective<'a, E> {
    eval: &'a E,
    column: usize,
    acc: bool,
}

impl<E: Eval> Scorer for Objective<'_, E> {
    type Score = f64;
    fn law<L: Law<Num = f32>>(&self, law: L) -> f64 {
        self.eval.family(self.column, law, self.acc)
    }
    fn tracker(&self, noise: KalmanNoise) -> f64 {
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
            for (s, &v) in self.samples.iter().zip(y) {
                out.push(ad.update(s.t_us, v).unwrap_or(f32::NAN));
            }
            let m = mse_range(&t, &out, reference, self.range);
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
            for (s, &v) in self.samples.iter().zip(y) {
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
            let m = mse_range(&t, &out, reference, self.range);
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

/// Minimises `f` from `x0` within the family's search box ([`Gains::search_box`]) at the
/// step `h_s` (s).
fn fit<G: Gains>(method: Method, h_s: f64, x0: &[f64], f: &dyn Fn(&[f64]) -> f64) -> Fit {
    let t = Instant::now();
    let (lo, hi) = G::search_box(h_s);
    let o = optim::minimise(method, x0, &lo, &hi, f);
    Fit {
        x: o.x,
        cost: o.cost,
        evals: o.evals,
        secs: t.elapsed().as_secs_f64(),
    }
}

/// Tunes one half of the bank (velocity or acceleration) starting from `start`: each family
/// present there, over every gain it searches ([`Gains::search_point`], within
/// [`Gains::search_box`]; candidates its law refuses cost infinity). Returns the gains and,
/// per family, (tuned MSE, evaluations, seconds).
fn tune_family(
    p: &impl Eval,
    start: &FamilyGains,
    acc: bool,
    method: Method,
) -> (FamilyGains, [(f64, usize, f64); FAMILY_COUNT]) {
    /// Tunes each family in turn.
    struct Tune<'a, E> {
        p: &'a E,
        start: &'a FamilyGains,
        acc: bool,
        method: Method,
        out: FamilyGains,
        stats: [(f64, usize, f64); FAMILY_COUNT],
    }
    impl<E: Eval> FamilyVisitor for Tune<'_, E> {
        fn family<F: Family>(&mut self, column: usize) {
            let Some(g0) = self.start.get::<F>() else {
                return;
            };
            let h = self.p.step_s();
            let objective = Objective {
                eval: self.p,
                column,
                acc: self.acc,
            };
            let f = |x: &[f64]| {
                let g = g0.with_search_point(x);
                g.score(h, &objective).unwrap_or(f64::INFINITY)
            };
            let r = fit::<F::Gains>(self.method, f64::from(h), &g0.search_point(), &f);
            self.stats[column] = (r.cost, r.evals, r.secs);
            self.p.fitted();
            self.out.set::<F>(Some(g0.with_search_point(&r.x)));
        }
    }
    let mut tune = Tune {
        p,
        start,
        acc,
        method,
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
    let started = Instant::now();
    check_range("--train", spec.train)?;
    let test = spec.test.unwrap_or(spec.train);
    check_range("--test", test)?;
    let seeds = spec.seeds.max(1);
    let noise_var = spec.noise_var;
    let opts = &opts.paper_law();
    let axis = opts.axis();
    let ys = noisy_inputs(samples, axis, noise_var, 1..=seeds)?;
    let holds = if spec.holds.is_empty() {
        vec![opts.hold]
    } else {
        spec.holds.clone()
    };
    let hold_before = opts.hold;
    let base_before = opts.bank_config_for(samples);
    let paper = GainsFile::from_bank(&base_before);
    // The Euler-kinematics rate; NaN (left out of every MSE) near gimbal lock.
    let vel_ref: Vec<f32> = samples
        .iter()
        .map(|s| s.reference(axis).unwrap_or(f32::NAN))
        .collect();
    let mut runs = Vec::new();
    // One acceleration reference for every hold: the AVE on the rate with the options' hold
    // (the paper's protocol), so that the holds are compared on the same target.
    let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, opts)?;
    let mut best: Option<(f64, GainsFile, Hold)> = None;
    for &hold in &holds {
        let o = EstimateOptions {
            hold,
            ..opts.clone()
        };
        let base = o.bank_config_for(samples);
        let problem = Problem {
            samples,
            ys: ys.clone(),
            vel_ref: vel_ref.clone(),
            acc_ref: acc_ref.clone(),
            opts: &o,
            max_gap_s: base.max_gap_s(),
            sample_period_s: base.sample_period_s,
            range: spec.train,
            progress: Some(progress),
        };
        let (velocity, acceleration) = std::thread::scope(|s| {
            let v = s.spawn(|| tune_family(&problem, &paper.velocity, false, spec.method));
            let a = tune_family(&problem, &paper.acceleration, true, spec.method);
            (v.join(), a)
        });
        let velocity = velocity.map_err(|_| Error::Other("tuning thread panicked".into()))?;
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
                log_sum += c.ln();
            }
        }
        run.score = (log_sum / TUNED_MSES as f64).exp();
        let gains = GainsFile {
            velocity: velocity.0,
            acceleration: acceleration.0,
        };
        if best.as_ref().is_none_or(|b| run.score < b.0) {
            best = Some((run.score, gains, hold));
        }
        runs.push(run);
    }
    let Some((_, gains, hold)) = best else {
        return Err(Error::Other("no hold to tune".into()));
    };
    // Before/after through the whole bank, on the test range, against the same references.
    let bank_mse =
        |cfg: BankConfig| bank_mse_with(samples, opts, &acc_ref, cfg, noise_var, 1..=seeds, test);
    let (vel_before, acc_before) = bank_mse(base_before)?;
    let mut tuned_cfg = gains.apply(base_before);
    tuned_cfg.hold = hold;
    let (vel_after, acc_after) = bank_mse(tuned_cfg)?;
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
    })
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

/// One case of the shipped preset's tuning family: a capture's samples, a noise level and
/// the MSE range.
#[derive(Clone, Debug)]
pub struct PresetCase {
    /// Name printed in the report.
    pub name: String,
    /// The capture's samples.
    pub samples: Vec<Sample>,
    /// Noise variance added to yaw, deg^2.
    pub noise_var: f64,
    /// Noise seed.
    pub seed: u64,
    /// MSE range, s.
    pub range: (f64, f64),
}

/// A preset's tuning family from synthetic motions: each motion (profile, shape seed, packet
/// rate Hz, duration s; [`crate::synth::a2_samples`]) at each of `noise_vars` (deg^2), MSE
/// over the whole capture. Noise seed 1 for the fig5 motions (their seed is their shape's),
/// the motion's seed for the closed-form spin and sin5 (it only draws their noise).
pub fn synth_family(
    motions: &[(crate::motion::ProfileKind, u64, u32, f64)],
    noise_vars: &[f64],
) -> Result<Vec<PresetCase>> {
    let mut cases = Vec::new();
    for &(profile, seed, rate_hz, duration_s) in motions {
        let samples = crate::synth::a2_samples(profile, seed, rate_hz, duration_s)?;
        for &noise_var in noise_vars {
            cases.push(PresetCase {
                name: format!(
                    "{} seed {seed} {rate_hz} Hz, {noise_var} deg^2",
                    profile.name()
                ),
                samples: samples.clone(),
                noise_var,
                seed: if profile == crate::motion::ProfileKind::Fig5 {
                    1
                } else {
                    seed
                },
                range: (0.0, duration_s),
            });
        }
    }
    Ok(cases)
}

/// Tunes one set of gains for a whole family of cases (the shipped preset,
/// `BankConfig::NAV440`): each family's objective is, without `beat`, the geometric mean over
/// the cases of its MSE (the objective of `nav440 tune`, one noise seed per case, `seed`), so
/// that no case's scale dominates; with `beat`, the worst ratio of that MSE to `beat`'s MSE
/// on the same case and seed, times the geometric mean of the ratios to the power 0.2, plus 1
/// unless it beats `beat` in every case. Starts from `base`'s gains (the paper's gains; the
/// AVE keeps `base`'s `deltahat` law), with `base`'s hold and step.
///
/// With `beat`, a family that does not beat it in every case after that search (an objective
/// of 1 or more: the worst case cannot be beaten) is searched a second time from `base`'s
/// gains with the hinge objective (see `Problems`: every case not beaten by 1 % counts, where the first
/// objective only sees the worst one). The second result is kept if, scored through the whole
/// bank, it loses fewer cases to `beat` (MSE ratio >= 1) and its geometric mean ratio is not
/// larger; otherwise the first is kept (the hinge objective does not reward a case beyond
/// 1 %, so it may lose quality everywhere to win one case).
///
/// Returns the gains, per family (velocity, acceleration) the kept search's objective, and a
/// report of the second search's selection (cases lost and geometric mean ratio of both
/// results, per family searched twice; empty without `beat`).
pub fn tune_preset(
    cases: &[PresetCase],
    base: &BankConfig,
    beat: Option<&BankConfig>,
    method: Method,
) -> Result<(GainsFile, [[f64; FAMILY_COUNT]; 2], String)> {
    let opts = EstimateOptions {
        hold: base.hold,
        step_s: base.h,
        config: Some(*base),
        ..Default::default()
    };
    let axis = opts.axis();
    let mut problems = Vec::new();
    let mut baselines = Vec::new();
    let mut acc_refs = Vec::new();
    for c in cases {
        let acc_ref = ave_on_rate(&c.samples, &REFERENCE_AVE, &opts)?;
        if let Some(b) = beat {
            let (v, a) = bank_mse_with(
                &c.samples,
                &opts,
                &acc_ref,
                *b,
                c.noise_var,
                c.seed..=c.seed,
                c.range,
            )?;
            baselines.push([v, a]);
        }
        acc_refs.push(acc_ref);
    }
    for (c, acc_ref) in cases.iter().zip(&acc_refs) {
        let ys = noisy_inputs(&c.samples, axis, c.noise_var, std::iter::once(c.seed))?;
        let cfg = opts.bank_config_for(&c.samples);
        problems.push(Problem {
            samples: &c.samples,
            ys,
            vel_ref: c
                .samples
                .iter()
                .map(|s| s.reference(axis).unwrap_or(f32::NAN))
                .collect(),
            acc_ref: acc_ref.clone(),
            opts: &opts,
            max_gap_s: cfg.max_gap_s(),
            sample_period_s: cfg.sample_period_s,
            range: c.range,
            progress: None,
        });
    }
    let start = GainsFile::from_bank(base);
    let first = Problems {
        problems: &problems,
        baselines: beat.map(|_| baselines.as_slice()),
        hinge: false,
    };
    let (mut gains, mut cost) = tune_both(&first, &start, |_, _| true, method)?;
    if beat.is_none() {
        return Ok((gains, cost, String::new()));
    }
    // Second search, hinge objective, for the families that could not beat `beat` everywhere.
    let infeasible = cost;
    let second = Problems {
        problems: &problems,
        baselines: Some(&baselines),
        hinge: true,
    };
    let (hinged, hinge_cost) = tune_both(
        &second,
        &start,
        |acc, i| infeasible[usize::from(acc)][i] >= 1.0,
        method,
    )?;
    let score = |g: &GainsFile| -> Result<[[(usize, f64); FAMILY_COUNT]; 2]> {
        let cfg = g.apply(*base);
        let mut out = [[(0usize, 0.0f64); FAMILY_COUNT]; 2];
        for ((c, acc_ref), base_mse) in cases.iter().zip(&acc_refs).zip(&baselines) {
            let (v, a) = bank_mse_with(
                &c.samples,
                &opts,
                acc_ref,
                cfg,
                c.noise_var,
                c.seed..=c.seed,
                c.range,
            )?;
            for (half, m) in [v, a].iter().enumerate() {
                for i in 0..FAMILY_COUNT {
                    let r = m[i] / base_mse[half][i];
                    out[half][i].0 += usize::from(r >= 1.0);
                    out[half][i].1 += r.ln() / cases.len() as f64;
                }
            }
        }
        Ok(out)
    };
    // The first gains with every family searched twice replaced by its second result.
    let mut merged = gains;
    for (half, (m, h)) in [
        (&mut merged.velocity, &hinged.velocity),
        (&mut merged.acceleration, &hinged.acceleration),
    ]
    .into_iter()
    .enumerate()
    {
        for i in (0..FAMILY_COUNT).filter(|&i| infeasible[half][i] >= 1.0) {
            m.set_column(i, h);
        }
    }
    let (s1, s2) = (score(&gains)?, score(&merged)?);
    let mut report = String::new();
    for half in 0..2 {
        for i in (0..FAMILY_COUNT).filter(|&i| infeasible[half][i] >= 1.0) {
            let (l1, g1) = s1[half][i];
            let (l2, g2) = s2[half][i];
            let keep = l2 < l1 && g2 <= g1;
            report += &format!(
                "{} {}: first search {l1} of {n} cases lost, geometric mean ratio {:.3}; hinge search {l2} lost, {:.3}: {} kept\n",
                ["velocity", "acceleration"][half],
                NAMES[i],
                g1.exp(),
                g2.exp(),
                if keep { "hinge" } else { "first" },
                n = cases.len(),
            );
            if keep {
                let (dst, src) = if half == 0 {
                    (&mut gains.velocity, &hinged.velocity)
                } else {
                    (&mut gains.acceleration, &hinged.acceleration)
                };
                dst.set_column(i, src);
                cost[half][i] = hinge_cost[half][i];
            }
        }
    }
    Ok((gains, cost, report))
}

/// [`tune_family`] for both halves (velocity on a second thread), only the families
/// `(acceleration, column)` for which `which` is true (the others are `None` in the result
/// and cost infinity).
fn tune_both(
    set: &Problems<'_>,
    start: &GainsFile,
    which: impl Fn(bool, usize) -> bool,
    method: Method,
) -> Result<(GainsFile, [[f64; FAMILY_COUNT]; 2])> {
    let v0 = start.velocity.only(|i| which(false, i));
    let a0 = start.acceleration.only(|i| which(true, i));
    let (velocity, acceleration) = std::thread::scope(|s| {
        let v = s.spawn(|| tune_family(set, &v0, false, method));
        let a = tune_family(set, &a0, true, method);
        (v.join(), a)
    });
    let velocity = velocity.map_err(|_| Error::Other("tuning thread panicked".into()))?;
    let mut cost = [[0.0; FAMILY_COUNT]; 2];
    for (half, stats) in [&velocity.1, &acceleration.1].into_iter().enumerate() {
        for (i, st) in stats.iter().enumerate() {
            cost[half][i] = st.0;
        }
    }
    Ok((
        GainsFile {
            velocity: velocity.0,
            acceleration: acceleration.0,
        },
        cost,
    ))
}

/// `nav440 tune --schedule V1,V2,..`: [`tune_with`] at each noise level (`spec.noise_var`
/// replaced; one hold: `spec.holds[0]`, linear by default); then, per velocity observer
/// family (AVE, ILO1-3, ED), each level takes the best of every level's tuned gains at its own
/// noise (the velocity MSE through the bank, the tuner's seeds and range: a level's search
/// can end in a worse basin than a neighbour's gains); records each level's AVE `deltahat`
/// ([`tuned_ave_deltahat`]) and where each observer family moves on to the next level
/// ([`crossover`] of the MSEs already scored). Returns the schedule file (with the nominal
/// sample period the bank ran at, [`EstimateOptions::bank_period_s`]) and the printed report
/// (each level's report, the gains taken from another level, the switch points). `progress`
/// is told of every objective evaluation and family fit.
pub fn tune_schedule(
    samples: &[Sample],
    opts: &EstimateOptions,
    spec: &TuneSpec,
    levels: &[f64],
    progress: &Progress,
) -> Result<(crate::gains::ScheduleFile, String)> {
    if levels.is_empty()
        || levels.len() > estimators::adaptive::MAX_LEVELS
        || levels.windows(2).any(|w| w[1] <= w[0])
        || levels.iter().any(|v| !(v.is_finite() && *v > 0.0))
    {
        return Err(Error::Usage(format!(
            "--schedule needs 1 to {} noise variances > 0 in increasing order, got {levels:?}",
            estimators::adaptive::MAX_LEVELS
        )));
    }
    let hold = spec.holds.first().copied().unwrap_or(Hold::Linear);
    // A schedule is for the device, which runs for hours: its AVE is tuned with the product's
    // leaky `deltahat` law (`estimators::presets::AVE_DEFAULT`) whatever law the start gains
    // have (the start is the paper's gains, as for `nav440 tune`, unless a gains file is
    // given). The paper's law (`deltahat` only grows) degrades a long run
    // (docs/RELIABILITY.md).
    let mut start = opts.paper_law().bank_config();
    for half in [&mut start.velocity, &mut start.acceleration] {
        half.ave.delta = estimators::presets::AVE_DEFAULT.delta;
    }
    let opts = &EstimateOptions {
        config: Some(start),
        ..opts.clone()
    };
    let mut text = String::new();
    let mut tuned: Vec<GainsFile> = Vec::new();
    for &v in levels {
        let res = tune_with_progress(
            samples,
            opts,
            &TuneSpec {
                noise_var: v,
                holds: vec![hold],
                ..spec.clone()
            },
            progress,
        )?;
        text.push_str(&format!("== schedule level {v} deg^2 ==\n"));
        text.push_str(&res.to_text());
        text.push('\n');
        tuned.push(res.gains);
    }
    let config = |g: &GainsFile| BankConfig {
        hold,
        ..g.apply(opts.bank_config_for(samples))
    };
    // Each level's observers: the best of every level's tuned gains at this level's noise
    // (the search of one level can end in a worse basin than a neighbour's gains).
    let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, opts)?;
    let mut at = vec![vec![[0.0f64; FAMILY_COUNT]; levels.len()]; levels.len()];
    for (i, g) in tuned.iter().enumerate() {
        for (j, &v) in levels.iter().enumerate() {
            let seeds = 1..=spec.seeds.max(1);
            at[i][j] = bank_mse_with(samples, opts, &acc_ref, config(g), v, seeds, spec.train)?.0;
        }
    }
    // `source[j][c]`: the level whose tuned gains level `j` runs for the observer family of
    // column `c`.
    let mut source: Vec<[usize; FAMILY_COUNT]> =
        (0..levels.len()).map(|j| [j; FAMILY_COUNT]).collect();
    let before = tuned.clone();
    for (j, &v) in levels.iter().enumerate() {
        for col in observer_columns() {
            let best = (0..levels.len())
                .min_by(|&a, &b| at[a][j][col].total_cmp(&at[b][j][col]))
                .unwrap_or(j);
            if best == j || at[best][j][col] >= at[j][j][col] {
                continue;
            }
            source[j][col] = best;
            tuned[j].velocity.set_column(col, &before[best].velocity);
            text.push_str(&format!(
                "level {v} deg^2: {} velocity gains of level {} deg^2 (MSE {:.4} instead of {:.4} at {v} deg^2)\n",
                NAMES[col], levels[best], at[best][j][col], at[j][j][col]
            ));
        }
    }
    let mut level = Vec::new();
    for (g, &v) in tuned.iter().zip(levels) {
        let deltahat = tuned_ave_deltahat(samples, opts, &config(g), v, spec.seeds, spec.train)?;
        text.push_str(&format!(
            "level {v} deg^2: AVE deltahat tuned with (mean over the run): velocity {} deg/s, AVE-AVE {} deg/s, {} deg/s^2\n",
            deltahat.velocity, deltahat.acceleration[0], deltahat.acceleration[1]
        ));
        level.push(crate::gains::ScheduleLevelFile {
            noise_var: v,
            velocity: g.velocity,
            acceleration: g.acceleration,
            ave_deltahat: Some(deltahat.into()),
            switch_up: None,
        });
    }
    // Where each observer family moves on: from the MSEs already scored (a family's velocity
    // MSE depends only on its own gains, so level `j`'s is that of its source level's).
    for i in 0..levels.len().saturating_sub(1) {
        let (a, b) = (levels[i], levels[i + 1]);
        let point = |col: usize| {
            let (sa, sb) = (source[i][col], source[i + 1][col]);
            let m = [
                at[sa][i][col],
                at[sa][i + 1][col],
                at[sb][i][col],
                at[sb][i + 1][col],
            ];
            crossover(m, a, b) as f32
        };
        let sw = switch_points(point);
        level[i].switch_up = Some(crate::gains::SwitchUpFile(sw));
        let points: Vec<String> = sw
            .points()
            .iter()
            .map(|&(col, x)| format!("{} {x}", NAMES[col]))
            .collect();
        text.push_str(&format!(
            "switch up from level {a} to {b} deg^2 (where each family takes the next level's gains: where the two levels' MSEs cross if they differ by more than {SWITCH_MATTERS}x at the midpoint, else the midpoint): {}\n",
            points.join(", ")
        ));
    }
    Ok((
        crate::gains::ScheduleFile {
            hold: hold_name(hold).to_string(),
            // The f32's shortest decimal form (0.01, not 0.009999999776482582).
            sample_period_s: opts.bank_period_s(samples).to_string().parse().ok(),
            level,
        },
        text,
    ))
}

/// [`crossover`] keeps the geometric midpoint unless the two levels' MSE lines differ by more
/// than this factor there.
pub const SWITCH_MATTERS: f64 = 1.2;

/// The columns of the observer families ([`Scheduling::Observer`]): those a schedule gives
/// per-level gains and switch points.
fn observer_columns() -> impl Iterator<Item = usize> {
    (0..FAMILY_COUNT).filter(|&c| FAMILIES[c].scheduling == Scheduling::Observer)
}

/// The switch points `point(column)` of every family that records one
/// ([`Family::switch_up_mut`]).
fn switch_points(point: impl Fn(usize) -> f32) -> estimators::ObserverSwitch {
    struct Set<P>(estimators::ObserverSwitch, P);
    impl<P: Fn(usize) -> f32> FamilyVisitor for Set<P> {
        fn family<F: Family>(&mut self, column: usize) {
            if let Some(x) = F::switch_up_mut(&mut self.0) {
                *x = (self.1)(column);
            }
        }
    }
    let none = estimators::ObserverSwitch::all(0.0);
    let mut set = Set(none, point);
    for_each_family(&mut set);
    set.0
}

/// The noise variance (deg^2) between two levels `a < b` at which level `b`'s gains become
/// the better of the two, from the MSEs `[a's gains at a, a's at b, b's at a, b's at b]`:
/// each level's log MSE taken as linear in `ln(noise)` between `a` and `b`, where the two
/// lines cross; `a` if `b`'s gains are already no worse at `a`, `b` if `a`'s are still better
/// at `b` (or an MSE is not finite and positive). The geometric midpoint when the choice
/// hardly matters there: the two lines within [`SWITCH_MATTERS`] of each other at the
/// midpoint (identical gains, or two sets about as good at both levels); moving the switch
/// then only delays it while the noise estimate follows a change.
pub fn crossover(m: [f64; 4], a: f64, b: f64) -> f64 {
    if m.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return b;
    }
    let [aa, ab, ba, bb] = m.map(f64::ln);
    let (d0, d1) = (aa - ba, ab - bb);
    if ((d0 + d1) / 2.0).abs() < SWITCH_MATTERS.ln() {
        (a * b).sqrt()
    } else if d0 >= 0.0 {
        a
    } else if d1 <= 0.0 {
        b
    } else {
        a * (b / a).powf(d0 / (d0 - d1))
    }
}

/// The AVE row's switching gains `deltahat` (`estimators::PaperBank::ave_deltahat`) that
/// the bank configuration `cfg` is tuned with on `samples` with N(0, `noise_var`) noise
/// (deg^2) on the first axis of `opts`: the mean of `deltahat` over `range` (s) in a run from
/// the capture's start (where `deltahat` starts at 0, as in every evaluation of the tuner),
/// averaged over the noise seeds `1..=seeds`. `nav440 tune --schedule` records it per level
/// (`estimators::ScheduleLevel::ave_deltahat`).
///
/// Why the tuning run's mean, not the law's steady state: the leak's time constant
/// (`1 / sigma`, 10 s) is a third of a 30 s capture, so the gains are tuned with a `deltahat`
/// that is still growing. On the noise-switch test's 40 draws, setting the fig5 schedule's
/// 0.5 deg^2 level's run mean (5.7 deg/s) at a gain change left the AVE below every fixed set
/// on 22 draws (geometric mean ratio 0.988); the steady state reached after three runs
/// (8.1 deg/s, each run starting at the previous one's mean over its second half) on 16
/// (1.027), with a worse 12-20 s MSE (157.0 against 146.9 (deg/s)^2). (Measured before the AVE's
/// retune kept `xhat` towards slower gains, which took the run mean's result to 26 draws,
/// 0.972.)
pub fn tuned_ave_deltahat(
    samples: &[Sample],
    opts: &EstimateOptions,
    cfg: &BankConfig,
    noise_var: f64,
    seeds: u64,
    range: (f64, f64),
) -> Result<estimators::AveDeltahat> {
    let axis = opts.axis();
    let (from, to) = (
        (range.0 * 1e6).round() as u64,
        (range.1 * 1e6).round() as u64,
    );
    let seeds = seeds.max(1);
    let mut sum = [0.0f64; 3];
    for seed in 1..=seeds {
        let y = replay::noisy_angle(
            samples,
            axis,
            Some(Noise {
                var: noise_var,
                seed,
            }),
        )?;
        let mut bank: estimators::PaperBank<f32> = nav440_pipeline::axis_bank(axis, cfg)
            .map_err(|e| Error::Usage(format!("bad estimator configuration: {e}")))?;
        let (mut acc, mut n) = ([0.0f64; 3], 0u32);
        for (s, &y) in samples.iter().zip(&y) {
            if bank.update(s.t_us, y).is_ok() && (from..=to).contains(&s.t_us) {
                let d = bank.ave_deltahat();
                for (a, x) in acc
                    .iter_mut()
                    .zip([d.velocity, d.acceleration[0], d.acceleration[1]])
                {
                    *a += f64::from(x);
                }
                n += 1;
            }
        }
        if n == 0 {
            return Err(Error::Usage(format!(
                "no sample in {}-{} s to measure the AVE's deltahat on",
                range.0, range.1
            )));
        }
        for (s, a) in sum.iter_mut().zip(acc) {
            *s += a / f64::from(n);
        }
    }
    let m = sum.map(|x| (x / seeds as f64) as f32);
    Ok(estimators::AveDeltahat {
        velocity: m[0],
        acceleration: [m[1], m[2]],
    })
}

/// The CLI's name of a hold (`--hold`).
fn hold_name(h: Hold) -> &'static str {
    match h {
        Hold::Linear => "linear",
        Hold::ZeroOrder => "zoh",
    }
}

/// The gains of column `i` in `f` on one line ([`Gains::describe`]), `-` if absent.
fn fmt_gains(f: &FamilyGains, i: usize) -> String {
    struct Describe<'a>(&'a FamilyGains, usize, String);
    impl FamilyVisitor for Describe<'_> {
        fn family<F: Family>(&mut self, column: usize) {
            if column == self.1 {
                if let Some(g) = self.0.get::<F>() {
                    let _ = g.describe(&mut self.2);
                }
            }
        }
    }
    let mut d = Describe(f, i, String::new());
    for_each_family(&mut d);
    if d.2.is_empty() {
        "-".into()
    } else {
        d.2
    }
}

impl TuneResult {
    /// The printed report.
    pub fn to_text(&self) -> String {
        // "YawBank" (the type is `PaperBank`): the report is kept byte for byte; changing it is
        // a change of the output of its own.
        let mut s = format!(
            "tuned for noise variance {} deg^2, trained on {}-{} s, scored on {}-{} s, mean of {} seeds (MSE measured through YawBank)\n",
            self.noise_var, self.train.0, self.train.1, self.test.0, self.test.1, self.seeds
        );
        s.push_str(&format!(
            "method: {}; hold kept: {} (before: {}); {} evaluations in {:.1} s\n",
            match self.method {
                Method::Search =>
                    "global search (coarse log grid + Nelder-Mead, argmin)".to_string(),
                Method::Exhaustive { points } =>
                    format!("exhaustive log grid, {points} points per gain"),
            },
            hold_name(self.hold),
            hold_name(self.hold_before),
            self.evals(),
            self.elapsed_s
        ));
        for r in &self.runs {
            s.push_str(&format!(
                "  hold {:<6} score (geometric mean of the {TUNED_MSES} tuned training MSEs) {:.4}\n",
                hold_name(r.hold),
                r.score
            ));
            for (half, name) in ["velocity", "acceleration"].iter().enumerate() {
                s.push_str(&format!("    {name:<12} training MSE / evaluations / s:"));
                for (i, name) in NAMES.iter().enumerate() {
                    s.push_str(&format!(
                        " {name} {:.4}/{}/{:.2}",
                        r.cost[half][i], r.evals[half][i], r.secs[half][i]
                    ));
                }
                s.push('\n');
            }
        }
        for (title, paper, tuned, before, after) in [
            (
                "velocity, MSE (deg/s)^2",
                &self.paper.velocity,
                &self.gains.velocity,
                &self.vel_before,
                &self.vel_after,
            ),
            (
                "acceleration (series), MSE (deg/s^2)^2",
                &self.paper.acceleration,
                &self.gains.acceleration,
                &self.acc_before,
                &self.acc_after,
            ),
        ] {
            s.push_str(&format!("\n{title}\n"));
            s.push_str(&format!(
                "{:<5} {:>12} {:>12}  {:<40} {}\n",
                "", "before", "after", "paper gains", "tuned gains"
            ));
            for i in 0..FAMILY_COUNT {
                s.push_str(&format!(
                    "{:<5} {:>12.3} {:>12.3}  {:<40} {}\n",
                    NAMES[i],
                    before[i],
                    after[i],
                    fmt_gains(paper, i),
                    fmt_gains(tuned, i)
                ));
            }
        }
        s
    }

    /// Objective evaluations over every hold and family.
    pub fn evals(&self) -> usize {
        self.runs
            .iter()
            .map(|r| r.evals.iter().flatten().sum::<usize>())
            .sum()
    }

    /// The gains file (TOML, read by `--gains`).
    pub fn to_toml(&self) -> String {
        format!(
            "# nav440 tune: gains for noise variance {} deg^2 (MSE over {}-{} s, {} seeds), hold {}\n# use: nav440 estimate FILE --gains THIS_FILE --hold {}\n{}",
            self.noise_var,
            self.train.0,
            self.train.1,
            self.seeds,
            hold_name(self.hold),
            hold_name(self.hold),
            self.gains.to_toml()
        )
    }

    /// A Rust snippet building the tuned `BankConfig` (paste into the firmware); it sets the
    /// hold the tuner kept.
    pub fn to_rust(&self) -> String {
        let s = self
            .gains
            .to_rust(&format!("noise variance {} deg^2", self.noise_var));
        match self.hold {
            Hold::Linear => s,
            Hold::ZeroOrder => s.replace(
                "    ..BankConfig::PAPER\n",
                "    hold: estimators::Hold::ZeroOrder,\n    ..BankConfig::PAPER\n",
            ),
        }
    }
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

    /// The ILO's `L` bound keeps `h L < 1` (the constructor's condition); both ends of the
    /// leak map to valid `K1` (`K1 = 1 - 1e-7` rounds to `1 - 2^-23` in f32). (That every
    /// family's paper gains lie in its search box is the estimators crate's test.)
    #[test]
    fn the_ilo_search_box_builds_valid_ilos() {
        let (lo, hi) = estimators::IloConfig::search_box(1e-4);
        assert!(hi[1] * 1e-4 < 1.0);
        let g = estimators::presets::ILO1_TABLE2;
        for c in [lo[0], hi[0]] {
            let i = g.with_search_point(&[c, 1.0, 1.0]);
            assert!(i.k1 > 0.0 && i.k1 < 1.0, "{}", i.k1);
            assert!(estimators::Ilo::<f32, 1>::new(&i, 1e-4).is_ok());
        }
    }
}
