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
//! "before" and "after" MSE printed are then measured through the whole `YawBank` with the
//! paper presets and with the tuned gains file, i.e. exactly what `nav440 estimate --gains`
//! computes.

use crate::error::{Error, Result};
use crate::gains::{FamilyGains, GainsFile};
use crate::optim::{self, Method};
use crate::paper::{ave_on_rate, row_mse, steps_between, REFERENCE_AVE};
use crate::progress::Progress;
use crate::replay::{self, EstimateOptions, Noise, Sample};
use estimators::{
    Ad, Ave, AveConfig, BankConfig, DeltaMode, Ed, EdConfig, Estimator, Hold, Ilo, IloConfig,
    Kalman, KalmanConfig, Law, SampleAdapter, Series, Stateful,
};
use std::time::Instant;

// Column names in bank order.
use crate::paper::COLUMNS as NAMES;

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
    pub cost: [[f64; 7]; 2],
    /// Objective evaluations per family.
    pub evals: [[usize; 7]; 2],
    /// Wall time per family, s (the two halves run in parallel).
    pub secs: [[f64; 7]; 2],
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
    pub vel_before: [f64; 7],
    /// Velocity MSE with the tuned gains.
    pub vel_after: [f64; 7],
    /// Acceleration MSE with the paper presets, (deg/s^2)^2.
    pub acc_before: [f64; 7],
    /// Acceleration MSE with the tuned gains.
    pub acc_after: [f64; 7],
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
    /// The objective of the estimator `make` builds (velocity half) or of two of them in
    /// series (acceleration half); `i`: the family's column (bank order, 0 to 5).
    fn family<L: Law<Num = f32>>(
        &self,
        i: usize,
        make: impl Fn() -> Option<Stateful<L>>,
        acc: bool,
    ) -> f64;
    /// The objective of a Kalman tracker with noise `q`, `r` (its `dt`: each problem's
    /// nominal sample period); column 6.
    fn kf(&self, q: f32, r: f32, acc: bool) -> f64;
    /// A family's fit is done.
    fn fitted(&self) {}
}

impl Eval for Problem<'_> {
    fn step_s(&self) -> f32 {
        self.opts.step_s
    }
    fn family<L: Law<Num = f32>>(
        &self,
        _i: usize,
        make: impl Fn() -> Option<Stateful<L>>,
        acc: bool,
    ) -> f64 {
        if let Some(p) = self.progress {
            p.evaluation();
        }
        self.eval_family(make, acc)
    }
    fn kf(&self, q: f32, r: f32, acc: bool) -> f64 {
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
    baselines: Option<&'a [[[f64; 7]; 2]]>,
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
    fn family<L: Law<Num = f32>>(
        &self,
        i: usize,
        make: impl Fn() -> Option<Stateful<L>>,
        acc: bool,
    ) -> f64 {
        self.combine(i, acc, |p| p.eval_family(&make, acc))
    }
    fn kf(&self, q: f32, r: f32, acc: bool) -> f64 {
        self.combine(6, acc, |p| p.kf(q, r, acc))
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

    /// [`Self::eval`] of what `make` builds (velocity half) or, for the acceleration half,
    /// of two of them in series (both stages with the same gains, as in the bank).
    fn eval_family<L: Law<Num = f32>>(
        &self,
        make: impl Fn() -> Option<Stateful<L>>,
        acc: bool,
    ) -> f64 {
        if acc {
            self.eval(&|| Some(Series::of(&make()?, &make()?)), true)
        } else {
            self.eval(&make, false)
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

/// Valid search range `(lo, hi)` of each gain of family `i` (bank order: AVE, ILO1-3, AD, ED,
/// KF) for the step `h_s`, s: AVE (k, gamma1); ILO (`1 - K1`, L, K2): `K1` is searched as its
/// leak `1 - K1` on a log scale, from 1e-7 (`K1 = 1` to f32 precision) to 0.95 (`K1 = 0.05`),
/// because the best `K1` lie within 1e-3 of 1 (a leak of a few 1/s at `tau = h`), and
/// `h L < 1` as the constructor demands; AD (T); ED (lambda, alpha); KF (q, with r kept: only
/// q/r matters for the steady-state gain). The bounds span the paper's presets by two
/// decades or more each side (AVE k and ED lambda down to 0.1: the tuned values at low noise
/// reach 10).
pub fn ranges(i: usize, h_s: f64) -> (Vec<f64>, Vec<f64>) {
    match i {
        0 => (vec![0.1, 10.0], vec![1e5, 1e8]),
        1..=3 => (vec![1e-7, 0.1, 1e-3], vec![0.95, 0.99 / h_s, 1e4]),
        4 => (vec![1e-4], vec![1.0]),
        5 => (vec![0.1, 10.0], vec![1e5, 1e6]),
        _ => (vec![1.0], vec![1e12]),
    }
}

/// One family's minimisation: result and its cost.
struct Fit {
    x: Vec<f64>,
    cost: f64,
    evals: usize,
    secs: f64,
}

fn fit(method: Method, i: usize, h_s: f64, x0: &[f64], f: &dyn Fn(&[f64]) -> f64) -> Fit {
    let t = Instant::now();
    let (lo, hi) = ranges(i, h_s);
    let o = optim::minimise(method, x0, &lo, &hi, f);
    Fit {
        x: o.x,
        cost: o.cost,
        evals: o.evals,
        secs: t.elapsed().as_secs_f64(),
    }
}

/// AVE gains `(k, gamma1)` with the `deltahat` law `delta` (the start's: the paper's for
/// `nav440 tune`, the leaky one for the shipped preset).
fn ave(g: &[f64], delta: DeltaMode) -> AveConfig {
    AveConfig {
        k: g[0] as f32,
        gamma1: g[1] as f32,
        delta,
    }
}
/// ILO gains from the search coordinates `(1 - K1, L, K2)`.
fn ilo(g: &[f64]) -> IloConfig {
    IloConfig {
        k1: (1.0 - g[0]) as f32,
        l: g[1] as f32,
        k2: g[2] as f32,
    }
}
fn ed(g: &[f64]) -> EdConfig {
    EdConfig {
        lambda: g[0] as f32,
        alpha: g[1] as f32,
    }
}

/// Tunes one half of the bank (velocity or acceleration) starting from `start`; returns the
/// gains and, per family, (tuned MSE, evaluations, seconds).
fn tune_family(
    p: &impl Eval,
    start: &FamilyGains,
    acc: bool,
    method: Method,
) -> (FamilyGains, [(f64, usize, f64); 7]) {
    let h = p.step_s();
    let hs = f64::from(h);
    let mut out = *start;
    let mut stats = [(f64::INFINITY, 0, 0.0); 7];
    let mut note = |i: usize, r: &Fit| {
        stats[i] = (r.cost, r.evals, r.secs);
        p.fitted();
    };
    if let Some(a) = start.ave {
        let f = |g: &[f64]| p.family(0, || Ave::<f32>::new(&ave(g, a.delta), h).ok(), acc);
        let r = fit(method, 0, hs, &[f64::from(a.k), f64::from(a.gamma1)], &f);
        note(0, &r);
        out.ave = Some(AveConfig {
            k: r.x[0] as f32,
            gamma1: r.x[1] as f32,
            delta: a.delta,
        });
    }
    let ilos = [start.ilo1, start.ilo2, start.ilo3];
    let mut tuned = [None; 3];
    for (j, (slot, g0)) in tuned.iter_mut().zip(ilos).enumerate() {
        let Some(g0) = g0 else { continue };
        let f = |g: &[f64]| p.family(1 + j, || Ilo::<f32, 1>::new(&ilo(g), h).ok(), acc);
        let x0 = [1.0 - f64::from(g0.k1), f64::from(g0.l), f64::from(g0.k2)];
        let r = fit(method, 1 + j, hs, &x0, &f);
        note(1 + j, &r);
        *slot = Some(ilo(&r.x));
    }
    [out.ilo1, out.ilo2, out.ilo3] = tuned;
    if let Some(a) = start.ad {
        let f = |g: &[f64]| {
            let t = g[0] as f32;
            p.family(4, || Ad::<f32>::new(t, h).ok(), acc)
        };
        let r = fit(method, 4, hs, &[f64::from(a.t)], &f);
        note(4, &r);
        out.ad = Some(estimators::AdConfig { t: r.x[0] as f32 });
    }
    if let Some(e) = start.ed {
        let f = |g: &[f64]| p.family(5, || Ed::<f32>::new(&ed(g), h).ok(), acc);
        let r = fit(
            method,
            5,
            hs,
            &[f64::from(e.lambda), f64::from(e.alpha)],
            &f,
        );
        note(5, &r);
        out.ed = Some(ed(&r.x));
    }
    if let Some(k) = start.kf {
        // Only q/r matters for the steady-state gain: r is kept, q is searched.
        let f = |g: &[f64]| p.kf(g[0] as f32, k.r, acc);
        let r = fit(method, 6, hs, &[f64::from(k.q)], &f);
        note(6, &r);
        out.kf = Some(estimators::KalmanNoise {
            q: r.x[0] as f32,
            r: k.r,
        });
    }
    (out, stats)
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
            cost: [[0.0; 7]; 2],
            evals: [[0; 7]; 2],
            secs: [[0.0; 7]; 2],
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
        run.score = (log_sum / 14.0).exp();
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
) -> Result<([f64; 7], [f64; 7])> {
    let axis = opts.axis();
    let mut v = [0.0; 7];
    let mut a = [0.0; 7];
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
        for i in 0..7 {
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
) -> Result<([f64; 7], [f64; 7])> {
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
) -> Result<(GainsFile, [[f64; 7]; 2], String)> {
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
    let score = |g: &GainsFile| -> Result<[[(usize, f64); 7]; 2]> {
        let cfg = g.apply(*base);
        let mut out = [[(0usize, 0.0f64); 7]; 2];
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
                for i in 0..7 {
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
        for i in (0..7).filter(|&i| infeasible[half][i] >= 1.0) {
            m.set_column(i, h);
        }
    }
    let (s1, s2) = (score(&gains)?, score(&merged)?);
    let mut report = String::new();
    for half in 0..2 {
        for i in (0..7).filter(|&i| infeasible[half][i] >= 1.0) {
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
) -> Result<(GainsFile, [[f64; 7]; 2])> {
    let v0 = start.velocity.only(|i| which(false, i));
    let a0 = start.acceleration.only(|i| which(true, i));
    let (velocity, acceleration) = std::thread::scope(|s| {
        let v = s.spawn(|| tune_family(set, &v0, false, method));
        let a = tune_family(set, &a0, true, method);
        (v.join(), a)
    });
    let velocity = velocity.map_err(|_| Error::Other("tuning thread panicked".into()))?;
    let mut cost = [[0.0; 7]; 2];
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
    let mut at = vec![vec![[0.0f64; 7]; levels.len()]; levels.len()];
    for (i, g) in tuned.iter().enumerate() {
        for (j, &v) in levels.iter().enumerate() {
            let seeds = 1..=spec.seeds.max(1);
            at[i][j] = bank_mse_with(samples, opts, &acc_ref, config(g), v, seeds, spec.train)?.0;
        }
    }
    // `source[j][f]`: the level whose tuned gains level `j` runs for observer family `f`.
    let mut source: Vec<[usize; OBSERVERS.len()]> =
        (0..levels.len()).map(|j| [j; OBSERVERS.len()]).collect();
    let before = tuned.clone();
    for (j, &v) in levels.iter().enumerate() {
        for (f, &(col, name)) in OBSERVERS.iter().enumerate() {
            let best = (0..levels.len())
                .min_by(|&a, &b| at[a][j][col].total_cmp(&at[b][j][col]))
                .unwrap_or(j);
            if best == j || at[best][j][col] >= at[j][j][col] {
                continue;
            }
            source[j][f] = best;
            let (from, to) = (&before[best].velocity, &mut tuned[j].velocity);
            match col {
                0 => to.ave = from.ave,
                1 => to.ilo1 = from.ilo1,
                2 => to.ilo2 = from.ilo2,
                3 => to.ilo3 = from.ilo3,
                _ => to.ed = from.ed,
            }
            text.push_str(&format!(
                "level {v} deg^2: {name} velocity gains of level {} deg^2 (MSE {:.4} instead of {:.4} at {v} deg^2)\n",
                levels[best], at[best][j][col], at[j][j][col]
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
        let point = |f: usize| {
            let ((sa, sb), col) = ((source[i][f], source[i + 1][f]), OBSERVERS[f].0);
            let m = [
                at[sa][i][col],
                at[sa][i + 1][col],
                at[sb][i][col],
                at[sb][i + 1][col],
            ];
            crossover(m, a, b) as f32
        };
        let sw = crate::gains::SwitchUpFile {
            ave: point(0),
            ilo1: point(1),
            ilo2: point(2),
            ilo3: point(3),
            ed: point(4),
        };
        level[i].switch_up = Some(sw);
        text.push_str(&format!(
            "switch up from level {a} to {b} deg^2 (where each family takes the next level's gains: where the two levels' MSEs cross if they differ by more than {SWITCH_MATTERS}x at the midpoint, else the midpoint): AVE {}, ILO1 {}, ILO2 {}, ILO3 {}, ED {}\n",
            sw.ave, sw.ilo1, sw.ilo2, sw.ilo3, sw.ed
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

/// The velocity observer families a schedule gives per-level gains and switch points:
/// (column of the bank's velocity MSE, name).
const OBSERVERS: [(usize, &str); 5] =
    [(0, "AVE"), (1, "ILO1"), (2, "ILO2"), (3, "ILO3"), (5, "ED")];

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
        let mut bank: estimators::YawBank<f32> = nav440_pipeline::axis_bank(axis, cfg)
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

fn fmt_gains(f: &FamilyGains, i: usize) -> String {
    match i {
        0 => f.ave.map(|g| format!("k={} gamma1={}", g.k, g.gamma1)),
        1..=3 => {
            [f.ilo1, f.ilo2, f.ilo3][i - 1].map(|g| format!("K1={} L={} K2={}", g.k1, g.l, g.k2))
        }
        4 => f.ad.map(|g| format!("T={}", g.t)),
        5 => {
            f.ed.map(|g| format!("lambda={} alpha={}", g.lambda, g.alpha))
        }
        _ => f.kf.map(|g| format!("q={} r={}", g.q, g.r)),
    }
    .unwrap_or_else(|| "-".into())
}

impl TuneResult {
    /// The printed report.
    pub fn to_text(&self) -> String {
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
                "  hold {:<6} score (geometric mean of the 14 tuned training MSEs) {:.4}\n",
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
            for i in 0..7 {
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

    #[test]
    fn every_preset_lies_inside_its_search_range() {
        let g = GainsFile::from_bank(&BankConfig::PAPER);
        for half in [g.velocity, g.acceleration] {
            let ave = half.ave.unwrap();
            let kf = half.kf.unwrap();
            let ed = half.ed.unwrap();
            let mut pts = vec![
                (0, vec![ave.k, ave.gamma1]),
                (4, vec![half.ad.unwrap().t]),
                (5, vec![ed.lambda, ed.alpha]),
                (6, vec![kf.q]),
            ];
            for (j, i) in [half.ilo1, half.ilo2, half.ilo3].into_iter().enumerate() {
                let i = i.unwrap();
                // Searched as 1 - K1; K1 = 1 is the range's end (1e-7) to f32 precision.
                pts.push((1 + j, vec![(1.0 - i.k1).max(1e-7), i.l, i.k2]));
            }
            for (i, x) in pts {
                let (lo, hi) = ranges(i, 1e-4);
                for ((v, l), h) in x.iter().zip(&lo).zip(&hi) {
                    let v = f64::from(*v);
                    assert!(v >= *l && v <= *h, "family {i}: {v} not in [{l}, {h}]");
                }
            }
        }
        // The ILO's L bound keeps h L < 1 (the constructor's condition); both ends of the
        // leak map to valid K1 (K1 = 1 - 1e-7 rounds to 1 - 2^-23 in f32).
        let (lo, hi) = ranges(1, 1e-4);
        assert!(hi[1] * 1e-4 < 1.0);
        for c in [lo[0], hi[0]] {
            let k1 = (1.0 - c) as f32;
            assert!(k1 > 0.0 && k1 < 1.0, "{k1}");
            assert!(estimators::Ilo::<f32, 1>::new(&ilo(&[c, 1.0, 1.0]), 1e-4).is_ok());
        }
    }
}
