//! Packet types, field IDs and the enumerated field values of the protocol.

/// The two type bytes of a frame (offset 2..4), e.g. `*b"A2"`; NAK is `[0x15, 0x15]`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PacketType(pub [u8; 2]);

impl PacketType {
    /// Scaled sensor data, 30-byte payload.
    pub const S0: Self = Self(*b"S0");
    /// Scaled sensor data with a counter, 24-byte payload.
    pub const S1: Self = Self(*b"S1");
    /// Delta velocity / delta angle, 28-byte payload.
    pub const S2: Self = Self(*b"S2");
    /// Angles with magnetic yaw and GPSITOW, 30-byte payload.
    pub const A0: Self = Self(*b"A0");
    /// Angles with magnetic yaw and timeITOW, 32-byte payload.
    pub const A1: Self = Self(*b"A1");
    /// Angles with free (true) yaw and timeITOW, 30-byte payload.
    pub const A2: Self = Self(*b"A2");
    /// Navigation with GPSITOW, 32-byte payload.
    pub const N0: Self = Self(*b"N0");
    /// Navigation with timeITOW (default NAV440 packet), 42-byte payload.
    pub const N1: Self = Self(*b"N1");
    /// Short angle packet, 18-byte payload.
    pub const B1: Self = Self(*b"B1");
    /// Built-in-test status words, 28-byte payload.
    pub const T0: Self = Self(*b"T0");
    /// Serial number and model string.
    pub const ID: Self = Self(*b"ID");
    /// Firmware version, 5-byte payload.
    pub const VR: Self = Self(*b"VR");
    /// Negative acknowledge `15 15`; payload: the failed request's type.
    pub const NAK: Self = Self([0x15, 0x15]);
    /// Ping command / reply.
    pub const PK: Self = Self(*b"PK");
    /// Echo command / reply.
    pub const CH: Self = Self(*b"CH");
    /// Get-packet command.
    pub const GP: Self = Self(*b"GP");
    /// Algorithm reset command / reply.
    pub const AR: Self = Self(*b"AR");
    /// Software reset command / reply.
    pub const SR: Self = Self(*b"SR");
    /// Set fields (RAM) command / reply.
    pub const SF: Self = Self(*b"SF");
    /// Write fields (EEPROM) command / reply.
    pub const WF: Self = Self(*b"WF");
    /// Get fields (RAM) command / reply.
    pub const GF: Self = Self(*b"GF");
    /// Read fields (EEPROM) command / reply.
    pub const RF: Self = Self(*b"RF");

    /// Every type this crate knows, in the order of [`Stats::per_type`](crate::Stats::per_type).
    pub const KNOWN: [Self; 22] = [
        Self::S0,
        Self::S1,
        Self::S2,
        Self::A0,
        Self::A1,
        Self::A2,
        Self::N0,
        Self::N1,
        Self::B1,
        Self::T0,
        Self::ID,
        Self::VR,
        Self::NAK,
        Self::PK,
        Self::CH,
        Self::GP,
        Self::AR,
        Self::SR,
        Self::SF,
        Self::WF,
        Self::GF,
        Self::RF,
    ];

    /// The type as the big-endian u16 used in GP requests and field 0x0003 (`A2` = 0x4132).
    pub const fn code(self) -> u16 {
        u16::from_be_bytes(self.0)
    }

    /// The type from its big-endian u16 code (0x4132 = `A2`).
    pub const fn from_code(code: u16) -> Self {
        Self(code.to_be_bytes())
    }

    /// Printable name: `"A2"`, `"z1"`, `"NAK"`; `"??"` when a byte is not printable ASCII.
    pub fn name(&self) -> &str {
        if *self == Self::NAK {
            return "NAK";
        }
        if self.0.iter().all(|b| b.is_ascii_graphic()) {
            core::str::from_utf8(&self.0).unwrap_or("??")
        } else {
            "??"
        }
    }

    /// Index into [`PacketType::KNOWN`], `None` for other types.
    ///
    /// Branch-free perfect hash of the 22 known codes (checked at compile time), so the
    /// per-frame type count costs a multiply, a table load and one compare.
    #[inline]
    pub fn known_index(self) -> Option<usize> {
        let i = *KNOWN_BY_HASH.get(type_hash(self.code()))? as usize;
        match Self::KNOWN.get(i) {
            Some(k) if *k == self => Some(i),
            _ => None,
        }
    }
}

/// Multiplier of the perfect hash of [`PacketType::KNOWN`] (found by search; any multiplier
/// that makes the 22 codes' top 5 product bits distinct works).
const TYPE_HASH_MUL: u32 = 0xB452_A4CF;

#[inline(always)]
const fn type_hash(code: u16) -> usize {
    ((code as u32).wrapping_mul(TYPE_HASH_MUL) >> 27) as usize
}

/// hash -> index into `KNOWN` (0xFF: no known type). Built and collision-checked at compile time.
const KNOWN_BY_HASH: [u8; 32] = {
    let mut t = [0xFF_u8; 32];
    let mut i = 0;
    while i < PacketType::KNOWN.len() {
        let h = type_hash(PacketType::KNOWN[i].code());
        assert!(t[h] == 0xFF, "perfect hash collision");
        t[h] = i as u8;
        i += 1;
    }
    t
};

impl core::fmt::Display for PacketType {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// A configuration field ID (U2) of SF / WF / GF / RF.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldId(pub u16);

impl FieldId {
    /// 0x0001: packet rate divider (see [`PacketRate`]).
    pub const PACKET_RATE_DIVIDER: Self = Self(0x0001);
    /// 0x0002: baud rate code (see [`Baud`]); takes effect at once.
    pub const BAUD_RATE: Self = Self(0x0002);
    /// 0x0003: continuous packet type (the type's [`PacketType::code`], e.g. 0x4132 for A2).
    pub const PACKET_TYPE: Self = Self(0x0003);
    /// 0x0007: orientation.
    pub const ORIENTATION: Self = Self(0x0007);
}

/// Values of field 0x0001 (packet rate divider): output rate of the continuous packet.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u16)]
pub enum PacketRate {
    /// 0: no continuous output (polled with GP).
    Quiet = 0,
    /// 1: 100 Hz.
    Hz100 = 1,
    /// 2: 50 Hz.
    Hz50 = 2,
    /// 4: 25 Hz.
    Hz25 = 4,
    /// 5: 20 Hz.
    Hz20 = 5,
    /// 10: 10 Hz.
    Hz10 = 10,
    /// 20: 5 Hz.
    Hz5 = 20,
    /// 25: 4 Hz.
    Hz4 = 25,
    /// 50: 2 Hz.
    Hz2 = 50,
}

impl PacketRate {
    /// The divider value written to field 0x0001.
    pub const fn divider(self) -> u16 {
        self as u16
    }

    /// Output rate in Hz (100 / divider; 0 for [`PacketRate::Quiet`]).
    pub const fn hz(self) -> f32 {
        match self {
            Self::Quiet => 0.0,
            other => 100.0 / other as u16 as f32,
        }
    }

    /// The rate for a divider value, `None` if the unit does not define it.
    pub const fn from_divider(d: u16) -> Option<Self> {
        Some(match d {
            0 => Self::Quiet,
            1 => Self::Hz100,
            2 => Self::Hz50,
            4 => Self::Hz25,
            5 => Self::Hz20,
            10 => Self::Hz10,
            20 => Self::Hz5,
            25 => Self::Hz4,
            50 => Self::Hz2,
            _ => return None,
        })
    }
}

/// Values of field 0x0002 (baud rate code).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u16)]
pub enum Baud {
    /// 0: 9600 bit/s.
    B9600 = 0,
    /// 1: 19200 bit/s.
    B19200 = 1,
    /// 2: 38400 bit/s.
    B38400 = 2,
    /// 3: 57600 bit/s.
    B57600 = 3,
}

impl Baud {
    /// The code written to field 0x0002.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The baud for a code of field 0x0002, `None` if the unit does not define it.
    pub const fn from_code(code: u16) -> Option<Self> {
        Some(match code {
            0 => Self::B9600,
            1 => Self::B19200,
            2 => Self::B38400,
            3 => Self::B57600,
            _ => return None,
        })
    }

    /// The baud for a line rate in bit/s, `None` if the unit does not support it.
    pub const fn from_bits_per_second(bps: u32) -> Option<Self> {
        Some(match bps {
            9600 => Self::B9600,
            19200 => Self::B19200,
            38400 => Self::B38400,
            57600 => Self::B57600,
            _ => return None,
        })
    }

    /// Line rate in bit/s.
    pub const fn bits_per_second(self) -> u32 {
        match self {
            Self::B9600 => 9600,
            Self::B19200 => 19200,
            Self::B38400 => 38400,
            Self::B57600 => 57600,
        }
    }
}
