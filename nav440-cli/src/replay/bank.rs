//! The banks the host runs per axis: f32 or fixed point, fixed or scheduled gains, paper or product ([`HostBank`]), with the noise added per sample or per observer step.

use super::*;

/// The host's run-time choice between two banks of the same output (f32 or fixed point;
/// fixed gains or a gain schedule): a thin wrapper that is itself an
/// `estimators::EstimatorBank`.
#[derive(Clone, Copy, Debug)]
pub enum Either<A, B> {
    /// The first kind.
    A(A),
    /// The second kind.
    B(B),
}

/// A bank output as the output `O` of another bank of the same rows: a fixed-point bank's
/// output (raw `Fx` values) as the `f32` bank's, so that [`Either`] of the two has one output.
pub trait IntoOutput<O> {
    /// The output as `O` (the values `EstimatorOutput` reads, unchanged).
    fn into_output(self) -> O;
}

impl<R, const N: usize, T: estimators::Real> IntoOutput<estimators::BankOutput<R, N, f32>>
    for estimators::BankOutput<R, N, T>
where
    R: estimators::ChannelLists,
{
    fn into_output(self) -> estimators::BankOutput<R, N, f32> {
        self.to_f32()
    }
}

impl<A: EstimatorBank, B: EstimatorBank> EstimatorBank for Either<A, B>
where
    A::Output: IntoOutput<A::Output>,
    B::Output: IntoOutput<A::Output>,
{
    type Output = A::Output;

    fn update(&mut self, t_us: u64, angle_deg: f32) -> std::result::Result<A::Output, SampleError> {
        match self {
            Either::A(b) => b.update(t_us, angle_deg),
            Either::B(b) => b.update(t_us, angle_deg).map(IntoOutput::into_output),
        }
    }

    fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> std::result::Result<A::Output, SampleError> {
        match self {
            Either::A(b) => b.update_scaled(t_us, raw, exp2),
            Either::B(b) => b
                .update_scaled(t_us, raw, exp2)
                .map(IntoOutput::into_output),
        }
    }

    fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        match self {
            Either::A(b) => b.observe_rate(t_us, rate_deg_s),
            Either::B(b) => b.observe_rate(t_us, rate_deg_s),
        }
    }

    fn new_epoch(&mut self) {
        match self {
            Either::A(b) => b.new_epoch(),
            Either::B(b) => b.new_epoch(),
        }
    }

    fn reinit_count(&self) -> u32 {
        match self {
            Either::A(b) => b.reinit_count(),
            Either::B(b) => b.reinit_count(),
        }
    }

    /// The take-over of the two banks when they are of the same kind (nothing otherwise).
    fn take_over(&mut self, old: &Self) {
        match (self, old) {
            (Either::A(new), Either::A(old)) => new.take_over(old),
            (Either::B(new), Either::B(old)) => new.take_over(old),
            _ => {}
        }
    }
}

/// The paper bank as the host runs it: fixed gains (f32 or `Fx`) or a gain schedule (the
/// noise-adaptive bank, f32 or `Fx`).
pub type PaperHostBank = Either<
    Either<PaperBank<f32>, PaperBank<Fx>>,
    Either<estimators::AdaptiveBank<f32>, estimators::AdaptiveBank<Fx>>,
>;
/// The product bank as the host runs it: fixed gains (`--fixed-gains`, `--preset`, `--gains`;
/// f32 or `Fx`), gains that follow the noise and the motion (the default, `--follow`:
/// `estimators::AdaptiveProductBank`, f32 or `Fx`) or ILO1
/// tuned online against the rate (`--self-tune`: `estimators::SelfTuningProductBank`).
pub type ProductHostBank = Either<
    Either<ProductBank<f32>, ProductBank<Fx>>,
    Either<
        Either<estimators::AdaptiveProductBank<f32>, estimators::AdaptiveProductBank<Fx>>,
        Either<estimators::SelfTuningProductBank<f32>, estimators::SelfTuningProductBank<Fx>>,
    >,
>;

/// Where a self-tuning product bank's ILO1 is (`--self-tune`), for the line `nav440 estimate`
/// prints on stderr at the end.
pub trait SelfTuneStatus {
    /// The line for `axis`, `None` for a bank that does not tune itself.
    fn self_tune_line(&self, axis: Axis) -> Option<String> {
        let _ = axis;
        None
    }
}

impl SelfTuneStatus for PaperHostBank {}

impl SelfTuneStatus for ProductHostBank {
    fn self_tune_line(&self, axis: Axis) -> Option<String> {
        match self {
            Either::B(Either::B(Either::A(b))) => Some(self_tune_line(axis, b)),
            Either::B(Either::B(Either::B(b))) => Some(self_tune_line(axis, b)),
            _ => None,
        }
    }
}

/// The end-of-run line of a self-tuning bank: where it settled, or where it is.
pub fn self_tune_line<T: estimators::Real>(
    axis: Axis,
    b: &estimators::SelfTuningProductBank<T>,
) -> String {
    let (wn, zeta) = b.gains();
    match b.settled() {
        Some(s) => format!(
            "self-tune: {}: ILO1 settled at wn {:.2} rad/s, zeta {:.3} (K1 {}, L {} 1/s, K2 {}; window MSE {:.2} (deg/s)^2 against the rate) after {} moves",
            axis.name(),
            s.wn_rad_s,
            s.zeta,
            s.ilo1.k1,
            s.ilo1.l,
            s.ilo1.k2,
            s.mse,
            s.moves
        ),
        None => format!(
            "self-tune: {}: ILO1 not settled: wn {wn:.2} rad/s, zeta {zeta:.3} after {} moves",
            axis.name(),
            b.move_count()
        ),
    }
}

/// A built host bank: the bank, and for a noise-adaptive bank whose schedule was tuned at
/// another sample period (`AdaptiveBank::period_fits`): (the schedule's period, the bank's), s.
pub type BuiltBank<B> = (B, Option<(f32, f32)>);

/// How the host builds the bank `B` of `axis` for `cfg` and the options (through
/// `nav440_pipeline::axis_bank`, `adaptive_axis_bank` or `adaptive_product_axis_bank`, which
/// set the axis's unwrapping): [`EstimateOptions::fixed`] selects `Fx`,
/// [`EstimateOptions::schedule`] the noise-adaptive paper bank,
/// [`EstimateOptions::follow_motion`] the motion-adaptive product bank. Errors are the CLI's
/// messages. [`paper_bank`] and [`product_bank`].
pub type BuildBank<B> = fn(
    axis: Axis,
    cfg: &BankConfig,
    opts: &EstimateOptions,
) -> std::result::Result<BuiltBank<B>, String>;

/// The CLI's message for a configuration the bank refuses.
pub(crate) fn bad_config(cfg: &BankConfig, e: estimators::ConfigError) -> String {
    let mut m = format!("bad estimator configuration: {e}");
    if e == estimators::ConfigError::SamplePeriodTooLong {
        m.push_str(&format!(
            " (nominal sample period {} s from the capture's first {WARMUP_SAMPLES} samples, h = {} s; use a larger --step)",
            cfg.sample_period_s, cfg.h
        ));
    }
    m
}

/// `(fits, schedule's period, bank's period)` of an adaptive bank -> the misfit, if any.
pub(crate) fn misfit(fits: bool, tuned: &GainSchedule, run: f32) -> Option<(f32, f32)> {
    if fits {
        return None;
    }
    Some((tuned.sample_period_s()?, run))
}

/// The paper bank of `axis` ([`BuildBank`]).
pub fn paper_bank(
    axis: Axis,
    cfg: &BankConfig,
    opts: &EstimateOptions,
) -> std::result::Result<BuiltBank<PaperHostBank>, String> {
    let bad = |e| bad_config(cfg, e);
    let fixed = opts.fixed;
    if opts.follow_motion {
        return Err(FOLLOW_PAPER.to_string());
    }
    if opts.self_tune {
        return Err(SELF_TUNE_PAPER.to_string());
    }
    if let Some(sched) = opts.schedule.as_ref() {
        return Ok(if fixed {
            let b: estimators::AdaptiveBank<Fx> =
                adaptive_axis_bank(axis, cfg, sched).map_err(bad)?;
            let m = misfit(b.period_fits(), b.schedule(), b.sample_period_s());
            (Either::B(Either::B(b)), m)
        } else {
            let b: estimators::AdaptiveBank<f32> =
                adaptive_axis_bank(axis, cfg, sched).map_err(bad)?;
            let m = misfit(b.period_fits(), b.schedule(), b.sample_period_s());
            (Either::B(Either::A(b)), m)
        });
    }
    let bank = if fixed {
        Either::B(axis_bank(axis, cfg).map_err(bad)?)
    } else {
        Either::A(axis_bank(axis, cfg).map_err(bad)?)
    };
    Ok((Either::A(bank), None))
}

/// The product bank of `axis` ([`BuildBank`]; a schedule is refused).
pub fn product_bank(
    axis: Axis,
    cfg: &BankConfig,
    opts: &EstimateOptions,
) -> std::result::Result<BuiltBank<ProductHostBank>, String> {
    if opts.schedule.is_some() {
        return Err(PRODUCT_SCHEDULE.to_string());
    }
    let bad = |e| bad_config(cfg, e);
    let bank = match (opts.follow_motion, opts.self_tune, opts.fixed) {
        (true, true, _) => return Err(FOLLOW_SELF_TUNE.to_string()),
        (false, false, false) => Either::A(Either::A(axis_bank(axis, cfg).map_err(bad)?)),
        (false, false, true) => Either::A(Either::B(axis_bank(axis, cfg).map_err(bad)?)),
        (true, false, false) => Either::B(Either::A(Either::A(
            adaptive_product_axis_bank(axis, cfg).map_err(bad)?,
        ))),
        (true, false, true) => Either::B(Either::A(Either::B(
            adaptive_product_axis_bank(axis, cfg).map_err(bad)?,
        ))),
        (false, true, false) => Either::B(Either::B(Either::A(
            self_tuning_product_axis_bank(axis, cfg).map_err(bad)?,
        ))),
        (false, true, true) => Either::B(Either::B(Either::B(
            self_tuning_product_axis_bank(axis, cfg).map_err(bad)?,
        ))),
    };
    Ok((bank, None))
}

/// Why the paper bank refuses `--follow`.
pub(crate) const FOLLOW_PAPER: &str = "--follow makes the product bank's gains follow the noise and the motion (estimators::AdaptiveProductBank): use it with --bank product";

/// Why the paper bank refuses `--self-tune`.
pub(crate) const SELF_TUNE_PAPER: &str = "--self-tune tunes the product bank's ILO1 online against the rate (estimators::SelfTuningProductBank): use it with --bank product";

/// Why `--follow` and `--self-tune` do not go together.
pub(crate) const FOLLOW_SELF_TUNE: &str =
    "--follow and --self-tune are two ways to move the product bank's gains: pick one";

/// Why `--self-tune` needs the Euler reference.
pub(crate) const SELF_TUNE_BODY: &str = "--self-tune tunes ILO1 against the Euler reference rate of each angle; --no-reference gives the body rates, which are not the angles' rates when the unit is tilted: drop --no-reference";

/// Why `--bank product` refuses a gain schedule.
pub(crate) const PRODUCT_SCHEDULE: &str = "--bank product runs ILO1 and the Kalman (gains that follow the motion, or fixed); a gain schedule (a --gains file written by `nav440 tune --schedule`) runs the noise-adaptive paper bank: use --bank paper, or a fixed gains file";

/// The added noise: N(0, var) draws from xoshiro256++ seeded with the seed, in order.
#[derive(Clone)]
pub(crate) struct NoiseGen {
    normal: Normal<f64>,
    rng: Xoshiro256PlusPlus,
    active: bool,
}

impl NoiseGen {
    pub(crate) fn new(noise: Option<Noise>, axis: Axis) -> Result<Self> {
        let (var, seed) = noise.map_or((0.0, 0), |n| (n.var, axis_seed(n.seed, axis)));
        let normal = Normal::new(0.0, var.max(0.0).sqrt())
            .map_err(|e| Error::Usage(format!("bad noise variance {var}: {e}")))?;
        Ok(NoiseGen {
            normal,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
            active: var > 0.0,
        })
    }

    /// `y` plus the next draw (exactly `y` without noise).
    fn add(&mut self, y: f64) -> f32 {
        if self.active {
            (y + self.normal.sample(&mut self.rng)) as f32
        } else {
            y as f32
        }
    }
}

/// What the [`NoiseAt::Step`] mode remembers between samples.
#[derive(Clone)]
pub(crate) struct StepState {
    /// Observer step, us.
    h_us: u64,
    /// The gap rule of the packet-rate bank ([`NoiseAt::Sample`]), us: an interval beyond it
    /// is not interpolated; the bank re-initialises there, as in sample mode.
    gap_us: u64,
    /// Restarts at such gaps.
    gaps: u32,
    /// Unwrapping (the rule of [`unwrap_deg`]; `None` for pitch, which does not wrap).
    unwrap: Option<DegUnwrapper>,
    /// The previous sample's time (us) and unwrapped angle (deg).
    prev: Option<(u64, f32)>,
    /// The pending new epoch went to the bank with the sample's rate
    /// ([`EstimatorBank::observe_rate`]); the update still keeps it from interpolating.
    epoch_sent: bool,
}

/// The host's bank of one axis: the bank `B` (the paper bank's by default, [`PaperHostBank`]),
/// the added noise and the per-mode state; `nav440_pipeline` drives it, as it drives any
/// `EstimatorBank`.
pub struct HostBank<B = PaperHostBank> {
    bank: B,
    axis: Axis,
    /// A new epoch was announced ([`EstimatorBank::new_epoch`]) for the next sample.
    new_epoch: bool,
    misfit: Option<(f32, f32)>,
    noise: NoiseGen,
    step: Option<StepState>,
}

impl<B> std::fmt::Debug for HostBank<B> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostBank").finish_non_exhaustive()
    }
}

impl<B: EstimatorBank> HostBank<B> {
    /// The bank of `axis` built by `build` for the options `opts` and the warm-up's
    /// configuration `cfg`.
    pub(crate) fn new(
        axis: Axis,
        opts: &EstimateOptions,
        cfg: &BankConfig,
        build: BuildBank<B>,
    ) -> std::result::Result<Self, String> {
        let mut cfg = opts.at_period(*cfg);
        let noise = NoiseGen::new(opts.noise, axis).map_err(|e| e.to_string())?;
        let step = if opts.noise_at == NoiseAt::Step {
            // The packet-level gap rule (the bank itself sees one sample per step).
            let gap_us = s_to_us(cfg.max_gap_s());
            // The bank sees one sample per step: closed-form maps and Kalman gains for that
            // period.
            cfg.sample_period_s = opts.step_s;
            Some(StepState {
                h_us: (f64::from(opts.step_s) * 1e6).round().max(1.0) as u64,
                gap_us,
                gaps: 0,
                unwrap: axis.wraps().then(DegUnwrapper::default),
                prev: None,
                epoch_sent: false,
            })
        } else {
            None
        };
        let (bank, misfit) = build(axis, &cfg, opts)?;
        Ok(HostBank {
            bank,
            axis,
            new_epoch: false,
            misfit,
            noise,
            step,
        })
    }

    /// For a noise-adaptive bank whose schedule was tuned at another sample period
    /// (`AdaptiveBank::period_fits`): (the schedule's period, the bank's), s.
    pub(crate) fn schedule_misfit(&self) -> Option<(f32, f32)> {
        self.misfit
    }
}

impl<B: SelfTuneStatus> HostBank<B> {
    /// The self-tuning bank's end-of-run line ([`SelfTuneStatus`]).
    pub(crate) fn self_tune_line(&self) -> Option<String> {
        self.bank.self_tune_line(self.axis)
    }
}

impl<B: EstimatorBank> EstimatorBank for HostBank<B> {
    type Output = B::Output;

    /// The per-sample step of both noise modes.
    fn update(&mut self, t_us: u64, angle_deg: f32) -> std::result::Result<B::Output, SampleError> {
        let new_epoch = core::mem::take(&mut self.new_epoch);
        let r = self;
        match r.step.as_mut() {
            None => {
                if new_epoch {
                    r.bank.new_epoch();
                }
                let y = r.noise.add(f64::from(angle_deg));
                r.bank.update(t_us, y)
            }
            Some(st) => {
                // The bank has had this sample's epoch already (given with its rate).
                let sent = core::mem::take(&mut st.epoch_sent);
                let y = match st.unwrap.as_mut() {
                    Some(u) => u.push(angle_deg),
                    None => angle_deg,
                };
                let prev = st.prev.replace((t_us, y));
                match prev {
                    None => r.bank.update(t_us, r.noise.add(f64::from(y))),
                    // A new epoch, or a gap the sample-mode bank re-initialises on: no
                    // interpolation across it; the bank restarts from this sample.
                    Some((pt, _)) if new_epoch || t_us.saturating_sub(pt) > st.gap_us => {
                        if !new_epoch {
                            st.gaps = st.gaps.saturating_add(1);
                        }
                        if !sent {
                            r.bank.new_epoch();
                        }
                        r.bank.update(t_us, r.noise.add(f64::from(y)))
                    }
                    Some((pt, py)) if t_us > pt => {
                        let h_us = st.h_us;
                        let n = ((t_us - pt + h_us / 2) / h_us).max(1);
                        let mut last = Err(SampleError::NonIncreasingTime);
                        for j in 1..=n {
                            let t = if j == n { t_us } else { pt + j * h_us };
                            let yi = f64::from(py)
                                + (f64::from(y) - f64::from(py)) * j as f64 / n as f64;
                            last = r.bank.update(t, r.noise.add(yi));
                        }
                        last
                    }
                    Some(_) => Err(SampleError::NonIncreasingTime),
                }
            }
        }
    }

    /// The rate goes to the bank as it is (the noise is the angle's). A new epoch announced
    /// for this sample reaches the bank first, as in the firmware (whose pipeline calls
    /// `new_epoch`, `observe_rate`, `update` in that order): a bank that differences the rate
    /// (the jerk estimate of `AdaptiveProductBank` and of a schedule that follows the motion)
    /// must not difference across the epoch.
    fn observe_rate(&mut self, t_us: u64, rate_deg_s: f32) {
        if self.new_epoch {
            match self.step.as_mut() {
                None => self.new_epoch = false,
                // The update still needs the flag (no interpolation across the epoch); the
                // bank has had its epoch.
                Some(st) => st.epoch_sent = true,
            }
            self.bank.new_epoch();
        }
        self.bank.observe_rate(t_us, rate_deg_s);
    }

    fn new_epoch(&mut self) {
        self.new_epoch = true;
    }

    fn reinit_count(&self) -> u32 {
        match &self.step {
            Some(st) => st.gaps,
            None => self.bank.reinit_count(),
        }
    }

    /// The bank's take-over (unwrapper, gap count), and the noise generator and the
    /// per-step mode's unwrapping and gap count continue where they were.
    fn take_over(&mut self, old: &Self) {
        self.bank.take_over(&old.bank);
        self.noise = old.noise.clone();
        if let (Some(st), Some(old_st)) = (self.step.as_mut(), old.step.clone()) {
            st.unwrap = old_st.unwrap;
            st.gaps = old_st.gaps;
            st.prev = old_st.prev;
        }
    }
}

/// The host's bank constructor (captures the options).
pub(crate) type BuildFn<B = PaperHostBank> =
    Box<dyn FnMut(Axis, &BankConfig) -> std::result::Result<HostBank<B>, String>>;

/// The pipeline's bank constructor: [`HostBank::new`] with `build` and the options.
pub(crate) fn build_fn<B: EstimatorBank + 'static>(
    opts: &EstimateOptions,
    build: BuildBank<B>,
) -> BuildFn<B> {
    let opts = opts.clone();
    Box::new(move |axis, cfg| HostBank::new(axis, &opts, cfg, build))
}

/// `nav440 estimate`'s pipeline: `nav440_pipeline::Pipeline` with the host's banks and the
/// rate column `R` (the Euler reference by default).
pub(crate) type HostPipeline<B, R = nav440_pipeline::EulerReference> =
    Pipeline<HostBank<B>, String, BuildFn<B>, 3, R>;

/// The options' bank is one the row APIs run (the paper bank's), with the Euler reference
/// they score against.
pub(crate) fn check_paper_bank(opts: &EstimateOptions) -> Result<()> {
    if opts.rate_column != RateColumn::Euler {
        return Err(Error::Usage(
            "--no-reference is for `nav440 estimate` and `nav440 live` only (their CSV); this command scores against the Euler reference"
                .into(),
        ));
    }
    match opts.bank {
        BankKind::Paper => Ok(()),
        k => Err(Error::Usage(format!(
            "--bank {} is for `nav440 estimate` only (its CSV); this command runs the paper bank",
            k.name()
        ))),
    }
}

/// The options' bank accepts the options: a gain schedule needs the paper bank, `--follow`
/// the product bank and one sample per packet (a usage error otherwise).
pub fn check_bank_options(opts: &EstimateOptions) -> Result<()> {
    if opts.bank == BankKind::Product && opts.schedule.is_some() {
        return Err(Error::Usage(PRODUCT_SCHEDULE.to_string()));
    }
    if opts.follow_motion && opts.bank != BankKind::Product {
        return Err(Error::Usage(FOLLOW_PAPER.to_string()));
    }
    if opts.follow_motion && opts.noise_at == NoiseAt::Step {
        return Err(Error::Usage(FOLLOW_STEP.to_string()));
    }
    if opts.self_tune {
        let refused = if opts.bank != BankKind::Product {
            Some(SELF_TUNE_PAPER)
        } else if opts.follow_motion {
            Some(FOLLOW_SELF_TUNE)
        } else if opts.rate_column != RateColumn::Euler {
            Some(SELF_TUNE_BODY)
        } else if opts.noise_at == NoiseAt::Step {
            Some(SELF_TUNE_STEP)
        } else {
            None
        };
        if let Some(m) = refused {
            return Err(Error::Usage(m.to_string()));
        }
    }
    Ok(())
}

/// Why `--self-tune` refuses `--noise-at step`.
pub(crate) const SELF_TUNE_STEP: &str = "--self-tune compares one sample per packet with the packet's rate; --noise-at step feeds the bank every observer step: use --noise-at sample";

/// Why `--follow` refuses `--noise-at step`.
pub(crate) const FOLLOW_STEP: &str = "the product bank's gains follow the motion (by default, or with --follow) from one sample per packet; --noise-at step feeds the bank every observer step: use --noise-at sample, or --fixed-gains";
