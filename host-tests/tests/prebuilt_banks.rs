//! A product bank read back from its words (`Bank::put_words`, `Bank::from_words`: the table of
//! banks the product firmware images carry, built by `firmware-example/build.rs` on the host,
//! each word a postcard varint) is the bank `Bank::new` builds: the same parameters and state, and bit for bit the same outputs on a
//! stream with turns, a gap and a rate change. Checked for every NAV440 packet rate, both
//! kinds of axis (wrapping at +-180 deg or not), in `Fx` and in `f32`. The table holds the
//! wrapping axes' banks only: one read back and switched to `Wrap::None` (`Bank::set_wrap`)
//! is the bank built for pitch.

use estimators::words::Words;
use estimators::{BankConfig, Fx, ProductBank, Real};
use nav440_pipeline::period::{PeriodEstimator, WARMUP_SAMPLES};
use nav440_pipeline::{axis_bank, Axis};

/// The dividers of the NAV440's packet rates (100 Hz / divider), `nav440_proto::PacketRate`.
fn dividers() -> impl Iterator<Item = u16> {
    (1..=50u16).filter(|&d| {
        nav440_proto::PacketRate::from_divider(d)
            .is_some_and(|r| r != nav440_proto::PacketRate::Quiet)
    })
}

/// The shipped preset for the period the firmware's warm-up measures at `divider`.
fn config(divider: u16) -> BankConfig {
    let period_us = 10_000 * u64::from(divider);
    PeriodEstimator::from_times((0..WARMUP_SAMPLES as u64).map(|k| k * period_us))
        .apply(BankConfig::NAV440)
        .with_nav440_gains()
}

/// A yaw turning at 400 deg/s (wrapping every 0.9 s), deg, at `t_us`.
fn turning_yaw(t_us: u64) -> f32 {
    let unwrapped = 400.0 * t_us as f64 * 1e-6 + 7.0 * (t_us as f64 * 3e-6).sin();
    ((unwrapped + 180.0).rem_euclid(360.0) - 180.0) as f32
}

/// Feeds both banks the same samples, `angle(t_us)` deg, and asserts equal outputs, bit for
/// bit: 300 packet periods, a gap of 30 periods, then twice the packet rate.
fn assert_same_run<T: Real>(
    a: &mut ProductBank<T>,
    b: &mut ProductBank<T>,
    period_us: u64,
    angle: impl Fn(u64) -> f32,
) {
    let mut t = 0u64;
    for k in 0..600u64 {
        t += if k == 300 {
            30 * period_us
        } else if k > 400 {
            period_us / 2
        } else {
            period_us
        };
        let y = angle(t);
        let (x, y) = (a.update(t, y), b.update(t, y));
        match (x, y) {
            (Ok(x), Ok(y)) => {
                // The outputs as the bank holds them (raw for `Fx`), then as `f32` bits.
                assert_eq!(x, y, "sample {k}");
                let (x, y) = (x.to_f32(), y.to_f32());
                let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&x.values), bits(&y.values), "sample {k}");
                assert_eq!(x.angle.0.to_bits(), y.angle.0.to_bits(), "sample {k}");
                assert_eq!(x.angle.1.to_bits(), y.angle.1.to_bits(), "sample {k}");
            }
            (x, y) => assert_eq!(x.map(|_| ()), y.map(|_| ()), "sample {k}"),
        }
    }
}

/// The bank's words.
fn words<T: Real + Words>(bank: &ProductBank<T>) -> Vec<i64> {
    let mut w = Vec::new();
    bank.put_words(&mut |x| w.push(x));
    w
}

/// The bank `words` give (`None`: refused).
fn read<T: Real + Words>(words: &[i64]) -> Option<ProductBank<T>> {
    let mut it = words.iter().copied();
    ProductBank::<T>::from_words(&mut || it.next())
}

/// A table entry as build.rs stores it: every word as a postcard `i64`.
fn table_bytes(words: &[i64]) -> Vec<u8> {
    words
        .iter()
        .flat_map(|w| postcard::to_stdvec(w).unwrap())
        .collect()
}

fn round_trip<T: Real + Words>() {
    for divider in dividers() {
        let cfg = config(divider);
        for axis in [Axis::Yaw, Axis::Pitch] {
            let built: ProductBank<T> = axis_bank(axis, &cfg).unwrap();
            let w = words(&built);
            let mut back: ProductBank<T> = read(&w).unwrap();
            assert_eq!(
                format!("{back:?}"),
                format!("{built:?}"),
                "{divider} {axis:?}"
            );
            // What a table entry costs in flash (build.rs stores one per rate).
            assert!(
                table_bytes(&w).len() <= 160,
                "{} bytes",
                table_bytes(&w).len()
            );
            // A word missing or one too many is refused.
            assert!(read::<T>(&w[..w.len() - 1]).is_none());
            let mut long = w.clone();
            long.push(0);
            assert!(read::<T>(&long).is_none());
            let mut fresh = built;
            assert_same_run(
                &mut fresh,
                &mut back,
                10_000 * u64::from(divider),
                turning_yaw,
            );
            // A bank that has run has the words of the bank built: its laws, not their state
            // (it reads back restarted, with no re-initialisation counted).
            assert!(fresh.reinit_count() > 0);
            assert_eq!(words(&fresh), w, "{divider} {axis:?}");
        }
    }
}

/// The bank of an axis that wraps, read back and switched to no unwrapping
/// (`Bank::set_wrap`, what the firmware does for pitch), is the bank built for pitch: the
/// same parameters, state and configuration, and bit for bit the same outputs on a pitch that
/// swings within +-90 deg with a gap and a rate change ([`assert_same_run`]).
fn set_wrap_is_the_pitch_bank<T: Real + Words>() {
    for divider in dividers() {
        let cfg = config(divider);
        let yaw: ProductBank<T> = axis_bank(Axis::Yaw, &cfg).unwrap();
        let mut pitch: ProductBank<T> = axis_bank(Axis::Pitch, &cfg).unwrap();
        let back: ProductBank<T> = read(&words(&yaw)).unwrap();
        let mut switched = back;
        switched.set_wrap(estimators::Wrap::None);
        assert_eq!(format!("{switched:?}"), format!("{pitch:?}"), "{divider}");
        assert_ne!(format!("{back:?}"), format!("{pitch:?}"), "{divider}");
        assert_same_run(
            &mut switched,
            &mut pitch,
            10_000 * u64::from(divider),
            |t| (85.0 * (t as f64 * 2e-6).sin()) as f32,
        );
    }
}

#[test]
fn fixed_point_banks_read_back_equal() {
    round_trip::<Fx>();
    set_wrap_is_the_pitch_bank::<Fx>();
}

#[test]
fn f32_banks_read_back_equal() {
    round_trip::<f32>();
    set_wrap_is_the_pitch_bank::<f32>();
}

#[test]
fn the_firmware_table_keys_are_the_period_rule_s() {
    // build.rs keys the table by the bits of `PeriodEstimator::period_s` over a steady stream;
    // the firmware looks up `BankConfig::sample_period_s`, which the pipeline sets from the
    // same rule (`PeriodEstimator::apply`). Both are `us as f32 * 1e-6`.
    for divider in dividers() {
        let us = 10_000 * u64::from(divider);
        assert_eq!(
            config(divider).sample_period_s.to_bits(),
            (us as f32 * 1e-6).to_bits()
        );
    }
}
