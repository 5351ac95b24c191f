//! The captures the firmware commands run: the bundled ones (`host-tests/data`) and those CI
//! synthesises or derives from them.

use super::nav440_cli::nav440_synth;
use super::{read_file, root, work_dir};
use std::path::{Path, PathBuf};

/// The `.bin` captures of `host-tests/data`, sorted.
pub(super) fn data_captures() -> Vec<PathBuf> {
    let data = root().join("host-tests").join("data");
    let mut bins: Vec<PathBuf> = std::fs::read_dir(&data)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "bin"))
                .collect()
        })
        .unwrap_or_default();
    bins.sort();
    bins
}

/// The bundled Fig. 5-like capture: `host-tests/data/*fig5*.bin` (else any `.bin` there);
/// if the data directory has none, one is synthesised with `nav440 synth --profile fig5`.
pub(super) fn bundled_capture() -> Result<PathBuf, String> {
    let data = root().join("host-tests").join("data");
    let bins = data_captures();
    if let Some(p) = bins
        .iter()
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().contains("fig5"))
        })
        .or(bins.first())
    {
        return Ok(p.clone());
    }
    let out = work_dir()?.join("fig5-synth.bin");
    eprintln!(
        "xtask: no capture in {}, synthesising one with `nav440 synth`",
        data.display()
    );
    nav440_synth(&out, &["--profile", "fig5"])?;
    Ok(out)
}

/// A bundled capture at 20 Hz (the adaptive firmware's schedule is tuned at 100 Hz).
pub(super) const SPIN_20HZ: &str = "host-tests/data/spin_n1_20hz.bin";

/// Synthesises (with `nav440 synth`) a capture of 20 packets at 100 Hz (0 to 190 ms) followed
/// by 50 packets at 50 Hz (210 to 1190 ms), and returns its path.
pub(super) fn rate_change_capture() -> Result<PathBuf, String> {
    let dir = work_dir()?;
    let mut bytes = Vec::new();
    // (file, rate Hz, duration s, timeITOW of the first packet ms)
    for (name, rate, duration, itow) in [
        ("ci-rate-100hz.bin", "100", "0.19", "100000"),
        ("ci-rate-50hz.bin", "50", "0.98", "100210"),
    ] {
        let part = dir.join(name);
        nav440_synth(
            &part,
            &[
                "--profile",
                "sin5",
                "--rate",
                rate,
                "--duration",
                duration,
                "--start-itow",
                itow,
            ],
        )?;
        bytes.extend(read_file(&part)?);
    }
    let out = dir.join("ci-rate-change.bin");
    std::fs::write(&out, &bytes).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(out)
}

/// What the firmware prints when a new time epoch comes at another packet rate
/// (firmware-example's `main.rs`): the pipeline measured the period again and rebuilt the banks.
pub(super) const PERIOD_CHANGE: &str = "firmware: new time epoch at another packet rate";

/// Writes `TAG-rate-drop.bin` (each caller its own tag: the files of one are read by running
/// jobs while another writes): 10 s of the `fig5` motion at 100 Hz, 10 s at 50 Hz in the same
/// epoch (the rate halves after the warm-up), then 10 s at 20 Hz whose time stamps start over
/// (a unit reset at a fifth of the first rate): 1,703 rows. Every estimate stays bounded and
/// the new epoch's period is measured again (`host-tests/tests/rate_change.rs`
/// checks the same capture on the host).
pub(super) fn rate_drop_capture(tag: &str) -> Result<PathBuf, String> {
    let dir = work_dir()?;
    let mut bytes = Vec::new();
    // (file, rate Hz, timeITOW of the first packet ms): the 50 Hz part starts 20 ms after the
    // last 100 Hz packet; the 20 Hz part at the first part's start (time goes back: a reset).
    for (rate, itow) in [
        ("100", "208800000"),
        ("50", "208810020"),
        ("20", "208800000"),
    ] {
        let part = dir.join(format!("{tag}-drop-{rate}hz.bin"));
        nav440_synth(
            &part,
            &[
                "--profile",
                "fig5",
                "--rate",
                rate,
                "--duration",
                "10",
                "--start-itow",
                itow,
            ],
        )?;
        bytes.extend(read_file(&part)?);
    }
    let out = dir.join(format!("{tag}-rate-drop.bin"));
    std::fs::write(&out, &bytes).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(out)
}

/// The packet period of [`off_rate_capture`], ms: 30 ms (33.3 Hz), not one of the NAV440's
/// rates (100 Hz / 1, 2, 4, 5, 10, 20, 25, 50).
pub(super) const OFF_RATE_MS: u32 = 30;

/// What the product firmware prints when its table of banks built on the host has none for
/// the measured packet period (`estimators::ConfigError::SamplePeriodNotPrebuilt`, through
/// firmware-example's `bank_failed`).
pub(super) const NOT_PREBUILT: &str = "SamplePeriodNotPrebuilt";

/// Writes `ci-off-rate.bin`: 100 A2 packets [`OFF_RATE_MS`] apart (a unit turning at 30
/// deg/s), a packet period the product images' table of banks does not hold.
pub(super) fn off_rate_capture() -> Result<PathBuf, String> {
    let mut out = Vec::new();
    for k in 0..100u32 {
        let t_ms = k * OFF_RATE_MS;
        let yaw_deg = 30.0 * f64::from(t_ms) * 1e-3;
        let fields = nav440_proto::A2Fields {
            // 2^16 LSB per turn; 30 deg/s at 1260/2^16 deg/s per LSB.
            yaw_true: (yaw_deg * 65536.0 / 360.0).round() as i16,
            rate_z: (30.0 * 65536.0 / 1260.0f64).round() as i16,
            time_itow: 100_000 + t_ms,
            ..Default::default()
        };
        let mut buf = [0u8; nav440_proto::MAX_FRAME];
        let n = fields
            .encode(&mut buf)
            .map_err(|e| format!("cannot encode an A2 frame: {e:?}"))?;
        out.extend_from_slice(buf.get(..n).unwrap_or_default());
    }
    let path = work_dir()?.join("ci-off-rate.bin");
    std::fs::write(&path, &out).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}

/// Packets (frame indices) of the bundled A2 capture whose BIT word becomes 0x0009
/// (masterFail + softwareError) in the BIT-failure capture of `ci-firmware`.
pub(super) const BIT_FAILED_FRAMES: std::ops::RangeInclusive<usize> = 1000..=1100;

/// Writes `ci-bit-fail.bin`: `bundled` (an A2 capture) with the BIT word of the frames
/// [`BIT_FAILED_FRAMES`] set to 0x0009, re-encoded (valid CRC). The firmware must drop and
/// count those samples (`bit_failed=101`) and print the same CSV as `nav440 estimate`.
pub(super) fn bit_fail_capture(bundled: &Path) -> Result<PathBuf, String> {
    use nav440_proto::{encode_frame, PacketType, Parser, A2};
    let bytes = read_file(bundled)?;
    let mut out = Vec::with_capacity(bytes.len());
    let mut parser = Parser::new();
    let (mut k, mut failed) = (0usize, 0usize);
    let mut err = None;
    parser.feed(&bytes, |f| {
        let mut payload = f.payload.to_vec();
        if BIT_FAILED_FRAMES.contains(&k) && f.packet_type == PacketType::A2 {
            if let Ok(view) = A2::new(f.payload) {
                let mut fields = view.fields();
                fields.bit = 0x0009;
                payload = fields.payload().to_vec();
                failed += 1;
            }
        }
        k += 1;
        let mut buf = [0u8; 512];
        match encode_frame(f.packet_type, &payload, &mut buf) {
            Ok(n) => out.extend_from_slice(buf.get(..n).unwrap_or_default()),
            Err(e) => err = Some(format!("cannot re-encode frame {k}: {e:?}")),
        }
    });
    if let Some(e) = err {
        return Err(e);
    }
    if failed != BIT_FAILED_FRAMES.clone().count() {
        return Err(format!(
            "{} is not an A2 capture of at least {} frames",
            bundled.display(),
            BIT_FAILED_FRAMES.end() + 1
        ));
    }
    let path = work_dir()?.join("ci-bit-fail.bin");
    std::fs::write(&path, &out).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}

/// The false frame header that [`false_header_capture`] inserts: `55 55 'A' '2'` announcing
/// 200 payload bytes.
pub(super) const FALSE_HEADER: [u8; 5] = [0x55, 0x55, b'A', b'2', 200];

/// Writes `ci-false-header.bin`: `bundled` with [`FALSE_HEADER`] inserted before its last two
/// frames. At the end of the input the parser resolves the held candidate: both frames are
/// recovered (the CSV equals the bundled capture's) and the 5 bytes are reported
/// (`end_dropped=5`).
pub(super) fn false_header_capture(bundled: &Path) -> Result<PathBuf, String> {
    use nav440_proto::Parser;
    let bytes = read_file(bundled)?;
    let mut ends = Vec::new();
    let mut parser = Parser::new();
    let base = bytes.as_ptr() as usize;
    parser.feed(&bytes, |f| {
        ends.push(f.payload.as_ptr() as usize - base + f.payload.len() + 2);
    });
    let at = match ends.len().checked_sub(3).and_then(|i| ends.get(i)) {
        Some(&at) if ends.last() == Some(&bytes.len()) => at,
        _ => {
            return Err(format!(
                "{} does not end on a frame boundary after at least 3 frames",
                bundled.display()
            ))
        }
    };
    let mut out = bytes.get(..at).unwrap_or_default().to_vec();
    out.extend_from_slice(&FALSE_HEADER);
    out.extend_from_slice(bytes.get(at..).unwrap_or_default());
    let path = work_dir()?.join("ci-false-header.bin");
    std::fs::write(&path, &out).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path)
}
