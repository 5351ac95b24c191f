//! [`crate::estimator_bank!`]: a bank generated from one table of rows.

/// Generates an estimator bank from one table: one row per estimator (a [`crate::Law`] and
/// how to build it from a [`BankConfig`](crate::BankConfig)), and the channels (CSV columns) the rows report.
///
/// Generated: the bank `$Bank<T, S>` (`new(&BankConfig)`, `update(t_us, angle_deg)`,
/// `new_epoch`, `set_turns`, `reinit_count`, `restart`, `params`, `state`), its parameters
/// `$Params<T, S>` (one field per row, validated once, shareable between axes) and state
/// `$State<T, S>` (one field per row), the channel enum `$Chan` (`ALL`, `COUNT`, `name`,
/// `CSV_COLUMNS`) and the output `$Out` (indexed by `$Chan`). Adding an estimator is one row
/// (and its channel). In a row, `cfg` (the `&BankConfig`) and `n0` (steps per
/// nominal period, for [`ClosedForm`](crate::ClosedForm)), named by `build(cfg, n0)`, are in scope of the
/// builder, which returns
/// `Result<Law, ConfigError>`; each `Channel = method` takes the row's output from
/// `law.method(&state)`. With `build(cfg, n0, prev)` the builder also sees `prev:
/// Option<&Law>`, the row being replaced by `set_gains` (`None` in `new`), so that it can
/// keep what did not change ([`ClosedForm::new_reusing`](crate::ClosedForm::new_reusing): a gain change that leaves a row's
/// gains alone then costs nothing for that row).
///
/// A row may end with a warm-start clause, `warm replay(gains)` or `warm bumpless(gains)`,
/// where `gains` is an expression of `cfg` naming what the row is built from (e.g.
/// `cfg.velocity.ilo[0]`): on a warm gain change (the generated `set_gains_warm_with`, what
/// [`crate::AdaptiveBank`] runs) the row, if `gains` changed, is replayed over the recent
/// samples or moved bumplessly; a row whose `gains` did not change keeps its state.
///
/// ```
/// use estimators::{estimator_bank, AdAdMap, AdParams, BankConfig, ClosedForm, Law, Series};
///
/// estimator_bank! {
///     /// AD velocity and AD-AD acceleration.
///     bank AdBank, params AdBankParams, state AdBankState, output AdOut, channel AdChannel;
///     build(cfg, n0);
///     channels {
///         /// AD velocity.
///         AdV = "ad_v",
///         /// AD-AD acceleration.
///         AdA = "ad_a",
///     }
///     rows {
///         /// AD, closed form.
///         ad_v: ClosedForm<AdParams<T>> = Ok(ClosedForm::new(AdParams::new(cfg.velocity.ad_t, cfg.h)?, n0, cfg.hold))
///             => [AdV = output] warm replay(cfg.velocity.ad_t);
///         /// AD-AD, closed form.
///         ad_a: AdAdMap<T> = {
///             let ad = AdParams::new(cfg.acceleration.ad_t, cfg.h)?;
///             Ok(ClosedForm::new(Series::new(ad, ad), n0, cfg.hold))
///         } => [AdA = output] warm bumpless(cfg.acceleration.ad_t);
///     }
/// }
///
/// let mut bank = AdBank::<f32>::new(&BankConfig::default()).unwrap();
/// for k in 0..100u64 {
///     let out = bank.update(k * 10_000, 20.0 * k as f32 * 0.01).unwrap();
///     if k == 99 {
///         assert!((out[AdChannel::AdV] - 20.0).abs() < 0.01);
///     }
/// }
/// assert_eq!(AdChannel::CSV_COLUMNS, "ad_v,ad_a");
/// ```
#[macro_export]
macro_rules! estimator_bank {
    (
        $(#[$bm:meta])*
        bank $Bank:ident, params $Params:ident, state $State:ident, output $Out:ident, channel $Chan:ident;
        build($cfg:ident, $n0:ident);
        channels { $($chans:tt)* }
        rows { $($rows:tt)* }
    ) => {
        $crate::estimator_bank! {
            $(#[$bm])*
            bank $Bank, params $Params, state $State, output $Out, channel $Chan;
            build($cfg, $n0, __estimator_bank_prev);
            channels { $($chans)* }
            rows { $($rows)* }
        }
    };
    (
        $(#[$bm:meta])*
        bank $Bank:ident, params $Params:ident, state $State:ident, output $Out:ident, channel $Chan:ident;
        build($cfg:ident, $n0:ident, $prev:ident);
        channels { $( $(#[$cm:meta])* $ch:ident = $csv:literal ),+ $(,)? }
        rows { $( $(#[$rm:meta])* $field:ident : $Law:ty = $build:expr => [ $( $rch:ident = $get:ident ),+ ] $( warm $warm:ident ( $key:expr ) )? ; )+ }
    ) => {
        /// The channels (output columns) of the bank, in CSV order.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $Chan {
            $( $(#[$cm])* $ch, )+
        }

        impl $Chan {
            /// Every channel, in order.
            pub const ALL: &'static [$Chan] = &[ $( $Chan::$ch ),+ ];
            /// The number of channels.
            pub const COUNT: usize = [ $( $csv ),+ ].len();
            /// The CSV column names, comma-separated, in order.
            pub const CSV_COLUMNS: &'static str = $crate::__bank_columns!($($csv),+);
            /// The CSV column names, in order.
            pub const NAMES: [&'static str; $Chan::COUNT] = [ $( $csv ),+ ];
            /// The channel's CSV column name.
            pub const fn name(self) -> &'static str {
                match self { $( $Chan::$ch => $csv, )+ }
            }
            /// The channel's position in [`Self::ALL`] and in the output.
            pub const fn index(self) -> usize {
                self as usize
            }
        }

        /// One output of the bank: the unwrapped input angle and one value per channel
        /// (velocities in deg/s, accelerations in deg/s^2).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct $Out {
            /// The unwrapped angle, deg, rounded to f32 (see `residual_deg`).
            pub unwrapped_deg: f32,
            /// What f32 rounding took off the unwrapped angle, deg: the exact unwrapped angle
            /// is `unwrapped_deg as f64 + residual_deg` (0 while f32 holds it).
            pub residual_deg: f64,
            /// The channels' values, indexed by the channel (`out[channel]`).
            pub values: [f32; $Chan::COUNT],
        }

        impl Default for $Out {
            fn default() -> Self {
                Self { unwrapped_deg: 0.0, residual_deg: 0.0, values: [0.0; $Chan::COUNT] }
            }
        }

        impl core::ops::Index<$Chan> for $Out {
            type Output = f32;
            fn index(&self, c: $Chan) -> &f32 {
                &self.values[c as usize]
            }
        }

        impl $Out {
            /// `(channel, value)` pairs in CSV order.
            pub fn iter(&self) -> impl Iterator<Item = ($Chan, f32)> + '_ {
                $Chan::ALL.iter().copied().zip(self.values.iter().copied())
            }
        }

        impl $crate::EstimatorOutput for $Out {
            const CHANNELS: usize = $Chan::COUNT;
            const CHANNEL_NAMES: &'static [&'static str] = &$Chan::NAMES;
            const CSV_COLUMNS: &'static str = $Chan::CSV_COLUMNS;

            #[inline]
            fn unwrapped_deg(&self) -> f32 {
                self.unwrapped_deg
            }

            #[inline]
            fn residual_deg(&self) -> f64 {
                self.residual_deg
            }

            #[inline]
            fn values(&self) -> &[f32] {
                &self.values
            }
        }

        /// The validated parameters of every row (computed once; shareable between axes).
        #[derive(Clone, Copy, Debug)]
        pub struct $Params<T: $crate::Real, S: $crate::SqrtFn<T> = $crate::NativeSqrt> {
            $( $(#[$rm])* pub $field: $Law, )+
            _sqrt: core::marker::PhantomData<(T, S)>,
        }

        /// The state of every row.
        #[derive(Clone, Copy, Debug)]
        pub struct $State<T: $crate::Real, S: $crate::SqrtFn<T> = $crate::NativeSqrt> {
            $( $(#[$rm])* pub $field: <$Law as $crate::Law>::State, )+
            _sqrt: core::marker::PhantomData<(T, S)>,
        }

        $(#[$bm])*
        #[derive(Clone, Copy, Debug)]
        pub struct $Bank<T: $crate::Real, S: $crate::SqrtFn<T> = $crate::NativeSqrt> {
            input: $crate::BankInput<T>,
            params: $Params<T, S>,
            state: $State<T, S>,
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $Params<T, S> {
            /// Validates `cfg` and builds every row's parameters; `n0` = steps per nominal
            /// sample period for the closed-form maps (0: no map).
            pub fn new($cfg: &$crate::BankConfig, $n0: u32) -> Result<Self, $crate::ConfigError> {
                Self::new_reusing($cfg, $n0, None)
            }

            /// [`Self::new`], where each row's builder may reuse the row of `prev` (the
            /// parameters being replaced; named by the third name of `build(cfg, n0, prev)`,
            /// an `Option<&Law>` in the row's scope) instead of recomputing what did not
            /// change, e.g. `ClosedForm::new_reusing`. Same result as `new`.
            #[allow(unused_variables)]
            pub fn new_reusing(
                $cfg: &$crate::BankConfig,
                $n0: u32,
                previous: Option<&Self>,
            ) -> Result<Self, $crate::ConfigError> {
                Ok(Self {
                    $( $field: {
                        let $prev: Option<&$Law> = previous.map(|p| &p.$field);
                        let r: Result<$Law, $crate::ConfigError> = $build;
                        r?
                    }, )+
                    _sqrt: core::marker::PhantomData,
                })
            }

            /// Every row's state, initialised at `y0`.
            pub fn init(&self, y0: T) -> $State<T, S> {
                use $crate::Law as _;
                $State { $( $field: self.$field.init(y0), )+ _sqrt: core::marker::PhantomData }
            }

            /// Translates every row's state by `d` (deg).
            #[inline]
            pub fn translate(&self, s: &mut $State<T, S>, d: T) {
                use $crate::Law as _;
                $( self.$field.translate(&mut s.$field, d); )+
            }

            /// Bumpless gain change: moves every row's state `s`, produced by the parameters
            /// `old`, to the equilibrium of these parameters at the last input `y` (the
            /// laws' frame) with the same outputs (`Law::retune_state`).
            pub fn retune_state(&self, old: &Self, s: &mut $State<T, S>, y: T) {
                use $crate::Law as _;
                $( self.$field.retune_state(&old.$field, &mut s.$field, y); )+
            }

            /// Every row's state after replaying `history` (what a bank's laws were fed,
            /// oldest first, see `update_fed`) through these parameters: started at rest at
            /// the first entry's input (`init`, then `on_init`), re-initialised where the
            /// history was (`Feed::Reset`, then `on_init`), translated where the frame
            /// shifted. `None` for an empty history.
            pub fn replay<'h, I, F>(&self, history: I, mut on_init: F) -> Option<$State<T, S>>
            where
                I: IntoIterator<Item = &'h $crate::Fed<T>>,
                F: FnMut(&mut $State<T, S>),
                T: 'h,
            {
                let mut state: Option<$State<T, S>> = None;
                for fed in history {
                    match (fed.feed, state.as_mut()) {
                        ($crate::Feed::Reset(y), _) => {
                            let mut s = self.init(y);
                            on_init(&mut s);
                            state = Some(s);
                        }
                        ($crate::Feed::Advance { y_prev, y, n, hold }, Some(s)) => {
                            if let Some(d) = fed.shift {
                                self.translate(s, d);
                            }
                            self.advance(s, y_prev, y, n, hold);
                        }
                        ($crate::Feed::Advance { y_prev, y, n, hold }, None) => {
                            // `y_prev` is already in this sample's frame.
                            let mut s = self.init(y_prev);
                            on_init(&mut s);
                            self.advance(&mut s, y_prev, y, n, hold);
                            state = Some(s);
                        }
                    }
                }
                state
            }

            /// Advances every row over one sample interval.
            #[inline]
            pub fn advance(&self, s: &mut $State<T, S>, y_prev: T, y: T, n: u32, hold: $crate::Hold) {
                use $crate::Law as _;
                $( self.$field.advance(&mut s.$field, y_prev, y, n, hold); )+
            }

            /// The channels' values of state `s`.
            #[inline]
            pub fn values(&self, s: &$State<T, S>) -> [f32; $Chan::COUNT] {
                #[allow(unused_imports)]
                use $crate::Law as _;
                let mut v = [0.0f32; $Chan::COUNT];
                $( $( v[$Chan::$rch as usize] = $crate::Real::to_f32(self.$field.$get(&s.$field)); )+ )+
                v
            }
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $Bank<T, S> {
            /// Largest accepted `|angle_deg|`, deg (`BankInput::MAX_ABS_DEG`, 1e6).
            pub const MAX_ABS_DEG: f32 = $crate::BankInput::<T>::MAX_ABS_DEG;

            /// Builds the bank (validates every parameter; computes the closed-form maps and
            /// the Kalman gains).
            pub fn new(cfg: &$crate::BankConfig) -> Result<Self, $crate::ConfigError> {
                let (input, n0) = $crate::BankInput::new(cfg)?;
                let params = $Params::new(cfg, n0)?;
                let state = params.init(T::ZERO);
                Ok(Self { input, params, state })
            }

            /// Feeds one sample. `t_us`: sample time in µs (monotonic); `angle_deg`: the angle
            /// in deg (within +-180 when wrapping).
            ///
            /// The first sample, and the first after a gap longer than the gap rule,
            /// initialise every state from it and report 0 velocities and accelerations.
            /// Otherwise every law runs `n = round(dt / h)` steps (see `SampleAdapter`).
            ///
            /// Errors (state unchanged): `SampleError::NotFinite` for NaN/infinite
            /// input, `SampleError::OutOfRange` for `|angle_deg|` above
            /// `MAX_ABS_DEG`, `SampleError::NonIncreasingTime` for `t_us` not
            /// later than the previous sample.
            #[inline]
            pub fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<$Out, $crate::SampleError> {
                self.update_fed(t_us, angle_deg).map(|(out, _)| out)
            }

            /// [`Self::update`], also returning what the laws were fed (`Fed`): what
            /// [`Self::set_gains_replaying`] replays.
            #[inline(always)]
            pub fn update_fed(&mut self, t_us: u64, angle_deg: f32) -> Result<($Out, $crate::Fed<T>), $crate::SampleError> {
                let a = self.input.accept(t_us, angle_deg)?;
                if let Some(d) = a.shift {
                    self.params.translate(&mut self.state, d);
                }
                let values = match a.feed {
                    $crate::Feed::Reset(y) => {
                        self.state = self.params.init(y);
                        [0.0; $Chan::COUNT]
                    }
                    $crate::Feed::Advance { y_prev, y, n, hold } => {
                        self.params.advance(&mut self.state, y_prev, y, n, hold);
                        self.params.values(&self.state)
                    }
                };
                let out = $Out { unwrapped_deg: a.angle.0, residual_deg: a.angle.1, values };
                Ok((out, $crate::Fed { shift: a.shift, feed: a.feed }))
            }

            /// How many times a gap longer than the gap rule re-initialised the bank.
            pub fn reinit_count(&self) -> u32 {
                self.input.reinit_count()
            }

            /// Starts a new epoch (a confirmed time jump): the next sample re-initialises every
            /// law from itself and reports 0, whatever its time; the unwrapper keeps its turn
            /// count. Not counted in [`Self::reinit_count`].
            pub fn new_epoch(&mut self) {
                self.input.new_epoch();
            }

            /// Sets the unwrapper's turn count to `turns`: only the angle column moves by
            /// `360 * delta` deg; the laws run in the local frame and are unaffected.
            pub fn set_turns(&mut self, turns: i64) {
                self.input.set_turns(turns);
            }

            /// Takes over from `old` (the bank this one replaces, built for another nominal
            /// period after a new epoch) its unwrapper and its re-init count; the next sample
            /// starts a new epoch (`EstimatorBank::take_over`).
            pub fn take_over(&mut self, old: &Self) {
                self.input.take_over(&old.input);
            }

            /// Forgets everything: the next sample is treated as the first one.
            pub fn restart(&mut self) {
                self.input.restart();
                self.state = self.params.init(T::ZERO);
            }

            /// Replaces every row's parameters by those of `cfg`; the laws continue from where
            /// they are with the new gains (what a gain schedule does, `AdaptiveBank`), their
            /// states moved so that each output continues without a jump (bumpless transfer,
            /// `Law::retune_state`: the ILO's and AD's steady state depends on their gains).
            /// Only the gains of `cfg` are meant to differ from the configuration the bank was
            /// built with: the input stage (step, hold, nominal period, gap rule, unwrapping)
            /// is kept as built. On error nothing changes.
            /// Cost: that of building the parameters (closed-form maps, Kalman gains) of the
            /// rows whose gains changed (for rows whose builder reuses the previous row, see
            /// `new_reusing` of the parameters; the same parameters as a full rebuild), see
            /// `cargo xtask bench`.
            pub fn set_gains(&mut self, cfg: &$crate::BankConfig) -> Result<(), $crate::ConfigError> {
                let (_, n0) = $crate::BankInput::<T>::new(cfg)?;
                let params = $Params::new_reusing(cfg, n0, Some(&self.params))?;
                params.retune_state(&self.params, &mut self.state, self.input.last());
                self.params = params;
                Ok(())
            }

            /// [`Self::set_gains`], with the new laws' states rebuilt by replaying `history`
            /// (oldest first: what the laws were fed for the last samples, from
            /// [`Self::update_fed`], ending with the last sample) through the new parameters
            /// (see the parameters' `replay`). The laws then continue as if they had run with
            /// the new gains over the history (warm start), not from the old gains' states.
            /// An empty history is [`Self::set_gains`]. On error nothing changes.
            /// Cost: [`Self::set_gains`] plus one advance of every row per history entry.
            pub fn set_gains_replaying<'h, I, F>(
                &mut self,
                cfg: &$crate::BankConfig,
                history: I,
                on_init: F,
            ) -> Result<(), $crate::ConfigError>
            where
                I: IntoIterator<Item = &'h $crate::Fed<T>>,
                F: FnMut(&mut $State<T, S>),
                T: 'h,
            {
                let (_, n0) = $crate::BankInput::<T>::new(cfg)?;
                let params = $Params::new_reusing(cfg, n0, Some(&self.params))?;
                match params.replay(history, on_init) {
                    Some(s) => self.state = s,
                    None => params.retune_state(&self.params, &mut self.state, self.input.last()),
                }
                self.params = params;
                Ok(())
            }

            /// The warm gain change (what a gain schedule does on a warm start,
            /// `AdaptiveBank`) from the gains of `old` (the configuration the bank runs now;
            /// only its gains are read) to those of `new`, row by row as the table says:
            ///
            /// * a row with `warm replay(gains)` whose `gains` differ between `old` and `new`
            ///   is rebuilt by replaying `history` (see [`Self::set_gains_replaying`]; `on_init`
            ///   is applied to the replay's initial states);
            /// * a row with `warm bumpless(gains)` whose `gains` differ moves bumplessly
            ///   (`Law::retune_state`);
            /// * a row with a `warm` clause whose `gains` did not change keeps its state
            ///   exactly;
            /// * a row without a `warm` clause moves bumplessly, as in [`Self::set_gains`].
            ///
            /// An empty history is [`Self::set_gains`] (every row bumpless). On error nothing
            /// changes. Cost: [`Self::set_gains`] plus one advance of every row per history
            /// entry.
            pub fn set_gains_warm_with<'h, I, F>(
                &mut self,
                old: &$crate::BankConfig,
                new: &$crate::BankConfig,
                history: I,
                on_init: F,
            ) -> Result<(), $crate::ConfigError>
            where
                I: IntoIterator<Item = &'h $crate::Fed<T>>,
                F: FnMut(&mut $State<T, S>),
                T: 'h,
            {
                let (_, n0) = $crate::BankInput::<T>::new(new)?;
                let params = $Params::new_reusing(new, n0, Some(&self.params))?;
                let Some(replayed) = params.replay(history, on_init) else {
                    params.retune_state(&self.params, &mut self.state, self.input.last());
                    self.params = params;
                    return Ok(());
                };
                let (before, state, y) = (&self.params, &mut self.state, self.input.last());
                // Read only by rows with a `warm` clause.
                let _ = (old, new, &replayed, &before, y);
                $(
                    $crate::__bank_warm_row!(
                        params, before, state, replayed, y, old, new, $cfg;
                        $field $(, $warm($key))?
                    );
                )+
                self.params = params;
                Ok(())
            }

            /// The rows' validated parameters.
            pub fn params(&self) -> &$Params<T, S> {
                &self.params
            }

            /// The rows' state.
            pub fn state(&self) -> &$State<T, S> {
                &self.state
            }
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $crate::EstimatorBank for $Bank<T, S> {
            type Output = $Out;

            #[inline]
            fn update(&mut self, t_us: u64, angle_deg: f32) -> Result<$Out, $crate::SampleError> {
                $Bank::update(self, t_us, angle_deg)
            }

            fn new_epoch(&mut self) {
                $Bank::new_epoch(self)
            }

            fn reinit_count(&self) -> u32 {
                $Bank::reinit_count(self)
            }

            fn take_over(&mut self, old: &Self) {
                $Bank::take_over(self, old)
            }
        }

        impl<T: $crate::Real, S: $crate::SqrtFn<T>> $crate::FromConfig for $Bank<T, S> {
            fn from_config(cfg: &$crate::BankConfig) -> Result<Self, $crate::ConfigError> {
                $Bank::new(cfg)
            }
        }
    };
}

/// Comma-joins string literals (for [`estimator_bank!`]'s `CSV_COLUMNS`).
#[doc(hidden)]
#[macro_export]
macro_rules! __bank_columns {
    ($first:literal $(, $rest:literal)*) => { concat!($first $(, ",", $rest)*) };
}

/// One row of a generated bank's `set_gains_warm_with` (see [`estimator_bank!`]): `params`
/// are the new parameters, `before` the old ones, `state` the bank's state, `replayed` the
/// state replayed through `params`, `y` the last input, `cfg` the table's configuration name.
#[doc(hidden)]
#[macro_export]
macro_rules! __bank_warm_row {
    ($params:ident, $before:ident, $state:ident, $replayed:ident, $y:ident, $old:ident, $new:ident, $cfg:ident; $field:ident) => {
        $crate::Law::retune_state(&$params.$field, &$before.$field, &mut $state.$field, $y);
    };
    ($params:ident, $before:ident, $state:ident, $replayed:ident, $y:ident, $old:ident, $new:ident, $cfg:ident; $field:ident, replay($key:expr)) => {
        if $crate::__bank_warm_row!(@changed $old, $new, $cfg, $key) {
            $state.$field = $replayed.$field;
        }
    };
    ($params:ident, $before:ident, $state:ident, $replayed:ident, $y:ident, $old:ident, $new:ident, $cfg:ident; $field:ident, bumpless($key:expr)) => {
        if $crate::__bank_warm_row!(@changed $old, $new, $cfg, $key) {
            $crate::Law::retune_state(&$params.$field, &$before.$field, &mut $state.$field, $y);
        }
    };
    (@changed $old:ident, $new:ident, $cfg:ident, $key:expr) => {{
        let old_gains = {
            let $cfg: &$crate::BankConfig = $old;
            $key
        };
        let new_gains = {
            let $cfg: &$crate::BankConfig = $new;
            $key
        };
        old_gains != new_gains
    }};
}
