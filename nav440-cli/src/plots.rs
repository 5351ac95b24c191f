//! `nav440 plot`: the paper's Figs. 5-9 for a capture, as stacked SVG panels.

use crate::error::{Error, Result};
use crate::paper::{ave_on_rate, REFERENCE_AVE};
use crate::plot::{render_svg, Panel, Series, ESTIMATOR_COLORS};
use crate::replay::{self, EstimateOptions, Sample};
use plotters::style::{RGBColor, BLACK};
use std::path::Path;

use crate::paper::COLUMNS as NAMES;

/// Builds the panels: yaw; velocity (AVE, ILOs) and (AD, ED, KF) against the measured rate;
/// acceleration likewise against the reference (AVE on the measured rate). Only rows with
/// `from <= t <= to` are drawn. Estimates far outside the reference's range (a diverging
/// series) are clipped to the panel, whose y range follows the reference.
pub fn panels(
    samples: &[Sample],
    opts: &EstimateOptions,
    from: Option<f64>,
    to: Option<f64>,
) -> Result<Vec<Panel>> {
    let (rows, _) = replay::estimate(samples, opts)?;
    let axis = opts.axis();
    let name = axis.name();
    let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, opts)?;
    let lo = from.unwrap_or(f64::NEG_INFINITY);
    let hi = to.unwrap_or(f64::INFINITY);
    let keep = |t: f64| t >= lo && t <= hi;
    let t_of = |us: u64| us as f64 * 1e-6;
    let mut accr_by_t = std::collections::HashMap::new();
    for (s, a) in samples.iter().zip(&acc_ref) {
        accr_by_t.insert(s.t_us, *a);
    }
    // Rows not scored (near gimbal lock and settling after it, crate::score) are drawn as
    // gaps in the estimates, as `paper` and `tune` leave them out.
    let scored = crate::paper::row_scored(axis, &rows, samples);
    let left_out = scored.iter().filter(|&&k| !k).count();
    if let Some(note) = crate::score::left_out_note(left_out, rows.len()) {
        eprintln!("nav440: plot: {note}; drawn as gaps");
    }
    let rows: Vec<(replay::Row, bool)> = rows
        .into_iter()
        .zip(scored)
        .filter(|(r, _)| keep(t_of(r.t_us)))
        .collect();
    if rows.is_empty() {
        return Err(Error::Usage("no sample in the requested time range".into()));
    }
    // `estimate`: a value left out where the row is not scored.
    let series = |name: &str,
                  color: RGBColor,
                  width: u32,
                  estimate: bool,
                  f: &dyn Fn(&replay::Row) -> f64| Series {
        name: name.to_string(),
        color,
        width,
        points: rows
            .iter()
            .map(|(r, k)| {
                let v = if estimate && !k { f64::NAN } else { f(r) };
                (t_of(r.t_us), v)
            })
            .collect(),
    };
    let line = |name: &str, color: RGBColor, width: u32, f: &dyn Fn(&replay::Row) -> f64| {
        series(name, color, width, false, f)
    };
    let out = |r: &replay::Row| r.axis(axis).map(|a| a.out);
    let yaw = Panel {
        title: if axis == replay::Axis::Yaw {
            "Yaw angle (unwrapped, with the added noise)".into()
        } else {
            format!("{name} angle (with the added noise)")
        },
        y_label: format!("{name} (deg)"),
        series: vec![line(name, BLACK, 1, &|r| {
            out(r).map_or(f64::NAN, |o| f64::from(o.unwrapped_deg))
        })],
        y_range: None,
    };
    let rate_ref = |r: &replay::Row| {
        r.axis(axis)
            .and_then(|a| a.reference_deg_s)
            .map_or(f64::NAN, f64::from)
    };
    let acc_ref_f =
        |r: &replay::Row| f64::from(accr_by_t.get(&r.t_us).copied().unwrap_or(f32::NAN));
    let range_of = |f: &dyn Fn(&replay::Row) -> f64| {
        let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
        for (r, _) in &rows {
            let v = f(r);
            if v.is_finite() {
                a = a.min(v);
                b = b.max(v);
            }
        }
        let pad = ((b - a) * 0.25).max(1.0);
        (a - pad, b + pad)
    };
    let vr = range_of(&rate_ref);
    let ar = range_of(&acc_ref_f);
    let group = |title: &str, unit: &str, idx: &[usize], acc: bool| {
        let mut lines = Vec::new();
        for &i in idx {
            lines.push(series(
                NAMES[i],
                ESTIMATOR_COLORS[i],
                1,
                true,
                &|r: &replay::Row| {
                    out(r).map_or(f64::NAN, |o| {
                        f64::from(if acc {
                            o[estimators::Channel::ACCELERATION[i]]
                        } else {
                            o[estimators::Channel::VELOCITY[i]]
                        })
                    })
                },
            ));
        }
        // The reference last, in black over the estimates, so it stays visible.
        lines.push(if acc {
            line("reference: AVE on measured rate", BLACK, 2, &acc_ref_f)
        } else {
            line("reference: measured rate", BLACK, 2, &rate_ref)
        });
        Panel {
            title: title.to_string(),
            y_label: unit.to_string(),
            series: lines,
            y_range: Some(if acc { ar } else { vr }),
        }
    };
    Ok(vec![
        yaw,
        group(
            "Velocity: AVE and ILO1-3 vs measured rate",
            "rate (deg/s)",
            &[0, 1, 2, 3],
            false,
        ),
        group(
            "Velocity: AD, ED, KF vs measured rate",
            "rate (deg/s)",
            &[4, 5, 6],
            false,
        ),
        group(
            "Acceleration (series): AVE and ILO1-3 vs reference",
            "acc (deg/s^2)",
            &[0, 1, 2, 3],
            true,
        ),
        group(
            "Acceleration (series): AD, ED, KF vs reference",
            "acc (deg/s^2)",
            &[4, 5, 6],
            true,
        ),
    ])
}

/// Renders the capture's plot into `out` (SVG).
pub fn plot_capture(
    samples: &[Sample],
    opts: &EstimateOptions,
    capture: &str,
    out: &Path,
    from: Option<f64>,
    to: Option<f64>,
) -> Result<()> {
    let p = panels(samples, opts, from, to)?;
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
    render_svg(out, &title, &p, 1400, 300).map_err(Error::Output)
}
