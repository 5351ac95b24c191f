//! Tuning one gain set for a family of motions and noise levels: how the shipped preset `BankConfig::NAV440` is tuned ([`tune_preset`]).

use super::*;

/// One case of the shipped preset's tuning family: a capture's samples, a noise level and
/// the MSE range.
#[derive(Clone, Debug)]
pub struct PresetCase {
    /// Name printed in the report.
    pub name: String,
    /// The capture's samples.
    pub samples: Vec<Sample>,
    /// Noise variance added to yaw, deg^2.
    pub noise_var: f64,
    /// Noise seed.
    pub seed: u64,
    /// MSE range, s.
    pub range: (f64, f64),
}

/// A preset's tuning family from synthetic motions: each motion (profile, shape seed, packet
/// rate Hz, duration s; [`crate::synth::a2_samples`]) at each of `noise_vars` (deg^2), MSE
/// over the whole capture. Noise seed 1 for the fig5 motions (their seed is their shape's),
/// the motion's seed for the closed-form spin and sin5 (it only draws their noise).
pub fn synth_family(
    motions: &[(crate::motion::ProfileKind, u64, u32, f64)],
    noise_vars: &[f64],
) -> Result<Vec<PresetCase>> {
    let mut cases = Vec::new();
    for &(profile, seed, rate_hz, duration_s) in motions {
        let samples = crate::synth::a2_samples(profile, seed, rate_hz, duration_s)?;
        for &noise_var in noise_vars {
            cases.push(PresetCase {
                name: format!(
                    "{} seed {seed} {rate_hz} Hz, {noise_var} deg^2",
                    profile.name()
                ),
                samples: samples.clone(),
                noise_var,
                seed: if profile == crate::motion::ProfileKind::Fig5 {
                    1
                } else {
                    seed
                },
                range: (0.0, duration_s),
            });
        }
    }
    Ok(cases)
}

/// Tunes one set of gains for a whole family of cases (the shipped preset,
/// `BankConfig::NAV440`): each family's objective is, without `beat`, the geometric mean over
/// the cases of its MSE (the objective of `nav440 tune`, one noise seed per case, `seed`), so
/// that no case's scale dominates; with `beat`, the worst ratio of that MSE to `beat`'s MSE
/// on the same case and seed, times the geometric mean of the ratios to the power 0.2, plus 1
/// unless it beats `beat` in every case. Starts from `base`'s gains (the paper's gains; the
/// AVE keeps `base`'s `deltahat` law), with `base`'s hold and step.
///
/// With `beat`, a family that does not beat it in every case after that search (an objective
/// of 1 or more: the worst case cannot be beaten) is searched a second time from `base`'s
/// gains with the hinge objective (see `Problems`: every case not beaten by 1 % counts, where the first
/// objective only sees the worst one). The second result is kept if, scored through the whole
/// bank, it loses fewer cases to `beat` (MSE ratio >= 1) and its geometric mean ratio is not
/// larger; otherwise the first is kept (the hinge objective does not reward a case beyond
/// 1 %, so it may lose quality everywhere to win one case).
///
/// With `constant_rate` (a fraction: [`CONSTANT_RATE_SHORTFALL`] for 0.1 %), both searches
/// run every velocity ILO held to it ([`crate::search::holding_constant_rate`]), so the tuned
/// ILOs read a constant rate within it; the acceleration half is searched as without.
///
/// Returns the gains, per family (velocity, acceleration) the kept search's objective, and a
/// report of the second search's selection (cases lost and geometric mean ratio of both
/// results, per family searched twice; empty without `beat`).
pub fn tune_preset(
    cases: &[PresetCase],
    base: &BankConfig,
    beat: Option<&BankConfig>,
    method: Method,
    constant_rate: Option<f64>,
) -> Result<(GainsFile, [[f64; FAMILY_COUNT]; 2], String)> {
    let opts = EstimateOptions {
        hold: base.hold,
        step_s: base.h,
        config: Some(*base),
        ..Default::default()
    };
    let axis = opts.axis();
    let mut problems = Vec::new();
    let mut baselines = Vec::new();
    let mut acc_refs = Vec::new();
    for c in cases {
        let acc_ref = ave_on_rate(&c.samples, &REFERENCE_AVE, &opts)?;
        if let Some(b) = beat {
            let (v, a) = bank_mse_with(
                &c.samples,
                &opts,
                &acc_ref,
                *b,
                c.noise_var,
                c.seed..=c.seed,
                c.range,
            )?;
            baselines.push([v, a]);
        }
        acc_refs.push(acc_ref);
    }
    for (c, acc_ref) in cases.iter().zip(&acc_refs) {
        let ys = noisy_inputs(&c.samples, axis, c.noise_var, std::iter::once(c.seed))?;
        let cfg = opts.bank_config_for(&c.samples);
        problems.push(Problem {
            samples: &c.samples,
            ys,
            vel_ref: c
                .samples
                .iter()
                .map(|s| s.reference(axis).unwrap_or(f32::NAN))
                .collect(),
            acc_ref: acc_ref.clone(),
            opts: &opts,
            max_gap_s: cfg.max_gap_s(),
            sample_period_s: cfg.sample_period_s,
            range: c.range,
            lock: crate::score::Lock::of(&c.samples, axis),
            progress: None,
        });
    }
    let start = GainsFile::from_bank(base);
    let first = Problems {
        problems: &problems,
        baselines: beat.map(|_| baselines.as_slice()),
        hinge: false,
        constant_rate,
    };
    let (mut gains, mut cost) = tune_both(&first, &start, |_, _| true, method)?;
    if beat.is_none() {
        return Ok((gains, cost, String::new()));
    }
    // Second search, hinge objective, for the families that could not beat `beat` everywhere.
    let infeasible = cost;
    let second = Problems {
        problems: &problems,
        baselines: Some(&baselines),
        hinge: true,
        constant_rate,
    };
    let (hinged, hinge_cost) = tune_both(
        &second,
        &start,
        |acc, i| infeasible[usize::from(acc)][i] >= 1.0,
        method,
    )?;
    let score = |g: &GainsFile| -> Result<[[(usize, f64); FAMILY_COUNT]; 2]> {
        let cfg = g.apply(*base);
        let mut out = [[(0usize, 0.0f64); FAMILY_COUNT]; 2];
        for ((c, acc_ref), base_mse) in cases.iter().zip(&acc_refs).zip(&baselines) {
            let (v, a) = bank_mse_with(
                &c.samples,
                &opts,
                acc_ref,
                cfg,
                c.noise_var,
                c.seed..=c.seed,
                c.range,
            )?;
            for (half, m) in [v, a].iter().enumerate() {
                for i in 0..FAMILY_COUNT {
                    let r = m[i] / base_mse[half][i];
                    out[half][i].0 += usize::from(r >= 1.0);
                    out[half][i].1 += r.ln() / cases.len() as f64;
                }
            }
        }
        Ok(out)
    };
    // The first gains with every family searched twice replaced by its second result.
    let mut merged = gains;
    for (half, (m, h)) in [
        (&mut merged.velocity, &hinged.velocity),
        (&mut merged.acceleration, &hinged.acceleration),
    ]
    .into_iter()
    .enumerate()
    {
        for i in (0..FAMILY_COUNT).filter(|&i| infeasible[half][i] >= 1.0) {
            m.set_column(i, h);
        }
    }
    let (s1, s2) = (score(&gains)?, score(&merged)?);
    let mut report = String::new();
    for half in 0..2 {
        for i in (0..FAMILY_COUNT).filter(|&i| infeasible[half][i] >= 1.0) {
            let (l1, g1) = s1[half][i];
            let (l2, g2) = s2[half][i];
            let keep = l2 < l1 && g2 <= g1;
            report += &format!(
                "{} {}: first search {l1} of {n} cases lost, geometric mean ratio {:.3}; hinge search {l2} lost, {:.3}: {} kept\n",
                ["velocity", "acceleration"][half],
                NAMES[i],
                g1.exp(),
                g2.exp(),
                if keep { "hinge" } else { "first" },
                n = cases.len(),
            );
            if keep {
                let (dst, src) = if half == 0 {
                    (&mut gains.velocity, &hinged.velocity)
                } else {
                    (&mut gains.acceleration, &hinged.acceleration)
                };
                dst.set_column(i, src);
                cost[half][i] = hinge_cost[half][i];
            }
        }
    }
    Ok((gains, cost, report))
}
