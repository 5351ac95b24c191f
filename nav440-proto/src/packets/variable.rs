//! The variable-length packets: ID, and the field-ID / field-value lists of SF, WF, GF, RF.

use super::fields::BeField;
use super::DecodeError;
use crate::encode::EncodeError;
use crate::types::{FieldId, PacketType};

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

/// Checks that `payload` is a count `n` (U1) followed by `n` items of `width` bytes.
fn counted(t: PacketType, payload: &[u8], width: usize) -> Result<&[u8], DecodeError> {
    let expected = payload.first().map_or(1, |&n| 1 + width * n as usize);
    if payload.len() == expected {
        Ok(payload)
    } else {
        Err(DecodeError::Length {
            packet_type: t,
            expected,
            actual: payload.len(),
        })
    }
}

/// A list payload of `n` (U1) followed by `n` entries of `$width` bytes: the view type
/// `$list` with `new`, `len`, `is_empty` (docs naming the entries `$entries`) and `entries`,
/// the raw entries in order.
macro_rules! counted_list {
    ($(#[$doc:meta])* $list:ident, $width:literal, $entries:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $list<'a> {
            payload: &'a [u8],
        }

        impl<'a> $list<'a> {
            #[doc = concat!(" Checks `payload.len() == 1 + ", $width, " n`; `t` names the type in the error.")]
            pub fn new(t: PacketType, payload: &'a [u8]) -> Result<Self, DecodeError> {
                counted(t, payload, $width).map(|payload| Self { payload })
            }

            #[doc = concat!(" Number of ", $entries, ".")]
            pub fn len(&self) -> usize {
                self.payload.len() / $width
            }

            #[doc = concat!(" True when there are no ", $entries, ".")]
            pub fn is_empty(&self) -> bool {
                self.len() == 0
            }

            /// The entries' bytes in order.
            fn entries(&self) -> core::slice::ChunksExact<'a, u8> {
                self.payload.get(1..).unwrap_or(&[]).chunks_exact($width)
            }
        }
    };
}

counted_list!(
    /// `n` (U1) followed by `n` field IDs (U2): the SF/WF reply and the GF/RF request.
    FieldIds,
    2,
    "IDs"
);

impl<'a> FieldIds<'a> {
    /// The IDs in order.
    pub fn iter(&self) -> impl Iterator<Item = FieldId> + 'a {
        self.entries().map(|c| FieldId(u16::read(c, 0)))
    }

    /// True when `id` is listed.
    pub fn contains(&self, id: FieldId) -> bool {
        self.iter().any(|i| i == id)
    }
}

counted_list!(
    /// `n` (U1) followed by `n` (field ID U2, value U2) pairs: the GF/RF reply and the SF/WF request.
    FieldValues,
    4,
    "pairs"
);

impl<'a> FieldValues<'a> {
    /// The (ID, value) pairs in order.
    pub fn iter(&self) -> impl Iterator<Item = (FieldId, u16)> + 'a {
        self.entries()
            .map(|c| (FieldId(u16::read(c, 0)), u16::read(c, 2)))
    }

    /// The value of field `id`, if listed.
    pub fn get(&self, id: FieldId) -> Option<u16> {
        self.iter().find(|(i, _)| *i == id).map(|(_, v)| v)
    }
}
