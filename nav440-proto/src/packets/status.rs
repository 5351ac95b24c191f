//! The BIT (built-in test) status word.

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

    /// Every named flag: (mask, the protocol document's name), bit 0 first.
    pub const NAMES: [(u16, &'static str); 9] = [
        (Self::MASTER_FAIL, "masterFail"),
        (Self::HARDWARE_ERROR, "hardwareError"),
        (Self::COM_ERROR, "comError"),
        (Self::SOFTWARE_ERROR, "softwareError"),
        (Self::MASTER_STATUS, "masterStatus"),
        (Self::HARDWARE_STATUS, "hardwareStatus"),
        (Self::COM_STATUS, "comStatus"),
        (Self::SOFTWARE_STATUS, "softwareStatus"),
        (Self::SENSOR_STATUS, "sensorStatus"),
    ];

    /// The names of the flags that are set, bit 0 first (reserved bits have no name).
    pub fn names(self) -> impl Iterator<Item = &'static str> {
        Self::NAMES
            .into_iter()
            .filter(move |(mask, _)| self.0 & mask != 0)
            .map(|(_, name)| name)
    }
}

/// `0x0003 (masterFail, hardwareError)`; `0x0000` when no flag is set.
impl core::fmt::Display for Bit {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "0x{:04X}", self.0)?;
        for (i, name) in self.names().enumerate() {
            f.write_str(if i == 0 { " (" } else { ", " })?;
            f.write_str(name)?;
        }
        if self.names().next().is_some() {
            f.write_str(")")?;
        }
        Ok(())
    }
}
