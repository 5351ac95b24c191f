//! What a replay runs: [`EstimateOptions`] (bank, gains, hold, step, noise, axes).

use super::*;

/// Options of `nav440 estimate` (and of every replay through the bank).
#[derive(Clone, Debug)]
pub struct EstimateOptions {
    /// Sample adapter input mode.
    pub hold: Hold,
    /// Observer step h, s.
    pub step_s: f32,
    /// Noise added to each estimated angle.
    pub noise: Option<Noise>,
    /// Run the fixed-point bank (`PaperBank<Fx>`) instead of f32.
    pub fixed: bool,
    /// Bank configuration with gains (from `--preset`, `--gains`); `None` =
    /// `BankConfig::NAV440` (with [`EstimateOptions::paper_law`]: `BankConfig::PAPER`).
    pub config: Option<BankConfig>,
    /// Replace the gains by the shipped preset's for the measured packet period
    /// (`BankConfig::with_nav440_gains`) once the warm-up has measured it, then apply
    /// [`EstimateOptions::overlay`]: what `nav440 estimate` does with the default `--preset
    /// nav440`, as the firmware does. Default `false`: `config`'s gains as they are.
    pub follow_rate: bool,
    /// The `--gains` file's gains, if one was given (`nav440 paper` names them in its
    /// settings). With [`EstimateOptions::follow_rate`] they are applied over the rate's preset
    /// gains (the families the file leaves out keep the preset's); without, `config` already
    /// holds them.
    pub overlay: Option<crate::gains::GainsFile>,
    /// Where the noise enters (per packet, or per observer step).
    pub noise_at: NoiseAt,
    /// The estimated axes (`--axis`; default yaw only).
    pub axes: Axes,
    /// A gain schedule (`--gains schedule.toml`): run the noise-adaptive bank
    /// (`estimators::AdaptiveBank`, `AdaptiveConfig::DEFAULT`) with `config`'s step, hold and
    /// period instead of fixed gains (paper bank only).
    pub schedule: Option<GainSchedule>,
    /// The bank `nav440 estimate` runs (`--bank`; default the paper bank). Only
    /// [`estimate_stream`] (and [`estimate_csv`]) run a bank other than the paper bank; the
    /// row APIs ([`Estimation`], [`estimate_rows`], ...) are the paper bank's and refuse
    /// another (a usage error).
    pub bank: BankKind,
    /// The rows' rate column after each angle (`--no-reference`: [`RateColumn::Body`], the
    /// unit's body rate about the axis in deg/s, column `<axis>_body_rate`, as the firmware
    /// built with `no-reference` prints; default [`RateColumn::Euler`], the Euler reference
    /// rate `<axis>_rate`). Only [`estimate_stream`] (and [`estimate_csv`]) print another
    /// column than the Euler reference; the row APIs score against it and refuse another (a
    /// usage error).
    pub rate_column: RateColumn,
    /// The product bank's gains follow the measured noise and the motion's jerk
    /// (`estimators::AdaptiveProductBank`, fed each row's rate about the axis; product bank
    /// only, one sample per packet). Default `false`: fixed gains. `nav440 estimate --bank
    /// product` sets it unless `--fixed-gains`, `--self-tune`, `--preset` or `--gains`.
    pub follow_motion: bool,
    /// The product bank tunes ILO1 online against each row's Euler reference rate
    /// (`--self-tune`: `estimators::SelfTuningProductBank`; product bank, Euler reference, one
    /// sample per packet, not with [`Self::follow_motion`]). Default `false`.
    pub self_tune: bool,
}

/// Which estimator bank `nav440 estimate` runs (`--bank`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BankKind {
    /// `estimators::PaperBank` (or `AdaptiveBank` with a gain schedule): the paper's 14
    /// estimators, CSV `t,yaw,yaw_rate,ave_v,...,kf_a` (the default).
    #[default]
    Paper,
    /// `estimators::ProductBank`: ILO1 velocity (`cfg.velocity.ilo[0]`) and Kalman
    /// acceleration (`cfg.acceleration.kf`), CSV `t,yaw,yaw_rate,ilo1_v,kf_a`: what the
    /// product firmware prints.
    Product,
}

impl BankKind {
    /// The `--bank` name.
    pub fn name(self) -> &'static str {
        match self {
            BankKind::Paper => "paper",
            BankKind::Product => "product",
        }
    }
}

/// Where the added noise enters the estimators.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NoiseAt {
    /// One N(0, V) draw per packet, added to its angle (the protocol as stated; default).
    #[default]
    Sample,
    /// The packets' unwrapped angle is linearly interpolated onto the observer's step grid
    /// (every `h` s) and an independent N(0, V) draw is added at every step; the bank is fed
    /// every step (`n = 1`) and a row is reported at each packet time. This is what a
    /// simulation that resamples the recording to the 1e-4 s integration step and adds the
    /// noise there computes (our reading of how the paper's small noise MSEs arise).
    Step,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        EstimateOptions {
            hold: Hold::Linear,
            step_s: 1e-4,
            noise: None,
            fixed: false,
            config: None,
            follow_rate: false,
            overlay: None,
            noise_at: NoiseAt::Sample,
            axes: Axes::only(Axis::Yaw),
            schedule: None,
            bank: BankKind::Paper,
            rate_column: RateColumn::Euler,
            follow_motion: false,
            self_tune: false,
        }
    }
}

impl EstimateOptions {
    /// The bank configuration these options describe (gains from `config` or the shipped
    /// preset `BankConfig::NAV440`, step and hold from the options), before adapting it to a
    /// capture.
    pub fn bank_config(&self) -> BankConfig {
        let mut cfg = self.config.unwrap_or(BankConfig::NAV440);
        cfg.h = self.step_s;
        cfg.hold = self.hold;
        cfg
    }

    /// The first estimated axis (the one `paper`, `tune` and `plot` score; yaw if none).
    pub fn axis(&self) -> Axis {
        self.axes.iter().next().unwrap_or(Axis::Yaw)
    }

    /// These options with the paper's laws as the base when no gains file is given
    /// (`BankConfig::PAPER`: the AVE's `deltahat` only grows), for the paper's experiment
    /// (`nav440 paper`, `nav440 tune`); `nav440 estimate` and the firmware run
    /// `BankConfig::NAV440` (tuned gains, leaky `deltahat`, docs/CALIBRATION.md).
    pub fn paper_law(&self) -> Self {
        Self {
            config: Some(self.config.unwrap_or(BankConfig::PAPER)),
            ..self.clone()
        }
    }

    /// [`EstimateOptions::bank_config`] with the nominal sample period set from the capture by
    /// `nav440_pipeline::period`, the causal rule the firmware uses too: the upper median of
    /// the intervals between the first [`WARMUP_SAMPLES`] samples (0.01 s for a 100 Hz capture,
    /// i.e. `BankConfig::PAPER`'s value), whatever the rate does later; a capture shorter than
    /// the warm-up uses the intervals it has, a single sample keeps the configured period. The
    /// closed-form maps and the Kalman gains are computed for it.
    pub fn bank_config_for(&self, samples: &[Sample]) -> BankConfig {
        self.at_period(
            PeriodEstimator::from_times(samples.iter().map(|s| s.t_us).take(WARMUP_SAMPLES))
                .apply(self.bank_config()),
        )
    }

    /// The configuration the bank runs once the warm-up has set `cfg`'s nominal sample
    /// period: with [`EstimateOptions::follow_rate`], the shipped preset's gains for that
    /// period with [`EstimateOptions::overlay`] over them; else `cfg` itself.
    pub fn at_period(&self, cfg: BankConfig) -> BankConfig {
        if !self.follow_rate {
            return cfg;
        }
        let cfg = cfg.with_nav440_gains();
        match &self.overlay {
            Some(g) => g.apply(cfg),
            None => cfg,
        }
    }

    /// The nominal sample period the bank runs at on `samples`, s: the step `step_s` with
    /// `--noise-at step` (the bank sees one sample per step), else
    /// [`EstimateOptions::bank_config_for`]'s.
    pub fn bank_period_s(&self, samples: &[Sample]) -> f32 {
        match self.noise_at {
            NoiseAt::Step => self.step_s,
            NoiseAt::Sample => self.bank_config_for(samples).sample_period_s,
        }
    }
}
