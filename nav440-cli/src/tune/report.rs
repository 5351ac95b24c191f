//! The text, TOML and Rust snippet a tuning run writes ([`TuneResult`]).

use super::*;

/// The CLI's name of a hold (`--hold`).
pub(super) fn hold_name(h: Hold) -> &'static str {
    match h {
        Hold::Linear => "linear",
        Hold::ZeroOrder => "zoh",
    }
}

/// The gains of column `i` in `f` on one line ([`search::describe`]), `-` if absent.
pub(super) fn fmt_gains(f: &FamilyGains, i: usize) -> String {
    struct Describe<'a>(&'a FamilyGains, usize, String);
    impl FamilyVisitor for Describe<'_> {
        fn family<F: Family>(&mut self, column: usize) {
            if column == self.1 {
                if let Some(g) = self.0.get::<F>() {
                    self.2 = search::describe(&g);
                }
            }
        }
    }
    let mut d = Describe(f, i, String::new());
    for_each_family(&mut d);
    if d.2.is_empty() {
        "-".into()
    } else {
        d.2
    }
}

impl TuneResult {
    /// The printed report.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "tuned for noise variance {} deg^2, trained on {}-{} s, scored on {}-{} s, mean of {} seeds (MSE measured through PaperBank)\n",
            self.noise_var, self.train.0, self.train.1, self.test.0, self.test.1, self.seeds
        );
        s.push_str(&format!(
            "training rows scored: {}{}\n",
            self.rows_scored,
            crate::score::left_out_note(self.rows_left_out, self.rows_scored + self.rows_left_out)
                .map_or(String::new(), |n| format!(" ({n})"))
        ));
        s.push_str(&format!(
            "method: {}; hold kept: {} (before: {}); {} evaluations in {:.1} s\n",
            match self.method {
                Method::Search =>
                    "global search (coarse log grid + Nelder-Mead, argmin)".to_string(),
                Method::Exhaustive { points } =>
                    format!("exhaustive log grid, {points} points per gain"),
            },
            hold_name(self.hold),
            hold_name(self.hold_before),
            self.evals(),
            self.elapsed_s
        ));
        for r in &self.runs {
            s.push_str(&format!(
                "  hold {:<6} score (geometric mean of the {} tuned training MSEs) {:.4}\n",
                hold_name(r.hold),
                self.families.count(),
                r.score
            ));
            for (half, name) in ["velocity", "acceleration"].iter().enumerate() {
                s.push_str(&format!("    {name:<12} training MSE / evaluations / s:"));
                for (i, name) in NAMES.iter().enumerate() {
                    if !self.families.tunes(half == 1, i) {
                        continue;
                    }
                    s.push_str(&format!(
                        " {name} {:.4}/{}/{:.2}",
                        r.cost[half][i], r.evals[half][i], r.secs[half][i]
                    ));
                }
                s.push('\n');
            }
        }
        for (acc, (title, paper, tuned, before, after)) in [
            (
                "velocity, MSE (deg/s)^2",
                &self.paper.velocity,
                &self.gains.velocity,
                &self.vel_before,
                &self.vel_after,
            ),
            (
                "acceleration (series), MSE (deg/s^2)^2",
                &self.paper.acceleration,
                &self.gains.acceleration,
                &self.acc_before,
                &self.acc_after,
            ),
        ]
        .into_iter()
        .enumerate()
        {
            s.push_str(&format!("\n{title}\n"));
            s.push_str(&format!(
                "{:<5} {:>12} {:>12}  {:<40} {}\n",
                "", "before", "after", "paper gains", "tuned gains"
            ));
            for i in (0..FAMILY_COUNT).filter(|&i| self.families.tunes(acc == 1, i)) {
                s.push_str(&format!(
                    "{:<5} {:>12.3} {:>12.3}  {:<40} {}\n",
                    NAMES[i],
                    before[i],
                    after[i],
                    fmt_gains(paper, i),
                    fmt_gains(tuned, i)
                ));
            }
        }
        s
    }

    /// Objective evaluations over every hold and family.
    pub fn evals(&self) -> usize {
        self.runs
            .iter()
            .map(|r| r.evals.iter().flatten().sum::<usize>())
            .sum()
    }

    /// The gains file (TOML, read by `--gains`).
    pub fn to_toml(&self) -> String {
        format!(
            "# nav440 tune: gains for noise variance {} deg^2 (MSE over {}-{} s, {} seeds), hold {}\n# use: nav440 estimate FILE{} --gains THIS_FILE --hold {}\n{}",
            self.noise_var,
            self.train.0,
            self.train.1,
            self.seeds,
            hold_name(self.hold),
            if self.families == Families::ALL {
                ""
            } else {
                " --bank product"
            },
            hold_name(self.hold),
            self.gains.to_toml()
        )
    }

    /// A Rust snippet building the tuned `BankConfig` (paste into the firmware); it sets the
    /// hold the tuner kept.
    pub fn to_rust(&self) -> String {
        let product = self.families != Families::ALL;
        let bank = if product { "ProductBank" } else { "PaperBank" };
        let mut s = self
            .gains
            .to_rust(&format!("noise variance {} deg^2", self.noise_var), bank);
        if product {
            s.insert_str(
                0,
                "// The product bank's two rows (ILO1 velocity, Kalman acceleration): `ProductBank::new(&TUNED)`,\n\
                 // or in the product firmware `PRESET = TUNED` with `FOLLOW_RATE = false` (firmware-example/src/pipeline.rs).\n",
            );
        }
        match self.hold {
            Hold::Linear => s,
            Hold::ZeroOrder => s.replace(
                "    ..BankConfig::PAPER\n",
                "    hold: estimators::Hold::ZeroOrder,\n    ..BankConfig::PAPER\n",
            ),
        }
    }
}
