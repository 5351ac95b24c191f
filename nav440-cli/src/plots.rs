//! `nav440 plot`: the paper's Figs. 5-9 for a capture, as stacked SVG panels.

use crate::error::{Error, Result};
use crate::paper::{ave_on_rate, REFERENCE_AVE};
use crate::plot::{render_svg, Panel, Series, ESTIMATOR_COLORS};
use crate::replay::{self, EstimateOptions, Sample};
use plotters::style::{RGBColor, BLACK};
use std::path::Path;

use crate::paper::COLUMNS as NAMES;

/// Decimation buckets per series across the plotted time range, more than the panel's
/// width in pixels (1400): a series of more points than [`FULL_POINTS`] keeps, per bucket, its
/// first, lowest, highest and last finite value and a break where a value is missing, so the
/// drawn line is the same at the SVG's resolution and memory does not grow with the capture.
pub const BUCKETS: usize = 2000;
/// The most rows a plot draws point for point (at most 5 points per bucket otherwise).
pub const FULL_POINTS: usize = 10_000;

/// One bucket being filled: its index and (first, min, max, last finite, first non-finite)
/// as (t, v).
type Bucket = (usize, [Option<(f64, f64)>; 5]);

/// The points of one series, kept whole or bucketed ([`BUCKETS`]).
struct Points {
    points: Vec<(f64, f64)>,
    /// (start time, bucket width) s, when decimating.
    grid: Option<(f64, f64)>,
    /// The bucket being filled.
    bucket: Option<Bucket>,
}

impl Points {
    fn new(grid: Option<(f64, f64)>) -> Self {
        Self {
            points: Vec::new(),
            grid,
            bucket: None,
        }
    }

    fn push(&mut self, t: f64, v: f64) {
        let Some((t0, w)) = self.grid else {
            self.points.push((t, v));
            return;
        };
        let b = (((t - t0) / w).max(0.0) as usize).min(BUCKETS - 1);
        if self.bucket.is_some_and(|(i, _)| i != b) {
            self.flush();
        }
        let (_, slots) = self.bucket.get_or_insert((b, [None; 5]));
        if !v.is_finite() {
            slots[4].get_or_insert((t, f64::NAN));
            return;
        }
        slots[0].get_or_insert((t, v));
        if slots[1].is_none_or(|(_, m)| v < m) {
            slots[1] = Some((t, v));
        }
        if slots[2].is_none_or(|(_, m)| v > m) {
            slots[2] = Some((t, v));
        }
        slots[3] = Some((t, v));
    }

    fn flush(&mut self) {
        if let Some((_, slots)) = self.bucket.take() {
            let mut kept: Vec<(f64, f64)> = slots.into_iter().flatten().collect();
            kept.sort_by(|a, b| a.0.total_cmp(&b.0));
            kept.dedup_by(|a, b| a.0 == b.0 && a.1.to_bits() == b.1.to_bits());
            self.points.extend(kept);
        }
    }

    fn finish(mut self) -> Vec<(f64, f64)> {
        self.flush();
        self.points
    }
}

/// Builds the panels: yaw; velocity (AVE, ILOs) and (AD, ED, KF) against the measured rate;
/// acceleration likewise against the reference (AVE on the measured rate). Only rows with
/// `from <= t <= to` are drawn. Estimates far outside the reference's range (a diverging
/// series) are clipped to the panel, whose y range follows the reference. The rows are
/// streamed into the series (bucketed beyond [`FULL_POINTS`]), not kept; also returns the
/// bank's summary (rejections, gaps).
pub fn panels(
    samples: &[Sample],
    opts: &EstimateOptions,
    from: Option<f64>,
    to: Option<f64>,
) -> Result<(Vec<Panel>, replay::EstimationSummary)> {
    let axis = opts.axis();
    let name = axis.name();
    let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, opts)?;
    let lo = from.unwrap_or(f64::NEG_INFINITY);
    let hi = to.unwrap_or(f64::INFINITY);
    let keep = |t: f64| t >= lo && t <= hi;
    let t_of = |us: u64| us as f64 * 1e-6;
    // Rows not scored (near gimbal lock and settling after it, crate::score) are drawn as
    // gaps in the estimates, as `paper` and `tune` leave them out.
    let lock = crate::score::Lock::of(samples, axis);
    let (mut n_in, mut t_first, mut t_last) = (0usize, f64::INFINITY, f64::NEG_INFINITY);
    for s in samples.iter().map(|s| t_of(s.t_us)).filter(|&t| keep(t)) {
        n_in += 1;
        t_first = t_first.min(s);
        t_last = t_last.max(s);
    }
    let grid = (n_in > FULL_POINTS && t_last > t_first)
        .then(|| (t_first, (t_last - t_first) / BUCKETS as f64));
    // The series in drawing order: yaw; velocity AVE, ILO1-3, reference; AD, ED, KF,
    // reference; the same two groups of accelerations.
    const VEL_A: [usize; 4] = [0, 1, 2, 3];
    const VEL_B: [usize; 3] = [4, 5, 6];
    let mut series: Vec<Points> = (0..1 + 2 * (VEL_A.len() + VEL_B.len() + 2))
        .map(|_| Points::new(grid))
        .collect();
    let (mut rows, mut left_out, mut drawn, mut j) = (0usize, 0usize, 0usize, 0usize);
    let (mut vr, mut ar) = (
        (f64::INFINITY, f64::NEG_INFINITY),
        (f64::INFINITY, f64::NEG_INFINITY),
    );
    let mut on_row = |r: replay::Row| {
        while j < samples.len() && samples[j].t_us < r.t_us {
            j += 1;
        }
        let k = lock.scored.get(j).copied().unwrap_or(false);
        rows += 1;
        left_out += usize::from(!k);
        let t = t_of(r.t_us);
        if !keep(t) {
            return Ok(());
        }
        drawn += 1;
        let out = r.axis(axis).map(|a| a.out);
        let rate_ref = r
            .axis(axis)
            .and_then(|a| a.reference_deg_s)
            .map_or(f64::NAN, f64::from);
        let acc_ref = f64::from(match samples.get(j) {
            Some(s) if s.t_us == r.t_us => acc_ref.get(j).copied().unwrap_or(f32::NAN),
            _ => f32::NAN,
        });
        for (v, range) in [(rate_ref, &mut vr), (acc_ref, &mut ar)] {
            if v.is_finite() {
                range.0 = range.0.min(v);
                range.1 = range.1.max(v);
            }
        }
        // `estimate`: a value left out where the row is not scored.
        let est = |c: estimators::Channel| {
            if k {
                out.map_or(f64::NAN, |o| f64::from(o[c]))
            } else {
                f64::NAN
            }
        };
        let mut values = vec![out.map_or(f64::NAN, |o| {
            f64::from(estimators::EstimatorOutput::unwrapped_deg(&o))
        })];
        for (channels, reference) in [
            (&estimators::Channel::VELOCITY, rate_ref),
            (&estimators::Channel::ACCELERATION, acc_ref),
        ] {
            for group in [&VEL_A[..], &VEL_B[..]] {
                values.extend(group.iter().map(|&i| est(channels[i])));
                values.push(reference);
            }
        }
        for (p, v) in series.iter_mut().zip(values) {
            p.push(t, v);
        }
        Ok(())
    };
    let mut est = replay::Estimation::new(opts)?;
    for &s in samples {
        est.push(s, &mut on_row)?;
    }
    let summary = est.finish(&mut on_row)?;
    if let Some(note) = crate::score::left_out_note(left_out, rows) {
        eprintln!("nav440: plot: {note}; drawn as gaps");
    }
    if drawn == 0 {
        return Err(Error::Usage("no sample in the requested time range".into()));
    }
    let pad = |(a, b): (f64, f64)| {
        let pad = ((b - a) * 0.25).max(1.0);
        (a - pad, b + pad)
    };
    let (vr, ar) = (pad(vr), pad(ar));
    let mut points = series.into_iter().map(Points::finish);
    let mut next = |name: &str, color: RGBColor, width: u32| Series {
        name: name.to_string(),
        color,
        width,
        points: points.next().unwrap_or_default(),
    };
    let yaw = Panel {
        title: if axis == replay::Axis::Yaw {
            "Yaw angle (unwrapped, with the added noise)".into()
        } else {
            format!("{name} angle (with the added noise)")
        },
        y_label: format!("{name} (deg)"),
        series: vec![next(name, BLACK, 1)],
        y_range: None,
    };
    let mut group = |title: &str, unit: &str, idx: &[usize], acc: bool| {
        let mut lines: Vec<Series> = idx
            .iter()
            .map(|&i| next(NAMES[i], ESTIMATOR_COLORS[i], 1))
            .collect();
        // The reference last, in black over the estimates, so it stays visible.
        lines.push(if acc {
            next("reference: AVE on measured rate", BLACK, 2)
        } else {
            next("reference: measured rate", BLACK, 2)
        });
        Panel {
            title: title.to_string(),
            y_label: unit.to_string(),
            series: lines,
            y_range: Some(if acc { ar } else { vr }),
        }
    };
    let panels = vec![
        yaw,
        group(
            "Velocity: AVE and ILO1-3 vs measured rate",
            "rate (deg/s)",
            &VEL_A,
            false,
        ),
        group(
            "Velocity: AD, ED, KF vs measured rate",
            "rate (deg/s)",
            &VEL_B,
            false,
        ),
        group(
            "Acceleration (series): AVE and ILO1-3 vs reference",
            "acc (deg/s^2)",
            &VEL_A,
            true,
        ),
        group(
            "Acceleration (series): AD, ED, KF vs reference",
            "acc (deg/s^2)",
            &VEL_B,
            true,
        ),
    ];
    Ok((panels, summary))
}

/// Renders the capture's plot into `out` (SVG); returns the bank's summary (rejections, gaps).
pub fn plot_capture(
    samples: &[Sample],
    opts: &EstimateOptions,
    capture: &str,
    out: &Path,
    from: Option<f64>,
    to: Option<f64>,
) -> Result<replay::EstimationSummary> {
    let (p, summary) = panels(samples, opts, from, to)?;
    let noise = match opts.noise {
        Some(n) => format!("noise var {} deg^2 (seed {})", n.var, n.seed),
        None => "no added noise".into(),
    };
    let hold = match opts.hold {
        estimators::Hold::Linear => "linear",
        estimators::Hold::ZeroOrder => "zoh",
    };
    let at = match (opts.noise, opts.noise_at) {
        (Some(_), crate::replay::NoiseAt::Step) => " per step",
        _ => "",
    };
    let title = format!("{capture}: {noise}{at}, hold {hold}, h = {} s", opts.step_s);
    render_svg(out, &title, &p, 1400, 300).map_err(Error::Output)?;
    Ok(summary)
}
