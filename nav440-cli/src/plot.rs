//! Stacked time-series panels rendered to SVG with `plotters` (the paper's Figs. 5-9 style).

use plotters::prelude::*;
use std::path::Path;

/// One line of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label.
    pub name: String,
    /// Line colour.
    pub color: RGBColor,
    /// Line width, px.
    pub width: u32,
    /// Points (t in s, value in the panel's unit).
    pub points: Vec<(f64, f64)>,
}

/// One panel (shared time axis).
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title drawn above the panel.
    pub title: String,
    /// Y axis label with unit.
    pub y_label: String,
    /// Lines, drawn in order (the reference first, so estimates are drawn over it).
    pub series: Vec<Series>,
    /// Fixed y range; `None` = fit all series.
    pub y_range: Option<(f64, f64)>,
}

/// Palette for estimator lines: AVE, ILO1, ILO2, ILO3, AD, ED, KF.
pub const ESTIMATOR_COLORS: [RGBColor; 7] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
];

/// Renders `panels` stacked vertically into an SVG of `width` px, each panel `panel_height`
/// px high, written to the file `path` (through a temporary file renamed at the end,
/// [`crate::output::OutputFile`]), or to standard output when `path` is `-`.
pub fn render_svg(
    path: &Path,
    title: &str,
    panels: &[Panel],
    width: u32,
    panel_height: u32,
) -> Result<(), String> {
    let height = 40 + panel_height * panels.len().max(1) as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        draw(&root, title, panels).map_err(|e| format!("cannot draw {}: {e}", path.display()))?;
        root.present()
            .map_err(|e| format!("cannot draw {}: {e}", path.display()))?;
    }
    crate::output::write_output(path, svg.as_bytes()).map_err(|e| e.to_string())
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    panels: &[Panel],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 22))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    let (t0, t1) = time_range(panels);
    for (area, panel) in areas.iter().zip(panels) {
        let (y0, y1) = panel.y_range.unwrap_or_else(|| value_range(panel));
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 17))
            .margin(8)
            .margin_right(20)
            .x_label_area_size(32)
            .y_label_area_size(70)
            .build_cartesian_2d(t0..t1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc(&panel.y_label)
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .max_light_lines(1)
            .light_line_style(RGBColor(0xf0, 0xf0, 0xf0))
            .draw()?;
        for s in &panel.series {
            let style = ShapeStyle::from(&s.color).stroke_width(s.width);
            // A non-finite value (no estimate: near gimbal lock, or not scored) breaks the
            // line: each finite run is its own polyline; the legend entry comes with the first.
            let mut runs = s
                .points
                .split(|&(t, v)| !(t.is_finite() && v.is_finite()))
                .filter(|run| !run.is_empty());
            let first = runs.next().unwrap_or(&[]);
            let clamp = move |&(t, v): &(f64, f64)| (t, v.clamp(y0, y1));
            chart
                .draw_series(LineSeries::new(first.iter().map(clamp), style))?
                .label(s.name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            for run in runs {
                chart.draw_series(LineSeries::new(run.iter().map(clamp), style))?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.7))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
    }
    Ok(())
}

fn time_range(panels: &[Panel]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in panels.iter().flat_map(|p| &p.series) {
        for &(t, _) in &s.points {
            lo = lo.min(t);
            hi = hi.max(t);
        }
    }
    if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

fn value_range(panel: &Panel) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in &panel.series {
        for &(_, v) in &s.points {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-6);
    (lo - pad, hi + pad)
}
