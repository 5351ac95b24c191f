//! The BIT (built-in test) status word of the attitude packets: which samples are not
//! estimated.
//!
//! NAV440 BIT word (docs: NAV440-PROTOCOL.md): bit 0 masterFail (the only fatal flag),
//! 1 hardwareError, 2 comError, 3 softwareError, 8..12 status flags. A healthy unit can show
//! 0x0002 (hardwareError alone), so only **masterFail** marks a failure: such a sample is not
//! estimated (it never reaches the clock or the banks), is counted, and the error flags set
//! with it are counted by name.

use nav440_proto::Bit;

/// The flag that marks a failing sample, as named by the protocol.
pub const FAILURE_FLAG: &str = "masterFail";

/// `true` if the BIT word flags a failure (masterFail, bit 0).
pub const fn is_failure(bit: Bit) -> bool {
    bit.is_fatal()
}

/// Samples not estimated because their BIT word flags a failure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitCounts {
    /// Samples with masterFail set (not estimated).
    pub failed: u64,
    /// Of those, with hardwareError (bit 1) set too.
    pub hardware_error: u64,
    /// Of those, with comError (bit 2) set too.
    pub com_error: u64,
    /// Of those, with softwareError (bit 3) set too.
    pub software_error: u64,
    /// The BIT word of the last failing sample (0 if none).
    pub last_word: u16,
}

impl BitCounts {
    /// Counts one sample's BIT word; returns `true` if the sample must be dropped.
    pub fn check(&mut self, bit: Bit) -> bool {
        if !is_failure(bit) {
            return false;
        }
        let add = |c: &mut u64, on: bool| *c = c.saturating_add(u64::from(on));
        add(&mut self.failed, true);
        add(&mut self.hardware_error, bit.hardware_error());
        add(&mut self.com_error, bit.com_error());
        add(&mut self.software_error, bit.software_error());
        self.last_word = bit.0;
        true
    }

    /// Writes the one-line report, e.g. `BIT failure: 12 samples not estimated (masterFail;
    /// with hardwareError 12, comError 0, softwareError 3; last BIT word 0x000b)`. Writes
    /// nothing when no sample failed.
    pub fn write_warning(&self, w: &mut impl core::fmt::Write) -> core::fmt::Result {
        if self.failed == 0 {
            return Ok(());
        }
        write!(
            w,
            "BIT failure: {} samples not estimated ({FAILURE_FLAG}; with hardwareError {}, comError {}, softwareError {}; last BIT word 0x{:04x})",
            self.failed, self.hardware_error, self.com_error, self.software_error, self.last_word
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_master_fail_is_a_failure() {
        let mut c = BitCounts::default();
        // A healthy unit (protocol: 0x0002), and every status flag: not failures.
        assert!(!c.check(Bit(0x0002)));
        assert!(!c.check(Bit(0x1F0E)));
        assert!(c.check(Bit(0x0001)));
        assert!(c.check(Bit(0x000B)));
        assert_eq!(
            c,
            BitCounts {
                failed: 2,
                hardware_error: 1,
                com_error: 0,
                software_error: 1,
                last_word: 0x000B
            }
        );
        let mut s = heapless::String::<200>::new();
        c.write_warning(&mut s).unwrap();
        assert_eq!(
            s.as_str(),
            "BIT failure: 2 samples not estimated (masterFail; with hardwareError 1, comError 0, softwareError 1; last BIT word 0x000b)"
        );
    }
}
