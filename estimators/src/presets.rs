//! Every parameter set of the paper, named after it, in the paper's units (degrees, seconds).

use crate::{AveConfig, DeltaMode, EdConfig, IloConfig};

/// An ILO preset from the paper's `(K1, L, K2)`.
const fn ilo(k1: f32, l: f32, k2: f32) -> IloConfig {
    IloConfig { k1, l, k2 }
}

/// The observers' internal step and the ILO learning delay of the experiment (section 5), s.
pub const H_PAPER: f32 = 1e-4;
/// ILO learning interval `tau` of Tables 2 and 4, s (`D = 1` at `h = 1e-4`).
pub const TAU_PAPER: f32 = 1e-4;

/// AVE of the experiment: `k = 500 1/s`, `gamma1 = 20000 1/s^2`, paper `deltahat` law.
pub const AVE_PAPER: AveConfig = AveConfig {
    k: 500.0,
    gamma1: 20000.0,
    delta: DeltaMode::Paper,
};

/// The product's AVE (default of [`crate::BankConfig`]): the paper's gains with a leaky
/// `deltahat` law, `d deltahat/dt = |e| - 0.1 deltahat` (time constant 10 s: as the paper's law
/// over a few seconds, bounded over hours). The paper's law (deltahat only grows) degrades a
/// long run (measured in `estimators/tests/long_run.rs`, see docs/RELIABILITY.md).
pub const AVE_DEFAULT: AveConfig = AveConfig {
    k: 500.0,
    gamma1: 20000.0,
    delta: DeltaMode::Leaky { sigma: 0.1 },
};

/// Table 2, ILO1 (velocity): `K1 = 1, L = 4, K2 = 0.2` (Q = 16).
pub const ILO1_TABLE2: IloConfig = ilo(1.0, 4.0, 0.2);
/// Table 2, ILO2 (velocity): `K1 = 0.9, L = 5, K2 = 10` (Q = 7).
pub const ILO2_TABLE2: IloConfig = ilo(0.9, 5.0, 10.0);
/// Table 2, ILO3 (velocity): `K1 = 0.7, L = 1, K2 = 20` (Q = 4).
pub const ILO3_TABLE2: IloConfig = ilo(0.7, 1.0, 20.0);
/// Table 2's `Q` column (not operative: the paper's `K2` does not always equal `Q / (2L)`).
pub const Q_TABLE2: [f32; 3] = [16.0, 7.0, 4.0];

/// Table 4, ILO1 (both stages of the acceleration series): `K1 = 1, L = 5, K2 = 0.01` (Q = 0.1).
pub const ILO1_TABLE4: IloConfig = ilo(1.0, 5.0, 0.01);
/// Table 4, ILO2: `K1 = 0.9, L = 3, K2 = 3.333` (Q = 20).
pub const ILO2_TABLE4: IloConfig = ilo(0.9, 3.0, 3.333);
/// Table 4, ILO3: `K1 = 0.7, L = 1, K2 = 8.333` (Q = 5).
pub const ILO3_TABLE4: IloConfig = ilo(0.7, 1.0, 8.333);
/// Table 4's `Q` column (not operative).
pub const Q_TABLE4: [f32; 3] = [0.1, 20.0, 5.0];

/// AD for velocity: `s / (0.01 s + 1)`, `T` in s.
pub const AD_VELOCITY_T: f32 = 0.01;
/// AD for acceleration: a series of two `s / (0.1 s + 1)`, `T` in s.
pub const AD_ACCELERATION_T: f32 = 0.1;

/// Levant's ED of the experiment: `lambda = 700 deg^(1/2)/s`, `alpha = 770 deg/s^2`.
pub const ED_PAPER: EdConfig = EdConfig {
    lambda: 700.0,
    alpha: 770.0,
};

/// Section 3.2.1 simulation: `L = 1, K1 = 1, K2 = 5` (`Q = 1`), `tau = 0.01 s`, on
/// `x = (1 - cos 5t) / 5`.
pub const ILO_SIM_3_2_1: IloConfig = ilo(1.0, 1.0, 5.0);
/// Section 3.2.1 learning interval `tau`, s.
pub const TAU_SIM_3_2_1: f32 = 0.01;
/// Section 3.2.2 simulation (series, both stages), `K1 = 1`: diverges (paper Fig. 3).
pub const ILO_SIM_3_2_2_K1_1: IloConfig = ilo(1.0, 0.2, 12.5);
/// Section 3.2.2 simulation (series, both stages), `K1 = 0.8`: small error (paper Fig. 4).
pub const ILO_SIM_3_2_2_K1_08: IloConfig = ilo(0.8, 0.2, 12.5);
/// Section 3.2.2 learning interval `tau`, s.
pub const TAU_SIM_3_2_2: f32 = 0.001;
