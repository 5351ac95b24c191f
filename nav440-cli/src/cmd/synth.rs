//! `nav440 synth`: a synthetic capture from a motion profile, optionally corrupted.

use std::path::PathBuf;

use crate::corrupt::Corruption;
use crate::error::{Error, Result};
use crate::motion::{self, Profile, ProfileKind};
use crate::progress::Progress;
use crate::synth;

/// Arguments of `nav440 synth`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Motion profile: fig5 (paper Fig. 5-like hand rotation), spin (many turns), sin5 (section 3.2),
    /// tumble (a hand-held unit nodding through pitch +-90 deg: three axes, gimbal lock), hand
    /// (strokes of 40-300 deg/s with pauses), fast-sine (2 Hz, 400 deg/s), violent (strokes to
    /// 600 deg/s and over 10,000 deg/s^2).
    #[arg(long, default_value = "fig5")]
    profile: ProfileKind,
    /// Packet type: A1, A2 or N1.
    #[arg(long = "packet", default_value = "A2")]
    packet: synth::PacketKind,
    /// Packet rate, Hz (100, 50, 25, 20, 10, 5, 4 or 2).
    #[arg(long, default_value_t = 100)]
    rate: u32,
    /// Duration, s (0 to 10000: the capture is built in memory).
    #[arg(long, default_value_t = 35.0)]
    duration: f64,
    /// Seed of the motion shape (fig5, hand, violent).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// timeITOW of the first packet, ms: a time of week (0 to 604799999).
    #[arg(long, default_value_t = synth::SynthConfig::default().start_itow_ms)]
    start_itow: u64,
    /// BIT word of every packet (e.g. 0x0002).
    #[arg(long, default_value = "0", value_parser = parse_u16)]
    bit: u16,
    /// Flip this many random bits (0 to 1000000).
    #[arg(long, default_value_t = 0)]
    flip_bits: usize,
    /// Delete this many random bytes (0 to 1000000).
    #[arg(long, default_value_t = 0)]
    drop_bytes: usize,
    /// Leave out this many random packets (0 to 1000000).
    #[arg(long, default_value_t = 0)]
    drop_packets: usize,
    /// Insert this many bursts of random bytes between packets (0 to 100000).
    #[arg(long, default_value_t = 0)]
    garbage: usize,
    /// Longest garbage burst, bytes (1 to 1024).
    #[arg(long, default_value_t = 32)]
    garbage_max_len: usize,
    /// Seed of the corruption.
    #[arg(long, default_value_t = 1)]
    corrupt_seed: u64,
    /// Gaussian noise added to the yaw angle: VAR (deg^2) from the start, or VAR@T from T s
    /// on; repeat for a noise level that changes (e.g. --yaw-noise 0.01 --yaw-noise 0.5@10).
    /// VAR 0 to 1e15, T 0 to 2592000 (30 days), at most 1000 steps.
    #[arg(long = "yaw-noise", value_name = "VAR[@T]")]
    yaw_noise: Vec<synth::NoiseStep>,
    /// Seed of the yaw noise.
    #[arg(long, default_value_t = 1)]
    noise_seed: u64,
    /// Output capture file (`-`: standard output; the JSON summary then goes to standard
    /// error).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
}

/// A 16-bit value, decimal or `0x` hexadecimal.
fn parse_u16(s: &str) -> std::result::Result<u16, String> {
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u16::from_str_radix(h, 16),
        None => s.parse(),
    };
    r.map_err(|_| format!("`{s}` is not a 16-bit value"))
}

/// The most events of each corruption kind (`--flip-bits`, `--drop-bytes`,
/// `--drop-packets`).
pub(crate) const MAX_CORRUPT_EVENTS: usize = 1_000_000;
/// The most garbage bursts (`--garbage`).
pub(crate) const MAX_GARBAGE_BURSTS: usize = 100_000;
/// The longest garbage burst (`--garbage-max-len`), bytes: with [`MAX_GARBAGE_BURSTS`] at most
/// 102.4 MB of garbage.
pub(crate) const MAX_GARBAGE_LEN: usize = 1024;

/// The most `--yaw-noise` steps (each packet looks them all up).
pub(crate) const MAX_NOISE_STEPS: usize = 1000;

/// Checks the corruption counts before any work (each a usage error naming its range).
fn check_corruption(a: &Args) -> Result<()> {
    use crate::limits::count;
    count("--flip-bits", a.flip_bits, 0..=MAX_CORRUPT_EVENTS, "")?;
    count("--drop-bytes", a.drop_bytes, 0..=MAX_CORRUPT_EVENTS, "")?;
    count("--drop-packets", a.drop_packets, 0..=MAX_CORRUPT_EVENTS, "")?;
    count("--garbage", a.garbage, 0..=MAX_GARBAGE_BURSTS, "")?;
    count(
        "--garbage-max-len",
        a.garbage_max_len,
        1..=MAX_GARBAGE_LEN,
        " bytes",
    )?;
    if a.yaw_noise.len() > MAX_NOISE_STEPS {
        return Err(Error::Usage(format!(
            "--yaw-noise must be given 0 to {MAX_NOISE_STEPS} times, got {}",
            a.yaw_noise.len()
        )));
    }
    Ok(())
}

/// Writes the capture to `-o` and prints its JSON summary (packets, intact packets, peaks).
pub fn run(a: Args) -> Result<()> {
    check_corruption(&a)?;
    // `-o -`: the capture on standard output, the summary on standard error.
    let to_stdout = crate::output::is_stdout(&a.output);
    crate::output::check_stdout()?;
    let cfg = synth::SynthConfig {
        profile: a.profile,
        seed: a.seed,
        duration_s: a.duration,
        rate_hz: a.rate,
        packet: a.packet,
        start_itow_ms: a.start_itow,
        bit: a.bit,
        corruption: Corruption {
            bit_flips: a.flip_bits,
            dropped_bytes: a.drop_bytes,
            dropped_packets: a.drop_packets,
            garbage_bursts: a.garbage,
            garbage_max_len: a.garbage_max_len,
            seed: a.corrupt_seed,
        },
        yaw_noise: a.yaw_noise,
        noise_seed: a.noise_seed,
    };
    // On a terminal: every motion sample and packet, of the capture then of the summary
    // (the profile's set-up again, peaks and RMS acceleration every 1 ms).
    let progress = match synth::packet_count(a.duration, a.rate) {
        Ok(packets) => {
            let setup = Profile::setup_samples(a.profile, a.duration);
            let sweep = motion::sample_count(a.duration, 1e-3);
            Progress::items("synth", packets as u64 + 2 * (setup + sweep), "samples")
        }
        Err(_) => Progress::hidden(),
    };
    let made = synth::generate_with(&cfg, &progress).map(|cap| {
        let motion = Profile::with_progress(a.profile, a.duration, a.seed, &progress);
        (cap, motion.peaks(1e-3), motion.rms_acc(1e-3))
    });
    progress.finish();
    let (cap, peaks, rms_acc) = made?;
    let output = a.output;
    crate::output::write_output(&output, &cap.bytes)?;
    let summary = serde_json::json!({
        "file": crate::output::output_name(&output),
        "bytes": cap.bytes.len(),
        "packets": cap.packets,
        "dropped_packets": cap.report.dropped.len(),
        "damaged_packets": cap.report.damaged.len(),
        "intact_packets": cap.report.intact(),
        "garbage_bytes": cap.report.garbage_bytes,
        "peak_yaw_deg": peaks.0,
        "peak_rate_deg_s": peaks.1,
        "peak_acc_deg_s2": peaks.2,
        "rms_acc_deg_s2": rms_acc,
    });
    if to_stdout {
        eprintln!("{summary}");
        return Ok(());
    }
    super::stdout_or_file(None, |w| writeln!(w, "{summary}"))
}
