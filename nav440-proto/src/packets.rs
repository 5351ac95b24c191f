//! Typed, zero-copy views of every packet, their raw-field structs and the [`Packet`] enum.
//!
//! Every view wraps a payload slice whose length was checked once in `new`, so accessors are
//! plain big-endian loads at fixed offsets. Raw accessors return the wire integers; SI
//! accessors (`*_rad`, `*_rad_s`, `*_g`, `*_m_s`, `*_gauss`, `*_degc`, `*_m`) and degree helpers
//! (`*_deg`, `*_deg_s`) return `f32` (`f64` for latitude/longitude). `fields()` copies a view
//! into its `*Fields` struct, whose `encode` writes a whole frame again.

use crate::encode::{encode_frame, EncodeError};
use crate::parser::Frame;
use crate::types::{FieldId, PacketType};

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
}

/// Why a CRC-valid frame could not be decoded as its type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// The payload length does not match the packet type.
    Length {
        /// The frame's type.
        packet_type: PacketType,
        /// Payload length the type requires (bytes; for variable-length types the minimum or
        /// the length implied by the count byte).
        expected: usize,
        /// Payload length received (bytes).
        actual: usize,
    },
}

/// Big-endian wire integers.
trait BeField: Sized + Copy {
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

/// The BIT (built-in test) status word of the output packets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bit(pub u16);

impl Bit {
    /// Bit 0: masterFail, the only fatal flag.
    pub const MASTER_FAIL: u16 = 1 << 0;
    /// Bit 1: hardwareError.
    pub const HARDWARE_ERROR: u16 = 1 << 1;
    /// Bit 2: comError.
    pub const COM_ERROR: u16 = 1 << 2;
    /// Bit 3: softwareError.
    pub const SOFTWARE_ERROR: u16 = 1 << 3;
    /// Bit 8: masterStatus.
    pub const MASTER_STATUS: u16 = 1 << 8;
    /// Bit 9: hardwareStatus.
    pub const HARDWARE_STATUS: u16 = 1 << 9;
    /// Bit 10: comStatus.
    pub const COM_STATUS: u16 = 1 << 10;
    /// Bit 11: softwareStatus.
    pub const SOFTWARE_STATUS: u16 = 1 << 11;
    /// Bit 12: sensorStatus.
    pub const SENSOR_STATUS: u16 = 1 << 12;

    /// masterFail (bit 0): the unit's data must not be used.
    pub const fn master_fail(self) -> bool {
        self.0 & Self::MASTER_FAIL != 0
    }
    /// hardwareError (bit 1). A healthy unit can show it (BIT 0x0002).
    pub const fn hardware_error(self) -> bool {
        self.0 & Self::HARDWARE_ERROR != 0
    }
    /// comError (bit 2).
    pub const fn com_error(self) -> bool {
        self.0 & Self::COM_ERROR != 0
    }
    /// softwareError (bit 3).
    pub const fn software_error(self) -> bool {
        self.0 & Self::SOFTWARE_ERROR != 0
    }
    /// masterStatus (bit 8).
    pub const fn master_status(self) -> bool {
        self.0 & Self::MASTER_STATUS != 0
    }
    /// hardwareStatus (bit 9).
    pub const fn hardware_status(self) -> bool {
        self.0 & Self::HARDWARE_STATUS != 0
    }
    /// comStatus (bit 10).
    pub const fn com_status(self) -> bool {
        self.0 & Self::COM_STATUS != 0
    }
    /// softwareStatus (bit 11).
    pub const fn software_status(self) -> bool {
        self.0 & Self::SOFTWARE_STATUS != 0
    }
    /// sensorStatus (bit 12).
    pub const fn sensor_status(self) -> bool {
        self.0 & Self::SENSOR_STATUS != 0
    }
    /// True when masterFail (the only fatal flag) is set.
    pub const fn is_fatal(self) -> bool {
        self.master_fail()
    }
}

/// One field of a fixed-layout packet, as yielded by the views' `for_each_field` and
/// [`Packet::for_each_field`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Field {
    /// The field's name, as in the view's raw accessor and the `*Fields` struct (e.g. `"roll"`,
    /// `"yaw_true"`, `"time_itow"`, `"bit"`).
    pub name: &'static str,
    /// The wire integer, sign- or zero-extended (e.g. `0x071C` = 1820 for a roll of 10 deg).
    pub raw: i64,
    /// The physical value and its unit, when the field has one: the view's first scaled
    /// accessor (`roll_rad`: 0.1745 `"rad"`), or the raw integer itself for a field whose
    /// LSB is a unit (timeITOW / GPSITOW: `"ms"`). `None` for counters, codes and status
    /// words.
    pub si: Option<Quantity>,
    /// True for bit-field status words (BIT and the T0 words), best shown in hex.
    pub flags: bool,
}

/// A physical value and its unit.
///
/// Units, per quantity: angles `"rad"`, angular rates `"rad/s"`, accelerations `"g"`
/// (standard gravity, 9.80665 m/s^2), magnetic field `"gauss"` (1e-4 T), temperatures
/// `"degC"`, velocities and delta velocities `"m/s"`, altitude `"m"`, time of week `"ms"`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quantity {
    /// The value, in the precision of the view's accessor.
    pub value: SiValue,
    /// The unit of `value` (see [`Quantity`]).
    pub unit: &'static str,
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

/// Table of a fixed-layout packet; each field line is
/// `name: type ["raw unit"]? = offset (as flags)? (=> si_accessor -> type ["unit"] scale
/// (=> other_accessor -> type ["unit"] scale)?)? ;` where the first accessor is the one
/// `for_each_field` reports.
macro_rules! fixed_packet {
    (@quantity $s:ident, $f:ident, [], [$si:ident $unit:literal]) => {
        Some(Quantity { value: SiValue::from($s.$si()), unit: $unit })
    };
    (@quantity $s:ident, $f:ident, [$runit:literal], []) => {
        Some(Quantity { value: SiValue::F64(f64::from($s.$f())), unit: $runit })
    };
    (@quantity $s:ident, $f:ident, [], []) => {
        None
    };
    (@flags) => {
        false
    };
    (@flags flags) => {
        true
    };
    (
        $(#[$vm:meta])*
        $view:ident, $fields:ident, $ptype:ident, $len:literal {
            $(
                $(#[$fm:meta])*
                $f:ident : $t:ty $([$runit:literal])? = $off:literal $(as $kind:ident)?
                $( => $si:ident -> $rt:ty [$unit:literal] $scale:expr
                   $( => $si2:ident -> $rt2:ty [$unit2:literal] $scale2:expr )? )? ;
            )*
        }
    ) => {
        $(#[$vm])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $view<'a> {
            payload: &'a [u8; $len],
        }

        impl<'a> $view<'a> {
            /// Payload length in bytes.
            pub const LEN: usize = $len;
            /// The packet type.
            pub const TYPE: PacketType = PacketType::$ptype;

            /// Wraps a payload; a length other than [`Self::LEN`] is [`DecodeError::Length`].
            pub fn new(payload: &'a [u8]) -> Result<Self, DecodeError> {
                match <&[u8; $len]>::try_from(payload) {
                    Ok(payload) => Ok(Self { payload }),
                    Err(_) => Err(DecodeError::Length {
                        packet_type: PacketType::$ptype,
                        expected: $len,
                        actual: payload.len(),
                    }),
                }
            }

            /// The raw payload bytes.
            pub fn payload(&self) -> &'a [u8] {
                self.payload
            }

            /// Copies every raw field into the fields struct.
            pub fn fields(&self) -> $fields {
                $fields { $($f: self.$f(),)* }
            }

            $(
                $(#[$fm])*
                #[inline]
                pub fn $f(&self) -> $t {
                    <$t as BeField>::read(self.payload, $off)
                }
                $(
                    #[doc = concat!("`", stringify!($f), "` in ", $unit, ".")]
                    #[inline]
                    pub fn $si(&self) -> $rt {
                        self.$f() as $rt * $scale
                    }
                    $(
                        #[doc = concat!("`", stringify!($f), "` in ", $unit2, ".")]
                        #[inline]
                        pub fn $si2(&self) -> $rt2 {
                            self.$f() as $rt2 * $scale2
                        }
                    )?
                )?
            )*

            /// Calls `f` with every field in payload order: its name, its raw wire integer,
            /// its physical value and unit where it has one (see [`Field`] and [`Quantity`]
            /// for the units) and whether it is a status word. No allocation, no panic.
            pub fn for_each_field(&self, mut f: impl FnMut(Field)) {
                $(
                    f(Field {
                        name: stringify!($f),
                        raw: i64::from(self.$f()),
                        si: fixed_packet!(@quantity self, $f, [$($runit)?], [$($si $unit)?]),
                        flags: fixed_packet!(@flags $($kind)?),
                    });
                )*
            }
        }

        #[doc = concat!("Raw fields of a `", stringify!($ptype), "` packet (wire integers; see [`", stringify!($view), "`] for units).")]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $fields {
            $(
                $(#[$fm])*
                pub $f: $t,
            )*
        }

        impl $fields {
            /// The payload bytes (big-endian fields at their offsets).
            pub fn payload(&self) -> [u8; $len] {
                #[allow(unused_mut)]
                let mut p = [0u8; $len];
                $( BeField::write(self.$f, &mut p, $off); )*
                p
            }

            /// Writes the whole frame (preamble, type, length, payload, CRC) into `out`;
            /// returns its length in bytes.
            pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
                encode_frame(PacketType::$ptype, &self.payload(), out)
            }
        }

        impl<'a> From<$view<'a>> for $fields {
            fn from(v: $view<'a>) -> Self {
                v.fields()
            }
        }
    };
}

macro_rules! bit_accessor {
    ($($view:ident),*) => {$(
        impl $view<'_> {
            /// The BIT word as named flags.
            pub fn bit_flags(&self) -> Bit {
                Bit(self.bit())
            }
        }
    )*};
}

fixed_packet! {
    /// S0: scaled sensor data (30-byte payload).
    S0, S0Fields, S0, 30 {
        /// X acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 0 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 2 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// Z acceleration, raw (20/2^16 g per LSB).
        accel_z: i16 = 4 => accel_z_g -> f32 ["g"] scale::ACCEL_G;
        /// X angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X magnetic field, raw (2/2^16 G per LSB).
        mag_x: i16 = 12 => mag_x_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// Y magnetic field, raw (2/2^16 G per LSB).
        mag_y: i16 = 14 => mag_y_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// Z magnetic field, raw (2/2^16 G per LSB).
        mag_z: i16 = 16 => mag_z_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// X rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_x: i16 = 18 => rate_temp_x_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Y rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_y: i16 = 20 => rate_temp_y_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Z rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_z: i16 = 22 => rate_temp_z_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Board temperature, raw (200/2^16 degC per LSB).
        board_temp: i16 = 24 => board_temp_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// GPSITOW: low 16 bits of the GPS time of week, ms (wraps every 65.536 s).
        gps_itow: u16 ["ms"] = 26;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 28 as flags;
    }
}

fixed_packet! {
    /// S1: scaled sensor data with a sample counter (24-byte payload).
    S1, S1Fields, S1, 24 {
        /// X acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 0 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 2 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// Z acceleration, raw (20/2^16 g per LSB).
        accel_z: i16 = 4 => accel_z_g -> f32 ["g"] scale::ACCEL_G;
        /// X angular rate (uncorrected), raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y angular rate (uncorrected), raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z angular rate (uncorrected), raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_x: i16 = 12 => rate_temp_x_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Y rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_y: i16 = 14 => rate_temp_y_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Z rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_z: i16 = 16 => rate_temp_z_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Board temperature, raw (200/2^16 degC per LSB).
        board_temp: i16 = 18 => board_temp_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Sample counter (wraps at 2^16).
        counter: u16 = 20;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 22 as flags;
    }
}

fixed_packet! {
    /// S2: delta velocity and delta angle since the previous packet (28-byte payload).
    S2, S2Fields, S2, 28 {
        /// X delta velocity, raw (200/2^32 m/s per LSB).
        delta_vel_x: i32 = 0 => delta_vel_x_m_s -> f32 ["m/s"] scale::DVEL_M_S;
        /// Y delta velocity, raw (200/2^32 m/s per LSB).
        delta_vel_y: i32 = 4 => delta_vel_y_m_s -> f32 ["m/s"] scale::DVEL_M_S;
        /// Z delta velocity, raw (200/2^32 m/s per LSB).
        delta_vel_z: i32 = 8 => delta_vel_z_m_s -> f32 ["m/s"] scale::DVEL_M_S;
        /// X delta angle, raw (7*pi/2^32 rad per LSB).
        delta_angle_x: i32 = 12 => delta_angle_x_rad -> f32 ["rad"] scale::DANGLE_RAD;
        /// Y delta angle, raw (7*pi/2^32 rad per LSB).
        delta_angle_y: i32 = 16 => delta_angle_y_rad -> f32 ["rad"] scale::DANGLE_RAD;
        /// Z delta angle, raw (7*pi/2^32 rad per LSB).
        delta_angle_z: i32 = 20 => delta_angle_z_rad -> f32 ["rad"] scale::DANGLE_RAD;
        /// Sample counter (wraps at 2^16).
        counter: u16 = 24;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 26 as flags;
    }
}

fixed_packet! {
    /// A0: angles with magnetic yaw, GPSITOW time (30-byte payload).
    A0, A0Fields, A0, 30 {
        /// Roll angle, raw (2*pi/2^16 rad per LSB).
        roll: i16 = 0 => roll_rad -> f32 ["rad"] scale::ANGLE_RAD => roll_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Pitch angle, raw (2*pi/2^16 rad per LSB).
        pitch: i16 = 2 => pitch_rad -> f32 ["rad"] scale::ANGLE_RAD => pitch_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Magnetic yaw, raw (2*pi/2^16 rad per LSB).
        yaw_mag: i16 = 4 => yaw_mag_rad -> f32 ["rad"] scale::ANGLE_RAD => yaw_mag_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// X corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X corrected acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 12 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y corrected acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 14 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// Z corrected acceleration, raw (20/2^16 g per LSB).
        accel_z: i16 = 16 => accel_z_g -> f32 ["g"] scale::ACCEL_G;
        /// X magnetic field, raw (2/2^16 G per LSB).
        mag_x: i16 = 18 => mag_x_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// Y magnetic field, raw (2/2^16 G per LSB).
        mag_y: i16 = 20 => mag_y_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// Z magnetic field, raw (2/2^16 G per LSB).
        mag_z: i16 = 22 => mag_z_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// X rate-sensor temperature, raw (200/2^16 degC per LSB).
        x_rate_temp: i16 = 24 => x_rate_temp_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// GPSITOW: low 16 bits of the GPS time of week, ms (wraps every 65.536 s).
        gps_itow: u16 ["ms"] = 26;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 28 as flags;
    }
}

fixed_packet! {
    /// A1: angles with magnetic yaw, timeITOW time (32-byte payload).
    A1, A1Fields, A1, 32 {
        /// Roll angle, raw (2*pi/2^16 rad per LSB).
        roll: i16 = 0 => roll_rad -> f32 ["rad"] scale::ANGLE_RAD => roll_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Pitch angle, raw (2*pi/2^16 rad per LSB).
        pitch: i16 = 2 => pitch_rad -> f32 ["rad"] scale::ANGLE_RAD => pitch_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Magnetic yaw, raw (2*pi/2^16 rad per LSB).
        yaw_mag: i16 = 4 => yaw_mag_rad -> f32 ["rad"] scale::ANGLE_RAD => yaw_mag_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// X corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 12 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 14 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// Z acceleration, raw (20/2^16 g per LSB).
        accel_z: i16 = 16 => accel_z_g -> f32 ["g"] scale::ACCEL_G;
        /// X magnetic field, raw (2/2^16 G per LSB).
        mag_x: i16 = 18 => mag_x_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// Y magnetic field, raw (2/2^16 G per LSB).
        mag_y: i16 = 20 => mag_y_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// Z magnetic field, raw (2/2^16 G per LSB).
        mag_z: i16 = 22 => mag_z_gauss -> f32 ["gauss"] scale::MAG_GAUSS;
        /// X rate-sensor temperature, raw (200/2^16 degC per LSB).
        x_rate_temp: i16 = 24 => x_rate_temp_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// timeITOW: GPS time of week, ms (wraps at 604 800 000 ms).
        time_itow: u32 ["ms"] = 26;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 30 as flags;
    }
}

fixed_packet! {
    /// A2: angles with free (true) yaw, timeITOW time (30-byte payload).
    A2, A2Fields, A2, 30 {
        /// Roll angle, raw (2*pi/2^16 rad per LSB).
        roll: i16 = 0 => roll_rad -> f32 ["rad"] scale::ANGLE_RAD => roll_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Pitch angle, raw (2*pi/2^16 rad per LSB).
        pitch: i16 = 2 => pitch_rad -> f32 ["rad"] scale::ANGLE_RAD => pitch_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// True (free) yaw, raw (2*pi/2^16 rad per LSB).
        yaw_true: i16 = 4 => yaw_true_rad -> f32 ["rad"] scale::ANGLE_RAD => yaw_true_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// X corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 12 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 14 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// Z acceleration, raw (20/2^16 g per LSB).
        accel_z: i16 = 16 => accel_z_g -> f32 ["g"] scale::ACCEL_G;
        /// X rate-sensor temperature, raw (200/2^16 degC per LSB; the manual's 2/2^16 is a typo).
        rate_temp_x: i16 = 18 => rate_temp_x_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Y rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_y: i16 = 20 => rate_temp_y_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// Z rate-sensor temperature, raw (200/2^16 degC per LSB).
        rate_temp_z: i16 = 22 => rate_temp_z_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// timeITOW: GPS time of week, ms (wraps at 604 800 000 ms).
        time_itow: u32 ["ms"] = 24;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 28 as flags;
    }
}

fixed_packet! {
    /// N0: navigation data, GPSITOW time (32-byte payload).
    N0, N0Fields, N0, 32 {
        /// Roll angle, raw (2*pi/2^16 rad per LSB).
        roll: i16 = 0 => roll_rad -> f32 ["rad"] scale::ANGLE_RAD => roll_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Pitch angle, raw (2*pi/2^16 rad per LSB).
        pitch: i16 = 2 => pitch_rad -> f32 ["rad"] scale::ANGLE_RAD => pitch_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// True yaw, raw (2*pi/2^16 rad per LSB).
        yaw_true: i16 = 4 => yaw_true_rad -> f32 ["rad"] scale::ANGLE_RAD => yaw_true_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// X corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// North velocity, raw (512/2^16 m/s per LSB).
        vel_n: i16 = 12 => vel_n_m_s -> f32 ["m/s"] scale::VEL_M_S;
        /// East velocity, raw (512/2^16 m/s per LSB).
        vel_e: i16 = 14 => vel_e_m_s -> f32 ["m/s"] scale::VEL_M_S;
        /// Down velocity, raw (512/2^16 m/s per LSB).
        vel_d: i16 = 16 => vel_d_m_s -> f32 ["m/s"] scale::VEL_M_S;
        /// Longitude, raw (2*pi/2^32 rad per LSB).
        longitude: i32 = 18 => longitude_rad -> f64 ["rad"] scale::LATLON_RAD => longitude_deg -> f64 ["deg"] scale::LATLON_DEG;
        /// Latitude, raw (2*pi/2^32 rad per LSB).
        latitude: i32 = 22 => latitude_rad -> f64 ["rad"] scale::LATLON_RAD => latitude_deg -> f64 ["deg"] scale::LATLON_DEG;
        /// Altitude, raw (0.25 m per LSB, read as plain i16).
        altitude: i16 = 26 => altitude_m -> f32 ["m"] scale::ALT_M;
        /// GPSITOW: low 16 bits of the GPS time of week, ms (wraps every 65.536 s).
        gps_itow: u16 ["ms"] = 28;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 30 as flags;
    }
}

fixed_packet! {
    /// N1: navigation data, timeITOW time; the NAV440's default packet (42-byte payload).
    N1, N1Fields, N1, 42 {
        /// Roll angle, raw (2*pi/2^16 rad per LSB).
        roll: i16 = 0 => roll_rad -> f32 ["rad"] scale::ANGLE_RAD => roll_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Pitch angle, raw (2*pi/2^16 rad per LSB).
        pitch: i16 = 2 => pitch_rad -> f32 ["rad"] scale::ANGLE_RAD => pitch_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// True yaw, raw (2*pi/2^16 rad per LSB).
        yaw_true: i16 = 4 => yaw_true_rad -> f32 ["rad"] scale::ANGLE_RAD => yaw_true_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// X corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_x: i16 = 6 => rate_x_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_x_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Y corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_y: i16 = 8 => rate_y_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_y_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// Z corrected angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 10 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 12 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 14 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// Z acceleration, raw (20/2^16 g per LSB).
        accel_z: i16 = 16 => accel_z_g -> f32 ["g"] scale::ACCEL_G;
        /// North velocity, raw (512/2^16 m/s per LSB).
        vel_n: i16 = 18 => vel_n_m_s -> f32 ["m/s"] scale::VEL_M_S;
        /// East velocity, raw (512/2^16 m/s per LSB).
        vel_e: i16 = 20 => vel_e_m_s -> f32 ["m/s"] scale::VEL_M_S;
        /// Down velocity, raw (512/2^16 m/s per LSB).
        vel_d: i16 = 22 => vel_d_m_s -> f32 ["m/s"] scale::VEL_M_S;
        /// Longitude, raw (2*pi/2^32 rad per LSB).
        longitude: i32 = 24 => longitude_rad -> f64 ["rad"] scale::LATLON_RAD => longitude_deg -> f64 ["deg"] scale::LATLON_DEG;
        /// Latitude, raw (2*pi/2^32 rad per LSB).
        latitude: i32 = 28 => latitude_rad -> f64 ["rad"] scale::LATLON_RAD => latitude_deg -> f64 ["deg"] scale::LATLON_DEG;
        /// Altitude, raw (0.25 m per LSB, read as plain i16).
        altitude: i16 = 32 => altitude_m -> f32 ["m"] scale::ALT_M;
        /// X rate-sensor temperature, raw (200/2^16 degC per LSB).
        x_rate_temp: i16 = 34 => x_rate_temp_degc -> f32 ["degC"] scale::TEMP_DEGC;
        /// timeITOW: GPS time of week, ms (wraps at 604 800 000 ms).
        time_itow: u32 ["ms"] = 36;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 40 as flags;
    }
}

fixed_packet! {
    /// B1: short angle packet (18-byte payload).
    B1, B1Fields, B1, 18 {
        /// Roll angle, raw (2*pi/2^16 rad per LSB).
        roll: i16 = 0 => roll_rad -> f32 ["rad"] scale::ANGLE_RAD => roll_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Pitch angle, raw (2*pi/2^16 rad per LSB).
        pitch: i16 = 2 => pitch_rad -> f32 ["rad"] scale::ANGLE_RAD => pitch_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Yaw angle, raw (2*pi/2^16 rad per LSB).
        yaw: i16 = 4 => yaw_rad -> f32 ["rad"] scale::ANGLE_RAD => yaw_deg -> f32 ["deg"] scale::ANGLE_DEG;
        /// Z angular rate, raw (7*pi/2^16 rad/s per LSB).
        rate_z: i16 = 6 => rate_z_rad_s -> f32 ["rad/s"] scale::RATE_RAD_S => rate_z_deg_s -> f32 ["deg/s"] scale::RATE_DEG_S;
        /// X acceleration, raw (20/2^16 g per LSB).
        accel_x: i16 = 8 => accel_x_g -> f32 ["g"] scale::ACCEL_G;
        /// Y acceleration, raw (20/2^16 g per LSB).
        accel_y: i16 = 10 => accel_y_g -> f32 ["g"] scale::ACCEL_G;
        /// timeITOW: GPS time of week, ms (wraps at 604 800 000 ms).
        time_itow: u32 ["ms"] = 12;
        /// BIT status word (see [`Bit`]).
        bit: u16 = 16 as flags;
    }
}

fixed_packet! {
    /// T0: built-in-test detail, 14 status words (28-byte payload).
    T0, T0Fields, T0, 28 {
        /// BITstatus (same layout as [`Bit`]).
        bit: u16 = 0 as flags;
        /// hardwareBIT.
        hardware_bit: u16 = 2 as flags;
        /// hardwarePowerBIT.
        hardware_power_bit: u16 = 4 as flags;
        /// hardwareEnvironmentalBIT.
        hardware_environmental_bit: u16 = 6 as flags;
        /// comBIT.
        com_bit: u16 = 8 as flags;
        /// comSerialABIT.
        com_serial_a_bit: u16 = 10 as flags;
        /// comSerialBBIT.
        com_serial_b_bit: u16 = 12 as flags;
        /// softwareBIT.
        software_bit: u16 = 14 as flags;
        /// softwareAlgorithmBIT.
        software_algorithm_bit: u16 = 16 as flags;
        /// softwareDataBIT.
        software_data_bit: u16 = 18 as flags;
        /// hardwareStatus.
        hardware_status: u16 = 20 as flags;
        /// comStatus.
        com_status: u16 = 22 as flags;
        /// softwareStatus.
        software_status: u16 = 24 as flags;
        /// sensorStatus.
        sensor_status: u16 = 26 as flags;
    }
}

fixed_packet! {
    /// VR: firmware version (5-byte payload).
    Vr, VrFields, VR, 5 {
        /// Major version.
        major: u8 = 0;
        /// Minor version.
        minor: u8 = 1;
        /// Patch level.
        patch: u8 = 2;
        /// Stage: 0 release candidate, 1 development, 2 alpha, 3 beta.
        stage: u8 = 3;
        /// Build number.
        build: u8 = 4;
    }
}

fixed_packet! {
    /// NAK (`15 15`): the unit rejected a request (2-byte payload).
    Nak, NakFields, NAK, 2 {
        /// The failed request's type code (big-endian u16, see [`PacketType::code`]).
        failed_code: u16 = 0;
    }
}

impl Nak<'_> {
    /// The type of the request that failed.
    pub fn failed_type(&self) -> PacketType {
        PacketType::from_code(self.failed_code())
    }
}

impl NakFields {
    /// The NAK fields for a failed request of type `t`.
    pub const fn for_request(t: PacketType) -> Self {
        Self {
            failed_code: t.code(),
        }
    }
}

bit_accessor!(S0, S1, S2, A0, A1, A2, N0, N1, B1, T0);

/// ID: serial number and model/version string (payload 4 + N + 1 bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Id<'a> {
    payload: &'a [u8],
}

impl<'a> Id<'a> {
    /// Minimum payload length in bytes (serial number + terminating 0x00).
    pub const MIN_LEN: usize = 5;

    /// Wraps a payload; shorter than [`Self::MIN_LEN`] is [`DecodeError::Length`].
    pub fn new(payload: &'a [u8]) -> Result<Self, DecodeError> {
        if payload.len() < Self::MIN_LEN {
            return Err(DecodeError::Length {
                packet_type: PacketType::ID,
                expected: Self::MIN_LEN,
                actual: payload.len(),
            });
        }
        Ok(Self { payload })
    }

    /// Serial number.
    pub fn serial(&self) -> u32 {
        u32::read(self.payload, 0)
    }

    /// The model/version string bytes, up to (not including) the first 0x00.
    pub fn model(&self) -> &'a [u8] {
        let s = self.payload.get(4..).unwrap_or(&[]);
        let end = s.iter().position(|&b| b == 0).unwrap_or(s.len());
        s.get(..end).unwrap_or(&[])
    }

    /// The model string as `&str`, `None` if it is not UTF-8.
    pub fn model_str(&self) -> Option<&'a str> {
        core::str::from_utf8(self.model()).ok()
    }

    /// The raw payload bytes.
    pub fn payload(&self) -> &'a [u8] {
        self.payload
    }

    /// The fields (borrowing the model string).
    pub fn fields(&self) -> IdFields<'a> {
        IdFields {
            serial: self.serial(),
            model: self.model(),
        }
    }
}

/// Fields of an ID packet.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IdFields<'a> {
    /// Serial number.
    pub serial: u32,
    /// Model/version string without terminator (must not contain 0x00; at most 250 bytes).
    pub model: &'a [u8],
}

impl IdFields<'_> {
    /// Writes the whole ID frame (serial, model, 0x00) into `out`; returns its length in bytes.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
        let len = 4 + self.model.len() + 1;
        crate::encode::encode_with(PacketType::ID, len, out, |p| {
            self.serial.write(p, 0);
            if let Some(d) = p.get_mut(4..4 + self.model.len()) {
                d.copy_from_slice(self.model);
            }
            if let Some(z) = p.last_mut() {
                *z = 0;
            }
        })
    }
}

/// `n` (U1) followed by `n` field IDs (U2): the SF/WF reply and the GF/RF request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldIds<'a> {
    payload: &'a [u8],
}

impl<'a> FieldIds<'a> {
    /// Checks `payload.len() == 1 + 2 n`; `t` names the type in the error.
    pub fn new(t: PacketType, payload: &'a [u8]) -> Result<Self, DecodeError> {
        let expected = payload.first().map_or(1, |&n| 1 + 2 * n as usize);
        if payload.len() != expected {
            return Err(DecodeError::Length {
                packet_type: t,
                expected,
                actual: payload.len(),
            });
        }
        Ok(Self { payload })
    }

    /// Number of IDs.
    pub fn len(&self) -> usize {
        self.payload.len() / 2
    }

    /// True when there are no IDs.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The IDs in order.
    pub fn iter(&self) -> impl Iterator<Item = FieldId> + 'a {
        self.payload
            .get(1..)
            .unwrap_or(&[])
            .chunks_exact(2)
            .map(|c| FieldId(u16::read(c, 0)))
    }

    /// True when `id` is listed.
    pub fn contains(&self, id: FieldId) -> bool {
        self.iter().any(|i| i == id)
    }
}

/// `n` (U1) followed by `n` (field ID U2, value U2) pairs: the GF/RF reply and the SF/WF request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldValues<'a> {
    payload: &'a [u8],
}

impl<'a> FieldValues<'a> {
    /// Checks `payload.len() == 1 + 4 n`; `t` names the type in the error.
    pub fn new(t: PacketType, payload: &'a [u8]) -> Result<Self, DecodeError> {
        let expected = payload.first().map_or(1, |&n| 1 + 4 * n as usize);
        if payload.len() != expected {
            return Err(DecodeError::Length {
                packet_type: t,
                expected,
                actual: payload.len(),
            });
        }
        Ok(Self { payload })
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.payload.len() / 4
    }

    /// True when there are no pairs.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The (ID, value) pairs in order.
    pub fn iter(&self) -> impl Iterator<Item = (FieldId, u16)> + 'a {
        self.payload
            .get(1..)
            .unwrap_or(&[])
            .chunks_exact(4)
            .map(|c| (FieldId(u16::read(c, 0)), u16::read(c, 2)))
    }

    /// The value of field `id`, if listed.
    pub fn get(&self, id: FieldId) -> Option<u16> {
        self.iter().find(|(i, _)| *i == id).map(|(_, v)| v)
    }
}

/// Time stamp carried by a packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TimeStamp {
    /// timeITOW (U4): GPS time of week, ms (wraps at 604 800 000 ms).
    Itow(u32),
    /// GPSITOW (U2): low 16 bits of the time of week, ms (wraps every 65.536 s).
    GpsItow(u16),
    /// The packet carries no time.
    None,
}

/// What the estimator pipeline needs from any packet that carries yaw (A0, A1, A2, N0, N1, B1).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct YawSample {
    /// The packet's time stamp.
    pub time: TimeStamp,
    /// Yaw (A0/A1 magnetic yaw, A2/N0/N1 true yaw, B1 yaw), deg, wrapped to [-180, 180).
    pub yaw_deg: f32,
    /// Body z angular rate (corrected), deg/s.
    pub yaw_rate_deg_s: f32,
}

/// A decoded frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Packet<'a> {
    /// S0 scaled sensor data.
    S0(S0<'a>),
    /// S1 scaled sensor data with counter.
    S1(S1<'a>),
    /// S2 delta velocity / delta angle.
    S2(S2<'a>),
    /// A0 angles, magnetic yaw, GPSITOW.
    A0(A0<'a>),
    /// A1 angles, magnetic yaw, timeITOW.
    A1(A1<'a>),
    /// A2 angles, free yaw, timeITOW.
    A2(A2<'a>),
    /// N0 navigation, GPSITOW.
    N0(N0<'a>),
    /// N1 navigation, timeITOW.
    N1(N1<'a>),
    /// B1 short angles.
    B1(B1<'a>),
    /// T0 BIT detail.
    T0(T0<'a>),
    /// ID serial number and model.
    Id(Id<'a>),
    /// VR firmware version.
    Vr(Vr<'a>),
    /// NAK: a request failed.
    Nak(Nak<'a>),
    /// PK ping reply (empty payload).
    Ping,
    /// CH echo reply: the echoed bytes.
    Echo(&'a [u8]),
    /// GP (a get-packet request seen on the line): the requested type.
    GetPacket(PacketType),
    /// AR algorithm-reset reply (empty payload).
    AlgorithmReset,
    /// SR software-reset reply (empty payload).
    SoftwareReset,
    /// SF reply: the accepted field IDs.
    SetFields(FieldIds<'a>),
    /// WF reply: the accepted field IDs.
    WriteFields(FieldIds<'a>),
    /// GF reply: (ID, value) pairs from RAM.
    GetFields(FieldValues<'a>),
    /// RF reply: (ID, value) pairs from EEPROM.
    ReadFields(FieldValues<'a>),
    /// Any other type (e.g. OpenIMU lower-case packets), passed through raw.
    Unknown(Frame<'a>),
}

fn empty(t: PacketType, p: &[u8]) -> Result<(), DecodeError> {
    if p.is_empty() {
        Ok(())
    } else {
        Err(DecodeError::Length {
            packet_type: t,
            expected: 0,
            actual: p.len(),
        })
    }
}

impl<'a> Packet<'a> {
    /// Decodes a CRC-checked frame (unit -> host direction: SF/WF/GF/RF are replies).
    /// A known type with the wrong payload length is a [`DecodeError`].
    pub fn decode(frame: Frame<'a>) -> Result<Packet<'a>, DecodeError> {
        let p = frame.payload;
        let t = frame.packet_type;
        Ok(match t {
            PacketType::S0 => Packet::S0(S0::new(p)?),
            PacketType::S1 => Packet::S1(S1::new(p)?),
            PacketType::S2 => Packet::S2(S2::new(p)?),
            PacketType::A0 => Packet::A0(A0::new(p)?),
            PacketType::A1 => Packet::A1(A1::new(p)?),
            PacketType::A2 => Packet::A2(A2::new(p)?),
            PacketType::N0 => Packet::N0(N0::new(p)?),
            PacketType::N1 => Packet::N1(N1::new(p)?),
            PacketType::B1 => Packet::B1(B1::new(p)?),
            PacketType::T0 => Packet::T0(T0::new(p)?),
            PacketType::ID => Packet::Id(Id::new(p)?),
            PacketType::VR => Packet::Vr(Vr::new(p)?),
            PacketType::NAK => Packet::Nak(Nak::new(p)?),
            PacketType::PK => {
                empty(t, p)?;
                Packet::Ping
            }
            PacketType::CH => Packet::Echo(p),
            PacketType::GP => match <[u8; 2]>::try_from(p) {
                Ok(b) => Packet::GetPacket(PacketType(b)),
                Err(_) => {
                    return Err(DecodeError::Length {
                        packet_type: t,
                        expected: 2,
                        actual: p.len(),
                    })
                }
            },
            PacketType::AR => {
                empty(t, p)?;
                Packet::AlgorithmReset
            }
            PacketType::SR => {
                empty(t, p)?;
                Packet::SoftwareReset
            }
            PacketType::SF => Packet::SetFields(FieldIds::new(t, p)?),
            PacketType::WF => Packet::WriteFields(FieldIds::new(t, p)?),
            PacketType::GF => Packet::GetFields(FieldValues::new(t, p)?),
            PacketType::RF => Packet::ReadFields(FieldValues::new(t, p)?),
            _ => Packet::Unknown(frame),
        })
    }

    /// The packet's type.
    pub fn packet_type(&self) -> PacketType {
        match self {
            Packet::S0(_) => PacketType::S0,
            Packet::S1(_) => PacketType::S1,
            Packet::S2(_) => PacketType::S2,
            Packet::A0(_) => PacketType::A0,
            Packet::A1(_) => PacketType::A1,
            Packet::A2(_) => PacketType::A2,
            Packet::N0(_) => PacketType::N0,
            Packet::N1(_) => PacketType::N1,
            Packet::B1(_) => PacketType::B1,
            Packet::T0(_) => PacketType::T0,
            Packet::Id(_) => PacketType::ID,
            Packet::Vr(_) => PacketType::VR,
            Packet::Nak(_) => PacketType::NAK,
            Packet::Ping => PacketType::PK,
            Packet::Echo(_) => PacketType::CH,
            Packet::GetPacket(_) => PacketType::GP,
            Packet::AlgorithmReset => PacketType::AR,
            Packet::SoftwareReset => PacketType::SR,
            Packet::SetFields(_) => PacketType::SF,
            Packet::WriteFields(_) => PacketType::WF,
            Packet::GetFields(_) => PacketType::GF,
            Packet::ReadFields(_) => PacketType::RF,
            Packet::Unknown(f) => f.packet_type,
        }
    }

    /// The time stamp of an output packet (`TimeStamp::None` for packets without one).
    pub fn time(&self) -> TimeStamp {
        match self {
            Packet::S0(p) => TimeStamp::GpsItow(p.gps_itow()),
            Packet::A0(p) => TimeStamp::GpsItow(p.gps_itow()),
            Packet::A1(p) => TimeStamp::Itow(p.time_itow()),
            Packet::A2(p) => TimeStamp::Itow(p.time_itow()),
            Packet::N0(p) => TimeStamp::GpsItow(p.gps_itow()),
            Packet::N1(p) => TimeStamp::Itow(p.time_itow()),
            Packet::B1(p) => TimeStamp::Itow(p.time_itow()),
            _ => TimeStamp::None,
        }
    }

    /// The BIT word of an output packet that has one.
    pub fn bit(&self) -> Option<Bit> {
        Some(match self {
            Packet::S0(p) => p.bit_flags(),
            Packet::S1(p) => p.bit_flags(),
            Packet::S2(p) => p.bit_flags(),
            Packet::A0(p) => p.bit_flags(),
            Packet::A1(p) => p.bit_flags(),
            Packet::A2(p) => p.bit_flags(),
            Packet::N0(p) => p.bit_flags(),
            Packet::N1(p) => p.bit_flags(),
            Packet::B1(p) => p.bit_flags(),
            Packet::T0(p) => p.bit_flags(),
            _ => return None,
        })
    }

    /// Calls `f` with every field of a fixed-layout packet (S0, S1, S2, A0, A1, A2, N0, N1,
    /// B1, T0, VR, NAK) in payload order: name, raw wire integer, physical value and unit
    /// (rad, rad/s, g, gauss, degC, m/s, m, ms; see [`Quantity`]) and whether it is a status
    /// word. Packets without a fixed layout (ID, PK, CH, GP, AR, SR, SF, WF, GF, RF and
    /// unknown types) have no such fields: `f` is not called. No allocation, no panic.
    ///
    /// ```
    /// use nav440_proto::{A2Fields, Frame, Packet, PacketType, SiValue};
    ///
    /// let payload = A2Fields { roll: 0x071C, time_itow: 123_456, ..Default::default() }.payload();
    /// let p = Packet::decode(Frame { packet_type: PacketType::A2, payload: &payload }).unwrap();
    /// let mut roll = None;
    /// p.for_each_field(|f| {
    ///     if f.name == "roll" {
    ///         roll = f.si.map(|q| (f.raw, q.value.to_f64(), q.unit));
    ///     }
    /// });
    /// let (raw, rad, unit) = roll.unwrap();
    /// assert_eq!((raw, unit), (0x071C, "rad"));
    /// assert!((rad - 10f64.to_radians()).abs() < 1e-4);
    /// ```
    pub fn for_each_field(&self, f: impl FnMut(Field)) {
        match self {
            Packet::S0(p) => p.for_each_field(f),
            Packet::S1(p) => p.for_each_field(f),
            Packet::S2(p) => p.for_each_field(f),
            Packet::A0(p) => p.for_each_field(f),
            Packet::A1(p) => p.for_each_field(f),
            Packet::A2(p) => p.for_each_field(f),
            Packet::N0(p) => p.for_each_field(f),
            Packet::N1(p) => p.for_each_field(f),
            Packet::B1(p) => p.for_each_field(f),
            Packet::T0(p) => p.for_each_field(f),
            Packet::Vr(p) => p.for_each_field(f),
            Packet::Nak(p) => p.for_each_field(f),
            Packet::Id(_)
            | Packet::Ping
            | Packet::Echo(_)
            | Packet::GetPacket(_)
            | Packet::AlgorithmReset
            | Packet::SoftwareReset
            | Packet::SetFields(_)
            | Packet::WriteFields(_)
            | Packet::GetFields(_)
            | Packet::ReadFields(_)
            | Packet::Unknown(_) => {}
        }
    }

    /// Time, yaw and body z rate of packets that carry yaw (A0, A1, A2, N0, N1, B1).
    pub fn yaw_sample(&self) -> Option<YawSample> {
        let (yaw, rate) = match self {
            Packet::A0(p) => (p.yaw_mag_deg(), p.rate_z_deg_s()),
            Packet::A1(p) => (p.yaw_mag_deg(), p.rate_z_deg_s()),
            Packet::A2(p) => (p.yaw_true_deg(), p.rate_z_deg_s()),
            Packet::N0(p) => (p.yaw_true_deg(), p.rate_z_deg_s()),
            Packet::N1(p) => (p.yaw_true_deg(), p.rate_z_deg_s()),
            Packet::B1(p) => (p.yaw_deg(), p.rate_z_deg_s()),
            _ => return None,
        };
        Some(YawSample {
            time: self.time(),
            yaw_deg: yaw,
            yaw_rate_deg_s: rate,
        })
    }
}

impl PacketType {
    /// Payload length in bytes of a packet type the unit can stream continuously (S0, S1,
    /// S2, A0, A1, A2, N0, N1, B1, T0); `None` for any other type (commands, ID, VR, unknown).
    pub const fn output_payload_len(self) -> Option<usize> {
        let c = self.code();
        let table: [(PacketType, usize); 10] = [
            (PacketType::S0, S0::LEN),
            (PacketType::S1, S1::LEN),
            (PacketType::S2, S2::LEN),
            (PacketType::A0, A0::LEN),
            (PacketType::A1, A1::LEN),
            (PacketType::A2, A2::LEN),
            (PacketType::N0, N0::LEN),
            (PacketType::N1, N1::LEN),
            (PacketType::B1, B1::LEN),
            (PacketType::T0, T0::LEN),
        ];
        let mut i = 0;
        while i < table.len() {
            if table[i].0.code() == c {
                return Some(table[i].1);
            }
            i += 1;
        }
        None
    }
}
