//! The shipped preset's packet-rate table: [`BankConfig::NAV440`]'s gains for each NAV440
//! output rate ([`BankConfig::with_nav440_gains`]).
//!
//! Gains tuned at some packet rates do not travel to others: [`BankConfig::NAV440`]'s own
//! gains, tuned on 100, 50, 25 and 20 Hz captures, are worse than the paper's at 10 Hz and
//! below (docs/PRESETS.md, "Below 20 Hz", printed by
//! `cargo test --release -p host-tests --test preset_rates -- --nocapture`). The NAV440 sends
//! at 100, 50, 25, 20, 10, 5, 4 or 2 Hz (packet rate divider 1, 2, 4, 5, 10, 20, 25 or 50), so
//! the preset is a table of [`RateGains`], one band of sample periods each: 100-20 Hz run
//! [`BankConfig::NAV440`]'s gains, 10 Hz, 5 Hz (and 4 Hz) and 2 Hz each run gains tuned on
//! synthetic motions and noise levels at that rate (not the bundled test captures), the
//! paper's where tuning did not beat them by 1 %.
//!
//! The tuned gains are the tables below: one per family (a column of the paper's tables),
//! one row per band, each gain in its shortest form that reads back to the same `f32`. The
//! host tool prints them (`nav440_cli::rust_literal::write_rate_tables`, whose tests check that
//! the tables in this file are its output for [`BankConfig::NAV440_RATES`]). Every band runs the
//! AVE's `deltahat` law of [`AVE_DEFAULT`] and the tracker's `r` of [`KF_DEFAULT`]; a family
//! the tables do not list runs the paper's gains ([`BankGains::PAPER_VELOCITY`],
//! [`BankGains::PAPER_ACCELERATION`]).

use crate::bank::{BankConfig, BankGains, KF_DEFAULT};
use crate::presets::AVE_DEFAULT;
use crate::{AveConfig, EdConfig, IloConfig, KalmanNoise};

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
    pub const NAV440_RATES: [RateGains; BANDS] = [band(0), band(1), band(2), band(3)];

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

/// The number of bands of [`BankConfig::NAV440_RATES`].
const BANDS: usize = 4;

/// Band `i` of [`BankConfig::NAV440_RATES`], from the tables.
const fn band(i: usize) -> RateGains {
    let (tuned_period_s, below_period_s) = PERIODS[i];
    RateGains {
        tuned_period_s,
        below_period_s,
        velocity: band_gains(i, 0),
        acceleration: band_gains(i, 1),
    }
}

/// The gains of half `half` (0: velocity, 1: acceleration) of band `i`, from the tables.
#[allow(
    clippy::needless_update,
    reason = "a family the tables do not list runs the paper's gains"
)]
pub(crate) const fn band_gains(i: usize, half: usize) -> BankGains {
    let (k, gamma1) = AVE[i][half];
    let ilo = [ILO_VELOCITY, ILO_ACCELERATION][half][i];
    let (lambda, alpha) = ED[i][half];
    BankGains {
        ave: AveConfig {
            k,
            gamma1,
            ..AVE_DEFAULT
        },
        ilo: [ilo_config(ilo[0]), ilo_config(ilo[1]), ilo_config(ilo[2])],
        ad_t: AD_T[i][half],
        ed: EdConfig { lambda, alpha },
        kf: KalmanNoise {
            q: KF_Q[i][half],
            ..KF_DEFAULT
        },
        ..[BankGains::PAPER_VELOCITY, BankGains::PAPER_ACCELERATION][half]
    }
}

/// An ILO's gains from a table's `(k1, l, k2)`.
const fn ilo_config((k1, l, k2): (f32, f32, f32)) -> IloConfig {
    IloConfig { k1, l, k2 }
}

/// Each band's `(tuned_period_s, below_period_s)`, s (see [`RateGains`]).
#[rustfmt::skip]
const PERIODS: [([f32; 2], f32); BANDS] = [
    ([0.01, 0.05], 0.075), // 100-20 Hz
    ([0.1, 0.1], 0.15), // 10 Hz
    ([0.2, 0.2], 0.35), // 5 Hz
    ([0.5, 0.5], f32::INFINITY), // 2 Hz
];

/// AVE `(k, gamma1)`, `[velocity, acceleration]`.
#[rustfmt::skip]
const AVE: [[(f32, f32); 2]; BANDS] = [
    [(43.09086, 1860.1345), (452.36716, 14271.597)], // 100-20 Hz
    [(15.901477, 2527.9377), (3907.8513, 41282.277)], // 10 Hz
    [(8.213926, 503.0125), (976.244, 12217.426)], // 5 Hz
    [(5.4977474, 1101.8396), (1980.9358, 13907.01)], // 2 Hz
];

/// ILO1, ILO2, ILO3 `(k1, l, k2)` of the velocity half.
#[rustfmt::skip]
const ILO_VELOCITY: [[(f32, f32, f32); 3]; BANDS] = [
    [(0.9975162, 0.13922282, 45.476727), (0.9988422, 0.81672835, 0.072374955), (0.9975247, 0.29125896, 0.1364848)], // 100-20 Hz
    [(0.99996746, 5.7086577, 0.1857496), (0.9986782, 0.19094329, 0.25213873), (0.9984446, 0.15877794, 0.2467157)], // 10 Hz
    [(1.0, 4.0, 0.2), (0.99919915, 0.23284973, 0.18629724), (0.99919647, 0.23498242, 0.18863817)], // 5 Hz
    [(0.9999516, 3.59186, 0.47710413), (0.9, 5.0, 10.0), (0.7, 1.0, 20.0)], // 2 Hz
];

/// ILO1, ILO2, ILO3 `(k1, l, k2)` of the acceleration half.
#[rustfmt::skip]
const ILO_ACCELERATION: [[(f32, f32, f32); 3]; BANDS] = [
    [(0.9987728, 2.9622777, 0.026748411), (0.8708157, 1.530036, 3.4881077), (0.99987406, 574.7061, 1.5084013)], // 100-20 Hz
    [(0.99986583, 20.535536, 0.03770592), (0.9964557, 2.7176259, 0.03758118), (0.9964763, 2.7924683, 0.04329888)], // 10 Hz
    [(0.99934953, 3.0830474, 0.013154294), (0.9999984, 92.38243, 0.116386585), (0.99999833, 102.395515, 0.12551305)], // 5 Hz
    [(0.99998593, 14.489442, 0.009862104), (0.9996201, 3.6620657, 0.0036763593), (0.9996201, 3.6620657, 0.0036763593)], // 2 Hz
];

/// AD time constant `T`, s, `[velocity, acceleration]`.
#[rustfmt::skip]
const AD_T: [[f32; 2]; BANDS] = [
    [0.011006941, 0.09932768], // 100-20 Hz
    [0.01, 0.1], // 10 Hz
    [0.01, 0.1], // 5 Hz
    [0.01, 0.15399265], // 2 Hz
];

/// ED `(lambda, alpha)`, `[velocity, acceleration]`.
#[rustfmt::skip]
const ED: [[(f32, f32); 2]; BANDS] = [
    [(26.93642, 873.99744), (28.747272, 6858.6904)], // 100-20 Hz
    [(41.933903, 792.0185), (64.92697, 1898.2759)], // 10 Hz
    [(35.588688, 738.0498), (67.739586, 34.97904)], // 5 Hz
    [(25.610422, 11.747248), (23.12775, 18.797533)], // 2 Hz
];

/// Kalman tracker `q`, deg^2/s^5, `[velocity, acceleration]`.
#[rustfmt::skip]
const KF_Q: [[f32; 2]; BANDS] = [
    [421696.5, 316227.78], // 100-20 Hz
    [865964.3, 562341.3], // 10 Hz
    [1000000.0, 1000000.0], // 5 Hz
    [1000000.0, 1000000.0], // 2 Hz
];

#[cfg(test)]
mod tests {
    extern crate std;
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

    /// A leaky ILO reads a sustained rotation low ([`IloConfig::constant_rate_gain`]): every
    /// band's ILO1 (the product's velocity) reads it within 0.1 %, and so does every velocity
    /// ILO tuned at 10, 5 and 2 Hz (searched held to it). The exceptions are gains not tuned
    /// here: the first band's ILO2 and ILO3 (`BankConfig::NAV440`'s, 1.29 % and 0.53 % low)
    /// and the paper's ILO2 and ILO3 (Table 2, 4.76 % and 1.48 % low) that the 2 Hz band keeps.
    #[test]
    fn the_velocity_ilos_read_a_constant_rate_within_a_tenth_of_a_percent() {
        let paper = BankConfig::PAPER.velocity.ilo;
        for (band, r) in BankConfig::NAV440_RATES.iter().enumerate() {
            for (i, ilo) in r.velocity.ilo.iter().enumerate() {
                let g = ilo.constant_rate_gain();
                let not_tuned_here = i > 0 && (band == 0 || *ilo == paper[i]);
                assert_eq!(g < 0.999, not_tuned_here, "band {band} ILO{}: {g}", i + 1);
            }
        }
    }
}
