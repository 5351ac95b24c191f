//! Frame encoders: any frame, every command, the unit's replies.

use crate::crc16::{Crc16Table, DefaultCrcTable};
use crate::packets::{DecodeError, FieldIds, FieldValues};
use crate::parser::Frame;
use crate::text::{lit, Text};
use crate::types::{FieldId, PacketType};
use crate::{copy_bytes, FRAME_OVERHEAD, MAX_PAYLOAD, PREAMBLE_BYTE};

/// Why a frame could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The payload would exceed [`MAX_PAYLOAD`] (255) bytes.
    PayloadTooLong {
        /// Payload length that was asked for, bytes.
        len: usize,
    },
    /// The output buffer is shorter than the frame.
    BufferTooSmall {
        /// Frame length in bytes.
        needed: usize,
    },
}

impl EncodeError {
    /// The diagnostic line (see [`Text`]).
    pub(crate) fn text<W: Text + ?Sized>(&self, w: &mut W) -> core::fmt::Result {
        let n = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        match self {
            EncodeError::PayloadTooLong { len } => {
                lit!(w, "payload of ")?;
                w.dec(n(*len))?;
                lit!(w, " bytes exceeds the maximum of ")?;
                w.dec(n(MAX_PAYLOAD))?;
                lit!(w, " bytes")
            }
            EncodeError::BufferTooSmall { needed } => {
                lit!(w, "output buffer too small: the frame needs ")?;
                w.dec(n(*needed))?;
                lit!(w, " bytes")
            }
        }
    }
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.text(f)
    }
}

impl core::error::Error for EncodeError {}

/// Writes a frame of type `t` with a `len`-byte payload filled in by `fill` (which gets exactly
/// `len` bytes, zeroed); returns the frame length in bytes.
pub fn encode_with(
    t: PacketType,
    len: usize,
    out: &mut [u8],
    fill: impl FnOnce(&mut [u8]),
) -> Result<usize, EncodeError> {
    if len > MAX_PAYLOAD {
        return Err(EncodeError::PayloadTooLong { len });
    }
    let total = len + FRAME_OVERHEAD;
    let Some(frame) = out.get_mut(..total) else {
        return Err(EncodeError::BufferTooSmall { needed: total });
    };
    let (head, rest) = frame.split_at_mut(5);
    copy_bytes(
        head,
        &[PREAMBLE_BYTE, PREAMBLE_BYTE, t.0[0], t.0[1], len as u8],
    );
    let (payload, _) = rest.split_at_mut(len);
    payload.fill(0);
    fill(payload);
    let crc = DefaultCrcTable::checksum(frame.get(2..5 + len).unwrap_or(&[]));
    if let Some(c) = frame.get_mut(5 + len..) {
        copy_bytes(c, &crc.to_be_bytes());
    }
    Ok(total)
}

/// Writes a whole frame (preamble `55 55`, type, length, payload, CRC MSB first) into `out`;
/// returns its length in bytes (payload length + 7).
pub fn encode_frame(t: PacketType, payload: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    encode_with(t, payload.len(), out, |p| copy_bytes(p, payload))
}

/// Re-encodes a parsed frame byte for byte.
pub fn encode_raw(frame: Frame<'_>, out: &mut [u8]) -> Result<usize, EncodeError> {
    encode_frame(frame.packet_type, frame.payload, out)
}

/// Command encoders (host -> unit) and reply encoders (unit -> host, for simulators).
///
/// Every function writes one whole frame into `out` and returns its length in bytes.
pub mod command {
    use super::*;

    /// Most (ID, value) pairs one SF/WF request can carry (1 + 4 n <= 255).
    pub const MAX_FIELD_VALUES: usize = 63;
    /// Most IDs one GF/RF request or SF/WF reply can carry (1 + 2 n <= 255).
    pub const MAX_FIELD_IDS: usize = 127;

    /// PK ping: `55 55 50 4B 00 9E F4`. The unit answers with the same bytes.
    pub fn ping(out: &mut [u8]) -> Result<usize, EncodeError> {
        encode_frame(PacketType::PK, &[], out)
    }

    /// CH echo of `data` (at most 255 bytes); the unit answers with the same bytes.
    pub fn echo(data: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
        encode_frame(PacketType::CH, data, out)
    }

    /// GP: ask for one packet of type `t` (payload: the type code U2).
    pub fn get_packet(t: PacketType, out: &mut [u8]) -> Result<usize, EncodeError> {
        encode_frame(PacketType::GP, &t.0, out)
    }

    /// AR algorithm reset.
    pub fn algorithm_reset(out: &mut [u8]) -> Result<usize, EncodeError> {
        encode_frame(PacketType::AR, &[], out)
    }

    /// SR software reset (the unit replies, then resets).
    pub fn software_reset(out: &mut [u8]) -> Result<usize, EncodeError> {
        encode_frame(PacketType::SR, &[], out)
    }

    fn values(
        t: PacketType,
        fields: &[(FieldId, u16)],
        out: &mut [u8],
    ) -> Result<usize, EncodeError> {
        let len = 1 + 4 * fields.len();
        if fields.len() > MAX_FIELD_VALUES {
            return Err(EncodeError::PayloadTooLong { len });
        }
        encode_with(t, len, out, |p| {
            if let Some(n) = p.first_mut() {
                *n = fields.len() as u8;
            }
            for (c, (id, v)) in p
                .get_mut(1..)
                .unwrap_or(&mut [])
                .chunks_exact_mut(4)
                .zip(fields)
            {
                copy_bytes(
                    c,
                    &[(id.0 >> 8) as u8, id.0 as u8, (v >> 8) as u8, *v as u8],
                );
            }
        })
    }

    fn ids(t: PacketType, ids: &[FieldId], out: &mut [u8]) -> Result<usize, EncodeError> {
        let len = 1 + 2 * ids.len();
        if ids.len() > MAX_FIELD_IDS {
            return Err(EncodeError::PayloadTooLong { len });
        }
        encode_with(t, len, out, |p| {
            if let Some(n) = p.first_mut() {
                *n = ids.len() as u8;
            }
            for (c, id) in p
                .get_mut(1..)
                .unwrap_or(&mut [])
                .chunks_exact_mut(2)
                .zip(ids)
            {
                copy_bytes(c, &id.0.to_be_bytes());
            }
        })
    }

    /// SF: set fields in RAM (effective now). At most [`MAX_FIELD_VALUES`] pairs.
    pub fn set_fields(fields: &[(FieldId, u16)], out: &mut [u8]) -> Result<usize, EncodeError> {
        values(PacketType::SF, fields, out)
    }

    /// WF: write fields to EEPROM (effective after a power cycle).
    pub fn write_fields(fields: &[(FieldId, u16)], out: &mut [u8]) -> Result<usize, EncodeError> {
        values(PacketType::WF, fields, out)
    }

    /// GF: get fields from RAM. At most [`MAX_FIELD_IDS`] IDs.
    pub fn get_fields(ids_: &[FieldId], out: &mut [u8]) -> Result<usize, EncodeError> {
        ids(PacketType::GF, ids_, out)
    }

    /// RF: read fields from EEPROM.
    pub fn read_fields(ids_: &[FieldId], out: &mut [u8]) -> Result<usize, EncodeError> {
        ids(PacketType::RF, ids_, out)
    }

    /// Unit side: SF or WF reply (`t`) listing the accepted IDs.
    pub fn fields_accepted_reply(
        t: PacketType,
        accepted: &[FieldId],
        out: &mut [u8],
    ) -> Result<usize, EncodeError> {
        ids(t, accepted, out)
    }

    /// Unit side: GF or RF reply (`t`) with (ID, value) pairs.
    pub fn field_values_reply(
        t: PacketType,
        fields: &[(FieldId, u16)],
        out: &mut [u8],
    ) -> Result<usize, EncodeError> {
        values(t, fields, out)
    }

    /// Unit side: NAK for a failed request of type `failed`.
    pub fn nak(failed: PacketType, out: &mut [u8]) -> Result<usize, EncodeError> {
        encode_frame(PacketType::NAK, &failed.0, out)
    }
}

/// A request as the unit sees it (host -> unit direction), for simulators and mock devices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request<'a> {
    /// PK ping.
    Ping,
    /// CH echo with its bytes.
    Echo(&'a [u8]),
    /// GP for the given type.
    GetPacket(PacketType),
    /// AR algorithm reset.
    AlgorithmReset,
    /// SR software reset.
    SoftwareReset,
    /// SF with (ID, value) pairs.
    SetFields(FieldValues<'a>),
    /// WF with (ID, value) pairs.
    WriteFields(FieldValues<'a>),
    /// GF with IDs.
    GetFields(FieldIds<'a>),
    /// RF with IDs.
    ReadFields(FieldIds<'a>),
    /// Anything else.
    Other(Frame<'a>),
}

impl<'a> Request<'a> {
    /// Decodes a frame sent to the unit. Wrong lengths are [`DecodeError::Length`].
    pub fn decode(frame: Frame<'a>) -> Result<Self, DecodeError> {
        let (t, p) = (frame.packet_type, frame.payload);
        let len_err = |expected| DecodeError::Length {
            packet_type: t,
            expected,
            actual: p.len(),
        };
        Ok(match t {
            PacketType::PK | PacketType::AR | PacketType::SR if !p.is_empty() => {
                return Err(len_err(0))
            }
            PacketType::PK => Request::Ping,
            PacketType::AR => Request::AlgorithmReset,
            PacketType::SR => Request::SoftwareReset,
            PacketType::CH => Request::Echo(p),
            PacketType::GP => match <[u8; 2]>::try_from(p) {
                Ok(b) => Request::GetPacket(PacketType(b)),
                Err(_) => return Err(len_err(2)),
            },
            PacketType::SF => Request::SetFields(FieldValues::new(t, p)?),
            PacketType::WF => Request::WriteFields(FieldValues::new(t, p)?),
            PacketType::GF => Request::GetFields(FieldIds::new(t, p)?),
            PacketType::RF => Request::ReadFields(FieldIds::new(t, p)?),
            _ => Request::Other(frame),
        })
    }
}
