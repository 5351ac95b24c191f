//! What `nav440 tune` searches in each family's gains: the coordinates, their box and the
//! one-line description of the report, derived from what the library says of every family
//! ([`estimators::Family`], [`estimators::Gains`]), so that the tuner iterates the library's
//! own family list ([`estimators::for_each_family`]) and a new family needs nothing here:
//!
//! * a family's gains are its configuration's numbers by name: the fields of its
//!   configuration type as `serde` writes them (the keys of its gains-file table), in
//!   declaration order; settings that are not numbers (the AVE's `deltahat` law) are kept;
//! * the estimator a candidate builds is the library's ([`estimators::Gains::build`]), which
//!   the tuner's objective receives as an [`estimators::LawVisitor`];
//! * the search box of a configuration type listed in `KNOWN` (below) is the one chosen for it
//!   there (which numbers, on which scale, in which range); any other family searches each of
//!   its numbers whose paper values (both halves) are positive, two decades either side of
//!   them (`[lowest / 100, highest * 100]`), the others kept.
//!
//! The gains file's check ([`crate::gains::FamilyGains::check`]) builds each table's law the
//! same way.

use std::any::{Any, TypeId};

use estimators::{AdConfig, AveConfig, BankGains, EdConfig, Family, IloConfig, KalmanNoise};
use serde_json::{Map, Number, Value};

/// How a coordinate of the search maps to its gain.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scale {
    /// The coordinate is the gain.
    Gain,
    /// The coordinate is the gain's leak `1 - gain` (a gain within a hair of 1, searched on a
    /// log scale through its distance to 1: the ILO's `K1`).
    Leak,
}

/// One end of a coordinate's range.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Bound {
    /// A fixed value.
    At(f64),
    /// `c / h`, `h` the step (s): a gain the law bounds by the step.
    PerStep(f64),
}

impl Bound {
    fn at(self, h_s: f64) -> f64 {
        match self {
            Bound::At(v) => v,
            Bound::PerStep(c) => c / h_s,
        }
    }
}

/// A searched gain: its name (the configuration's field), its scale and its range.
#[derive(Clone, Debug, PartialEq)]
struct Coordinate {
    gain: String,
    scale: Scale,
    lo: Bound,
    hi: Bound,
}

/// The search chosen for one configuration type: the coordinates (the numbers not listed are
/// kept) and the labels of its numbers in the report (the others by their field name).
struct Known {
    /// The configuration type.
    ty: fn() -> TypeId,
    /// Each searched gain: its field, scale, lowest and highest value.
    coordinates: &'static [(&'static str, Scale, Bound, Bound)],
    labels: &'static [(&'static str, &'static str)],
}

/// The configuration types whose search box was chosen by hand (each range spans the paper's
/// gains by two decades or more each side, within what the law accepts at the step).
const KNOWN: &[Known] = &[
    // `(k, gamma1)`, the `deltahat` law not searched: `k` in `[0.1, 1e5]` 1/s (tuned at low
    // noise it reaches 10), `gamma1` in `[10, 1e8]` 1/s^2; `AveParams::new` refuses what the
    // step does not resolve.
    Known {
        ty: TypeId::of::<AveConfig>,
        coordinates: &[
            ("k", Scale::Gain, Bound::At(0.1), Bound::At(1e5)),
            ("gamma1", Scale::Gain, Bound::At(10.0), Bound::At(1e8)),
        ],
        labels: &[],
    },
    // `(1 - K1, L, K2)`: `K1` through its leak on a log scale, because the best `K1` lie
    // within 1e-3 of 1 (a leak of a few 1/s at `tau = h`); the leak in `[1e-7, 0.95]` (`K1 = 1`
    // to f32 precision, to `K1 = 0.05`), `L` in `[0.1, 0.99 / h]` 1/s (`h L < 1`, as
    // `IloParams::new` demands), `K2` in `[1e-3, 1e4]`.
    Known {
        ty: TypeId::of::<IloConfig>,
        coordinates: &[
            ("k1", Scale::Leak, Bound::At(1e-7), Bound::At(0.95)),
            ("l", Scale::Gain, Bound::At(0.1), Bound::PerStep(0.99)),
            ("k2", Scale::Gain, Bound::At(1e-3), Bound::At(1e4)),
        ],
        labels: &[("k1", "K1"), ("l", "L"), ("k2", "K2")],
    },
    // `T` in `[1e-4, 1]` s.
    Known {
        ty: TypeId::of::<AdConfig>,
        coordinates: &[("t", Scale::Gain, Bound::At(1e-4), Bound::At(1.0))],
        labels: &[("t", "T")],
    },
    // `lambda` in `[0.1, 1e5]` (tuned at low noise it reaches 10), `alpha` in `[10, 1e6]`
    // (within `estimators::ED_MAX_H_ALPHA` at every step `h <= 1` s).
    Known {
        ty: TypeId::of::<EdConfig>,
        coordinates: &[
            ("lambda", Scale::Gain, Bound::At(0.1), Bound::At(1e5)),
            ("alpha", Scale::Gain, Bound::At(10.0), Bound::At(1e6)),
        ],
        labels: &[],
    },
    // `q` in `[1, 1e12]` deg^2/s^5; only `q / r` matters for the steady-state gain, so `r` is
    // kept.
    Known {
        ty: TypeId::of::<KalmanNoise>,
        coordinates: &[("q", Scale::Gain, Bound::At(1.0), Bound::At(1e12))],
        labels: &[],
    },
];

/// The search chosen for `G` in [`KNOWN`], if any.
fn known<G: 'static>() -> Option<&'static Known> {
    KNOWN.iter().find(|k| (k.ty)() == TypeId::of::<G>())
}

/// A gain (an `f32`) read from a field of [`fields`], widened exactly. The number's text is
/// read back to `f32` first: with serde_json's `arbitrary_precision` (which a crate in the
/// same build may turn on) an `f32` field is its shortest decimal text, whose `f64` is not
/// the `f32` widened.
fn gain(v: &Value) -> Option<f64> {
    v.as_f64().map(|x| f64::from(x as f32))
}

/// The gains' fields as `serde` writes them (an empty map for gains that are not a struct).
fn fields<G: serde::Serialize>(g: &G) -> Map<String, Value> {
    match serde_json::to_value(g) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    }
}

/// The numbers of `g` by name, in declaration order (the fields that are numbers).
pub fn numbers<G: serde::Serialize>(g: &G) -> Vec<(String, f64)> {
    fields(g)
        .into_iter()
        .filter_map(|(k, v)| gain(&v).map(|x| (k, x)))
        .collect()
}

/// The coordinates `nav440 tune` searches for the family `F`.
fn coordinates<F: Family>() -> Vec<Coordinate> {
    if let Some(k) = known::<F::Gains>() {
        return k
            .coordinates
            .iter()
            .map(|&(gain, scale, lo, hi)| Coordinate {
                gain: gain.to_string(),
                scale,
                lo,
                hi,
            })
            .collect();
    }
    let velocity = numbers(&F::get(&BankGains::PAPER_VELOCITY));
    let acceleration = numbers(&F::get(&BankGains::PAPER_ACCELERATION));
    velocity
        .into_iter()
        .zip(acceleration)
        .filter(|((_, v), (_, a))| *v > 0.0 && *a > 0.0)
        .map(|((gain, v), (_, a))| Coordinate {
            gain,
            scale: Scale::Gain,
            lo: Bound::At(v.min(a) / 100.0),
            hi: Bound::At(v.max(a) * 100.0),
        })
        .collect()
}

/// The gains the tuner searches in `g`, as coordinates (in the order of [`search_box`]).
pub fn search_point<F: Family>(g: &F::Gains) -> Vec<f64> {
    let f = fields(g);
    coordinates::<F>()
        .iter()
        .map(|c| {
            let v = f.get(&c.gain).and_then(gain).unwrap_or(f64::NAN);
            match c.scale {
                Scale::Gain => v,
                Scale::Leak => 1.0 - v,
            }
        })
        .collect()
}

/// `g` with the searched gains set from the coordinates `x` (each gain rounded to its type as
/// a gains file reads it; the others, and any coordinate `x` lacks, kept).
pub fn with_search_point<F: Family>(g: &F::Gains, x: &[f64]) -> F::Gains {
    let mut f = fields(g);
    for (c, &v) in coordinates::<F>().iter().zip(x) {
        let v = match c.scale {
            Scale::Gain => v,
            Scale::Leak => 1.0 - v,
        };
        // Rounded to the gain's `f32` here, so that the text of a number (with
        // `arbitrary_precision`) reads back to the same `f32`.
        if let (Some(slot), Some(n)) = (f.get_mut(&c.gain), Number::from_f64(f64::from(v as f32))) {
            *slot = Value::Number(n);
        }
    }
    serde_json::from_value(Value::Object(f)).unwrap_or(*g)
}

/// `g` held to a constant rate: for an ILO ([`IloConfig`]) whose velocity estimate settles
/// below `1 - shortfall` of a constant rate ([`IloConfig::constant_rate_gain`]), `K1` raised
/// (its leak `1 - K1` lowered) to the smallest `f32` at which it settles within `shortfall`,
/// `L (1 - K1) <= K2 shortfall / (1 - shortfall)`; other gains, and an ILO that already
/// holds, unchanged. `shortfall` is a fraction (0.001: 0.1 %).
pub fn holding_constant_rate<F: Family>(g: &F::Gains, shortfall: f64) -> F::Gains {
    let Some(c) = (g as &dyn Any).downcast_ref::<IloConfig>() else {
        return *g;
    };
    let holds = |c: &IloConfig| c.constant_rate_gain() >= 1.0 - shortfall;
    if holds(c) {
        return *g;
    }
    let leak = f64::from(c.k2) * shortfall / (1.0 - shortfall) / f64::from(c.l);
    let mut held = IloConfig {
        k1: (1.0 - leak) as f32,
        ..*c
    };
    // The rounding to f32 may leave it a step short.
    while !holds(&held) && held.k1 < 1.0 {
        held.k1 = held.k1.next_up().min(1.0);
    }
    (&held as &dyn Any)
        .downcast_ref::<F::Gains>()
        .copied()
        .unwrap_or(*g)
}

/// The search range `(lowest, highest)` of each coordinate of [`search_point`] at the step
/// `h_s` (s).
pub fn search_box<F: Family>(h_s: f64) -> (Vec<f64>, Vec<f64>) {
    coordinates::<F>()
        .iter()
        .map(|c| (c.lo.at(h_s), c.hi.at(h_s)))
        .unzip()
}

/// The gains on one line, `name=value` separated by spaces (e.g. `k=500 gamma1=20000`), as the
/// tuner's report prints them: every number of the gains, by its label.
pub fn describe<G: estimators::Gains>(g: &G) -> String {
    let labels = known::<G>().map_or(&[][..], |k| k.labels);
    numbers(g)
        .iter()
        .map(|(name, v)| {
            let label = labels
                .iter()
                .find(|(n, _)| n == name)
                .map_or(name.as_str(), |(_, l)| l);
            // The gains are f32: written as such (`0.2`, not its f64 widening).
            format!("{label}={}", *v as f32)
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimators::{
        for_each_family, AdFamily, BankConfig, FamilyVisitor, Gains, IloFamily, LawVisitor,
    };

    /// Each family's search point round-trips, and its paper gains lie in its search box.
    #[test]
    fn paper_gains_lie_in_the_search_box() {
        struct Check;
        impl FamilyVisitor for Check {
            fn family<F: Family>(&mut self, _: usize) {
                for half in [BankConfig::PAPER.velocity, BankConfig::PAPER.acceleration] {
                    let g = F::get(&half);
                    let x = search_point::<F>(&g);
                    assert!(!x.is_empty(), "{}", F::NAME);
                    assert_eq!(with_search_point::<F>(&g, &x), g, "{}", F::NAME);
                    let (lo, hi) = search_box::<F>(1e-4);
                    assert_eq!((lo.len(), hi.len()), (x.len(), x.len()));
                    for ((v, l), h) in x.iter().zip(&lo).zip(&hi) {
                        // `K1 = 1` is the leak's lower end (1e-7) to f32 precision.
                        let v = v.max(1e-7);
                        assert!(v >= *l && v <= *h, "{}: {v} not in [{l}, {h}]", F::NAME);
                    }
                }
            }
        }
        for_each_family(&mut Check);
    }

    /// The coordinates are the gains exactly (f32 widened), the ILO's `K1` through its leak,
    /// and a point sets each gain as `as f32` does.
    #[test]
    fn coordinates_are_the_gains_exactly() {
        let g = estimators::presets::ILO2_TABLE2;
        let x = search_point::<IloFamily<1>>(&g);
        assert_eq!(x, [1.0 - f64::from(g.k1), f64::from(g.l), f64::from(g.k2)]);
        let p = [1e-3, 7.123456789, 0.3];
        let i = with_search_point::<IloFamily<1>>(&g, &p);
        assert_eq!(
            (i.k1, i.l, i.k2),
            ((1.0 - p[0]) as f32, p[1] as f32, p[2] as f32)
        );
        // A shorter point keeps the gains it does not reach.
        let a = with_search_point::<AdFamily>(&AdConfig { t: 0.01 }, &[]);
        assert_eq!(a.t, 0.01);
    }

    /// The ILO's `L` bound keeps `h L < 1` (the constructor's condition); both ends of the
    /// leak map to valid `K1` (`K1 = 1 - 1e-7` rounds to `1 - 2^-23` in f32).
    #[test]
    fn the_ilo_search_box_builds_valid_ilos() {
        struct Builds;
        impl LawVisitor for Builds {
            type Output = ();
            fn law<L: estimators::Law<Num = f32>>(self, _: L) {}
            fn tracker(self, _: KalmanNoise) {}
        }
        let (lo, hi) = search_box::<IloFamily<0>>(1e-4);
        assert!(hi[1] * 1e-4 < 1.0);
        let g = estimators::presets::ILO1_TABLE2;
        for c in [lo[0], hi[0]] {
            let i = with_search_point::<IloFamily<0>>(&g, &[c, 1.0, 1.0]);
            assert!(i.k1 > 0.0 && i.k1 < 1.0, "{}", i.k1);
            assert!(i.build(1e-4, Builds).is_ok());
        }
    }

    /// The one-line descriptions of the paper's velocity gains.
    #[test]
    fn describe_writes_each_gain_by_name() {
        let g = BankConfig::PAPER.velocity;
        assert_eq!(describe(&g.ave), "k=500 gamma1=20000");
        assert_eq!(describe(&g.ilo[1]), "K1=0.9 L=5 K2=10");
        assert_eq!(describe(&AdConfig { t: g.ad_t }), "T=0.01");
        assert_eq!(describe(&g.ed), "lambda=700 alpha=770");
        assert_eq!(describe(&g.kf), "q=1000000 r=0.01");
    }

    /// A configuration type without a chosen box searches each positive number two decades
    /// either side of its paper values, by its field name.
    #[test]
    fn an_unlisted_family_searches_two_decades_around_its_paper_gains() {
        /// The AD's gains under another type: not in [`KNOWN`].
        #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        struct Other {
            t: f32,
        }
        impl Gains for Other {
            fn interpolate(&self, _: &Self, _: f32) -> Self {
                *self
            }
            fn build<V: LawVisitor>(
                &self,
                h: f32,
                to: V,
            ) -> Result<V::Output, estimators::ConfigError> {
                AdConfig { t: self.t }.build(h, to)
            }
        }
        struct OtherFamily;
        impl Family for OtherFamily {
            type Gains = Other;
            const NAME: &'static str = "other";
            const LABEL: &'static str = "OTHER";
            const VELOCITY: estimators::Channel = estimators::Channel::AdV;
            const ACCELERATION: estimators::Channel = estimators::Channel::AdA;
            const SCHEDULING: estimators::Scheduling = estimators::Scheduling::Smooth;
            fn get(half: &BankGains) -> Other {
                Other { t: half.ad_t }
            }
            fn set(half: &mut BankGains, g: Other) {
                half.ad_t = g.t;
            }
        }
        let (lo, hi) = search_box::<OtherFamily>(1e-4);
        assert_eq!(lo, [f64::from(0.01f32) / 100.0]);
        assert_eq!(hi, [f64::from(0.1f32) * 100.0]);
        let g = Other { t: 0.01 };
        assert_eq!(search_point::<OtherFamily>(&g), [f64::from(0.01f32)]);
        assert_eq!(
            with_search_point::<OtherFamily>(&g, &[0.5]),
            Other { t: 0.5 }
        );
        assert_eq!(describe(&g), "t=0.01");
    }

    /// The paper's ILO2 (Table 2: `K1` 0.9, `L` 5, `K2` 10) settles at 10 / 10.5 of a constant
    /// rate; held to 0.1 %, its `K1` rises to the smallest `f32` at which
    /// `K2 / (K2 + L (1 - K1)) >= 0.999` (`1 - K1 <= 10 x 0.001 / 0.999 / 5 = 0.002002`), with
    /// `L` and `K2` kept. ILO1 (`K1` 1) and a family without `K1` are unchanged.
    #[test]
    fn holding_a_constant_rate_raises_k1_just_enough() {
        let ilo2 = BankConfig::PAPER.velocity.ilo[1];
        assert!((ilo2.constant_rate_gain() - 10.0 / 10.5).abs() < 1e-6);
        let held = holding_constant_rate::<IloFamily<1>>(&ilo2, 1e-3);
        assert_eq!((held.l, held.k2), (ilo2.l, ilo2.k2));
        assert!(held.constant_rate_gain() >= 0.999);
        let below = IloConfig {
            k1: held.k1.next_down(),
            ..held
        };
        assert!(below.constant_rate_gain() < 0.999);
        assert!((f64::from(held.k1) - (1.0 - 0.002 / 0.999)).abs() < 1e-7);
        let ilo1 = BankConfig::PAPER.velocity.ilo[0];
        assert_eq!(holding_constant_rate::<IloFamily<0>>(&ilo1, 1e-3), ilo1);
        let ed = BankConfig::PAPER.velocity.ed;
        assert_eq!(holding_constant_rate::<estimators::EdFamily>(&ed, 1e-3), ed);
    }
}
