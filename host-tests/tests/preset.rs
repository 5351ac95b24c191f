//! The shipped preset `BankConfig::NAV440` (docs/PRESETS.md).
//!
//! * `print_nav440_preset` (ignored; how the preset was produced):
//!   `cargo test --release -p host-tests --test preset -- --ignored --nocapture print_nav440_preset`
//!   tunes one set of gains for a family of synthetic motions and noise levels ([`family`]:
//!   `nav440 synth` motions, none of them a bundled capture with its noise) and prints the
//!   rate tables of `estimators/src/rates.rs` with these gains as their first band
//!   (`nav440_cli::rust_literal::write_rate_tables`), to paste there.
//! * `nav440_beats_paper_on_the_bundled_captures_but_for_the_listed_cells`: on the bundled
//!   captures, at the paper's two noise levels, the MSE of every column (7 velocity, 7
//!   acceleration) with `BankConfig::NAV440` is below the MSE with `BankConfig::PAPER` (both
//!   measured as `nav440 tune` measures its "before"/"after": through the whole bank, mean of
//!   3 noise seeds, `nav440_cli::tune::bank_mse`), but for the 5 listed cells ([`EXCEPTIONS`]:
//!   4 of them the AD, for which no gain beats the paper's everywhere, shown by
//!   `no_single_ad_t_beats_the_paper_on_every_bundled_capture`), held to 1.02 x PAPER. The
//!   references are independent of the code under test: the motion's analytic rate, and the
//!   paper's AVE on that rate for acceleration.

use estimators::{BankConfig, Hold};
use host_tests::data;
use nav440_cli::motion::ProfileKind;
use nav440_cli::optim::Method;
use nav440_cli::paper::COLUMNS;
use nav440_cli::replay;
use nav440_cli::rust_literal::write_rate_tables;
use nav440_cli::tune::{bank_mse, synth_family, tune_preset, PresetCase};

/// The tuning family: synthetic motions (fig5 shapes of seeds 11-14, none of them a bundled
/// capture's seed, at 100, 50, 25 and 20 Hz; the closed-form spin and sin5 motions at rates
/// no bundled capture has: spin at 25 Hz, sin5 at 100 Hz, noise seed 1; and, since the spin
/// at 20 Hz is sampled more coarsely relative to its motion than any of those, spin at 20 Hz
/// (16 s) and sin5 at 25 Hz (8 s) with noise seed 11, A2 packets), each at 0.01, 0.1 and
/// 0.5 deg^2, MSE over the whole capture: 24 cases. The spin and sin5 motions have no shape
/// seed (closed form), so the last two are the motions of two bundled captures at their
/// rates, with other packets, durations and noise draws (the bundled scores use noise seeds
/// 1-3).
fn family() -> Vec<PresetCase> {
    let motions = [
        (ProfileKind::Fig5, 11, 100, 20.0),
        (ProfileKind::Fig5, 12, 50, 20.0),
        (ProfileKind::Fig5, 13, 25, 20.0),
        (ProfileKind::Fig5, 14, 20, 20.0),
        (ProfileKind::Spin, 1, 25, 16.0),
        (ProfileKind::Sin5, 1, 100, 8.0),
        (ProfileKind::Spin, 11, 20, 16.0),
        (ProfileKind::Sin5, 11, 25, 8.0),
    ];
    synth_family(&motions, &[0.01, 0.1, 0.5]).unwrap()
}

#[test]
#[ignore = "produces the NAV440 preset (minutes, release): cargo test --release -p host-tests --test preset -- --ignored --nocapture"]
fn print_nav440_preset() {
    let cases = family();
    let t = std::time::Instant::now();
    // Each family minimises its worst MSE ratio to the paper's preset over the cases; where
    // that cannot beat it in every case, a second search counts every case (`tune_preset`).
    let (gains, cost, report) = tune_preset(
        &cases,
        &BankConfig::DEFAULT,
        Some(&BankConfig::PAPER),
        Method::Search,
        None,
    )
    .unwrap();
    let cfg = gains.apply(BankConfig::DEFAULT);
    println!(
        "tuned on {} cases in {:.0} s; objective (worst MSE ratio to PAPER over the cases x geometric mean of the ratios^0.2, +1 if some case is not below PAPER; where the second, hinge search was kept: 1 + its hinge sum):",
        cases.len(),
        t.elapsed().as_secs_f64()
    );
    println!("  velocity     {:?}", cost[0]);
    println!("  acceleration {:?}", cost[1]);
    print!("{report}");
    let mut bands = BankConfig::NAV440_RATES;
    bands[0].velocity = cfg.velocity;
    bands[0].acceleration = cfg.acceleration;
    let mut tables = String::new();
    write_rate_tables(&bands, &mut tables).unwrap();
    println!("{tables}");
}

/// The bundled captures scored (the corrupt and time-fault captures are fault-handling tests:
/// a 5 s piece of fig5, and a capture without a motion reference of its own).
const BUNDLED: [(&str, f64); 4] = [
    ("fig5_a2_100hz.bin", 30.0),
    ("sin5_a1_50hz.bin", 10.0),
    ("sin5_a2_25hz_weekwrap.bin", 10.0),
    ("spin_n1_20hz.bin", 20.0),
];

/// Capture, noise variance, MSE per column with PAPER, with NAV440.
type Scores = (
    String,
    f64,
    [[f64; estimators::FAMILY_COUNT]; 2],
    [[f64; estimators::FAMILY_COUNT]; 2],
);

/// An MSE as the tables of docs/CALIBRATION.md print it: 4 significant digits below 1e5,
/// else 3 in exponent form.
fn fmt(v: f64) -> String {
    if v >= 1e5 {
        let e = v.log10().floor() as i32;
        format!("{:.2}e+{e:02}", v / 10f64.powi(e))
    } else if v >= 1000.0 {
        format!("{v:.0}")
    } else if v >= 100.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// Per capture and noise level: the MSE of every column with PAPER and with NAV440.
fn nav440_vs_paper() -> Vec<Scores> {
    let mut out = Vec::new();
    for (file, window) in BUNDLED {
        let samples = replay::read_samples(&data(file)).unwrap();
        for noise_var in [0.01, 0.5] {
            let p = bank_mse(&samples, BankConfig::PAPER, noise_var, 3, (0.0, window)).unwrap();
            let n = bank_mse(&samples, BankConfig::NAV440, noise_var, 3, (0.0, window)).unwrap();
            out.push((file.to_string(), noise_var, [p.0, p.1], [n.0, n.1]));
        }
    }
    out
}

/// Where NAV440 does not beat PAPER (capture, noise variance, half 0 velocity / 1
/// acceleration, column), each held to at most [`EXCEPTION_BOUND`] x PAPER; every other cell
/// must be strictly below PAPER.
///
/// * The AD (4 cells): no AD gain beats the paper's on every bundled capture (the AD has one
///   gain, T; see [`no_single_ad_t_beats_the_paper_on_every_bundled_capture`]). The preset
///   has T = 0.011 s for the velocity AD (+1.0 % on sin5 at 25 Hz and +0.006 % on the spin at
///   0.01 deg^2, below PAPER on the other six cells) and T = 0.0993 s for AD-AD (+0.7 % and
///   +1.4 % on the spin, below PAPER on the other six).
/// * The ILO3-ILO3 on the spin at 0.01 deg^2 (+0.35 %): its training objective could not beat
///   PAPER in every one of the 24 tuning cases either (docs/CALIBRATION.md).
const EXCEPTIONS: [(&str, f64, usize, usize); 5] = [
    ("sin5_a2_25hz_weekwrap.bin", 0.01, 0, 4),
    ("spin_n1_20hz.bin", 0.01, 0, 4),
    ("spin_n1_20hz.bin", 0.01, 1, 3),
    ("spin_n1_20hz.bin", 0.01, 1, 4),
    ("spin_n1_20hz.bin", 0.5, 1, 4),
];

/// How far a listed cell may be above PAPER: 2 % (measured at most +1.05 %, the AD velocity on
/// sin5 at 25 Hz).
const EXCEPTION_BOUND: f64 = 1.02;

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test preset"
)]
fn nav440_beats_paper_on_the_bundled_captures_but_for_the_listed_cells() {
    assert_eq!(BankConfig::NAV440.hold, Hold::Linear);
    assert_eq!(BankConfig::NAV440.h, BankConfig::PAPER.h);
    let names = COLUMNS;
    let mut failures = Vec::new();
    let (mut wins, mut cells, mut log_ratio) = (0, 0, 0.0);
    let scores = nav440_vs_paper();
    for (file, var, paper, nav) in scores.clone() {
        for half in 0..2 {
            let row: Vec<String> = (0..estimators::FAMILY_COUNT)
                .map(|i| format!("{} {:.4} -> {:.4}", names[i], paper[half][i], nav[half][i]))
                .collect();
            println!(
                "{file} {var} deg^2 {}: {}",
                ["velocity", "acceleration"][half],
                row.join(", ")
            );
            for i in 0..estimators::FAMILY_COUNT {
                let (n, p) = (nav[half][i], paper[half][i]);
                cells += 1;
                log_ratio += (n / p).ln();
                if n < p {
                    wins += 1;
                }
                let listed = EXCEPTIONS.contains(&(file.as_str(), var, half, i));
                let ok = if listed {
                    n <= EXCEPTION_BOUND * p
                } else {
                    n < p
                };
                if !ok {
                    failures.push(format!(
                        "{file} {var} {} {}: NAV440 {n} vs PAPER {p} (listed: {listed})",
                        ["velocity", "acceleration"][half],
                        names[i],
                    ));
                }
            }
        }
    }
    for (half, unit) in ["velocity, MSE (deg/s)^2", "acceleration, MSE (deg/s^2)^2"]
        .iter()
        .enumerate()
    {
        println!("\n{unit}, PAPER -> NAV440 (markdown):");
        for (file, var, paper, nav) in &scores {
            let cells: Vec<String> = (0..estimators::FAMILY_COUNT)
                .map(|i| {
                    let c = format!("{} -> {}", fmt(paper[half][i]), fmt(nav[half][i]));
                    if nav[half][i] < paper[half][i] {
                        c
                    } else {
                        format!("**{c}**")
                    }
                })
                .collect();
            let name = file.trim_end_matches(".bin");
            println!("| {name} | {var} | {} |", cells.join(" | "));
        }
    }
    let gm = (log_ratio / f64::from(cells)).exp();
    println!(
        "NAV440 below PAPER in {wins} of {cells} cells; geometric mean of NAV440/PAPER {gm:.3}"
    );
    assert!(failures.is_empty(), "{failures:#?}");
    assert_eq!(wins, cells - EXCEPTIONS.len() as u32);
}

/// Why the AD cells are exceptions: the AD has one gain per half, T (the bank runs both stages
/// of AD-AD with the same T), and no T beats the paper's (velocity 0.01 s, acceleration 0.1 s)
/// on every bundled cell. Measured (ratio to PAPER; docs/CALIBRATION.md): velocity, T below
/// 0.01 s loses on fig5 (T = 0.009: 1.09 at 0.01 deg^2, 1.16 at 0.5), above it on
/// sin5 at 25 Hz and the spin at 0.01 deg^2 (T = 0.011: 1.010 and 1.0001); AD-AD, T below 0.1 s
/// loses on the spin (T = 0.099: 1.010 and 1.021), above it on every other capture (T = 0.101:
/// 1.007 to 1.016). Checked on a log grid of T from 1 ms to 1 s and next to the paper's T
/// (+-0.1 %, +-1 %): for every T some cell of each half is not below PAPER. For the velocity
/// AD it holds even per capture on sin5 at 25 Hz and the spin at 20 Hz (T = 0.0099: 1.0020
/// and 1.0008 at 0.5 deg^2; T = 0.0101: 1.0009 and 1.0000 at 0.01 deg^2), so no gain per
/// packet rate could beat the paper's there either.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test preset"
)]
fn no_single_ad_t_beats_the_paper_on_every_bundled_capture() {
    let caps: Vec<_> = BUNDLED
        .iter()
        .map(|(f, w)| (replay::read_samples(&data(f)).unwrap(), *w))
        .collect();
    let score = |cfg: BankConfig| -> Vec<(
        [f64; estimators::FAMILY_COUNT],
        [f64; estimators::FAMILY_COUNT],
    )> {
        let mut out = Vec::new();
        for (s, w) in &caps {
            for noise_var in [0.01, 0.5] {
                out.push(bank_mse(s, cfg, noise_var, 3, (0.0, *w)).unwrap());
            }
        }
        out
    };
    let paper = score(BankConfig::PAPER);
    let (tv, ta) = (
        BankConfig::PAPER.velocity.ad_t,
        BankConfig::PAPER.acceleration.ad_t,
    );
    let mut ts: Vec<f32> = (0..=24)
        .map(|k| 10f32.powf(-3.0 + 3.0 * k as f32 / 24.0))
        .collect();
    for t in [tv, ta] {
        ts.extend([0.99, 0.999, 1.001, 1.01].map(|f| t * f));
    }
    for t in ts {
        let mut cfg = BankConfig::PAPER;
        cfg.velocity.ad_t = t;
        cfg.acceleration.ad_t = t;
        let s = score(cfg);
        let worst = |half: usize| {
            s.iter()
                .zip(&paper)
                .map(|(n, p)| {
                    let (n, p) = if half == 0 {
                        (n.0[4], p.0[4])
                    } else {
                        (n.1[4], p.1[4])
                    };
                    n / p
                })
                .fold(0.0f64, f64::max)
        };
        let (wv, wa) = (worst(0), worst(1));
        // Per capture (velocity AD): the worse of its two noise levels. On sin5 at 25 Hz and
        // on the spin at 20 Hz no T beats the paper's at both levels (the 0.01 deg^2 cell
        // wants a shorter T, the 0.5 one a longer): no gain per packet rate (a rate entry of
        // `BankConfig::NAV440_RATES`) or per capture could.
        let per_capture: Vec<f64> = s
            .chunks(2)
            .zip(paper.chunks(2))
            .map(|(n, p)| (n[0].0[4] / p[0].0[4]).max(n[1].0[4] / p[1].0[4]))
            .collect();
        println!(
            "AD T = {t}: worst ratio to PAPER, velocity {wv:.5}, AD-AD {wa:.5}; velocity per capture {per_capture:.5?}"
        );
        assert!(wv >= 1.0 && wa >= 1.0, "T = {t}: {wv} {wa}");
        assert!(
            per_capture[2] >= 1.0 && per_capture[3] >= 1.0,
            "T = {t}: {per_capture:?}"
        );
    }
}
