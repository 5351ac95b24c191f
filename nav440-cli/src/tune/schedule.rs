//! Tuning a gain schedule: one gain set per noise level, the observers' switch points and the AVEs' `deltahat` ([`tune_schedule`]).

use super::*;

/// [`tune_family`] for both halves (velocity on a second thread), only the families
/// `(acceleration, column)` for which `which` is true (the others are `None` in the result
/// and cost infinity).
pub(super) fn tune_both(
    set: &Problems<'_>,
    start: &GainsFile,
    which: impl Fn(bool, usize) -> bool,
    method: Method,
) -> Result<(GainsFile, [[f64; FAMILY_COUNT]; 2])> {
    let v0 = start.velocity.only(|i| which(false, i));
    let a0 = start.acceleration.only(|i| which(true, i));
    let (velocity, acceleration) = std::thread::scope(|s| {
        let v = s.spawn(|| tune_family(set, &v0, false, method, Families::ALL));
        let a = tune_family(set, &a0, true, method, Families::ALL);
        (v.join(), a)
    });
    let velocity = velocity.map_err(|_| Error::Other("tuning thread panicked".into()))?;
    let mut cost = [[0.0; FAMILY_COUNT]; 2];
    for (half, stats) in [&velocity.1, &acceleration.1].into_iter().enumerate() {
        for (i, st) in stats.iter().enumerate() {
            cost[half][i] = st.0;
        }
    }
    Ok((
        GainsFile {
            velocity: velocity.0,
            acceleration: acceleration.0,
        },
        cost,
    ))
}

/// Checks the noise variances of `--schedule`: 1 to [`estimators::adaptive::MAX_LEVELS`]
/// levels, each > 0 and at most `MAX_NOISE_VAR` (1e15) deg^2, in increasing order.
pub fn check_levels(levels: &[f64]) -> Result<()> {
    if levels.is_empty()
        || levels.len() > estimators::adaptive::MAX_LEVELS
        || levels.windows(2).any(|w| w[1] <= w[0])
        || levels
            .iter()
            .any(|v| !(v.is_finite() && *v > 0.0 && *v <= crate::limits::MAX_NOISE_VAR))
    {
        return Err(Error::Usage(format!(
            "--schedule needs 1 to {} noise variances > 0 and <= 1e15 deg^2 in increasing order, got {levels:?}",
            estimators::adaptive::MAX_LEVELS
        )));
    }
    Ok(())
}

/// `nav440 tune --schedule V1,V2,..`: [`tune_with`] at each noise level (`spec.noise_var`
/// replaced; one hold: `spec.holds[0]`, linear by default); then, per velocity observer
/// family (AVE, ILO1-3, ED), each level takes the best of every level's tuned gains at its own
/// noise (the velocity MSE through the bank, the tuner's seeds and range: a level's search
/// can end in a worse basin than a neighbour's gains); records each level's AVE `deltahat`
/// ([`tuned_ave_deltahat`]) and where each observer family moves on to the next level
/// ([`crossover`] of the MSEs already scored). Returns the schedule file (with the nominal
/// sample period the bank ran at, [`EstimateOptions::bank_period_s`]) and the printed report
/// (each level's report, the gains taken from another level, the switch points). `progress`
/// is told of every objective evaluation and family fit.
pub fn tune_schedule(
    samples: &[Sample],
    opts: &EstimateOptions,
    spec: &TuneSpec,
    levels: &[f64],
    progress: &Progress,
) -> Result<(crate::gains::ScheduleFile, String)> {
    tune_schedule_on(&[samples], opts, spec, levels, progress)
}

/// [`tune_schedule`] on several captures at once (`nav440 tune FILE FILE ... --schedule`):
/// each level is tuned on all of them ([`tune_on`]); the MSEs that pick each level's observers
/// and the switch points are the means over the captures, and so is the AVE's `deltahat`. The
/// captures must share one packet rate. With one capture it is exactly [`tune_schedule`].
pub fn tune_schedule_on(
    captures: &[&[Sample]],
    opts: &EstimateOptions,
    spec: &TuneSpec,
    levels: &[f64],
    progress: &Progress,
) -> Result<(crate::gains::ScheduleFile, String)> {
    check_levels(levels)?;
    let Some(&samples) = captures.first() else {
        return Err(Error::Usage("no capture to tune on".into()));
    };
    check_one_rate(captures, opts)?;
    let hold = spec.holds.first().copied().unwrap_or(Hold::Linear);
    // A schedule is for the device, which runs for hours: its AVE is tuned with the product's
    // leaky `deltahat` law (`estimators::presets::AVE_DEFAULT`) whatever law the start gains
    // have (the start is the paper's gains, as for `nav440 tune`, unless a gains file is
    // given). The paper's law (`deltahat` only grows) degrades a long run
    // (docs/RELIABILITY.md).
    let mut start = opts.paper_law().bank_config();
    for half in [&mut start.velocity, &mut start.acceleration] {
        half.ave.delta = estimators::presets::AVE_DEFAULT.delta;
    }
    let opts = &EstimateOptions {
        config: Some(start),
        ..opts.clone()
    };
    let mut text = String::new();
    let mut tuned: Vec<GainsFile> = Vec::new();
    for &v in levels {
        let res = tune_on(
            captures,
            opts,
            &TuneSpec {
                noise_var: v,
                holds: vec![hold],
                ..spec.clone()
            },
            progress,
        )?;
        text.push_str(&format!("== schedule level {v} deg^2 ==\n"));
        text.push_str(&res.to_text());
        text.push('\n');
        tuned.push(res.gains);
    }
    let config = |g: &GainsFile| BankConfig {
        hold,
        ..g.apply(opts.bank_config_for(samples))
    };
    // Each level's observers: the best of every level's tuned gains at this level's noise
    // (the search of one level can end in a worse basin than a neighbour's gains).
    // The mean over the captures of each level's velocity MSEs at each level's noise.
    let acc_refs = captures
        .iter()
        .map(|c| ave_on_rate(c, &REFERENCE_AVE, opts))
        .collect::<Result<Vec<_>>>()?;
    let mut at = vec![vec![[0.0f64; FAMILY_COUNT]; levels.len()]; levels.len()];
    for (i, g) in tuned.iter().enumerate() {
        for (j, &v) in levels.iter().enumerate() {
            for (c, acc_ref) in captures.iter().zip(&acc_refs) {
                let seeds = 1..=spec.seeds.max(1);
                let m = bank_mse_with(c, opts, acc_ref, config(g), v, seeds, spec.train)?.0;
                for (x, y) in at[i][j].iter_mut().zip(m) {
                    *x += y;
                }
            }
            at[i][j] = at[i][j].map(|x| x / captures.len() as f64);
        }
    }
    // `source[j][c]`: the level whose tuned gains level `j` runs for the observer family of
    // column `c`.
    let mut source: Vec<[usize; FAMILY_COUNT]> =
        (0..levels.len()).map(|j| [j; FAMILY_COUNT]).collect();
    let before = tuned.clone();
    // Gains that read a constant rate low are taken only when no level's gains hold it
    // ([`holds_constant_rate`]): a motion of sustained rate (a spin) finds them biased.
    let holds: Vec<[bool; FAMILY_COUNT]> = before
        .iter()
        .map(|g| std::array::from_fn(|col| holds_constant_rate(&g.velocity, col)))
        .collect();
    for (j, &v) in levels.iter().enumerate() {
        for col in observer_columns() {
            let any_holds = holds.iter().any(|h| h[col]);
            let best = (0..levels.len())
                .filter(|&i| holds[i][col] || !any_holds)
                .min_by(|&a, &b| at[a][j][col].total_cmp(&at[b][j][col]))
                .unwrap_or(j);
            let own_holds = holds[j][col] || !any_holds;
            if best == j || (own_holds && at[best][j][col] >= at[j][j][col]) {
                continue;
            }
            source[j][col] = best;
            tuned[j].velocity.set_column(col, &before[best].velocity);
            let why = if own_holds {
                String::new()
            } else {
                format!(
                    "; its own read a constant rate {:.2} % low",
                    100.0 * (1.0 - constant_rate_gain(&before[j].velocity, col))
                )
            };
            text.push_str(&format!(
                "level {v} deg^2: {} velocity gains of level {} deg^2 (MSE {:.4} instead of {:.4} at {v} deg^2{why})\n",
                NAMES[col], levels[best], at[best][j][col], at[j][j][col]
            ));
        }
    }
    let mut level = Vec::new();
    for (g, &v) in tuned.iter().zip(levels) {
        let mut sum = [0.0f64; 3];
        for c in captures {
            let d = tuned_ave_deltahat(c, opts, &config(g), v, spec.seeds, spec.train)?;
            for (x, y) in sum
                .iter_mut()
                .zip([d.velocity, d.acceleration[0], d.acceleration[1]])
            {
                *x += f64::from(y);
            }
        }
        let m = sum.map(|x| (x / captures.len() as f64) as f32);
        let deltahat = estimators::AveDeltahat {
            velocity: m[0],
            acceleration: [m[1], m[2]],
        };
        text.push_str(&format!(
            "level {v} deg^2: AVE deltahat tuned with (mean over the run): velocity {} deg/s, AVE-AVE {} deg/s, {} deg/s^2\n",
            deltahat.velocity, deltahat.acceleration[0], deltahat.acceleration[1]
        ));
        level.push(crate::gains::ScheduleLevelFile {
            noise_var: v,
            velocity: g.velocity,
            acceleration: g.acceleration,
            ave_deltahat: Some(deltahat.into()),
            switch_up: None,
        });
    }
    // Where each observer family moves on: from the MSEs already scored (a family's velocity
    // MSE depends only on its own gains, so level `j`'s is that of its source level's).
    for i in 0..levels.len().saturating_sub(1) {
        let (a, b) = (levels[i], levels[i + 1]);
        let point = |col: usize| {
            let (sa, sb) = (source[i][col], source[i + 1][col]);
            let m = [
                at[sa][i][col],
                at[sa][i + 1][col],
                at[sb][i][col],
                at[sb][i + 1][col],
            ];
            crossover(m, a, b) as f32
        };
        let sw = switch_points(point);
        level[i].switch_up = Some(crate::gains::SwitchUpFile(sw));
        let points: Vec<String> = sw
            .points()
            .iter()
            .map(|&(col, x)| format!("{} {x}", NAMES[col]))
            .collect();
        text.push_str(&format!(
            "switch up from level {a} to {b} deg^2 (where each family takes the next level's gains: where the two levels' MSEs cross if they differ by more than {SWITCH_MATTERS}x at the midpoint, else the midpoint): {}\n",
            points.join(", ")
        ));
    }
    let motion = motion_powers(captures, opts)?;
    Ok((
        crate::gains::ScheduleFile {
            hold: hold_name(hold).to_string(),
            // The f32's shortest decimal form (0.01, not 0.009999999776482582).
            sample_period_s: opts.bank_period_s(samples).to_string().parse().ok(),
            tuned_jerk_power: motion.map(|m| m.0),
            tuned_acceleration_power: motion.map(|m| m.1),
            level,
        },
        text,
    ))
}

/// The jerk power, (deg/s^3)^2, and the acceleration power, (deg/s^2)^2, of the motion in
/// `captures` as the bank measures them: an `estimators::JerkEstimator` with a time constant
/// longer than any capture (so the plain means over the rows) fed each row's rate about the
/// tuned axis (the rate the pipeline gives the banks: the Euler reference, or the body rate
/// with `--no-reference`), over every capture (each restarts the differences). Recorded in
/// the schedule file (`tuned_jerk_power`, `tuned_acceleration_power`), so that its bank
/// follows the motion as well as the noise. `None` when there is no capture, no row has a
/// rate (a capture entirely near gimbal lock) or the period is not one the estimator takes.
pub fn motion_powers(captures: &[&[Sample]], opts: &EstimateOptions) -> Result<Option<(f64, f64)>> {
    let axis = opts.axis();
    let plain = EstimateOptions {
        noise: None,
        ..opts.clone()
    };
    let Some(first) = captures.first() else {
        return Ok(None);
    };
    let Ok(jerk) = estimators::JerkEstimator::new(1e12, opts.bank_period_s(first)) else {
        return Ok(None);
    };
    let mut jerk = jerk.with_acceleration();
    for samples in captures {
        jerk.restart();
        let (rows, _) = replay::estimate(samples, &plain)?;
        for r in &rows {
            if let Some(rate) = r.axis(axis).and_then(|a| a.reference_deg_s) {
                jerk.update(r.t_us, rate);
            }
        }
    }
    // The shortest decimal forms of the f32s (3850048, not 3850047.75).
    let shortest = |p: f32| p.to_string().parse().ok();
    Ok(jerk
        .power()
        .and_then(shortest)
        .zip(jerk.acceleration_power().and_then(shortest)))
}

/// [`crossover`] keeps the geometric midpoint unless the two levels' MSE lines differ by more
/// than this factor there.
pub const SWITCH_MATTERS: f64 = 1.2;

/// The largest shortfall on a constant rate a schedule level's velocity gains may have: 0.1 %
/// (0.3 deg/s at 300 deg/s; [`estimators::IloConfig::constant_rate_gain`]).
pub const CONSTANT_RATE_SHORTFALL: f64 = 1e-3;

/// The fraction of a constant rate the velocity gains of column `col` in `g` settle at:
/// [`estimators::IloConfig::constant_rate_gain`] for ILO1-3, 1 for the other families (their
/// laws hold a constant rate) and for gains not present.
pub fn constant_rate_gain(g: &FamilyGains, col: usize) -> f64 {
    use estimators::IloFamily;
    let ilo = match NAMES[col] {
        "ILO1" => g.get::<IloFamily<0>>(),
        "ILO2" => g.get::<IloFamily<1>>(),
        "ILO3" => g.get::<IloFamily<2>>(),
        _ => None,
    };
    ilo.map_or(1.0, |c| c.constant_rate_gain())
}

/// `true` if a constant rate gain (from [`constant_rate_gain`]) is within
/// [`CONSTANT_RATE_SHORTFALL`] of 1.
pub(super) fn holds(constant_rate_gain: f64) -> bool {
    constant_rate_gain >= 1.0 - CONSTANT_RATE_SHORTFALL
}

/// `true` if the velocity gains of column `col` in `g` read a constant rate within
/// [`CONSTANT_RATE_SHORTFALL`].
pub fn holds_constant_rate(g: &FamilyGains, col: usize) -> bool {
    holds(constant_rate_gain(g, col))
}

/// The columns of the observer families ([`Scheduling::Observer`]): those a schedule gives
/// per-level gains and switch points.
pub(super) fn observer_columns() -> impl Iterator<Item = usize> {
    (0..FAMILY_COUNT).filter(|&c| FAMILIES[c].scheduling == Scheduling::Observer)
}

/// The switch points `point(column)` of every family that records one
/// ([`Family::switch_up_mut`]).
pub(super) fn switch_points(point: impl Fn(usize) -> f32) -> estimators::ObserverSwitch {
    struct Set<P>(estimators::ObserverSwitch, P);
    impl<P: Fn(usize) -> f32> FamilyVisitor for Set<P> {
        fn family<F: Family>(&mut self, column: usize) {
            if let Some(x) = F::switch_up_mut(&mut self.0) {
                *x = (self.1)(column);
            }
        }
    }
    let none = estimators::ObserverSwitch::all(0.0);
    let mut set = Set(none, point);
    for_each_family(&mut set);
    set.0
}

/// The noise variance (deg^2) between two levels `a < b` at which level `b`'s gains become
/// the better of the two, from the MSEs `[a's gains at a, a's at b, b's at a, b's at b]`:
/// each level's log MSE taken as linear in `ln(noise)` between `a` and `b`, where the two
/// lines cross; `a` if `b`'s gains are already no worse at `a`, `b` if `a`'s are still better
/// at `b` (or an MSE is not finite and positive). The geometric midpoint when the choice
/// hardly matters there: the two lines within [`SWITCH_MATTERS`] of each other at the
/// midpoint (identical gains, or two sets about as good at both levels); moving the switch
/// then only delays it while the noise estimate follows a change.
pub fn crossover(m: [f64; 4], a: f64, b: f64) -> f64 {
    if m.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return b;
    }
    let [aa, ab, ba, bb] = m.map(f64::ln);
    let (d0, d1) = (aa - ba, ab - bb);
    if ((d0 + d1) / 2.0).abs() < SWITCH_MATTERS.ln() {
        (a * b).sqrt()
    } else if d0 >= 0.0 {
        a
    } else if d1 <= 0.0 {
        b
    } else {
        a * (b / a).powf(d0 / (d0 - d1))
    }
}

/// The AVE row's switching gains `deltahat` (`estimators::PaperBank::ave_deltahat`) that
/// the bank configuration `cfg` is tuned with on `samples` with N(0, `noise_var`) noise
/// (deg^2) on the first axis of `opts`: the mean of `deltahat` over `range` (s) in a run from
/// the capture's start (where `deltahat` starts at 0, as in every evaluation of the tuner),
/// averaged over the noise seeds `1..=seeds`. `nav440 tune --schedule` records it per level
/// (`estimators::ScheduleLevel::ave_deltahat`).
///
/// Why the tuning run's mean, not the law's steady state: the leak's time constant
/// (`1 / sigma`, 10 s) is a third of a 30 s capture, so the gains are tuned with a `deltahat`
/// that is still growing. On the noise-switch test's 40 draws, setting the fig5 schedule's
/// 0.5 deg^2 level's run mean (5.7 deg/s) at a gain change left the AVE below every fixed set
/// on 22 draws (geometric mean ratio 0.988); the steady state reached after three runs
/// (8.1 deg/s, each run starting at the previous one's mean over its second half) on 16
/// (1.027), with a worse 12-20 s MSE (157.0 against 146.9 (deg/s)^2). (Measured before the AVE's
/// retune kept `xhat` towards slower gains, which took the run mean's result to 26 draws,
/// 0.972.)
pub fn tuned_ave_deltahat(
    samples: &[Sample],
    opts: &EstimateOptions,
    cfg: &BankConfig,
    noise_var: f64,
    seeds: u64,
    range: (f64, f64),
) -> Result<estimators::AveDeltahat> {
    let axis = opts.axis();
    let (from, to) = (
        (range.0 * 1e6).round() as u64,
        (range.1 * 1e6).round() as u64,
    );
    let seeds = seeds.max(1);
    let mut sum = [0.0f64; 3];
    for seed in 1..=seeds {
        let y = replay::noisy_angle(
            samples,
            axis,
            Some(Noise {
                var: noise_var,
                seed,
            }),
        )?;
        let mut bank: estimators::PaperBank<f32> = nav440_pipeline::axis_bank(axis, cfg)
            .map_err(|e| Error::Usage(format!("bad estimator configuration: {e}")))?;
        let (mut acc, mut n) = ([0.0f64; 3], 0u32);
        for (s, &y) in samples.iter().zip(&y) {
            if bank.update(s.t_us, y).is_ok() && (from..=to).contains(&s.t_us) {
                let d = bank.ave_deltahat();
                for (a, x) in acc
                    .iter_mut()
                    .zip([d.velocity, d.acceleration[0], d.acceleration[1]])
                {
                    *a += f64::from(x);
                }
                n += 1;
            }
        }
        if n == 0 {
            return Err(Error::Usage(format!(
                "no sample in {}-{} s to measure the AVE's deltahat on",
                range.0, range.1
            )));
        }
        for (s, a) in sum.iter_mut().zip(acc) {
            *s += a / f64::from(n);
        }
    }
    let m = sum.map(|x| (x / seeds as f64) as f32);
    Ok(estimators::AveDeltahat {
        velocity: m[0],
        acceleration: [m[1], m[2]],
    })
}
