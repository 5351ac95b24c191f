//! ItowClock: wraps, week rollover, duplicates and backward jumps.

use nav440_proto::clock::WEEK_MS;
use nav440_proto::{ItowClock, TimeStamp};

#[test]
fn first_sample_is_zero_and_steps_are_in_microseconds() {
    let mut c = ItowClock::new();
    assert_eq!(c.update(TimeStamp::Itow(123_456)), Some(0));
    assert_eq!(c.update(TimeStamp::Itow(123_466)), Some(10_000));
    assert_eq!(c.update(TimeStamp::Itow(124_456)), Some(1_000_000));
    assert_eq!(c.now_us(), 1_000_000);
}

#[test]
fn gpsitow_wraps_every_65536_ms() {
    let mut c = ItowClock::new();
    // 100 Hz samples across the U2 wrap: 65530, 65540 -> 4 (mod 65536), ...
    assert_eq!(c.update(TimeStamp::GpsItow(65_530)), Some(0));
    assert_eq!(c.update(TimeStamp::GpsItow(4)), Some(10_000));
    assert_eq!(c.update(TimeStamp::GpsItow(14)), Some(20_000));
    // Five minutes of 100 Hz samples: continuous, no jump at any of the 4+ wraps.
    let mut t: u32 = 65_530 + 20;
    let mut expected = 20_000u64;
    for _ in 0..30_000 {
        t += 10;
        expected += 10_000;
        assert_eq!(c.update(TimeStamp::GpsItow(t as u16)), Some(expected));
    }
}

#[test]
fn itow_rolls_over_at_the_week() {
    let mut c = ItowClock::new();
    assert_eq!(c.update(TimeStamp::Itow(WEEK_MS - 20)), Some(0));
    assert_eq!(c.update(TimeStamp::Itow(WEEK_MS - 10)), Some(10_000));
    assert_eq!(c.update(TimeStamp::Itow(0)), Some(20_000));
    assert_eq!(c.update(TimeStamp::Itow(10)), Some(30_000));
}

#[test]
fn duplicates_return_none_and_change_nothing() {
    let mut c = ItowClock::new();
    assert_eq!(c.update(TimeStamp::Itow(1000)), Some(0));
    assert_eq!(c.update(TimeStamp::Itow(1000)), None);
    assert_eq!(c.update(TimeStamp::Itow(1010)), Some(10_000));
    assert_eq!(c.update(TimeStamp::None), None);
    assert_eq!(c.update(TimeStamp::Itow(1020)), Some(20_000));
}

#[test]
fn backward_jump_is_dropped_and_starts_a_new_epoch() {
    let mut c = ItowClock::new();
    assert_eq!(c.update(TimeStamp::Itow(50_000)), Some(0));
    assert_eq!(c.update(TimeStamp::Itow(50_010)), Some(10_000));
    // The unit's clock jumps back by 40 s: that sample is dropped ...
    assert_eq!(c.update(TimeStamp::Itow(10_010)), None);
    // ... and time continues forward from it without going backwards.
    assert_eq!(c.update(TimeStamp::Itow(10_020)), Some(20_000));
    assert_eq!(c.update(TimeStamp::Itow(10_030)), Some(30_000));
    // GPSITOW: a step of >= 32.768 s is taken as backwards.
    let mut g = ItowClock::new();
    assert_eq!(g.update(TimeStamp::GpsItow(1000)), Some(0));
    assert_eq!(g.update(TimeStamp::GpsItow(1000 + 32_768)), None);
    assert_eq!(g.update(TimeStamp::GpsItow(1000 + 32_778)), Some(10_000));
}

#[test]
fn large_forward_gap_passes_through() {
    let mut c = ItowClock::new();
    assert_eq!(c.update(TimeStamp::Itow(0)), Some(0));
    // A 2 s gap (dropped packets) is a real forward step; the estimators handle gaps.
    assert_eq!(c.update(TimeStamp::Itow(2000)), Some(2_000_000));
}

#[test]
fn impossible_itow_and_kind_switch_reanchor() {
    let mut c = ItowClock::new();
    assert_eq!(c.update(TimeStamp::Itow(100)), Some(0));
    assert_eq!(c.update(TimeStamp::Itow(WEEK_MS)), None);
    assert_eq!(c.update(TimeStamp::Itow(500)), None); // re-anchor, output stays continuous
    assert_eq!(c.update(TimeStamp::Itow(510)), Some(10_000));
    assert_eq!(c.update(TimeStamp::GpsItow(7)), None); // switch of time source
    assert_eq!(c.update(TimeStamp::GpsItow(17)), Some(20_000));
}
