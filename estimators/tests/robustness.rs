//! Any input sequence (any f32 yaw, including NaN, infinities and huge values; repeated,
//! jittered and huge time steps): the bank never panics, rejects exactly the bad samples with
//! the right typed error, and every accepted sample gives outputs that are not NaN (f32) and
//! finite (Q31.32, which saturates). Before the range check a finite 3.4e38 deg yaw turned the
//! f32 bank's states to NaN for good; this test found it.

use estimators::{BankConfig, Fx, PaperBank, SampleError};
use proptest::prelude::*;

fn yaw_value() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -180.0f32..180.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => -1e6f32..1e6,
        1 => any::<f32>(),
    ]
}

fn step_us() -> impl Strategy<Value = u64> {
    prop_oneof![
        6 => Just(10_000u64),
        2 => 0u64..50_000,
        1 => Just(0u64),
        1 => 0u64..10_000_000_000,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn any_sequence_is_handled(seq in prop::collection::vec((step_us(), yaw_value()), 1..120)) {
        let mut f = PaperBank::<f32>::new(&BankConfig::default()).unwrap();
        let mut x = PaperBank::<Fx>::new(&BankConfig::default()).unwrap();
        let mut t = 0u64;
        let mut last_t: Option<u64> = None;
        for (dt, yaw) in seq {
            t = t.saturating_add(dt);
            let expected = if !yaw.is_finite() {
                Some(SampleError::NotFinite)
            } else if yaw.abs() > PaperBank::<f32>::MAX_ABS_DEG {
                Some(SampleError::OutOfRange)
            } else if last_t.is_some_and(|l| t <= l) {
                Some(SampleError::NonIncreasingTime)
            } else {
                None
            };
            let rf = f.update(t, yaw);
            let rx = x.update(t, yaw);
            if let Some(e) = expected {
                prop_assert_eq!(rf.err(), Some(e));
                prop_assert_eq!(rx.err(), Some(e));
            } else {
                let of = rf.unwrap();
                prop_assert!(of.values.iter().all(|v| !v.is_nan()), "{:?}", of);
                let out = rx.unwrap();
                // Fixed point saturates: every output is a finite number.
                prop_assert!(out.velocities().iter().chain(&out.accelerations()).all(|v| v.is_finite()));
                last_t = Some(t);
            }
        }
    }
}
