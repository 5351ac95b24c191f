//! The steps of `cargo xtask ci`, each timed: its wall time is printed as it ends, and a
//! table of every step at the end of the run (also when a step failed), with the step's
//! budget from docs/TESTS.md. A step over twice its budget is warned about, never failed:
//! machines are noisy, and the warning is there so a slow step is seen long before CI's
//! 90-minute limit.

use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The page whose budget table [`budgets`] reads, relative to the workspace root.
pub const BUDGET_PAGE: &str = "docs/TESTS.md";

/// A step over this many times its budget is warned about.
const WARN_FACTOR: f64 = 2.0;

/// One finished step: its name, wall time, whether it passed, and whether it ran in the pool
/// of QEMU jobs (then its time is the sum of its jobs' times, which overlap other steps).
#[derive(Clone, Debug)]
struct Done {
    name: String,
    took: Duration,
    ok: bool,
    pooled: bool,
}

/// The steps of one run and their budgets. Cloning gives another handle to the same record
/// (the pool's jobs add to it from their threads).
#[derive(Clone)]
pub struct Steps {
    done: Arc<Mutex<Vec<Done>>>,
    budgets: Arc<Vec<(String, u64)>>,
    start: Instant,
}

impl Steps {
    /// A record whose budgets come from [`BUDGET_PAGE`] under `root` (none when the page
    /// cannot be read: every step is then reported without a budget).
    pub fn new(root: &Path) -> Self {
        let budgets = std::fs::read_to_string(root.join(BUDGET_PAGE))
            .map(|t| budgets(&t))
            .unwrap_or_else(|e| {
                eprintln!("xtask ci: warning: cannot read {BUDGET_PAGE} ({e}): no budgets");
                Vec::new()
            });
        Self {
            done: Arc::default(),
            budgets: Arc::new(budgets),
            start: Instant::now(),
        }
    }

    /// The budget of `name`, s.
    fn budget(&self, name: &str) -> Option<u64> {
        self.budgets
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| *b)
    }

    /// Runs `f` as the step `name`, then prints its time (and a warning when it is over twice
    /// its budget).
    pub fn run<T>(&self, name: &str, f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
        eprintln!("xtask ci: step `{name}` ...");
        let t = Instant::now();
        let r = f();
        self.record(name, t.elapsed(), r.is_ok(), false);
        r
    }

    /// Adds a finished step (or, `pooled`, a group of jobs whose times are summed).
    pub fn record(&self, name: &str, took: Duration, ok: bool, pooled: bool) {
        let budget = self.budget(name);
        let status = if ok { "done" } else { "FAILED" };
        let budget_text =
            budget.map_or_else(|| "no budget".to_owned(), |b| format!("budget {b} s"));
        if !pooled {
            eprintln!(
                "xtask ci: step `{name}` {status} in {:.0} s ({budget_text}; {:.0} s since the start)",
                took.as_secs_f64(),
                self.start.elapsed().as_secs_f64()
            );
        }
        if !pooled {
            self.warn_if_slow(name, took, budget);
        }
        let mut done = self.done.lock().unwrap_or_else(|p| p.into_inner());
        match done
            .iter_mut()
            .find(|d| d.name == name && d.pooled && pooled)
        {
            Some(d) => {
                d.took += took;
                d.ok &= ok;
            }
            None => done.push(Done {
                name: name.to_owned(),
                took,
                ok,
                pooled,
            }),
        }
    }

    fn warn_if_slow(&self, name: &str, took: Duration, budget: Option<u64>) {
        match budget {
            Some(b) if took.as_secs_f64() > WARN_FACTOR * b as f64 => eprintln!(
                "xtask ci: WARNING: step `{name}` took {:.0} s, over {WARN_FACTOR}x its budget of {b} s ({BUDGET_PAGE})",
                took.as_secs_f64()
            ),
            Some(_) => {}
            None => eprintln!(
                "xtask ci: WARNING: step `{name}` has no budget in {BUDGET_PAGE}"
            ),
        }
    }

    /// The table of every step so far, with the whole run's wall time.
    pub fn table(&self) -> String {
        let done = self.done.lock().unwrap_or_else(|p| p.into_inner());
        let mut s = String::from(
            "xtask ci: time per step (wall s; a pooled step is the sum of its QEMU jobs, which run beside the others)\n",
        );
        s.push_str(&format!(
            "  {:<34} {:>7} {:>8}  {}\n",
            "step", "s", "budget", "status"
        ));
        for d in done.iter() {
            let budget = self
                .budget(&d.name)
                .map_or_else(|| "-".to_owned(), |b| b.to_string());
            let over = self
                .budget(&d.name)
                .is_some_and(|b| d.took.as_secs_f64() > WARN_FACTOR * b as f64);
            s.push_str(&format!(
                "  {:<34} {:>7.0} {:>8}  {}{}{}\n",
                d.name,
                d.took.as_secs_f64(),
                budget,
                if d.ok { "ok" } else { "FAILED" },
                if d.pooled { ", pooled" } else { "" },
                if over { ", OVER 2x BUDGET" } else { "" },
            ));
        }
        s.push_str(&format!(
            "  {:<34} {:>7.0}\n",
            "whole run",
            self.start.elapsed().as_secs_f64()
        ));
        // The pooled steps' totals are known only now.
        for d in done.iter().filter(|d| d.pooled) {
            match self.budget(&d.name) {
                Some(b) if d.took.as_secs_f64() > WARN_FACTOR * b as f64 => s.push_str(&format!(
                    "xtask ci: WARNING: step `{}` took {:.0} s, over {WARN_FACTOR}x its budget of {b} s ({BUDGET_PAGE})\n",
                    d.name,
                    d.took.as_secs_f64()
                )),
                Some(_) => {}
                None => s.push_str(&format!(
                    "xtask ci: WARNING: step `{}` has no budget in {BUDGET_PAGE}\n",
                    d.name
                )),
            }
        }
        s
    }
}

/// The budgets of a page's step table: every table row whose first cell is a step name in
/// backquotes and whose second cell is a whole number of seconds (`| `name` | 120 | ... |`).
pub fn budgets(page: &str) -> Vec<(String, u64)> {
    page.lines()
        .filter_map(|line| {
            let mut cells = line.trim().strip_prefix('|')?.split('|').map(str::trim);
            let name = cells.next()?.strip_prefix('`')?.strip_suffix('`')?;
            let budget = cells.next()?.parse().ok()?;
            Some((name.to_owned(), budget))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_are_read_from_step_rows_only() {
        let page = "| step | budget (s) | measured (s) |\n|---|---:|---:|\n| `fmt` | 5 | 2 |\n| `release tests` | 300 | 250 |\n| fmt | 9 | 9 |\n| `x` | n/a | 1 |\ntext `y` | 3\n";
        assert_eq!(
            budgets(page),
            vec![("fmt".to_owned(), 5), ("release tests".to_owned(), 300)]
        );
    }

    #[test]
    fn pooled_jobs_add_up_and_the_table_flags_a_slow_step() {
        let s = Steps {
            done: Arc::default(),
            budgets: Arc::new(vec![("a".to_owned(), 10), ("q".to_owned(), 100)]),
            start: Instant::now(),
        };
        s.record("a", Duration::from_secs(25), true, false);
        s.record("q", Duration::from_secs(30), true, true);
        s.record("q", Duration::from_secs(40), false, true);
        let t = s.table();
        let row = |name: &str| {
            t.lines()
                .find(|l| l.split_whitespace().next() == Some(name))
                .unwrap_or_default()
                .to_owned()
        };
        assert!(row("a").contains("25") && row("a").contains("OVER 2x BUDGET"));
        assert!(row("q").contains("70") && row("q").contains("FAILED, pooled"));
        assert!(!row("q").contains("OVER"));
    }
}
