//! A bank as plain generic code: a [`Row`] is one law (how it is built from the
//! [`BankConfig`], the channels it reports, how it takes a warm gain change); a bank is a tuple
//! of rows ([`Rows`]) behind the shared input stage ([`BankInput`]): [`Bank`].
//!
//! The bank's channels follow from its rows: every row's velocity channels in row order, then
//! every row's acceleration channels in row order ([`Channels`]). Its output is a
//! [`BankOutput`] of `N` values in that order, and its CSV columns are the channels' names
//! ([`Columns`]).
//!
//! ```
//! use estimators::{
//!     AdAdMap, AdParams, Bank, BankConfig, Channels, ClosedForm, ConfigError, Law, Real, Row,
//!     RowValues, Series, SqrtFn, Warm, EstimatorOutput,
//! };
//!
//! /// AD velocity (a row of its own).
//! #[derive(Clone, Copy, Debug, PartialEq, Eq)]
//! struct MyAdV;
//! impl Channels for MyAdV {
//!     const VELOCITY: &'static [&'static str] = &["ad_v"];
//!     const ACCELERATION: &'static [&'static str] = &[];
//! }
//! impl<T: Real, S: SqrtFn<T>> Row<T, S> for MyAdV {
//!     type Law = ClosedForm<AdParams<T>>;
//!     fn build(cfg: &BankConfig, n0: u32, _: Option<&Self::Law>) -> Result<Self::Law, ConfigError> {
//!         Ok(ClosedForm::new(AdParams::new(cfg.velocity.ad_t, cfg.h)?, n0, cfg.hold))
//!     }
//!     fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
//!         out.velocity(law.output(s));
//!     }
//!     fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
//!         Warm::replay_if(old.velocity.ad_t != new.velocity.ad_t)
//!     }
//! }
//!
//! // A bank of one row (a tuple of one), one channel.
//! type AdBank = Bank<(MyAdV,), 1, f32>;
//! let mut bank = AdBank::new(&BankConfig::default()).unwrap();
//! for k in 0..100u64 {
//!     let out = bank.update(k * 10_000, 20.0 * k as f32 * 0.01).unwrap();
//!     if k == 99 {
//!         assert!((out.values[0] - 20.0).abs() < 0.01);
//!     }
//! }
//! assert_eq!(<AdBank as estimators::EstimatorBank>::CSV_COLUMNS, "ad_v");
//! ```

use crate::words::{WordReader, Words};
use core::marker::PhantomData;

use super::{BankConfig, BankInput, Fed, Feed, Wrap};
use crate::{
    ConfigError, EstimatorBank, EstimatorOutput, Hold, Law, NativeSqrt, Real, SampleError, SqrtFn,
};

/// The channels (CSV columns) a row reports. Independent of the number
/// type, so that an output type can name its columns.
pub trait Channels {
    /// The velocity channels' names, deg/s (e.g. `"ilo1_v"`), in the order the row writes them.
    const VELOCITY: &'static [&'static str];
    /// The acceleration channels' names, deg/s^2 (e.g. `"kf_a"`).
    const ACCELERATION: &'static [&'static str];
}

/// The channels of a tuple of rows: each row's [`Channels`], in row order.
pub trait ChannelLists {
    /// Each row's [`Channels::VELOCITY`].
    const VELOCITY: &'static [&'static [&'static str]];
    /// Each row's [`Channels::ACCELERATION`].
    const ACCELERATION: &'static [&'static [&'static str]];
}

/// How a row takes a warm gain change ([`Bank::set_gains_warm_with`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Warm {
    /// Its gains did not change: the row keeps its state exactly.
    Keep,
    /// Rebuilt by replaying the recent samples through the new gains.
    Replay,
    /// Moved bumplessly to the new gains' equilibrium ([`Law::retune_state`]).
    Bumpless,
}

impl Warm {
    /// [`Warm::Replay`] when the row's gains `changed`, [`Warm::Keep`] otherwise.
    pub const fn replay_if(changed: bool) -> Self {
        if changed {
            Self::Replay
        } else {
            Self::Keep
        }
    }

    /// [`Warm::Bumpless`] when the row's gains `changed`, [`Warm::Keep`] otherwise.
    pub const fn bumpless_if(changed: bool) -> Self {
        if changed {
            Self::Bumpless
        } else {
            Self::Keep
        }
    }
}

/// Where a row writes its values ([`Row::values`]): the next velocity and the next
/// acceleration slot of the bank's output, held as the number type holds outputs
/// ([`Real::OutputValue`]: `f32` for the float types, the number itself for [`crate::Fx`]).
#[derive(Debug)]
pub struct RowValues<'a, T: Real> {
    velocity: core::slice::IterMut<'a, T::OutputValue>,
    acceleration: core::slice::IterMut<'a, T::OutputValue>,
}

impl<T: Real> RowValues<'_, T> {
    /// Writes the row's next velocity channel, deg/s.
    #[inline(always)]
    pub fn velocity(&mut self, x: T) {
        if let Some(v) = self.velocity.next() {
            *v = x.output_value();
        }
    }

    /// Writes the row's next acceleration channel, deg/s^2.
    #[inline(always)]
    pub fn acceleration(&mut self, x: T) {
        if let Some(v) = self.acceleration.next() {
            *v = x.output_value();
        }
    }
}

/// One row of a bank: a law, how it is built from the configuration, and its channels.
///
/// Implemented by a marker type (e.g. [`crate::IloV`]); `S` is the ED's square root, unused by
/// the other laws.
pub trait Row<T: Real, S: SqrtFn<T>>: Channels {
    /// The law the row runs.
    type Law: Law<Num = T>;

    /// Builds the law from `cfg` (`n0`: steps per nominal sample period, for the closed-form
    /// maps, 0 for none). `prev`: the row being replaced by a gain change (`None` when the
    /// bank is built), so that the builder can keep what did not change
    /// ([`crate::ClosedForm::new_reusing`]).
    fn build(cfg: &BankConfig, n0: u32, prev: Option<&Self::Law>)
        -> Result<Self::Law, ConfigError>;

    /// Writes the row's channels' values of state `s`: one [`RowValues::velocity`] per name of
    /// [`Channels::VELOCITY`] and one [`RowValues::acceleration`] per name of
    /// [`Channels::ACCELERATION`], in order.
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>);

    /// How the row takes a warm gain change from the gains of `old` to those of `new`. The
    /// default: moved bumplessly, whatever changed.
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        let _ = (old, new);
        Warm::Bumpless
    }
}

/// The rows of a bank: a tuple of [`Row`]s (implemented for tuples of 1 to 16 rows). Each
/// method runs every row in order.
pub trait Rows<T: Real, S: SqrtFn<T>>: ChannelLists {
    /// Every row's law.
    type Params: Copy;
    /// Every row's state.
    type State: Copy;
    /// Writes every row's law, as a tuple's `Debug` does (`core` implements `Debug` only for
    /// tuples of up to 12 elements).
    fn fmt_params(p: &Self::Params, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result;
    /// Writes every row's state, as a tuple's `Debug` does.
    fn fmt_state(s: &Self::State, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result;
    /// Every row's law, printable with `{:?}` ([`Self::fmt_params`]).
    fn params_debug(p: &Self::Params) -> RowsDebug<'_, Self::Params> {
        RowsDebug(p, Self::fmt_params)
    }
    /// Every row's state, printable with `{:?}` ([`Self::fmt_state`]).
    fn state_debug(s: &Self::State) -> RowsDebug<'_, Self::State> {
        RowsDebug(s, Self::fmt_state)
    }

    /// Builds every row ([`Row::build`]; `prev`: the rows being replaced).
    fn build(
        cfg: &BankConfig,
        n0: u32,
        prev: Option<&Self::Params>,
    ) -> Result<Self::Params, ConfigError>;
    /// Every row's state, initialised at `y0`.
    fn init(p: &Self::Params, y0: T) -> Self::State;
    /// Translates every row's state by `d` (deg).
    fn translate(p: &Self::Params, s: &mut Self::State, d: T);
    /// Advances every row over one sample interval.
    fn advance(p: &Self::Params, s: &mut Self::State, y_prev: T, y: T, n: u32, hold: Hold);
    /// Bumpless gain change of every row from the parameters `old` ([`Law::retune_state`]).
    fn retune_state(p: &Self::Params, old: &Self::Params, s: &mut Self::State, y: T);
    /// Writes every row's values.
    fn values(p: &Self::Params, s: &Self::State, out: &mut RowValues<'_, T>);
    /// The warm gain change of every row ([`Row::warm`]): `p` the new parameters, `before`
    /// the old ones, `replayed` the state replayed through `p`, `y` the last input.
    #[allow(clippy::too_many_arguments)]
    fn warm(
        p: &Self::Params,
        before: &Self::Params,
        s: &mut Self::State,
        replayed: &Self::State,
        y: T,
        old: &BankConfig,
        new: &BankConfig,
    );
}

/// Every row's law or state of a bank, printable with `{:?}` (as a tuple is, whatever the number
/// of rows): [`Rows::params_debug`], [`Rows::state_debug`].
pub struct RowsDebug<'a, X>(
    &'a X,
    fn(&X, &mut core::fmt::Formatter<'_>) -> core::fmt::Result,
);

impl<X> core::fmt::Debug for RowsDebug<'_, X> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        (self.1)(self.0, f)
    }
}

/// Implements [`Channels`] and [`Rows`] for a tuple of rows, and [`Words`] for a tuple (a
/// bank's laws: `Rows::Params`).
macro_rules! tuple_rows {
    ($($R:ident $i:tt),+) => {
        /// A tuple's words ([`crate::words`]): its elements' words, in order (a bank's laws).
        impl<$($R: Words),+> Words for ($($R,)+) {
            fn put_words(&self, out: &mut dyn FnMut(i64)) {
                $(self.$i.put_words(out);)+
            }
            fn take_words(r: &mut WordReader<'_>) -> Self {
                ($($R::take_words(r),)+)
            }
        }
        impl<$($R: Channels),+> ChannelLists for ($($R,)+) {
            const VELOCITY: &'static [&'static [&'static str]] = &[$($R::VELOCITY),+];
            const ACCELERATION: &'static [&'static [&'static str]] = &[$($R::ACCELERATION),+];
        }
        impl<T: Real, S: SqrtFn<T>, $($R: Row<T, S>),+> Rows<T, S> for ($($R,)+) {
            type Params = ($($R::Law,)+);
            type State = ($(<$R::Law as Law>::State,)+);
            fn fmt_params(p: &Self::Params, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.debug_tuple("")$(.field(&p.$i))+.finish()
            }
            fn fmt_state(s: &Self::State, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.debug_tuple("")$(.field(&s.$i))+.finish()
            }
            fn build(cfg: &BankConfig, n0: u32, prev: Option<&Self::Params>) -> Result<Self::Params, ConfigError> {
                Ok(($($R::build(cfg, n0, prev.map(|p| &p.$i))?,)+))
            }
            #[inline]
            fn init(p: &Self::Params, y0: T) -> Self::State {
                ($(p.$i.init(y0),)+)
            }
            #[inline]
            fn translate(p: &Self::Params, s: &mut Self::State, d: T) {
                $(p.$i.translate(&mut s.$i, d);)+
            }
            #[inline]
            fn advance(p: &Self::Params, s: &mut Self::State, y_prev: T, y: T, n: u32, hold: Hold) {
                $(p.$i.advance(&mut s.$i, y_prev, y, n, hold);)+
            }
            fn retune_state(p: &Self::Params, old: &Self::Params, s: &mut Self::State, y: T) {
                $(p.$i.retune_state(&old.$i, &mut s.$i, y);)+
            }
            #[inline]
            fn values(p: &Self::Params, s: &Self::State, out: &mut RowValues<'_, T>) {
                $($R::values(&p.$i, &s.$i, out);)+
            }
            fn warm(p: &Self::Params, before: &Self::Params, s: &mut Self::State, replayed: &Self::State, y: T, old: &BankConfig, new: &BankConfig) {
                $(match $R::warm(old, new) {
                    Warm::Keep => {}
                    Warm::Replay => s.$i = replayed.$i,
                    Warm::Bumpless => p.$i.retune_state(&before.$i, &mut s.$i, y),
                })+
            }
        }
    };
}

tuple_rows!(A 0);
tuple_rows!(A 0, B 1);
tuple_rows!(A 0, B 1, C 2);
tuple_rows!(A 0, B 1, C 2, D 3);
tuple_rows!(A 0, B 1, C 2, D 3, E 4);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10, L 11);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10, L 11, M 12);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10, L 11, M 12, N 13);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10, L 11, M 12, N 13, O 14);
tuple_rows!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10, L 11, M 12, N 13, O 14, P 15);

/// The number of names in `lists`.
const fn count(lists: &[&[&str]]) -> usize {
    let (mut n, mut i) = (0, 0);
    while i < lists.len() {
        n += lists[i].len();
        i += 1;
    }
    n
}

/// The names of `velocity`, then those of `acceleration`, in order, in an array of `N`
/// (a compile-time error when they are not `N`).
const fn flatten<const N: usize>(
    velocity: &[&[&'static str]],
    acceleration: &[&[&'static str]],
) -> [&'static str; N] {
    let mut out = [""; N];
    let mut n = 0;
    let mut half = 0;
    while half < 2 {
        let lists = if half == 0 { velocity } else { acceleration };
        let mut i = 0;
        while i < lists.len() {
            let mut j = 0;
            while j < lists[i].len() {
                assert!(
                    n < N,
                    "a bank's channel count N is less than its rows' channels"
                );
                out[n] = lists[i][j];
                n += 1;
                j += 1;
            }
            i += 1;
        }
        half += 1;
    }
    assert!(
        n == N,
        "a bank's channel count N is more than its rows' channels"
    );
    out
}

/// A bank's CSV columns: its channels' names joined with `,` when displayed (and when
/// formatted with defmt), e.g. `ilo1_v,kf_a`. Compares equal to that string.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Columns(pub &'static [&'static str]);

impl core::fmt::Display for Columns {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (i, name) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            f.write_str(name)?;
        }
        Ok(())
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Columns {
    fn format(&self, f: defmt::Formatter<'_>) {
        for (i, name) in self.0.iter().enumerate() {
            if i > 0 {
                defmt::write!(f, ",");
            }
            defmt::write!(f, "{=str}", name);
        }
    }
}

impl PartialEq<str> for Columns {
    fn eq(&self, other: &str) -> bool {
        let mut rest = other.as_bytes();
        for (i, name) in self.0.iter().enumerate() {
            if i > 0 {
                match rest.split_first() {
                    Some((b',', r)) => rest = r,
                    _ => return false,
                }
            }
            match rest.strip_prefix(name.as_bytes()) {
                Some(r) => rest = r,
                None => return false,
            }
        }
        rest.is_empty()
    }
}

impl PartialEq<&str> for Columns {
    fn eq(&self, other: &&str) -> bool {
        *self == **other
    }
}

impl PartialEq<Columns> for &str {
    fn eq(&self, other: &Columns) -> bool {
        *other == **self
    }
}

/// The length in bytes of the names of `lists` joined with `,` (see [`join_columns`]).
pub const fn columns_len(lists: &[&[&str]]) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < lists.len() {
        let mut j = 0;
        while j < lists[i].len() {
            n += lists[i][j].len() + if n > 0 { 1 } else { 0 };
            j += 1;
        }
        i += 1;
    }
    n
}

/// The names of `lists`, in order, joined with `,`, as `L` bytes ([`columns_len`] of them; a
/// compile-time error otherwise): a concrete bank's CSV columns (or a whole header line) as a
/// `const`, for a firmware that sends them as one string without joining them at run time:
///
/// ```
/// use estimators::{columns_len, join_columns, EstimatorOutput, ProductOutput};
///
/// const NAMES: &[&[&str]] = &[&["t", "yaw", "yaw_rate"], <ProductOutput>::CHANNEL_NAMES];
/// const BYTES: [u8; columns_len(NAMES)] = join_columns(NAMES);
/// const HEADER: &str = match core::str::from_utf8(&BYTES) {
///     Ok(s) => s,
///     Err(_) => panic!("channel names are UTF-8"),
/// };
/// assert_eq!(HEADER, "t,yaw,yaw_rate,ilo1_v,kf_a");
/// ```
pub const fn join_columns<const L: usize>(lists: &[&[&str]]) -> [u8; L] {
    let mut out = [0u8; L];
    let mut n = 0;
    let mut i = 0;
    while i < lists.len() {
        let mut j = 0;
        while j < lists[i].len() {
            if n > 0 {
                out[n] = b',';
                n += 1;
            }
            let b = lists[i][j].as_bytes();
            let mut k = 0;
            while k < b.len() {
                out[n] = b[k];
                n += 1;
                k += 1;
            }
            j += 1;
        }
        i += 1;
    }
    assert!(n == L, "L is not the joined names' length");
    out
}

/// One output of a bank of rows `R` with `N` channels, number type `T`: the unwrapped input
/// angle and one value per channel (velocities in deg/s, then accelerations in deg/s^2, see
/// [`Channels`]), held as `T` holds outputs: rounded to `f32` for the float types, raw for
/// [`crate::Fx`] ([`Real::OutputValue`], [`Real::OutputAngle`]). [`EstimatorOutput`] reads
/// both as `f32` (and the angle's `f64` residual) either way, with the same values.
pub struct BankOutput<R, const N: usize, T: Real = f32> {
    /// The unwrapped angle as `T` holds it: `(f32 rounding, f64 residual)` for the float types,
    /// `(turns, wrapped angle)` for [`crate::Fx`]; read it with
    /// [`EstimatorOutput::unwrapped_deg`] and [`EstimatorOutput::residual_deg`].
    pub angle: T::OutputAngle,
    /// The channels' values, in the order of [`EstimatorOutput::CHANNEL_NAMES`], as `T` holds
    /// them (`f32` for the float types; read as `f32` with [`EstimatorOutput::values`]).
    pub values: [T::OutputValue; N],
    rows: PhantomData<fn() -> R>,
}

impl<R, const N: usize, T: Real> Clone for BankOutput<R, N, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<R, const N: usize, T: Real> Copy for BankOutput<R, N, T> {}

impl<R, const N: usize, T: Real> PartialEq for BankOutput<R, N, T> {
    fn eq(&self, other: &Self) -> bool {
        (self.angle, self.values) == (other.angle, other.values)
    }
}

impl<R, const N: usize, T: Real> core::fmt::Debug for BankOutput<R, N, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("BankOutput")
            .field("angle", &self.angle)
            .field("values", &self.values)
            .finish()
    }
}

impl<R, const N: usize, T: Real> Default for BankOutput<R, N, T> {
    fn default() -> Self {
        Self::from_parts(T::OutputAngle::default(), [T::OutputValue::default(); N])
    }
}

impl<R, const N: usize> BankOutput<R, N, f32> {
    /// An output of these values: the unwrapped angle's `f32` rounding and residual (deg) and
    /// the channels' values.
    pub const fn new(unwrapped_deg: f32, residual_deg: f64, values: [f32; N]) -> Self {
        Self::from_parts((unwrapped_deg, residual_deg), values)
    }
}

impl<R, const N: usize, T: Real> BankOutput<R, N, T> {
    /// An output of these parts, as `T` holds them ([`BankOutput::angle`],
    /// [`BankOutput::values`]).
    pub const fn from_parts(angle: T::OutputAngle, values: [T::OutputValue; N]) -> Self {
        Self {
            angle,
            values,
            rows: PhantomData,
        }
    }
}

impl<R: ChannelLists, const N: usize, T: Real> BankOutput<R, N, T> {
    /// The channels' names, velocities then accelerations.
    pub const NAMES: [&'static str; N] = flatten::<N>(R::VELOCITY, R::ACCELERATION);
    /// The CSV columns: [`Self::NAMES`] joined with `,` when displayed.
    pub const CSV_COLUMNS: Columns = Columns(&Self::NAMES);
    /// The number of velocity channels (the first of [`Self::NAMES`]).
    pub const VELOCITIES: usize = count(R::VELOCITY);

    /// `(name, value)` pairs in CSV order, the values as `f32`.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f32)> + '_ {
        Self::NAMES
            .iter()
            .copied()
            .zip(self.values.iter().map(|&v| T::output_value_f32(v)))
    }

    /// The value of the channel named `name` as `f32`, if the bank has it.
    pub fn get(&self, name: &str) -> Option<f32> {
        self.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    /// The same output held as `f32` ([`EstimatorOutput`]'s values): what a host compares or
    /// stores, whatever the number type.
    pub fn to_f32(&self) -> BankOutput<R, N, f32> {
        let (angle, residual) = T::output_angle_f32(self.angle);
        BankOutput::new(angle, residual, self.values.map(|v| T::output_value_f32(v)))
    }
}

impl<R: ChannelLists, const N: usize, T: Real> EstimatorOutput for BankOutput<R, N, T> {
    const CHANNELS: usize = N;
    const CHANNEL_NAMES: &'static [&'static str] = &Self::NAMES;

    #[inline]
    fn unwrapped_deg(&self) -> f32 {
        T::output_angle_f32(self.angle).0
    }

    #[inline]
    fn residual_deg(&self) -> f64 {
        T::output_angle_f32(self.angle).1
    }

    #[inline]
    fn value(&self, channel: usize) -> f32 {
        self.values
            .get(channel)
            .map_or(f32::NAN, |&v| T::output_value_f32(v))
    }
}

/// An estimator bank for one angle: the input stage ([`BankInput`]: input checks, sample
/// clock, unwrapping) and the rows `R` ([`Rows`], a tuple of [`Row`]s), reporting `N`
/// channels (the rows' channels; a different `N` does not compile). `T`: the number type
/// ([`Real`]); `S`: the ED's square root ([`SqrtFn`]).
///
/// No heap: the whole state is inline. [`crate::PaperBank`] and [`crate::ProductBank`] are
/// two of them.
pub struct Bank<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T> = NativeSqrt> {
    input: BankInput<T>,
    params: R::Params,
    state: R::State,
}

impl<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>> Clone for Bank<R, N, T, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>> Copy for Bank<R, N, T, S> {}

impl<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>> core::fmt::Debug for Bank<R, N, T, S> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Bank")
            .field("input", &self.input)
            .field("params", &R::params_debug(&self.params))
            .field("state", &R::state_debug(&self.state))
            .finish()
    }
}

/// A bank's words ([`crate::words`]): its input stage's (step, gap rule, hold, unwrapping),
/// then every row's law's (gains, closed-form maps, the Kalman's gain), not the laws' state.
/// So a bank built on a host ([`Bank::new`], with `f64` and `libm`) can be stored, and read
/// back on a device with integer moves only ([`Bank::from_words`]): the project's firmware
/// holds such a table of banks, one per packet period (docs/FOOTPRINT.md).
impl<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>> Bank<R, N, T, S>
where
    R::Params: Words,
{
    /// Writes the bank's words, in order (see the `impl` block).
    pub fn put_words(&self, out: &mut dyn FnMut(i64)) {
        self.input.put_words(out);
        self.params.put_words(out);
    }

    /// Reads back a bank [`Bank::put_words`] wrote, from the words `next` yields (`None` when
    /// it is exhausted): the bank as [`Bank::new`] built it, before its first sample (a bank
    /// that had run reads back restarted, with no re-initialisation counted). `None` when the
    /// words run out early or some are left over. Read only what `put_words` of the same type
    /// and crate version wrote ([`crate::words`]: the words are not validated again).
    pub fn from_words(next: &mut dyn FnMut() -> Option<i64>) -> Option<Self> {
        let mut r = WordReader::new(next);
        let input = BankInput::take_words(&mut r);
        let params = R::Params::take_words(&mut r);
        if !r.read_exactly() {
            return None;
        }
        Some(Self {
            input,
            state: R::init(&params, T::ZERO),
            params,
        })
    }
}

/// Every row's state after replaying `history` (what the laws were fed, oldest first, see
/// [`Bank::update_fed`]) through the parameters `p`: started at rest at the first entry's
/// input (`init`, then `on_init`), re-initialised where the history was (`Feed::Reset`, then
/// `on_init`), translated where the frame shifted. `None` for an empty history.
pub fn replay<'h, T, S, R, I, F>(p: &R::Params, history: I, mut on_init: F) -> Option<R::State>
where
    T: Real + 'h,
    S: SqrtFn<T>,
    R: Rows<T, S>,
    I: IntoIterator<Item = &'h Fed<T>>,
    F: FnMut(&mut R::State),
{
    let mut state: Option<R::State> = None;
    for fed in history {
        match (fed.feed, state.as_mut()) {
            (Feed::Reset(y), _) => {
                let mut s = R::init(p, y);
                on_init(&mut s);
                state = Some(s);
            }
            (Feed::Advance { y_prev, y, n, hold }, Some(s)) => {
                if let Some(d) = fed.shift {
                    R::translate(p, s, d);
                }
                R::advance(p, s, y_prev, y, n, hold);
            }
            (Feed::Advance { y_prev, y, n, hold }, None) => {
                // `y_prev` is already in this sample's frame.
                let mut s = R::init(p, y_prev);
                on_init(&mut s);
                R::advance(p, &mut s, y_prev, y, n, hold);
                state = Some(s);
            }
        }
    }
    state
}

impl<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>> Bank<R, N, T, S> {
    /// Largest accepted `|angle_deg|`, deg (`BankInput::MAX_ABS_DEG`, 1e6).
    pub const MAX_ABS_DEG: f32 = BankInput::<T>::MAX_ABS_DEG;

    /// Builds the bank (validates every parameter; computes the closed-form maps and the
    /// Kalman gains).
    pub fn new(cfg: &BankConfig) -> Result<Self, ConfigError> {
        const {
            assert!(
                count(R::VELOCITY) + count(R::ACCELERATION) == N,
                "a bank's channel count N differs from its rows' channels"
            )
        };
        let (input, n0) = BankInput::new(cfg)?;
        let params = R::build(cfg, n0, None)?;
        let state = R::init(&params, T::ZERO);
        Ok(Self {
            input,
            params,
            state,
        })
    }

    /// Feeds one sample. `t_us`: sample time in µs (monotonic); `angle_deg`: the angle in deg
    /// (within +-180 when wrapping).
    ///
    /// The first sample, and the first after a gap longer than the gap rule, initialise every
    /// state from it and report 0 velocities and accelerations. Otherwise every law runs
    /// `n = round(dt / h)` steps (see `SampleAdapter`).
    ///
    /// Errors (state unchanged): `SampleError::NotFinite` for NaN/infinite input,
    /// `SampleError::OutOfRange` for `|angle_deg|` above `MAX_ABS_DEG`,
    /// `SampleError::NonIncreasingTime` for `t_us` not later than the previous sample.
    #[inline]
    pub fn update(
        &mut self,
        t_us: u64,
        angle_deg: f32,
    ) -> Result<BankOutput<R, N, T>, SampleError> {
        self.update_fed(t_us, angle_deg).map(|(out, _)| out)
    }

    /// [`Self::update`], also returning what the laws were fed ([`Fed`]): what
    /// [`Self::set_gains_replaying`] replays.
    #[inline(always)]
    pub fn update_fed(
        &mut self,
        t_us: u64,
        angle_deg: f32,
    ) -> Result<(BankOutput<R, N, T>, Fed<T>), SampleError> {
        let a = self.input.accept(t_us, angle_deg)?;
        Ok(self.feed(a))
    }

    /// [`Self::update`] for an angle `angle` already in the number type, deg (what
    /// [`EstimatorBank::update_scaled`] feeds): the same checks, and the same output as
    /// `update` of the `f32` it equals.
    #[inline]
    pub fn update_value(
        &mut self,
        t_us: u64,
        angle: T,
    ) -> Result<BankOutput<R, N, T>, SampleError> {
        let a = self.input.accept_value(t_us, angle)?;
        Ok(self.feed(a).0)
    }

    /// Runs the laws on an accepted sample.
    #[inline(always)]
    fn feed(&mut self, a: super::input::Accepted<T>) -> (BankOutput<R, N, T>, Fed<T>) {
        if let Some(d) = a.shift {
            R::translate(&self.params, &mut self.state, d);
        }
        let mut values = [T::OutputValue::default(); N];
        match a.feed {
            Feed::Reset(y) => self.state = R::init(&self.params, y),
            Feed::Advance { y_prev, y, n, hold } => {
                R::advance(&self.params, &mut self.state, y_prev, y, n, hold);
                let (velocity, acceleration) =
                    values.split_at_mut(BankOutput::<R, N, T>::VELOCITIES.min(N));
                let mut out = RowValues {
                    velocity: velocity.iter_mut(),
                    acceleration: acceleration.iter_mut(),
                };
                R::values(&self.params, &self.state, &mut out);
            }
        }
        let out = BankOutput::from_parts(a.angle, values);
        (
            out,
            Fed {
                shift: a.shift,
                feed: a.feed,
            },
        )
    }

    /// How many times a gap longer than the gap rule re-initialised the bank.
    pub fn reinit_count(&self) -> u32 {
        self.input.reinit_count()
    }

    /// Starts a new epoch (a confirmed time jump): the next sample re-initialises every law
    /// from itself and reports 0, whatever its time; the unwrapper keeps its turn count. Not
    /// counted in [`Self::reinit_count`].
    pub fn new_epoch(&mut self) {
        self.input.new_epoch();
    }

    /// Sets the unwrapper's turn count to `turns`: only the angle column moves by
    /// `360 * delta` deg; the laws run in the local frame and are unaffected.
    pub fn set_turns(&mut self, turns: i64) {
        self.input.set_turns(turns);
    }

    /// Takes over from `old` (the bank this one replaces, built for another nominal period
    /// after a new epoch) its unwrapper and its re-init count; the next sample starts a new
    /// epoch ([`EstimatorBank::take_over`]).
    pub fn take_over(&mut self, old: &Self) {
        self.input.take_over(&old.input);
    }

    /// Forgets everything: the next sample is treated as the first one.
    pub fn restart(&mut self) {
        self.input.restart();
        self.state = R::init(&self.params, T::ZERO);
    }

    /// Unwraps the input per `wrap` from now on ([`BankConfig::wrap`]) and restarts: the bank
    /// is then the one [`Bank::new`] builds from the same configuration with that `wrap` (the
    /// laws do not depend on it). One stored bank thus serves the axes that wrap at +-180 deg
    /// and those that do not (the firmware's table of banks, docs/FOOTPRINT.md).
    pub fn set_wrap(&mut self, wrap: Wrap) {
        self.input.set_wrap(wrap);
        self.state = R::init(&self.params, T::ZERO);
    }

    /// The parameters of `cfg`, each row's builder seeing the row it replaces.
    fn rebuilt(&self, cfg: &BankConfig) -> Result<R::Params, ConfigError> {
        let (_, n0) = BankInput::<T>::new(cfg)?;
        R::build(cfg, n0, Some(&self.params))
    }

    /// Replaces every row's parameters by those of `cfg`; the laws continue from where they
    /// are with the new gains (what a gain schedule does, `AdaptiveBank`), their states moved
    /// so that each output continues without a jump (bumpless transfer, `Law::retune_state`:
    /// the ILO's and AD's steady state depends on their gains). Only the gains of `cfg` are
    /// meant to differ from the configuration the bank was built with: the input stage (step,
    /// hold, nominal period, gap rule, unwrapping) is kept as built. On error nothing changes.
    /// Cost: that of building the parameters (closed-form maps, Kalman gains) of the rows
    /// whose gains changed (the rows' builders reuse the previous row), see `cargo xtask
    /// bench`.
    pub fn set_gains(&mut self, cfg: &BankConfig) -> Result<(), ConfigError> {
        let params = self.rebuilt(cfg)?;
        R::retune_state(&params, &self.params, &mut self.state, self.input.last());
        self.params = params;
        Ok(())
    }

    /// [`Self::set_gains`], with the new laws' states rebuilt by replaying `history` (oldest
    /// first: what the laws were fed for the last samples, from [`Self::update_fed`], ending
    /// with the last sample) through the new parameters ([`replay`]). The laws then continue
    /// as if they had run with the new gains over the history (warm start), not from the old
    /// gains' states. An empty history is [`Self::set_gains`]. On error nothing changes.
    /// Cost: [`Self::set_gains`] plus one advance of every row per history entry.
    pub fn set_gains_replaying<'h, I, F>(
        &mut self,
        cfg: &BankConfig,
        history: I,
        on_init: F,
    ) -> Result<(), ConfigError>
    where
        I: IntoIterator<Item = &'h Fed<T>>,
        F: FnMut(&mut R::State),
        T: 'h,
    {
        self.regain(cfg, history, on_init, |_, _, state, replayed, _| {
            *state = *replayed
        })
    }

    /// The warm gain change (what a gain schedule does on a warm start, `AdaptiveBank`) from
    /// the gains of `old` (the configuration the bank runs now; only its gains are read) to
    /// those of `new`, row by row as each row's [`Row::warm`] says: [`Warm::Replay`], rebuilt
    /// by replaying `history` (see [`Self::set_gains_replaying`]; `on_init` is applied to the
    /// replay's initial states); [`Warm::Bumpless`], moved bumplessly
    /// ([`Law::retune_state`]); [`Warm::Keep`], its state kept exactly.
    ///
    /// An empty history is [`Self::set_gains`] (every row bumpless). On error nothing changes.
    /// Cost: [`Self::set_gains`] plus one advance of every row per history entry.
    pub fn set_gains_warm_with<'h, I, F>(
        &mut self,
        old: &BankConfig,
        new: &BankConfig,
        history: I,
        on_init: F,
    ) -> Result<(), ConfigError>
    where
        I: IntoIterator<Item = &'h Fed<T>>,
        F: FnMut(&mut R::State),
        T: 'h,
    {
        self.regain(
            new,
            history,
            on_init,
            |params, before, state, replayed, y| {
                R::warm(params, before, state, replayed, y, old, new)
            },
        )
    }

    /// The gain change of [`Self::set_gains_replaying`] and [`Self::set_gains_warm_with`]:
    /// the parameters of `cfg`, `history` replayed through them, then `take(new parameters,
    /// old parameters, state, replayed state, last input)`; with nothing replayed (an empty
    /// history), every row bumpless ([`Self::set_gains`]). On error nothing changes.
    fn regain<'h, I, F>(
        &mut self,
        cfg: &BankConfig,
        history: I,
        on_init: F,
        take: impl FnOnce(&R::Params, &R::Params, &mut R::State, &R::State, T),
    ) -> Result<(), ConfigError>
    where
        I: IntoIterator<Item = &'h Fed<T>>,
        F: FnMut(&mut R::State),
        T: 'h,
    {
        let params = self.rebuilt(cfg)?;
        let y = self.input.last();
        match replay::<T, S, R, I, F>(&params, history, on_init) {
            Some(replayed) => take(&params, &self.params, &mut self.state, &replayed, y),
            None => R::retune_state(&params, &self.params, &mut self.state, y),
        }
        self.params = params;
        Ok(())
    }

    /// The rows' validated parameters (a tuple, one per row).
    pub fn params(&self) -> &R::Params {
        &self.params
    }

    /// The rows' state (a tuple, one per row).
    pub fn state(&self) -> &R::State {
        &self.state
    }

    /// The rows' state, to change (e.g. the AVE's switching gains).
    pub(crate) fn state_mut(&mut self) -> &mut R::State {
        &mut self.state
    }
}

impl<R: Rows<T, S>, const N: usize, T: Real, S: SqrtFn<T>> EstimatorBank for Bank<R, N, T, S> {
    type Output = BankOutput<R, N, T>;

    #[inline]
    fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<Self::Output, SampleError> {
        Bank::update(self, t_us, angle_deg)
    }

    /// The angle converted to `T` directly ([`Real::from_scaled`]), not through `f32`.
    #[inline]
    fn update_scaled(
        &mut self,
        t_us: u64,
        raw: i32,
        exp2: i32,
    ) -> Result<Self::Output, SampleError> {
        self.update_value(t_us, T::from_scaled(raw, exp2))
    }

    fn new_epoch(&mut self) {
        Bank::new_epoch(self)
    }

    fn reinit_count(&self) -> u32 {
        Bank::reinit_count(self)
    }

    fn take_over(&mut self, old: &Self) {
        Bank::take_over(self, old)
    }
}
