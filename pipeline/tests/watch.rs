//! The stream watchdog (`nav440_pipeline::watch`): each fault reported once, at the frame
//! (or the poll) where the limits of the module doc are reached, and nothing on a clean
//! stream. Frames are encoded with the protocol crate (`A2Fields::encode`); the expected
//! frame counts and times follow from the documented limits (25 nominal periods, 500 ms,
//! 10 s of stream).

use nav440_pipeline::watch::{Event, StreamWatch};
use nav440_proto::{A2Fields, PacketRate, PacketType, MAX_FRAME};

/// An A2 frame stamped `itow_ms`.
fn a2(itow_ms: u32) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = A2Fields {
        time_itow: itow_ms,
        ..Default::default()
    }
    .encode(&mut buf)
    .unwrap();
    buf[..n].to_vec()
}

/// Feeds frames stamped `stamps` one at a time at 10 ms intervals from `t0_ms`; returns the
/// events with the index of the frame that raised them.
fn run(w: &mut StreamWatch, stamps: &[u32], t0_ms: u32) -> Vec<(usize, Event)> {
    let mut out = Vec::new();
    for (i, s) in stamps.iter().enumerate() {
        w.feed(&a2(*s), t0_ms + 10 * i as u32, |e| out.push((i, e)));
    }
    out
}

fn watch_100hz() -> StreamWatch {
    StreamWatch::new(PacketType::A2, PacketRate::Hz100, 0)
}

#[test]
fn a_clean_stream_reports_only_the_periodic_counters() {
    let mut w = watch_100hz();
    let stamps: Vec<u32> = (0..2500).map(|k| 1_000 + 10 * k).collect();
    let ev = run(&mut w, &stamps, 0);
    // Every 10 s of stream = 1,000 frames at 100 Hz.
    assert_eq!(
        ev,
        vec![
            (999, Event::Periodic { stream_s: 10 }),
            (1999, Event::Periodic { stream_s: 20 })
        ]
    );
    assert_eq!(w.poll(24_990 + 499), None);
}

#[test]
fn silence_is_reported_once_after_the_limit() {
    let mut w = watch_100hz();
    assert_eq!(w.silence_limit_ms(), 500, "max(500 ms, 25 x 10 ms)");
    run(&mut w, &[0, 10, 20], 0);
    // The last frame came at 20 ms.
    assert_eq!(w.poll(519), None);
    assert_eq!(
        w.poll(520),
        Some(Event::Silence {
            silent_ms: 500,
            limit_ms: 500
        })
    );
    assert_eq!(w.poll(5_000), None, "once per silence");
    // A frame ends the silence; the next one is reported again.
    w.feed(&a2(30), 6_000, |_| {});
    assert_eq!(w.poll(6_499), None);
    assert!(matches!(w.poll(6_500), Some(Event::Silence { .. })));
    // At 2 Hz the limit is 25 periods: 12.5 s.
    assert_eq!(
        StreamWatch::new(PacketType::A2, PacketRate::Hz2, 0).silence_limit_ms(),
        12_500
    );
}

#[test]
fn frozen_stamps_are_reported_at_the_25th_frame_and_when_they_move_again() {
    let mut w = watch_100hz();
    // 20 good frames, then 40 frames all stamped 200, then good again.
    let mut stamps: Vec<u32> = (0..20).map(|k| 10 * k).collect();
    stamps.extend(std::iter::repeat_n(200, 40));
    stamps.extend((0..5).map(|k| 210 + 10 * k));
    let ev = run(&mut w, &stamps, 0);
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
    // A run of 24 is not reported.
    let mut w = watch_100hz();
    let mut stamps: Vec<u32> = vec![0];
    stamps.extend(std::iter::repeat_n(10, 24));
    stamps.push(20);
    assert_eq!(run(&mut w, &stamps, 0), vec![]);
}

#[test]
fn another_rate_is_reported_once_with_both_values() {
    // 200 Hz (5 ms stamps) while 100 Hz was configured.
    let mut w = watch_100hz();
    let stamps: Vec<u32> = (0..100).map(|k| 5 * k).collect();
    let ev = run(&mut w, &stamps, 0);
    // The 16th stamp completes the measurement.
    assert_eq!(
        ev,
        vec![(
            15,
            Event::RateMismatch {
                measured_hz: 200.0,
                configured_hz: 100.0
            }
        )]
    );
    // 10 % off (11 ms) is within the tolerance.
    let mut w = watch_100hz();
    let stamps: Vec<u32> = (0..100).map(|k| 11 * k).collect();
    assert_eq!(run(&mut w, &stamps, 0), vec![]);
}

#[test]
fn another_type_is_reported_once_with_both_types() {
    let mut w = watch_100hz();
    let mut buf = [0u8; MAX_FRAME];
    let n = nav440_proto::encode_frame(PacketType::S1, &[0u8; 24], &mut buf).unwrap();
    let mut ev = Vec::new();
    for _ in 0..3 {
        w.feed(&buf[..n], 0, |e| ev.push(e));
    }
    assert_eq!(
        ev,
        vec![Event::ForeignType {
            got: PacketType::S1,
            configured: PacketType::A2
        }]
    );
}
