//! Shared by the integration tests that check the ILOs on a constant rate.

use estimators::IloConfig;

/// Steady-state gain of an ILO velocity estimator on a constant rate (dimensionless): with
/// `v = K1 v + K2 e` per step and `L e + v = rate`, `v = rate * c / (L + c)`,
/// `c = K2 / (1 - K1)`; 1 for `K1 = 1` (the paper's ILO2: c = 100, L = 5, 0.952; ILO3:
/// c = 66.7, L = 1, 0.985).
pub fn ilo_dc_gain(ilo: &IloConfig) -> f64 {
    let (k1, l, k2) = (f64::from(ilo.k1), f64::from(ilo.l), f64::from(ilo.k2));
    if k1 >= 1.0 {
        1.0
    } else {
        let c = k2 / (1.0 - k1);
        c / (l + c)
    }
}
