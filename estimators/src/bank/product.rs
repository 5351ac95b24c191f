//! [`ProductBank`]: one velocity and one acceleration estimator.

use super::paper::{IloV, KfA};
use super::rows::{Bank, BankOutput, Rows};

/// The product bank's rows: ILO1 velocity and the Kalman tracker's acceleration.
pub type ProductRows = (IloV<0>, KfA);

/// The product preset: one velocity and one acceleration estimator per axis, the two cheapest
/// good ones of the paper bank: ILO1 (Table 2 gains of `cfg.velocity.ilo[0]`, through its exact
/// closed-form map; the best ILO without noise) for velocity and the Kalman tracker
/// (`cfg.acceleration.kf`) for acceleration, each a few dozen operations per sample. Same input
/// stage, API and output conventions as [`PaperBank`](crate::PaperBank); a firmware that wants
/// other estimators names its own tuple of rows ([`crate::Row`]).
pub type ProductBank<T, S = crate::NativeSqrt> = Bank<ProductRows, { ProductChannel::COUNT }, T, S>;
/// The output of [`ProductBank`], indexed by [`ProductChannel`].
pub type ProductOutput<T = f32> = BankOutput<ProductRows, { ProductChannel::COUNT }, T>;

/// The parameters of both rows of [`ProductBank`].
pub type ProductParams<T, S = crate::NativeSqrt> = <ProductRows as Rows<T, S>>::Params;
/// The state of both rows of [`ProductBank`].
pub type ProductState<T, S = crate::NativeSqrt> = <ProductRows as Rows<T, S>>::State;

/// The channels of [`ProductBank`], in CSV order: `out[channel]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProductChannel {
    /// ILO1 velocity, deg/s.
    Ilo1V,
    /// Kalman tracker acceleration, deg/s^2.
    KfA,
}

impl ProductChannel {
    /// Every channel, in order.
    pub const ALL: &'static [ProductChannel] = &[ProductChannel::Ilo1V, ProductChannel::KfA];
    /// The number of channels.
    pub const COUNT: usize = Self::ALL.len();

    /// The channel's CSV column name.
    pub const fn name(self) -> &'static str {
        <ProductOutput>::NAMES[self as usize]
    }
}

/// The channel's value as the output holds it (`f32` for the float types, the raw number for
/// [`Fx`](crate::Fx); [`EstimatorOutput::value`](crate::EstimatorOutput::value) reads it as `f32`).
impl<T: crate::Real> core::ops::Index<ProductChannel> for ProductOutput<T> {
    type Output = T::OutputValue;
    fn index(&self, c: ProductChannel) -> &T::OutputValue {
        &self.values[c as usize]
    }
}

impl<T: crate::Real> ProductOutput<T> {
    /// The value of channel `c` as `f32` (deg/s or deg/s^2).
    pub fn channel(&self, c: ProductChannel) -> f32 {
        T::output_value_f32(self[c])
    }
}
