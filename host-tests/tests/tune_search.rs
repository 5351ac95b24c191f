//! `nav440 tune`'s global search against its reference, the exhaustive log grid
//! (docs/CALIBRATION.md): on slices of the bundled captures, for every
//! family of both bank halves, the MSE the search reaches is within 5 % of the best point of
//! the grid (it is usually below it: the grid is coarse, the search continues from it).
//!
//! The grid's MSE is an independent reference: each of its points is the same objective
//! evaluated at fixed, log-spaced gains, no search involved. Slices are short (first 4 s, one
//! seed) and the grid has 8 points per gain so the test runs in seconds in release mode:
//! `cargo test --release -p host-tests --test tune_search` (in `cargo xtask ci`'s release list).

use estimators::Hold;
use host_tests::data;
use nav440_cli::optim::Method;
use nav440_cli::paper::COLUMNS;
use nav440_cli::replay::{self, EstimateOptions};
use nav440_cli::tune::{tune_with, Families, TuneSpec};

fn run(
    file: &str,
    slice_s: f64,
    noise_var: f64,
    hold: Hold,
    method: Method,
) -> [[f64; estimators::FAMILY_COUNT]; 2] {
    let samples = replay::read_samples(&data(file)).unwrap();
    let end = (slice_s * 1e6) as u64;
    let samples: Vec<_> = samples.into_iter().filter(|s| s.t_us <= end).collect();
    let res = tune_with(
        &samples,
        &EstimateOptions::default(),
        &TuneSpec {
            noise_var,
            seeds: 1,
            train: (0.0, slice_s),
            test: None,
            method,
            holds: vec![hold],
            families: Families::ALL,
        },
    )
    .unwrap();
    assert_eq!(res.runs.len(), 1);
    res.runs[0].cost
}

fn check(file: &str, slice_s: f64, noise_var: f64, hold: Hold) {
    let search = run(file, slice_s, noise_var, hold, Method::Search);
    let grid = run(
        file,
        slice_s,
        noise_var,
        hold,
        Method::Exhaustive { points: 8 },
    );
    let names = COLUMNS;
    for half in 0..2 {
        for i in 0..estimators::FAMILY_COUNT {
            let (s, g) = (search[half][i], grid[half][i]);
            assert!(
                g.is_finite() && s.is_finite() && s <= 1.05 * g,
                "{file} var {noise_var} {hold:?} half {half} {}: search {s} vs grid {g}",
                names[i]
            );
        }
    }
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test tune_search"
)]
fn search_is_within_5_percent_of_the_exhaustive_grid_on_fig5() {
    check("fig5_a2_100hz.bin", 4.0, 0.01, Hold::Linear);
    check("fig5_a2_100hz.bin", 4.0, 0.5, Hold::ZeroOrder);
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p host-tests --test tune_search"
)]
fn search_is_within_5_percent_of_the_exhaustive_grid_on_sin5_and_spin() {
    check("sin5_a1_50hz.bin", 4.0, 0.1, Hold::Linear);
    check("spin_n1_20hz.bin", 4.0, 0.1, Hold::Linear);
}
