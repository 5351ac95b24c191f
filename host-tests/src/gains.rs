//! Gains file (TOML): what `nav440 tune` writes and `--gains FILE` reads.
//!
//! ```toml
//! [velocity.ave]            # AveConfig { k, gamma1 }
//! k = 500.0
//! gamma1 = 20000.0
//! [velocity.ilo1]           # IloConfig { k1, l, k2 } (tau = h)
//! k1 = 1.0
//! l = 4.0
//! k2 = 0.2
//! # ... ilo2, ilo3
//! [velocity.ad]             # s / (T s + 1)
//! t = 0.01
//! [velocity.ed]             # EdConfig { lambda, alpha }
//! lambda = 700.0
//! alpha = 770.0
//! [velocity.kf]             # KalmanConfig { q, r } (dt = nominal sample period)
//! q = 1e6
//! r = 0.01
//! [acceleration.ave]        # the same tables for the series (acceleration) estimators
//! ...
//! ```
//! Every table and key is optional: what is left out keeps the paper preset.

use crate::error::{Error, Result};
use estimators::{BankConfig, BankGains};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// AVE gains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AveGains {
    /// `k`, 1/s.
    pub k: f32,
    /// `gamma1`, 1/s^2.
    pub gamma1: f32,
}

/// ILO gains (`tau = h`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IloGains {
    /// `K1`, in (0, 1].
    pub k1: f32,
    /// `L`, 1/s.
    pub l: f32,
    /// `K2`.
    pub k2: f32,
}

/// Approximate differentiator time constant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdGains {
    /// `T`, s.
    pub t: f32,
}

/// Levant differentiator gains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdGains {
    /// `lambda`, deg^(1/2)/s.
    pub lambda: f32,
    /// `alpha`, deg/s^2.
    pub alpha: f32,
}

/// Kalman tracker noise parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KfGains {
    /// Jerk PSD `q`, deg^2/s^5.
    pub q: f32,
    /// Measurement variance `r`, deg^2.
    pub r: f32,
}

/// Gains of one bank half (velocity estimators or acceleration series).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FamilyGains {
    /// AVE (series: both stages).
    pub ave: Option<AveGains>,
    /// ILO preset 1.
    pub ilo1: Option<IloGains>,
    /// ILO preset 2.
    pub ilo2: Option<IloGains>,
    /// ILO preset 3.
    pub ilo3: Option<IloGains>,
    /// AD.
    pub ad: Option<AdGains>,
    /// ED.
    pub ed: Option<EdGains>,
    /// Kalman tracker.
    pub kf: Option<KfGains>,
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
        toml::from_str(text)
            .map_err(|e| Error::Usage(format!("bad gains file: {}", one_line(&e.to_string()))))
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
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
        let ilo = |c: &estimators::IloConfig| {
            Some(IloGains {
                k1: c.k1,
                l: c.l,
                k2: c.k2,
            })
        };
        FamilyGains {
            ave: Some(AveGains {
                k: g.ave.k,
                gamma1: g.ave.gamma1,
            }),
            ilo1: ilo(&g.ilo[0]),
            ilo2: ilo(&g.ilo[1]),
            ilo3: ilo(&g.ilo[2]),
            ad: Some(AdGains { t: g.ad_t }),
            ed: Some(EdGains {
                lambda: g.ed.lambda,
                alpha: g.ed.alpha,
            }),
            kf: Some(KfGains {
                q: g.kf.q,
                r: g.kf.r,
            }),
        }
    }

    /// `base` with every gain present here replaced.
    pub fn apply(&self, mut base: BankGains) -> BankGains {
        if let Some(a) = self.ave {
            base.ave.k = a.k;
            base.ave.gamma1 = a.gamma1;
        }
        for (slot, g) in base.ilo.iter_mut().zip([self.ilo1, self.ilo2, self.ilo3]) {
            if let Some(g) = g {
                *slot = estimators::IloConfig {
                    k1: g.k1,
                    l: g.l,
                    k2: g.k2,
                };
            }
        }
        if let Some(a) = self.ad {
            base.ad_t = a.t;
        }
        if let Some(e) = self.ed {
            base.ed = estimators::EdConfig {
                lambda: e.lambda,
                alpha: e.alpha,
            };
        }
        if let Some(k) = self.kf {
            base.kf = estimators::KalmanNoise { q: k.q, r: k.r };
        }
        base
    }

    fn rust(&self, base: &BankGains, indent: &str) -> String {
        let g = self.apply(*base);
        let ilo = |c: &estimators::IloConfig| {
            format!(
                "IloConfig {{ k1: {:?}, l: {:?}, k2: {:?} }}",
                c.k1, c.l, c.k2
            )
        };
        format!(
            "BankGains {{\n{i}    ave: AveConfig {{ k: {:?}, gamma1: {:?}, delta: DeltaMode::Paper }},\n{i}    ilo: [\n{i}        {},\n{i}        {},\n{i}        {},\n{i}    ],\n{i}    ad_t: {:?},\n{i}    ed: EdConfig {{ lambda: {:?}, alpha: {:?} }},\n{i}    kf: KalmanNoise {{ q: {:?}, r: {:?} }},\n{i}}}",
            g.ave.k,
            g.ave.gamma1,
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

    #[test]
    fn paper_gains_round_trip_through_toml() {
        let paper = GainsFile::from_bank(&BankConfig::PAPER);
        let back = GainsFile::from_toml(&paper.to_toml()).unwrap();
        assert_eq!(back, paper);
        assert_eq!(back.apply(BankConfig::PAPER), BankConfig::PAPER);
        // Table 2, ILO3 and Table 4, ILO2 as the paper gives them.
        assert_eq!(
            paper.velocity.ilo3,
            Some(IloGains {
                k1: 0.7,
                l: 1.0,
                k2: 20.0
            })
        );
        assert_eq!(
            paper.acceleration.ilo2,
            Some(IloGains {
                k1: 0.9,
                l: 3.0,
                k2: 3.333
            })
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
