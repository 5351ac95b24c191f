//! The shipped preset's packet-rate table: [`BankConfig::NAV440`]'s gains for each NAV440
//! output rate ([`BankConfig::with_nav440_gains`]).
//!
//! Gains tuned at some packet rates do not travel to others: [`BankConfig::NAV440`]'s own
//! gains, tuned on 100, 50, 25 and 20 Hz captures, are worse than the paper's at 10 Hz and
//! below (docs/PRESETS.md, "Below 20 Hz", printed by
//! `cargo test --release -p host-tests --test preset_rates -- --nocapture`). The NAV440 sends at 100, 50, 25, 20, 10, 5, 4 or 2 Hz (packet rate divider 1,
//! 2, 4, 5, 10, 20, 25 or 50), so the preset is a table of [`RateGains`], one band of sample
//! periods each: 100-20 Hz run [`BankConfig::NAV440`]'s gains, 10 Hz, 5 Hz (and 4 Hz) and
//! 2 Hz each run gains tuned on synthetic motions and noise levels at that rate (not the
//! bundled test captures), the paper's where tuning did not beat them by 1 %.

use crate::bank::{BankConfig, BankGains};
use crate::{AveConfig, DeltaMode, EdConfig, IloConfig, KalmanNoise};

/// One band of the shipped preset's rate table ([`BankConfig::NAV440_RATES`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RateGains {
    /// The shortest and longest nominal sample periods of the captures the gains were tuned
    /// on, s.
    pub tuned_period_s: [f32; 2],
    /// The band: these gains serve nominal sample periods below this bound, s (the last
    /// entry: every longer period).
    pub below_period_s: f32,
    /// Velocity estimators' gains.
    pub velocity: BankGains,
    /// Acceleration series' gains.
    pub acceleration: BankGains,
}

impl BankConfig {
    /// The shipped preset's gains per NAV440 packet rate, by increasing sample period; see
    /// [`BankConfig::with_nav440_gains`]. The first entry is [`BankConfig::NAV440`]'s gains;
    /// the others were printed by
    /// `cargo test --release -p host-tests --test preset_rates -- --ignored --nocapture`
    /// (docs/PRESETS.md, "Below 20 Hz").
    pub const NAV440_RATES: [RateGains; 4] = [
        RateGains {
            tuned_period_s: [0.01, 0.05],
            below_period_s: 0.075,
            velocity: BankGains::NAV440_VELOCITY,
            acceleration: BankGains::NAV440_ACCELERATION,
        },
        RateGains {
            tuned_period_s: [0.1, 0.1],
            below_period_s: 0.15,
            velocity: VELOCITY_10HZ,
            acceleration: ACCELERATION_10HZ,
        },
        RateGains {
            tuned_period_s: [0.2, 0.2],
            below_period_s: 0.35,
            velocity: VELOCITY_5HZ,
            acceleration: ACCELERATION_5HZ,
        },
        RateGains {
            tuned_period_s: [0.5, 0.5],
            below_period_s: f32::INFINITY,
            velocity: VELOCITY_2HZ,
            acceleration: ACCELERATION_2HZ,
        },
    ];

    /// The entry of [`BankConfig::NAV440_RATES`] whose band holds `sample_period_s` (s): the
    /// first whose `below_period_s` exceeds it; the last for a longer (or non-finite) period.
    pub fn nav440_rate_gains(sample_period_s: f32) -> &'static RateGains {
        let table = &Self::NAV440_RATES;
        table
            .iter()
            .find(|r| sample_period_s < r.below_period_s)
            .unwrap_or(&table[table.len() - 1])
    }

    /// `self` with the shipped preset's gains for its nominal sample period
    /// ([`BankConfig::sample_period_s`], s; [`BankConfig::nav440_rate_gains`]): what
    /// `nav440 estimate` and the firmware run once the warm-up has measured the unit's
    /// packet period. Step, hold, gap rule and laws are kept.
    ///
    /// ```
    /// use estimators::{BankConfig, BankGains};
    /// let at_100_hz = BankConfig { sample_period_s: 0.01, ..BankConfig::NAV440 };
    /// assert_eq!(at_100_hz.with_nav440_gains(), at_100_hz);
    /// let at_10_hz = BankConfig { sample_period_s: 0.1, ..BankConfig::NAV440 }; // s
    /// let cfg = at_10_hz.with_nav440_gains();
    /// assert_eq!(cfg.velocity, BankConfig::NAV440_RATES[1].velocity);
    /// assert_eq!(BankConfig::NAV440_RATES[1].tuned_period_s, [0.1, 0.1]);
    /// assert_eq!((cfg.sample_period_s, cfg.h), (0.1, at_10_hz.h));
    /// ```
    pub fn with_nav440_gains(self) -> Self {
        let r = Self::nav440_rate_gains(self.sample_period_s);
        Self {
            velocity: r.velocity,
            acceleration: r.acceleration,
            ..self
        }
    }
}

/// Velocity gains at 10 Hz.
const VELOCITY_10HZ: BankGains = BankGains {
    ave: AveConfig {
        k: 15.901477,
        gamma1: 2527.9377,
        delta: DeltaMode::Leaky { sigma: 0.1 },
    },
    ilo: [
        IloConfig {
            k1: 0.99963784,
            l: 3.3495007,
            k2: 0.18083054,
        },
        IloConfig {
            k1: 0.99874496,
            l: 0.9821319,
            k2: 0.2513233,
        },
        IloConfig {
            k1: 0.9984375,
            l: 0.51490784,
            k2: 0.24682654,
        },
    ],
    ad_t: 0.01,
    ed: EdConfig {
        lambda: 41.933903,
        alpha: 792.0185,
    },
    kf: KalmanNoise {
        q: 865964.3,
        r: 0.01,
    },
};

/// Acceleration gains at 10 Hz.
const ACCELERATION_10HZ: BankGains = BankGains {
    ave: AveConfig {
        k: 3907.8513,
        gamma1: 41282.277,
        delta: DeltaMode::Leaky { sigma: 0.1 },
    },
    ilo: [
        IloConfig {
            k1: 0.99986583,
            l: 20.535536,
            k2: 0.03770592,
        },
        IloConfig {
            k1: 0.9964557,
            l: 2.7176259,
            k2: 0.03758118,
        },
        IloConfig {
            k1: 0.9964763,
            l: 2.7924683,
            k2: 0.04329888,
        },
    ],
    ad_t: 0.1,
    ed: EdConfig {
        lambda: 64.92697,
        alpha: 1898.2759,
    },
    kf: KalmanNoise {
        q: 562341.3,
        r: 0.01,
    },
};

/// Velocity gains at 5 Hz (and 4 Hz).
const VELOCITY_5HZ: BankGains = BankGains {
    ave: AveConfig {
        k: 8.100932,
        gamma1: 492.2327,
        delta: DeltaMode::Leaky { sigma: 0.1 },
    },
    ilo: [
        IloConfig {
            k1: 0.9997079,
            l: 0.95763564,
            k2: 0.017412001,
        },
        IloConfig {
            k1: 0.9999586,
            l: 7.9813766,
            k2: 0.044160113,
        },
        IloConfig {
            k1: 0.99996984,
            l: 9.791185,
            k2: 0.04394129,
        },
    ],
    ad_t: 0.01,
    ed: EdConfig {
        lambda: 35.588688,
        alpha: 738.0498,
    },
    kf: KalmanNoise {
        q: 1000000.0,
        r: 0.01,
    },
};

/// Acceleration gains at 5 Hz (and 4 Hz).
const ACCELERATION_5HZ: BankGains = BankGains {
    ave: AveConfig {
        k: 976.244,
        gamma1: 12217.426,
        delta: DeltaMode::Leaky { sigma: 0.1 },
    },
    ilo: [
        IloConfig {
            k1: 0.99934953,
            l: 3.0830474,
            k2: 0.013154294,
        },
        IloConfig {
            k1: 0.9999984,
            l: 92.38243,
            k2: 0.116386585,
        },
        IloConfig {
            k1: 0.99999833,
            l: 102.395515,
            k2: 0.12551305,
        },
    ],
    ad_t: 0.1,
    ed: EdConfig {
        lambda: 67.739586,
        alpha: 34.97904,
    },
    kf: KalmanNoise {
        q: 1000000.0,
        r: 0.01,
    },
};

/// Velocity gains at 2 Hz.
const VELOCITY_2HZ: BankGains = BankGains {
    ave: AveConfig {
        k: 5.4977474,
        gamma1: 1101.8396,
        delta: DeltaMode::Leaky { sigma: 0.1 },
    },
    ilo: [
        IloConfig {
            k1: 0.99962264,
            l: 0.28474265,
            k2: 0.3196953,
        },
        IloConfig {
            k1: 0.9,
            l: 5.0,
            k2: 10.0,
        },
        IloConfig {
            k1: 0.7,
            l: 1.0,
            k2: 20.0,
        },
    ],
    ad_t: 0.01,
    ed: EdConfig {
        lambda: 25.610422,
        alpha: 11.747248,
    },
    kf: KalmanNoise {
        q: 1000000.0,
        r: 0.01,
    },
};

/// Acceleration gains at 2 Hz.
const ACCELERATION_2HZ: BankGains = BankGains {
    ave: AveConfig {
        k: 1980.9358,
        gamma1: 13907.01,
        delta: DeltaMode::Leaky { sigma: 0.1 },
    },
    ilo: [
        IloConfig {
            k1: 0.99998593,
            l: 14.489442,
            k2: 0.009862104,
        },
        IloConfig {
            k1: 0.9996201,
            l: 3.6620657,
            k2: 0.0036763593,
        },
        IloConfig {
            k1: 0.9996201,
            l: 3.6620657,
            k2: 0.0036763593,
        },
    ],
    ad_t: 0.15399265,
    ed: EdConfig {
        lambda: 23.12775,
        alpha: 18.797533,
    },
    kf: KalmanNoise {
        q: 1000000.0,
        r: 0.01,
    },
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PaperBank;

    /// Every NAV440 packet rate (divider 1, 2, 4, 5, 10, 20, 25, 50: NAV440-PROTOCOL.md) runs
    /// the entry tuned at it or, for 25 and 20 Hz, on it (the first entry's family), and 4 Hz
    /// the 5 Hz entry.
    #[test]
    fn each_nav440_rate_runs_the_entry_of_its_band() {
        let table = &BankConfig::NAV440_RATES;
        for (rate_hz, entry) in [
            (100.0, 0),
            (50.0, 0),
            (25.0, 0),
            (20.0, 0),
            (10.0, 1),
            (5.0, 2),
            (4.0, 2),
            (2.0, 3),
            (1.0, 3),
        ] {
            let period = 1.0 / rate_hz;
            assert_eq!(
                BankConfig::nav440_rate_gains(period),
                &table[entry],
                "{rate_hz} Hz"
            );
        }
        assert_eq!(BankConfig::nav440_rate_gains(f32::NAN), &table[3]);
        // The first entry is BankConfig::NAV440's own gains.
        assert_eq!(table[0].velocity, BankConfig::NAV440.velocity);
        assert_eq!(table[0].acceleration, BankConfig::NAV440.acceleration);
    }

    /// The bands increase, each holds the periods its gains were tuned at, and every entry's
    /// gains build a bank at those periods (valid gains, a whole number of steps).
    #[test]
    fn the_bands_hold_their_tuning_periods_and_their_gains_build() {
        let mut below = 0.0;
        for r in &BankConfig::NAV440_RATES {
            let [lo, hi] = r.tuned_period_s;
            assert!(below <= lo && lo <= hi && hi < r.below_period_s, "{r:?}");
            below = r.below_period_s;
            for p in [lo, hi] {
                let cfg = BankConfig {
                    sample_period_s: p,
                    ..BankConfig::NAV440
                }
                .with_nav440_gains();
                assert_eq!(cfg.velocity, r.velocity);
                assert!(PaperBank::<f32>::new(&cfg).is_ok(), "{p} s");
            }
        }
        assert_eq!(below, f32::INFINITY);
    }
}
