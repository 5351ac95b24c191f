//! Reading packets by meaning: time, attitude, body rates and BIT from whichever packet
//! carries them, through each packet's role layout (generated from the table).

use super::fields::{scale, BeField, Kind, Role};
use super::status::Bit;

/// Time stamp carried by a packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TimeStamp {
    /// timeITOW (U4): GPS time of week, ms (wraps at 604 800 000 ms).
    Itow(u32),
    /// GPSITOW (U2): low 16 bits of the time of week, ms (wraps every 65.536 s).
    GpsItow(u16),
    /// The packet carries no time.
    None,
}

/// What the yaw estimator pipeline needs from any packet that carries yaw and the body z
/// rate (A0, A1, A2, N0, N1, B1).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct YawSample {
    /// The packet's time stamp.
    pub time: TimeStamp,
    /// Yaw (A0/A1 magnetic yaw, A2/N0/N1 true yaw, B1 yaw), deg, wrapped to [-180, 180).
    pub yaw_deg: f32,
    /// Body z angular rate (corrected), deg/s.
    pub yaw_rate_deg_s: f32,
}

/// Euler angles of a packet that carries all three (A0, A1, A2, N0, N1, B1); see
/// [`Packet::attitude`](crate::Packet::attitude).
///
/// Each angle is the wire I2 times 360/2^16 deg, so every value lies in [-180, 180): roll
/// and yaw wrap there; pitch stays within [-90, 90] on a real unit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Attitude {
    /// Roll phi, deg.
    pub roll_deg: f32,
    /// Pitch theta, deg.
    pub pitch_deg: f32,
    /// Yaw psi (magnetic yaw for A0/A1, true yaw for A2/N0/N1), deg.
    pub yaw_deg: f32,
}

/// Body angular rates of a packet that carries all three (S0, S1, A0, A1, A2, N0, N1); see
/// [`Packet::body_rates`](crate::Packet::body_rates). Each is the wire I2 times 1260/2^16
/// deg/s (corrected rates, except S0/S1 whose rates are the sensors').
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BodyRates {
    /// Body x rate p, deg/s.
    pub p_deg_s: f32,
    /// Body y rate q, deg/s.
    pub q_deg_s: f32,
    /// Body z rate r, deg/s.
    pub r_deg_s: f32,
}

/// Offsets of a packet's role fields (built at compile time from the table; at most one
/// field per role).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Roles {
    roll: Option<usize>,
    pitch: Option<usize>,
    yaw: Option<usize>,
    p: Option<usize>,
    q: Option<usize>,
    r: Option<usize>,
    time: Option<(usize, Kind)>,
    bit: Option<usize>,
}

/// Sets `slot` to `off`; a second field of the same role fails the build.
const fn once(slot: Option<usize>, off: usize) -> Option<usize> {
    assert!(slot.is_none(), "two fields of one role in a packet");
    Some(off)
}

#[inline(always)]
fn angle_deg(p: &[u8], off: usize) -> f32 {
    scale::angle_deg(i16::read(p, off))
}

#[inline(always)]
fn rate_deg_s(p: &[u8], off: usize) -> f32 {
    scale::rate_deg_s(i16::read(p, off))
}

impl Roles {
    pub(crate) const NONE: Roles = Roles {
        roll: None,
        pitch: None,
        yaw: None,
        p: None,
        q: None,
        r: None,
        time: None,
        bit: None,
    };

    /// Adds a field of kind `kind` at `off` with `role` (`None`: no role).
    pub(crate) const fn with(self, role: Option<Role>, kind: Kind, off: usize) -> Roles {
        let mut r = self;
        match role {
            None => {}
            Some(Role::Roll) => r.roll = once(r.roll, off),
            Some(Role::Pitch) => r.pitch = once(r.pitch, off),
            Some(Role::Yaw) => r.yaw = once(r.yaw, off),
            Some(Role::P) => r.p = once(r.p, off),
            Some(Role::Q) => r.q = once(r.q, off),
            Some(Role::R) => r.r = once(r.r, off),
            Some(Role::Time) => {
                assert!(r.time.is_none(), "two fields of one role in a packet");
                r.time = Some((off, kind));
            }
            Some(Role::Bit) => r.bit = once(r.bit, off),
        }
        r
    }

    #[inline(always)]
    pub(crate) fn time(&self, p: &[u8]) -> TimeStamp {
        match self.time {
            Some((off, Kind::Itow)) => TimeStamp::Itow(u32::read(p, off)),
            Some((off, _)) => TimeStamp::GpsItow(u16::read(p, off)),
            None => TimeStamp::None,
        }
    }

    #[inline(always)]
    pub(crate) fn bit(&self, p: &[u8]) -> Option<Bit> {
        self.bit.map(|off| Bit(u16::read(p, off)))
    }

    #[inline(always)]
    pub(crate) fn attitude(&self, p: &[u8]) -> Option<Attitude> {
        match (self.roll, self.pitch, self.yaw) {
            (Some(roll), Some(pitch), Some(yaw)) => Some(Attitude {
                roll_deg: angle_deg(p, roll),
                pitch_deg: angle_deg(p, pitch),
                yaw_deg: angle_deg(p, yaw),
            }),
            _ => None,
        }
    }

    #[inline(always)]
    pub(crate) fn body_rates(&self, p: &[u8]) -> Option<BodyRates> {
        match (self.p, self.q, self.r) {
            (Some(x), Some(y), Some(z)) => Some(BodyRates {
                p_deg_s: rate_deg_s(p, x),
                q_deg_s: rate_deg_s(p, y),
                r_deg_s: rate_deg_s(p, z),
            }),
            _ => None,
        }
    }

    #[inline(always)]
    pub(crate) fn yaw_sample(&self, p: &[u8]) -> Option<YawSample> {
        match (self.yaw, self.r) {
            (Some(yaw), Some(r)) => Some(YawSample {
                time: self.time(p),
                yaw_deg: angle_deg(p, yaw),
                yaw_rate_deg_s: rate_deg_s(p, r),
            }),
            _ => None,
        }
    }
}
