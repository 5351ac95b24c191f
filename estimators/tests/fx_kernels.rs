//! The integer kernels of the fixed-point AVE and ED rows (`estimators::fxk`, used by
//! `Law::advance` for `Fx`) give bit for bit the states of the generic saturating code stepped
//! one step at a time (`Law::step`, the independent reference here), on ordinary inputs, on
//! inputs that leave the kernels' fast 32-bit paths (errors of 1 deg and more, the ED-ED's
//! second stage), and on inputs near the ends of the Q31.32 range where the range guard hands
//! the interval to the generic code (saturation).

use estimators::law::step_n;
use estimators::presets::*;
use estimators::{
    AveConfig, AveParams, BankGains, DeltaMode, EdConfig, EdParams, EdScheme, Fx, Hold, Law, Real,
    VelAcc, COARSE_STABILITY_MARGIN,
};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Seeded generator (rand's xoshiro256++) with the one draw the test needs.
struct Rng(Xoshiro256PlusPlus);
impl Rng {
    fn new(seed: u64) -> Self {
        Self(Xoshiro256PlusPlus::seed_from_u64(seed))
    }
    /// Uniform in [-1, 1).
    fn unit(&mut self) -> f64 {
        self.0.random_range(-1.0..1.0)
    }
}

/// The input of sample `k` of scenario `sc`, deg.
fn input(sc: u32, k: u32, r: &mut Rng) -> f64 {
    let t = f64::from(k) * 0.01;
    match sc {
        // The paper-like run: +-90 deg, 0.1 deg noise.
        0 => 90.0 * (1.3 * t).sin() + 0.1 * r.unit(),
        // Fast spin with big noise: errors of several deg (the 64-bit paths).
        1 => 2000.0 * t % 360.0 - 180.0 + 5.0 * r.unit(),
        // Jumps across the whole accepted input range.
        2 => 1.0e6 * r.unit(),
        // Near the Q31.32 range ends: the generic code saturates.
        _ => 2.0e9 * r.unit(),
    }
}

/// `n` steps per interval for sample `k` (mostly 100, some gaps and short intervals).
fn steps(k: u32) -> u32 {
    match k % 17 {
        3 => 1,
        5 => 2,
        7 => 250,
        9 if k.is_multiple_of(3) => 5000,
        11 => 37,
        13 => 99,
        _ => 100,
    }
}

fn check_pair<L: Law<Num = Fx>>(v: L, a2: L, label: &str)
where
    L::State: PartialEq,
{
    check_row(v, None, a2, label);
}

/// `a1`: the series' own first stage (a row with its own acceleration gains, not shared with
/// the velocity law), or `None` (shared: the velocity law feeds `a2`).
fn check_row<L: Law<Num = Fx>>(v: L, a1: Option<L>, a2: L, label: &str)
where
    L::State: PartialEq,
{
    let row = VelAcc::new(v, a1.unwrap_or(v), a2, a1.is_none());
    let first = a1.unwrap_or(v);
    for sc in 0..4 {
        for hold in [Hold::Linear, Hold::ZeroOrder] {
            let mut r = Rng::new(0x9E37_79B9 + u64::from(sc));
            let y0 = Fx::from_f64(input(sc, 0, &mut r));
            let mut s = row.init(y0);
            // The reference: the three laws stepped one by one with the generic code.
            let (mut rv, mut r1) = (v.init(y0), first.init(y0));
            let mut ra = a2.init(first.output(&first.init(y0)));
            let mut yp = y0;
            for k in 1..300 {
                let y = Fx::from_f64(input(sc, k, &mut r));
                let n = steps(k);
                row.advance(&mut s, yp, y, n, hold);
                // Generic: the same inputs as the kernels (`step_n`'s grid), the second stage
                // fed by the first's output of each step. With a coarse step (the fixed-point
                // AVE, `Law::coarse`, factor m): steps m, 2m, .. of the grid as coarse steps,
                // each seeing the grid's input at its end, then the rest one by one.
                let inc = (y - yp).div_int(n);
                let mut grid = Vec::with_capacity(n as usize);
                let mut yy = yp;
                for j in 1..=n {
                    grid.push(match hold {
                        Hold::ZeroOrder => y,
                        Hold::Linear if j == n => y,
                        Hold::Linear => {
                            yy = yy + inc;
                            yy
                        }
                    });
                }
                let coarse = match (v.coarse(), a2.coarse(), a1.map(|l| l.coarse())) {
                    (Some((cv, m)), Some((ca, _)), None) => Some((cv, cv, ca, m)),
                    (Some((cv, m)), Some((ca, _)), Some(Some((c1, _)))) => Some((cv, c1, ca, m)),
                    _ => None,
                };
                let m = coarse.map_or(1, |c| c.3);
                let q = if coarse.is_some() { n / m } else { 0 };
                let mut one = |v: &L, first: &L, a2: &L, x: Fx| {
                    let o = v.step(&mut rv, x);
                    let o1 = if a1.is_some() {
                        first.step(&mut r1, x)
                    } else {
                        o
                    };
                    a2.step(&mut ra, o1);
                };
                if let Some((cv, c1, ca, _)) = coarse {
                    for g in 1..=q {
                        one(&cv, &c1, &ca, grid[(g * m - 1) as usize]);
                    }
                }
                for j in q * m + 1..=n {
                    one(&v, &first, &a2, grid[(j - 1) as usize]);
                }
                assert!(
                    s.v == rv && s.a2 == ra && (a1.is_none() || s.a1 == r1),
                    "{label}: scenario {sc}, {hold:?}, sample {k}"
                );
                // The single law too (`Law::advance` against `step_n` of the generic step).
                let mut one = rv;
                let mut reference = rv;
                v.advance(&mut one, yp, y, n, hold);
                step_n(&Generic(v), &mut reference, yp, y, n, hold);
                assert!(one == reference, "{label} alone: scenario {sc}, sample {k}");
                // The frame translation of the bank (every 50 samples), on both.
                if k % 50 == 0 {
                    let d = Fx::from_f64(-12.5);
                    row.translate(&mut s, d);
                    v.translate(&mut rv, d);
                    first.translate(&mut r1, d);
                }
                yp = y;
            }
        }
    }
}

/// A law with the default `advance` (the generic stepping, with the law's coarse step), as
/// the reference.
#[derive(Clone, Copy, Debug)]
struct Generic<L>(L);

impl<L: Law> Law for Generic<L> {
    type Num = L::Num;
    type State = L::State;
    fn init(&self, y0: L::Num) -> L::State {
        self.0.init(y0)
    }
    fn step(&self, s: &mut L::State, y: L::Num) -> L::Num {
        self.0.step(s, y)
    }
    fn output(&self, s: &L::State) -> L::Num {
        self.0.output(s)
    }
    fn translate(&self, s: &mut L::State, d: L::Num) {
        self.0.translate(s, d);
    }
    fn coarse(&self) -> Option<(Self, u32)> {
        self.0.coarse().map(|(c, m)| (Generic(c), m))
    }
}

#[test]
fn ave_kernels_equal_generic_steps() {
    let h = H_PAPER;
    for (cfg, label) in [
        (AVE_PAPER, "AVE paper"),
        (AVE_DEFAULT, "AVE leaky"),
        (
            AveConfig {
                delta: DeltaMode::Bounded { max: 50.0 },
                ..AVE_PAPER
            },
            "AVE bounded",
        ),
        (
            AveConfig {
                k: 300.0,
                gamma1: 12345.6,
                delta: DeltaMode::Paper,
            },
            "AVE other gains",
        ),
        (
            AveConfig {
                k: 300.0,
                gamma1: 12345.6,
                delta: DeltaMode::Leaky { sigma: 0.37 },
            },
            "AVE other gains, leaky",
        ),
    ] {
        let p = AveParams::<Fx>::new(&cfg, h).unwrap();
        check_pair(p, p, label);
    }
}

#[test]
fn ed_kernels_equal_generic_steps() {
    for (cfg, label) in [
        (ED_PAPER, "ED paper"),
        (
            EdConfig {
                lambda: 123.4,
                alpha: 5000.5,
            },
            "ED other gains",
        ),
    ] {
        let p = EdParams::<Fx>::new(&cfg, H_PAPER, EdScheme::Euler).unwrap();
        check_pair(p, p, label);
    }
}

/// Rows whose series has its own gains (the NAV440 preset: velocity and acceleration AVE and
/// ED gains differ, so the first stage is not shared): the series runs through the kernels
/// and the velocity law through its own; the same states as the generic steps.
#[test]
fn unshared_rows_equal_generic_steps() {
    use estimators::BankGains;
    let (v, a) = (BankGains::NAV440_VELOCITY, BankGains::NAV440_ACCELERATION);
    let (pv, pa) = (
        AveParams::<Fx>::new(&v.ave, H_PAPER).unwrap(),
        AveParams::<Fx>::new(&a.ave, H_PAPER).unwrap(),
    );
    check_row(pv, Some(pa), pa, "AVE, NAV440 gains");
    let (ev, ea) = (
        EdParams::<Fx>::new(&v.ed, H_PAPER, EdScheme::Euler).unwrap(),
        EdParams::<Fx>::new(&a.ed, H_PAPER, EdScheme::Euler).unwrap(),
    );
    check_row(ev, Some(ea), ea, "ED, NAV440 gains");
}

/// The fixed-point AVE's coarse step (`Real::AVE_STEP_FACTOR`): `2 h` for a bounded `deltahat`
/// law, `h` for the paper's law and for the float types.
#[test]
fn ave_step_factor() {
    let h = H_PAPER;
    assert_eq!(
        AveParams::<Fx>::new(&AVE_DEFAULT, h).unwrap().step_factor(),
        2
    );
    let bounded = AveConfig {
        delta: DeltaMode::Bounded { max: 50.0 },
        ..AVE_PAPER
    };
    assert_eq!(AveParams::<Fx>::new(&bounded, h).unwrap().step_factor(), 2);
    assert_eq!(
        AveParams::<Fx>::new(&AVE_PAPER, h).unwrap().step_factor(),
        1
    );
    assert_eq!(
        AveParams::<f32>::new(&AVE_DEFAULT, h)
            .unwrap()
            .step_factor(),
        1
    );
    assert_eq!(
        AveParams::<f64>::new(&AVE_DEFAULT, h)
            .unwrap()
            .step_factor(),
        1
    );
    // 2 h k = 1.2 >= 1: valid at h, no coarse step.
    let big_k = AveConfig {
        k: 6000.0,
        ..AVE_DEFAULT
    };
    assert_eq!(AveParams::<Fx>::new(&big_k, h).unwrap().step_factor(), 1);
    // The coarse step only at COARSE_STABILITY_MARGIN (10) x below the longest stable step
    // k / gamma1: the 0.1 deg^2 level of the bundled schedule (k 47.39 1/s, gamma1 425,822
    // 1/s^2: h gamma1 / k = 0.90, stable at h, unstable at 2 h) steps at h; at 2 h it diverged
    // to the Q31.32 limit (`nav440 estimate --gains schedule_fig5.toml --fixed`).
    let tuned = AveConfig {
        k: 47.390957,
        gamma1: 425822.44,
        ..AVE_DEFAULT
    };
    assert_eq!(AveParams::<Fx>::new(&tuned, h).unwrap().step_factor(), 1);
    let at = |ratio: f64| AveConfig {
        gamma1: (ratio * 50.0 / (2.0 * f64::from(h))) as f32,
        k: 50.0,
        ..AVE_DEFAULT
    };
    assert_eq!(
        AveParams::<Fx>::new(&at(0.099), h).unwrap().step_factor(),
        2
    );
    assert_eq!(
        AveParams::<Fx>::new(&at(0.101), h).unwrap().step_factor(),
        1
    );
    assert!((COARSE_STABILITY_MARGIN - 10.0).abs() < 1e-12);
    // The shipped presets keep the coarse step (2 h gamma1 / k: paper 0.008, NAV440 velocity
    // 0.0086, acceleration 0.0063).
    for cfg in [
        BankGains::NAV440_VELOCITY.ave,
        BankGains::NAV440_ACCELERATION.ave,
    ] {
        assert_eq!(AveParams::<Fx>::new(&cfg, h).unwrap().step_factor(), 2);
    }
}

/// A row whose laws disagree on the coarse step (velocity AVE leaky: `2 h`; the series with
/// the paper's law: `h`) runs every law at `h`, kernel or not: the states equal the generic
/// steps at `h` (the reference of `check_row` steps at `h` when the laws disagree).
#[test]
fn ave_row_with_mixed_step_factors() {
    let pv = AveParams::<Fx>::new(&AVE_DEFAULT, H_PAPER).unwrap();
    let pa = AveParams::<Fx>::new(&AVE_PAPER, H_PAPER).unwrap();
    check_row(pv, Some(pa), pa, "AVE leaky velocity, paper series");
}

/// The inputs of the coarse steps under linear hold are the true input at the end of each
/// step's span: on a ramp (exact in f64 up to rounding), `f(y)` of the step ending at
/// `j h` is `y_prev + j (y_new - y_prev) / n`; the coarse / step-h split is `floor(n / m)`
/// then `n mod m`; zero-order hold gives `y_new` throughout.
#[test]
fn stepped_inputs_are_on_the_grid() {
    use estimators::law::stepped_inputs;
    for n in [1u32, 2, 3, 37, 99, 100, 5000] {
        for m in [1u32, 2, 3] {
            let (y0, y1) = (-3.25f64, 17.5f64);
            let mut calls = Vec::new();
            stepped_inputs(y0, y1, n, m, Hold::Linear, |y, c| calls.push((y, c)));
            let q = (n / m) as usize;
            assert_eq!(calls.len(), q + (n % m) as usize);
            let mut j = 0u32;
            for (i, (y, c)) in calls.iter().enumerate() {
                assert_eq!(*c, i < q);
                j += if *c { m } else { 1 };
                let want = y0 + f64::from(j) * (y1 - y0) / f64::from(n);
                assert!(
                    (y - want).abs() < 1e-9,
                    "n {n} m {m} step {i}: {y} vs {want}"
                );
            }
            assert_eq!(j, n);
            assert_eq!(calls.last().unwrap().0, y1);
            let mut zoh = Vec::new();
            stepped_inputs(y0, y1, n, m, Hold::ZeroOrder, |y, c| zoh.push((y, c)));
            assert!(zoh.iter().all(|(y, _)| *y == y1) && zoh.len() == calls.len());
        }
    }
}
