//! The live chart of `nav440 live --plot`: the estimate CSV, as the pipeline writes it, drawn
//! in the terminal with ratatui while the rows arrive.
//!
//! The estimation runs on another thread and writes its CSV into a [`ChannelWriter`]; [`run`]
//! takes the text from the channel, parses the header and the rows ([`Series`]) and redraws at
//! most every [`REDRAW`]. Per axis of the CSV (roll, pitch, yaw: the columns `ROLL_rate`, ...)
//! it draws two charts over the last [`WINDOW_S`] seconds: the reference rate (`*_rate`, the
//! Euler-kinematics rate) with the ILO1 velocity (`ilo1_v`), deg/s, and the Kalman
//! acceleration (`kf_a`), deg/s^2. Both banks print these columns. Empty fields (near gimbal
//! lock) leave a gap. The first line shows the row count and the latest time.

use std::collections::VecDeque;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, TryRecvError};
use std::time::Duration;

use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, LegendPosition, Paragraph};
use ratatui::Frame;

/// The time span the charts show, s (the newest row at the right edge).
pub const WINDOW_S: f64 = 10.0;

/// The longest time between two redraws while rows arrive (also the key poll interval).
pub const REDRAW: Duration = Duration::from_millis(100);

/// A writer that sends what is written to the chart ([`run`]); a closed chart is a closed
/// pipe (`BrokenPipe`), which ends the estimation quietly.
pub struct ChannelWriter(pub Sender<Vec<u8>>);

impl Write for ChannelWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0
            .send(buf.to_vec())
            .map_err(|_| io::Error::from(io::ErrorKind::BrokenPipe))?;
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// One plotted quantity: its CSV column and the points in the window, (t s, value).
#[derive(Debug)]
struct Trace {
    name: &'static str,
    column: usize,
    points: VecDeque<(f64, f64)>,
}

impl Trace {
    fn new(name: &'static str, column: usize) -> Self {
        Self {
            name,
            column,
            points: VecDeque::new(),
        }
    }
}

/// The traces of one axis: reference rate, ILO1 velocity, Kalman acceleration.
#[derive(Debug)]
struct AxisTraces {
    axis: &'static str,
    rate: Trace,
    velocity: Trace,
    acceleration: Trace,
}

impl AxisTraces {
    fn traces_mut(&mut self) -> [&mut Trace; 3] {
        [&mut self.rate, &mut self.velocity, &mut self.acceleration]
    }
}

/// The CSV text parsed into the traces of the window.
#[derive(Debug, Default)]
pub struct Series {
    partial: Vec<u8>,
    axes: Vec<AxisTraces>,
    header_seen: bool,
    rows: u64,
    t_last: Option<f64>,
}

impl Series {
    /// Nothing seen yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The rows parsed so far (the header not counted).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// The time of the newest row, s.
    pub fn t_last(&self) -> Option<f64> {
        self.t_last
    }

    /// The axes found in the header, in CSV order (`roll`, `pitch`, `yaw`).
    pub fn axes(&self) -> Vec<&'static str> {
        self.axes.iter().map(|a| a.axis).collect()
    }

    /// Takes the next bytes of the CSV (any split); complete lines are parsed.
    pub fn feed(&mut self, bytes: &[u8]) {
        self.partial.extend_from_slice(bytes);
        let Some(last_nl) = self.partial.iter().rposition(|&b| b == b'\n') else {
            return;
        };
        let rest = self.partial.split_off(last_nl + 1);
        let text = std::mem::replace(&mut self.partial, rest);
        for line in String::from_utf8_lossy(&text).lines() {
            self.line(line);
        }
    }

    fn line(&mut self, line: &str) {
        let fields: Vec<&str> = line.split(',').collect();
        if !self.header_seen {
            self.header(&fields);
            return;
        }
        let Some(t) = fields.first().and_then(|f| f.parse::<f64>().ok()) else {
            return;
        };
        self.rows += 1;
        self.t_last = Some(t);
        for a in &mut self.axes {
            for trace in a.traces_mut() {
                if let Some(v) = fields.get(trace.column).and_then(|f| f.parse::<f64>().ok()) {
                    if v.is_finite() {
                        trace.points.push_back((t, v));
                    }
                }
                while trace.points.front().is_some_and(|p| p.0 < t - WINDOW_S) {
                    trace.points.pop_front();
                }
            }
        }
    }

    /// `t,yaw,yaw_rate,ilo1_v,...,kf_a,...`, or with every axis `t,roll,roll_rate,roll_ilo1_v,...`;
    /// with `--no-reference` `<axis>_body_rate` in place of `<axis>_rate`.
    fn header(&mut self, fields: &[&str]) {
        self.header_seen = true;
        let col = |name: &str| fields.iter().position(|f| *f == name);
        for axis in ["roll", "pitch", "yaw"] {
            let rate = col(&format!("{axis}_rate"))
                .map(|c| ("rate (reference)", c))
                .or_else(|| col(&format!("{axis}_body_rate")).map(|c| ("body rate", c)));
            let Some((rate_label, rate)) = rate else {
                continue;
            };
            let pick = |name: &str| col(&format!("{axis}_{name}")).or_else(|| col(name));
            if let (Some(v), Some(acc)) = (pick("ilo1_v"), pick("kf_a")) {
                self.axes.push(AxisTraces {
                    axis,
                    rate: Trace::new(rate_label, rate),
                    velocity: Trace::new("ilo1_v", v),
                    acceleration: Trace::new("kf_a", acc),
                });
            }
        }
    }

    /// Draws the status line and, per axis, the velocity and the acceleration chart.
    pub fn draw(&mut self, frame: &mut Frame<'_>, title: &str, ended: bool) {
        let [status, charts] =
            Layout::vertical([Constraint::Length(1), Constraint::Min(0)]).areas(frame.area());
        let t = self.t_last.map_or("-".to_string(), |t| format!("{t:.2} s"));
        let state = if ended { "end of stream" } else { "q: quit" };
        let line = format!("{title}  rows {}  t {t}  ({state})", self.rows);
        frame.render_widget(Paragraph::new(line), status);
        let t1 = self.t_last.unwrap_or(WINDOW_S).max(WINDOW_S);
        let x = [t1 - WINDOW_S, t1];
        let n = self.axes.len().max(1) as u32;
        let columns = Layout::horizontal((0..n).map(|_| Constraint::Ratio(1, n))).split(charts);
        for (a, area) in self.axes.iter_mut().zip(columns.iter()) {
            let [top, bottom] =
                Layout::vertical([Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)]).areas(*area);
            let velocity_title = format!("{} rate, deg/s", a.axis);
            let velocity = [(&mut a.rate, Color::Gray), (&mut a.velocity, Color::Cyan)];
            frame.render_widget(chart(&velocity_title, x, velocity), top);
            let acceleration_title = format!("{} acceleration, deg/s^2", a.axis);
            let acceleration = [(&mut a.acceleration, Color::Yellow)];
            frame.render_widget(chart(&acceleration_title, x, acceleration), bottom);
        }
        if self.axes.is_empty() {
            let what = if self.header_seen {
                "no rate, ilo1_v and kf_a columns in the CSV header"
            } else {
                "waiting for the first rows (the warm-up holds 16 samples)"
            };
            frame.render_widget(Paragraph::new(what).block(Block::bordered()), charts);
        }
    }
}

/// A line chart of `traces` over `x` (s), the y range from the points shown.
fn chart<'a, const N: usize>(
    title: &'a str,
    x: [f64; 2],
    traces: [(&'a mut Trace, Color); N],
) -> Chart<'a> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut datasets = Vec::with_capacity(N);
    for (trace, color) in traces {
        for &(_, v) in trace.points.iter() {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        let name = trace.name;
        datasets.push(
            Dataset::default()
                .name(name)
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::default().fg(color))
                .data(trace.points.make_contiguous()),
        );
    }
    if lo > hi {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-3);
    let (lo, hi) = (lo - pad, hi + pad);
    Chart::new(datasets)
        .block(Block::bordered().title(title))
        .legend_position(Some(LegendPosition::TopLeft))
        .hidden_legend_constraints((Constraint::Percentage(60), Constraint::Percentage(60)))
        .x_axis(
            Axis::default()
                .bounds(x)
                .labels([format!("{:.1}", x[0]), format!("{:.1} s", x[1])]),
        )
        .y_axis(Axis::default().bounds([lo, hi]).labels([
            format!("{lo:.1}"),
            format!("{:.1}", (lo + hi) / 2.0),
            format!("{hi:.1}"),
        ]))
}

/// Draws the chart in the terminal (alternate screen, raw mode) from the CSV text that arrives
/// on `rx`, until the sender is gone (the end of the stream), `q`/Esc/Ctrl-C (which set
/// `stop`), or `stop` set elsewhere (SIGINT, SIGTERM). The terminal is restored in every case.
/// Returns the number of rows plotted.
pub fn run(rx: Receiver<Vec<u8>>, stop: &AtomicBool, title: &str) -> io::Result<u64> {
    let mut terminal = ratatui::try_init()?;
    let mut series = Series::new();
    let drawn = (|| -> io::Result<()> {
        let mut dirty = true;
        loop {
            let mut ended = false;
            loop {
                match rx.try_recv() {
                    Ok(bytes) => {
                        series.feed(&bytes);
                        dirty = true;
                    }
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => {
                        ended = true;
                        break;
                    }
                }
            }
            if dirty || ended {
                terminal.draw(|f| series.draw(f, title, ended))?;
                dirty = false;
            }
            if ended || stop.load(Ordering::Relaxed) {
                return Ok(());
            }
            if event::poll(REDRAW)? {
                match event::read()? {
                    Event::Key(k) if k.kind == KeyEventKind::Press => {
                        let ctrl_c = k.code == KeyCode::Char('c')
                            && k.modifiers.contains(KeyModifiers::CONTROL);
                        if ctrl_c || matches!(k.code, KeyCode::Char('q') | KeyCode::Esc) {
                            stop.store(true, Ordering::Relaxed);
                            return Ok(());
                        }
                    }
                    Event::Resize(..) => dirty = true,
                    _ => {}
                }
            }
        }
    })();
    let restored = ratatui::try_restore();
    drawn.and(restored).map(|()| series.rows())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_parses_header_and_rows_in_any_split_and_keeps_the_window() {
        let mut s = Series::new();
        let mut text = String::from("t,yaw,yaw_rate,ilo1_v,kf_a\n");
        for k in 0..2000 {
            let t = k as f64 * 0.01;
            text.push_str(&format!("{t:.2},1.0,30.0,29.5,0.1\n"));
        }
        for chunk in text.as_bytes().chunks(7) {
            s.feed(chunk);
        }
        assert_eq!(s.rows(), 2000);
        assert_eq!(s.axes(), ["yaw"]);
        let a = &s.axes[0];
        assert_eq!(
            (a.rate.column, a.velocity.column, a.acceleration.column),
            (2, 3, 4)
        );
        // 19.99 s of rows: the window keeps those within 10 s of the newest.
        assert_eq!(a.velocity.points.len(), 1001);
        assert_eq!(a.velocity.points.back(), Some(&(19.99, 29.5)));
    }

    #[test]
    fn every_axis_and_empty_fields() {
        let mut s = Series::new();
        s.feed(b"t,roll,roll_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_rate,yaw_ilo1_v,yaw_kf_a\n");
        s.feed(b"0.01,,,,,85.0,1,2,3,,,,\n");
        assert_eq!(s.axes(), ["roll", "pitch", "yaw"]);
        assert_eq!(s.rows(), 1);
        assert!(s.axes[0].velocity.points.is_empty());
        assert_eq!(s.axes[1].velocity.points.back(), Some(&(0.01, 2.0)));
        assert_eq!(s.axes[1].acceleration.points.back(), Some(&(0.01, 3.0)));
    }

    /// `--no-reference`: the body-rate column is the rate trace, labelled as such.
    #[test]
    fn body_rate_columns() {
        let mut s = Series::new();
        s.feed(b"t,yaw,yaw_body_rate,ilo1_v,kf_a\n0.01,1.0,30.0,29.5,0.1\n");
        assert_eq!(s.axes(), ["yaw"]);
        let a = &s.axes[0];
        assert_eq!((a.rate.name, a.rate.column), ("body rate", 2));
        assert_eq!(a.rate.points.back(), Some(&(0.01, 30.0)));
    }
}
