//! What `nav440 tune` searches in each family's gains: the coordinates, their box, the
//! estimator a candidate builds ([`Search`], implemented here for the estimators crate's
//! configuration types), and the families it tunes ([`for_each_searched_family`]). The gains
//! file's check ([`crate::gains::FamilyGains::check`]) builds each table's law the same way.

use estimators::{
    AdConfig, AdFamily, AdParams, AveConfig, AveFamily, AveParams, ConfigError, EdConfig, EdFamily,
    EdParams, EdScheme, Family, Gains, IloConfig, IloFamily, IloParams, KalmanNoise, KfFamily, Law,
};

/// A family's gains as the tuner sees them: the gains it searches as coordinates, the box it
/// searches them in, and the estimator a candidate builds.
pub trait Search: Gains {
    /// The gains the tuner searches, as coordinates (in the order of [`Self::search_box`]).
    fn search_point(&self) -> Vec<f64>;

    /// These gains with the searched ones set from the coordinates `x` (the others, e.g. the
    /// AVE's `deltahat` law, kept).
    fn with_search_point(&self, x: &[f64]) -> Self;

    /// The search range `(lowest, highest)` of each coordinate of [`Self::search_point`] at
    /// the step `h_s` (s): the gains the law accepts at that step, spanning the paper's by
    /// two decades or more each side.
    fn search_box(h_s: f64) -> (Vec<f64>, Vec<f64>);

    /// Hands the estimator these gains build at the step `h` (s) to `scorer`, which scores it
    /// (the tuner's objective); the error of the law's constructor if they do not build one.
    fn score<S: Scorer>(&self, h: f32, scorer: &S) -> Result<S::Score, ConfigError>;

    /// The gains on one line, `name=value` separated by spaces (e.g. `k=500 gamma1=20000`),
    /// as the tuner's report prints them.
    fn describe(&self) -> String;
}

/// What scores a family's candidate gains ([`Search::score`]): the tuner's objective, given
/// the estimator the gains build.
pub trait Scorer {
    /// The score (e.g. a mean square error).
    type Score;

    /// Scores a law stepped at `h` between samples: its output is the velocity estimate; the
    /// scorer may run two of it in series for the acceleration (as the bank does).
    fn law<L: Law<Num = f32>>(&self, law: L) -> Self::Score;

    /// Scores a Kalman tracker with the noise `noise` (run once per sample, the bank's
    /// `KalmanParams`; velocity or acceleration output as the scorer needs).
    fn tracker(&self, noise: KalmanNoise) -> Self::Score;
}

/// Something done for every family the tuner searches: [`for_each_searched_family`] calls
/// [`SearchVisitor::family`] once per family, in column order.
pub trait SearchVisitor {
    /// Called with the family `F` and its column (0-based, the order of
    /// [`estimators::FAMILIES`]).
    fn family<F: Family>(&mut self, column: usize)
    where
        F::Gains: Search;
}

/// Calls `visitor.family::<F>(column)` for each family of the paper bank, in column order:
/// [`estimators::for_each_family`]'s list, with the bound `F::Gains: Search` (a test checks
/// that the two lists are the same).
pub fn for_each_searched_family<V: SearchVisitor>(visitor: &mut V) {
    visitor.family::<AveFamily>(0);
    visitor.family::<IloFamily<0>>(1);
    visitor.family::<IloFamily<1>>(2);
    visitor.family::<IloFamily<2>>(3);
    visitor.family::<AdFamily>(4);
    visitor.family::<EdFamily>(5);
    visitor.family::<KfFamily>(6);
}

/// Coordinate `i` of `x` as f32, or `current` if `x` is shorter.
fn coordinate(x: &[f64], i: usize, current: f32) -> f32 {
    x.get(i).map_or(current, |&v| v as f32)
}

impl Search for AveConfig {
    /// `(k, gamma1)`; the `deltahat` law is not searched.
    fn search_point(&self) -> Vec<f64> {
        vec![f64::from(self.k), f64::from(self.gamma1)]
    }

    fn with_search_point(&self, x: &[f64]) -> Self {
        AveConfig {
            k: coordinate(x, 0, self.k),
            gamma1: coordinate(x, 1, self.gamma1),
            delta: self.delta,
        }
    }

    /// `k` in `[0.1, 1e5]` 1/s (tuned at low noise it reaches 10), `gamma1` in `[10, 1e8]`
    /// 1/s^2; `AveParams::new` refuses what the step does not resolve.
    fn search_box(_h_s: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![0.1, 10.0], vec![1e5, 1e8])
    }

    fn score<S: Scorer>(&self, h: f32, scorer: &S) -> Result<S::Score, ConfigError> {
        Ok(scorer.law(AveParams::<f32>::new(self, h)?))
    }

    fn describe(&self) -> String {
        format!("k={} gamma1={}", self.k, self.gamma1)
    }
}

impl Search for IloConfig {
    /// `(1 - K1, L, K2)`: `K1` is searched as its leak on a log scale, because the best
    /// `K1` lie within 1e-3 of 1 (a leak of a few 1/s at `tau = h`).
    fn search_point(&self) -> Vec<f64> {
        vec![
            1.0 - f64::from(self.k1),
            f64::from(self.l),
            f64::from(self.k2),
        ]
    }

    fn with_search_point(&self, x: &[f64]) -> Self {
        IloConfig {
            k1: x.first().map_or(self.k1, |&leak| (1.0 - leak) as f32),
            l: coordinate(x, 1, self.l),
            k2: coordinate(x, 2, self.k2),
        }
    }

    /// The leak `1 - K1` in `[1e-7, 0.95]` (`K1 = 1` to f32 precision, to `K1 = 0.05`), `L`
    /// in `[0.1, 0.99 / h]` 1/s (`h L < 1`, as `IloParams::new` demands), `K2` in
    /// `[1e-3, 1e4]`.
    fn search_box(h_s: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![1e-7, 0.1, 1e-3], vec![0.95, 0.99 / h_s, 1e4])
    }

    fn score<S: Scorer>(&self, h: f32, scorer: &S) -> Result<S::Score, ConfigError> {
        Ok(scorer.law(IloParams::<f32, 1>::new(self, h)?))
    }

    fn describe(&self) -> String {
        format!("K1={} L={} K2={}", self.k1, self.l, self.k2)
    }
}

impl Search for AdConfig {
    /// `(T)`.
    fn search_point(&self) -> Vec<f64> {
        vec![f64::from(self.t)]
    }

    fn with_search_point(&self, x: &[f64]) -> Self {
        AdConfig {
            t: coordinate(x, 0, self.t),
        }
    }

    /// `T` in `[1e-4, 1]` s.
    fn search_box(_h_s: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![1e-4], vec![1.0])
    }

    fn score<S: Scorer>(&self, h: f32, scorer: &S) -> Result<S::Score, ConfigError> {
        Ok(scorer.law(AdParams::<f32>::new(self.t, h)?))
    }

    fn describe(&self) -> String {
        format!("T={}", self.t)
    }
}

impl Search for EdConfig {
    /// `(lambda, alpha)`.
    fn search_point(&self) -> Vec<f64> {
        vec![f64::from(self.lambda), f64::from(self.alpha)]
    }

    fn with_search_point(&self, x: &[f64]) -> Self {
        EdConfig {
            lambda: coordinate(x, 0, self.lambda),
            alpha: coordinate(x, 1, self.alpha),
        }
    }

    /// `lambda` in `[0.1, 1e5]` (tuned at low noise it reaches 10), `alpha` in `[10, 1e6]`
    /// (within `estimators::ED_MAX_H_ALPHA` at every step `h <= 1` s).
    fn search_box(_h_s: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![0.1, 10.0], vec![1e5, 1e6])
    }

    /// The ED with the paper's explicit Euler scheme.
    fn score<Sc: Scorer>(&self, h: f32, scorer: &Sc) -> Result<Sc::Score, ConfigError> {
        Ok(scorer.law(EdParams::<f32>::new(self, h, EdScheme::Euler)?))
    }

    fn describe(&self) -> String {
        format!("lambda={} alpha={}", self.lambda, self.alpha)
    }
}

impl Search for KalmanNoise {
    /// `(q)`: only `q / r` matters for the steady-state gain, so `r` is kept.
    fn search_point(&self) -> Vec<f64> {
        vec![f64::from(self.q)]
    }

    fn with_search_point(&self, x: &[f64]) -> Self {
        KalmanNoise {
            q: coordinate(x, 0, self.q),
            r: self.r,
        }
    }

    /// `q` in `[1, 1e12]` deg^2/s^5.
    fn search_box(_h_s: f64) -> (Vec<f64>, Vec<f64>) {
        (vec![1.0], vec![1e12])
    }

    /// The tracker (it needs the nominal sample period, which the scorer knows: it checks
    /// the noise when it builds the tracker).
    fn score<S: Scorer>(&self, _h: f32, scorer: &S) -> Result<S::Score, ConfigError> {
        Ok(scorer.tracker(*self))
    }

    fn describe(&self) -> String {
        format!("q={} r={}", self.q, self.r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimators::{for_each_family, BankConfig, FamilyInfo, FamilyVisitor, FAMILIES};

    /// The tuner's list is the library's: the same families, in the same columns.
    #[test]
    fn the_searched_families_are_the_paper_banks() {
        struct Library(Vec<(usize, FamilyInfo)>);
        impl FamilyVisitor for Library {
            fn family<F: Family>(&mut self, column: usize) {
                self.0.push((column, FamilyInfo::of::<F>()));
            }
        }
        struct Searched(Vec<(usize, FamilyInfo)>);
        impl SearchVisitor for Searched {
            fn family<F: Family>(&mut self, column: usize)
            where
                F::Gains: Search,
            {
                self.0.push((column, FamilyInfo::of::<F>()));
            }
        }
        let mut library = Library(Vec::new());
        for_each_family(&mut library);
        let mut searched = Searched(Vec::new());
        for_each_searched_family(&mut searched);
        assert_eq!(searched.0, library.0);
        let names: Vec<_> = searched.0.iter().map(|(_, f)| f.name).collect();
        assert_eq!(names, ["ave", "ilo1", "ilo2", "ilo3", "ad", "ed", "kf"]);
        assert_eq!(searched.0.len(), FAMILIES.len());
    }

    /// Each family's search point round-trips, and its paper gains lie in its search box.
    #[test]
    fn paper_gains_lie_in_the_search_box() {
        struct Check;
        impl SearchVisitor for Check {
            fn family<F: Family>(&mut self, _: usize)
            where
                F::Gains: Search,
            {
                for half in [BankConfig::PAPER.velocity, BankConfig::PAPER.acceleration] {
                    let g = F::get(&half);
                    let x = g.search_point();
                    assert_eq!(g.with_search_point(&x), g, "{}", F::NAME);
                    let (lo, hi) = F::Gains::search_box(1e-4);
                    assert_eq!((lo.len(), hi.len()), (x.len(), x.len()));
                    for ((v, l), h) in x.iter().zip(&lo).zip(&hi) {
                        // `K1 = 1` is the leak's lower end (1e-7) to f32 precision.
                        let v = v.max(1e-7);
                        assert!(v >= *l && v <= *h, "{}: {v} not in [{l}, {h}]", F::NAME);
                    }
                }
            }
        }
        for_each_searched_family(&mut Check);
    }

    /// The ILO's `L` bound keeps `h L < 1` (the constructor's condition); both ends of the
    /// leak map to valid `K1` (`K1 = 1 - 1e-7` rounds to `1 - 2^-23` in f32).
    #[test]
    fn the_ilo_search_box_builds_valid_ilos() {
        let (lo, hi) = IloConfig::search_box(1e-4);
        assert!(hi[1] * 1e-4 < 1.0);
        let g = estimators::presets::ILO1_TABLE2;
        for c in [lo[0], hi[0]] {
            let i = g.with_search_point(&[c, 1.0, 1.0]);
            assert!(i.k1 > 0.0 && i.k1 < 1.0, "{}", i.k1);
            assert!(estimators::Ilo::<f32, 1>::new(&i, 1e-4).is_ok());
        }
    }

    /// The one-line descriptions of the paper's velocity gains.
    #[test]
    fn describe_writes_each_gain_by_name() {
        let g = BankConfig::PAPER.velocity;
        assert_eq!(g.ave.describe(), "k=500 gamma1=20000");
        assert_eq!(g.ilo[1].describe(), "K1=0.9 L=5 K2=10");
        assert_eq!(AdConfig { t: g.ad_t }.describe(), "T=0.01");
        assert_eq!(g.ed.describe(), "lambda=700 alpha=770");
        assert_eq!(g.kf.describe(), "q=1000000 r=0.01");
    }
}
