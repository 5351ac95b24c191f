//! TimeBase: time faults (impossible, backward, forward, real jumps, dropouts), mixed time-stamp
//! kinds. Each case states the expected times from the stamps themselves.

use nav440_proto::clock::WEEK_MS;
use nav440_proto::{TimeBase, TimeStamp, Timed};

/// Runs stamps (payload = index) through a time base; returns (index, t_us, new_epoch).
fn run(stamps: &[TimeStamp]) -> (Vec<(usize, u64, bool)>, TimeBase<usize>) {
    let mut tb = TimeBase::new();
    let mut out = Vec::new();
    let mut take = |t: Timed<usize>| out.push((t.payload, t.t_us, t.new_epoch));
    for (i, &s) in stamps.iter().enumerate() {
        tb.update(s, i).for_each(&mut take);
    }
    if let Some(t) = tb.finish() {
        take(t);
    }
    (out, tb)
}

fn itow_100hz(n: usize, start: u32) -> Vec<TimeStamp> {
    (0..n as u32)
        .map(|k| TimeStamp::Itow(start + 10 * k))
        .collect()
}

/// Expected (index, t_us) of an undisturbed 100 Hz stream, without the listed indices.
fn expected_without(n: usize, lost: &[usize]) -> Vec<(usize, u64, bool)> {
    (0..n)
        .filter(|i| !lost.contains(i))
        .map(|i| (i, i as u64 * 10_000, false))
        .collect()
}

#[test]
fn an_impossible_stamp_costs_its_own_sample_and_shifts_nothing() {
    for bad in [0xFFFF_FFFF, WEEK_MS] {
        let mut s = itow_100hz(200, 1_000_000);
        s[50] = TimeStamp::Itow(bad);
        let (out, tb) = run(&s);
        assert_eq!(out, expected_without(200, &[50]));
        assert_eq!(tb.faults().impossible, 1);
        assert_eq!(tb.faults().discarded(), 1);
    }
}

#[test]
fn a_single_backward_or_forward_stamp_is_discarded_and_counted() {
    // Backward by 5 s, backward by 10 ms (a repeat of an older stamp), forward by one hour,
    // forward by 50 ms (5 periods): each costs exactly its own sample.
    for (delta, backward) in [
        (-5_000i64, true),
        (-20, true),
        (3_600_000, false),
        (50, false),
    ] {
        let mut s = itow_100hz(200, 1_000_000);
        s[100] = TimeStamp::Itow((1_000_000 + 1000 + delta) as u32);
        let (out, tb) = run(&s);
        assert_eq!(out, expected_without(200, &[100]), "delta {delta} ms");
        let f = tb.faults();
        assert_eq!(
            (f.bad_backward, f.bad_forward),
            (u32::from(backward), u32::from(!backward))
        );
        assert_eq!((f.backward_jumps, f.discarded()), (0, 1));
    }
}

#[test]
fn a_confirmed_backward_jump_starts_a_new_epoch_without_losing_a_sample() {
    // Two recordings stitched: the second starts 20 s earlier in time of week.
    let mut s = itow_100hz(100, 500_000);
    s.extend(itow_100hz(100, 480_000));
    let (out, tb) = run(&s);
    assert_eq!(out.len(), 200);
    for (k, &(i, t, new_epoch)) in out.iter().enumerate() {
        // Time keeps increasing by one period across the stitch.
        assert_eq!((i, t, new_epoch), (k, k as u64 * 10_000, k == 100));
    }
    assert_eq!(tb.faults().backward_jumps, 1);
    assert_eq!(tb.faults().discarded(), 0);
}

#[test]
fn a_dropout_keeps_its_true_time_and_costs_nothing() {
    // 2 s without packets, then the stream continues: the sample after the gap is held one
    // sample (suspicious), then released with its true time.
    let mut s = itow_100hz(100, 0);
    s.extend((0..100u32).map(|k| TimeStamp::Itow(990 + 2_000 + 10 + 10 * k)));
    let (out, tb) = run(&s);
    assert_eq!(out.len(), 200);
    assert_eq!(out[100], (100, 3_000_000, false));
    assert_eq!(out[199], (199, 3_990_000, false));
    assert!(!tb.faults().any());
    // A dropout in the last sample is released at the end of input.
    let (out, _) = run(&[
        TimeStamp::Itow(0),
        TimeStamp::Itow(10),
        TimeStamp::Itow(900),
    ]);
    assert_eq!(out.last(), Some(&(2, 900_000, false)));
}

#[test]
fn a_backward_stamp_left_at_the_end_is_discarded() {
    let (out, tb) = run(&[
        TimeStamp::Itow(100),
        TimeStamp::Itow(110),
        TimeStamp::Itow(50),
    ]);
    assert_eq!(out, vec![(0, 0, false), (1, 10_000, false)]);
    assert_eq!(tb.faults().bad_backward, 1);
}

#[test]
fn week_rollover_and_gpsitow_wrap_are_not_faults() {
    let s: Vec<_> = (0..100u32)
        .map(|k| TimeStamp::Itow((WEEK_MS - 500 + 10 * k) % WEEK_MS))
        .collect();
    let (out, tb) = run(&s);
    assert_eq!(out, expected_without(100, &[]));
    assert!(!tb.faults().any());
    let s: Vec<_> = (0..10_000u32)
        .map(|k| TimeStamp::GpsItow((65_000 + 10 * k) as u16))
        .collect();
    let (out, tb) = run(&s);
    assert_eq!(out, expected_without(10_000, &[]));
    assert!(!tb.faults().any());
}

#[test]
fn duplicates_are_dropped_and_counted() {
    let s = [100, 110, 110, 120].map(TimeStamp::Itow);
    let (out, tb) = run(&s);
    assert_eq!(
        out,
        vec![(0, 0, false), (1, 10_000, false), (3, 20_000, false)]
    );
    assert_eq!(tb.faults().duplicates, 1);
}

/// A0 (GPSITOW = low 16 bits of the same counter) polled between A2 (timeITOW).
fn mixed(n_a2: u32, every: u32, gps_first: bool) -> (Vec<TimeStamp>, Vec<usize>) {
    let mut s = Vec::new();
    let mut a2 = Vec::new();
    let start = 400_000_000u32;
    for k in 0..n_a2 {
        let t = start + 10 * k;
        if k % every == 0 && gps_first {
            s.push(TimeStamp::GpsItow((t + 3) as u16));
        }
        a2.push(s.len());
        s.push(TimeStamp::Itow(t));
        if k % every == 0 && !gps_first {
            s.push(TimeStamp::GpsItow((t + 3) as u16));
        }
    }
    (s, a2)
}

#[test]
fn polled_gpsitow_samples_never_cost_a_timeitow_sample() {
    // One A0 per ten A2, alternating A2/A0, and alternating starting with an A0.
    for (every, gps_first, n_gps) in [(10, false, 200), (1, false, 2000), (1, true, 2000)] {
        let (s, a2) = mixed(2000, every, gps_first);
        let (out, tb) = run(&s);
        let got: Vec<usize> = out
            .iter()
            .filter(|o| a2.contains(&o.0))
            .map(|o| o.0)
            .collect();
        assert_eq!(
            got, a2,
            "every {every}, gps first {gps_first}: every A2 kept"
        );
        let f = tb.faults();
        if gps_first {
            // The leading A0 runs alone, the first A2 switches the base (new epoch).
            assert_eq!(out.len(), 2001);
            assert_eq!((f.kind_switches, f.other_kind), (1, n_gps - 1));
            assert!(out[1].2);
            let t0 = out[1].1;
            for (k, o) in out[1..].iter().enumerate() {
                assert_eq!(o.1, t0 + 10_000 * k as u64);
            }
        } else {
            assert_eq!(out.len(), 2000);
            assert_eq!((f.kind_switches, f.other_kind), (0, n_gps));
            for (k, o) in out.iter().enumerate() {
                assert_eq!((o.1, o.2), (10_000 * k as u64, false));
            }
        }
    }
}
