//! The boot sequence: find the unit, switch the link to the target baud, select the continuous
//! packet type and rate, read them back, all through the [`Driver`].
//!
//! [`boot`] is the whole sequence as one call, so firmware and host tools contain no protocol
//! code. The target configuration is a [`Target`] whose byte budget can be checked at compile
//! time:
//!
//! ```
//! use nav440_proto::boot::Target;
//! use nav440_proto::{Baud, PacketRate, PacketType};
//!
//! const TARGET: Target = Target::DEFAULT; // A2 at 100 Hz at 57600 Bd
//! const _: () = assert!(TARGET.fits_budget());
//! // N1 at 100 Hz does not fit 57600 Bd (49 B x 100 = 4900 B/s > 4665 B/s).
//! const N1: Target = Target { packet: PacketType::N1, ..Target::DEFAULT };
//! const _: () = assert!(!N1.fits_budget());
//! assert_eq!(TARGET.bytes_per_second(), Some(3700));
//! assert_eq!(nav440_proto::boot::budget_bytes_per_second(Baud::B38400), 3110);
//! ```
//!
//! # The sequence
//! 1. **Find the unit**: at each candidate baud (the one given in [`Options::start_baud`], or
//!    57600, 38400, 19200, 9600 in that order), switch the local port, then ping (PK) up to
//!    [`Options::ping_attempts`] times, each waiting the driver's reply time-out.
//! 2. **Read its configuration**: GF of fields 0x0001 (rate divider), 0x0002 (baud), 0x0003
//!    (packet type). The baud it reports is the truth: under emulation a UART ignores its baud
//!    setting, so a ping answers at any local baud; if the reported baud differs from the one
//!    that answered, the local port is switched to the reported one.
//! 3. **Switch the baud** if it differs from the target: SF of field 0x0002, then the local
//!    port switches (the unit answers at the new baud), then a ping confirms the link. When
//!    the target baud is lower, the packet type and rate are set first, so that the unit's
//!    byte budget is never exceeded in between.
//! 4. **Set the packet type and rate** in one SF (fields 0x0003, 0x0001); with
//!    [`Target::persist`] also WF of the three fields (EEPROM, effective after a power cycle).
//! 5. **Read back** with GF (0x0001, 0x0002, 0x0003) and compare with the target.
//!
//! Replies are found among the frames the unit streams meanwhile (it may stream its power-up
//! configuration all along); those frames are counted ([`Report::unsolicited_frames`]), never
//! yielded. After `Ok`, the next byte the port delivers is the first byte after the read-back
//! reply, preceded by [`Driver::pending_bytes`] (empty unless a corrupted candidate frame
//! spanned the reply): feed those first, then the port, and every frame that follows the
//! confirmed configuration is seen exactly once.

use core::fmt;

use embedded_hal::delay::DelayNs;

use crate::driver::{
    block_on, AsyncDriver, AsyncLink, BlockingLink, Driver, Engine, Error, Link, Port,
};
use crate::encode::EncodeError;
#[cfg(feature = "defmt")]
use crate::text::Defmt;
use crate::text::{lit, Text};
use crate::types::{Baud, FieldId, PacketRate, PacketType};
use crate::FRAME_OVERHEAD;

/// The bauds tried, in order, when the unit's baud is unknown.
pub const SEARCH_ORDER: [Baud; 4] = [Baud::B57600, Baud::B38400, Baud::B19200, Baud::B9600];

/// The fields read by the GF requests of the sequence, in request order (the protocol
/// document's "GF 1,2,3" vector).
pub const READ_FIELDS: [FieldId; 3] = [
    FieldId::PACKET_RATE_DIVIDER,
    FieldId::BAUD_RATE,
    FieldId::PACKET_TYPE,
];

/// The unit's output budget at `baud`, bytes/s: 0.81 x baud / 10, rounded down (3110 B/s at
/// 38400 Bd, 4665 B/s at 57600 Bd). The unit NAKs a type/rate/baud combination above it.
pub const fn budget_bytes_per_second(baud: Baud) -> u32 {
    baud.bits_per_second() * 81 / 1000
}

/// Bytes/s of streaming `packet` at `rate`: (payload + 7) x 100 / divider; 0 for
/// [`PacketRate::Quiet`]; `None` when `packet` is not a continuous output type.
pub const fn stream_bytes_per_second(packet: PacketType, rate: PacketRate) -> Option<u32> {
    let Some(payload) = packet.output_payload_len() else {
        return None;
    };
    let frame = (payload + FRAME_OVERHEAD) as u32;
    Some(match rate {
        PacketRate::Quiet => 0,
        r => frame * 100 / r.divider() as u32,
    })
}

/// True when streaming `packet` at `rate` fits the unit's budget at `baud`
/// ([`budget_bytes_per_second`]); false for a type that cannot be streamed.
pub const fn fits_budget(packet: PacketType, rate: PacketRate, baud: Baud) -> bool {
    match stream_bytes_per_second(packet, rate) {
        Some(b) => b <= budget_bytes_per_second(baud),
        None => false,
    }
}

/// The configuration the boot sequence establishes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Target {
    /// Continuous packet type (field 0x0003).
    pub packet: PacketType,
    /// Output rate (field 0x0001).
    pub rate: PacketRate,
    /// Link baud (field 0x0002).
    pub baud: Baud,
    /// Also write the three fields to EEPROM with WF (the unit powers up configured).
    pub persist: bool,
}

impl Target {
    /// A2 at 100 Hz at 57600 Bd, RAM only: 37 B x 100 = 3700 B/s of a 4665 B/s budget.
    pub const DEFAULT: Self = Self {
        packet: PacketType::A2,
        rate: PacketRate::Hz100,
        baud: Baud::B57600,
        persist: false,
    };

    /// Bytes/s of the target stream (see [`stream_bytes_per_second`]).
    pub const fn bytes_per_second(&self) -> Option<u32> {
        stream_bytes_per_second(self.packet, self.rate)
    }

    /// True when the target stream fits the unit's budget at the target baud; usable in a
    /// const assertion: `const _: () = assert!(TARGET.fits_budget());`.
    pub const fn fits_budget(&self) -> bool {
        fits_budget(self.packet, self.rate, self.baud)
    }

    /// The SF fields selecting the packet type and rate.
    pub const fn output_fields(&self) -> [(FieldId, u16); 2] {
        [
            (FieldId::PACKET_TYPE, self.packet.code()),
            (FieldId::PACKET_RATE_DIVIDER, self.rate.divider()),
        ]
    }

    /// The fields written by WF when [`Self::persist`] is set.
    pub const fn persist_fields(&self) -> [(FieldId, u16); 3] {
        [
            (FieldId::PACKET_TYPE, self.packet.code()),
            (FieldId::PACKET_RATE_DIVIDER, self.rate.divider()),
            (FieldId::BAUD_RATE, self.baud.code()),
        ]
    }

    /// The value the target expects for `id` in the read-back.
    const fn expected(&self, id: FieldId) -> u16 {
        match id.0 {
            0x0001 => self.rate.divider(),
            0x0002 => self.baud.code(),
            _ => self.packet.code(),
        }
    }
}

impl Default for Target {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// How the unit is searched for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Options {
    /// The unit's baud if known (only that one is tried); `None`: try [`SEARCH_ORDER`].
    pub start_baud: Option<Baud>,
    /// Pings per baud before giving up on it (at least 1).
    pub ping_attempts: u8,
}

impl Options {
    /// Search every baud, 3 pings each.
    pub const DEFAULT: Self = Self {
        start_baud: None,
        ping_attempts: 3,
    };
}

impl Default for Options {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What [`boot`] found and did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Report {
    /// The local baud at which the unit first answered a ping.
    pub found_at: Baud,
    /// The baud the unit reported (GF of 0x0002) before any change.
    pub unit_baud: Baud,
    /// The continuous packet type the unit reported before any change.
    pub initial_packet: PacketType,
    /// The rate divider the unit reported before any change.
    pub initial_rate_divider: u16,
    /// True when the link baud was changed with SF.
    pub switched: bool,
    /// The link baud at the end (the target's).
    pub baud: Baud,
    /// Pings that got no answer before the unit was found or the baud switch confirmed.
    pub ping_retries: u32,
    /// Frames received while configuring that were not the awaited reply (the unit's
    /// streaming output, stray replies): counted, not yielded.
    pub unsolicited_frames: u32,
    /// Bytes the parser skipped while configuring (noise, frames cut by a baud change).
    pub skipped_bytes: u64,
}

/// A set of bauds (those tried), displayed like `57600, 38400 Bd`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Bauds(u8);

impl Bauds {
    /// The set holding `b` alone.
    pub const fn one(b: Baud) -> Self {
        Self(1 << b.code())
    }

    /// Adds `b`.
    pub fn insert(&mut self, b: Baud) {
        self.0 |= 1 << b.code();
    }

    /// True when `b` is in the set.
    pub const fn contains(&self, b: Baud) -> bool {
        self.0 & (1 << b.code()) != 0
    }
}

impl Bauds {
    /// `57600, 38400 Bd`: the bauds in search order.
    fn text<W: Text + ?Sized>(&self, w: &mut W) -> fmt::Result {
        let mut first = true;
        for b in SEARCH_ORDER.iter().filter(|b| self.contains(**b)) {
            if !first {
                lit!(w, ", ")?;
            }
            w.dec(b.bits_per_second())?;
            first = false;
        }
        lit!(w, " Bd")
    }
}

impl fmt::Display for Bauds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.text(f)
    }
}

/// Up to three (field, value) pairs of a rejected request, displayed with names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FieldList {
    pairs: [(u16, u16); 3],
    len: u8,
    ids_only: bool,
}

impl FieldList {
    /// The first three pairs of `fields` (a SF/WF request).
    pub fn new(fields: &[(FieldId, u16)]) -> Self {
        let mut l = Self::default();
        for (slot, (id, v)) in l.pairs.iter_mut().zip(fields) {
            *slot = (id.0, *v);
            l.len += 1;
        }
        l
    }

    /// The first three IDs of `ids` (a GF/RF request: no values).
    pub fn ids(ids: &[FieldId]) -> Self {
        let mut l = Self {
            ids_only: true,
            ..Self::default()
        };
        for (slot, id) in l.pairs.iter_mut().zip(ids) {
            *slot = (id.0, 0);
            l.len += 1;
        }
        l
    }

    /// True when the request carried no field (PK).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// True for the IDs of a GF/RF request (the values are not meaningful).
    pub fn ids_only(&self) -> bool {
        self.ids_only
    }

    /// The pairs.
    pub fn iter(&self) -> impl Iterator<Item = (FieldId, u16)> + '_ {
        self.pairs
            .iter()
            .take(self.len as usize)
            .map(|&(id, v)| (FieldId(id), v))
    }
}

/// Writes `value` of field `id` with its meaning, e.g. `packet type 0x0003=0x4132 (A2)`.
fn write_field<W: Text + ?Sized>(w: &mut W, id: FieldId, value: Option<u16>) -> fmt::Result {
    match id.0 {
        0x0001 => lit!(w, "rate divider"),
        0x0002 => lit!(w, "baud"),
        0x0003 => lit!(w, "packet type"),
        0x0007 => lit!(w, "orientation"),
        _ => lit!(w, "field"),
    }?;
    lit!(w, " 0x")?;
    w.hex4(id.0)?;
    lit!(w, "=")?;
    let Some(v) = value else {
        return lit!(w, "(missing)");
    };
    match id.0 {
        0x0001 => {
            w.dec(v.into())?;
            match PacketRate::from_divider(v) {
                Some(PacketRate::Quiet) => lit!(w, " (quiet)"),
                Some(r) => {
                    lit!(w, " (")?;
                    w.dec((100 / r.divider()).into())?;
                    lit!(w, " Hz)")
                }
                None => lit!(w, " (undefined)"),
            }
        }
        0x0002 => {
            w.dec(v.into())?;
            match Baud::from_code(v) {
                Some(b) => {
                    lit!(w, " (")?;
                    w.dec(b.bits_per_second())?;
                    lit!(w, " Bd)")
                }
                None => lit!(w, " (undefined)"),
            }
        }
        0x0003 => {
            lit!(w, "0x")?;
            w.hex4(v)?;
            lit!(w, " (")?;
            w.str(PacketType::from_code(v).name())?;
            lit!(w, ")")
        }
        _ => w.dec(v.into()),
    }
}

impl FieldList {
    /// The fields with their meanings (see [`write_field`]), or `fields 0x0001, 0x0002` for IDs.
    fn text<W: Text + ?Sized>(&self, w: &mut W) -> fmt::Result {
        if self.ids_only {
            lit!(w, "fields")?;
        }
        for (i, (id, v)) in self.iter().enumerate() {
            if i > 0 {
                lit!(w, ", ")?;
            } else if self.ids_only {
                lit!(w, " ")?;
            }
            if self.ids_only {
                lit!(w, "0x")?;
                w.hex4(id.0)?;
            } else {
                write_field(w, id, Some(v))?;
            }
        }
        Ok(())
    }
}

impl fmt::Display for FieldList {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.text(f)
    }
}

/// Why the boot sequence failed. `Display` and `defmt::Format` give the same diagnostic line
/// (no newline).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BootError<E> {
    /// The unit did not answer `request` at any baud tried.
    NoAnswer {
        /// The request left unanswered (PK while searching or confirming a baud switch, GF).
        request: PacketType,
        /// The bauds tried.
        tried: Bauds,
        /// Attempts per baud.
        attempts: u8,
        /// Reply time-out of each attempt, ms.
        timeout_ms: u32,
    },
    /// The unit NAKed a request.
    Nak {
        /// The rejected request's type (SF, WF, GF).
        request: PacketType,
        /// The fields it carried (SF/WF: with values; GF: IDs only, see [`FieldList::ids_only`]).
        fields: FieldList,
    },
    /// The unit's SF/WF reply listed only some fields, and no NAK came.
    NotAccepted {
        /// The request's type.
        request: PacketType,
        /// The fields it carried.
        fields: FieldList,
        /// How many of them the reply listed.
        accepted: u8,
    },
    /// The read-back (GF) does not show the target.
    WrongReadBack {
        /// The field that differs.
        field: FieldId,
        /// The value the target sets.
        expected: u16,
        /// The value read (`None`: missing from the reply).
        got: Option<u16>,
    },
    /// The unit's configuration (the first GF) holds a value the protocol does not define
    /// for that field (a baud code or a rate divider outside the protocol's table).
    UndefinedValue {
        /// The field.
        field: FieldId,
        /// The value read.
        value: u16,
    },
    /// The serial port failed.
    Serial(E),
    /// The serial port accepted no byte.
    WriteZero,
    /// A request could not be encoded (not reachable with the fixed requests of the sequence).
    Encode(EncodeError),
}

impl<E> BootError<E> {
    /// The diagnostic line, but for the serial port's error `E`, which `serial` writes.
    fn text<W: Text + ?Sized>(
        &self,
        w: &mut W,
        serial: impl FnOnce(&mut W, &E) -> fmt::Result,
    ) -> fmt::Result {
        match self {
            BootError::NoAnswer {
                request,
                tried,
                attempts,
                timeout_ms,
            } => {
                lit!(w, "no answer from the unit: ")?;
                w.str(request.name())?;
                lit!(w, " unanswered at ")?;
                tried.text(w)?;
                lit!(w, " (")?;
                w.dec((*attempts).into())?;
                lit!(w, " x ")?;
                w.dec(*timeout_ms)?;
                lit!(w, " ms each)")
            }
            BootError::Nak { request, fields } => {
                lit!(w, "unit rejected (NAK) ")?;
                w.str(request.name())?;
                if fields.is_empty() {
                    if *request == PacketType::PK {
                        lit!(w, " (ping)")
                    } else {
                        lit!(w, " (request without fields)")
                    }
                } else {
                    lit!(w, ": ")?;
                    fields.text(w)
                }
            }
            BootError::NotAccepted {
                request,
                fields,
                accepted,
            } => {
                lit!(w, "unit accepted only ")?;
                w.dec((*accepted).into())?;
                lit!(w, " of the fields of ")?;
                w.str(request.name())?;
                lit!(w, ": ")?;
                fields.text(w)
            }
            BootError::WrongReadBack {
                field,
                expected,
                got,
            } => {
                lit!(w, "wrong read-back (GF): expected ")?;
                write_field(w, *field, Some(*expected))?;
                lit!(w, ", got ")?;
                write_field(w, *field, *got)
            }
            BootError::UndefinedValue { field, value } => {
                lit!(
                    w,
                    "the unit's configuration (GF) holds an undefined value: "
                )?;
                write_field(w, *field, Some(*value))
            }
            BootError::Serial(e) => {
                lit!(w, "serial port error: ")?;
                serial(w, e)
            }
            BootError::WriteZero => lit!(w, "serial port error: it accepted no byte"),
            BootError::Encode(e) => {
                lit!(w, "request could not be encoded: ")?;
                e.text(w)
            }
        }
    }
}

impl<E: fmt::Debug> fmt::Display for BootError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.text(f, |f, e| write!(f, "{e:?}"))
    }
}

/// The same line as `Display` (the serial port's error as its `defmt::Format`), so a firmware
/// prints it without `core::fmt`.
#[cfg(feature = "defmt")]
impl<E: defmt::Format> defmt::Format for BootError<E> {
    fn format(&self, f: defmt::Formatter<'_>) {
        let _ = self.text(&mut Defmt(f), |w, e| {
            defmt::write!(w.0, "{:?}", e);
            Ok(())
        });
    }
}

impl<E: fmt::Debug> core::error::Error for BootError<E> {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            BootError::Encode(e) => Some(e),
            _ => None,
        }
    }
}

/// Converts a driver error of `request` (with `fields`) at `baud`.
fn convert<E>(
    e: Error<E>,
    request: PacketType,
    fields: FieldList,
    baud: Baud,
    timeout_ms: u32,
) -> BootError<E> {
    match e {
        Error::Serial(e) => BootError::Serial(e),
        Error::WriteZero => BootError::WriteZero,
        Error::Encode(e) => BootError::Encode(e),
        Error::Nak { request } => BootError::Nak { request, fields },
        Error::NotAccepted { accepted, .. } => BootError::NotAccepted {
            request,
            fields,
            accepted,
        },
        Error::NoReply => BootError::NoAnswer {
            request,
            tried: Bauds::one(baud),
            attempts: 1,
            timeout_ms,
        },
    }
}

/// The sequence's state between steps.
struct Session<'d, L, F> {
    driver: &'d mut Engine,
    link: L,
    set_baud: F,
    attempts: u8,
    retries: u32,
    baud: Baud,
}

impl<L, F> Session<'_, L, F>
where
    L: Link,
    F: FnMut(&mut L::Serial, Baud) -> Result<(), L::Error>,
{
    fn timeout_ms(&self) -> u32 {
        self.driver.timing.reply_timeout_ms
    }

    /// Switches the local port only.
    fn local_baud(&mut self, b: Baud) -> Result<(), BootError<L::Error>> {
        (self.set_baud)(self.link.serial_mut(), b).map_err(BootError::Serial)?;
        self.driver.line_baud = b.bits_per_second().max(1);
        self.driver.parser.clear();
        self.baud = b;
        Ok(())
    }

    /// Pings up to `attempts` times at the current baud; `Ok(true)` on an answer.
    async fn ping(&mut self) -> Result<bool, BootError<L::Error>> {
        for _ in 0..self.attempts.max(1) {
            match self.driver.ping_wait(&mut self.link).await {
                Ok(()) => return Ok(true),
                Err(Error::NoReply) => self.retries = self.retries.saturating_add(1),
                Err(e) => {
                    let none = FieldList::default();
                    return Err(convert(e, PacketType::PK, none, self.baud, 0));
                }
            }
        }
        Ok(false)
    }

    /// GF of [`READ_FIELDS`]: (rate divider, baud code, packet type), each `None` if missing.
    async fn read(&mut self) -> Result<[Option<u16>; 3], BootError<L::Error>> {
        let timeout = self.timeout_ms();
        let v = self
            .driver
            .get_fields(&mut self.link, PacketType::GF, &READ_FIELDS)
            .await
            .map_err(|e| {
                let ids = FieldList::ids(&READ_FIELDS);
                convert(e, PacketType::GF, ids, self.baud, timeout)
            })?;
        Ok([v[0], v[1], v[2]])
    }

    async fn set_output(&mut self, target: &Target) -> Result<(), BootError<L::Error>> {
        let fields = target.output_fields();
        let timeout = self.timeout_ms();
        let r = self
            .driver
            .configure(&mut self.link, PacketType::SF, &fields)
            .await;
        r.map_err(|e| {
            convert(
                e,
                PacketType::SF,
                FieldList::new(&fields),
                self.baud,
                timeout,
            )
        })
    }

    /// SF of the baud, local switch, ping to confirm.
    async fn switch(&mut self, to: Baud) -> Result<(), BootError<L::Error>> {
        let fields = [(FieldId::BAUD_RATE, to.code())];
        let timeout = self.timeout_ms();
        let set_baud = &mut self.set_baud;
        let r = self
            .driver
            .set_baud(&mut self.link, to, |s, b| set_baud(s, b))
            .await;
        self.baud = to;
        match r {
            // The reply may be lost while both ends change rate: the ping decides.
            Ok(()) | Err(Error::NoReply) => {}
            Err(e) => {
                let list = FieldList::new(&fields);
                return Err(convert(e, PacketType::SF, list, to, timeout));
            }
        }
        if self.ping().await? {
            Ok(())
        } else {
            Err(BootError::NoAnswer {
                request: PacketType::PK,
                tried: Bauds::one(to),
                attempts: self.attempts.max(1),
                timeout_ms: timeout,
            })
        }
    }
}

/// Runs the boot sequence (see the module docs) over `driver`, whose port is at any baud.
///
/// `set_baud` changes the local port's baud rate (the caller's UART or host serial port);
/// `delay` paces the reply waits (time-outs: the driver's [`crate::driver::Timing`]).
/// Never blocks longer than (bauds tried x pings + a few requests) x the reply time-out.
pub fn boot<P, D>(
    driver: &mut Driver<P>,
    target: &Target,
    options: &Options,
    delay: &mut D,
    set_baud: impl FnMut(&mut P::Serial, Baud) -> Result<(), P::Error>,
) -> Result<Report, BootError<P::Error>>
where
    P: Port,
    D: DelayNs,
{
    let (port, engine) = driver.parts_mut();
    let link = BlockingLink { port, delay };
    block_on(sequence(engine, link, target, options, set_baud))
}

/// [`boot`] over the async driver: the same sequence (one shared implementation), awaiting
/// the port and `delay` (e.g. `embassy_time::Delay`) so that other tasks run meanwhile.
/// `set_baud` changes the local UART's baud rate (e.g. `embassy_stm32`'s `set_baudrate`).
pub async fn boot_async<S, D>(
    driver: &mut AsyncDriver<S>,
    target: &Target,
    options: &Options,
    delay: &mut D,
    set_baud: impl FnMut(&mut S, Baud) -> Result<(), S::Error>,
) -> Result<Report, BootError<S::Error>>
where
    S: embedded_io_async::Read + embedded_io_async::Write + embedded_io::ReadReady,
    D: embedded_hal_async::delay::DelayNs,
{
    let (serial, engine) = driver.parts_mut();
    let link = AsyncLink { serial, delay };
    sequence(engine, link, target, options, set_baud).await
}

/// The boot sequence over any [`Link`] (blocking or async).
async fn sequence<L: Link>(
    driver: &mut Engine,
    link: L,
    target: &Target,
    options: &Options,
    set_baud: impl FnMut(&mut L::Serial, Baud) -> Result<(), L::Error>,
) -> Result<Report, BootError<L::Error>> {
    let unsolicited0 = driver.unsolicited;
    let skipped0 = driver.parser.stats().skipped_bytes;
    let attempts = options.ping_attempts.max(1);
    let mut s = Session {
        driver,
        link,
        set_baud,
        attempts,
        retries: 0,
        baud: options.start_baud.unwrap_or(Baud::B57600),
    };

    // 1. Find the unit.
    let single = options.start_baud.map(|b| [b]);
    let candidates: &[Baud] = match &single {
        Some(one) => one,
        None => &SEARCH_ORDER,
    };
    let mut tried = Bauds::default();
    let mut found = None;
    for &b in candidates {
        s.local_baud(b)?;
        tried.insert(b);
        if s.ping().await? {
            found = Some(b);
            break;
        }
    }
    let Some(found_at) = found else {
        return Err(BootError::NoAnswer {
            request: PacketType::PK,
            tried,
            attempts,
            timeout_ms: s.timeout_ms(),
        });
    };

    // 2. Read its configuration; its baud field is the truth.
    let [rate0, baud0, type0] = s.read().await?;
    let undefined = |field: FieldId, value: Option<u16>, defined: bool| match value {
        Some(value) if !defined => Err(BootError::UndefinedValue { field, value }),
        _ => Ok(()),
    };
    undefined(
        FieldId::BAUD_RATE,
        baud0,
        baud0.is_none_or(|v| Baud::from_code(v).is_some()),
    )?;
    undefined(
        FieldId::PACKET_RATE_DIVIDER,
        rate0,
        rate0.is_none_or(|v| PacketRate::from_divider(v).is_some()),
    )?;
    let unit_baud = baud0.and_then(Baud::from_code).unwrap_or(found_at);
    if unit_baud != found_at {
        s.local_baud(unit_baud)?;
    }

    // 3./4. Baud and output, in the order that keeps the budget.
    // Up: the baud first; down: the output first (one await of each step).
    let switched = unit_baud != target.baud;
    let up = switched && target.baud.bits_per_second() > unit_baud.bits_per_second();
    if up {
        s.switch(target.baud).await?;
    }
    s.set_output(target).await?;
    if switched && !up {
        s.switch(target.baud).await?;
    }
    if target.persist {
        let fields = target.persist_fields();
        let timeout = s.timeout_ms();
        let baud = s.baud;
        s.driver
            .configure(&mut s.link, PacketType::WF, &fields)
            .await
            .map_err(|e| convert(e, PacketType::WF, FieldList::new(&fields), baud, timeout))?;
    }

    // 5. Read back.
    let got = s.read().await?;
    for (id, got) in READ_FIELDS.iter().zip(got) {
        let expected = target.expected(*id);
        if got != Some(expected) {
            return Err(BootError::WrongReadBack {
                field: *id,
                expected,
                got,
            });
        }
    }

    Ok(Report {
        found_at,
        unit_baud,
        initial_packet: PacketType::from_code(type0.unwrap_or(0)),
        initial_rate_divider: rate0.unwrap_or(0),
        switched,
        baud: s.baud,
        ping_retries: s.retries,
        unsolicited_frames: s.driver.unsolicited.saturating_sub(unsolicited0),
        skipped_bytes: s
            .driver
            .parser
            .stats()
            .skipped_bytes
            .saturating_sub(skipped0),
    })
}
