//! Capture generator: a motion profile -> the byte stream a NAV440 sends.
//!
//! Each packet holds the motion at its time stamp, quantised to the protocol's LSBs
//! (docs/NAV440-PROTOCOL.md): roll, pitch and yaw wrapped to [-180, 180) deg in 360/2^16 deg
//! steps, the body rates p, q, r (the analytic angular velocity of the motion) in 1260/2^16
//! deg/s steps (saturating), timeITOW in ms (wrapping at the end of the GPS week), and the BIT
//! word. The yaw-only profiles keep the unit level (roll = pitch = 0, x/y rates 0). The
//! accelerometers read gravity only, (0, 0, 1) g for a level unit as in the protocol's example
//! packet, rotated into the body frame for any other attitude; the A1's magnetometer reads a
//! field of 0.25 G north and 0.4 G down rotated the same way. Temperatures are 25 degC. Frames
//! are encoded field by field from `nav440-proto`'s packet table
//! ([`crate::raw_sample::encode_sample`], the encoder `nav440 sim` streams with).

use crate::corrupt::{self, Corruption, CorruptionReport};
use crate::error::{Error, Result};
use crate::motion::{Profile, ProfileKind};
use crate::progress::Progress;
use crate::raw_sample::{encode_sample, RawSample};
use nav440_proto::PacketType;
use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::fmt;
use std::str::FromStr;

/// Milliseconds in a GPS week (timeITOW wraps here).
pub const MS_PER_WEEK: u64 = 604_800_000;
/// Output rates the unit supports (100 Hz divided by its rate-divider field 0x0001), Hz.
pub const RATES_HZ: [u32; 8] = [100, 50, 25, 20, 10, 5, 4, 2];

/// Angle LSB, degrees (2 pi / 2^16 rad).
pub const ANGLE_LSB_DEG: f64 = 360.0 / 65536.0;
/// Angular-rate LSB, deg/s (7 pi / 2^16 rad/s).
pub const RATE_LSB_DEG_S: f64 = 1260.0 / 65536.0;
/// Acceleration LSB, g.
pub const ACCEL_LSB_G: f64 = 20.0 / 65536.0;
/// Magnetic field LSB, gauss.
pub const MAG_LSB_G: f64 = 2.0 / 65536.0;
/// Temperature LSB, degC.
pub const TEMP_LSB_C: f64 = 200.0 / 65536.0;
/// Velocity LSB, m/s.
pub const VEL_LSB_M_S: f64 = 512.0 / 65536.0;
/// Latitude/longitude LSB (I4), degrees (2 pi / 2^32 rad).
pub const LATLON_LSB_DEG: f64 = 360.0 / 4_294_967_296.0;
/// Altitude LSB, m.
pub const ALT_LSB_M: f64 = 0.25;

/// Which packet the synthetic unit sends continuously.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketKind {
    /// Angle packet 1 (yaw from the magnetometer, timeITOW U4), 32-byte payload.
    A1,
    /// Angle packet 2 (free/true yaw, timeITOW U4), 30-byte payload.
    A2,
    /// Navigation packet 1 (the NAV440's default), 42-byte payload.
    N1,
}

impl PacketKind {
    /// Two-letter name.
    pub fn name(self) -> &'static str {
        match self {
            PacketKind::A1 => "A1",
            PacketKind::A2 => "A2",
            PacketKind::N1 => "N1",
        }
    }
    /// The packet type of the packet table.
    pub fn packet_type(self) -> PacketType {
        match self {
            PacketKind::A1 => PacketType::A1,
            PacketKind::A2 => PacketType::A2,
            PacketKind::N1 => PacketType::N1,
        }
    }
    /// Whole frame length in bytes (preamble, type, length, payload, CRC).
    pub fn frame_len(self) -> usize {
        7 + match self {
            PacketKind::A1 => 32,
            PacketKind::A2 => 30,
            PacketKind::N1 => 42,
        }
    }
}

impl fmt::Display for PacketKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PacketKind {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.to_ascii_uppercase().as_str() {
            "A1" => Ok(PacketKind::A1),
            "A2" => Ok(PacketKind::A2),
            "N1" => Ok(PacketKind::N1),
            _ => Err(format!(
                "unsupported packet type `{s}` (expected A1, A2 or N1)"
            )),
        }
    }
}

/// Everything `nav440 synth` needs.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthConfig {
    /// Motion profile.
    pub profile: ProfileKind,
    /// Seed of the profile's shape (Fig5 only).
    pub seed: u64,
    /// Duration, s (packets at t = 0, 1/rate, ... while t <= duration).
    pub duration_s: f64,
    /// Packet rate, Hz: one of [`RATES_HZ`].
    pub rate_hz: u32,
    /// Packet type.
    pub packet: PacketKind,
    /// timeITOW of the first packet, ms: a time of week, below [`MS_PER_WEEK`] (later packets
    /// wrap to 0 at the end of the week).
    pub start_itow_ms: u64,
    /// BIT word put in every packet.
    pub bit: u16,
    /// Corruption applied to the stream.
    pub corruption: Corruption,
    /// Measurement noise added to the yaw angle (before quantisation), by time; empty: none.
    pub yaw_noise: Vec<NoiseStep>,
    /// Seed of the yaw noise.
    pub noise_seed: u64,
}

/// From `from_s` on (until a later step), Gaussian noise of variance `var_deg2` is added to
/// the yaw angle of every packet (`nav440 synth --yaw-noise VAR[@T]`, e.g. `0.01` then
/// `0.5@10`: 0.01 deg^2 from the start, 0.5 deg^2 from 10 s). The reference rate stays exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseStep {
    /// Noise variance, deg^2 (0: none).
    pub var_deg2: f64,
    /// Start time, s.
    pub from_s: f64,
}

impl FromStr for NoiseStep {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let (var, from) = match s.split_once('@') {
            Some((v, t)) => (v, Some(t)),
            None => (s, None),
        };
        let num = |x: &str, what: &str, max: f64| -> std::result::Result<f64, String> {
            match x.trim().parse::<f64>() {
                Ok(v) if v.is_finite() && (0.0..=max).contains(&v) => Ok(v),
                _ => Err(format!(
                    "{what} must be >= 0 and <= {max:e}, got {x:?} (expected VAR or VAR@SECONDS, e.g. 0.5@10)"
                )),
            }
        };
        Ok(NoiseStep {
            var_deg2: num(
                var,
                "the noise variance (deg^2)",
                crate::limits::MAX_NOISE_VAR,
            )?,
            from_s: from.map_or(Ok(0.0), |t| {
                num(t, "the start time (s)", crate::limits::MAX_SECONDS)
            })?,
        })
    }
}

/// The noise variance at `t_s` (deg^2): the step with the latest start at or before `t_s`.
fn noise_var_at(steps: &[NoiseStep], t_s: f64) -> f64 {
    steps
        .iter()
        .filter(|n| n.from_s <= t_s)
        .max_by(|a, b| a.from_s.total_cmp(&b.from_s))
        .map_or(0.0, |n| n.var_deg2)
}

impl Default for SynthConfig {
    fn default() -> Self {
        SynthConfig {
            profile: ProfileKind::Fig5,
            seed: 1,
            duration_s: 35.0,
            rate_hz: 100,
            packet: PacketKind::A2,
            // Tuesday 10:00:00 GPS time: far from the week rollover unless asked.
            start_itow_ms: 2 * 86_400_000 + 10 * 3_600_000,
            bit: 0,
            corruption: Corruption::default(),
            yaw_noise: Vec::new(),
            noise_seed: 1,
        }
    }
}

/// A generated capture.
#[derive(Clone, Debug)]
pub struct Capture {
    /// The byte stream.
    pub bytes: Vec<u8>,
    /// Number of packets generated before corruption.
    pub packets: usize,
    /// What the corruption did.
    pub report: CorruptionReport,
}

/// Packet period in ms for a supported rate.
pub fn period_ms(rate_hz: u32) -> Result<u64> {
    if RATES_HZ.contains(&rate_hz) {
        Ok(1000 / u64::from(rate_hz))
    } else {
        Err(Error::Usage(format!(
            "--rate {rate_hz} Hz is not supported (the NAV440 sends at 100/divider: 100, 50, 25, 20, 10, 5, 4 or 2 Hz)"
        )))
    }
}

/// Longest capture `synth` generates, s (it builds the whole capture in memory: 10,000 s at
/// 100 Hz are 1,000,001 packets, 37 MB of A2 frames, about 30 s of work).
pub const MAX_DURATION_S: f64 = 10_000.0;

/// Number of packets of a capture: t_k = k * period for k = 0.. while t_k <= duration.
/// A duration outside `[0, MAX_DURATION_S]` is an [`Error::Usage`].
pub fn packet_count(duration_s: f64, rate_hz: u32) -> Result<usize> {
    let p = period_ms(rate_hz)?;
    if !(duration_s.is_finite() && (0.0..=MAX_DURATION_S).contains(&duration_s)) {
        return Err(Error::Usage(format!(
            "--duration must be between 0 and {MAX_DURATION_S} s (the capture is built in memory), got {duration_s}"
        )));
    }
    Ok(((duration_s * 1000.0 + 1e-6) / p as f64).floor() as usize + 1)
}

/// Quantises an angle (deg) to the I2 angle field, wrapping into [-180, 180).
pub fn angle_raw(deg: f64) -> i16 {
    let raw = (deg / ANGLE_LSB_DEG).round() as i64;
    ((raw + 32768).rem_euclid(65536) - 32768) as i16
}

/// Quantises a value to an I2 field of the given LSB, saturating at the field's range.
pub fn sat_i16(value: f64, lsb: f64) -> i16 {
    (value / lsb).round().clamp(-32768.0, 32767.0) as i16
}

/// Generates the frames (uncorrupted) of `cfg`, one `Vec<u8>` per frame.
pub fn frames(cfg: &SynthConfig) -> Result<Vec<Vec<u8>>> {
    frames_with(cfg, &Progress::hidden())
}

/// [`frames`], advancing `progress` by every packet and motion sample.
fn frames_with(cfg: &SynthConfig, progress: &Progress) -> Result<Vec<Vec<u8>>> {
    if cfg.start_itow_ms >= MS_PER_WEEK {
        return Err(Error::Usage(format!(
            "--start-itow must be a time of week in ms, below {MS_PER_WEEK}, got {}",
            cfg.start_itow_ms
        )));
    }
    let period = period_ms(cfg.rate_hz)?;
    let n = packet_count(cfg.duration_s, cfg.rate_hz)?;
    let profile = Profile::with_progress(cfg.profile, cfg.duration_s, cfg.seed, progress);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(cfg.noise_seed);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let ms = k as u64 * period;
        let t = ms as f64 / 1000.0;
        let m = profile.at(t);
        let itow = ((cfg.start_itow_ms + ms) % MS_PER_WEEK) as u32;
        // One draw per packet while the noise is on (none at all without noise, so that a
        // capture without noise is the same as before the option existed).
        let var = noise_var_at(&cfg.yaw_noise, t);
        let noise = if var > 0.0 {
            var.sqrt() * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut rng)
        } else {
            0.0
        };
        out.push(encode_attitude(
            cfg.packet,
            [m.roll_deg, m.pitch_deg, m.yaw_deg + noise],
            m.body_rates_deg_s,
            itow,
            cfg.bit,
        )?);
        progress.inc(1);
    }
    Ok(out)
}

/// Generates the capture of `cfg` (frames, then corruption).
pub fn generate(cfg: &SynthConfig) -> Result<Capture> {
    generate_with(cfg, &Progress::hidden())
}

/// [`generate`], advancing `progress` by every packet and motion sample (the profile's
/// set-up, [`Profile::setup_samples`], then one per packet).
pub fn generate_with(cfg: &SynthConfig, progress: &Progress) -> Result<Capture> {
    let f = frames_with(cfg, progress)?;
    let (bytes, report) = corrupt::apply(&f, &cfg.corruption);
    Ok(Capture {
        bytes,
        packets: f.len(),
        report,
    })
}

/// The samples of a clean capture of A2 packets of `profile` (shape `seed`), `duration_s`
/// s at `rate_hz` Hz, as `nav440 synth --packet A2` writes it and the replay decodes it.
pub fn a2_samples(
    profile: ProfileKind,
    seed: u64,
    rate_hz: u32,
    duration_s: f64,
) -> Result<Vec<crate::replay::Sample>> {
    let cap = generate(&SynthConfig {
        profile,
        seed,
        duration_s,
        rate_hz,
        packet: PacketKind::A2,
        ..Default::default()
    })?;
    crate::replay::samples(&cap.bytes)
}

/// Encodes one packet of a level unit with the given yaw (deg, any range), z rate (deg/s),
/// timeITOW (ms) and BIT word: [`encode_attitude`] with roll = pitch = 0 and rates
/// `[0, 0, rate_deg_s]`.
pub fn encode_packet(
    kind: PacketKind,
    yaw_deg: f64,
    rate_deg_s: f64,
    itow: u32,
    bit: u16,
) -> Result<Vec<u8>> {
    encode_attitude(kind, [0.0, 0.0, yaw_deg], [0.0, 0.0, rate_deg_s], itow, bit)
}

/// The level unit's magnetic field in the NED frame (north, east, down), gauss.
const MAG_NED_G: [f64; 3] = [0.25, 0.0, 0.4];

/// Encodes one packet of a unit at Euler angles `angles_deg` = [roll, pitch, yaw] (deg, any
/// range; aerospace ZYX sequence) turning at body rates `rates_deg_s` = [p, q, r] (deg/s),
/// with the given timeITOW (ms) and BIT word. The accelerometers read (0, 0, 1) g rotated into
/// the body frame, R^T (0, 0, 1) = (-sin pitch, sin roll cos pitch, cos roll cos pitch) g
/// (gravity only, no motion of the unit's centre); the A1's magnetometer reads R^T (0.25, 0,
/// 0.4) G (north, east, down). A level unit reads (0, 0, 1) g and (0.25 cos yaw, -0.25 sin
/// yaw, 0.4) G.
pub fn encode_attitude(
    kind: PacketKind,
    angles_deg: [f64; 3],
    rates_deg_s: [f64; 3],
    itow: u32,
    bit: u16,
) -> Result<Vec<u8>> {
    let [roll_deg, pitch_deg, yaw_deg] = angles_deg;
    let (roll, pitch, yaw) = (
        angle_raw(roll_deg),
        angle_raw(pitch_deg),
        angle_raw(yaw_deg),
    );
    let [rx, ry, rz] = rates_deg_s.map(|w| sat_i16(w, RATE_LSB_DEG_S));
    let (sf, cf) = (roll_deg.to_radians().sin(), roll_deg.to_radians().cos());
    let (st, ct) = (pitch_deg.to_radians().sin(), pitch_deg.to_radians().cos());
    let y = yaw_deg.to_radians();
    let (sy, cy) = (y.sin(), y.cos());
    let [ax, ay, az] = [-st, sf * ct, cf * ct].map(|g| sat_i16(g, ACCEL_LSB_G));
    let temp = sat_i16(25.0, TEMP_LSB_C);
    // R^T m with R = Rz(yaw) Ry(pitch) Rx(roll) and m = (n, 0, d): the first and third rows
    // of R times n and d (only the A1 carries it).
    let [n, _, d] = MAG_NED_G;
    let mag = [
        n * (cy * ct) + d * -st,
        n * (cy * st * sf - sy * cf) + d * (ct * sf),
        n * (cy * st * cf + sy * sf) + d * (ct * cf),
    ];
    let sample = RawSample {
        angles: [roll, pitch, yaw],
        rates: [rx, ry, rz],
        accels: [ax, ay, az],
        mags: mag.map(|m| sat_i16(m, MAG_LSB_G)),
        // The A2 carries the three rate sensors' temperatures, the A1 and N1 the X sensor's.
        temps: [temp; 3],
        // A bench somewhere at 35.0 N, 139.0 E, 40 m, standing still (the N1's fields).
        lon_lat: [
            (139.0 / LATLON_LSB_DEG).round() as i32,
            (35.0 / LATLON_LSB_DEG).round() as i32,
        ],
        altitude: (40.0 / ALT_LSB_M) as i16,
        itow,
        bit,
        ..RawSample::default()
    };
    encode_sample(kind.packet_type(), &sample, 0)
        .ok_or_else(|| Error::Other(format!("cannot encode {kind} packet")))
}

/// Angle in degrees of a quantised I2 angle field.
pub fn angle_deg(raw: i16) -> f64 {
    f64::from(raw) * ANGLE_LSB_DEG
}

/// Rate in deg/s of a quantised I2 rate field.
pub fn rate_deg_s(raw: i16) -> f64 {
    f64::from(raw) * RATE_LSB_DEG_S
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The protocol document's synthetic A2 frame (roll 10 deg, pitch -5, yaw 90, rates
    /// 1/2/3 deg/s, accel 0/0/1 g, temps 25 degC, ITOW 123456 ms, BIT 0), rebuilt with this
    /// module's quantisers.
    #[test]
    fn quantisers_reproduce_the_protocol_test_vector() {
        let f = nav440_proto::A2Fields {
            roll: angle_raw(10.0),
            pitch: angle_raw(-5.0),
            yaw_true: angle_raw(90.0),
            rate_x: sat_i16(1.0, RATE_LSB_DEG_S),
            rate_y: sat_i16(2.0, RATE_LSB_DEG_S),
            rate_z: sat_i16(3.0, RATE_LSB_DEG_S),
            accel_x: 0,
            accel_y: 0,
            accel_z: sat_i16(1.0, ACCEL_LSB_G),
            rate_temp_x: sat_i16(25.0, TEMP_LSB_C),
            rate_temp_y: sat_i16(25.0, TEMP_LSB_C),
            rate_temp_z: sat_i16(25.0, TEMP_LSB_C),
            time_itow: 123_456,
            bit: 0,
        };
        let mut buf = [0u8; 64];
        let n = f.encode(&mut buf).unwrap();
        let want = "55 55 41 32 1e 07 1c fc 72 40 00 00 34 00 68 00 9c 00 00 00 00 0c cd 20 00 20 00 20 00 00 01 e2 40 00 00 9d 25";
        let want: Vec<u8> = want
            .split(' ')
            .map(|h| u8::from_str_radix(h, 16).unwrap())
            .collect();
        assert_eq!(&buf[..n], &want[..]);
    }

    /// The yaw-only profiles' frames are the level unit's packets as they are encoded field by
    /// field: yaw and z rate quantised, roll, pitch, x/y rates and accelerations 0, accel z 1 g,
    /// the A1's magnetometer (0.25 cos yaw, -0.25 sin yaw, 0.4) G, with the yaw noise on.
    #[test]
    fn level_profiles_encode_as_before() {
        let one_g = (1.0 / ACCEL_LSB_G).round() as i16;
        let temp = (25.0 / TEMP_LSB_C).round() as i16;
        for profile in [ProfileKind::Fig5, ProfileKind::Spin, ProfileKind::Sin5] {
            for packet in [PacketKind::A1, PacketKind::A2, PacketKind::N1] {
                let cfg = SynthConfig {
                    profile,
                    packet,
                    duration_s: 3.0,
                    rate_hz: 50,
                    ..SynthConfig::default()
                };
                let noisy = SynthConfig {
                    yaw_noise: vec!["0.2@1".parse().unwrap()],
                    ..cfg.clone()
                };
                let motion = Profile::new(profile, cfg.duration_s, cfg.seed);
                let (clean, with_noise) = (frames(&cfg).unwrap(), frames(&noisy).unwrap());
                assert_eq!(clean.len(), 151);
                for (k, (f, g)) in clean.iter().zip(&with_noise).enumerate() {
                    let t = k as f64 * 0.02;
                    let m = motion.at(t);
                    let itow = (cfg.start_itow_ms + 20 * k as u64) as u32;
                    let yaw = (m.yaw_deg / ANGLE_LSB_DEG).round() as i64;
                    let yaw = ((yaw + 32768).rem_euclid(65536) - 32768) as i16;
                    let rz = (m.rate_deg_s / RATE_LSB_DEG_S).round() as i16;
                    let mut buf = [0u8; 64];
                    let n = match packet {
                        PacketKind::A1 => {
                            let y = m.yaw_deg.to_radians();
                            nav440_proto::A1Fields {
                                yaw_mag: yaw,
                                rate_z: rz,
                                accel_z: one_g,
                                mag_x: (0.25 * y.cos() / MAG_LSB_G).round() as i16,
                                mag_y: (-0.25 * y.sin() / MAG_LSB_G).round() as i16,
                                mag_z: (0.4 / MAG_LSB_G).round() as i16,
                                x_rate_temp: temp,
                                time_itow: itow,
                                ..Default::default()
                            }
                            .encode(&mut buf)
                        }
                        PacketKind::A2 => nav440_proto::A2Fields {
                            yaw_true: yaw,
                            rate_z: rz,
                            accel_z: one_g,
                            rate_temp_x: temp,
                            rate_temp_y: temp,
                            rate_temp_z: temp,
                            time_itow: itow,
                            ..Default::default()
                        }
                        .encode(&mut buf),
                        PacketKind::N1 => nav440_proto::N1Fields {
                            yaw_true: yaw,
                            rate_z: rz,
                            accel_z: one_g,
                            longitude: (139.0 / LATLON_LSB_DEG).round() as i32,
                            latitude: (35.0 / LATLON_LSB_DEG).round() as i32,
                            altitude: 160,
                            x_rate_temp: temp,
                            time_itow: itow,
                            ..Default::default()
                        }
                        .encode(&mut buf),
                    }
                    .unwrap();
                    assert_eq!(f[..], buf[..n], "{profile} {packet} packet {k}");
                    if k < 50 {
                        assert_eq!(f, g, "{profile} {packet}: no noise before 1 s");
                    }
                }
                assert_ne!(clean, with_noise);
            }
        }
    }

    /// A tumble capture of A2 packets decodes to the profile's roll, pitch, yaw (wrapped) and
    /// body rates within half an LSB (plus the f32 rounding of the decoded sample, below 2e-5
    /// deg), one sample per packet at its time; its pitch reaches beyond 89 deg in magnitude
    /// and the x, y rates are not all 0.
    #[test]
    fn tumble_a2_capture_decodes_to_the_profile() {
        let samples = a2_samples(ProfileKind::Tumble, 1, 100, 60.0).unwrap();
        assert_eq!(samples.len(), 6001);
        let motion = Profile::new(ProfileKind::Tumble, 60.0, 1);
        let (mut max_pitch, mut max_pq) = (0.0f64, 0.0f64);
        for (k, s) in samples.iter().enumerate() {
            assert_eq!(s.t_us, k as u64 * 10_000);
            let m = motion.at(k as f64 * 0.01);
            let want = [m.roll_deg, m.pitch_deg, m.yaw_deg];
            for (ax, (got, w)) in s.angles_deg().iter().zip(want).enumerate() {
                let d = (f64::from(*got) - w + 180.0).rem_euclid(360.0) - 180.0;
                assert!(
                    d.abs() <= ANGLE_LSB_DEG / 2.0 + 2e-5,
                    "angle {ax} at {k}: {d}"
                );
            }
            for (ax, (got, w)) in s.rates_deg_s.iter().zip(m.body_rates_deg_s).enumerate() {
                let d = f64::from(*got) - w;
                assert!(
                    d.abs() <= RATE_LSB_DEG_S / 2.0 + 2e-5,
                    "rate {ax} at {k}: {d}"
                );
            }
            max_pitch = max_pitch.max(f64::from(s.angles_deg()[1]).abs());
            max_pq = max_pq.max(f64::from(
                s.rates_deg_s[0].abs().max(s.rates_deg_s[1].abs()),
            ));
        }
        assert!(max_pitch > 89.0, "{max_pitch}");
        assert!(max_pq > 50.0, "{max_pq}");
    }

    /// Gravity and the magnetic field rotate into the body frame: pitched up 90 deg the
    /// accelerometers read (-1, 0, 0) g; rolled 90 deg, (0, 1, 0) g; at yaw 90 deg, pitch 30
    /// deg the A1's magnetometer reads R^T (0.25, 0, 0.4) G = (-0.4 sin 30, -0.25, 0.4 cos 30)
    /// = (-0.2, -0.25, 0.3464) G. Byte offsets of the fields from docs/NAV440-PROTOCOL.md (the
    /// payload starts at byte 5).
    #[test]
    fn gravity_and_field_rotate_into_the_body() {
        let field = |f: &[u8], off: usize| i16::from_be_bytes([f[5 + off], f[6 + off]]);
        let accel = |f: &[u8]| [12, 14, 16].map(|o| f64::from(field(f, o)) * ACCEL_LSB_G);
        let close =
            |a: [f64; 3], b: [f64; 3], tol: f64| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        let a2 = |angles| encode_attitude(PacketKind::A2, angles, [0.0; 3], 0, 0).unwrap();
        let g = accel(&a2([0.0, 90.0, 0.0]));
        assert!(close(g, [-1.0, 0.0, 0.0], ACCEL_LSB_G), "{g:?}");
        let g = accel(&a2([90.0, 0.0, 30.0]));
        assert!(close(g, [0.0, 1.0, 0.0], ACCEL_LSB_G), "{g:?}");
        let a1 = encode_attitude(PacketKind::A1, [0.0, 30.0, 90.0], [1.0, 2.0, 3.0], 0, 0).unwrap();
        let mag = [18, 20, 22].map(|o| f64::from(field(&a1, o)) * MAG_LSB_G);
        let want = [-0.2, -0.25, 0.4 * 3f64.sqrt() / 2.0];
        assert!(close(mag, want, MAG_LSB_G), "{mag:?}");
        let rates = [6, 8, 10].map(|o| f64::from(field(&a1, o)) * RATE_LSB_DEG_S);
        assert!(
            close(rates, [1.0, 2.0, 3.0], RATE_LSB_DEG_S / 2.0),
            "{rates:?}"
        );
    }

    #[test]
    fn angles_wrap_and_rates_saturate() {
        assert_eq!(angle_raw(180.0), -32768);
        assert_eq!(angle_raw(-180.0), -32768);
        assert_eq!(angle_raw(360.0 + 90.0), 16384);
        assert_eq!(angle_raw(-90.0 - 720.0), -16384);
        assert_eq!(sat_i16(1000.0, RATE_LSB_DEG_S), 32767);
        assert_eq!(sat_i16(-1000.0, RATE_LSB_DEG_S), -32768);
    }

    #[test]
    fn packet_counts_and_rates() {
        assert_eq!(packet_count(35.0, 100).unwrap(), 3501);
        assert_eq!(packet_count(10.0, 4).unwrap(), 41);
        assert_eq!(packet_count(0.0, 2).unwrap(), 1);
        assert!(packet_count(1.0, 3).is_err());
        assert!(packet_count(f64::NAN, 100).is_err());
        assert_eq!(packet_count(MAX_DURATION_S, 100).unwrap(), 1_000_001);
        assert!(packet_count(MAX_DURATION_S + 0.01, 100).is_err());
        assert!(packet_count(1e12, 100).is_err());
        for r in RATES_HZ {
            assert_eq!(1000 % period_ms(r).unwrap(), 0);
        }
    }

    /// `--yaw-noise 0.5@2`: the first 2 s are the clean capture's packets, byte for byte; after
    /// that the decoded yaw minus the clean one (wrapped) has mean ~0 and variance 0.5 deg^2
    /// (+ the quantisation's LSB^2/12, negligible) within 10 % (about 1,800 draws: the
    /// variance estimate's relative standard deviation is sqrt(2/1800) = 3.3 %), and the rate
    /// field is untouched.
    #[test]
    fn yaw_noise_switches_on_at_its_time() {
        let clean = SynthConfig {
            duration_s: 20.0,
            ..SynthConfig::default()
        };
        let noisy = SynthConfig {
            yaw_noise: vec!["0.5@2".parse().unwrap()],
            noise_seed: 5,
            ..clean.clone()
        };
        let (a, b) = (frames(&clean).unwrap(), frames(&noisy).unwrap());
        assert_eq!(a.len(), b.len());
        assert_eq!(
            a[..200],
            b[..200],
            "no noise before 2 s (packets 0..=199 at 100 Hz)"
        );
        let yaw = |f: &[u8]| f64::from(i16::from_be_bytes([f[9], f[10]])) * ANGLE_LSB_DEG;
        let rate = |f: &[u8]| i16::from_be_bytes([f[15], f[16]]);
        let d: Vec<f64> = a[200..]
            .iter()
            .zip(&b[200..])
            .map(|(x, y)| {
                assert_eq!(rate(x), rate(y));
                (yaw(y) - yaw(x) + 180.0).rem_euclid(360.0) - 180.0
            })
            .collect();
        let n = d.len() as f64;
        let mean = d.iter().sum::<f64>() / n;
        let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        assert!(mean.abs() < 0.05, "{mean}");
        assert!((var / 0.5 - 1.0).abs() < 0.1, "{var}");
    }

    #[test]
    fn noise_steps_parse_and_select() {
        let s: Vec<NoiseStep> = vec!["0.01".parse().unwrap(), "0.5@10".parse().unwrap()];
        assert_eq!(
            s[1],
            NoiseStep {
                var_deg2: 0.5,
                from_s: 10.0
            }
        );
        assert_eq!(noise_var_at(&s, 0.0), 0.01);
        assert_eq!(noise_var_at(&s, 9.99), 0.01);
        assert_eq!(noise_var_at(&s, 10.0), 0.5);
        assert_eq!(noise_var_at(&[], 3.0), 0.0);
        for bad in [
            "", "x", "-1", "0.5@", "0.5@-2", "nan", "0.1@inf", "1e16", "0.1@3e6",
        ] {
            assert!(bad.parse::<NoiseStep>().is_err(), "{bad}");
        }
    }

    #[test]
    fn itow_wraps_at_the_end_of_the_week() {
        let cfg = SynthConfig {
            duration_s: 0.05,
            start_itow_ms: MS_PER_WEEK - 20,
            ..SynthConfig::default()
        };
        let f = frames(&cfg).unwrap();
        let itow: Vec<u32> = f
            .iter()
            .map(|b| u32::from_be_bytes([b[29], b[30], b[31], b[32]]))
            .collect();
        assert_eq!(itow, vec![604_799_980, 604_799_990, 0, 10, 20, 30]);
    }
}
