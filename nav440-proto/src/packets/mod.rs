//! Typed, zero-copy views of every packet, their raw-field structs and the [`Packet`] enum,
//! all generated from one table.
//!
//! * `table.rs`: the packet table. Each fixed-layout packet is one declaration; each of its
//!   fields one line naming its [`Kind`] (angle, rate, accel, mag, temp, time, status, ...),
//!   its offset, its SI accessors and optionally its [`Role`].
//! * `fields.rs`: the kinds: wire type, [`scale`], [`Unit`] and docs of each, written once.
//! * `macros.rs`: the generator: views, `*Fields` structs, [`Packet`] and every dispatch
//!   ([`Packet::decode`], [`Packet::packet_type`], [`Packet::time`], [`Packet::bit`],
//!   [`Packet::attitude`], [`Packet::body_rates`], [`Packet::yaw_sample`],
//!   [`Packet::for_each_field`], [`PacketType::output_payload_len`]).
//! * `roles.rs`: reading by meaning ([`Attitude`], [`BodyRates`], [`YawSample`],
//!   [`TimeStamp`]); `status.rs`: [`Bit`]; `variable.rs`: the variable-length packets (ID,
//!   field lists).
//!
//! Every view wraps a payload slice whose length was checked once in `new`, so accessors are
//! plain big-endian loads at fixed offsets. Raw accessors return the wire integers; SI
//! accessors (`*_rad`, `*_rad_s`, `*_g`, `*_m_s`, `*_gauss`, `*_degc`, `*_m`) and degree helpers
//! (`*_deg`, `*_deg_s`) return `f32` (`f64` for latitude/longitude). `fields()` copies a view
//! into its `*Fields` struct, whose `encode` writes a whole frame again. Each view's `FIELDS`
//! constant is its line of the table as data ([`FieldInfo`]).
//!
//! The table and how to add a packet type: docs/PACKETS.md.

#[macro_use]
mod fields;
#[macro_use]
mod macros;
mod roles;
mod status;
mod table;
mod variable;

pub use fields::{scale, Field, FieldInfo, Kind, Quantity, Role, SiValue, Unit};
pub use roles::{Attitude, BodyRates, TimeStamp, YawSample};
pub use status::Bit;
pub use table::{
    A0Fields, A1Fields, A2Fields, B1Fields, N0Fields, N1Fields, Nak, NakFields, Packet, S0Fields,
    S1Fields, S2Fields, T0Fields, Vr, VrFields, A0, A1, A2, B1, N0, N1, S0, S1, S2, T0,
};
pub use variable::{FieldIds, FieldValues, Id, IdFields};

use crate::types::PacketType;

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

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::Length {
                packet_type,
                expected,
                actual,
            } => write!(
                f,
                "{packet_type} payload of {actual} bytes, expected {expected}"
            ),
        }
    }
}

impl core::error::Error for DecodeError {}

/// An empty payload, or the length error of type `t`.
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
