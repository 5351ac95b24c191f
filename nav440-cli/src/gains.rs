//! Gains file (TOML): what `nav440 tune` writes and `--gains FILE` reads.
//!
//! ```toml
//! [velocity.ave]            # estimators::AveConfig { k, gamma1, delta }
//! k = 500.0
//! gamma1 = 20000.0
//! delta = { leaky = { sigma = 0.1 } }   # or "paper", or { bounded = { max = 1e3 } };
//!                                       # optional: left out, the base's law is kept
//! [velocity.ilo1]           # estimators::IloConfig { k1, l, k2 } (tau = h)
//! k1 = 1.0
//! l = 4.0
//! k2 = 0.2
//! # ... ilo2, ilo3
//! [velocity.ad]             # estimators::AdConfig { t }: s / (T s + 1)
//! t = 0.01
//! [velocity.ed]             # estimators::EdConfig { lambda, alpha }
//! lambda = 700.0
//! alpha = 770.0
//! [velocity.kf]             # estimators::KalmanNoise { q, r } (dt = nominal sample period)
//! q = 1e6
//! r = 0.01
//! [acceleration.ave]        # the same tables for the series (acceleration) estimators
//! ...
//! ```
//! Every table is optional (what is left out keeps the preset); within a table every key but
//! `delta` is required. The tables deserialize straight into the estimators crate's
//! configuration types (its `serde` feature).

use crate::error::{Error, Result};
use estimators::{AdConfig, AveConfig, BankConfig, BankGains, EdConfig, IloConfig, KalmanNoise};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Gains of one bank half (velocity estimators or acceleration series): the estimators
/// crate's own configuration types (its `serde` feature), one optional TOML table each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FamilyGains {
    /// AVE (series: both stages). A table without `delta` keeps the base's `deltahat` law
    /// (see [`FamilyGains::ave_delta_from_base`]).
    pub ave: Option<AveConfig>,
    /// ILO preset 1 (`tau = h`).
    pub ilo1: Option<IloConfig>,
    /// ILO preset 2.
    pub ilo2: Option<IloConfig>,
    /// ILO preset 3.
    pub ilo3: Option<IloConfig>,
    /// AD time constant.
    pub ad: Option<AdConfig>,
    /// ED.
    pub ed: Option<EdConfig>,
    /// Kalman tracker noise (`dt` = nominal sample period).
    pub kf: Option<KalmanNoise>,
    /// The `[*.ave]` table had no `delta` key (files written before it existed): applying
    /// keeps the base configuration's `deltahat` law.
    #[serde(skip)]
    pub ave_delta_from_base: bool,
}

/// A whole gains file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GainsFile {
    /// Velocity estimators.
    #[serde(default)]
    pub velocity: FamilyGains,
    /// Acceleration (series) estimators.
    #[serde(default)]
    pub acceleration: FamilyGains,
}

impl GainsFile {
    /// Parses TOML text.
    pub fn from_toml(text: &str) -> Result<Self> {
        let bad = |e: &dyn std::fmt::Display| {
            Error::Usage(format!("bad gains file: {}", one_line(&e.to_string())))
        };
        let mut table: toml::Table = toml::from_str(text).map_err(|e| bad(&e))?;
        // `[*.ave]` without `delta`: a placeholder law, replaced by the base's on apply.
        let mut from_base = [false; 2];
        for (half, flag) in ["velocity", "acceleration"]
            .iter()
            .zip(from_base.iter_mut())
        {
            if let Some(toml::Value::Table(ave)) = table
                .get_mut(*half)
                .and_then(|h| h.as_table_mut())
                .and_then(|h| h.get_mut("ave"))
            {
                if !ave.contains_key("delta") {
                    ave.insert("delta".into(), toml::Value::String("paper".into()));
                    *flag = true;
                }
            }
        }
        let mut g: GainsFile = table.try_into().map_err(|e| bad(&e))?;
        g.velocity.ave_delta_from_base = from_base[0];
        g.acceleration.ave_delta_from_base = from_base[1];
        Ok(g)
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// What `--gains FILE` holds: fixed gains, or a gain schedule (noise-adaptive bank).
#[derive(Clone, Debug, PartialEq)]
pub enum Loaded {
    /// A gains file, applied over the base preset.
    Fixed(GainsFile),
    /// A schedule file (`nav440 tune --schedule`).
    Schedule(ScheduleFile),
}

/// One level of a schedule file: a noise variance and the gains tuned for it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleLevelFile {
    /// Noise variance, deg^2.
    pub noise_var: f64,
    /// Velocity gains (every table present).
    pub velocity: FamilyGains,
    /// Acceleration gains.
    pub acceleration: FamilyGains,
    /// The AVEs' switching gains these gains were tuned with, their mean over the tuning run
    /// (`estimators::ScheduleLevel::ave_deltahat`; optional: without it a gain change keeps
    /// the AVEs' `deltahat`, as files written before it was recorded do).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ave_deltahat: Option<AveDeltahatFile>,
    /// Where each observer family moves on to the next level
    /// (`estimators::ScheduleLevel::switch_up`; optional: without it, at the geometric
    /// midpoint of the two levels, as files written before it was recorded do).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub switch_up: Option<SwitchUpFile>,
}

/// The `[level.switch_up]` table of a schedule file (`estimators::ObserverSwitch`): the noise
/// variance (deg^2) from which each observer family takes the next level's gains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SwitchUpFile {
    /// AVE, deg^2.
    pub ave: f32,
    /// ILO1, deg^2.
    pub ilo1: f32,
    /// ILO2, deg^2.
    pub ilo2: f32,
    /// ILO3, deg^2.
    pub ilo3: f32,
    /// ED, deg^2.
    pub ed: f32,
}

impl From<SwitchUpFile> for estimators::ObserverSwitch {
    fn from(w: SwitchUpFile) -> Self {
        estimators::ObserverSwitch {
            ave: w.ave,
            ilo: [w.ilo1, w.ilo2, w.ilo3],
            ed: w.ed,
        }
    }
}

/// The `[level.ave_deltahat]` table of a schedule file (`estimators::AveDeltahat`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AveDeltahatFile {
    /// The velocity AVE's `deltahat`, deg/s.
    pub velocity: f32,
    /// The AVE-AVE series' stages', deg/s and deg/s^2.
    pub acceleration: [f32; 2],
}

impl From<AveDeltahatFile> for estimators::AveDeltahat {
    fn from(d: AveDeltahatFile) -> Self {
        estimators::AveDeltahat {
            velocity: d.velocity,
            acceleration: d.acceleration,
        }
    }
}

impl From<estimators::AveDeltahat> for AveDeltahatFile {
    fn from(d: estimators::AveDeltahat) -> Self {
        AveDeltahatFile {
            velocity: d.velocity,
            acceleration: d.acceleration,
        }
    }
}

/// A schedule file (TOML), what `nav440 tune --schedule V1,V2,.. -o FILE` writes:
///
/// ```toml
/// hold = "linear"            # the hold the levels were tuned with ("linear" or "zoh")
/// sample_period_s = 0.01     # the nominal sample period they were tuned at, s (optional)
/// [[level]]
/// noise_var = 0.001          # deg^2, increasing from level to level
/// [level.velocity.ave]       # the tables of a gains file, every one present
/// ...
/// [level.ave_deltahat]       # optional: the AVEs' deltahat this level was tuned with
/// velocity = 0.9             # deg/s
/// acceleration = [0.9, 12.0] # the AVE-AVE series' stages, deg/s and deg/s^2
/// [level.switch_up]          # optional: the noise (deg^2) from which each observer family
/// ave = 0.006                # takes the next level's gains (default: the two levels'
/// ilo1 = 0.003               # geometric midpoint)
/// ilo2 = 0.003
/// ilo3 = 0.003
/// ed = 0.002
/// [[level]]
/// noise_var = 0.01
/// ...
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleFile {
    /// The hold the levels were tuned with: "linear" or "zoh".
    pub hold: String,
    /// The nominal sample period the levels were tuned at, s (`None`: not recorded, as in
    /// files written before it was). `nav440 estimate --gains` warns when a capture's period
    /// does not fit it (`estimators::GainSchedule::fits_period`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_period_s: Option<f64>,
    /// The levels, by increasing noise variance.
    pub level: Vec<ScheduleLevelFile>,
}

impl ScheduleFile {
    /// The hold named in the file.
    pub fn hold(&self) -> Result<estimators::Hold> {
        match self.hold.as_str() {
            "linear" => Ok(estimators::Hold::Linear),
            "zoh" => Ok(estimators::Hold::ZeroOrder),
            h => Err(Error::Usage(format!(
                "bad schedule file: hold must be \"linear\" or \"zoh\", got {h:?}"
            ))),
        }
    }

    /// The schedule over `base`'s gains (tables left out keep `base`'s).
    pub fn schedule(&self, base: &BankConfig) -> Result<estimators::GainSchedule> {
        let levels: Vec<estimators::ScheduleLevel> = self
            .level
            .iter()
            .map(|l| estimators::ScheduleLevel {
                noise_var: l.noise_var as f32,
                velocity: l.velocity.apply(base.velocity),
                acceleration: l.acceleration.apply(base.acceleration),
                ave_deltahat: l.ave_deltahat.map(Into::into),
                switch_up: l.switch_up.map(Into::into),
            })
            .collect();
        let schedule = estimators::GainSchedule::new(&levels);
        match self.sample_period_s {
            None => schedule,
            Some(p) => schedule.and_then(|s| s.with_sample_period(p as f32)),
        }
        .map_err(|e| Error::Usage(format!("bad schedule file: {e}")))
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// A Rust snippet: the schedule's levels as a const array and the period they were tuned
    /// at (for the firmware: `GainSchedule::new(&SCHEDULE)`, then `with_sample_period` if
    /// `SCHEDULE_PERIOD_S` is `Some`), over `base`'s gains.
    pub fn to_rust(&self, what: &str, base: &BankConfig) -> String {
        let period = match self.sample_period_s {
            Some(p) => format!("Some({:?})", p as f32),
            None => "None".to_string(),
        };
        // `AveDeltahat` and `ObserverSwitch` only when a level records them (an unused import
        // would warn).
        let deltahat = if self.level.iter().any(|l| l.ave_deltahat.is_some()) {
            "AveDeltahat, "
        } else {
            ""
        };
        let switch = if self.level.iter().any(|l| l.switch_up.is_some()) {
            ", ObserverSwitch"
        } else {
            ""
        };
        let mut s = format!(
            "// Generated by `nav440 tune` ({what}), hold {}. Build the bank with\n\
             // `AdaptiveBank::new(&BankConfig {{ hold, ..BankConfig::NAV440 }}, &schedule, &AdaptiveConfig::DEFAULT)`,\n\
             // `schedule` being `GainSchedule::new(&SCHEDULE)?` with `.with_sample_period(p)?` when\n\
             // `SCHEDULE_PERIOD_S` is `Some(p)`.\n\
             use estimators::{{AveConfig, {deltahat}BankGains, DeltaMode, EdConfig, IloConfig, KalmanNoise{switch}, ScheduleLevel}};\n\n\
             /// The nominal sample period the levels were tuned at, s.\n\
             pub const SCHEDULE_PERIOD_S: Option<f32> = {period};\n\n\
             pub const SCHEDULE: [ScheduleLevel; {}] = [\n",
            self.hold,
            self.level.len()
        );
        for l in &self.level {
            let deltahat = match l.ave_deltahat {
                Some(d) => format!(
                    "Some(AveDeltahat {{ velocity: {:?}, acceleration: [{:?}, {:?}] }})",
                    d.velocity, d.acceleration[0], d.acceleration[1]
                ),
                None => "None".to_string(),
            };
            let switch = match l.switch_up {
                Some(w) => format!(
                    "Some(ObserverSwitch {{ ave: {:?}, ilo: [{:?}, {:?}, {:?}], ed: {:?} }})",
                    w.ave, w.ilo1, w.ilo2, w.ilo3, w.ed
                ),
                None => "None".to_string(),
            };
            s.push_str(&format!(
                "    ScheduleLevel {{\n        noise_var: {:?},\n        velocity: {},\n        acceleration: {},\n        ave_deltahat: {deltahat},\n        switch_up: {switch},\n    }},\n",
                l.noise_var as f32,
                l.velocity.rust(&base.velocity, "        "),
                l.acceleration.rust(&base.acceleration, "        ")
            ));
        }
        s.push_str("];\n");
        s
    }
}

/// Reads a gains file or a schedule file (told apart by its `[[level]]` tables).
pub fn load_any(path: &Path) -> Result<Loaded> {
    let text = read_text(path)?;
    let is_schedule = toml::from_str::<toml::Table>(&text)
        .map(|t| t.contains_key("level"))
        .unwrap_or(false);
    if is_schedule {
        let f: ScheduleFile = toml::from_str(&text).map_err(|e| {
            Error::Usage(format!(
                "{}: bad schedule file: {}",
                path.display(),
                one_line(&e.to_string())
            ))
        })?;
        f.hold()?;
        f.schedule(&BankConfig::NAV440)
            .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
        return Ok(Loaded::Schedule(f));
    }
    GainsFile::from_toml(&text)
        .map(Loaded::Fixed)
        .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))
}

fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::Input(format!("cannot read gains file {}: {e}", path.display())))?;
    // A file that is not text is a bad gains file (usage error, exit 2), like bad TOML.
    String::from_utf8(bytes).map_err(|e| {
        Error::Usage(format!(
            "{}: bad gains file: not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

/// Reads a gains file and applies it over the paper presets.
pub fn load(path: &Path) -> Result<estimators::BankConfig> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::Input(format!("cannot read gains file {}: {e}", path.display())))?;
    // A file that is not text is a bad gains file (usage error, exit 2), like bad TOML.
    let text = String::from_utf8(bytes).map_err(|e| {
        Error::Usage(format!(
            "{}: bad gains file: not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })?;
    let g = GainsFile::from_toml(&text)
        .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
    Ok(g.apply(BankConfig::default()))
}

impl FamilyGains {
    /// The gains of one bank half, all present.
    pub fn from_bank(g: &BankGains) -> Self {
        let [ilo1, ilo2, ilo3] = g.ilo.map(Some);
        FamilyGains {
            ave: Some(g.ave),
            ilo1,
            ilo2,
            ilo3,
            ad: Some(AdConfig { t: g.ad_t }),
            ed: Some(g.ed),
            kf: Some(g.kf),
            ave_delta_from_base: false,
        }
    }

    /// These gains with only the columns `keep(i)` is true for (bank column order: AVE,
    /// ILO1, ILO2, ILO3, AD, ED, KF); the others `None`.
    pub fn only(&self, keep: impl Fn(usize) -> bool) -> Self {
        let mut out = *self;
        for i in 0..7 {
            if !keep(i) {
                out.clear_column(i);
            }
        }
        out
    }

    /// Sets column `i` (bank column order) to `src`'s.
    pub fn set_column(&mut self, i: usize, src: &Self) {
        match i {
            0 => self.ave = src.ave,
            1 => self.ilo1 = src.ilo1,
            2 => self.ilo2 = src.ilo2,
            3 => self.ilo3 = src.ilo3,
            4 => self.ad = src.ad,
            5 => self.ed = src.ed,
            _ => self.kf = src.kf,
        }
    }

    fn clear_column(&mut self, i: usize) {
        self.set_column(i, &Self::default());
    }

    /// `base` with every gain present here replaced.
    pub fn apply(&self, mut base: BankGains) -> BankGains {
        if let Some(a) = self.ave {
            let delta = base.ave.delta;
            base.ave = a;
            if self.ave_delta_from_base {
                base.ave.delta = delta;
            }
        }
        for (slot, g) in base.ilo.iter_mut().zip([self.ilo1, self.ilo2, self.ilo3]) {
            if let Some(g) = g {
                *slot = g;
            }
        }
        if let Some(a) = self.ad {
            base.ad_t = a.t;
        }
        if let Some(e) = self.ed {
            base.ed = e;
        }
        if let Some(k) = self.kf {
            base.kf = k;
        }
        base
    }

    pub(crate) fn rust(&self, base: &BankGains, indent: &str) -> String {
        bank_gains_literal(&self.apply(*base), indent)
    }
}

/// A Rust expression `BankGains { .. }` that builds `g` (every field spelled out; gains printed
/// with `{:?}`, which round-trips f32 exactly), each line after the first indented by `indent`.
/// Used by `nav440 tune --rust` and by the test that prints `BankGains::NAV440_*`
/// (host-tests/tests/preset.rs).
pub fn bank_gains_literal(g: &BankGains, indent: &str) -> String {
    let ilo = |c: &IloConfig| {
        format!(
            "IloConfig {{ k1: {:?}, l: {:?}, k2: {:?} }}",
            c.k1, c.l, c.k2
        )
    };
    format!(
        "BankGains {{\n{i}    ave: AveConfig {{ k: {:?}, gamma1: {:?}, delta: DeltaMode::{:?} }},\n{i}    ilo: [\n{i}        {},\n{i}        {},\n{i}        {},\n{i}    ],\n{i}    ad_t: {:?},\n{i}    ed: EdConfig {{ lambda: {:?}, alpha: {:?} }},\n{i}    kf: KalmanNoise {{ q: {:?}, r: {:?} }},\n{i}}}",
        g.ave.k,
        g.ave.gamma1,
        g.ave.delta,
        ilo(&g.ilo[0]),
        ilo(&g.ilo[1]),
        ilo(&g.ilo[2]),
        g.ad_t,
        g.ed.lambda,
        g.ed.alpha,
        g.kf.q,
        g.kf.r,
        i = indent
    )
}

impl GainsFile {
    /// The gains of a bank configuration.
    pub fn from_bank(cfg: &BankConfig) -> Self {
        GainsFile {
            velocity: FamilyGains::from_bank(&cfg.velocity),
            acceleration: FamilyGains::from_bank(&cfg.acceleration),
        }
    }

    /// `base` with every gain present here replaced (step, hold, gap and period untouched).
    pub fn apply(&self, mut base: BankConfig) -> BankConfig {
        base.velocity = self.velocity.apply(base.velocity);
        base.acceleration = self.acceleration.apply(base.acceleration);
        base
    }

    /// A Rust snippet that builds the same configuration (for the firmware's `BankConfig`).
    pub fn to_rust(&self, what: &str) -> String {
        let base = BankConfig::PAPER;
        format!(
            "// Generated by `nav440 tune` ({what}). Paste into the firmware and pass to `YawBank::new`.\n\
             use estimators::{{AveConfig, BankConfig, BankGains, DeltaMode, EdConfig, IloConfig, KalmanNoise}};\n\n\
             pub const TUNED: BankConfig = BankConfig {{\n    velocity: {},\n    acceleration: {},\n    ..BankConfig::PAPER\n}};\n",
            self.velocity.rust(&base.velocity, "    "),
            self.acceleration.rust(&base.acceleration, "    ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimators::DeltaMode;

    #[test]
    fn paper_gains_round_trip_through_toml() {
        let paper = GainsFile::from_bank(&BankConfig::PAPER);
        let back = GainsFile::from_toml(&paper.to_toml()).unwrap();
        assert_eq!(back, paper);
        assert_eq!(back.apply(BankConfig::PAPER), BankConfig::PAPER);
        // Table 2, ILO3 and Table 4, ILO2 as the paper gives them.
        assert_eq!(
            paper.velocity.ilo3,
            Some(IloConfig {
                k1: 0.7,
                l: 1.0,
                k2: 20.0
            })
        );
        assert_eq!(
            paper.acceleration.ilo2,
            Some(IloConfig {
                k1: 0.9,
                l: 3.0,
                k2: 3.333
            })
        );
    }

    /// `[*.ave]` without `delta` (every gains file written before the key existed) keeps the
    /// base configuration's law; with `delta` the file's law is used.
    #[test]
    fn ave_delta_is_optional() {
        let old = GainsFile::from_toml("[velocity.ave]\nk = 300.0\ngamma1 = 9000.0\n").unwrap();
        let cfg = old.apply(BankConfig::DEFAULT);
        assert_eq!(cfg.velocity.ave.k, 300.0);
        assert_eq!(cfg.velocity.ave.delta, DeltaMode::Leaky { sigma: 0.1 });
        assert_eq!(
            old.apply(BankConfig::PAPER).velocity.ave.delta,
            DeltaMode::Paper
        );
        let new = GainsFile::from_toml(
            "[acceleration.ave]\nk = 300.0\ngamma1 = 9000.0\ndelta = { bounded = { max = 50.0 } }\n",
        )
        .unwrap();
        let cfg = new.apply(BankConfig::DEFAULT);
        assert_eq!(cfg.acceleration.ave.delta, DeltaMode::Bounded { max: 50.0 });
        assert_eq!(cfg.velocity, BankConfig::DEFAULT.velocity);
        assert!(
            GainsFile::from_toml("[velocity.ave]\nk = 1.0\ngamma1 = 2.0\ndelta = \"huge\"\n")
                .is_err()
        );
        // What `tune` writes now names the law and reads back to the same configuration.
        let g = GainsFile::from_bank(&BankConfig::DEFAULT);
        let text = g.to_toml();
        assert!(
            text.contains("[velocity.ave]") && text.contains("leaky"),
            "{text}"
        );
        assert_eq!(
            GainsFile::from_toml(&text)
                .unwrap()
                .apply(BankConfig::PAPER),
            BankConfig {
                ..BankConfig::DEFAULT
            }
        );
    }

    #[test]
    fn partial_files_override_only_what_they_name() {
        let g = GainsFile::from_toml("[acceleration.ad]\nt = 0.05\n").unwrap();
        let cfg = g.apply(BankConfig::PAPER);
        assert_eq!(cfg.acceleration.ad_t, 0.05);
        assert_eq!(cfg.velocity, BankConfig::PAPER.velocity);
        assert!(
            GainsFile::from_toml("[velocity.ave]\nk = 1.0\n").is_err(),
            "gamma1 missing"
        );
        assert!(
            GainsFile::from_toml("[velocity.avx]\nk = 1.0\n").is_err(),
            "unknown table"
        );
    }
}
