//! The stream watchdog (`nav440_pipeline::watch`) fed by the pipeline's own parse
//! (`Pipeline::watch`, `Pipeline::feed_watched`, `Pipeline::poll_watch`): each fault reported
//! once, at the frame (or the poll) where the limits of the module doc are reached, nothing on
//! a clean stream, and the rows the same as without the watch. Frames are encoded with the
//! protocol crate (`A2Fields::encode`); the expected frame counts and times follow from the
//! documented limits (25 nominal periods, 500 ms, 10 s of stream).

use estimators::{BankConfig, ConfigError, ProductBank};
use nav440_pipeline::watch::Event;
use nav440_pipeline::{axis_bank, Axes, Axis, Pipeline};
use nav440_proto::{A2Fields, PacketRate, PacketType, MAX_FRAME};

type Bank = ProductBank<f32>;
type Build = fn(Axis, &BankConfig) -> Result<Bank, ConfigError>;
type Pipe = Pipeline<Bank, ConfigError, Build>;

/// The yaw axis's product bank.
fn build(axis: Axis, cfg: &BankConfig) -> Result<Bank, ConfigError> {
    axis_bank(axis, cfg)
}

fn pipe() -> Pipe {
    Pipeline::new(Axes::only(Axis::Yaw), BankConfig::NAV440, build as Build)
}

/// A pipeline whose watch is armed at 0 ms for A2 at 100 Hz.
fn watched_100hz() -> Pipe {
    let mut p = pipe();
    p.watch(PacketType::A2, PacketRate::Hz100, 0);
    p
}

/// An A2 frame stamped `itow_ms`, yaw 0.1 deg per ms of stamp.
fn a2(itow_ms: u32) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = A2Fields {
        time_itow: itow_ms,
        yaw_true: (itow_ms % 3600) as i16,
        ..Default::default()
    }
    .encode(&mut buf)
    .unwrap();
    buf[..n].to_vec()
}

/// Feeds frames stamped `stamps` one at a time at 10 ms intervals from `t0_ms`; returns the
/// events with the index of the frame that raised them.
fn run(p: &mut Pipe, stamps: &[u32], t0_ms: u32) -> Vec<(usize, Event)> {
    let mut out = Vec::new();
    for (i, s) in stamps.iter().enumerate() {
        p.feed_watched(&a2(*s), t0_ms + 10 * i as u32, &mut |_| {}, &mut |e| {
            out.push((i, e))
        })
        .unwrap();
    }
    out
}

#[test]
fn a_clean_stream_reports_only_the_periodic_counters() {
    let mut p = watched_100hz();
    let stamps: Vec<u32> = (0..2500).map(|k| 1_000 + 10 * k).collect();
    let ev = run(&mut p, &stamps, 0);
    // Every 10 s of stream = 1,000 frames at 100 Hz.
    assert_eq!(
        ev,
        vec![
            (999, Event::Periodic { stream_s: 10 }),
            (1999, Event::Periodic { stream_s: 20 })
        ]
    );
    assert_eq!(p.poll_watch(24_990 + 499), None);
    assert_eq!(p.stream_watch().map(|w| w.frames()), Some(2500));
}

#[test]
fn the_periodic_counters_continue_across_a_new_configuration() {
    let mut p = watched_100hz();
    let stamps: Vec<u32> = (0..600).map(|k| 1_000 + 10 * k).collect();
    assert_eq!(run(&mut p, &stamps, 0), vec![]);
    // Configured again at 7 s: 400 more frames complete the first 10 s of stream.
    p.watch(PacketType::A2, PacketRate::Hz100, 7_000);
    let stamps: Vec<u32> = (0..400).map(|k| 8_000 + 10 * k).collect();
    assert_eq!(
        run(&mut p, &stamps, 7_000),
        vec![(399, Event::Periodic { stream_s: 10 })]
    );
}

#[test]
fn the_watch_leaves_the_rows_unchanged() {
    // Frozen stamps, then a clean stream: the rows with the watch are the rows without it.
    let mut stamps: Vec<u32> = (0..40).map(|k| 10 * k).collect();
    stamps.extend(std::iter::repeat_n(400, 30));
    stamps.extend((0..100).map(|k| 410 + 10 * k));
    let bytes: Vec<u8> = stamps.iter().flat_map(|s| a2(*s)).collect();
    let mut plain = Vec::new();
    pipe().feed(&bytes, &mut |r| plain.push(*r)).unwrap();
    let mut watched = Vec::new();
    let mut events = 0;
    watched_100hz()
        .feed_watched(&bytes, 0, &mut |r| watched.push(*r), &mut |_| events += 1)
        .unwrap();
    assert_eq!(events, 2, "frozen, then thawed");
    // One row per distinct stamp: 40 + 1 + 100 (the repeats are duplicates).
    assert_eq!(plain.len(), 141);
    assert_eq!(watched, plain);
}

#[test]
fn silence_is_reported_once_after_the_limit() {
    let mut p = watched_100hz();
    assert_eq!(
        p.stream_watch().map(|w| w.silence_limit_ms()),
        Some(500),
        "max(500 ms, 25 x 10 ms)"
    );
    run(&mut p, &[0, 10, 20], 0);
    // The last frame came at 20 ms.
    assert_eq!(p.poll_watch(519), None);
    assert_eq!(
        p.poll_watch(520),
        Some(Event::Silence {
            silent_ms: 500,
            limit_ms: 500
        })
    );
    assert_eq!(p.poll_watch(5_000), None, "once per silence");
    // A frame ends the silence; the next one is reported again.
    p.feed_watched(&a2(30), 6_000, &mut |_| {}, &mut |_| {})
        .unwrap();
    assert_eq!(p.poll_watch(6_499), None);
    assert!(matches!(p.poll_watch(6_500), Some(Event::Silence { .. })));
    // Bytes without a complete frame do not end it: half a frame at 7 s.
    let half = a2(40);
    p.feed_watched(&half[..10], 7_000, &mut |_| {}, &mut |_| {})
        .unwrap();
    p.feed_watched(&half[10..], 7_100, &mut |_| {}, &mut |_| {})
        .unwrap();
    assert_eq!(p.poll_watch(7_599), None, "the frame completed at 7,100 ms");
    assert!(matches!(p.poll_watch(7_600), Some(Event::Silence { .. })));
    // At 2 Hz the limit is 25 periods: 12.5 s.
    let mut slow = pipe();
    slow.watch(PacketType::A2, PacketRate::Hz2, 0);
    assert_eq!(
        slow.stream_watch().map(|w| w.silence_limit_ms()),
        Some(12_500)
    );
    assert_eq!(slow.poll_watch(12_499), None);
    assert!(matches!(
        slow.poll_watch(12_500),
        Some(Event::Silence { .. })
    ));
}

#[test]
fn without_a_watch_nothing_is_reported() {
    let mut p = pipe();
    assert!(p.stream_watch().is_none());
    let mut events = 0;
    for k in 0..50u32 {
        p.feed_watched(&a2(5 * k), 0, &mut |_| {}, &mut |_| events += 1)
            .unwrap();
    }
    assert_eq!(events, 0);
    assert_eq!(p.poll_watch(1_000_000), None);
}

#[test]
fn frozen_stamps_are_reported_at_the_25th_frame_and_when_they_move_again() {
    let mut p = watched_100hz();
    // 20 good frames, then 40 frames all stamped 200, then good again.
    let mut stamps: Vec<u32> = (0..20).map(|k| 10 * k).collect();
    stamps.extend(std::iter::repeat_n(200, 40));
    stamps.extend((0..5).map(|k| 210 + 10 * k));
    let ev = run(&mut p, &stamps, 0);
    // Frame 20 is the first with stamp 200; frame 44 is the 25th in the run.
    assert_eq!(
        ev,
        vec![
            (
                44,
                Event::Frozen {
                    frames: 25,
                    stamp_ms: 200
                }
            ),
            (60, Event::Thawed { frames: 40 }),
        ]
    );
    // The pipeline dropped the 39 repeats (counted as duplicates).
    assert_eq!(p.front().time_faults().duplicates, 39);
    // A run of 24 is not reported.
    let mut p = watched_100hz();
    let mut stamps: Vec<u32> = vec![0];
    stamps.extend(std::iter::repeat_n(10, 24));
    stamps.push(20);
    assert_eq!(run(&mut p, &stamps, 0), vec![]);
}

#[test]
fn another_rate_is_reported_once_with_both_values() {
    // 200 Hz (5 ms stamps) while 100 Hz was configured.
    let mut p = watched_100hz();
    let stamps: Vec<u32> = (0..100).map(|k| 5 * k).collect();
    let ev = run(&mut p, &stamps, 0);
    // The 16th stamp completes the measurement.
    assert_eq!(
        ev,
        vec![(
            15,
            Event::RateMismatch {
                measured_us: 5_000,
                configured_us: 10_000
            }
        )]
    );
    // The banks run at the measured period, as without the watch.
    assert_eq!(p.estimation().period_s(), Some(0.005));
    assert_eq!(p.estimation().period_us(), Some(5_000));
    // 10 % off (11 ms) and 20 % off (12 ms, the tolerance itself) are within the tolerance;
    // 30 % (13 ms) is not.
    for (ms, reported) in [(11, false), (12, false), (13, true), (8, false), (7, true)] {
        let mut p = watched_100hz();
        let stamps: Vec<u32> = (0..100).map(|k| ms * k).collect();
        let want = reported.then_some((
            15,
            Event::RateMismatch {
                measured_us: ms * 1000,
                configured_us: 10_000,
            },
        ));
        assert_eq!(
            run(&mut p, &stamps, 0),
            want.into_iter().collect::<Vec<_>>(),
            "{ms} ms"
        );
    }
}

#[test]
fn another_type_is_reported_once_with_both_types() {
    let mut p = watched_100hz();
    let mut buf = [0u8; MAX_FRAME];
    let n = nav440_proto::encode_frame(PacketType::S1, &[0u8; 24], &mut buf).unwrap();
    let mut ev = Vec::new();
    for _ in 0..3 {
        p.feed_watched(&buf[..n], 0, &mut |_| {}, &mut |e| ev.push(e))
            .unwrap();
    }
    assert_eq!(
        ev,
        vec![Event::ForeignType {
            got: PacketType::S1,
            configured: PacketType::A2
        }]
    );
    assert_eq!(p.front().parser_stats().frames, 3);
    // S1 frames are frames: no silence until 500 ms after the last one.
    assert_eq!(p.poll_watch(499), None);
}
