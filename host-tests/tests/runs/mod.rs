//! Runs of the bank through `nav440 estimate`'s replay, shared by the tests that score the
//! noise schedule (`schedule.rs`, `motion_family.rs`).

use estimators::BankConfig;
use host_tests::data;
use nav440_cli::gains::{self, Loaded};
use nav440_cli::replay::{self, Axis, EstimateOptions, Sample};
use nav440_cli::tune::mse_range;

/// Velocity MSE per family over each range (s), against the motion's analytic rate.
pub fn mse_over(
    samples: &[Sample],
    opts: &EstimateOptions,
    ranges: &[(f64, f64)],
) -> Vec<[f64; estimators::FAMILY_COUNT]> {
    mse_over_axis(samples, opts, ranges, Axis::Yaw)
}

/// [`mse_over`] of the estimates about `axis` (which `opts` must estimate).
pub fn mse_over_axis(
    samples: &[Sample],
    opts: &EstimateOptions,
    ranges: &[(f64, f64)],
    axis: Axis,
) -> Vec<[f64; estimators::FAMILY_COUNT]> {
    let (rows, rejected) = replay::estimate(samples, opts).unwrap();
    assert_eq!(rejected, 0);
    let t: Vec<u64> = rows.iter().map(|r| r.t_us).collect();
    let reference: Vec<f32> = rows
        .iter()
        .map(|r| r.axis(axis).unwrap().reference_deg_s.unwrap())
        .collect();
    let velocities: Vec<[f32; estimators::FAMILY_COUNT]> = rows
        .iter()
        .map(|r| r.axis(axis).unwrap().out.velocities())
        .collect();
    ranges
        .iter()
        .map(|range| {
            let mut o = [0.0; estimators::FAMILY_COUNT];
            for (i, o) in o.iter_mut().enumerate() {
                let est: Vec<f32> = velocities.iter().map(|v| v[i]).collect();
                *o = mse_range(&t, &est, &reference, *range);
            }
            o
        })
        .collect()
}

/// The schedule file `data/NAME` and the options that run it (`nav440 estimate FILE --gains
/// NAME`).
pub fn schedule(name: &str) -> (gains::ScheduleFile, EstimateOptions) {
    let Loaded::Schedule(file) = gains::load_any(&data(name)).unwrap() else {
        panic!("not a schedule file");
    };
    options_of(file)
}

/// [`schedule`] without the file's `tuned_jerk_power`: the gains follow the noise alone.
#[allow(dead_code)] // not every test that includes this module uses it
pub fn schedule_by_noise(name: &str) -> (gains::ScheduleFile, EstimateOptions) {
    let (mut file, _) = schedule(name);
    file.tuned_jerk_power = None;
    options_of(file)
}

/// The options that run the schedule `file`.
fn options_of(file: gains::ScheduleFile) -> (gains::ScheduleFile, EstimateOptions) {
    let opts = EstimateOptions {
        hold: file.hold().unwrap(),
        config: Some(BankConfig::NAV440),
        schedule: Some(file.schedule(&BankConfig::NAV440).unwrap()),
        ..Default::default()
    };
    (file, opts)
}
