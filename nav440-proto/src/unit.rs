//! The unit's side of the protocol: request parsing, field state in RAM and EEPROM, replies,
//! NAKs. For simulators and mock devices (the host's `nav440 sim`, tests); no I/O, no clock.
//!
//! [`Unit::receive`] takes the bytes the host sent and reports, per request, the frames the
//! unit answers with ([`Response`]). What the unit streams between replies (its continuous
//! output, at the rate and type of [`Unit::ram`]) is up to the caller, which owns the data and
//! the clock.
//!
//! Rules (the protocol document's command table):
//! * PK, CH, AR: the same type back (CH with the same bytes). SR: SR back, then the unit
//!   resets ([`Response::reset`]: RAM reloaded from EEPROM).
//! * GP of a continuous output type: the caller sends one packet of that type
//!   ([`Response::get_packet`]); GP of ID or VR: answered here; any other type: NAK.
//! * SF (RAM, effective at once) and WF (EEPROM): fields 0x0001 (a defined rate divider),
//!   0x0002 (baud code 0-3), 0x0003 (a continuous output type), 0x0007 (orientation, any
//!   value). The reply lists the accepted IDs; a NAK follows when some were rejected (unknown
//!   ID, undefined value), and a NAK alone when none was accepted. A request whose resulting
//!   packet type, rate and baud exceed the byte budget (0.81 x baud/10 bytes/s, see
//!   [`crate::boot::fits_budget`]) is rejected whole with a NAK: nothing changes.
//! * SF of the baud: the reply is sent at the new baud ([`Response::baud_after`]).
//! * GF (RAM) / RF (EEPROM): the values of the known IDs; a NAK too if some were unknown.
//! * Any other request, or a request with a malformed payload: NAK.

use crate::boot::fits_budget;
use crate::encode::{command, Request};
use crate::packets::{IdFields, VrFields};
use crate::parser::Parser;
use crate::types::{Baud, FieldId, PacketRate, PacketType};
use crate::MAX_FRAME;

/// The unit's configuration fields (one copy in RAM, one in EEPROM).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UnitFields {
    /// 0x0001: packet rate divider.
    pub rate_divider: u16,
    /// 0x0002: baud code.
    pub baud: u16,
    /// 0x0003: continuous packet type code.
    pub packet_type: u16,
    /// 0x0007: orientation.
    pub orientation: u16,
}

impl UnitFields {
    /// A realistic power-up configuration: S1 at 20 Hz at 38400 Bd (31 B x 20 = 620 B/s).
    pub const POWER_UP: Self = Self {
        rate_divider: PacketRate::Hz20.divider(),
        baud: Baud::B38400.code(),
        packet_type: PacketType::S1.code(),
        orientation: 0,
    };

    /// The value of field `id`, `None` for an ID the unit does not know.
    pub const fn get(&self, id: FieldId) -> Option<u16> {
        match id.0 {
            0x0001 => Some(self.rate_divider),
            0x0002 => Some(self.baud),
            0x0003 => Some(self.packet_type),
            0x0007 => Some(self.orientation),
            _ => None,
        }
    }

    /// Sets field `id` if it is known and `value` is defined for it; returns whether it did.
    pub fn set(&mut self, id: FieldId, value: u16) -> bool {
        if !valid(id, value) {
            return false;
        }
        match id.0 {
            0x0001 => self.rate_divider = value,
            0x0002 => self.baud = value,
            0x0003 => self.packet_type = value,
            _ => self.orientation = value,
        }
        true
    }

    /// The baud in force (38400 for an undefined code).
    pub const fn baud(&self) -> Baud {
        match Baud::from_code(self.baud) {
            Some(b) => b,
            None => Baud::B38400,
        }
    }

    /// The continuous output: packet type and rate; `None` when quiet or undefined.
    pub const fn stream(&self) -> Option<(PacketType, PacketRate)> {
        let t = PacketType::from_code(self.packet_type);
        match PacketRate::from_divider(self.rate_divider) {
            Some(PacketRate::Quiet) | None => None,
            Some(r) => Some((t, r)),
        }
    }

    /// True when the output fits the byte budget at the baud (a quiet output always does).
    pub const fn fits_budget(&self) -> bool {
        match PacketRate::from_divider(self.rate_divider) {
            Some(PacketRate::Quiet) => true,
            Some(r) => fits_budget(PacketType::from_code(self.packet_type), r, self.baud()),
            None => false,
        }
    }
}

impl Default for UnitFields {
    fn default() -> Self {
        Self::POWER_UP
    }
}

/// True when `value` is defined for field `id`.
const fn valid(id: FieldId, value: u16) -> bool {
    match id.0 {
        0x0001 => PacketRate::from_divider(value).is_some(),
        0x0002 => Baud::from_code(value).is_some(),
        0x0003 => PacketType::from_code(value).output_payload_len().is_some(),
        0x0007 => true,
        _ => false,
    }
}

/// Deliberate misbehaviour, for fault tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quirks {
    /// Ignore every request (no reply, no NAK).
    pub ignore_requests: bool,
    /// NAK every SF/WF that sets the packet type (0x0003) or rate (0x0001).
    pub nak_output_config: bool,
    /// Accept SF of the rate divider (listed in the reply) but keep the old value.
    pub keep_rate: bool,
}

/// The unit's answer to one request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Response<'a> {
    /// The request's type.
    pub request: PacketType,
    /// The frames to send (reply and/or NAK, in order; empty for a GP the caller answers or
    /// an ignored request).
    pub frames: &'a [u8],
    /// SF changed the baud: `frames` go out at this new baud.
    pub baud_after: Option<Baud>,
    /// GP of a continuous output type: the caller sends one packet of this type.
    pub get_packet: Option<PacketType>,
    /// SR: after `frames`, the unit resets (RAM reloaded from EEPROM, see [`Unit::ram`]).
    pub reset: bool,
    /// SF changed the packet type or rate divider (the commanded output starts now).
    pub output_changed: bool,
}

/// Serial number reported in the ID packet.
pub const SERIAL_NUMBER: u32 = 440_0001;
/// Model string reported in the ID packet.
pub const MODEL: &[u8] = b"NAV440 simulated (nav440-proto unit model)";

/// The unit model: parser of the host's requests and the field state.
pub struct Unit {
    ram: UnitFields,
    eeprom: UnitFields,
    quirks: Quirks,
    parser: Parser,
    out: [u8; 2 * MAX_FRAME],
}

impl Unit {
    /// A unit whose EEPROM (and RAM, as after power-up) holds `eeprom`.
    pub const fn new(eeprom: UnitFields, quirks: Quirks) -> Self {
        Self {
            ram: eeprom,
            eeprom,
            quirks,
            parser: Parser::new(),
            out: [0; 2 * MAX_FRAME],
        }
    }

    /// The fields in RAM (in force).
    pub fn ram(&self) -> &UnitFields {
        &self.ram
    }

    /// The fields in EEPROM (in force after a reset).
    pub fn eeprom(&self) -> &UnitFields {
        &self.eeprom
    }

    /// The quirks.
    pub fn quirks(&self) -> Quirks {
        self.quirks
    }

    /// Power cycle or reset: RAM reloaded from EEPROM, partial request dropped.
    pub fn reset(&mut self) {
        self.ram = self.eeprom;
        self.parser = Parser::new();
    }

    /// Takes bytes from the host; calls `on_response` once per complete request, in order.
    pub fn receive(&mut self, bytes: &[u8], mut on_response: impl FnMut(Response<'_>)) {
        let mut rest = bytes;
        while !rest.is_empty() {
            // Stop after each request so that its response is built before the next one.
            let mut req: Option<([u8; 2], [u8; 256], usize)> = None;
            let n = self.parser.feed_until(rest, |f| {
                let mut p = [0u8; 256];
                let len = f.payload.len().min(256);
                if let (Some(d), Some(s)) = (p.get_mut(..len), f.payload.get(..len)) {
                    d.copy_from_slice(s);
                }
                req = Some((f.packet_type.0, p, len));
                core::ops::ControlFlow::Break(())
            });
            rest = rest.get(n..).unwrap_or(&[]);
            let Some((t, p, len)) = req else {
                break;
            };
            let r = self.answer(PacketType(t), p.get(..len).unwrap_or(&[]));
            on_response(r);
        }
    }

    /// Answers one request.
    fn answer(&mut self, t: PacketType, payload: &[u8]) -> Response<'_> {
        let mut r = Out {
            request: t,
            len: 0,
            baud_after: None,
            get_packet: None,
            reset: false,
            output_changed: false,
        };
        if !self.quirks.ignore_requests {
            let frame = crate::parser::Frame {
                packet_type: t,
                payload,
            };
            match Request::decode(frame) {
                Ok(req) => self.handle(req, &mut r),
                Err(_) => r.push(&mut self.out, |o| command::nak(t, o)),
            }
        }
        Response {
            request: r.request,
            frames: self.out.get(..r.len).unwrap_or(&[]),
            baud_after: r.baud_after,
            get_packet: r.get_packet,
            reset: r.reset,
            output_changed: r.output_changed,
        }
    }

    fn handle(&mut self, req: Request<'_>, r: &mut Out) {
        let t = r.request;
        let out = &mut self.out;
        match req {
            Request::Ping => r.push(out, command::ping),
            Request::Echo(d) => r.push(out, |o| command::echo(d, o)),
            Request::AlgorithmReset => r.push(out, command::algorithm_reset),
            Request::SoftwareReset => {
                r.push(out, command::software_reset);
                r.reset = true;
                self.ram = self.eeprom;
            }
            Request::GetPacket(p) if p.output_payload_len().is_some() => r.get_packet = Some(p),
            Request::GetPacket(PacketType::ID) => r.push(out, |o| {
                IdFields {
                    serial: SERIAL_NUMBER,
                    model: MODEL,
                }
                .encode(o)
            }),
            Request::GetPacket(PacketType::VR) => r.push(out, |o| {
                VrFields {
                    major: 1,
                    minor: 0,
                    patch: 0,
                    stage: 0,
                    build: 0,
                }
                .encode(o)
            }),
            Request::SetFields(v) | Request::WriteFields(v) => {
                let ram = t == PacketType::SF;
                let before = if ram { self.ram } else { self.eeprom };
                let mut after = before;
                let mut ids = [FieldId(0); 63];
                let mut n_ok = 0usize;
                let mut rejected = false;
                for (id, value) in v.iter() {
                    let output = id == FieldId::PACKET_TYPE || id == FieldId::PACKET_RATE_DIVIDER;
                    let ok = if self.quirks.nak_output_config && output {
                        false
                    } else if ram && self.quirks.keep_rate && id == FieldId::PACKET_RATE_DIVIDER {
                        valid(id, value)
                    } else {
                        after.set(id, value)
                    };
                    match (ok, ids.get_mut(n_ok)) {
                        (true, Some(slot)) => {
                            *slot = id;
                            n_ok += 1;
                        }
                        _ => rejected = true,
                    }
                }
                if !after.fits_budget() {
                    // Over budget at the baud in force: the whole request is rejected.
                    r.push(out, |o| command::nak(t, o));
                    return;
                }
                let accepted = ids.get(..n_ok).unwrap_or(&[]);
                if !accepted.is_empty() {
                    r.push(out, |o| command::fields_accepted_reply(t, accepted, o));
                }
                if rejected || accepted.is_empty() {
                    r.push(out, |o| command::nak(t, o));
                }
                if ram {
                    if after.baud != before.baud {
                        r.baud_after = Some(after.baud());
                    }
                    r.output_changed = accepted.iter().any(|id| {
                        *id == FieldId::PACKET_TYPE || *id == FieldId::PACKET_RATE_DIVIDER
                    });
                    self.ram = after;
                } else {
                    self.eeprom = after;
                }
            }
            Request::GetFields(ids) | Request::ReadFields(ids) => {
                let src = if t == PacketType::GF {
                    self.ram
                } else {
                    self.eeprom
                };
                let mut pairs = [(FieldId(0), 0u16); 63];
                let mut n = 0usize;
                let mut rejected = false;
                for id in ids.iter() {
                    match (src.get(id), pairs.get_mut(n)) {
                        (Some(v), Some(slot)) => {
                            *slot = (id, v);
                            n += 1;
                        }
                        _ => rejected = true,
                    }
                }
                let pairs = pairs.get(..n).unwrap_or(&[]);
                if !pairs.is_empty() {
                    r.push(out, |o| command::field_values_reply(t, pairs, o));
                }
                if rejected || pairs.is_empty() {
                    r.push(out, |o| command::nak(t, o));
                }
            }
            Request::GetPacket(_) | Request::Other(_) => r.push(out, |o| command::nak(t, o)),
        }
    }
}

/// A response being built in the unit's output buffer.
struct Out {
    request: PacketType,
    len: usize,
    baud_after: Option<Baud>,
    get_packet: Option<PacketType>,
    reset: bool,
    output_changed: bool,
}

impl Out {
    fn push(
        &mut self,
        out: &mut [u8],
        f: impl FnOnce(&mut [u8]) -> Result<usize, crate::EncodeError>,
    ) {
        if let Some(dst) = out.get_mut(self.len..) {
            if let Ok(n) = f(dst) {
                self.len += n;
            }
        }
    }
}
