//! The front end: bytes -> frames (`nav440_proto::Parser`) -> attitude packets (A0, A1, A2,
//! N0, N1, B1) -> BIT check -> clock (`nav440_proto::TimeBase`) -> timed [`Sample`]s.

use crate::bit::BitCounts;
use crate::reference::{EulerReference, Reference};
use crate::Axis;
use core::marker::PhantomData;
use nav440_proto::{
    Bit, DecodeError, Frame, Packet, PacketType, Parser, TimeBase, TimeFaults, TimeStamp, Timed, A2,
};

/// What the pipeline takes from a packet that carries the attitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attitude {
    /// The packet's time stamp.
    pub time: TimeStamp,
    /// Roll, pitch, yaw as sent (A0/A1: magnetic yaw; A2/N0/N1: true yaw; B1: yaw), the
    /// packet's integers, 360/2^16 deg per LSB ([`Attitude::angles_deg`] in degrees).
    pub angles_raw: [i16; 3],
    /// Body rates p, q, r (x, y, z; corrected), deg/s (B1 sends r only: p, q are NaN).
    pub rates_deg_s: [f32; 3],
    /// The BIT status word.
    pub bit: Bit,
}

/// The attitude of a packet that carries one (A0, A1, A2, N0, N1, B1), from the packets'
/// public accessors; `None` for any other packet.
pub fn attitude(packet: &Packet<'_>) -> Option<Attitude> {
    attitude_of(packet)
}

/// [`attitude`], inlined where it is called: a caller that knows the packet's type keeps that
/// type's arm only ([`OnlyA2`]).
#[inline(always)]
fn attitude_of(packet: &Packet<'_>) -> Option<Attitude> {
    macro_rules! att {
        ($p:expr, $yaw:ident) => {
            (
                [$p.roll(), $p.pitch(), $p.$yaw()],
                [$p.rate_x_deg_s(), $p.rate_y_deg_s(), $p.rate_z_deg_s()],
            )
        };
    }
    let (angles_raw, rates_deg_s) = match packet {
        Packet::A0(p) => att!(p, yaw_mag),
        Packet::A1(p) => att!(p, yaw_mag),
        Packet::A2(p) => att!(p, yaw_true),
        Packet::N0(p) => att!(p, yaw_true),
        Packet::N1(p) => att!(p, yaw_true),
        // B1 carries the z rate only: p and q unknown (NaN), so its reference rates are empty.
        Packet::B1(p) => (
            [p.roll(), p.pitch(), p.yaw()],
            [f32::NAN, f32::NAN, p.rate_z_deg_s()],
        ),
        _ => return None,
    };
    Some(Attitude {
        time: packet.time(),
        angles_raw,
        rates_deg_s,
        bit: packet.bit().unwrap_or_default(),
    })
}

impl Attitude {
    /// Roll, pitch, yaw in deg: the exact values of [`Attitude::angles_raw`]
    /// (`nav440_proto::scale::angle_deg`).
    pub fn angles_deg(&self) -> [f32; 3] {
        self.angles_raw.map(nav440_proto::scale::angle_deg)
    }
}

/// One timed attitude sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time since the first sample, us (timeITOW / GPSITOW through `nav440_proto::TimeBase`:
    /// wraps handled, strictly increasing within an epoch).
    pub t_us: u64,
    /// Roll, pitch, yaw (wrapped), deg ([`Sample::angles_deg`]).
    pub(crate) angles_deg: [f32; 3],
    /// The same angles as the packet's integers (360/2^16 deg per LSB) while they are the
    /// packet's (`raw`; 0 otherwise): not once an angle was set otherwise
    /// ([`Sample::set_angle_deg`]), so the two never disagree ([`Sample::angles_raw`]). A flag
    /// beside them rather than an `Option`: 40 bytes a sample instead of 48 (the warm-up holds
    /// 16 of them).
    pub(crate) angles_raw: [i16; 3],
    /// Body rates p, q, r as sent, deg/s.
    pub rates_deg_s: [f32; 3],
    /// First sample of a new time epoch (a confirmed backward jump of the time stamps, or the
    /// switch from GPSITOW to timeITOW): the banks re-initialise from it.
    pub new_epoch: bool,
    /// `angles_raw` holds the packet's integers.
    pub(crate) raw: bool,
}

impl Sample {
    /// Time in seconds.
    pub fn t_s(&self) -> f64 {
        self.t_us as f64 * 1e-6
    }

    /// The angle of `axis`, deg.
    pub fn angle(&self, axis: Axis) -> f32 {
        self.angles_deg[axis.index()]
    }

    /// Roll, pitch, yaw (wrapped), deg.
    pub fn angles_deg(&self) -> [f32; 3] {
        self.angles_deg
    }

    /// The angles as the packet's integers (360/2^16 deg per LSB; [`Sample::angles_deg`] is
    /// their exact value), `None` once an angle was set otherwise. The pipeline feeds the
    /// banks these when it has them (`EstimatorBank::update_scaled`: a fixed-point bank's
    /// input then takes no `f32`), otherwise [`Sample::angle`] in the same form
    /// (`estimators::f32_scaled`, exact; a NaN or infinite angle is rejected as
    /// `SampleError::NotFinite` without reaching the bank).
    pub fn angles_raw(&self) -> Option<[i16; 3]> {
        self.raw.then_some(self.angles_raw)
    }

    /// Sets the angle of `axis` to `deg` (e.g. with added noise): the sample no longer holds
    /// the packet's integers ([`Sample::angles_raw`] is `None`).
    pub fn set_angle_deg(&mut self, axis: Axis, deg: f32) {
        self.angles_deg[axis.index()] = deg;
        self.angles_raw = [0; 3];
        self.raw = false;
    }

    /// A sample of the angles `angles_deg` (deg, not a packet's integers) and the body rates
    /// `rates_deg_s`, at `t_us`.
    pub fn new(t_us: u64, angles_deg: [f32; 3], rates_deg_s: [f32; 3], new_epoch: bool) -> Self {
        Sample {
            t_us,
            angles_deg,
            angles_raw: [0; 3],
            rates_deg_s,
            new_epoch,
            raw: false,
        }
    }

    /// The reference rate of `axis` (the angle's derivative by the Euler kinematics, deg/s;
    /// `None` near gimbal lock, see [`crate::euler`]).
    pub fn reference(&self, axis: Axis) -> Option<f32> {
        self.references()[axis.index()]
    }

    /// `true` when the sample's pitch is at or beyond the gimbal-lock limit
    /// ([`crate::euler::near_lock`]).
    pub fn near_lock(&self) -> bool {
        crate::euler::near_lock(self.angles_deg[1])
    }

    /// The reference rates of roll, pitch, yaw (deg/s), see [`crate::euler`].
    pub fn references(&self) -> [Option<f32>; 3] {
        EulerReference::rates_deg_s(self.angles_deg, self.rates_deg_s)
    }

    /// A sample of the angles `angles_raw` (360/2^16 deg per LSB; `angles_deg` their exact
    /// value) and the body rates `rates_deg_s`, at `t_us`.
    pub fn from_raw(
        t_us: u64,
        angles_raw: [i16; 3],
        rates_deg_s: [f32; 3],
        new_epoch: bool,
    ) -> Self {
        Sample {
            t_us,
            angles_deg: angles_raw.map(nav440_proto::scale::angle_deg),
            angles_raw,
            rates_deg_s,
            new_epoch,
            raw: true,
        }
    }

    fn from_timed(t: Timed<Payload>) -> Self {
        let (angles_raw, rates_deg_s) = t.payload;
        Self::from_raw(t.t_us, angles_raw, rates_deg_s, t.new_epoch)
    }
}

/// What rides through the time base with each time stamp: the angles as sent (360/2^16 deg
/// per LSB), the body rates (deg/s).
type Payload = ([i16; 3], [f32; 3]);

/// Counters of the front end. Every counter saturates. Invariant: `attitude_packets =
/// bit.failed + samples + time faults' discarded + duplicates` (plus one sample held by the
/// time base before `finish`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrontCounters {
    /// CRC-valid frames.
    pub frames: u64,
    /// CRC-valid frames that failed to decode (a known type with a wrong length).
    pub decode_errors: u64,
    /// Decoded packets that carry the attitude (A0/A1/A2/N0/N1/B1), before the BIT and time
    /// rules (`yaw_packets` in the firmware's summary line).
    pub attitude_packets: u64,
    /// Packets dropped for their BIT word.
    pub bit: BitCounts,
    /// Samples released by the time base.
    pub samples: u64,
    /// Bytes at the end of a finite input that did not complete a frame (after every complete
    /// frame among them was recovered; see [`Frontend::finish`]).
    pub end_dropped_bytes: u64,
}

/// One CRC-valid frame as the front end sees it, before the BIT and time rules: what the
/// stream watchdog ([`crate::watch::StreamWatch`]) consumes ([`Frontend::feed_frames`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameSeen {
    /// The frame's packet type.
    pub packet_type: PacketType,
    /// The time stamp of a packet that carries the attitude (A0/A1/A2/N0/N1/B1); `None` for
    /// another packet or a frame that does not decode.
    pub time: Option<TimeStamp>,
}

/// The packets the front end decodes and estimates from ([`Frontend`]'s `D`, a marker type:
/// `Default` builds it).
pub trait Decoder: Default {
    /// Decodes a CRC-valid frame: [`Packet::Unknown`] for a type this decoder does not decode
    /// (counted as a frame only), `Err` for one of its types that does not decode (a wrong
    /// payload length, counted in [`FrontCounters::decode_errors`]).
    fn decode(frame: Frame<'_>) -> Result<Packet<'_>, DecodeError>;
    /// The attitude of a packet [`Self::decode`] gave ([`attitude`]).
    fn attitude(packet: &Packet<'_>) -> Option<Attitude>;
}

/// Every packet type of the protocol ([`Packet::decode`], then [`attitude`]): the host tools'
/// and the firmware images' front end.
#[derive(Clone, Copy, Debug, Default)]
pub struct AllPackets;

impl Decoder for AllPackets {
    #[inline]
    fn decode(frame: Frame<'_>) -> Result<Packet<'_>, DecodeError> {
        Packet::decode(frame)
    }
    #[inline]
    fn attitude(packet: &Packet<'_>) -> Option<Attitude> {
        attitude(packet)
    }
}

/// A2 only, the packet type the firmware configures (`nav440_proto::boot::Target::DEFAULT`): A2's
/// decoder alone is linked, not the packet table's. Every other frame is counted as a frame
/// and not estimated from, as [`AllPackets`] treats a packet without the attitude; an A2
/// stream gives the same samples as with [`AllPackets`]. For a part with little flash (the
/// NUCLEO-G031K8's image, docs/PORTING.md).
#[derive(Clone, Copy, Debug, Default)]
pub struct OnlyA2;

impl Decoder for OnlyA2 {
    #[inline]
    fn decode(frame: Frame<'_>) -> Result<Packet<'_>, DecodeError> {
        if frame.packet_type == PacketType::A2 {
            A2::new(frame.payload).map(Packet::A2)
        } else {
            Ok(Packet::Unknown(frame))
        }
    }
    #[inline]
    fn attitude(packet: &Packet<'_>) -> Option<Attitude> {
        match packet {
            Packet::A2(_) => attitude_of(packet),
            _ => None,
        }
    }
}

/// One CRC-valid frame through the decoder `D`, the BIT check and the time base; `seen` gets
/// the frame first.
fn on_frame<D: Decoder>(
    frame: Frame<'_>,
    clock: &mut TimeBase<Payload>,
    counters: &mut FrontCounters,
    seen: &mut impl FnMut(&FrameSeen),
    out: &mut impl FnMut(Sample),
) {
    counters.frames = counters.frames.saturating_add(1);
    let packet_type = frame.packet_type;
    let packet = match D::decode(frame) {
        Ok(p) => p,
        Err(_) => {
            counters.decode_errors = counters.decode_errors.saturating_add(1);
            seen(&FrameSeen {
                packet_type,
                time: None,
            });
            return;
        }
    };
    let Some(a) = D::attitude(&packet) else {
        seen(&FrameSeen {
            packet_type,
            time: None,
        });
        return;
    };
    seen(&FrameSeen {
        packet_type,
        time: Some(a.time),
    });
    counters.attitude_packets = counters.attitude_packets.saturating_add(1);
    if counters.bit.check(a.bit) {
        return;
    }
    for t in clock.update(a.time, (a.angles_raw, a.rates_deg_s)) {
        counters.samples = counters.samples.saturating_add(1);
        out(Sample::from_timed(t));
    }
}

/// bytes -> parser -> attitude packets -> BIT check -> time base -> [`Sample`]s, in any
/// chunking; samples come out in stream order (a suspicious time stamp is released one
/// sample late, see `TimeBase`). Call [`Frontend::finish`] at the end of a finite input.
/// `D`: the packets it decodes ([`Decoder`]; every type by default).
#[derive(Debug, Default)]
pub struct Frontend<D = AllPackets> {
    parser: Parser,
    clock: TimeBase<Payload>,
    counters: FrontCounters,
    decoder: PhantomData<D>,
}

impl Frontend {
    /// A front end at the start of a stream, decoding every packet type ([`AllPackets`];
    /// another decoder: `Frontend::<D>::default()`).
    pub fn new() -> Self {
        Self::default()
    }
}

impl<D: Decoder> Frontend<D> {
    /// Feeds bytes; `out` gets every sample released.
    pub fn feed(&mut self, bytes: &[u8], out: impl FnMut(Sample)) {
        self.feed_frames(bytes, |_| {}, out);
    }

    /// [`Frontend::feed`] that also reports every CRC-valid frame to `seen` (in stream order,
    /// before the samples it releases): the one parse the stream watchdog consumes.
    pub fn feed_frames(
        &mut self,
        bytes: &[u8],
        mut seen: impl FnMut(&FrameSeen),
        mut out: impl FnMut(Sample),
    ) {
        let Self {
            parser,
            clock,
            counters,
            ..
        } = self;
        parser.feed(bytes, |frame| {
            on_frame::<D>(frame, clock, counters, &mut seen, &mut out)
        });
    }

    /// End of input: resolves a frame the parser still holds (complete frames behind a false
    /// header are recovered, the bytes of an incomplete one are counted in
    /// [`FrontCounters::end_dropped_bytes`]), then releases a held sample if the time rules
    /// allow it.
    pub fn finish(&mut self, mut out: impl FnMut(Sample)) {
        let Self {
            parser,
            clock,
            counters,
            ..
        } = self;
        let dropped =
            parser.finish(|frame| on_frame::<D>(frame, clock, counters, &mut |_| {}, &mut out));
        counters.end_dropped_bytes = counters.end_dropped_bytes.saturating_add(dropped as u64);
        if let Some(t) = clock.finish() {
            counters.samples = counters.samples.saturating_add(1);
            out(Sample::from_timed(t));
        }
    }

    /// Counters so far.
    pub fn counters(&self) -> &FrontCounters {
        &self.counters
    }

    /// Parser statistics (bytes, frames, CRC errors, skipped bytes).
    pub fn parser_stats(&self) -> &nav440_proto::Stats {
        self.parser.stats()
    }

    /// Time-stamp faults so far.
    pub fn time_faults(&self) -> &TimeFaults {
        self.clock.faults()
    }
}
