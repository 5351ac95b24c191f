//! [`ProductBank`]: one velocity and one acceleration estimator.

use super::paper::{ilo_v, kalman};
use crate::kalman::{KalmanOutput, KalmanParams};
use crate::{ClosedForm, IloParams};

crate::estimator_bank! {
    /// The product preset: one velocity and one acceleration estimator per axis, the two
    /// cheapest good ones of the paper bank: ILO1 (Table 2 gains of `cfg.velocity.ilo[0]`,
    /// through its exact closed-form map; the best ILO without noise) for velocity and the
    /// Kalman tracker (`cfg.acceleration.kf`) for acceleration, each a few dozen operations per
    /// sample. Same input stage, API and output conventions as [`PaperBank`](crate::PaperBank); a firmware that
    /// wants other estimators writes its own table with [`crate::estimator_bank!`].
    bank ProductBank, params ProductParams, state ProductState, output ProductOutput, channel ProductChannel;
    build(cfg, n0, prev);
    channels {
        /// ILO1 velocity, deg/s.
        Ilo1V = "ilo1_v",
        /// Kalman tracker acceleration, deg/s^2.
        KfA = "kf_a",
    }
    rows {
        /// ILO1, Table 2 gains.
        ilo1_v: ClosedForm<IloParams<T, 1>> = ilo_v(cfg, 0, n0, prev) => [Ilo1V = output]
            warm replay(cfg.velocity.ilo[0]);
        /// Kalman tracker with the acceleration noise.
        kf_a: KalmanParams<T> = kalman(cfg, &cfg.acceleration, KalmanOutput::Acceleration) => [KfA = acceleration]
            warm replay(cfg.acceleration.kf);
    }
}
