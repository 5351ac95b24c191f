//! [`PaperBank`](crate::PaperBank): the paper's 14 estimators.

use super::rows::{Bank, BankOutput, Channels, Row, RowValues, Rows, Warm};
use super::{BankConfig, Fed, KF_DEFAULT};
use crate::kalman::{KalmanConfig, KalmanOutput, KalmanParams};
use crate::presets::*;
use crate::Law;
use crate::{
    AdFamily, AdParams, AveConfig, AveFamily, AveParams, ClosedForm, ConfigError, EdConfig,
    EdFamily, EdParams, IloConfig, IloFamily, IloParams, KalmanNoise, KfFamily, Real, Series,
    SqrtFn, VelAcc,
};

// The paper bank is defined by two tables: its families with their gains (the columns of the
// paper's tables, each a `Family` next to its law, and the field of `BankGains` that holds its
// gains in one half of the bank) and, below, its rows (the laws it runs, each with the channels
// it reports and how it takes a warm gain change). A family added to the list needs its two
// channels and its rows in the table.
crate::family::families! {
    /// Gains of one half of the bank: the velocity estimators, or the acceleration series
    /// (where both stages of a series get the same gains). One field per family of the paper
    /// bank ([`crate::FAMILIES`]; [`crate::Family::get`] reads a family's gains from here).
    #[derive(Clone, Copy, Debug, PartialEq)]
    #[cfg_attr(feature = "defmt", derive(defmt::Format))]
    #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
    #[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
    pub struct BankGains {
        /// AVE.
        ave: AveConfig = (AVE_PAPER, AVE_PAPER) => [AveFamily],
        /// ILO1, ILO2, ILO3 (learning delay `tau = h`, `D = 1`).
        ilo: [IloConfig; 3] = (
            [ILO1_TABLE2, ILO2_TABLE2, ILO3_TABLE2],
            [ILO1_TABLE4, ILO2_TABLE4, ILO3_TABLE4]
        ) => [IloFamily<0>, IloFamily<1>, IloFamily<2>],
        /// AD time constant `T`, s.
        ad_t: f32 = (AD_VELOCITY_T, AD_ACCELERATION_T) => [AdFamily],
        /// Levant ED.
        ed: EdConfig = (ED_PAPER, ED_PAPER) => [EdFamily],
        /// Kalman tracker noise (the velocity column uses the velocity half's tracker, the
        /// acceleration column the acceleration half's).
        kf: KalmanNoise = (KF_DEFAULT, KF_DEFAULT) => [KfFamily],
    }
}

/// The names of the paper bank's families ([`FAMILIES`]), in column order: the velocity
/// channels are these with `_v`, the acceleration channels with `_a` (see [`Channel`]).
pub const VELOCITY_NAMES: [&str; FAMILY_COUNT] = {
    let mut names = [""; FAMILY_COUNT];
    let mut i = 0;
    while i < FAMILY_COUNT {
        names[i] = FAMILIES[i].name;
        i += 1;
    }
    names
};

/// ILO (`D = 1`) through its closed-form map, stored for its 2 states: the banks' ILO velocity
/// rows.
pub type IloMap<T> = ClosedForm<IloParams<T, 1>, 2>;
/// AD through its closed-form map, stored for its 2 states: the paper bank's AD velocity row.
pub type AdMap<T> = ClosedForm<AdParams<T>, 2>;
/// ILO-ILO (both stages `D = 1`) through its closed-form map: the paper bank's ILO
/// acceleration row.
pub type IloIloMap<T> = ClosedForm<Series<IloParams<T, 1>, IloParams<T, 1>>>;
/// AD-AD through its closed-form map: the paper bank's AD acceleration row.
pub type AdAdMap<T> = ClosedForm<Series<AdParams<T>, AdParams<T>>>;

/// The Kalman tracker row of a gains half.
pub(super) fn kalman<T: Real>(
    cfg: &BankConfig,
    g: &BankGains,
    out: KalmanOutput,
) -> Result<KalmanParams<T>, ConfigError> {
    KalmanParams::new(
        &KalmanConfig {
            dt: cfg.sample_period_s,
            q: g.kf.q,
            r: g.kf.r,
        },
        cfg.h,
        out,
    )
}

/// ILO row `i` of the velocity half, closed form.
pub(super) fn ilo_v<T: Real>(
    cfg: &BankConfig,
    i: usize,
    n0: u32,
    prev: Option<&IloMap<T>>,
) -> Result<IloMap<T>, ConfigError> {
    let c: &IloConfig = cfg.velocity.ilo.get(i).unwrap_or(&ILO1_TABLE2);
    let p = IloParams::new(c, cfg.h)?;
    Ok(ClosedForm::sized_reusing(p, n0, cfg.hold, prev))
}

/// ILO-ILO row `i` of the acceleration half (both stages the same gains), closed form.
fn ilo_a<T: Real>(
    cfg: &BankConfig,
    i: usize,
    n0: u32,
    prev: Option<&IloIloMap<T>>,
) -> Result<IloIloMap<T>, ConfigError> {
    let c: &IloConfig = cfg.acceleration.ilo.get(i).unwrap_or(&ILO1_TABLE4);
    let p = IloParams::new(c, cfg.h)?;
    Ok(ClosedForm::new_reusing(
        Series::new(p, p),
        n0,
        cfg.hold,
        prev,
    ))
}

/// AVE and AVE-AVE (shared first stage when the velocity and acceleration AVE are equal).
fn ave_pair<T: Real>(cfg: &BankConfig) -> Result<VelAcc<AveParams<T>>, ConfigError> {
    let (v, a): (&AveConfig, &AveConfig) = (&cfg.velocity.ave, &cfg.acceleration.ave);
    let pa = AveParams::new(a, cfg.h)?;
    Ok(VelAcc::new(AveParams::new(v, cfg.h)?, pa, pa, v == a))
}

/// ED and ED-ED (shared first stage when the velocity and acceleration ED are equal).
fn ed_pair<T: Real, S: SqrtFn<T>>(cfg: &BankConfig) -> Result<VelAcc<EdParams<T, S>>, ConfigError> {
    let (v, a): (&EdConfig, &EdConfig) = (&cfg.velocity.ed, &cfg.acceleration.ed);
    let pa = EdParams::new(a, cfg.h, cfg.ed_scheme)?;
    Ok(VelAcc::new(
        EdParams::new(v, cfg.h, cfg.ed_scheme)?,
        pa,
        pa,
        v == a,
    ))
}

/// AD velocity, closed form.
fn ad_v<T: Real>(
    cfg: &BankConfig,
    n0: u32,
    prev: Option<&AdMap<T>>,
) -> Result<AdMap<T>, ConfigError> {
    let p = AdParams::new(cfg.velocity.ad_t, cfg.h)?;
    Ok(ClosedForm::sized_reusing(p, n0, cfg.hold, prev))
}

/// AD-AD acceleration, closed form.
fn ad_a<T: Real>(
    cfg: &BankConfig,
    n0: u32,
    prev: Option<&AdAdMap<T>>,
) -> Result<AdAdMap<T>, ConfigError> {
    let p = AdParams::new(cfg.acceleration.ad_t, cfg.h)?;
    Ok(ClosedForm::new_reusing(
        Series::new(p, p),
        n0,
        cfg.hold,
        prev,
    ))
}

/// The channels of an ILO row `I` (0-based), velocity then acceleration.
const ILO_NAMES: [[&str; 1]; 6] = [
    ["ilo1_v"],
    ["ilo2_v"],
    ["ilo3_v"],
    ["ilo1_a"],
    ["ilo2_a"],
    ["ilo3_a"],
];

/// AVE velocity and AVE-AVE acceleration (`cfg.velocity.ave`, `cfg.acceleration.ave`; one
/// shared first stage when the two are equal). Replayed on a warm gain change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AveRow;

impl Channels for AveRow {
    const VELOCITY: &'static [&'static str] = &["ave_v"];
    const ACCELERATION: &'static [&'static str] = &["ave_a"];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for AveRow {
    type Law = VelAcc<AveParams<T>>;
    fn build(cfg: &BankConfig, _: u32, _: Option<&Self::Law>) -> Result<Self::Law, ConfigError> {
        ave_pair(cfg)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.velocity(law.velocity(s));
        out.acceleration(law.acceleration(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::replay_if(
            (old.velocity.ave, old.acceleration.ave) != (new.velocity.ave, new.acceleration.ave),
        )
    }
}

/// ILO `I + 1` velocity (`cfg.velocity.ilo[I]`, Table 2 gains by default) through its
/// closed-form map. Replayed on a warm gain change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IloV<const I: usize>;

impl<const I: usize> Channels for IloV<I> {
    const VELOCITY: &'static [&'static str] = &ILO_NAMES[I];
    const ACCELERATION: &'static [&'static str] = &[];
}

impl<T: Real, S: SqrtFn<T>, const I: usize> Row<T, S> for IloV<I> {
    type Law = IloMap<T>;
    fn build(
        cfg: &BankConfig,
        n0: u32,
        prev: Option<&Self::Law>,
    ) -> Result<Self::Law, ConfigError> {
        ilo_v(cfg, I, n0, prev)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.velocity(law.output(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::replay_if(old.velocity.ilo.get(I) != new.velocity.ilo.get(I))
    }
}

/// ILO `I + 1` - ILO `I + 1` acceleration (both stages `cfg.acceleration.ilo[I]`, Table 4 gains
/// by default) through its closed-form map. Moved bumplessly on a warm gain change (replayed
/// from rest, its second stage takes longer than the replayed history to settle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IloA<const I: usize>;

impl<const I: usize> Channels for IloA<I> {
    const VELOCITY: &'static [&'static str] = &[];
    const ACCELERATION: &'static [&'static str] = &ILO_NAMES[3 + I];
}

impl<T: Real, S: SqrtFn<T>, const I: usize> Row<T, S> for IloA<I> {
    type Law = IloIloMap<T>;
    fn build(
        cfg: &BankConfig,
        n0: u32,
        prev: Option<&Self::Law>,
    ) -> Result<Self::Law, ConfigError> {
        ilo_a(cfg, I, n0, prev)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.acceleration(law.output(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::bumpless_if(old.acceleration.ilo.get(I) != new.acceleration.ilo.get(I))
    }
}

/// AD velocity (`cfg.velocity.ad_t`) through its closed-form map. Replayed on a warm gain
/// change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdV;

impl Channels for AdV {
    const VELOCITY: &'static [&'static str] = &["ad_v"];
    const ACCELERATION: &'static [&'static str] = &[];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for AdV {
    type Law = AdMap<T>;
    fn build(
        cfg: &BankConfig,
        n0: u32,
        prev: Option<&Self::Law>,
    ) -> Result<Self::Law, ConfigError> {
        ad_v(cfg, n0, prev)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.velocity(law.output(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::replay_if(old.velocity.ad_t != new.velocity.ad_t)
    }
}

/// AD-AD acceleration (both stages `cfg.acceleration.ad_t`) through its closed-form map.
/// Moved bumplessly on a warm gain change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdA;

impl Channels for AdA {
    const VELOCITY: &'static [&'static str] = &[];
    const ACCELERATION: &'static [&'static str] = &["ad_a"];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for AdA {
    type Law = AdAdMap<T>;
    fn build(
        cfg: &BankConfig,
        n0: u32,
        prev: Option<&Self::Law>,
    ) -> Result<Self::Law, ConfigError> {
        ad_a(cfg, n0, prev)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.acceleration(law.output(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::bumpless_if(old.acceleration.ad_t != new.acceleration.ad_t)
    }
}

/// Levant ED velocity and ED-ED acceleration (`cfg.velocity.ed`, `cfg.acceleration.ed`; one
/// shared first stage when the two are equal). Moved bumplessly on a warm gain change (its
/// velocity state moves at most `alpha` deg/s per second, too slowly for a replay).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdRow;

impl Channels for EdRow {
    const VELOCITY: &'static [&'static str] = &["ed_v"];
    const ACCELERATION: &'static [&'static str] = &["ed_a"];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for EdRow {
    type Law = VelAcc<EdParams<T, S>>;
    fn build(cfg: &BankConfig, _: u32, _: Option<&Self::Law>) -> Result<Self::Law, ConfigError> {
        ed_pair(cfg)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.velocity(law.velocity(s));
        out.acceleration(law.acceleration(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::bumpless_if(
            (old.velocity.ed, old.acceleration.ed) != (new.velocity.ed, new.acceleration.ed),
        )
    }
}

/// The Kalman tracker with the velocity half's noise (`cfg.velocity.kf`), its velocity.
/// Replayed on a warm gain change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KfV;

impl Channels for KfV {
    const VELOCITY: &'static [&'static str] = &["kf_v"];
    const ACCELERATION: &'static [&'static str] = &[];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for KfV {
    type Law = KalmanParams<T>;
    fn build(cfg: &BankConfig, _: u32, _: Option<&Self::Law>) -> Result<Self::Law, ConfigError> {
        kalman(cfg, &cfg.velocity, KalmanOutput::Velocity)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.velocity(law.velocity(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::replay_if(old.velocity.kf != new.velocity.kf)
    }
}

/// The Kalman tracker with the acceleration half's noise (`cfg.acceleration.kf`), its
/// acceleration. Replayed on a warm gain change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KfA;

impl Channels for KfA {
    const VELOCITY: &'static [&'static str] = &[];
    const ACCELERATION: &'static [&'static str] = &["kf_a"];
}

impl<T: Real, S: SqrtFn<T>> Row<T, S> for KfA {
    type Law = KalmanParams<T>;
    fn build(cfg: &BankConfig, _: u32, _: Option<&Self::Law>) -> Result<Self::Law, ConfigError> {
        kalman(cfg, &cfg.acceleration, KalmanOutput::Acceleration)
    }
    #[inline]
    fn values(law: &Self::Law, s: &<Self::Law as Law>::State, out: &mut RowValues<'_, T>) {
        out.acceleration(law.acceleration(s));
    }
    fn warm(old: &BankConfig, new: &BankConfig) -> Warm {
        Warm::replay_if(old.acceleration.kf != new.acceleration.kf)
    }
}

/// The paper bank's rows, one family after the other (the channels: every velocity, then
/// every acceleration, in family order).
pub type PaperRows = (
    AveRow,
    IloV<0>,
    IloA<0>,
    IloV<1>,
    IloA<1>,
    IloV<2>,
    IloA<2>,
    AdV,
    AdA,
    EdRow,
    KfV,
    KfA,
);

/// The paper's bank for one angle: unwrap -> sample adapter -> AVE, ILO1-3 (Table 2), AD
/// (T = 0.01), ED (700/770), Kalman for velocity, and AVE-AVE, ILO1-3-ILO1-3 (Table 4), AD-AD
/// (T = 0.1), ED-ED, Kalman for acceleration ([`PaperRows`]).
///
/// Generic over [`Real`]: `PaperBank<f32>` for FPU targets, `PaperBank<Fx>` for Cortex-M0/M3
/// (the `f32` inputs and outputs are only converted; all arithmetic is integer). No heap; the
/// whole state is inline (see [`crate::ram`] for its size). `S` is the ED's square root
/// (default [`NativeSqrt`](crate::NativeSqrt); see [`SqrtFn`] for plugging in an FPU
/// instruction with identical results).
pub type PaperBank<T, S = crate::NativeSqrt> = Bank<PaperRows, { Channel::COUNT }, T, S>;
/// The output of [`PaperBank`], indexed by [`Channel`].
pub type PaperOutput<T = f32> = BankOutput<PaperRows, { Channel::COUNT }, T>;
/// The parameters of every row of [`PaperBank`] (validated once; shareable between axes).
pub type PaperParams<T, S = crate::NativeSqrt> = <PaperRows as Rows<T, S>>::Params;
/// The state of every row of [`PaperBank`].
pub type PaperState<T, S = crate::NativeSqrt> = <PaperRows as Rows<T, S>>::State;

/// The channels of [`PaperBank`] (output columns), in CSV order: `out[channel]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// AVE velocity, deg/s.
    AveV,
    /// ILO1 (Table 2) velocity, deg/s.
    Ilo1V,
    /// ILO2 (Table 2) velocity, deg/s.
    Ilo2V,
    /// ILO3 (Table 2) velocity, deg/s.
    Ilo3V,
    /// AD (T = 0.01 s) velocity, deg/s.
    AdV,
    /// Levant ED velocity, deg/s.
    EdV,
    /// Kalman tracker velocity, deg/s.
    KfV,
    /// AVE-AVE acceleration, deg/s^2.
    AveA,
    /// ILO1-ILO1 (Table 4) acceleration, deg/s^2.
    Ilo1A,
    /// ILO2-ILO2 (Table 4) acceleration, deg/s^2.
    Ilo2A,
    /// ILO3-ILO3 (Table 4) acceleration, deg/s^2.
    Ilo3A,
    /// AD-AD (T = 0.1 s) acceleration, deg/s^2.
    AdA,
    /// ED-ED acceleration, deg/s^2.
    EdA,
    /// Kalman tracker acceleration, deg/s^2.
    KfA,
}

impl Channel {
    /// Every channel, in order.
    pub const ALL: &'static [Channel] = {
        use Channel::*;
        &[
            AveV, Ilo1V, Ilo2V, Ilo3V, AdV, EdV, KfV, AveA, Ilo1A, Ilo2A, Ilo3A, AdA, EdA, KfA,
        ]
    };
    /// The number of channels.
    pub const COUNT: usize = Self::ALL.len();
    /// The CSV column names, in order (the rows' channels, [`PaperRows`]).
    pub const NAMES: [&'static str; Self::COUNT] = <PaperOutput>::NAMES;

    /// The channel's CSV column name.
    pub const fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// The channel's position in [`Self::ALL`] and in the output.
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// The channel's value as the output holds it (`f32` for the float types, the raw number for
/// [`Fx`](crate::Fx); [`EstimatorOutput::value`](crate::EstimatorOutput::value) reads it as `f32`).
impl<T: Real> core::ops::Index<Channel> for PaperOutput<T> {
    type Output = T::OutputValue;
    fn index(&self, c: Channel) -> &T::OutputValue {
        &self.values[c as usize]
    }
}

impl<T: Real> PaperOutput<T> {
    /// The value of channel `c` as `f32` (deg/s or deg/s^2).
    pub fn channel(&self, c: Channel) -> f32 {
        T::output_value_f32(self[c])
    }

    /// The velocities as `f32`, deg/s, one per family in [`Channel::VELOCITY`] order.
    pub fn velocities(&self) -> [f32; FAMILY_COUNT] {
        Channel::VELOCITY.map(|c| T::output_value_f32(self[c]))
    }

    /// The accelerations as `f32`, deg/s^2, one per family in [`Channel::ACCELERATION`] order.
    pub fn accelerations(&self) -> [f32; FAMILY_COUNT] {
        Channel::ACCELERATION.map(|c| T::output_value_f32(self[c]))
    }
}

impl Channel {
    /// The velocity channels, one per family in column order ([`FAMILIES`]: ave, ilo1,
    /// ilo2, ilo3, ad, ed, kf).
    pub const VELOCITY: [Channel; FAMILY_COUNT] = family_channels(false);
    /// The acceleration channels, same order.
    pub const ACCELERATION: [Channel; FAMILY_COUNT] = family_channels(true);
}

/// The velocity (or acceleration) channel of each family, in column order.
const fn family_channels(acceleration: bool) -> [Channel; FAMILY_COUNT] {
    let mut out = [Channel::AveV; FAMILY_COUNT];
    let mut i = 0;
    while i < FAMILY_COUNT {
        out[i] = if acceleration {
            FAMILIES[i].acceleration
        } else {
            FAMILIES[i].velocity
        };
        i += 1;
    }
    out
}

impl<T: Real, S: SqrtFn<T>> PaperBank<T, S> {
    /// The switching gains `deltahat` of the AVE row: the velocity AVE's (deg/s) and the
    /// AVE-AVE series' stages' (deg/s, deg/s^2; the first stage's is the velocity AVE's when
    /// the row shares it, [`VelAcc::is_shared`]).
    pub fn ave_deltahat(&self) -> crate::AveDeltahat {
        let s = &self.state().0;
        let a1 = if self.params().0.is_shared() {
            s.v.delta
        } else {
            s.a1.delta
        };
        crate::AveDeltahat {
            velocity: s.v.delta.to_f32(),
            acceleration: [a1.to_f32(), s.a2.delta.to_f32()],
        }
    }

    /// Sets the AVE row's switching gains (see [`Self::ave_deltahat`]; a negative or
    /// non-finite value leaves its `deltahat` as it is). What [`crate::AdaptiveBank`] does
    /// when it changes the AVE gains and its schedule records the `deltahat` they were tuned
    /// with.
    pub fn set_ave_deltahat(&mut self, d: &crate::AveDeltahat) {
        set_ave_deltahat::<T, S>(self.state_mut(), d);
    }
}

impl<T: Real, S: SqrtFn<T>> PaperBank<T, S> {
    /// The gain change of [`crate::AdaptiveBank`] (warm start) from the gains of `old` (what
    /// the bank runs now; only its gains are read) to those of `new`: the generated
    /// [`Self::set_gains_warm_with`], row by row as the table's `warm` clauses say (the AVE /
    /// AVE-AVE row, the velocity ILOs and AD and both trackers replayed over `history` when
    /// their gains changed; the ED / ED-ED row and the ILO-ILO and AD-AD series moved
    /// bumplessly; unchanged rows kept), where the AVE row starts its replay with the
    /// switching gains `deltahat` (deg/s, deg/s^2), or, when `None`, with those it has now.
    ///
    /// `history`: what the laws were fed for the last samples, oldest first, ending with the
    /// last one ([`Self::update_fed`]). An empty history is [`Self::set_gains`] (every row
    /// bumpless). On error nothing changes.
    pub fn set_gains_warm<'h, I>(
        &mut self,
        old: &BankConfig,
        new: &BankConfig,
        history: I,
        deltahat: Option<crate::AveDeltahat>,
    ) -> Result<(), ConfigError>
    where
        I: IntoIterator<Item = &'h Fed<T>>,
        T: 'h,
    {
        let deltahat = deltahat.unwrap_or_else(|| self.ave_deltahat());
        self.set_gains_warm_with(old, new, history, |s| {
            set_ave_deltahat::<T, S>(s, &deltahat)
        })
    }
}

/// Sets the AVE row's switching gains in `state` (see [`PaperBank::set_ave_deltahat`]).
pub(crate) fn set_ave_deltahat<T: Real, S: SqrtFn<T>>(
    state: &mut PaperState<T, S>,
    d: &crate::AveDeltahat,
) {
    let set = |x: &mut T, v: f32| {
        if v.is_finite() && v >= 0.0 {
            *x = T::from_f32(v);
        }
    };
    let s = &mut state.0;
    set(&mut s.v.delta, d.velocity);
    set(&mut s.a1.delta, d.acceleration[0]);
    set(&mut s.a2.delta, d.acceleration[1]);
}
