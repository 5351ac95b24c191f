//! One sample as the NAV440's packets carry it ([`RawSample`]: the raw fields of every output
//! packet), read from and written to frames through `nav440-proto`'s packet table: the one
//! encoder of the host tools. `nav440 sim` re-encodes a capture's samples as the commanded
//! packet type with it; `nav440 synth` encodes its motions with it.

use nav440_proto::{
    encode_frame, FieldInfo, Kind, Packet, PacketType, Parser, Role, TimeStamp, MAX_FRAME,
};

use crate::error::Result;

/// Raw fields of one sample, as the packets carry them (the union of every output packet).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RawSample {
    /// Roll, pitch, yaw (I2 angles).
    pub angles: [i16; 3],
    /// Angular rates x, y, z.
    pub rates: [i16; 3],
    /// Accelerations x, y, z.
    pub accels: [i16; 3],
    /// Magnetic field x, y, z.
    pub mags: [i16; 3],
    /// Rate sensor temperatures x, y, z.
    pub temps: [i16; 3],
    /// Board temperature.
    pub board_temp: i16,
    /// Velocity N, E, D.
    pub vel: [i16; 3],
    /// Longitude, latitude (I4).
    pub lon_lat: [i32; 2],
    /// Altitude.
    pub altitude: i16,
    /// timeITOW, ms (GPSITOW-only packets: unwrapped from the 16-bit value).
    pub itow: u32,
    /// BIT word.
    pub bit: u16,
}

impl RawSample {
    /// The protocol document's real S1 frame (a stationary unit, BIT 0x0002).
    pub const POWER_UP: Self = Self {
        angles: [0; 3],
        rates: [-2, -7, -1],
        accels: [-32, 22, 3264],
        mags: [0; 3],
        temps: [0x27eb; 3],
        board_temp: 0x27f7,
        vel: [0; 3],
        lon_lat: [0; 2],
        altitude: 0,
        itow: 0,
        bit: 0x0002,
    };
}

/// Where a field of the packet table lives in a [`RawSample`]: from its role, else its kind
/// and the axis its name gives (`accel_x`, `rate_temp_y`, `x_rate_temp`, `vel_d`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    Angle(usize),
    Rate(usize),
    Accel(usize),
    Mag(usize),
    RateTemp(usize),
    BoardTemp,
    Vel(usize),
    LonLat(usize),
    Altitude,
    Time,
    Bit,
    Counter,
    /// Not simulated: sent as 0 (S2's delta velocities and angles, T0's detail words).
    Zero,
}

impl Slot {
    fn of(f: &FieldInfo) -> Slot {
        let axis = |names: [&str; 3]| {
            f.name
                .split('_')
                .find_map(|part| names.iter().position(|n| *n == part))
        };
        let xyz = axis(["x", "y", "z"]);
        match (f.role, f.kind) {
            (Some(Role::Roll), _) => Slot::Angle(0),
            (Some(Role::Pitch), _) => Slot::Angle(1),
            (Some(Role::Yaw), _) => Slot::Angle(2),
            (Some(Role::P), _) => Slot::Rate(0),
            (Some(Role::Q), _) => Slot::Rate(1),
            (Some(Role::R), _) => Slot::Rate(2),
            (Some(Role::Time), _) => Slot::Time,
            (Some(Role::Bit), _) => Slot::Bit,
            (None, Kind::Rate) => xyz.map_or(Slot::Zero, Slot::Rate),
            (None, Kind::Accel) => xyz.map_or(Slot::Zero, Slot::Accel),
            (None, Kind::Mag) => xyz.map_or(Slot::Zero, Slot::Mag),
            (None, Kind::Temp) if f.name == "board_temp" => Slot::BoardTemp,
            (None, Kind::Temp) => xyz.map_or(Slot::Zero, Slot::RateTemp),
            (None, Kind::Velocity) => axis(["n", "e", "d"]).map_or(Slot::Zero, Slot::Vel),
            (None, Kind::LatLon) => match f.name {
                "longitude" => Slot::LonLat(0),
                "latitude" => Slot::LonLat(1),
                _ => Slot::Zero,
            },
            (None, Kind::Altitude) => Slot::Altitude,
            (None, Kind::Counter) => Slot::Counter,
            _ => Slot::Zero,
        }
    }
}

impl RawSample {
    /// The wire value of `slot` (sign-extended; the encoder keeps the field's low bytes, so a
    /// GPSITOW field gets the low 16 bits of [`Self::itow`]).
    fn get(&self, slot: Slot, counter: u16) -> i64 {
        match slot {
            Slot::Angle(i) => self.angles[i].into(),
            Slot::Rate(i) => self.rates[i].into(),
            Slot::Accel(i) => self.accels[i].into(),
            Slot::Mag(i) => self.mags[i].into(),
            Slot::RateTemp(i) => self.temps[i].into(),
            Slot::BoardTemp => self.board_temp.into(),
            Slot::Vel(i) => self.vel[i].into(),
            Slot::LonLat(i) => self.lon_lat[i].into(),
            Slot::Altitude => self.altitude.into(),
            Slot::Time => self.itow.into(),
            Slot::Bit => self.bit.into(),
            Slot::Counter => counter.into(),
            Slot::Zero => 0,
        }
    }

    /// Stores the wire bits `raw` of a field into `slot` (time and counter are not stored:
    /// the time comes unwrapped from [`Packet::time`], the counter from the session).
    fn set(&mut self, slot: Slot, raw: u64) {
        match slot {
            Slot::Angle(i) => self.angles[i] = raw as i16,
            Slot::Rate(i) => self.rates[i] = raw as i16,
            Slot::Accel(i) => self.accels[i] = raw as i16,
            Slot::Mag(i) => self.mags[i] = raw as i16,
            Slot::RateTemp(i) => self.temps[i] = raw as i16,
            Slot::BoardTemp => self.board_temp = raw as i16,
            Slot::Vel(i) => self.vel[i] = raw as i16,
            Slot::LonLat(i) => self.lon_lat[i] = raw as i32,
            Slot::Altitude => self.altitude = raw as i16,
            Slot::Bit => self.bit = raw as u16,
            Slot::Time | Slot::Counter | Slot::Zero => {}
        }
    }
}

/// The samples of every packet of `bytes` that carries yaw and a time stamp, in order, read
/// through the packet table. A packet with the X rate-sensor temperature only (A0, A1, N1)
/// gives it to all three sensors.
pub fn capture_samples(bytes: &[u8]) -> Result<Vec<RawSample>> {
    let mut parser = Parser::new();
    let mut out = Vec::new();
    let mut gps: Option<(u16, u32)> = None;
    let mut frames = 0u64;
    parser.feed(bytes, |frame| {
        frames += 1;
        let Ok(p) = Packet::decode(frame) else { return };
        let Some(fields) = frame.packet_type.payload_fields() else {
            return;
        };
        if !fields.iter().any(|f| f.role == Some(Role::Yaw)) {
            return;
        }
        let mut s = RawSample::default();
        let mut temps = [false; 3];
        for f in fields {
            let Some(wire) = frame.payload.get(f.offset..f.offset + f.size) else {
                return;
            };
            let slot = Slot::of(f);
            if let Slot::RateTemp(i) = slot {
                temps[i] = true;
            }
            s.set(slot, wire.iter().fold(0, |v, &b| v << 8 | u64::from(b)));
        }
        if temps == [true, false, false] {
            s.temps = [s.temps[0]; 3];
        }
        s.itow = match p.time() {
            TimeStamp::Itow(t) => t,
            TimeStamp::GpsItow(g) => {
                let t = match gps {
                    Some((last, acc)) => acc.wrapping_add(u32::from(g.wrapping_sub(last))),
                    None => u32::from(g),
                };
                gps = Some((g, t));
                t
            }
            TimeStamp::None => return,
        };
        out.push(s);
    });
    crate::replay::check_yaw_stream(frames, out.len() as u64)?;
    Ok(out)
}

/// Encodes `s` as one frame of the continuous output type `t` (`counter` for S1/S2), field by
/// field from the packet table; `None` for a type the unit does not stream.
pub fn encode_sample(t: PacketType, s: &RawSample, counter: u16) -> Option<Vec<u8>> {
    let mut payload = vec![0u8; t.output_payload_len()?];
    for f in t.payload_fields()? {
        let wire = s.get(Slot::of(f), counter).to_be_bytes();
        payload
            .get_mut(f.offset..f.offset + f.size)?
            .copy_from_slice(wire.get(wire.len().checked_sub(f.size)?..)?);
    }
    let mut buf = [0u8; MAX_FRAME];
    let n = encode_frame(t, &payload, &mut buf).ok()?;
    buf.get(..n).map(<[u8]>::to_vec)
}
