//! CRC-16 of the NAV440 frame (poly 0x1021, init 0x1D0F, no reflection, xorout 0).
//!
//! This is the catalogue algorithm CRC-16/SPI-FUJITSU (also called CRC-16/AUG-CCITT),
//! computed by the [`crc`] crate. The manual's "initial value 0xFFFF" is the augmented
//! form of the same register; a plain register starting at 0xFFFF gives wrong results.
//!
//! # Table choice
//! The `crc` crate offers three implementations with different size/speed trade-offs:
//!
//! | type | table | speed |
//! |---|---|---|
//! | [`crc::Table<0>`] (`NoTable`) | none | bit-serial, slowest |
//! | [`crc::Table<1>`] | 256 x u16 = 512 B | one table look-up per byte |
//! | [`crc::Table<16>`] | 16 x 256 x u16 = 8 KiB | 16 bytes per step ("slice-by-16") |
//!
//! [`DefaultCrcTable`] is `Table<16>` on hosted targets (plenty of cache, ~3x faster than
//! `Table<1>` on x86-64) and `Table<1>` on bare-metal targets (`target_os = "none"`, i.e. the
//! Cortex-M builds): 512 bytes of flash instead of 8 KiB, and on an M0/M3/M4 without a data
//! cache the 16-lane loop saves few cycles per byte (every look-up is a flash load either way)
//! while the byte loop costs a few instructions per byte (`cargo xtask bench` reports the
//! parser's instructions per byte, CRC included). The cargo feature `crc-table16` forces
//! `Table<16>` on bare metal too (e.g. a Cortex-M7 with caches), and `crc-no-table` picks
//! `Table<0>` there (a part with little flash: 32 KiB). Any of the three can be picked per
//! parser with [`Parser::with_crc_table`](crate::Parser::with_crc_table).

use crc::{Crc, Table, CRC_16_SPI_FUJITSU};

/// The CRC algorithm of the protocol: CRC-16/SPI-FUJITSU (poly 0x1021, init 0x1D0F).
pub const ALGORITHM: &crc::Algorithm<u16> = &CRC_16_SPI_FUJITSU;

/// A CRC-16/SPI-FUJITSU implementation (one of the `crc` crate's table variants).
///
/// Implemented for [`crc::Table<0>`], [`crc::Table<1>`] and [`crc::Table<16>`].
pub trait Crc16Table {
    /// CRC of `bytes` (the whole message; init 0x1D0F, no final xor).
    fn checksum(bytes: &[u8]) -> u16;

    /// Same value as [`checksum`](Self::checksum); the parser calls this once per candidate
    /// frame. Implementations may trade a small copy for speed on short messages.
    #[inline]
    fn message_crc(msg: &[u8]) -> u16 {
        Self::checksum(msg)
    }
}

/// Register value that becomes 0x1D0F (the algorithm's init) after `k` zero bytes:
/// init * x^(-8k) mod P, by running the zero-input bit step backwards 8k times.
const fn init_before_zeros(k: usize) -> u16 {
    let poly = CRC_16_SPI_FUJITSU.poly;
    let mut reg = CRC_16_SPI_FUJITSU.init;
    let mut i = 0;
    while i < 8 * k {
        // forward: reg' = (reg << 1) ^ (msb ? poly : 0); poly has bit 0 set, so bit 0 of reg'
        // tells the old msb.
        reg = if reg & 1 == 1 {
            ((reg ^ poly) >> 1) | 0x8000
        } else {
            reg >> 1
        };
        i += 1;
    }
    reg
}

/// `INIT_BEFORE_ZEROS[k]`: see [`init_before_zeros`].
const INIT_BEFORE_ZEROS: [u16; 48] = {
    let mut t = [0u16; 48];
    let mut k = 0;
    while k < 48 {
        t[k] = init_before_zeros(k);
        k += 1;
    }
    t
};

#[inline(always)]
fn init_before_zero_bytes(k: usize) -> u16 {
    INIT_BEFORE_ZEROS.get(k).copied().unwrap_or(ALGORITHM.init)
}

static CRC_T0: Crc<u16, Table<0>> = Crc::<u16, Table<0>>::new(&CRC_16_SPI_FUJITSU);
static CRC_T1: Crc<u16, Table<1>> = Crc::<u16, Table<1>>::new(&CRC_16_SPI_FUJITSU);
static CRC_T16: Crc<u16, Table<16>> = Crc::<u16, Table<16>>::new(&CRC_16_SPI_FUJITSU);

impl Crc16Table for Table<0> {
    #[inline]
    fn checksum(bytes: &[u8]) -> u16 {
        CRC_T0.checksum(bytes)
    }
}

impl Crc16Table for Table<1> {
    #[inline]
    fn checksum(bytes: &[u8]) -> u16 {
        CRC_T1.checksum(bytes)
    }
}

impl Crc16Table for Table<16> {
    #[inline]
    fn checksum(bytes: &[u8]) -> u16 {
        CRC_T16.checksum(bytes)
    }

    /// Slice-by-16 handles whole 16-byte blocks fast but the last `len % 16` bytes one at a
    /// time, which dominates for 30-50 byte frames. Leading zero bytes are absorbed by
    /// starting from `INIT_BEFORE_ZEROS[k]` (the register that becomes 0x1D0F after `k` zero
    /// bytes), so the message is checked as `0^k || msg` with the same result:
    /// * messages of up to 48 bytes (all output packets but long ID/CH) are right-aligned in a
    ///   48-byte stack block: always exactly three 16-byte steps;
    /// * longer ones get `k` = the padding to a multiple of 16; only their first block is
    ///   copied (16 bytes on the stack), the rest runs in place in 16-byte steps.
    #[inline]
    fn message_crc(msg: &[u8]) -> u16 {
        // Typical output packets (messages of up to 48 bytes): one fixed 3-block shape, so the
        // loop trip counts do not depend on the packet type (no branch mispredictions).
        if msg.len() <= 48 {
            let k = 48 - msg.len();
            let mut block = [0u8; 48];
            if let Some(dst) = block.get_mut(k..) {
                crate::copy_bytes(dst, msg);
            }
            let mut d = CRC_T16.digest_with_initial(init_before_zero_bytes(k));
            d.update(&block);
            return d.finalize();
        }
        let k = (16 - msg.len() % 16) % 16;
        let (head, rest) = msg.split_at((16 - k).min(msg.len()));
        let mut first = [0u8; 16];
        if let Some(dst) = first.get_mut(k..k + head.len()) {
            crate::copy_bytes(dst, head);
        }
        let mut d = CRC_T16.digest_with_initial(init_before_zero_bytes(k));
        d.update(first.get(..k + head.len()).unwrap_or(&first));
        d.update(rest);
        d.finalize()
    }
}

/// The table variant used by [`Parser::new`](crate::Parser::new) and the encoders
/// (`Table<16>` on hosted targets or with feature `crc-table16`, else `Table<1>`).
#[cfg(any(feature = "crc-table16", not(target_os = "none")))]
pub type DefaultCrcTable = Table<16>;

/// The table variant used by [`Parser::new`](crate::Parser::new) and the encoders
/// (`Table<16>` on hosted targets or with feature `crc-table16`, `Table<0>` with feature
/// `crc-no-table`, else `Table<1>`).
#[cfg(all(
    not(feature = "crc-table16"),
    not(feature = "crc-no-table"),
    target_os = "none"
))]
pub type DefaultCrcTable = Table<1>;

/// The table variant used by [`Parser::new`](crate::Parser::new) and the encoders
/// (`Table<16>` on hosted targets or with feature `crc-table16`, `Table<0>` with feature
/// `crc-no-table`, else `Table<1>`).
#[cfg(all(
    not(feature = "crc-table16"),
    feature = "crc-no-table",
    target_os = "none"
))]
pub type DefaultCrcTable = Table<0>;

/// CRC-16 of a NAV440 message (type + length + payload, i.e. a frame without its preamble and
/// CRC), with the [`DefaultCrcTable`].
///
/// ```
/// assert_eq!(nav440_proto::crc16(b"123456789"), 0xE5CC);
/// ```
#[inline]
pub fn crc16(bytes: &[u8]) -> u16 {
    DefaultCrcTable::checksum(bytes)
}
