//! Replay of a recorded byte stream through `nav440_pipeline` (the firmware's pipeline):
//! parser -> attitude packets -> BIT check -> timed samples -> estimator banks -> CSV.
//!
//! What `nav440 stats|decode|estimate`, the paper protocol, the tuner, the plots and the
//! integration tests all call.

mod capture;
pub use capture::*;
mod stats;
pub use stats::*;
mod samples;
pub use samples::*;
mod noise;
pub use noise::*;
mod options;
pub use options::*;
mod bank;
pub use bank::*;
mod csv;
pub use csv::*;

use crate::error::{Error, Result};
use estimators::{
    BankConfig, EstimatorBank, EstimatorOutput, Fx, GainSchedule, Hold, PaperBank, PaperOutput,
    ProductBank, ProductOutput, SampleError,
};
pub use nav440_pipeline::bit::BitCounts;
use nav440_pipeline::period::PeriodEstimator;
pub use nav440_pipeline::period::WARMUP_SAMPLES;
use nav440_pipeline::{
    adaptive_axis_bank, adaptive_product_axis_bank, axis_bank, self_tuning_product_axis_bank,
    Frontend, Pipeline,
};
use nav440_proto::Parser;
pub use nav440_proto::TimeFaults;
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::Path;

pub use nav440_pipeline::{Axes, Axis, AxisRow, RateColumn, Rejections, Row, Sample};

/// What a run of the bank gives: rows and the counts of samples it did not turn into rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// One row per accepted sample.
    pub rows: Vec<Row>,
    /// Samples the bank rejected (non-finite or out-of-range angle).
    pub rejected: usize,
    /// Gaps longer than the gap rule (`BankConfig::max_gap_periods` nominal periods): the bank
    /// re-initialised there (`PaperBank::reinit_count`).
    pub gaps: u32,
}

/// Runs the estimator bank over `samples`. A sample the bank rejects (non-finite or
/// out-of-range angle) yields no row; the count of those is returned too.
pub fn estimate(samples: &[Sample], opts: &EstimateOptions) -> Result<(Vec<Row>, usize)> {
    estimate_report(samples, opts).map(|e| (e.rows, e.rejected))
}

/// [`estimate`] with the bank's gap count.
pub fn estimate_report(samples: &[Sample], opts: &EstimateOptions) -> Result<Estimate> {
    let (rows, summary) = estimate_rows(samples, opts)?;
    Ok(Estimate {
        rows,
        rejected: usize::try_from(summary.rejected.total()).unwrap_or(usize::MAX),
        gaps: summary.gaps,
    })
}

/// [`estimate`] with the rejected samples counted by reason.
pub fn estimate_rows(
    samples: &[Sample],
    opts: &EstimateOptions,
) -> Result<(Vec<Row>, EstimationSummary)> {
    let mut rows = Vec::with_capacity(samples.len());
    let mut est = Estimation::new(opts)?;
    let mut keep = |r: Row| {
        rows.push(r);
        Ok(())
    };
    for &s in samples {
        est.push(s, &mut keep)?;
    }
    let summary = est.finish(&mut keep)?;
    Ok((rows, summary))
}

/// The one-line `nav440 estimate` warning for time faults and gaps (`None` when there were
/// none): `time faults: impossible=N bad_backward=N bad_forward=N backward_jumps=N
/// kind_switches=N other_kind=N duplicates=N gaps=N`.
pub fn fault_warning(f: &TimeFaults, gaps: u32) -> Option<String> {
    (f.any() || f.duplicates > 0 || gaps > 0).then(|| {
        format!(
            "time faults: impossible={} bad_backward={} bad_forward={} backward_jumps={} kind_switches={} other_kind={} duplicates={} gaps={}",
            f.impossible, f.bad_backward, f.bad_forward, f.backward_jumps, f.kind_switches, f.other_kind, f.duplicates, gaps
        )
    })
}

/// The one-line warning for samples not estimated because of their BIT word (`None` when
/// there were none): `BIT failure: N samples not estimated (masterFail; ...)`.
pub fn bit_warning(b: &BitCounts) -> Option<String> {
    let mut s = String::new();
    b.write_warning(&mut s).ok()?;
    (!s.is_empty()).then_some(s)
}

/// The end of an [`Estimation`]: the samples that gave no row, and the gaps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EstimationSummary {
    /// Samples the bank rejected, by reason.
    pub rejected: Rejections,
    /// Gaps longer than the gap rule, where the bank re-initialised (new epochs not counted).
    pub gaps: u32,
    /// Samples near gimbal lock whose roll and yaw were not estimated
    /// (`nav440_pipeline::Counters::near_lock`).
    pub near_lock: u64,
    /// Returns from gimbal lock, where the roll and yaw banks restarted.
    pub lock_passes: u32,
    /// New epochs at another nominal sample period, where the banks were rebuilt
    /// (`nav440_pipeline::Counters::period_changes`).
    pub period_changes: u32,
}

impl EstimationSummary {
    /// The summary of the back end's counters.
    pub fn of(c: &nav440_pipeline::Counters) -> Self {
        Self {
            rejected: c.rejected,
            gaps: c.gaps,
            near_lock: c.near_lock,
            lock_passes: c.lock_passes,
            period_changes: c.period_changes,
        }
    }
}

/// The one-line warning for samples near gimbal lock (`None` when there were none).
pub fn lock_warning(near_lock: u64, passes: u32) -> Option<String> {
    (near_lock > 0).then(|| {
        format!(
            "{near_lock} samples with |pitch| >= {} deg (gimbal lock): roll and yaw are not estimated there (empty fields) and their banks restart after each of the {passes} returns below it",
            nav440_pipeline::euler::PITCH_LIMIT_DEG
        )
    })
}

/// What [`estimate_stream`] reports besides the CSV.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamReport {
    /// Rejected samples and gaps.
    pub summary: EstimationSummary,
    /// Time-stamp faults met by the sample extraction.
    pub faults: TimeFaults,
    /// Samples not estimated because their BIT word flags a failure.
    pub bit: BitCounts,
    /// With a gain schedule tuned at another sample period than the capture's
    /// (`estimators::GainSchedule::fits_period`): (the schedule's period, the bank's), us.
    pub schedule_misfit_us: Option<(u64, u64)>,
    /// Bytes at the end of the input that did not complete a frame
    /// (`FrontCounters::end_dropped_bytes`).
    pub end_dropped_bytes: u64,
}

impl StreamReport {
    /// The warning lines `nav440 estimate` (and `nav440 live`) print on stderr: BIT failures,
    /// rejected samples, then time faults and gaps (none when everything was clean).
    pub fn warnings(&self) -> impl Iterator<Item = String> {
        bit_warning(&self.bit)
            .into_iter()
            .chain(rejection_warning(&self.summary.rejected))
            .chain(fault_warning(&self.faults, self.summary.gaps))
            .chain(lock_warning(
                self.summary.near_lock,
                self.summary.lock_passes,
            ))
            .chain(self.schedule_misfit_us.map(schedule_warning))
            .chain(end_of_input_warning(self.end_dropped_bytes))
    }
}

/// The one-line warning for bytes at the end of the input that did not complete a frame
/// (`None` for a clean end).
pub fn end_of_input_warning(bytes: u64) -> Option<String> {
    (bytes > 0).then(|| {
        format!("the input ends inside a frame: its last {bytes} bytes did not complete a frame and are dropped")
    })
}

/// The CLI's warning for a gain schedule run at another sample period than it was tuned at
/// (periods in us).
pub fn schedule_warning((tuned_us, run_us): (u64, u64)) -> String {
    let at = |us: u64| {
        let (s, hz) = (us as f64 / 1e6, (1e9 / us.max(1) as f64).round() / 1e3);
        format!("{s} s ({hz} Hz)")
    };
    format!(
        "the gain schedule was tuned at a sample period of {}, the bank runs at {} on this capture: a schedule's gains are tuned to its rate and can do worse here than the fixed NAV440 preset (docs/CALIBRATION.md, Low packet rates); tune one on a capture at this rate (nav440 tune CAPTURE --schedule ...)",
        at(tuned_us),
        at(run_us)
    )
}

/// The CLI's one-line warning for rejected samples, `None` if nothing was rejected, e.g. "3
/// samples rejected by the estimator bank: 2 with time not increasing, 1 with |yaw| above
/// 1000000 deg".
pub fn rejection_warning(r: &Rejections) -> Option<String> {
    if r.total() == 0 {
        return None;
    }
    let mut parts = Vec::new();
    if r.time_not_increasing > 0 {
        parts.push(format!(
            "{} with time not increasing",
            r.time_not_increasing
        ));
    }
    if r.angle_out_of_range > 0 {
        parts.push(format!(
            "{} with |yaw| above {} deg",
            r.angle_out_of_range,
            PaperBank::<f32>::MAX_ABS_DEG
        ));
    }
    if r.angle_not_finite > 0 {
        parts.push(format!("{} with yaw NaN or infinite", r.angle_not_finite));
    }
    Some(format!(
        "{} samples rejected by the estimator bank: {}",
        r.total(),
        parts.join(", ")
    ))
}
