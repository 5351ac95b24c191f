//! Noise-adaptive gains (docs/ADAPTIVE-GAINS.md): a
//! capture whose noise switches from 0.01 to 0.5 deg^2 half-way, run through the scheduled
//! bank (`nav440 estimate FILE --gains schedule.toml`: `estimators::AdaptiveBank`).
//!
//! The schedule is `data/gains/schedule_fig5.toml`, written by
//! `nav440 tune host-tests/data/fig5_a2_100hz.bin --schedule 0.001,0.01,0.1,0.5,1 -o schedule_fig5.toml`
//! (constant noise at each level, noise seeds 1-3, MSE over 0-30 s). The test capture is the
//! first 20 s of the same motion with other noise: N(0, 0.01) before 10 s, N(0, 0.5) from
//! 10 s (xoshiro256++ seed 7). The gains "tuned for a half" are tuned here, by the tuner,
//! on that half at that half's noise level (one seed). Velocity MSE against the motion's
//! analytic rate (independent of the code under test), per family:
//!
//! * in each half, the scheduled bank is within 1.2x of the gains tuned for that half;
//! * over the whole capture, it is below every fixed gain set: each schedule level, both
//!   gains tuned for a half, `BankConfig::PAPER` and `BankConfig::NAV440` - for every family
//!   but the ED, which is held to 1.02 x the best of them (not met on this draw: see the
//!   test);
//! * on 40 other noise draws (`scheduled_bank_against_every_fixed_set_on_forty_draws`), the
//!   previous point holds for the ILO, AD and tracker on at least 38 draws, for the AVE on 32
//!   (below the best fixed set on a typical draw, thanks to the switching gains the schedule
//!   records: 22 without them), and not for the ED (5 of 40): measured, bounded and
//!   explained there;
//! * on one draw, the AVE's and the ED's MSE move by more than those margins when their gains
//!   move by 0.5 % (`one_draw_margins_of_the_ave_and_ed_are_inside_their_gain_sensitivity`);
//! * each level records the AVEs' switching gains it was tuned with
//!   (`each_level_records_the_deltahat_it_was_tuned_with`);
//! * on six other noise draws of the same switch (`scheduled_bank_does_not_ring_on_other_noise_draws`),
//!   in each half, every family is within 1.2x of the gains tuned for that half: a gain change
//!   does not ring (it did before gain changes were made bumpless: ILO 161x);
//! * on a 20 Hz spin (`the_100_hz_schedule_survives_retunes_at_20_hz`), every family within
//!   1.2x of fixed `BankConfig::NAV440` (the AVE was 5.74x before its retune was bumpless).
//!
//! Release only (tuning): `cargo test --release -p host-tests --test schedule -- --nocapture`.

use estimators::{BankConfig, Hold};
use host_tests::data;
use nav440_cli::gains::{self, Loaded};
use nav440_cli::motion::{Profile, ProfileKind};
use nav440_cli::optim::Method;
use nav440_cli::paper::{ave_on_rate, COLUMNS as NAMES, REFERENCE_AVE};
use nav440_cli::replay::{self, Axis, EstimateOptions, Sample};
use nav440_cli::synth::{angle_raw, ANGLE_LSB_DEG};
use nav440_cli::tune::{mse_range, tune_with, tuned_ave_deltahat, Families, TuneSpec};
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::sync::OnceLock;

mod runs;
use runs::{mse_over, schedule};

/// Capture length and switch time, s.
const END_S: f64 = 20.0;
const SWITCH_S: f64 = 10.0;

fn clean() -> Vec<Sample> {
    let end = (END_S * 1e6) as u64;
    replay::read_samples(&data("fig5_a2_100hz.bin"))
        .unwrap()
        .into_iter()
        .filter(|s| s.t_us <= end)
        .collect()
}

/// The capture with the switching noise added to yaw (re-wrapped to +-180 deg).
fn switching(samples: &[Sample], seed: u64) -> Vec<Sample> {
    with_noise(samples, seed, |t| if t < SWITCH_S { 0.01 } else { 0.5 })
}

/// `samples` with N(0, `var_at(t)`) deg^2 added to yaw at each sample time `t` (s;
/// xoshiro256++ `seed`), re-wrapped to +-180 deg.
fn with_noise(samples: &[Sample], seed: u64, var_at: impl Fn(f64) -> f64) -> Vec<Sample> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    samples
        .iter()
        .map(|s| {
            let noise = Normal::new(0.0, var_at(s.t_s()).sqrt()).unwrap();
            let mut y = f64::from(s.angles_deg()[2]) + noise.sample(&mut rng);
            if y > 180.0 {
                y -= 360.0;
            } else if y <= -180.0 {
                y += 360.0;
            }
            let mut o = *s;
            o.set_angle_deg(Axis::Yaw, y as f32);
            o
        })
        .collect()
}

/// Velocity MSE per family over the first half, the second half and the whole capture.
fn mse(samples: &[Sample], opts: &EstimateOptions) -> [[f64; estimators::FAMILY_COUNT]; 3] {
    // Halves: [0, 10 s) and [10 s, 20 s] (mse_range includes both ends: 9.99 s ends the first).
    let ranges = [(0.0, SWITCH_S - 0.005), (SWITCH_S, END_S), (0.0, END_S)];
    let m = mse_over(samples, opts, &ranges);
    [m[0], m[1], m[2]]
}

/// The samples of a 30 s synthetic A2 capture of `profile` (motion seed 21) at `rate_hz` with
/// constant N(0, `var_deg2`) yaw noise (noise seed 5): `nav440 synth --profile PROFILE --rate
/// RATE --duration 30 --seed 21 --yaw-noise VAR --noise-seed 5`.
fn synth_samples(profile: ProfileKind, rate_hz: u32, var_deg2: f64) -> Vec<Sample> {
    use nav440_cli::synth::{self, NoiseStep, PacketKind, SynthConfig};
    let cap = synth::generate(&SynthConfig {
        profile,
        seed: 21,
        duration_s: 30.0,
        rate_hz,
        packet: PacketKind::A2,
        yaw_noise: vec![NoiseStep {
            var_deg2,
            from_s: 0.0,
        }],
        noise_seed: 5,
        ..Default::default()
    })
    .unwrap();
    replay::samples(&cap.bytes).unwrap()
}

fn fixed(cfg: BankConfig) -> EstimateOptions {
    EstimateOptions {
        hold: cfg.hold,
        config: Some(cfg),
        ..Default::default()
    }
}

/// The schedule file and the options that run it (`nav440 estimate FILE --gains
/// schedule_fig5.toml`).
fn schedule_fig5() -> (gains::ScheduleFile, EstimateOptions) {
    schedule("gains/schedule_fig5.toml")
}

/// The gains tuned for the first half (0.01 deg^2) and for the second (0.5 deg^2), tuned
/// once per test binary (the tests that need them run in parallel and share them).
fn tuned_for_the_halves(clean: &[Sample]) -> (BankConfig, BankConfig) {
    static TUNED: OnceLock<(BankConfig, BankConfig)> = OnceLock::new();
    *TUNED.get_or_init(|| {
        (
            tuned_for(clean, 0.01, (0.0, SWITCH_S - 0.005)),
            tuned_for(clean, 0.5, (SWITCH_S, END_S)),
        )
    })
}

/// Every fixed gain set the scheduled bank is compared with over the whole capture: both
/// halves' tuned gains, `PAPER`, `NAV440` and each level of the schedule as a fixed set.
fn fixed_sets(clean: &[Sample], file: &gains::ScheduleFile) -> Vec<(String, BankConfig)> {
    let (first, second) = tuned_for_the_halves(clean);
    let mut sets = vec![
        ("tuned for 0-10 s".to_string(), first),
        ("tuned for 10-20 s".to_string(), second),
        ("PAPER".to_string(), BankConfig::PAPER),
        ("NAV440".to_string(), BankConfig::NAV440),
    ];
    for l in file.schedule(&BankConfig::NAV440).unwrap().levels() {
        let cfg = BankConfig {
            velocity: l.velocity,
            acceleration: l.acceleration,
            hold: file.hold().unwrap(),
            ..BankConfig::NAV440
        };
        sets.push((format!("level {}", l.noise_var), cfg));
    }
    sets
}

/// Gains tuned by `nav440 tune` for one half: that half's noise, MSE over that half.
fn tuned_for(samples: &[Sample], noise_var: f64, range: (f64, f64)) -> BankConfig {
    let res = tune_with(
        samples,
        &EstimateOptions::default(),
        &TuneSpec {
            noise_var,
            seeds: 1,
            train: range,
            test: None,
            method: Method::Search,
            holds: vec![Hold::Linear],
            families: Families::ALL,
        },
    )
    .unwrap();
    res.gains.apply(BankConfig::NAV440)
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn scheduled_bank_follows_a_noise_switch() {
    let clean = clean();
    let noisy = switching(&clean, 7);
    let (file, scheduled) = schedule_fig5();
    let sched = mse(&noisy, &scheduled);
    let (first, second) = tuned_for_the_halves(&clean);
    let t_first = mse(&noisy, &fixed(first));
    let t_second = mse(&noisy, &fixed(second));
    let mut failures = Vec::new();
    println!("velocity MSE (deg/s)^2: scheduled / tuned for the half (ratio)");
    for i in 0..estimators::FAMILY_COUNT {
        let r1 = sched[0][i] / t_first[0][i];
        let r2 = sched[1][i] / t_second[1][i];
        println!(
            "  {:<4} 0-10 s: {:.3} / {:.3} ({:.3})   10-20 s: {:.3} / {:.3} ({:.3})   0-20 s: {:.3}",
            NAMES[i], sched[0][i], t_first[0][i], r1, sched[1][i], t_second[1][i], r2, sched[2][i]
        );
        if !(r1 <= 1.2 && r2 <= 1.2) {
            failures.push(format!("{}: ratios {r1:.3} {r2:.3} > 1.2", NAMES[i]));
        }
    }
    let sets: Vec<(String, [[f64; estimators::FAMILY_COUNT]; 3])> = fixed_sets(&clean, &file)
        .into_iter()
        .map(|(name, cfg)| (name, mse(&noisy, &fixed(cfg))))
        .collect();
    println!("whole capture, 0-20 s:");
    for (name, m) in &sets {
        let row: Vec<String> = (0..estimators::FAMILY_COUNT)
            .map(|i| format!("{:.3}", m[2][i]))
            .collect();
        println!("  {name:<18} {}", row.join(" "));
        for i in 0..estimators::FAMILY_COUNT {
            // Not met for the ED (measured: scheduled 177.7 against 175.7 for the 0.5 level as
            // a fixed set, below every other set). In 10-20 s the scheduled ED runs the 0.5
            // level's gains (282.7, below the half's own tuning, 321.2); in 0-10 s the 0.01
            // level's (72.7), where the 0.5 level's ED gains happen to do better on this noise
            // draw (about 69): the ED's MSE is rugged in its gains and depends on the noise
            // draw (docs/ADAPTIVE-RESULTS.md), by more than any ED schedule could gain
            // (`one_draw_margins_of_the_ave_and_ed_are_inside_their_gain_sensitivity`). Held
            // to 1.02 x the best fixed set. (The AVE was held so too, at 69.063 against
            // 68.966, until the schedule took each level's best observer gains and recorded
            // where each family switches: 67.287 now.)
            if i == 5 {
                let held = sched[2][i] <= 1.02 * m[2][i];
                if !held {
                    failures.push(format!(
                        "{}: scheduled {} above 1.02 x {name} {}",
                        NAMES[i], sched[2][i], m[2][i]
                    ));
                }
                continue;
            }
            let below = sched[2][i] < m[2][i];
            if !below {
                failures.push(format!(
                    "{}: scheduled {} not below {name} {}",
                    NAMES[i], sched[2][i], m[2][i]
                ));
            }
        }
    }
    let row: Vec<String> = (0..estimators::FAMILY_COUNT)
        .map(|i| format!("{:.3}", sched[2][i]))
        .collect();
    println!("  {:<18} {}", "scheduled", row.join(" "));
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A steady noise level between two schedule levels, where the noise estimate (about +-25 %)
/// hovers around the boundary of the nearer level and the gains change back and forth: fig5
/// (the whole 30 s, MSE over 2-30 s) with constant N(0, v) yaw noise, v = 0.002, 0.003 (the
/// 0.001 and 0.01 levels meet at 0.0032 in ln(noise)), 0.2 and 0.3 (0.1 and 0.5 meet at
/// 0.22), noise seeds 201-205. Per family, the scheduled bank's velocity MSE against the best
/// schedule level run as a fixed set on the same draw (geometric mean and worst over the
/// seeds), and the same for the level the schedule's observers take (the nearer one in
/// ln(noise)) run as a fixed set.
///
/// Measured: every family within 1.04x of the best level on average (worst 1.10, the ILO3 at
/// 0.003); the AVE 0.99-1.00x (worst 1.02), the ED 1.01-1.04x (worst 1.08), the AD and the
/// tracker below every level (0.86-0.97). Asserted: below 1.1x, worst 1.15x. Before, with
/// the bundled schedule as it was (each level's own tuned gains, observers switched at the
/// geometric midpoints) and the ED's old gain change: the ED 2.07x and 9.6x (worst 87x) at
/// 0.002 and 0.003, the AVE 1.02, 1.28, 1.18, 1.28x. Three changes brought it here, each
/// measured by this test: the ED's gain change made bumpless (`EdParams`' `retune_state`; ED
/// 1.23x); each level's observers the best of every level's tuned gains at its noise (the
/// 0.5 level's AVE is now the 0.1 level's) and switch points where two levels' MSEs cross
/// (`ScheduleLevel::switch_up`, recorded by `nav440 tune --schedule`): AVE and ED within
/// 1.04x (docs/ADAPTIVE-RESULTS.md, "Between the levels").
///
/// Independent of the code under test: MSE against the motion's analytic rate.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn the_schedule_between_its_levels() {
    let (file, scheduled) = schedule_fig5();
    let levels = file
        .schedule(&BankConfig::NAV440)
        .unwrap()
        .levels()
        .to_vec();
    let clean = replay::read_samples(&data("fig5_a2_100hz.bin")).unwrap();
    let window = [(2.0, 30.0)];
    let level_cfg = |l: &estimators::ScheduleLevel| BankConfig {
        velocity: l.velocity,
        acceleration: l.acceleration,
        hold: file.hold().unwrap(),
        ..BankConfig::NAV440
    };
    for v in [0.002f64, 0.003, 0.2, 0.3] {
        // The level the observers take: the nearer in ln(noise).
        let nearer = levels
            .iter()
            .min_by(|a, b| {
                let d = |l: &estimators::ScheduleLevel| (f64::from(l.noise_var) / v).ln().abs();
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let seeds = 201..=205u64;
        let n = seeds.clone().count() as f64;
        let (mut gm, mut worst, mut gm_nearer) = (
            [0.0f64; estimators::FAMILY_COUNT],
            [0.0f64; estimators::FAMILY_COUNT],
            [0.0f64; estimators::FAMILY_COUNT],
        );
        for seed in seeds {
            let noisy = with_noise(&clean, seed, |_| v);
            let sched = mse_over(&noisy, &scheduled, &window)[0];
            let fixed_mse: Vec<[f64; estimators::FAMILY_COUNT]> = levels
                .iter()
                .map(|l| mse_over(&noisy, &fixed(level_cfg(l)), &window)[0])
                .collect();
            let near = mse_over(&noisy, &fixed(level_cfg(nearer)), &window)[0];
            for i in 0..estimators::FAMILY_COUNT {
                let best = fixed_mse.iter().map(|m| m[i]).fold(f64::MAX, f64::min);
                gm[i] += (sched[i] / best).ln() / n;
                gm_nearer[i] += (near[i] / best).ln() / n;
                worst[i] = worst[i].max(sched[i] / best);
            }
        }
        let (gm, gm_nearer) = (gm.map(f64::exp), gm_nearer.map(f64::exp));
        println!(
            "{v} deg^2: scheduled / best level, geometric mean {gm:.2?}, worst {worst:.2?}; the nearer level ({}) as a fixed set {gm_nearer:.2?}",
            nearer.noise_var
        );
        assert!(
            gm[5] < 1.1 && worst[5] < 1.15,
            "ED at {v}: {} {}",
            gm[5],
            worst[5]
        );
        assert!(
            gm[0] < 1.1 && worst[0] < 1.15,
            "AVE at {v}: {} {}",
            gm[0],
            worst[0]
        );
        for i in [1, 2, 3, 4, 6] {
            assert!(
                gm[i] < 1.1 && worst[i] < 1.15,
                "{} at {v}: {}",
                NAMES[i],
                gm[i]
            );
        }
    }
}

/// The fixed-point adaptive bank (`nav440 estimate FILE --gains schedule_fig5.toml --fixed`,
/// what the `adaptive-gains` firmware runs on thumbv6m) follows the f32 one on the noise
/// switch: in each half, every family's velocity MSE within 1.05x of f32's (measured: at most
/// 1.0002x, the ILOs in 0-10 s; the AVE 0.997 and 0.996), and no estimate beyond 1000 deg/s.
/// Before the fixed-point AVE's coarse step `2 h` was limited to gains it keeps stable
/// (`estimators::COARSE_STABILITY_MARGIN`), the schedule's 0.001-0.1 levels (tuned at
/// `h gamma1 / k` = 0.83-0.98) ran at `2 h` and the AVE saturated at the Q31.32 limit
/// (2.1e9 deg/s) on this capture; CI's firmware check compares the firmware with this host
/// path byte for byte, so this test is what says that path is right.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn the_fixed_point_schedule_follows_f32_on_the_noise_switch() {
    let noisy = switching(&clean(), 7);
    let (_, scheduled) = schedule_fig5();
    let fx = EstimateOptions {
        fixed: true,
        ..scheduled.clone()
    };
    let (f, x) = (mse(&noisy, &scheduled), mse(&noisy, &fx));
    for half in 0..2 {
        let r: Vec<f64> = (0..estimators::FAMILY_COUNT)
            .map(|i| x[half][i] / f[half][i])
            .collect();
        println!("half {half}: fixed point / f32 velocity MSE {r:.4?}");
        for (i, r) in r.iter().enumerate() {
            assert!(*r < 1.05, "{} half {half}: {r}", NAMES[i]);
        }
    }
    let (rows, _) = replay::estimate(&noisy, &fx).unwrap();
    for r in &rows {
        let v = r.axis(Axis::Yaw).unwrap().out.velocities();
        assert!(v.iter().all(|v| v.abs() < 1000.0), "{} s: {v:?}", r.t_us);
    }
}

/// Why "below every fixed set" on one noise draw is not a fair test of the AVE and the ED:
/// on one draw their MSE moves with the gains by more than the margins at stake.
///
/// * On draw 7, moving the best fixed set's two gains (the AVE of the 0.1 level: `k`,
///   `gamma1`; the ED of the 0.5 level: `lambda`, `alpha`) by at most 0.5 % each (5 x 5
///   points) moves the family's 0-20 s velocity MSE by more than 2 % (measured: AVE 64.1-78.4,
///   a 22 % spread; ED 174.7-183.3, 4.9 %), more than the schedule's margin to that set on
///   this draw (AVE -2.4 %, +0.14 % with the schedule before its levels took the best
///   observer gains and its switch points; ED +1.15 %). A fixed AVE set within 0.5 % of the
///   0.1 level's gains is 4.7 % below the schedule on this draw, another 16 % above it; no
///   tuner can tell such sets apart.
///   The two differ in kind. The AVE's MSE is smooth but steep in `gamma1` (about +1.2 % per
///   +0.05 %): the tuned 0.1 level sits at 0.90 of the Euler step's stability bound
///   (`h gamma1 < k`), where the step keeps a tenth of the continuous law's damping
///   (docs/ADAPTIVE-GAINS.md, "Gains at the edge of the Euler step"). The ED's is rugged: its
///   switching law's MSE changes by percents between gain sets 0.1 % apart.
/// * An estimate of what any ED schedule can gain over fixed ED gains on this switch: on a
///   log grid of (`lambda`, `alpha`) (14 x 14 points, 3-60 x 100-4000), the grid's best pair
///   for each half (mean MSE over draws 101-110) against its best pair for the whole
///   capture. Measured 1.8 %: less than 3 %, and less than the ED's spread above. The Levant
///   differentiator's gains are set by the motion (`alpha` above the bound of the velocity's
///   derivative), not by the noise, so there is little to schedule.
///
/// Independent of the code under test: MSE against the motion's analytic rate.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn one_draw_margins_of_the_ave_and_ed_are_inside_their_gain_sensitivity() {
    let clean = clean();
    let noisy = switching(&clean, 7);
    let (file, scheduled) = schedule_fig5();
    let sched = mse(&noisy, &scheduled)[2];
    let sets = fixed_sets(&clean, &file);
    let level = |name: &str| sets.iter().find(|(n, _)| n == name).unwrap().1;
    let factors = [0.995f32, 0.9975, 1.0, 1.0025, 1.005];
    // (column, best fixed set on this draw, how to set its two gains)
    type Set2 = fn(&mut BankConfig, f32, f32);
    let cases: [(usize, &str, Set2); 2] = [
        (0, "level 0.1", |c, a, b| {
            c.velocity.ave.k *= a;
            c.velocity.ave.gamma1 *= b;
        }),
        (5, "level 0.5", |c, a, b| {
            c.velocity.ed.lambda *= a;
            c.velocity.ed.alpha *= b;
        }),
    ];
    let mut spreads = [0.0f64; 2];
    for (j, (col, name, set)) in cases.into_iter().enumerate() {
        let base = level(name);
        let mut all = Vec::new();
        for a in factors {
            for b in factors {
                let mut cfg = base;
                set(&mut cfg, a, b);
                all.push(mse(&noisy, &fixed(cfg))[2][col]);
            }
        }
        let (lo, hi) = all
            .iter()
            .fold((f64::MAX, 0.0f64), |(lo, hi), &m| (lo.min(m), hi.max(m)));
        let at = mse(&noisy, &fixed(base))[2][col];
        spreads[j] = hi / lo - 1.0;
        let margin = sched[col] / at - 1.0;
        println!(
            "{}: {name} gains within 0.5 %: MSE {lo:.3}-{hi:.3} (spread {:.1} %); scheduled {:.3}, {name} {at:.3} (margin {:+.2} %)",
            NAMES[col],
            100.0 * spreads[j],
            sched[col],
            100.0 * margin
        );
        assert!(spreads[j] > 0.02, "{}: spread {}", NAMES[col], spreads[j]);
        assert!(spreads[j] > margin.abs(), "{}: margin {margin}", NAMES[col]);
    }
    // What an ED schedule could gain at best: per-half grid optima against the whole's.
    let draws: Vec<Vec<Sample>> = (101..=110).map(|d| switching(&clean, d)).collect();
    let grid: Vec<(f32, f32)> = (0..14)
        .flat_map(|i| {
            (0..14).map(move |j| {
                (
                    3.0 * 20f32.powf(i as f32 / 13.0),
                    100.0 * 40f32.powf(j as f32 / 13.0),
                )
            })
        })
        .collect();
    let base = level("level 0.5");
    let means: Vec<[f64; 3]> = std::thread::scope(|scope| {
        let jobs: Vec<_> = grid
            .chunks(grid.len().div_ceil(2))
            .map(|chunk| {
                let draws = &draws;
                scope.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(lambda, alpha)| {
                            let mut cfg = base;
                            cfg.velocity.ed = estimators::EdConfig { lambda, alpha };
                            let mut m = [0.0f64; 3];
                            for d in draws {
                                let r = mse(d, &fixed(cfg));
                                for (k, m) in m.iter_mut().enumerate() {
                                    *m += r[k][5] / draws.len() as f64;
                                }
                            }
                            m
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        jobs.into_iter().flat_map(|j| j.join().unwrap()).collect()
    });
    let best = |k: usize| means.iter().map(|m| m[k]).fold(f64::MAX, f64::min);
    // Halves of 999 and 1001 samples ([0, 9.99] s, [10, 20] s): weight them as mse_range does.
    let (n1, n2) = (999.0, 1001.0);
    let per_half = (n1 * best(0) + n2 * best(1)) / (n1 + n2);
    let gain = 1.0 - per_half / best(2);
    println!(
        "ED, draws 101-110: best fixed pair {:.3}, best pair per half {:.3} ({:.1} % below)",
        best(2),
        per_half,
        100.0 * gain
    );
    assert!(gain < 0.03 && gain < spreads[1], "ED schedule gain {gain}");
}

/// The same switch with six other noise draws (xoshiro256++ seeds 101-106): in each half,
/// every family of the scheduled bank is within 2x of the gains tuned for that half (tuned
/// once, as above). Guards the bumpless gain change (`estimators::Law::retune_state`): with the
/// states kept as they were, a retune between the 1 and 0.5 deg^2 levels made the tuned,
/// lightly damped ILO ring (10-20 s MSE 13,962 against 86.8 tuned, on draw 103). Measured
/// now: worst ratio 1.172 (the ILO on draw 103); the AVE at most 1.126 (draw 101, 10-20 s;
/// 1.263 before the schedule recorded the AVEs' switching gains, `ScheduleLevel::ave_deltahat`).
/// So item 3's 1.2x holds on these draws too, and is asserted; 2x would still catch ringing.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn scheduled_bank_does_not_ring_on_other_noise_draws() {
    let clean = clean();
    let (_, scheduled) = schedule_fig5();
    let (first, second) = tuned_for_the_halves(&clean);
    let mut worst = [0.0f64; estimators::FAMILY_COUNT];
    for seed in 101..=106 {
        let noisy = switching(&clean, seed);
        let sched = mse(&noisy, &scheduled);
        let t1 = mse(&noisy, &fixed(first));
        let t2 = mse(&noisy, &fixed(second));
        let ratios: Vec<String> = (0..estimators::FAMILY_COUNT)
            .map(|i| {
                let r = (sched[0][i] / t1[0][i]).max(sched[1][i] / t2[1][i]);
                worst[i] = worst[i].max(r);
                format!("{} {r:.3}", NAMES[i])
            })
            .collect();
        println!("draw {seed}: worst half ratio {}", ratios.join(", "));
    }
    for i in 0..estimators::FAMILY_COUNT {
        assert!(worst[i] <= 1.2, "{}: {}", NAMES[i], worst[i]);
    }
}

/// Item 3's "below every fixed gain set over the whole capture" on 40 other noise draws of the
/// same switch (xoshiro256++ seeds 101-140; the capture of
/// `scheduled_bank_follows_a_noise_switch` is draw 7): per family, on how many draws the
/// scheduled bank's 0-20 s velocity MSE is below every fixed set of [`fixed_sets`], and the
/// geometric mean over the draws of its ratio to the best fixed set of that draw.
///
/// Measured (docs/ADAPTIVE-RESULTS.md "Forty noise draws"): ILO1-3, the AD and the tracker below
/// every fixed set on 40 of 40 draws (geometric mean ratios 0.776, 0.790, 0.790); the AVE on
/// 32 (0.949; the best fixed set is the 0.1 level, whose AVE gains the 0.5 level now shares,
/// on all 40), **the ED on 5 (1.034)**. With bumpless gain changes instead of the warm start
/// (`replay_samples` 0): ILO 38 (0.819), AVE 24 (1.006). Before the schedule took each
/// level's best observer gains and recorded its switch points (`nav440 tune --schedule`,
/// docs/ADAPTIVE-RESULTS.md "Between the levels"): AVE 25 (0.951).
///
/// The AVE's figure depends on the switching gains the schedule records
/// (`ScheduleLevel::ave_deltahat`: a gain change sets `deltahat` to the new level's). The same
/// schedule without them (a gain change keeps `deltahat`): 22 draws, 1.036. With the switch
/// made at exactly 10 s (`AdaptiveBank::retune(0.5)`, no estimate), mean AVE MSE over the
/// draws in 10-11 s, 11-12 s, 12-20 s: 105.7, 121.0, 134.1 with the recorded `deltahat`;
/// 120.3, 156.3, 138.1 with the 0.01 level's kept; 120.2, 156.0, 138.0 for the 0.5 level's
/// gains throughout. (When the 0.5 level's AVE was its own tuned one, slow and lightly damped,
/// `k` 3.8 1/s, tuned with a `deltahat` of 5.7 deg/s, the kept `deltahat` cost 114.5 and 129.9
/// in the first two seconds against 88.8 and 68.3 set.) With the estimate, its delay adds to
/// this.
/// The ED's tuned gains hardly depend on the noise (its levels' fixed sets are within 2 % of
/// each other here), so a schedule can at best tie a fixed set; on one draw its MSE moves
/// with the gains by more than scheduling could gain
/// (`one_draw_margins_of_the_ave_and_ed_are_inside_their_gain_sensitivity`). The assertions hold
/// these figures (the ED's as a regression bound).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn scheduled_bank_against_every_fixed_set_on_forty_draws() {
    let clean = clean();
    let (file, scheduled) = schedule_fig5();
    // The same schedule with no switching gains recorded.
    let kept = {
        let mut f = file.clone();
        for l in &mut f.level {
            l.ave_deltahat = None;
        }
        EstimateOptions {
            schedule: Some(f.schedule(&BankConfig::NAV440).unwrap()),
            ..scheduled.clone()
        }
    };
    let sets = fixed_sets(&clean, &file);
    let draws = 101..=140u64;
    let n = draws.clone().count() as f64;
    let mut wins = [0u32; estimators::FAMILY_COUNT];
    let mut log_ratio = [0.0f64; estimators::FAMILY_COUNT];
    let (mut kept_wins, mut kept_log_ratio) = (0u32, 0.0f64);
    let mut best_count: Vec<[u32; estimators::FAMILY_COUNT]> =
        vec![[0; estimators::FAMILY_COUNT]; sets.len()];
    // The switch made exactly at 10 s: the AVE's transient after a gain change, with the
    // recorded switching gains and without, against the 0.5 level's gains throughout.
    let base = BankConfig {
        hold: file.hold().unwrap(),
        sample_period_s: 0.01,
        ..BankConfig::NAV440
    };
    let never = estimators::AdaptiveConfig {
        retune_ratio: f32::MAX,
        ..estimators::AdaptiveConfig::DEFAULT
    };
    let level_05 = sets.iter().find(|(name, _)| name == "level 0.5").unwrap().1;
    let windows = [(SWITCH_S, 11.0), (11.0, 12.0), (12.0, END_S)];
    let (mut at_switch, mut at_switch_kept, mut fixed_05) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
    let bumpless = estimators::AdaptiveConfig {
        replay_samples: 0,
        ..estimators::AdaptiveConfig::DEFAULT
    };
    let (mut bumpless_wins, mut bumpless_log_ratio) = (
        [0u32; estimators::FAMILY_COUNT],
        [0.0f64; estimators::FAMILY_COUNT],
    );
    // Acceleration: the series against the paper's AVE on the motion's rate (as `nav440
    // tune`), warm start over bumpless.
    let acc_ref = ave_on_rate(&clean, &REFERENCE_AVE, &scheduled).unwrap();
    let mut acc_log_ratio = [0.0f64; estimators::FAMILY_COUNT];
    for seed in draws {
        let noisy = switching(&clean, seed);
        let sched = mse(&noisy, &scheduled)[2];
        let sched_kept = mse(&noisy, &kept)[2][0];
        let fixed_mse: Vec<[f64; estimators::FAMILY_COUNT]> = sets
            .iter()
            .map(|(_, cfg)| mse(&noisy, &fixed(*cfg))[2])
            .collect();
        let mut best_of = [0.0f64; estimators::FAMILY_COUNT];
        for i in 0..estimators::FAMILY_COUNT {
            let (k, best) = fixed_mse
                .iter()
                .map(|m| m[i])
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            best_of[i] = best;
            best_count[k][i] += 1;
            if sched[i] < best {
                wins[i] += 1;
            }
            log_ratio[i] += (sched[i] / best).ln();
            if i == 0 {
                kept_wins += u32::from(sched_kept < best);
                kept_log_ratio += (sched_kept / best).ln();
            }
        }

        let hold = mse_over(&noisy, &fixed(level_05), &windows);
        let t: Vec<u64> = noisy.iter().map(|s| s.t_us).collect();
        let reference: Vec<f32> = noisy
            .iter()
            .map(|s| s.reference(Axis::Yaw).unwrap())
            .collect();
        for (opts, sums) in [(&scheduled, &mut at_switch), (&kept, &mut at_switch_kept)] {
            let levels = opts.schedule.as_ref().unwrap();
            let out = run_adaptive(&noisy, &base, levels, &never, Some(0.5));
            let est: Vec<f32> = out.iter().map(|o| o.velocities()[0]).collect();
            for (k, w) in windows.iter().enumerate() {
                sums[k] += mse_range(&t, &est, &reference, *w) / n;
            }
        }
        for k in 0..windows.len() {
            fixed_05[k] += hold[k][0] / n;
        }

        // The same schedule with bumpless gain changes (no replay) and with the warm start,
        // run directly: velocity against the best fixed set, acceleration warm / bumpless.
        let levels = scheduled.schedule.as_ref().unwrap();
        let mut acc = [[0.0f64; estimators::FAMILY_COUNT]; 2];
        for (j, cfg) in [bumpless, estimators::AdaptiveConfig::DEFAULT]
            .iter()
            .enumerate()
        {
            let out = run_adaptive(&noisy, &base, levels, cfg, None);
            for i in 0..estimators::FAMILY_COUNT {
                let a: Vec<f32> = out.iter().map(|o| o.accelerations()[i]).collect();
                acc[j][i] = mse_range(&t, &a, &acc_ref, (0.0, END_S));
                if j == 0 {
                    let e: Vec<f32> = out.iter().map(|o| o.velocities()[i]).collect();
                    let m = mse_range(&t, &e, &reference, (0.0, END_S));
                    bumpless_wins[i] += u32::from(m < best_of[i]);
                    bumpless_log_ratio[i] += (m / best_of[i]).ln();
                }
            }
        }
        for i in 0..estimators::FAMILY_COUNT {
            acc_log_ratio[i] += (acc[1][i] / acc[0][i]).ln();
        }
    }
    let gm = log_ratio.map(|l| (l / n).exp());
    let kept_gm = (kept_log_ratio / n).exp();
    println!("0-20 s velocity MSE, draws 101-140: scheduled below every fixed set / geometric mean ratio to the best fixed set");
    for i in 0..estimators::FAMILY_COUNT {
        let most = (0..sets.len()).max_by_key(|&k| best_count[k][i]).unwrap();
        println!(
            "  {:<4} {:>2} of {n} draws, {:.3} (best fixed set most often: {}, {} draws)",
            NAMES[i], wins[i], gm[i], sets[most].0, best_count[most][i]
        );
    }
    println!("  AVE without recorded switching gains: {kept_wins} of {n} draws, {kept_gm:.3}");
    let bumpless_gm = bumpless_log_ratio.map(|l| (l / n).exp());
    println!("bumpless gain changes instead of the warm start (replay_samples 0):");
    for i in 0..estimators::FAMILY_COUNT {
        println!(
            "  {:<4} {:>2} of {n} draws, {:.3}",
            NAMES[i], bumpless_wins[i], bumpless_gm[i]
        );
    }
    let acc_gm = acc_log_ratio.map(|l| (l / n).exp());
    println!("0-20 s acceleration MSE, warm start / bumpless, geometric mean over the draws: {acc_gm:.3?}");
    println!("AVE, mean velocity MSE over the draws in 10-11 s, 11-12 s, 12-20 s:");
    println!(
        "  0.01 level's gains, the 0.5 level's from exactly 10 s, deltahat set: {at_switch:.1?}"
    );
    println!(
        "  the same, deltahat kept (not recorded):                       {at_switch_kept:.1?}"
    );
    println!("  the 0.5 level's gains throughout:                             {fixed_05:.1?}");

    for i in [1, 2, 3, 4, 6] {
        assert!(
            wins[i] >= 38 && gm[i] < 0.85,
            "{}: {} draws, {}",
            NAMES[i],
            wins[i],
            gm[i]
        );
    }
    // The AVE: below the best fixed set on a typical draw, and clearly better than without
    // the recorded switching gains (measured 32 / 0.949 against 22 / 1.036).
    assert!(
        wins[0] >= 28 && gm[0] < 0.96,
        "AVE: {} draws, {}",
        wins[0],
        gm[0]
    );
    assert!(
        kept_gm > gm[0] + 0.04,
        "AVE: {kept_gm} without, {} with",
        gm[0]
    );
    // Not met (above): a regression bound on the measured 1.034.
    assert!(gm[5] < 1.04, "ED: {}", gm[5]);
    // The warm start is worth it: the AVE and the ILOs are further below the best fixed set
    // than with bumpless gain changes (measured 0.949 against 1.006 and 0.776 against 0.819);
    // the other families' figures do not move (their rows are linear and at equilibrium).
    assert!(
        gm[0] < bumpless_gm[0] - 0.01,
        "AVE {} {}",
        gm[0],
        bumpless_gm[0]
    );
    assert!(
        gm[1] < bumpless_gm[1] - 0.02,
        "ILO1 {} {}",
        gm[1],
        bumpless_gm[1]
    );
    // Acceleration: the replayed AVE-AVE and trackers gain (measured 0.966, 0.995), the
    // series kept bumpless do not move (replayed, the ILO-ILO was 1.07 over 20 draws).
    assert!(acc_gm[0] < 0.99, "AVE-AVE {acc_gm:?}");
    assert!(acc_gm.iter().all(|&r| r <= 1.0), "{acc_gm:?}");
    // The transient of a perfect switch: with the warm start the first two seconds after it
    // are as good as the 0.5 level's gains throughout (105.7 and 121.0 against 120.2 and
    // 156.0), and the recorded switching gains do not make them worse than the `deltahat`
    // the 0.01 level left (120.3, 156.3).
    assert!(at_switch[0] < 1.05 * fixed_05[0] && at_switch[1] < 1.05 * fixed_05[1]);
    assert!(at_switch[0] <= at_switch_kept[0] && at_switch[1] <= at_switch_kept[1]);
}

/// The yaw of `samples` through an `AdaptiveBank` built from `base`, `levels` and `cfg`: one
/// output per sample; with `switch_to`, the gains are set for that noise variance (deg^2) at
/// the first sample at or after the switch (`SWITCH_S`).
fn run_adaptive(
    samples: &[Sample],
    base: &BankConfig,
    levels: &estimators::GainSchedule,
    cfg: &estimators::AdaptiveConfig,
    switch_to: Option<f32>,
) -> Vec<estimators::PaperOutput> {
    let mut bank = estimators::AdaptiveBank::<f32>::new(base, levels, cfg).unwrap();
    let mut switched = false;
    samples
        .iter()
        .map(|s| {
            if let (Some(v), false) = (switch_to, switched) {
                if s.t_s() >= SWITCH_S {
                    bank.retune(v);
                    switched = true;
                }
            }
            bank.update(s.t_us, s.angles_deg()[2]).unwrap()
        })
        .collect()
}

/// The `--rust` output of the same run (`firmware-example/src/gains/schedule_fig5.rs`, compiled
/// into the firmware's bench) holds the same schedule as the TOML file, tuned at 0.01 s
/// (the fig5 capture's 100 Hz).
mod snippet {
    include!("../../firmware-example/src/gains/schedule_fig5.rs");
}

#[test]
fn rust_snippet_and_toml_hold_the_same_schedule() {
    let Loaded::Schedule(file) = gains::load_any(&data("gains/schedule_fig5.toml")).unwrap() else {
        panic!("not a schedule file");
    };
    assert_eq!(file.hold().unwrap(), Hold::Linear);
    assert_eq!(snippet::SCHEDULE_PERIOD_S, Some(0.01));
    assert_eq!(file.sample_period_s, Some(0.01));
    // The bundled capture's jerk and acceleration powers as `nav440 tune` measures them
    // (`motion_powers`); the jerk power is close to fig5's 3.68e6 over 1-30 s that
    // `AdaptiveProductConfig::START_JERK` records.
    assert_eq!(snippet::SCHEDULE_TUNED_JERK, Some(3_850_048.0));
    assert_eq!(file.tuned_jerk_power, Some(3_850_048.0));
    assert_eq!(snippet::SCHEDULE_TUNED_ACCELERATION, Some(142_703.13));
    assert_eq!(file.tuned_acceleration_power, Some(142_703.13));
    let captured = replay::read_samples(&data("fig5_a2_100hz.bin")).unwrap();
    assert_eq!(
        nav440_cli::tune::motion_powers(&[&captured], &EstimateOptions::default()).unwrap(),
        file.tuned_jerk_power.zip(file.tuned_acceleration_power)
    );
    assert_eq!(
        estimators::GainSchedule::new(&snippet::SCHEDULE)
            .unwrap()
            .with_sample_period(0.01)
            .unwrap()
            .with_tuned_jerk(3_850_048.0)
            .unwrap()
            .with_tuned_acceleration(142_703.13)
            .unwrap(),
        file.schedule(&BankConfig::NAV440).unwrap()
    );
    let levels: Vec<f32> = snippet::SCHEDULE.iter().map(|l| l.noise_var).collect();
    assert_eq!(levels, [0.001, 0.01, 0.1, 0.5, 1.0]);
    assert!(snippet::SCHEDULE.iter().all(|l| l.ave_deltahat.is_some()));
    // Every level but the last records where its observers move on.
    let n = snippet::SCHEDULE.len();
    assert!(snippet::SCHEDULE[..n - 1]
        .iter()
        .all(|l| l.switch_up.is_some()));
    assert!(snippet::SCHEDULE[n - 1].switch_up.is_none());
    // The committed snippet is what the generator writes from the TOML file.
    let committed = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../firmware-example/src/gains/schedule_fig5.rs"
    ))
    .unwrap();
    let what = "--schedule 0.001,0.01,0.1,0.5,1";
    assert_eq!(file.to_rust(what, &BankConfig::NAV440), committed);
    // Without recorded switching gains (a file written before they were): `None`, and no
    // import of `AveDeltahat` (it would be unused).
    let mut old = file.clone();
    for l in &mut old.level {
        l.ave_deltahat = None;
        l.switch_up = None;
    }
    old.tuned_jerk_power = None;
    let text = old.to_rust(what, &BankConfig::NAV440);
    assert!(text.contains("SCHEDULE_TUNED_JERK: Option<f32> = None;"));
    assert!(!text.contains("AveDeltahat") && text.contains("ave_deltahat: None,"));
    assert!(!text.contains("ObserverSwitch") && text.contains("switch_up: None,"));
    // And such a file (no `[level.switch_up]`) loads, switching at the midpoints.
    let toml = old.to_toml();
    assert!(!toml.contains("switch_up") && !toml.contains("tuned_jerk_power"));
    let reread: gains::ScheduleFile = toml::from_str(&toml).unwrap();
    assert_eq!(reread, old);
}

/// Each level of the bundled schedule records the AVEs' switching gains its gains were tuned
/// with (`ave_deltahat`): the mean of `deltahat` over the tuning run, what
/// `nav440_cli::tune::tuned_ave_deltahat` computes for the level's gains on the tuning capture
/// (fig5, 0-30 s, noise seeds 1-8 at the level's variance). Recomputed here from the file's
/// gains, it matches the file to f32 rounding. Property: it grows with the noise level (the
/// AVE's `|e|` does) for every stage.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn each_level_records_the_deltahat_it_was_tuned_with() {
    let (file, _) = schedule_fig5();
    let samples = replay::read_samples(&data("fig5_a2_100hz.bin")).unwrap();
    let opts = EstimateOptions::default();
    let mut prev = [0.0f32; 3];
    for (l, s) in file
        .level
        .iter()
        .zip(file.schedule(&BankConfig::NAV440).unwrap().levels())
    {
        let cfg = BankConfig {
            hold: file.hold().unwrap(),
            velocity: s.velocity,
            acceleration: s.acceleration,
            ..opts.bank_config_for(&samples)
        };
        let d = tuned_ave_deltahat(&samples, &opts, &cfg, l.noise_var, 8, (0.0, 30.0)).unwrap();
        let recorded = s.ave_deltahat.unwrap();
        println!("level {}: {d:?}", l.noise_var);
        let now = [d.velocity, d.acceleration[0], d.acceleration[1]];
        let was = [
            recorded.velocity,
            recorded.acceleration[0],
            recorded.acceleration[1],
        ];
        for k in 0..3 {
            assert!(
                (now[k] - was[k]).abs() <= 1e-5 * was[k],
                "{}: {now:?} {was:?}",
                l.noise_var
            );
            assert!(was[k] > prev[k], "{}: {was:?} after {prev:?}", l.noise_var);
        }
        prev = was;
    }
}

/// The schedule runs on the device for hours (checked over 24 h): every
/// level's AVE uses a bounded `deltahat` law (the leaky one `nav440 tune --schedule` tunes
/// with), and the adaptive bank with this schedule (`AdaptiveBank<f32>`, the firmware's
/// `adaptive-gains` bank) does not degrade over 3 h of a spin (rate 200 + 100 sin(0.4 pi t)
/// deg/s, `motion::ProfileKind::Spin`, the closed-form motion of `estimators/tests/long_run.rs`,
/// quantised to the A2 yaw LSB by `synth::angle_raw`) with N(0, 0.1 deg^2) yaw noise: every
/// velocity column's RMS error against the true rate in the third hour is within 5 % of the
/// first hour's (after its first second), and the AVE's within 10 % of the ILO1's every hour.
/// Measured: AVE 4.67, 4.65, 4.66 deg/s in hours 1-3. With the paper's law (the schedule
/// before `--schedule` switched the law,
/// `git show c8bcf79:host-tests/data/gains/schedule_fig5.rs`)
/// the AVE was 40.4, 33.4, 27.0 deg/s.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn the_schedule_runs_for_hours_without_degrading() {
    use estimators::{AdaptiveBank, AdaptiveConfig, DeltaMode, GainSchedule};
    for l in &snippet::SCHEDULE {
        for g in [&l.velocity, &l.acceleration] {
            assert!(
                matches!(
                    g.ave.delta,
                    DeltaMode::Leaky { .. } | DeltaMode::Bounded { .. }
                ),
                "level {}: {:?}",
                l.noise_var,
                g.ave.delta
            );
        }
    }
    let schedule = GainSchedule::new(&snippet::SCHEDULE).unwrap();
    let base = BankConfig {
        hold: Hold::Linear,
        ..BankConfig::NAV440
    };
    let mut bank = AdaptiveBank::<f32>::new(&base, &schedule, &AdaptiveConfig::DEFAULT).unwrap();
    let spin = Profile::new(ProfileKind::Spin, 3.0 * 3600.0, 0);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let noise = Normal::new(0.0, 0.1f64.sqrt()).unwrap();
    let hour = 360_000u64;
    let mut hourly = Vec::new();
    for h in 0..3 {
        let (mut sum, mut n) = ([0.0f64; estimators::FAMILY_COUNT], 0u32);
        for k in h * hour..(h + 1) * hour {
            let t = k as f64 * 0.01;
            let m = spin.at(t);
            let rate = m.rate_deg_s;
            let yaw = f64::from(angle_raw(m.yaw_deg + noise.sample(&mut rng))) * ANGLE_LSB_DEG;
            let out = bank.update(k * 10_000, yaw as f32).unwrap();
            if k >= 100 {
                for (s, v) in sum.iter_mut().zip(out.velocities()) {
                    *s += (f64::from(v) - rate).powi(2);
                }
                n += 1;
            }
        }
        hourly.push(sum.map(|s| (s / f64::from(n)).sqrt()));
        println!(
            "hour {}: RMS velocity error (deg/s) {:?}",
            h + 1,
            hourly[h as usize].map(|r| (r * 100.0).round() / 100.0)
        );
    }
    println!(
        "noise estimate {:?} deg^2, level {}, retunes {}",
        bank.noise_var(),
        bank.gain_level(),
        bank.retune_count()
    );
    // The AVE as accurate as the ILO within 10 % each hour (4.7 deg/s; the paper-law schedule's
    // AVE was at 40.4, 33.4, 27.0).
    for h in &hourly {
        assert!(h[0] <= 1.1 * h[1], "AVE {} vs ILO1 {} deg/s", h[0], h[1]);
    }
    for i in 0..estimators::FAMILY_COUNT {
        assert!(
            hourly[2][i] <= 1.05 * hourly[0][i],
            "{}: {:?}",
            NAMES[i],
            hourly.iter().map(|r| r[i]).collect::<Vec<_>>()
        );
    }
}

/// The 100 Hz schedule on a unit streaming at 20 Hz does not blow up on a retune: a 30 s
/// spin (`nav440 synth --profile spin --rate 20 --duration 30 --yaw-noise 0.5 --noise-seed 5`;
/// the spin is closed-form, its seed unused) run through the adaptive bank and through fixed
/// `BankConfig::NAV440`, velocity MSE against the motion's analytic rate over 2-30 s. The
/// AVE takes the nearer level's gains (`gamma1` 498 at the 0.5 level, 425,822 at the 0.1
/// level). Before the AVE's `retune_state` (`xhat = y`), and before the noise estimate
/// averaged at least 50 samples (then 10 terms per time constant at 20 Hz: it wandered
/// between 0.2 and 1.4 deg^2 and the bank retuned 13 times), the retune at 5.95 s from the
/// 0.68 to the 0.21 deg^2 level swung the AVE to 981 deg/s (true rate 295) and its MSE over
/// 6-8 s was 19,835 (deg/s)^2: the adaptive AVE was 5.74 x NAV440's over the capture (1716
/// against 299). Now every family is within 1.2 x NAV440's (measured: AVE 0.71; 1.02 before
/// the schedule recorded the AVEs' switching gains, 1.06 before the 50-sample floor; the ILO1
/// 0.05: past the schedule's top level on this spin, far gentler than fig5). The
/// schedule was tuned at 100 Hz and runs off its rate here on purpose (`nav440 estimate`
/// warns); at 10 Hz its AVE reaches 1.37-1.53 x NAV440's and its ILO1 on fig5 1.28 x, which
/// a schedule tuned at 10 Hz fixes (`a_schedule_tuned_at_10_hz_fits_10_hz`).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn the_100_hz_schedule_survives_retunes_at_20_hz() {
    let samples = synth_samples(ProfileKind::Spin, 20, 0.5);
    let (_, adaptive) = schedule_fig5();
    let run = |o: &EstimateOptions| mse_over(&samples, o, &[(2.0, 30.0)])[0];
    let (a, f) = (run(&adaptive), run(&fixed(BankConfig::NAV440)));
    let ratios: Vec<f64> = a.iter().zip(&f).map(|(a, f)| a / f).collect();
    println!(
        "20 Hz spin, 0.5 deg^2: adaptive / NAV440 velocity MSE {ratios:.2?} (adaptive {a:.1?})"
    );
    for (i, r) in ratios.iter().enumerate() {
        assert!(*r <= 1.2, "{}: {r:.2} x NAV440", NAMES[i]);
    }
}

/// A schedule tuned at the unit's rate is the remedy for a low rate: at 10 Hz with 0.5 deg^2
/// the 100 Hz schedule's AVE reaches 1.37-1.53 x fixed `BankConfig::NAV440`'s and its ILO1 on
/// fig5 1.28 x (the adaptive bank runs the schedule's 0.5 level there: its gains, tuned at
/// 100 Hz, not the noise estimate, are the cause), while `data/gains/schedule_fig5_10hz.toml`, tuned at 10 Hz
/// on another fig5 motion (`nav440 synth --profile fig5 --rate 10 --duration 35 --seed 3 -o
/// fig5_10hz.bin`, then `nav440 tune fig5_10hz.bin --schedule 0.001,0.01,0.1,0.5,1 --seeds 8
/// -o schedule_fig5_10hz.toml`: 7.1 min), keeps them within 1.1x (measured: 0.17 to 1.08) on
/// the fig5 and spin motions of seed 21 at 10 Hz, 0.01 and 0.5 deg^2 (noise seed 5), and is
/// better than the 100 Hz schedule in each of those AVE and ILO1 cells at 0.5 deg^2 but the
/// spin's ILO1: on that motion, far gentler than fig5, the 100 Hz schedule (which records its
/// tuning motion's jerk; the 10 Hz one does not) runs ILO1 past its top level, whose rule
/// places the poles for the unit's own period (0.69x `NAV440`'s, against the 10 Hz
/// schedule's 1.08x).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test schedule"
)]
fn a_schedule_tuned_at_10_hz_fits_10_hz() {
    let (_, at_100) = schedule_fig5();
    let (file, at_10) = schedule("gains/schedule_fig5_10hz.toml");
    assert_eq!(file.sample_period_s, Some(0.1));
    for profile in [ProfileKind::Fig5, ProfileKind::Spin] {
        for var_deg2 in [0.01, 0.5] {
            let samples = synth_samples(profile, 10, var_deg2);
            let run = |o: &EstimateOptions| mse_over(&samples, o, &[(2.0, 30.0)])[0];
            let f = run(&fixed(BankConfig::NAV440));
            let (a10, a100) = (run(&at_10), run(&at_100));
            println!(
                "10 Hz {profile:?}, {var_deg2} deg^2, over NAV440: AVE {:.2} ILO1 {:.2} (the 100 Hz schedule: {:.2} {:.2})",
                a10[0] / f[0],
                a10[1] / f[1],
                a100[0] / f[0],
                a100[1] / f[1]
            );
            for i in [0, 1] {
                assert!(a10[i] <= 1.1 * f[i], "{}: {} vs {}", NAMES[i], a10[i], f[i]);
                if var_deg2 == 0.5 && !(profile == ProfileKind::Spin && i == 1) {
                    assert!(a10[i] < a100[i], "{}: {} vs {}", NAMES[i], a10[i], a100[i]);
                }
            }
        }
    }
}

/// Every level of the bundled 100 Hz schedule reads a constant rate within 0.1 %
/// (`tune::holds_constant_rate`, what `nav440 tune --schedule` gives a level), and the bank at
/// each level's gains, fed a 200 deg/s rotation at 100 Hz for 30 s, settles its ILO1-3
/// velocity within 0.1 % of it: the formula (`IloConfig::constant_rate_gain`) checked by
/// simulation. The 10 Hz schedule's ILOs read it 0.15 to 0.95 % low at every level (no level
/// qualifies, so the tuner leaves them: docs/ADAPTIVE-GAINS.md).
#[test]
fn every_level_of_the_100_hz_schedule_holds_a_constant_rate() {
    use nav440_cli::tune::{constant_rate_gain, holds_constant_rate};
    let (file, _) = schedule_fig5();
    let base = BankConfig::NAV440;
    for level in &file.level {
        for (col, name) in NAMES.iter().enumerate() {
            assert!(
                holds_constant_rate(&level.velocity, col),
                "level {} {name}",
                level.noise_var
            );
        }
        let cfg = BankConfig {
            velocity: level.velocity.apply(base.velocity),
            acceleration: level.acceleration.apply(base.acceleration),
            ..base
        };
        let mut bank = estimators::PaperBank::<f32>::new(&cfg).unwrap();
        let mut out = None;
        for k in 0..3000u64 {
            let deg = (200.0 * k as f64 * 0.01 + 180.0).rem_euclid(360.0) - 180.0;
            out = Some(bank.update(k * 10_000, deg as f32).unwrap());
        }
        let v = out.unwrap().velocities();
        for (v, name) in v.iter().zip(NAMES).skip(1).take(3) {
            assert!(
                (f64::from(*v) / 200.0 - 1.0).abs() < 1e-3,
                "level {} {name}: {v}",
                level.noise_var
            );
        }
    }
    let (slow, _) = schedule("gains/schedule_fig5_10hz.toml");
    for level in &slow.level {
        for col in 1..=3 {
            let short = 1.0 - constant_rate_gain(&level.velocity, col);
            assert!(
                short > 0.0015 && short < 0.0095,
                "10 Hz level {}: {short}",
                level.noise_var
            );
        }
    }
}
