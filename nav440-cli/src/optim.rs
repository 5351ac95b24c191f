//! The minimisers behind `nav440 tune` (docs/CALIBRATION.md): a global search (Nelder-Mead of
//! the `argmin` crate, in log coordinates, from several starts) and an exhaustive log grid,
//! the reference the search is tested against.
//!
//! Every gain is positive and searched on a log scale within its valid range `[lo, hi]`
//! (both > 0). The objective is minimised as `ln f` (an MSE spans decades; the simplex
//! tolerance is then relative). Points outside the range, and non-finite values, count as
//! infinitely bad, so the search never leaves the valid range.

use argmin::core::{CostFunction, Error as ArgminError, Executor, State};
use argmin::solver::neldermead::NelderMead;
use std::cell::Cell;

/// How `nav440 tune` minimises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Global search: a coarse log grid (`GRID_COARSE` points per gain) picks the starts,
    /// then Nelder-Mead (restarted until it stops improving) from the best `STARTS` of them
    /// and from the paper preset, then once more from the best point with a finer simplex.
    Search,
    /// Exhaustive log grid of `points` per gain (`points^d` evaluations), the reference.
    Exhaustive {
        /// Grid points per gain (>= 2), log-spaced from `lo` to `hi` inclusive.
        points: usize,
    },
}

/// Coarse grid points per gain used to choose the search's starts.
pub const GRID_COARSE: usize = 4;
/// Nelder-Mead starts taken from the coarse grid (the paper preset is one more).
pub const STARTS: usize = 4;
/// Nelder-Mead restarts from a run's result, at most.
pub const RESTARTS: usize = 4;
/// Nelder-Mead iterations per start, at most.
pub const MAX_ITERS: u64 = 120;
/// Simplex tolerance on `ln f` (standard deviation over the vertices): 0.1 % of the MSE.
pub const SD_TOLERANCE: f64 = 1e-3;

/// A minimiser's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Best point found (gains).
    pub x: Vec<f64>,
    /// Objective there (`f(x)`, not its log); `INFINITY` if no point was valid.
    pub cost: f64,
    /// Objective evaluations made.
    pub evals: usize,
}

/// Objective wrapper: log coordinates, bounds, evaluation count, best point seen.
struct Objective<'a> {
    f: &'a dyn Fn(&[f64]) -> f64,
    lo: Vec<f64>,
    hi: Vec<f64>,
    evals: Cell<usize>,
    best: Cell<f64>,
    best_x: std::cell::RefCell<Vec<f64>>,
}

impl Objective<'_> {
    /// `f` at gains `x` (already within bounds), recorded.
    fn at(&self, x: &[f64]) -> f64 {
        self.evals.set(self.evals.get() + 1);
        let v = (self.f)(x);
        let v = if v.is_finite() { v } else { f64::INFINITY };
        if v < self.best.get() {
            self.best.set(v);
            *self.best_x.borrow_mut() = x.to_vec();
        }
        v
    }

    /// `ln f` at log coordinates `u`; outside the bounds: infinite (not evaluated).
    fn ln_at(&self, u: &[f64]) -> f64 {
        let x: Vec<f64> = u.iter().map(|v| v.exp()).collect();
        let inside = x
            .iter()
            .zip(self.lo.iter().zip(&self.hi))
            .all(|(v, (l, h))| v.is_finite() && *v >= *l && *v <= *h);
        if !inside {
            return f64::INFINITY;
        }
        let v = self.at(&x);
        if v > 0.0 {
            v.ln()
        } else if v == 0.0 {
            f64::NEG_INFINITY
        } else {
            // A negative objective is not an MSE; keep the order anyway.
            -(-v).ln_1p() - 1e3
        }
    }
}

impl CostFunction for &Objective<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, ArgminError> {
        Ok(self.ln_at(u))
    }
}

/// `n` log-spaced values from `lo` to `hi` inclusive (`n >= 2`; `n = 1`: the geometric mean).
pub fn log_space(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let (a, b) = (lo.ln(), hi.ln());
    match n {
        0 => Vec::new(),
        1 => vec![((a + b) / 2.0).exp()],
        _ => (0..n)
            .map(|i| {
                if i + 1 == n {
                    hi
                } else if i == 0 {
                    lo
                } else {
                    (a + (b - a) * i as f64 / (n - 1) as f64).exp()
                }
            })
            .collect(),
    }
}

/// Every point of the log grid, `points` per dimension, with its objective (row-major).
fn grid(obj: &Objective<'_>, points: usize) -> Vec<(Vec<f64>, f64)> {
    let axes: Vec<Vec<f64>> = obj
        .lo
        .iter()
        .zip(&obj.hi)
        .map(|(&l, &h)| log_space(l, h, points))
        .collect();
    let d = axes.len();
    let total = points.pow(d as u32);
    let mut out = Vec::with_capacity(total);
    for mut k in 0..total {
        let mut x = vec![0.0; d];
        for j in (0..d).rev() {
            x[j] = axes[j][k % points];
            k /= points;
        }
        let v = obj.at(&x);
        out.push((x, v));
    }
    out
}

/// Nelder-Mead in log coordinates from `x` (within bounds), initial simplex one step of
/// `step` (natural-log units) along each axis, towards the inside of the range. Returns the
/// best point of the run (gains) and its `ln f`.
fn nelder_mead(obj: &Objective<'_>, x: &[f64], step: &[f64]) -> Option<(Vec<f64>, f64)> {
    let u0: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let mut simplex = vec![u0.clone()];
    for (j, &s) in step.iter().enumerate() {
        let mut u = u0.clone();
        let up = u[j] + s;
        // Step inwards when the upward step leaves the range.
        u[j] = if up <= obj.hi[j].ln() { up } else { u[j] - s };
        simplex.push(u);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(SD_TOLERANCE)
        .ok()?;
    // The objective never fails; an error would only end this run (the best point seen is
    // recorded by the objective itself).
    let r = Executor::new(obj, solver)
        .configure(|s| s.max_iters(MAX_ITERS))
        .run()
        .ok()?;
    let u = r.state().get_best_param()?.clone();
    Some((
        u.iter().map(|v| v.exp()).collect(),
        r.state().get_best_cost(),
    ))
}

/// Nelder-Mead from `x`, restarted from its result with a fresh simplex (the usual remedy
/// for a simplex that collapsed in a curved valley or on a plateau) until a restart gains
/// less than [`SD_TOLERANCE`] in `ln f`, at most [`RESTARTS`] times.
fn nelder_mead_restarted(obj: &Objective<'_>, x: &[f64], step: &[f64]) {
    let mut x = x.to_vec();
    let mut last = f64::INFINITY;
    for _ in 0..=RESTARTS {
        let Some((nx, c)) = nelder_mead(obj, &x, step) else {
            return;
        };
        if c.is_nan() || c >= last - SD_TOLERANCE {
            return;
        }
        x = nx;
        last = c;
    }
}

/// Minimises `f` over the box `[lo, hi]` (all > 0) from the start `x0` (clamped into it).
pub fn minimise(
    method: Method,
    x0: &[f64],
    lo: &[f64],
    hi: &[f64],
    f: &dyn Fn(&[f64]) -> f64,
) -> Outcome {
    let obj = Objective {
        f,
        lo: lo.to_vec(),
        hi: hi.to_vec(),
        evals: Cell::new(0),
        best: Cell::new(f64::INFINITY),
        best_x: std::cell::RefCell::new(Vec::new()),
    };
    let x0: Vec<f64> = x0
        .iter()
        .zip(lo.iter().zip(hi))
        .map(|(v, (l, h))| v.clamp(*l, *h))
        .collect();
    match method {
        Method::Exhaustive { points } => {
            grid(&obj, points.max(2));
        }
        Method::Search => {
            obj.at(&x0);
            let mut pts = grid(&obj, GRID_COARSE);
            pts.sort_by(|a, b| a.1.total_cmp(&b.1));
            // Initial simplex: a quarter of the coarse grid's spacing per axis.
            let step: Vec<f64> = lo
                .iter()
                .zip(hi)
                .map(|(l, h)| (h / l).ln() / (GRID_COARSE - 1) as f64 / 2.0)
                .collect();
            let mut starts = vec![x0.clone()];
            starts.extend(
                pts.into_iter()
                    .filter(|p| p.1.is_finite())
                    .take(STARTS)
                    .map(|p| p.0),
            );
            for s in &starts {
                nelder_mead_restarted(&obj, s, &step);
            }
            // Polish the best point with a smaller simplex.
            let best = obj.best_x.borrow().clone();
            if !best.is_empty() {
                let fine: Vec<f64> = step.iter().map(|s| s / 8.0).collect();
                nelder_mead_restarted(&obj, &best, &fine);
            }
        }
    }
    let x = obj.best_x.borrow().clone();
    Outcome {
        x: if x.is_empty() { x0 } else { x },
        cost: obj.best.get(),
        evals: obj.evals.get(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_space_ends_exactly_at_the_bounds() {
        let v = log_space(1e-3, 10.0, 5);
        assert_eq!(v.len(), 5);
        assert_eq!(v[0], 1e-3);
        assert_eq!(v[4], 10.0);
        assert!((v[1] - 1e-2).abs() < 1e-15);
        assert!((v[2] - 1e-1).abs() < 1e-14);
    }

    /// The search finds the minimum of a function with a decoy: a local minimum at the
    /// start and a deeper global one two decades away in each gain.
    #[test]
    fn search_finds_the_global_minimum_and_stays_in_bounds() {
        let f = |x: &[f64]| {
            let a = (x[0] / 50.0).ln().powi(2) + (x[1] / 0.02).ln().powi(2);
            let b = (x[0] / 1.0).ln().powi(2) + (x[1] / 1.0).ln().powi(2);
            (1.0 + 0.25 * a).min(2.0 + 0.1 * b)
        };
        let o = minimise(Method::Search, &[1.0, 1.0], &[1e-3, 1e-4], &[1e4, 10.0], &f);
        assert!(
            (o.x[0] / 50.0 - 1.0).abs() < 0.1 && (o.x[1] / 0.02 - 1.0).abs() < 0.1,
            "{o:?}"
        );
        // The simplex stops at a spread of 0.1 % in the objective.
        assert!((o.cost - 1.0).abs() < 2e-3, "{o:?}");
        assert!(o.evals > 16 && o.evals < 2000, "{o:?}");
        // Bounds: the unconstrained minimum (x = 2) lies outside [0.05, 1].
        let o = minimise(Method::Search, &[0.5], &[0.05], &[1.0], &|x: &[f64]| {
            1.0 + (x[0] - 2.0).powi(2)
        });
        assert!(o.x[0] <= 1.0 && o.x[0] > 0.99, "{o:?}");
    }

    #[test]
    fn exhaustive_grid_evaluates_every_point_and_keeps_the_best() {
        let f = |x: &[f64]| (x[0].log10() - 1.0).powi(2) + (x[1].log10() + 1.0).powi(2) + 1.0;
        let o = minimise(
            Method::Exhaustive { points: 5 },
            &[1.0, 1.0],
            &[1e-2, 1e-3],
            &[1e2, 1e1],
            &f,
        );
        assert_eq!(o.evals, 25);
        // Grid points: 1e-2, 1e-1, 1, 1e1, 1e2 and 1e-3, 1e-2, 1e-1, 1, 1e1.
        assert!(
            (o.x[0] - 10.0).abs() < 1e-9 && (o.x[1] - 0.1).abs() < 1e-12,
            "{o:?}"
        );
        assert!((o.cost - 1.0).abs() < 1e-12);
        // Invalid everywhere: infinite cost, the start returned.
        let o = minimise(Method::Search, &[3.0], &[1.0], &[10.0], &|_: &[f64]| {
            f64::NAN
        });
        assert_eq!(o.cost, f64::INFINITY);
        assert_eq!(o.x, vec![3.0]);
    }
}
