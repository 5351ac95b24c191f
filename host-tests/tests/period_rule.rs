//! The nominal sample period of the bank (`BankConfig::sample_period_s`) is decided by one
//! causal rule, `nav440_pipeline::period`, in `nav440 estimate` and in the firmware: the first
//! `WARMUP_SAMPLES` samples, never the rest of the capture. A capture whose packet rate changes
//! after its first 16 packets (20 packets at 100 Hz, then 50 at 50 Hz) shows the host replay
//! builds exactly the bank the firmware builds after its warm-up.

use estimators::{BankConfig, PaperBank};
use nav440_cli::replay::{self, Axis, EstimateOptions};
use nav440_pipeline::period::{PeriodEstimator, WARMUP_SAMPLES};
use nav440_proto::A2Fields;

/// Packet times, ms from the first: 20 at 10 ms, then 50 at 20 ms.
fn times_ms() -> Vec<u32> {
    let fast = (0..20u32).map(|k| k * 10);
    let slow = (1..=50u32).map(|j| 190 + j * 20);
    fast.chain(slow).collect()
}

/// An A2 stream of a unit turning at 30 deg/s, one packet per time of [`times_ms`].
fn capture() -> Vec<u8> {
    let mut bytes = Vec::new();
    for t_ms in times_ms() {
        let yaw_deg = 30.0 * f64::from(t_ms) * 1e-3;
        let fields = A2Fields {
            // 2^16 LSB per turn; 30 deg/s at 1260/2^16 deg/s per LSB.
            yaw_true: (yaw_deg * 65536.0 / 360.0).round() as i16,
            rate_z: (30.0 * 65536.0 / 1260.0f64).round() as i16,
            time_itow: 100_000 + t_ms,
            ..Default::default()
        };
        let mut buf = [0u8; nav440_proto::MAX_FRAME];
        let n = fields.encode(&mut buf).unwrap();
        bytes.extend_from_slice(&buf[..n]);
    }
    bytes
}

#[test]
fn rate_change_after_the_warm_up_keeps_the_warm_up_period() {
    let bytes = capture();
    let samples = replay::samples(&bytes).unwrap();
    assert_eq!(samples.len(), 70);
    let t_us: Vec<u64> = samples.iter().map(|s| s.t_us).collect();
    let want_us: Vec<u64> = times_ms().iter().map(|&t| u64::from(t) * 1000).collect();
    assert_eq!(t_us, want_us);

    // What the whole capture would say: 19 intervals of 10 ms, then 190 -> 210 ms and 49 more
    // of 20 ms, so its median interval is 20 ms. The first 16 samples have 15 of 10 ms.
    let long = t_us.windows(2).filter(|w| w[1] - w[0] == 20_000).count();
    assert_eq!(long, 50);
    assert!(long > (t_us.len() - 1) / 2);

    // The host's configuration: period 0.01 s.
    let opts = EstimateOptions::default();
    let host = opts.bank_config_for(&samples);
    assert!((host.sample_period_s - 0.01).abs() < 1e-9);
    assert_eq!(host.sample_period_s, 10_000.0f32 * 1e-6);

    // The firmware's: it holds back its first WARMUP_SAMPLES samples and applies the same
    // rule to their times on top of `BankConfig::NAV440` (what the host options give).
    assert_eq!(WARMUP_SAMPLES, 16);
    assert_eq!(opts.bank_config(), BankConfig::NAV440);
    let mut est = PeriodEstimator::new();
    for s in &samples {
        if !est.push(s.t_us) {
            break;
        }
    }
    assert!(est.is_complete());
    let firmware = est.apply(BankConfig::NAV440);
    assert_eq!(host, firmware);

    // `nav440 estimate`: one row per packet, from a bank built for 0.01 s.
    let (rows, rejected) = replay::estimate(&samples, &opts).unwrap();
    assert_eq!((rows.len(), rejected), (70, 0));
    let mut bank = PaperBank::<f32>::new(&firmware).unwrap();
    for (row, s) in rows.iter().zip(&samples) {
        assert_eq!(row.t_us, s.t_us);
        assert_eq!(
            row.axis(Axis::Yaw).unwrap().out,
            bank.update(s.t_us, s.angle(Axis::Yaw)).unwrap()
        );
    }
    // ... which matters: a bank built for the whole capture's 20 ms gives other rows.
    let mut slow = PaperBank::<f32>::new(&BankConfig {
        sample_period_s: 0.02,
        ..firmware
    })
    .unwrap();
    let differs = samples.iter().zip(&rows).any(|(s, row)| {
        slow.update(s.t_us, s.angle(Axis::Yaw)).unwrap() != row.axis(Axis::Yaw).unwrap().out
    });
    assert!(differs);

    // The CSV text: header plus one line per packet.
    let (csv, rejected) = replay::estimate_csv(&bytes, &opts).unwrap();
    assert_eq!(rejected, 0);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 71);
    assert_eq!(lines[0], replay::CSV_HEADER);
    // The last row is at 1.19 s.
    assert!(lines[70].starts_with("1.1900,"), "{}", lines[70]);
}

#[test]
fn capture_shorter_than_the_warm_up_uses_its_intervals() {
    // The first 10 packets only (all 10 ms apart): period 0.01 s; a single packet keeps the
    // configured period.
    let bytes = capture();
    let samples = replay::samples(&bytes).unwrap();
    let opts = EstimateOptions::default();
    let short = &samples[..10];
    let cfg = opts.bank_config_for(short);
    assert_eq!(cfg.sample_period_s, 10_000.0f32 * 1e-6);
    let one = opts.bank_config_for(&samples[..1]);
    assert_eq!(one.sample_period_s, BankConfig::default().sample_period_s);
    let (rows, rejected) = replay::estimate(short, &opts).unwrap();
    assert_eq!((rows.len(), rejected), (10, 0));
}
