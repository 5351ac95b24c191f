//! Field kinds, their scales and units: what one line of the packet table expands to.
//!
//! A field of the table names a *kind* (`angle`, `rate`, `accel`, ...). The kind fixes the
//! wire type, the scale (value of one LSB), the [`Unit`] of each SI accessor and the
//! generated docs, so these are written once here and never per packet. The `kind!` macro
//! below is the compile-time side of a kind, [`Kind`] its run-time description.

/// Scale factors (value of one LSB) of the protocol's fixed-point fields.
pub mod scale {
    use core::f32::consts::PI;
    /// Angle, rad per LSB (2*pi/2^16).
    pub const ANGLE_RAD: f32 = 2.0 * PI / 65536.0;
    /// Angle, deg per LSB (360/2^16).
    pub const ANGLE_DEG: f32 = 360.0 / 65536.0;
    /// Angular rate, rad/s per LSB (7*pi/2^16).
    pub const RATE_RAD_S: f32 = 7.0 * PI / 65536.0;
    /// Angular rate, deg/s per LSB (1260/2^16).
    pub const RATE_DEG_S: f32 = 1260.0 / 65536.0;
    /// Acceleration, g per LSB (20/2^16).
    pub const ACCEL_G: f32 = 20.0 / 65536.0;
    /// Magnetic field, gauss per LSB (2/2^16).
    pub const MAG_GAUSS: f32 = 2.0 / 65536.0;
    /// Temperature, degC per LSB (200/2^16).
    pub const TEMP_DEGC: f32 = 200.0 / 65536.0;
    /// Velocity N/E/D, m/s per LSB (512/2^16).
    pub const VEL_M_S: f32 = 512.0 / 65536.0;
    /// Latitude / longitude (I4), rad per LSB (2*pi/2^32).
    pub const LATLON_RAD: f64 = 2.0 * core::f64::consts::PI / 4_294_967_296.0;
    /// Latitude / longitude (I4), deg per LSB (360/2^32).
    pub const LATLON_DEG: f64 = 360.0 / 4_294_967_296.0;
    /// Altitude, m per LSB (0.25; read as plain i16 like known decoders).
    pub const ALT_M: f32 = 0.25;
    /// Delta velocity (S2, I4), m/s per LSB (200/2^32).
    pub const DVEL_M_S: f32 = 200.0 / 4_294_967_296.0;
    /// Delta angle (S2, I4), rad per LSB (7*pi/2^32).
    pub const DANGLE_RAD: f32 = 7.0 * PI / 4_294_967_296.0;

    /// An angle field's value in deg as an integer and a power of two: `raw * 360/2^16` deg is
    /// `(raw * ANGLE_DEG_SCALED.0) * 2^ANGLE_DEG_SCALED.1` = `45 raw * 2^-13` exactly. What a
    /// fixed-point consumer converts without a float on the way
    /// (`estimators::EstimatorBank::update_scaled`).
    pub const ANGLE_DEG_SCALED: (i32, i32) = (45, -13);

    /// An angle field in deg: `raw * 360/2^16` = `raw * 45 * 2^-13`, exact in `f32` and the
    /// same bits on every target: built with integer operations only on a bare-metal target without
    /// hardware floating point (an ABI other than `eabihf`): no soft-float routine is linked.
    #[inline]
    pub fn angle_deg(raw: i16) -> f32 {
        exact(raw, ANGLE_DEG_SCALED.0, ANGLE_DEG_SCALED.1, ANGLE_DEG)
    }

    /// An angular rate field in deg/s: `raw * 1260/2^16` = `raw * 315 * 2^-14`, exact in `f32`,
    /// built as [`angle_deg`] is.
    #[inline]
    pub fn rate_deg_s(raw: i16) -> f32 {
        exact(raw, 315, -14, RATE_DEG_S)
    }

    /// `raw * lsb` where `lsb = m 2^e` exactly and `|raw m| < 2^24`, so that the product is
    /// exact in `f32`. On a bare-metal target without hardware floating point (an ABI other
    /// than `eabihf`) it is built from the integers' bits ([`dyadic_f32`]), so no soft-float
    /// routine is linked; elsewhere it is the float product `raw as f32 * lsb`, also exact:
    /// the same bits either way.
    #[inline]
    fn exact(raw: i16, m: i32, e: i32, lsb: f32) -> f32 {
        if INTEGER_ONLY {
            dyadic_f32(i32::from(raw) * m, e)
        } else {
            f32::from(raw) * lsb
        }
    }

    /// A bare-metal target without hardware floating point: the degree conversions use
    /// integer operations.
    const INTEGER_ONLY: bool = cfg!(all(target_os = "none", not(target_abi = "eabihf")));

    /// `m * 2^e` as an `f32` built from its bits: exact for `|m| < 2^24` and a result in the
    /// normal range (the callers' `m` and `e` keep it there); `m = 0` gives `+0.0`. Out of
    /// line: one copy for every accessor.
    #[inline(never)]
    pub(crate) fn dyadic_f32(m: i32, e: i32) -> f32 {
        if m == 0 {
            return 0.0;
        }
        let sign = if m < 0 { 0x8000_0000 } else { 0 };
        let a = m.unsigned_abs();
        // The leading one's position, at most 23 (|m| < 2^24).
        let msb = 31 - a.leading_zeros();
        let fraction = (a << (23 - msb)) & 0x007F_FFFF;
        let exponent = (msb as i32 + e + 127) as u32;
        f32::from_bits(sign | exponent << 23 | fraction)
    }
}

/// A physical unit of a field value.
///
/// Not to be confused with [`crate::unit::Unit`], the simulated NAV440 device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unit {
    /// Radian (angles, latitude, longitude, delta angles).
    Rad,
    /// Degree (the `*_deg` helpers).
    Deg,
    /// Radian per second (angular rates).
    RadPerS,
    /// Degree per second (the `*_deg_s` helpers).
    DegPerS,
    /// Standard gravity, 9.80665 m/s^2 (accelerations).
    G,
    /// Gauss, 1e-4 T (magnetic field).
    Gauss,
    /// Degree Celsius (temperatures).
    DegC,
    /// Metre per second (velocities, delta velocities).
    MPerS,
    /// Metre (altitude).
    M,
    /// Millisecond (time of week).
    Ms,
}

impl Unit {
    /// Every unit.
    pub const ALL: [Unit; 10] = [
        Unit::Rad,
        Unit::Deg,
        Unit::RadPerS,
        Unit::DegPerS,
        Unit::G,
        Unit::Gauss,
        Unit::DegC,
        Unit::MPerS,
        Unit::M,
        Unit::Ms,
    ];

    /// The unit's symbol: `"rad"`, `"deg"`, `"rad/s"`, `"deg/s"`, `"g"`, `"gauss"`, `"degC"`,
    /// `"m/s"`, `"m"`, `"ms"` (also what `Display` writes).
    pub const fn symbol(self) -> &'static str {
        match self {
            Unit::Rad => "rad",
            Unit::Deg => "deg",
            Unit::RadPerS => "rad/s",
            Unit::DegPerS => "deg/s",
            Unit::G => "g",
            Unit::Gauss => "gauss",
            Unit::DegC => "degC",
            Unit::MPerS => "m/s",
            Unit::M => "m",
            Unit::Ms => "ms",
        }
    }

    /// The unit whose [`symbol`](Self::symbol) is `s`.
    pub fn from_symbol(s: &str) -> Option<Unit> {
        Unit::ALL.into_iter().find(|u| u.symbol() == s)
    }
}

impl core::fmt::Display for Unit {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.symbol())
    }
}

/// What a field of the packet table holds: fixes its wire type, scale, unit and docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Kind {
    /// Euler angle (roll, pitch, yaw): I2, 2*pi/2^16 rad per LSB.
    Angle,
    /// Angular rate: I2, 7*pi/2^16 rad/s per LSB.
    Rate,
    /// Acceleration: I2, 20/2^16 g per LSB.
    Accel,
    /// Magnetic field: I2, 2/2^16 gauss per LSB.
    Mag,
    /// Temperature: I2, 200/2^16 degC per LSB.
    Temp,
    /// Velocity north/east/down: I2, 512/2^16 m/s per LSB.
    Velocity,
    /// Latitude or longitude: I4, 2*pi/2^32 rad per LSB (f64 accessors).
    LatLon,
    /// Altitude: I2, 0.25 m per LSB.
    Altitude,
    /// Delta velocity (S2): I4, 200/2^32 m/s per LSB.
    DeltaVelocity,
    /// Delta angle (S2): I4, 7*pi/2^32 rad per LSB.
    DeltaAngle,
    /// timeITOW: U4, GPS time of week in ms (wraps at 604 800 000 ms).
    Itow,
    /// GPSITOW: U2, low 16 bits of the time of week in ms (wraps every 65.536 s).
    GpsItow,
    /// Bit-field status word: U2 (BIT and the T0 words).
    Status,
    /// Sample counter: U2 (wraps at 2^16).
    Counter,
    /// Plain integer code (U1 or U2): version numbers, a type code.
    Code,
}

impl Kind {
    /// The unit of the value the field's first SI accessor returns ([`Field::si`]); `None` for
    /// status words, counters and codes.
    pub const fn unit(self) -> Option<Unit> {
        Some(match self {
            Kind::Angle | Kind::LatLon | Kind::DeltaAngle => Unit::Rad,
            Kind::Rate => Unit::RadPerS,
            Kind::Accel => Unit::G,
            Kind::Mag => Unit::Gauss,
            Kind::Temp => Unit::DegC,
            Kind::Velocity | Kind::DeltaVelocity => Unit::MPerS,
            Kind::Altitude => Unit::M,
            Kind::Itow | Kind::GpsItow => Unit::Ms,
            Kind::Status | Kind::Counter | Kind::Code => return None,
        })
    }

    /// Value of one LSB in [`Kind::unit`] (the [`scale`] constant, widened to `f64`; 1 for
    /// the time of week); `None` when the kind has no unit.
    pub fn lsb(self) -> Option<f64> {
        Some(match self {
            Kind::Angle => f64::from(scale::ANGLE_RAD),
            Kind::Rate => f64::from(scale::RATE_RAD_S),
            Kind::Accel => f64::from(scale::ACCEL_G),
            Kind::Mag => f64::from(scale::MAG_GAUSS),
            Kind::Temp => f64::from(scale::TEMP_DEGC),
            Kind::Velocity => f64::from(scale::VEL_M_S),
            Kind::LatLon => scale::LATLON_RAD,
            Kind::Altitude => f64::from(scale::ALT_M),
            Kind::DeltaVelocity => f64::from(scale::DVEL_M_S),
            Kind::DeltaAngle => f64::from(scale::DANGLE_RAD),
            Kind::Itow | Kind::GpsItow => 1.0,
            Kind::Status | Kind::Counter | Kind::Code => return None,
        })
    }

    /// True for bit-field status words (best shown in hex).
    pub const fn is_flags(self) -> bool {
        matches!(self, Kind::Status)
    }
}

/// What a field means to a consumer that reads packets by meaning rather than by type:
/// [`Packet::attitude`](crate::Packet::attitude), [`Packet::body_rates`](crate::Packet::body_rates),
/// [`Packet::time`](crate::Packet::time), [`Packet::bit`](crate::Packet::bit).
/// At most one field per role in a packet (checked at compile time).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Role {
    /// Roll angle phi (an [`Kind::Angle`]).
    Roll,
    /// Pitch angle theta (an [`Kind::Angle`]).
    Pitch,
    /// Yaw angle psi, true or magnetic (an [`Kind::Angle`]).
    Yaw,
    /// Body x angular rate p (a [`Kind::Rate`]).
    P,
    /// Body y angular rate q (a [`Kind::Rate`]).
    Q,
    /// Body z angular rate r (a [`Kind::Rate`]).
    R,
    /// The packet's time stamp ([`Kind::Itow`] or [`Kind::GpsItow`]).
    Time,
    /// The BIT status word (a [`Kind::Status`], see [`Bit`](crate::Bit)).
    Bit,
}

/// One line of the packet table, as data: [`S0::FIELDS`](crate::S0::FIELDS) etc.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldInfo {
    /// The field's name (raw accessor and `*Fields` member).
    pub name: &'static str,
    /// Offset in the payload, bytes.
    pub offset: usize,
    /// Size on the wire, bytes.
    pub size: usize,
    /// The field's kind.
    pub kind: Kind,
    /// The field's role, if any.
    pub role: Option<Role>,
}

/// True when `fields` tile `0..len` in order with no gap or overlap (checked at compile time
/// for every packet of the table). Used only in those `const` assertions, which rustc 1.85 (the
/// crate's minimum) does not count as a use.
#[allow(dead_code)]
pub(crate) const fn tiles(fields: &[FieldInfo], len: usize) -> bool {
    let mut at = 0;
    let mut i = 0;
    while i < fields.len() {
        if fields[i].offset != at {
            return false;
        }
        at += fields[i].size;
        i += 1;
    }
    at == len
}

/// One field of a fixed-layout packet, as yielded by the views' `for_each_field` and
/// [`Packet::for_each_field`](crate::Packet::for_each_field).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Field {
    /// The field's name, as in the view's raw accessor and the `*Fields` struct (e.g. `"roll"`,
    /// `"yaw_true"`, `"time_itow"`, `"bit"`).
    pub name: &'static str,
    /// The wire integer, sign- or zero-extended (e.g. `0x071C` = 1820 for a roll of 10 deg).
    pub raw: i64,
    /// The physical value and its unit, when the field has one: the view's first scaled
    /// accessor (`roll_rad`: 0.1745 [`Unit::Rad`]), or the raw integer itself for a field whose
    /// LSB is a unit (timeITOW / GPSITOW: [`Unit::Ms`]). `None` for counters, codes and status
    /// words.
    pub si: Option<Quantity>,
    /// True for bit-field status words (BIT and the T0 words), best shown in hex.
    pub flags: bool,
    /// The field's kind (fixes its unit and scale).
    pub kind: Kind,
}

/// A physical value and its unit.
///
/// Units, per [`Kind`]: angles [`Unit::Rad`], angular rates [`Unit::RadPerS`], accelerations
/// [`Unit::G`] (standard gravity, 9.80665 m/s^2), magnetic field [`Unit::Gauss`] (1e-4 T),
/// temperatures [`Unit::DegC`], velocities and delta velocities [`Unit::MPerS`], altitude
/// [`Unit::M`], time of week [`Unit::Ms`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quantity {
    /// The value, in the precision of the view's accessor.
    pub value: SiValue,
    /// The unit of `value`.
    pub unit: Unit,
}

/// A physical value in the precision its accessor returns: `f32`, or `f64` for latitude,
/// longitude and time of week.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SiValue {
    /// An `f32` accessor's value.
    F32(f32),
    /// An `f64` value (latitude, longitude, time of week).
    F64(f64),
}

impl SiValue {
    /// The value as `f64` (exact for both variants).
    pub fn to_f64(self) -> f64 {
        match self {
            SiValue::F32(v) => f64::from(v),
            SiValue::F64(v) => v,
        }
    }
}

impl From<f32> for SiValue {
    fn from(v: f32) -> Self {
        SiValue::F32(v)
    }
}

impl From<f64> for SiValue {
    fn from(v: f64) -> Self {
        SiValue::F64(v)
    }
}

/// Big-endian wire integers.
pub(crate) trait BeField: Sized + Copy {
    fn read(p: &[u8], off: usize) -> Self;
    fn write(self, p: &mut [u8], off: usize);
}

macro_rules! be_field {
    ($($t:ty),*) => {$(
        impl BeField for $t {
            #[inline(always)]
            fn read(p: &[u8], off: usize) -> Self {
                let mut b = [0u8; core::mem::size_of::<$t>()];
                if let Some(s) = p.get(off..off + b.len()) {
                    b.copy_from_slice(s);
                }
                <$t>::from_be_bytes(b)
            }
            #[inline(always)]
            fn write(self, p: &mut [u8], off: usize) {
                let b = self.to_be_bytes();
                if let Some(d) = p.get_mut(off..off + b.len()) {
                    d.copy_from_slice(&b);
                }
            }
        }
    )*};
}
be_field!(u8, i16, u16, i32, u32);

/// One SI accessor: `$f` (the raw accessor) times `$scale`, in `$unit`.
macro_rules! si_accessor {
    ($f:ident, $name:ident, $rt:ty, $scale:expr, $unit:literal, $lsb:literal) => {
        #[doc = concat!("`", stringify!($f), "` in ", $unit, " (", $lsb, " per LSB).")]
        #[inline]
        pub fn $name(&self) -> $rt {
            self.$f() as $rt * $scale
        }
    };
}

/// An SI accessor computed exactly with integer operations by `$conv` (`scale::angle_deg`,
/// `scale::rate_deg_s`): the degree accessors, which the pipeline reads on every packet.
macro_rules! exact_accessor {
    ($f:ident, $name:ident, $conv:path, $unit:literal, $lsb:literal) => {
        #[doc = concat!("`", stringify!($f), "` in ", $unit, " (", $lsb, " per LSB; exact, integer operations only).")]
        #[inline]
        pub fn $name(&self) -> f32 {
            $conv(self.$f())
        }
    };
}

/// The compile-time side of a field kind. Arms per kind: `@ty` (wire type), `@kind`
/// ([`Kind`] value), `@doc` (the wire paragraph of the raw accessor's doc) and `@si` (the SI
/// accessors, whose names the table gives). Adding a kind: one arm of each, plus a [`Kind`]
/// variant.
macro_rules! kind {
    (@ty angle) => { i16 };
    (@ty rate) => { i16 };
    (@ty accel) => { i16 };
    (@ty mag) => { i16 };
    (@ty temp) => { i16 };
    (@ty vel) => { i16 };
    (@ty latlon) => { i32 };
    (@ty alt) => { i16 };
    (@ty dvel) => { i32 };
    (@ty dangle) => { i32 };
    (@ty itow) => { u32 };
    (@ty gps_itow) => { u16 };
    (@ty status) => { u16 };
    (@ty counter) => { u16 };
    (@ty code8) => { u8 };
    (@ty code16) => { u16 };

    (@kind angle) => { Kind::Angle };
    (@kind rate) => { Kind::Rate };
    (@kind accel) => { Kind::Accel };
    (@kind mag) => { Kind::Mag };
    (@kind temp) => { Kind::Temp };
    (@kind vel) => { Kind::Velocity };
    (@kind latlon) => { Kind::LatLon };
    (@kind alt) => { Kind::Altitude };
    (@kind dvel) => { Kind::DeltaVelocity };
    (@kind dangle) => { Kind::DeltaAngle };
    (@kind itow) => { Kind::Itow };
    (@kind gps_itow) => { Kind::GpsItow };
    (@kind status) => { Kind::Status };
    (@kind counter) => { Kind::Counter };
    (@kind code8) => { Kind::Code };
    (@kind code16) => { Kind::Code };

    (@doc angle) => { "Raw I2, 2*pi/2^16 rad (360/2^16 deg) per LSB." };
    (@doc rate) => { "Raw I2, 7*pi/2^16 rad/s (1260/2^16 deg/s) per LSB." };
    (@doc accel) => { "Raw I2, 20/2^16 g per LSB." };
    (@doc mag) => { "Raw I2, 2/2^16 gauss per LSB." };
    (@doc temp) => { "Raw I2, 200/2^16 degC per LSB." };
    (@doc vel) => { "Raw I2, 512/2^16 m/s per LSB." };
    (@doc latlon) => { "Raw I4, 2*pi/2^32 rad (360/2^32 deg) per LSB." };
    (@doc alt) => { "Raw I2, 0.25 m per LSB (read as plain i16)." };
    (@doc dvel) => { "Raw I4, 200/2^32 m/s per LSB." };
    (@doc dangle) => { "Raw I4, 7*pi/2^32 rad per LSB." };
    (@doc itow) => { "U4, ms (wraps at 604 800 000 ms)." };
    (@doc gps_itow) => { "U2, ms (low 16 bits of the time of week; wraps every 65.536 s)." };
    (@doc status) => { "U2 bit-field status word." };
    (@doc counter) => { "U2 counter (wraps at 2^16)." };
    (@doc code8) => { "U1." };
    (@doc code16) => { "U2." };

    (@si angle, $f:ident, [$rad:ident, $deg:ident]) => {
        si_accessor!($f, $rad, f32, scale::ANGLE_RAD, "rad", "2*pi/2^16 rad");
        exact_accessor!($f, $deg, scale::angle_deg, "deg", "360/2^16 deg");
    };
    (@si rate, $f:ident, [$rad_s:ident, $deg_s:ident]) => {
        si_accessor!($f, $rad_s, f32, scale::RATE_RAD_S, "rad/s", "7*pi/2^16 rad/s");
        exact_accessor!($f, $deg_s, scale::rate_deg_s, "deg/s", "1260/2^16 deg/s");
    };
    (@si accel, $f:ident, [$g:ident]) => {
        si_accessor!($f, $g, f32, scale::ACCEL_G, "g", "20/2^16 g");
    };
    (@si mag, $f:ident, [$gauss:ident]) => {
        si_accessor!($f, $gauss, f32, scale::MAG_GAUSS, "gauss", "2/2^16 gauss");
    };
    (@si temp, $f:ident, [$degc:ident]) => {
        si_accessor!($f, $degc, f32, scale::TEMP_DEGC, "degC", "200/2^16 degC");
    };
    (@si vel, $f:ident, [$m_s:ident]) => {
        si_accessor!($f, $m_s, f32, scale::VEL_M_S, "m/s", "512/2^16 m/s");
    };
    (@si latlon, $f:ident, [$rad:ident, $deg:ident]) => {
        si_accessor!($f, $rad, f64, scale::LATLON_RAD, "rad", "2*pi/2^32 rad");
        si_accessor!($f, $deg, f64, scale::LATLON_DEG, "deg", "360/2^32 deg");
    };
    (@si alt, $f:ident, [$m:ident]) => {
        si_accessor!($f, $m, f32, scale::ALT_M, "m", "0.25 m");
    };
    (@si dvel, $f:ident, [$m_s:ident]) => {
        si_accessor!($f, $m_s, f32, scale::DVEL_M_S, "m/s", "200/2^32 m/s");
    };
    (@si dangle, $f:ident, [$rad:ident]) => {
        si_accessor!($f, $rad, f32, scale::DANGLE_RAD, "rad", "7*pi/2^32 rad");
    };
    // Kinds without SI accessors (time of week, status words, counters, codes).
    (@si $k:ident, $f:ident, []) => {};

    // The value `for_each_field` reports: the first SI accessor, or the raw integer itself in
    // the kind's unit (time of week), or nothing.
    (@quantity $k:ident, $s:ident, $f:ident, [$first:ident $(, $rest:ident)*]) => {
        kind!(@kind $k).unit().map(|unit| Quantity { value: SiValue::from($s.$first()), unit })
    };
    (@quantity $k:ident, $s:ident, $f:ident, []) => {
        kind!(@kind $k).unit().map(|unit| Quantity { value: SiValue::F64(f64::from($s.$f())), unit })
    };

    // Roles: only these (kind, role) pairs exist; any other is a compile error.
    (@role $k:ident) => { None };
    (@role angle roll) => { Some(Role::Roll) };
    (@role angle pitch) => { Some(Role::Pitch) };
    (@role angle yaw) => { Some(Role::Yaw) };
    (@role rate p) => { Some(Role::P) };
    (@role rate q) => { Some(Role::Q) };
    (@role rate r) => { Some(Role::R) };
    (@role itow time) => { Some(Role::Time) };
    (@role gps_itow time) => { Some(Role::Time) };
    (@role status bit) => { Some(Role::Bit) };

    // Methods a role adds to the view.
    (@role_methods $f:ident bit) => {
        /// The BIT word as named flags.
        #[inline]
        pub fn bit_flags(&self) -> Bit {
            Bit(self.$f())
        }
    };
    (@role_methods $f:ident $($role:ident)?) => {};
}

#[cfg(test)]
mod tests {
    use super::scale;

    /// The integer conversion of the targets without an FPU gives, for every raw value, the
    /// exact value of the document's scale (360/2^16 deg, 1260/2^16 deg/s, computed in `f64`,
    /// where it is exact) and the bits of the float product the other targets compute.
    #[test]
    fn degree_conversions_are_exact_for_every_raw_value() {
        for raw in i16::MIN..=i16::MAX {
            let angle = scale::dyadic_f32(i32::from(raw) * 45, -13);
            assert_eq!(f64::from(angle), f64::from(raw) * 360.0 / 65536.0, "{raw}");
            assert_eq!(angle.to_bits(), scale::angle_deg(raw).to_bits(), "{raw}");
            let rate = scale::dyadic_f32(i32::from(raw) * 315, -14);
            assert_eq!(f64::from(rate), f64::from(raw) * 1260.0 / 65536.0, "{raw}");
            assert_eq!(rate.to_bits(), scale::rate_deg_s(raw).to_bits(), "{raw}");
        }
        // Zero is +0, as the float product of +0.
        assert_eq!(scale::dyadic_f32(0, -13).to_bits(), 0);
    }
}
