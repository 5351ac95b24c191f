//! The paper's experiment (section 5, Tables 1 and 3) on a capture.
//!
//! Protocol: Gaussian noise of variance 0.01 and 0.5 deg^2 is added to the yaw angle; each
//! estimator's output is compared, at every packet time `t <= window` (30 s), with the
//! reference; the mean square error is averaged over 3 noise seeds (1, 2, 3).
//! Velocity reference: the packet's measured z rate. Acceleration reference: the AVE with the
//! paper's gains (k = 500, gamma1 = 20000) applied to the measured rate, stepped by the same
//! sample adapter (hold mode, step) as the estimators.

use crate::error::{Error, Result};
use crate::replay::{self, Axis, EstimateOptions, Noise, Row, Sample};
use estimators::{
    Ave, AveConfig, BankConfig, Channel, DeltaMode, SampleAdapter, FAMILIES, FAMILY_COUNT,
};

/// Noise variances of the paper's Tables 1 and 3, deg^2.
pub const NOISE_VARS: [f64; 2] = [0.01, 0.5];
/// Noise seeds averaged (the paper: "mean of 3 runs").
pub const SEEDS: [u64; 3] = [1, 2, 3];
/// Column names, one per family of the paper bank ([`estimators::FAMILIES`]' labels): the six
/// estimators of the paper, then our Kalman filter.
pub const COLUMNS: [&str; FAMILY_COUNT] = {
    let mut names = [""; FAMILY_COUNT];
    let mut i = 0;
    while i < FAMILY_COUNT {
        names[i] = FAMILIES[i].label;
        i += 1;
    }
    names
};
/// Paper Table 1: velocity MSE, (deg/s)^2, rows sigma^2 = 0.01, 0.5; columns AVE..ED.
pub const PAPER_VEL_MSE: [[f64; 6]; 2] = [
    [11.1, 18.1, 11.0, 10.9, 18.7, 14.7],
    [12.4, 31.6, 13.9, 15.3, 71.7, 26.7],
];
/// Paper Table 3: acceleration MSE, (deg/s^2)^2, rows sigma^2 = 0.01, 0.5; columns AVE..ED.
pub const PAPER_ACC_MSE: [[f64; 6]; 2] = [
    [232.3, 500.8, 212.4, 222.6, 289.5, 378.6],
    [261.0, 500.9, 246.3, 275.7, 297.8, 392.1],
];
/// Paper gains of the acceleration reference AVE.
pub const REFERENCE_AVE: AveConfig = AveConfig {
    k: 500.0,
    gamma1: 20000.0,
    delta: DeltaMode::Paper,
};

/// Applies an AVE (`cfg`) to the reference rate of `samples` (of the axis `opts.axis()`: the
/// Euler-kinematics rate, NaN where there is none) behind the same
/// `estimators::SampleAdapter` the bank uses (same step, hold and maximum gap): reset to the
/// first sample (output 0), then `n = round(dt / h)` steps per sample. Returns one
/// acceleration per sample, deg/s^2 (NaN for a sample the adapter refuses, and near gimbal
/// lock, where there is no rate: the AVE restarts at the next sample with one).
pub fn ave_on_rate(
    samples: &[Sample],
    cfg: &AveConfig,
    opts: &EstimateOptions,
) -> Result<Vec<f32>> {
    let bad =
        |e: estimators::ConfigError| Error::Usage(format!("bad reference AVE configuration: {e}"));
    let bank = opts.bank_config_for(samples);
    let ave = Ave::<f32>::new(cfg, opts.step_s).map_err(bad)?;
    let mut adapter =
        SampleAdapter::new(ave, opts.step_s, bank.max_gap_s(), opts.hold).map_err(bad)?;
    let axis = opts.axis();
    let mut restart = false;
    Ok(samples
        .iter()
        .map(|s| match s.reference(axis) {
            // Near gimbal lock: no rate to differentiate; restart after it, as the bank.
            None => {
                restart = true;
                f32::NAN
            }
            Some(rate) => {
                if std::mem::take(&mut restart) {
                    adapter.restart();
                }
                adapter.update(s.t_us, rate).unwrap_or(f32::NAN)
            }
        })
        .collect())
}

/// Number of observer steps between two sample times (us) for step `h_us`.
pub fn steps_between(t0_us: u64, t1_us: u64, h_us: f64) -> u32 {
    let dt = t1_us.saturating_sub(t0_us) as f64;
    (dt / h_us).round().min(f64::from(u32::MAX)) as u32
}

/// Mean square error of `est` against `reference` over the rows with `t <= window_s`. Rows
/// without a reference (NaN: near gimbal lock, see `nav440_pipeline::euler`) are left out.
pub fn mse(t_us: &[u64], est: &[f32], reference: &[f32], window_s: f64) -> f64 {
    let lim = (window_s * 1e6).round() as u64;
    let (mut sum, mut n) = (0.0f64, 0usize);
    for ((&t, &e), &r) in t_us.iter().zip(est).zip(reference) {
        if t <= lim && !r.is_nan() {
            let d = f64::from(e) - f64::from(r);
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        sum / n as f64
    }
}

/// MSE of every velocity and acceleration column of `rows` for `axis` (against its reference
/// rate and `acc_ref`, matched by time; rows without a reference left out).
pub fn row_mse(
    axis: Axis,
    rows: &[Row],
    samples: &[Sample],
    acc_ref: &[f32],
    window_s: f64,
) -> ([f64; FAMILY_COUNT], [f64; FAMILY_COUNT]) {
    // Rows are a subsequence of samples (rejected samples are missing): match by time. A row
    // not scored (gimbal lock, crate::score) gets a NaN reference, which `mse` leaves out.
    let scored = row_scored(axis, rows, samples);
    let mut accr = Vec::with_capacity(rows.len());
    let mut j = 0;
    for (r, &k) in rows.iter().zip(&scored) {
        while j < samples.len() && samples[j].t_us < r.t_us {
            j += 1;
        }
        accr.push(match k {
            true => acc_ref.get(j).copied().unwrap_or(f32::NAN),
            false => f32::NAN,
        });
    }
    let t: Vec<u64> = rows.iter().map(|r| r.t_us).collect();
    let rate: Vec<f32> = rows
        .iter()
        .zip(&scored)
        .map(|(r, &k)| {
            r.axis(axis)
                .and_then(|a| a.reference_deg_s)
                .filter(|_| k)
                .unwrap_or(f32::NAN)
        })
        .collect();
    let out = |r: &Row| r.axis(axis).map(|a| a.out);
    let mut v = [0.0; FAMILY_COUNT];
    let mut a = [0.0; FAMILY_COUNT];
    for i in 0..FAMILY_COUNT {
        let ev: Vec<f32> = rows
            .iter()
            .map(|r| out(r).map_or(f32::NAN, |o| o[Channel::VELOCITY[i]]))
            .collect();
        let ea: Vec<f32> = rows
            .iter()
            .map(|r| out(r).map_or(f32::NAN, |o| o[Channel::ACCELERATION[i]]))
            .collect();
        v[i] = mse(&t, &ev, &rate, window_s);
        a[i] = mse(&t, &ea, &accr, window_s);
    }
    (v, a)
}

/// Per row of `rows` (a subsequence of `samples`, matched by time): whether `axis` is scored
/// there ([`crate::score::Lock`]).
pub fn row_scored(axis: Axis, rows: &[Row], samples: &[Sample]) -> Vec<bool> {
    let lock = crate::score::Lock::of(samples, axis);
    let mut j = 0;
    rows.iter()
        .map(|r| {
            while j < samples.len() && samples[j].t_us < r.t_us {
                j += 1;
            }
            lock.scored.get(j).copied().unwrap_or(false)
        })
        .collect()
}

/// (noise variance index, velocity MSE, acceleration MSE) of one run.
type RunMse = (usize, [f64; FAMILY_COUNT], [f64; FAMILY_COUNT]);

/// Result of the paper protocol.
#[derive(Clone, Debug)]
pub struct PaperResult {
    /// Capture name.
    pub capture: String,
    /// The scored axis (`--axis`).
    pub axis: Axis,
    /// Samples (packets with yaw) in the capture.
    pub samples: usize,
    /// Capture duration, s.
    pub duration_s: f64,
    /// Hold mode used.
    pub hold: estimators::Hold,
    /// Observer step, s.
    pub step_s: f32,
    /// MSE window end, s.
    pub window_s: f64,
    /// Gains: "paper presets" or the gains file.
    pub gains: String,
    /// Where the noise entered.
    pub noise_at: crate::replay::NoiseAt,
    /// Velocity MSE per noise variance and column, (deg/s)^2.
    pub vel: [[f64; FAMILY_COUNT]; 2],
    /// Acceleration MSE per noise variance and column, (deg/s^2)^2.
    pub acc: [[f64; FAMILY_COUNT]; 2],
    /// Velocity MSE without added noise (the tracking-error floor), (deg/s)^2.
    pub vel_clean: [f64; FAMILY_COUNT],
    /// Acceleration MSE without added noise, (deg/s^2)^2.
    pub acc_clean: [f64; FAMILY_COUNT],
    /// Rows in the MSE window (of the run without noise).
    pub rows_in_window: usize,
    /// Of those, the rows scored: the others are near gimbal lock or within
    /// [`crate::score::LOCK_SETTLE_S`] after it (roll and yaw only).
    pub rows_scored: usize,
    /// The run without noise: samples the bank rejected, gaps (for the input warnings).
    pub summary: replay::EstimationSummary,
}

/// Checks an MSE window end (`--window` of `paper` and `tune`): a finite number of seconds in
/// (0, 30 days], else an [`Error::Usage`].
pub fn check_window(window_s: f64) -> Result<()> {
    crate::limits::seconds("--window", window_s, false).map(drop)
}

/// Runs the protocol. The 6 (variance, seed) runs are spread over 2 threads.
pub fn run(
    samples: &[Sample],
    opts: &EstimateOptions,
    window_s: f64,
    capture: &str,
) -> Result<PaperResult> {
    let duration_s = samples.last().map_or(0.0, |s| s.t_s());
    run_counted(
        samples,
        (samples.len(), duration_s),
        opts,
        window_s,
        capture,
    )
}

/// The MSE window's end, us.
pub fn window_end_us(window_s: f64) -> u64 {
    (window_s * 1e6).round() as u64
}

/// [`run`] on the samples a capture reader kept ([`crate::replay::read_samples_until`] up to
/// [`window_end_us`]: the MSEs are causal, so they are those of the whole capture), with the
/// whole capture's sample count and duration (s) for the report. Each run streams its rows
/// into the MSE sums: memory is the samples' and 7 bytes per sample (the acceleration
/// reference and the lock masks), whatever the window.
pub fn run_counted(
    samples: &[Sample],
    (total, duration_s): (usize, f64),
    opts: &EstimateOptions,
    window_s: f64,
    capture: &str,
) -> Result<PaperResult> {
    check_window(window_s)?;
    if samples.len() < crate::score::MIN_ROWS {
        return Err(Error::Usage(format!(
            "{capture}: {} sample(s) carrying the angle: the paper's tables need at least {} (fewer give all-zero MSEs)",
            samples.len(),
            crate::score::MIN_ROWS
        )));
    }
    // What the report names as the gains (`--gains` files set `overlay`, `--preset nav440`
    // `follow_rate`).
    let gains = if opts.overlay.is_some() {
        "from --gains file"
    } else if opts.follow_rate {
        "NAV440 preset (its entry for the capture's packet rate)"
    } else if opts.config.is_none_or(|c| c == BankConfig::PAPER) {
        "paper presets (Tables 2 and 4)"
    } else {
        "given bank configuration"
    };
    let opts = &opts.paper_law();
    let acc_ref = ave_on_rate(samples, &REFERENCE_AVE, opts)?;
    let lock = crate::score::Lock::of(samples, opts.axis());
    let jobs: Vec<(usize, u64)> = (0..NOISE_VARS.len())
        .flat_map(|i| SEEDS.iter().map(move |&s| (i, s)))
        .collect();
    let results: Vec<Result<RunMse>> = std::thread::scope(|scope| {
        let chunks: Vec<Vec<(usize, u64)>> = vec![
            jobs.iter().copied().step_by(2).collect(),
            jobs.iter().copied().skip(1).step_by(2).collect(),
        ];
        let handles: Vec<_> = chunks
            .into_iter()
            .map(|chunk| {
                let (acc_ref, lock) = (&acc_ref, &lock);
                scope.spawn(move || {
                    chunk
                        .into_iter()
                        .map(|(i, seed)| {
                            let mut o = opts.clone();
                            o.noise = Some(Noise {
                                var: NOISE_VARS[i],
                                seed,
                            });
                            let r = stream_mse(&o, samples, lock, acc_ref, window_s)?;
                            Ok((i, r.vel, r.acc))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| {
                h.join()
                    .unwrap_or_else(|_| vec![Err(Error::Other("worker thread panicked".into()))])
            })
            .collect()
    });
    let mut vel = [[0.0; FAMILY_COUNT]; 2];
    let mut acc = [[0.0; FAMILY_COUNT]; 2];
    for r in results {
        let (i, v, a) = r?;
        for c in 0..FAMILY_COUNT {
            vel[i][c] += v[c] / SEEDS.len() as f64;
            acc[i][c] += a[c] / SEEDS.len() as f64;
        }
    }
    // Baseline without noise: the estimators' own tracking error (lag) on this motion.
    let mut o = opts.clone();
    o.noise = None;
    let clean = stream_mse(&o, samples, &lock, &acc_ref, window_s)?;
    let (vel_clean, acc_clean) = (clean.vel, clean.acc);
    let (rows_in_window, rows_scored) = (clean.rows_in_window, clean.rows_scored);
    Ok(PaperResult {
        capture: capture.to_string(),
        axis: opts.axis(),
        samples: total,
        duration_s,
        hold: opts.hold,
        step_s: opts.step_s,
        window_s,
        gains: gains.into(),
        noise_at: opts.noise_at,
        vel,
        acc,
        vel_clean,
        acc_clean,
        rows_in_window,
        rows_scored,
        summary: clean.summary,
    })
}

/// What one run of the bank gives the tables ([`stream_mse`]).
struct RunScore {
    vel: [f64; FAMILY_COUNT],
    acc: [f64; FAMILY_COUNT],
    rows_in_window: usize,
    rows_scored: usize,
    summary: replay::EstimationSummary,
}

/// One run of the bank `o` over `samples`, its rows streamed into the MSE sums of [`row_mse`]
/// (same rows, same order, same sums) without keeping them.
fn stream_mse(
    o: &EstimateOptions,
    samples: &[Sample],
    lock: &crate::score::Lock,
    acc_ref: &[f32],
    window_s: f64,
) -> Result<RunScore> {
    let axis = o.axis();
    let lim = window_end_us(window_s);
    let (mut sv, mut sa) = ([0.0f64; FAMILY_COUNT], [0.0f64; FAMILY_COUNT]);
    let (mut nv, mut na) = (0usize, 0usize);
    let (mut in_window, mut scored, mut j) = (0usize, 0usize, 0usize);
    let mut on_row = |r: Row| {
        while j < samples.len() && samples[j].t_us < r.t_us {
            j += 1;
        }
        let k = lock.scored.get(j).copied().unwrap_or(false);
        if r.t_us > lim {
            return Ok(());
        }
        in_window += 1;
        if !k {
            return Ok(());
        }
        scored += 1;
        let out = r.axis(axis).map(|a| a.out);
        let rate = r.axis(axis).and_then(|a| a.reference_deg_s);
        let accr = acc_ref.get(j).copied().unwrap_or(f32::NAN);
        let add = |sum: &mut [f64; FAMILY_COUNT], n: &mut usize, reference: f32, ch: &[Channel]| {
            if reference.is_nan() {
                return;
            }
            for (s, &c) in sum.iter_mut().zip(ch) {
                let e = out.map_or(f32::NAN, |o| o[c]);
                let d = f64::from(e) - f64::from(reference);
                *s += d * d;
            }
            *n += 1;
        };
        add(
            &mut sv,
            &mut nv,
            rate.unwrap_or(f32::NAN),
            &Channel::VELOCITY,
        );
        add(&mut sa, &mut na, accr, &Channel::ACCELERATION);
        Ok(())
    };
    let mut est = replay::Estimation::new(o)?;
    for &s in samples {
        est.push(s, &mut on_row)?;
    }
    let summary = est.finish(&mut on_row)?;
    let mean = |sum: [f64; FAMILY_COUNT], n: usize| {
        sum.map(|s| if n == 0 { f64::NAN } else { s / n as f64 })
    };
    Ok(RunScore {
        vel: mean(sv, nv),
        acc: mean(sa, na),
        rows_in_window: in_window,
        rows_scored: scored,
        summary,
    })
}

/// What the velocity MSEs are scored against.
fn velocity_reference(axis: Axis) -> String {
    format!(
        "{} rate from the packet's body rates and angles by the Euler kinematics (the z rate when level; rows with |pitch| >= {} deg left out)",
        axis.name(),
        nav440_pipeline::euler::PITCH_LIMIT_DEG
    )
}

fn hold_name(h: estimators::Hold) -> &'static str {
    match h {
        estimators::Hold::Linear => "linear",
        estimators::Hold::ZeroOrder => "zoh",
    }
}

fn noise_at_name(n: crate::replay::NoiseAt) -> &'static str {
    match n {
        crate::replay::NoiseAt::Sample => "one N(0, var) draw per packet",
        crate::replay::NoiseAt::Step => {
            "one N(0, var) draw per observer step h (yaw interpolated to the step grid)"
        }
    }
}

fn fmt_val(v: f64) -> String {
    if !v.is_finite() {
        "diverged".to_string()
    } else if v.abs() >= 1e5 {
        format!("{v:.2e}")
    } else {
        format!("{v:.1}")
    }
}

impl PaperResult {
    /// The line every output form reports about the rows scored, e.g. "rows scored: 3480 of
    /// 3501 in the MSE window (21 left out near gimbal lock (|pitch| >= 80 deg) and within 1 s
    /// after it)".
    pub fn scored_line(&self) -> String {
        let left = self.rows_in_window - self.rows_scored.min(self.rows_in_window);
        let mut s = format!(
            "rows scored: {} of {} in the MSE window",
            self.rows_scored, self.rows_in_window
        );
        if left > 0 {
            s.push_str(&format!(
                " ({left} left out near gimbal lock (|pitch| >= {} deg) and within {} s after it)",
                nav440_pipeline::euler::PITCH_LIMIT_DEG,
                crate::score::LOCK_SETTLE_S
            ));
        }
        s
    }

    /// One warning per family and table whose MSE is not finite (no row scored, or the
    /// estimate diverged), naming the window; empty when every MSE is a number.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (what, ours, clean) in [
            ("velocity", &self.vel, &self.vel_clean),
            ("acceleration", &self.acc, &self.acc_clean),
        ] {
            for (i, name) in COLUMNS.iter().enumerate() {
                let runs = [ours[0][i], ours[1][i], clean[i]];
                if runs.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let why = if self.rows_scored == 0 {
                    "no row is scored"
                } else {
                    "the estimate is not finite (diverged)"
                };
                out.push(format!(
                    "{name} {what} MSE over 0-{} s is not a number: {why}",
                    self.window_s
                ));
            }
        }
        out
    }

    /// (title, ours, paper, no-noise baseline) of Tables 1 and 3.
    #[allow(clippy::type_complexity)]
    fn tables(
        &self,
    ) -> [(
        &'static str,
        &[[f64; FAMILY_COUNT]; 2],
        &'static [[f64; 6]; 2],
        &[f64; FAMILY_COUNT],
    ); 2] {
        [
            (
                "Table 1 - velocity MSE ((deg/s)^2)",
                &self.vel,
                &PAPER_VEL_MSE,
                &self.vel_clean,
            ),
            (
                "Table 3 - acceleration MSE ((deg/s^2)^2), series connections",
                &self.acc,
                &PAPER_ACC_MSE,
                &self.acc_clean,
            ),
        ]
    }

    /// Human-readable tables: ours next to the paper's, plus our no-noise baseline.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "capture {} ({} samples, {:.2} s); hold {}, step h = {} s, MSE over 0-{} s, mean of seeds {:?}\n",
            self.capture,
            self.samples,
            self.duration_s,
            hold_name(self.hold),
            self.step_s,
            self.window_s,
            SEEDS
        ));
        s.push_str(&format!(
            "gains: {}; noise: {}\n",
            self.gains,
            noise_at_name(self.noise_at)
        ));
        s.push_str(&format!(
            "velocity reference: {}; acceleration reference: AVE (k=500, gamma1=20000) on it, same adapter\n",
            velocity_reference(self.axis)
        ));
        s.push_str(&self.scored_line());
        s.push('\n');
        for (title, ours, paper, clean) in self.tables() {
            s.push_str(&format!("\n{title}\n"));
            s.push_str(&format!("{:<14}", "sigma^2"));
            for c in COLUMNS {
                s.push_str(&format!("{c:>10}"));
            }
            s.push('\n');
            for (i, var) in NOISE_VARS.iter().enumerate() {
                s.push_str(&format!("{:<14}", format!("{var} ours")));
                for v in ours[i] {
                    s.push_str(&format!("{:>10}", fmt_val(v)));
                }
                s.push('\n');
                s.push_str(&format!("{:<14}", format!("{var} paper")));
                for v in paper[i] {
                    s.push_str(&format!("{:>10}", fmt_val(v)));
                }
                // The columns the paper has no figure for (our Kalman filter).
                for _ in paper[i].len()..FAMILY_COUNT {
                    s.push_str(&format!("{:>10}", "-"));
                }
                s.push('\n');
            }
            s.push_str(&format!("{:<14}", "0 (no noise)"));
            for v in clean {
                s.push_str(&format!("{:>10}", fmt_val(*v)));
            }
            s.push('\n');
        }
        s
    }

    /// Markdown tables (for the README).
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        if self.rows_scored < self.rows_in_window {
            s.push_str(&format!("\n{}\n", self.scored_line()));
        }
        for (title, ours, paper, clean) in self.tables() {
            s.push_str(&format!(
                "\n{title}\n\n| sigma^2 | | {} |\n|---|---|{}\n",
                COLUMNS.join(" | "),
                "---|".repeat(FAMILY_COUNT)
            ));
            for (i, var) in NOISE_VARS.iter().enumerate() {
                let o: Vec<String> = ours[i].iter().map(|&v| fmt_val(v)).collect();
                let p: Vec<String> = paper[i].iter().map(|&v| fmt_val(v)).collect();
                s.push_str(&format!("| {var} | ours | {} |\n", o.join(" | ")));
                let none = vec!["-"; FAMILY_COUNT - p.len()].join(" | ");
                s.push_str(&format!("| {var} | paper | {} | {none} |\n", p.join(" | ")));
            }
            let c: Vec<String> = clean.iter().map(|&v| fmt_val(v)).collect();
            s.push_str(&format!("| 0 | ours, no noise | {} |\n", c.join(" | ")));
        }
        s
    }

    /// The `--json` object.
    pub fn to_json(&self) -> serde_json::Value {
        let row = |vals: &[f64]| -> serde_json::Map<String, serde_json::Value> {
            COLUMNS
                .iter()
                .zip(vals)
                .map(|(c, v)| (c.to_string(), json_num(*v)))
                .collect()
        };
        let table = |ours: &[[f64; FAMILY_COUNT]; 2],
                     paper: &[[f64; 6]; 2],
                     clean: &[f64; FAMILY_COUNT]| {
            let mut m = serde_json::Map::new();
            for (i, var) in NOISE_VARS.iter().enumerate() {
                m.insert(
                    var.to_string(),
                    serde_json::json!({"ours": row(&ours[i]), "paper": row(&paper[i])}),
                );
            }
            m.insert("0".to_string(), serde_json::json!({"ours": row(clean)}));
            serde_json::Value::Object(m)
        };
        serde_json::json!({
            "capture": self.capture,
            "samples": self.samples,
            "duration_s": self.duration_s,
            "settings": {
                "hold": hold_name(self.hold),
                "step_s": self.step_s,
                "window_s": self.window_s,
                "seeds": SEEDS,
                "noise_vars": NOISE_VARS,
                "gains": self.gains,
                "noise_at": noise_at_name(self.noise_at),
                "axis": self.axis.name(),
                "velocity_reference": velocity_reference(self.axis),
                "acceleration_reference": "AVE k=500 gamma1=20000 on the velocity reference, same sample adapter",
            },
            "rows_in_window": self.rows_in_window,
            "rows_scored": self.rows_scored,
            "velocity_mse": table(&self.vel, &PAPER_VEL_MSE, &self.vel_clean),
            "acceleration_mse": table(&self.acc, &PAPER_ACC_MSE, &self.acc_clean),
        })
    }
}

fn json_num(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mse_uses_only_the_window() {
        let t = [0, 10_000_000, 30_000_000, 30_000_001];
        let est = [1.0f32, 3.0, 0.0, 100.0];
        let reference = [0.0f32, 0.0, 0.0, 0.0];
        assert_eq!(mse(&t, &est, &reference, 30.0), (1.0 + 9.0) / 3.0);
        assert!(mse(&[], &[], &[], 30.0).is_nan());
    }

    #[test]
    fn steps_between_rounds_to_whole_steps() {
        assert_eq!(steps_between(0, 10_000, 100.0), 100);
        assert_eq!(steps_between(0, 10_049, 100.0), 100);
        assert_eq!(steps_between(0, 10_050, 100.0), 101);
        assert_eq!(steps_between(10, 0, 100.0), 0);
    }
}
