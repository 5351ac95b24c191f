//! The packet table: every fixed-layout packet, declared once.
//!
//! One line per field: `name: kind[si accessors] @ offset => role;` (grammar in
//! `macros.rs`, kinds in [`fields`](super::fields)), or one line per group of fields several
//! packets share: `..group @ offset;` (the groups are `field_group!`'s arms, below). The kind
//! fixes wire type, scale, unit and docs; the role (optional) feeds [`Packet::attitude`],
//! [`Packet::body_rates`], [`Packet::yaw_sample`], [`Packet::time`] and [`Packet::bit`].
//! Offsets are checked at compile time to tile the payload. Adding a packet type is one more entry here (plus its
//! [`PacketType`] constant); see docs/PACKETS.md.

#[allow(unused_imports)] // doc links
use super::fields::Unit;
use super::fields::{tiles, BeField, Field, FieldInfo, Kind, Quantity, Role, SiValue};
use super::roles::{Attitude, BodyRates, Roles, TimeStamp, YawSample};
use super::status::Bit;
use super::variable::{FieldIds, FieldValues, Id};
use super::{empty, scale, DecodeError};
use crate::encode::{encode_frame, EncodeError};
use crate::parser::Frame;
use crate::types::PacketType;

/// The field groups several packets share: `..group @ offset;` in a packet's body stands for
/// the group's fields, the first at `offset` (`$o` below), the others after it.
macro_rules! field_group {
    (roll_pitch @ $o:literal, $($k:tt)*) => { group_fields! { [$($k)*]
        /// Roll angle.
        roll: angle[roll_rad, roll_deg] @ $o => roll;
        /// Pitch angle.
        pitch: angle[pitch_rad, pitch_deg] @ $o + 2 => pitch;
    } };
    (corrected_rates @ $o:literal, $($k:tt)*) => { group_fields! { [$($k)*]
        /// X corrected angular rate.
        rate_x: rate[rate_x_rad_s, rate_x_deg_s] @ $o => p;
        /// Y corrected angular rate.
        rate_y: rate[rate_y_rad_s, rate_y_deg_s] @ $o + 2 => q;
        /// Z corrected angular rate.
        rate_z: rate[rate_z_rad_s, rate_z_deg_s] @ $o + 4 => r;
    } };
    (accel @ $o:literal, $($k:tt)*) => { group_fields! { [$($k)*]
        /// X acceleration.
        accel_x: accel[accel_x_g] @ $o;
        /// Y acceleration.
        accel_y: accel[accel_y_g] @ $o + 2;
        /// Z acceleration.
        accel_z: accel[accel_z_g] @ $o + 4;
    } };
    (mag @ $o:literal, $($k:tt)*) => { group_fields! { [$($k)*]
        /// X magnetic field.
        mag_x: mag[mag_x_gauss] @ $o;
        /// Y magnetic field.
        mag_y: mag[mag_y_gauss] @ $o + 2;
        /// Z magnetic field.
        mag_z: mag[mag_z_gauss] @ $o + 4;
    } };
    (velocity @ $o:literal, $($k:tt)*) => { group_fields! { [$($k)*]
        /// North velocity.
        vel_n: vel[vel_n_m_s] @ $o;
        /// East velocity.
        vel_e: vel[vel_e_m_s] @ $o + 2;
        /// Down velocity.
        vel_d: vel[vel_d_m_s] @ $o + 4;
    } };
}

packet_table! {
    /// S0: scaled sensor data (30-byte payload).
    S0(S0Fields, S0, 30, stream) {
        ..accel @ 0;
        /// X angular rate.
        rate_x: rate[rate_x_rad_s, rate_x_deg_s] @ 6 => p;
        /// Y angular rate.
        rate_y: rate[rate_y_rad_s, rate_y_deg_s] @ 8 => q;
        /// Z angular rate.
        rate_z: rate[rate_z_rad_s, rate_z_deg_s] @ 10 => r;
        ..mag @ 12;
        /// X rate-sensor temperature.
        rate_temp_x: temp[rate_temp_x_degc] @ 18;
        /// Y rate-sensor temperature.
        rate_temp_y: temp[rate_temp_y_degc] @ 20;
        /// Z rate-sensor temperature.
        rate_temp_z: temp[rate_temp_z_degc] @ 22;
        /// Board temperature.
        board_temp: temp[board_temp_degc] @ 24;
        /// GPSITOW: low 16 bits of the GPS time of week.
        gps_itow: gps_itow @ 26 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 28 => bit;
    }

    /// S1: scaled sensor data with a sample counter (24-byte payload).
    S1(S1Fields, S1, 24, stream) {
        ..accel @ 0;
        /// X angular rate (uncorrected).
        rate_x: rate[rate_x_rad_s, rate_x_deg_s] @ 6 => p;
        /// Y angular rate (uncorrected).
        rate_y: rate[rate_y_rad_s, rate_y_deg_s] @ 8 => q;
        /// Z angular rate (uncorrected).
        rate_z: rate[rate_z_rad_s, rate_z_deg_s] @ 10 => r;
        /// X rate-sensor temperature.
        rate_temp_x: temp[rate_temp_x_degc] @ 12;
        /// Y rate-sensor temperature.
        rate_temp_y: temp[rate_temp_y_degc] @ 14;
        /// Z rate-sensor temperature.
        rate_temp_z: temp[rate_temp_z_degc] @ 16;
        /// Board temperature.
        board_temp: temp[board_temp_degc] @ 18;
        /// Sample counter.
        counter: counter @ 20;
        /// BIT status word (see [`Bit`]).
        bit: status @ 22 => bit;
    }

    /// S2: delta velocity and delta angle since the previous packet (28-byte payload).
    S2(S2Fields, S2, 28, stream) {
        /// X delta velocity.
        delta_vel_x: dvel[delta_vel_x_m_s] @ 0;
        /// Y delta velocity.
        delta_vel_y: dvel[delta_vel_y_m_s] @ 4;
        /// Z delta velocity.
        delta_vel_z: dvel[delta_vel_z_m_s] @ 8;
        /// X delta angle.
        delta_angle_x: dangle[delta_angle_x_rad] @ 12;
        /// Y delta angle.
        delta_angle_y: dangle[delta_angle_y_rad] @ 16;
        /// Z delta angle.
        delta_angle_z: dangle[delta_angle_z_rad] @ 20;
        /// Sample counter.
        counter: counter @ 24;
        /// BIT status word (see [`Bit`]).
        bit: status @ 26 => bit;
    }

    /// A0: angles with magnetic yaw, GPSITOW time (30-byte payload).
    A0(A0Fields, A0, 30, stream) {
        ..roll_pitch @ 0;
        /// Magnetic yaw.
        yaw_mag: angle[yaw_mag_rad, yaw_mag_deg] @ 4 => yaw;
        ..corrected_rates @ 6;
        /// X corrected acceleration.
        accel_x: accel[accel_x_g] @ 12;
        /// Y corrected acceleration.
        accel_y: accel[accel_y_g] @ 14;
        /// Z corrected acceleration.
        accel_z: accel[accel_z_g] @ 16;
        ..mag @ 18;
        /// X rate-sensor temperature.
        x_rate_temp: temp[x_rate_temp_degc] @ 24;
        /// GPSITOW: low 16 bits of the GPS time of week.
        gps_itow: gps_itow @ 26 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 28 => bit;
    }

    /// A1: angles with magnetic yaw, timeITOW time (32-byte payload).
    A1(A1Fields, A1, 32, stream) {
        ..roll_pitch @ 0;
        /// Magnetic yaw.
        yaw_mag: angle[yaw_mag_rad, yaw_mag_deg] @ 4 => yaw;
        ..corrected_rates @ 6;
        ..accel @ 12;
        ..mag @ 18;
        /// X rate-sensor temperature.
        x_rate_temp: temp[x_rate_temp_degc] @ 24;
        /// timeITOW: GPS time of week.
        time_itow: itow @ 26 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 30 => bit;
    }

    /// A2: angles with free (true) yaw, timeITOW time (30-byte payload).
    A2(A2Fields, A2, 30, stream) {
        ..roll_pitch @ 0;
        /// True (free) yaw.
        yaw_true: angle[yaw_true_rad, yaw_true_deg] @ 4 => yaw;
        ..corrected_rates @ 6;
        ..accel @ 12;
        /// X rate-sensor temperature (the manual's 2/2^16 scale is a typo for 200/2^16).
        rate_temp_x: temp[rate_temp_x_degc] @ 18;
        /// Y rate-sensor temperature.
        rate_temp_y: temp[rate_temp_y_degc] @ 20;
        /// Z rate-sensor temperature.
        rate_temp_z: temp[rate_temp_z_degc] @ 22;
        /// timeITOW: GPS time of week.
        time_itow: itow @ 24 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 28 => bit;
    }

    /// N0: navigation data, GPSITOW time (32-byte payload).
    N0(N0Fields, N0, 32, stream) {
        ..roll_pitch @ 0;
        /// True yaw.
        yaw_true: angle[yaw_true_rad, yaw_true_deg] @ 4 => yaw;
        ..corrected_rates @ 6;
        ..velocity @ 12;
        /// Longitude.
        longitude: latlon[longitude_rad, longitude_deg] @ 18;
        /// Latitude.
        latitude: latlon[latitude_rad, latitude_deg] @ 22;
        /// Altitude.
        altitude: alt[altitude_m] @ 26;
        /// GPSITOW: low 16 bits of the GPS time of week.
        gps_itow: gps_itow @ 28 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 30 => bit;
    }

    /// N1: navigation data, timeITOW time; the NAV440's default packet (42-byte payload).
    N1(N1Fields, N1, 42, stream) {
        ..roll_pitch @ 0;
        /// True yaw.
        yaw_true: angle[yaw_true_rad, yaw_true_deg] @ 4 => yaw;
        ..corrected_rates @ 6;
        ..accel @ 12;
        ..velocity @ 18;
        /// Longitude.
        longitude: latlon[longitude_rad, longitude_deg] @ 24;
        /// Latitude.
        latitude: latlon[latitude_rad, latitude_deg] @ 28;
        /// Altitude.
        altitude: alt[altitude_m] @ 32;
        /// X rate-sensor temperature.
        x_rate_temp: temp[x_rate_temp_degc] @ 34;
        /// timeITOW: GPS time of week.
        time_itow: itow @ 36 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 40 => bit;
    }

    /// B1: short angle packet (18-byte payload).
    B1(B1Fields, B1, 18, stream) {
        ..roll_pitch @ 0;
        /// Yaw angle.
        yaw: angle[yaw_rad, yaw_deg] @ 4 => yaw;
        /// Z angular rate.
        rate_z: rate[rate_z_rad_s, rate_z_deg_s] @ 6 => r;
        /// X acceleration.
        accel_x: accel[accel_x_g] @ 8;
        /// Y acceleration.
        accel_y: accel[accel_y_g] @ 10;
        /// timeITOW: GPS time of week.
        time_itow: itow @ 12 => time;
        /// BIT status word (see [`Bit`]).
        bit: status @ 16 => bit;
    }

    /// T0: built-in-test detail, 14 status words (28-byte payload).
    T0(T0Fields, T0, 28, stream) {
        /// BITstatus (same layout as [`Bit`]).
        bit: status @ 0 => bit;
        /// hardwareBIT.
        hardware_bit: status @ 2;
        /// hardwarePowerBIT.
        hardware_power_bit: status @ 4;
        /// hardwareEnvironmentalBIT.
        hardware_environmental_bit: status @ 6;
        /// comBIT.
        com_bit: status @ 8;
        /// comSerialABIT.
        com_serial_a_bit: status @ 10;
        /// comSerialBBIT.
        com_serial_b_bit: status @ 12;
        /// softwareBIT.
        software_bit: status @ 14;
        /// softwareAlgorithmBIT.
        software_algorithm_bit: status @ 16;
        /// softwareDataBIT.
        software_data_bit: status @ 18;
        /// hardwareStatus.
        hardware_status: status @ 20;
        /// comStatus.
        com_status: status @ 22;
        /// softwareStatus.
        software_status: status @ 24;
        /// sensorStatus.
        sensor_status: status @ 26;
    }

    /// VR: firmware version (5-byte payload).
    Vr(VrFields, VR, 5, reply) {
        /// Major version.
        major: code8 @ 0;
        /// Minor version.
        minor: code8 @ 1;
        /// Patch level.
        patch: code8 @ 2;
        /// Stage: 0 release candidate, 1 development, 2 alpha, 3 beta.
        stage: code8 @ 3;
        /// Build number.
        build: code8 @ 4;
    }

    /// NAK (`15 15`): the unit rejected a request (2-byte payload).
    Nak(NakFields, NAK, 2, reply) {
        /// The failed request's type code (big-endian u16, see [`PacketType::code`]).
        failed_code: code16 @ 0;
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

/// Number of streamable types in the table.
const N_STREAM: usize = {
    let mut n = 0;
    let mut i = 0;
    while i < FIXED.len() {
        if FIXED[i].2 {
            n += 1;
        }
        i += 1;
    }
    n
};

/// (type, payload length) of the streamable types, in table order (built at compile time).
const STREAM: [(PacketType, usize); N_STREAM] = {
    let mut out = [(PacketType([0, 0]), 0); N_STREAM];
    let (mut i, mut j) = (0, 0);
    while i < FIXED.len() {
        if FIXED[i].2 {
            out[j] = (FIXED[i].0, FIXED[i].1);
            j += 1;
        }
        i += 1;
    }
    out
};

impl PacketType {
    /// Payload length in bytes of a packet type the unit can stream continuously (S0, S1,
    /// S2, A0, A1, A2, N0, N1, B1, T0: the table's `stream` entries); `None` for any other
    /// type (commands, ID, VR, unknown).
    pub const fn output_payload_len(self) -> Option<usize> {
        let c = self.code();
        let mut i = 0;
        while i < STREAM.len() {
            if STREAM[i].0.code() == c {
                return Some(STREAM[i].1);
            }
            i += 1;
        }
        None
    }
}
