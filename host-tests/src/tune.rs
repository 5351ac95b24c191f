//! `nav440 tune`: per-capture, per-noise-level calibration of each estimator family's gains
//! (the paper: "gains must be re-calibrated to the noise level").
//!
//! Method: for each family (AVE; ILO1, ILO2, ILO3 from their presets; AD; ED; KF) and each half
//! of the bank (velocity against the measured rate; series acceleration against the AVE on the
//! measured rate), a multiplicative coordinate search on the MSE over `0..window` averaged over
//! `seeds` noise seeds, starting from the paper presets: each gain is tried at `x * f` and
//! `x / f` (f = 4, 2, 1.41, 1.19, 1.09), the best improvement is kept, the factor shrinks when
//! no coordinate improves. Candidates the constructors reject (e.g. `h * L >= 1`,
//! `K1 > 1`) or that diverge count as infinite MSE. The single estimators run behind
//! `estimators::SampleAdapter` (unwrapped noisy yaw, same hold and step as the bank); the
//! "before" and "after" MSE printed are then measured through the whole `YawBank` with the
//! paper presets and with the tuned gains file, i.e. exactly what `nav440 estimate --gains`
//! computes.

use crate::error::{Error, Result};
use crate::gains::{FamilyGains, GainsFile};
use crate::paper::{ave_on_rate, mse, row_mse, steps_between, REFERENCE_AVE};
use crate::replay::{self, EstimateOptions, Noise, Sample};
use estimators::{
    Ad, Ave, AveConfig, BankConfig, DeltaMode, Ed, EdConfig, Estimator, Ilo, IloConfig, Kalman,
    KalmanConfig, Law, SampleAdapter, Series, Stateful,
};

/// Column names in bank order.
const NAMES: [&str; 7] = ["AVE", "ILO1", "ILO2", "ILO3", "AD", "ED", "KF"];

/// What the tuner found.
#[derive(Clone, Debug)]
pub struct TuneResult {
    /// Noise variance, deg^2.
    pub noise_var: f64,
    /// Seeds averaged.
    pub seeds: u64,
    /// MSE window, s.
    pub window_s: f64,
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
    window_s: f64,
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
            let m = mse(&t, &out, reference, self.window_s);
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
            let m = mse(&t, &out, reference, self.window_s);
            if !m.is_finite() {
                return f64::INFINITY;
            }
            total += m;
        }
        total / self.ys.len() as f64
    }
}

/// Multiplicative coordinate search from `x0` (all entries > 0) within `[lo, hi]`.
fn coord_search(x0: &[f64], lo: &[f64], hi: &[f64], f: &dyn Fn(&[f64]) -> f64) -> Vec<f64> {
    let mut x = x0.to_vec();
    let mut best = f(&x);
    for factor in [4.0, 2.0, std::f64::consts::SQRT_2, 1.19, 1.09] {
        // Repeat at this factor while some coordinate improves (bounded).
        for _ in 0..6 {
            let mut improved = false;
            for i in 0..x.len() {
                for cand in [x[i] * factor, x[i] / factor] {
                    let c = cand.clamp(lo[i], hi[i]);
                    if c == x[i] {
                        continue;
                    }
                    let mut y = x.clone();
                    y[i] = c;
                    let v = f(&y);
                    if v < best {
                        best = v;
                        x = y;
                        improved = true;
                    }
                }
            }
            if !improved {
                break;
            }
        }
    }
    x
}

fn ave(g: &[f64]) -> AveConfig {
    AveConfig {
        k: g[0] as f32,
        gamma1: g[1] as f32,
        delta: DeltaMode::Paper,
    }
}
fn ilo(g: &[f64]) -> IloConfig {
    IloConfig {
        k1: g[0] as f32,
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

/// Tunes one half of the bank (velocity or acceleration) starting from `start`.
fn tune_family(p: &Problem<'_>, start: &FamilyGains, acc: bool) -> FamilyGains {
    let h = p.opts.step_s;
    let mut out = *start;
    if let Some(a) = start.ave {
        let f = |g: &[f64]| p.eval_family(|| Ave::<f32>::new(&ave(g), h).ok(), acc);
        let x = coord_search(
            &[f64::from(a.k), f64::from(a.gamma1)],
            &[1e-3, 1e-3],
            &[1e9, 1e12],
            &f,
        );
        out.ave = Some(AveConfig {
            k: x[0] as f32,
            gamma1: x[1] as f32,
            delta: a.delta,
        });
    }
    let ilos = [start.ilo1, start.ilo2, start.ilo3];
    let mut tuned = [None; 3];
    for (slot, g0) in tuned.iter_mut().zip(ilos) {
        let Some(g0) = g0 else { continue };
        let f = |g: &[f64]| p.eval_family(|| Ilo::<f32, 1>::new(&ilo(g), h).ok(), acc);
        let x = coord_search(
            &[f64::from(g0.k1), f64::from(g0.l), f64::from(g0.k2)],
            &[0.05, 1e-3, 1e-4],
            &[1.0, 1e6, 1e6],
            &f,
        );
        *slot = Some(IloConfig {
            k1: x[0] as f32,
            l: x[1] as f32,
            k2: x[2] as f32,
        });
    }
    [out.ilo1, out.ilo2, out.ilo3] = tuned;
    if let Some(a) = start.ad {
        let f = |g: &[f64]| {
            let t = g[0] as f32;
            p.eval_family(|| Ad::<f32>::new(t, h).ok(), acc)
        };
        let x = coord_search(&[f64::from(a.t)], &[1e-4], &[10.0], &f);
        out.ad = Some(estimators::AdConfig { t: x[0] as f32 });
    }
    if let Some(e) = start.ed {
        let f = |g: &[f64]| p.eval_family(|| Ed::<f32>::new(&ed(g), h).ok(), acc);
        let x = coord_search(
            &[f64::from(e.lambda), f64::from(e.alpha)],
            &[1e-2, 1e-2],
            &[1e7, 1e9],
            &f,
        );
        out.ed = Some(EdConfig {
            lambda: x[0] as f32,
            alpha: x[1] as f32,
        });
    }
    if let Some(k) = start.kf {
        let dt = p.sample_period_s;
        // Only q/r matters for the steady-state gain: r is kept, q is searched.
        let f = |g: &[f64]| {
            p.eval_kf(
                &KalmanConfig {
                    dt,
                    q: g[0] as f32,
                    r: k.r,
                },
                acc,
            )
        };
        let x = coord_search(&[f64::from(k.q)], &[1e-6], &[1e18], &f);
        out.kf = Some(estimators::KalmanNoise {
            q: x[0] as f32,
            r: k.r,
        });
    }
    out
}

/// Runs the tuner. The velocity and acceleration halves run on 2 threads.
pub fn tune(
    samples: &[Sample],
    opts: &EstimateOptions,
    noise_var: f64,
    seeds: u64,
    window_s: f64,
) -> Result<TuneResult> {
    crate::paper::check_window(window_s)?;
    let opts = &opts.paper_law();
    let base = opts.bank_config_for(samples);
    let paper = GainsFile::from_bank(&base);
    let axis = opts.axis();
    let ys = (1..=seeds)
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
        .collect::<Result<Vec<_>>>()?;
    let problem = Problem {
        samples,
        ys,
        // The Euler-kinematics rate; NaN (left out of every MSE) near gimbal lock.
        vel_ref: samples
            .iter()
            .map(|s| s.reference(axis).unwrap_or(f32::NAN))
            .collect(),
        acc_ref: ave_on_rate(samples, &REFERENCE_AVE, opts)?,
        opts,
        max_gap_s: base.max_gap_s(),
        sample_period_s: base.sample_period_s,
        window_s,
    };
    let (velocity, acceleration) = std::thread::scope(|s| {
        let v = s.spawn(|| tune_family(&problem, &paper.velocity, false));
        let a = tune_family(&problem, &paper.acceleration, true);
        (v.join(), a)
    });
    let velocity = velocity.map_err(|_| Error::Other("tuning thread panicked".into()))?;
    let gains = GainsFile {
        velocity,
        acceleration,
    };
    let bank_mse = |cfg: BankConfig| -> Result<([f64; 7], [f64; 7])> {
        let mut v = [0.0; 7];
        let mut a = [0.0; 7];
        for seed in 1..=seeds {
            let mut o = opts.clone();
            o.config = Some(cfg);
            o.noise = Some(Noise {
                var: noise_var,
                seed,
            });
            let (rows, _) = replay::estimate(samples, &o)?;
            let (vv, aa) = row_mse(axis, &rows, samples, &problem.acc_ref, window_s);
            for i in 0..7 {
                v[i] += vv[i] / seeds as f64;
                a[i] += aa[i] / seeds as f64;
            }
        }
        Ok((v, a))
    };
    let (vel_before, acc_before) = bank_mse(base)?;
    let (vel_after, acc_after) = bank_mse(gains.apply(base))?;
    Ok(TuneResult {
        noise_var,
        seeds,
        window_s,
        gains,
        paper,
        vel_before,
        vel_after,
        acc_before,
        acc_after,
    })
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
            "tuned for noise variance {} deg^2, MSE over 0-{} s, mean of {} seeds (MSE measured through YawBank)\n",
            self.noise_var, self.window_s, self.seeds
        );
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

    /// The gains file (TOML, read by `--gains`).
    pub fn to_toml(&self) -> String {
        format!(
            "# nav440 tune: gains for noise variance {} deg^2 (MSE over 0-{} s, {} seeds)\n# use: nav440 estimate FILE --gains THIS_FILE\n{}",
            self.noise_var,
            self.window_s,
            self.seeds,
            self.gains.to_toml()
        )
    }

    /// A Rust snippet building the tuned `BankConfig` (paste into the firmware).
    pub fn to_rust(&self) -> String {
        self.gains
            .to_rust(&format!("noise variance {} deg^2", self.noise_var))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinate_search_finds_the_minimum_of_a_log_quadratic() {
        // Minimum at (50, 0.02); start two decades away.
        let f = |x: &[f64]| (x[0] / 50.0).ln().powi(2) + (x[1] / 0.02).ln().powi(2);
        let x = coord_search(&[1.0, 1.0], &[1e-6, 1e-6], &[1e6, 1e6], &f);
        assert!(
            (x[0] / 50.0 - 1.0).abs() < 0.05 && (x[1] / 0.02 - 1.0).abs() < 0.05,
            "{x:?}"
        );
        // Bounds are respected.
        let x = coord_search(&[0.5], &[0.05], &[1.0], &|x: &[f64]| -x[0]);
        assert_eq!(x, vec![1.0]);
    }
}
