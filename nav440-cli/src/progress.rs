//! Progress of long commands (`tune`, `synth`) on stderr, drawn only when stderr is a
//! terminal: piped or redirected output stays exactly what the command prints without it.
//!
//! A [`Progress`] is a counter that the long-running code advances ([`Progress::inc`] for
//! work items such as motion samples, [`Progress::evaluation`] and [`Progress::fitted`] for
//! the tuner); the command that made it chooses what the bar counts and its total, and
//! clears it with [`Progress::finish`]. [`Progress::hidden`] counts nothing and draws nothing.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// What the bar's position counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Counts {
    /// [`Progress::inc`] items (and tuner evaluations: an exhaustive grid's total is known).
    Items,
    /// Tuner family fits; the evaluations (total unknown) go in the message.
    Fits,
}

/// A progress bar on stderr, or nothing (stderr not a terminal, or [`Progress::hidden`]).
/// Cheap to share between threads (`&Progress` is `Sync`).
#[derive(Clone, Debug)]
pub struct Progress {
    bar: Option<ProgressBar>,
    counts: Counts,
    evaluations: Arc<AtomicU64>,
}

impl Progress {
    /// Counts nothing, draws nothing.
    pub fn hidden() -> Self {
        Self {
            bar: None,
            counts: Counts::Items,
            evaluations: Arc::default(),
        }
    }

    /// A bar of `total` items of `what` (e.g. "evaluations", "samples"), prefixed by `name`,
    /// with the time left; hidden unless stderr is a terminal.
    pub fn items(name: &str, total: u64, what: &str) -> Self {
        Self::new(
            total,
            Counts::Items,
            &format!("{name}: {{bar:20}} {{human_pos}}/{{human_len}} {what}, {{eta}} left"),
        )
    }

    /// A bar of `total` tuner family fits, with the evaluations made so far and the time
    /// left; hidden unless stderr is a terminal.
    pub fn fits(name: &str, total: u64) -> Self {
        Self::new(
            total,
            Counts::Fits,
            &format!(
                "{name}: {{bar:20}} {{pos}}/{{len}} families, {{msg}} evaluations, {{eta}} left"
            ),
        )
    }

    fn new(total: u64, counts: Counts, template: &str) -> Self {
        if !std::io::stderr().is_terminal() {
            return Self::hidden();
        }
        let style = ProgressStyle::with_template(template)
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr())
            .with_style(style)
            .with_message("0");
        Self {
            bar: Some(bar),
            counts,
            evaluations: Arc::default(),
        }
    }

    /// `n` more items done.
    pub fn inc(&self, n: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(n);
        }
    }

    /// One more objective evaluation of the tuner.
    pub fn evaluation(&self) {
        match (&self.bar, self.counts) {
            (Some(bar), Counts::Items) => bar.inc(1),
            (Some(bar), Counts::Fits) => {
                self.evaluations.fetch_add(1, Ordering::Relaxed);
                bar.set_message(self.evaluations.load(Ordering::Relaxed).to_string());
            }
            (None, _) => {}
        }
    }

    /// One more tuner family fitted.
    pub fn fitted(&self) {
        if let (Some(bar), Counts::Fits) = (&self.bar, self.counts) {
            bar.inc(1);
        }
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Default for Progress {
    fn default() -> Self {
        Self::hidden()
    }
}
