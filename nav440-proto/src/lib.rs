//! Crossbow NAV440 (440 series) serial protocol: framing, CRC, typed packets, commands and
//! drivers, for microcontrollers and hosts alike.
//!
//! `#![no_std]`, no heap, `#![forbid(unsafe_code)]`, and no panics on any input.
//!
//! * [`Parser`]: streaming frame parser (any chunking, one-byte resynchronisation, counters).
//! * [`Packet`]: zero-copy typed views of every packet with raw and SI accessors, all
//!   generated from one table ([`packets`]: one declaration per packet, one line per field
//!   naming its [`Kind`]; values carry a [`Unit`]).
//! * Reading by meaning, whatever the packet type: [`Packet::attitude`] (roll, pitch, yaw),
//!   [`Packet::body_rates`] (p, q, r), [`Packet::time`], [`Packet::bit`],
//!   [`Packet::yaw_sample`].
//! * `*Fields` structs and [`command`]: encoders for every packet and command.
//! * [`ItowClock`]: continuous time from the wrapping time-of-week stamps.
//! * [`boot`]: the whole boot sequence (find the unit, baud switch, packet type and rate,
//!   read-back), blocking ([`boot::boot`]) or async ([`boot::boot_async`]).
//! * [`unit`](mod@unit): the unit's side (requests, field state, replies, NAKs) for simulators.
//! * [`driver`]: an `embedded-io`, an `embedded-hal-nb` and an async (`embedded-io-async`)
//!   driver that yield packets and configure the unit (SF with reply and NAK handling), with
//!   time-outs in time through `DelayNs`; any other port through [`driver::Port`].
//!
//! Every error type ([`DecodeError`], [`EncodeError`], [`driver::Error`],
//! [`boot::BootError`]) implements `Display` (one line) and `core::error::Error`.
//!
//! All multi-byte fields are big-endian. Frame: `55 55`, two type bytes, payload length N,
//! N payload bytes, CRC-16/SPI-FUJITSU (poly 0x1021, init 0x1D0F) of type+length+payload,
//! MSB first.
//!
//! # Example
//! ```
//! use nav440_proto::{command, A2Fields, ItowClock, Packet, PacketType, Parser};
//!
//! // A synthetic A2 frame: yaw 90 deg (0x4000), z rate 3 deg/s (0x009C), ITOW 123456 ms.
//! let a2 = A2Fields { yaw_true: 0x4000, rate_z: 0x009C, time_itow: 123_456, ..Default::default() };
//! let mut stream = [0u8; 64];
//! let n = a2.encode(&mut stream)?;
//! assert_eq!(n, 37);
//!
//! // Commands are whole frames too (the manual's ping).
//! let mut ping = [0u8; 7];
//! command::ping(&mut ping)?;
//! assert_eq!(ping, [0x55, 0x55, 0x50, 0x4B, 0x00, 0x9E, 0xF4]);
//!
//! // Feed bytes in any chunks; garbage before the frame is skipped.
//! let mut parser = Parser::new();
//! let mut clock = ItowClock::new();
//! let mut yaw = None;
//! parser.feed(&[0x00, 0x55, 0x13], |_| {});
//! for chunk in stream[..n].chunks(5) {
//!     parser.feed(chunk, |frame| {
//!         if let Ok(packet) = Packet::decode(frame) {
//!             if let Some(s) = packet.yaw_sample() {
//!                 yaw = Some((clock.update(s.time), s.yaw_deg, s.yaw_rate_deg_s));
//!             }
//!         }
//!     });
//! }
//! let (t_us, yaw_deg, rate_deg_s) = yaw.unwrap();
//! assert_eq!(t_us, Some(0)); // first sample is time 0
//! assert_eq!(yaw_deg, 90.0);
//! assert!((rate_deg_s - 3.0).abs() < 0.01); // 156 * 1260/65536 = 2.9993 deg/s
//! assert_eq!(parser.stats().count(PacketType::A2), 1);
//! assert_eq!(parser.stats().skipped_bytes, 3);
//! # Ok::<(), nav440_proto::EncodeError>(())
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod boot;
pub mod clock;
pub mod crc16;
pub mod driver;
pub mod encode;
pub mod packets;
pub mod parser;
mod text;
pub mod types;
pub mod unit;

pub use clock::{ItowClock, Released, TimeBase, TimeFaults, Timed};
pub use crc16::{crc16, Crc16Table, DefaultCrcTable};
pub use encode::{command, encode_frame, encode_raw, EncodeError, Request};
pub use packets::{
    scale, A0Fields, A1Fields, A2Fields, Attitude, B1Fields, Bit, BodyRates, DecodeError, Field,
    FieldIds, FieldInfo, FieldValues, Id, IdFields, Kind, N0Fields, N1Fields, Nak, NakFields,
    Packet, Quantity, Role, S0Fields, S1Fields, S2Fields, SiValue, T0Fields, TimeStamp, Unit, Vr,
    VrFields, YawSample, A0, A1, A2, B1, N0, N1, S0, S1, S2, T0,
};
pub use parser::{Frame, Parser, Stats};
pub use types::{Baud, FieldId, PacketRate, PacketType};

/// Largest payload in bytes (the length field is one byte).
pub const MAX_PAYLOAD: usize = 255;
/// Largest frame in bytes: preamble 2 + type 2 + length 1 + payload 255 + CRC 2.
pub const MAX_FRAME: usize = 2 + 2 + 1 + 255 + 2;
/// Frame bytes besides the payload (preamble 2 + type 2 + length 1 + CRC 2).
pub const FRAME_OVERHEAD: usize = 7;
/// The preamble byte (`U`); a frame starts with two of them.
pub const PREAMBLE_BYTE: u8 = 0x55;
/// The preamble.
pub const PREAMBLE: [u8; 2] = [PREAMBLE_BYTE, PREAMBLE_BYTE];

/// The examples of the crate README, compiled and run as doc tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

/// Copies `src` to the start of `dst` (nothing when `dst` is shorter: the crate's copies fit by
/// construction). Unlike `copy_from_slice` on a range, it has no panic path, whose message
/// would link `core`'s number formatting into a firmware.
#[inline]
pub(crate) fn copy_bytes(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}
