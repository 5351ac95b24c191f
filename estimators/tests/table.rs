//! The banks (tuples of rows behind one input stage), the `Law` API (parameters apart
//! from state) and the exactness of the bank's shortcuts, each checked against an independent
//! computation: the same laws run one by one through `SampleAdapter`.

use estimators::presets::*;
use estimators::EstimatorOutput as _;
use estimators::{
    AveConfig, AveParams, BankConfig, Channel, ClosedForm, DeltaMode, EdParams, EdScheme,
    Estimator, Fx, Hold, IloParams, Kalman, KalmanConfig, KalmanOutput, KalmanParams, Law,
    PaperBank, PaperOutput, ProductBank, ProductChannel, ProductOutput, Real, SampleAdapter,
    Series, Stateful, Wrap,
};

/// A paper-like yaw (deg) at sample `k` of a 100 Hz stream: +-90 deg sweeps plus a
/// deterministic ripple, wrapped to +-180.
fn yaw(k: u64) -> f32 {
    let t = k as f64 * 0.01;
    let y = 120.0 * (0.7 * t).sin() + 70.0 * (2.3 * t).sin() + 0.3 * (37.0 * t).sin();
    (((y + 180.0).rem_euclid(360.0)) - 180.0) as f32
}

/// The unwrapped twin of [`yaw`] (what a law alone must be fed).
fn yaw_unwrapped(k: u64) -> f32 {
    let t = k as f64 * 0.01;
    (120.0 * (0.7 * t).sin() + 70.0 * (2.3 * t).sin() + 0.3 * (37.0 * t).sin()) as f32
}

/// Runs `e` alone through a sample adapter on the unwrapped yaw; returns every output.
fn alone<E: Estimator<f64>>(e: E, n: u64) -> Vec<f32> {
    let cfg = BankConfig::default();
    let mut ad = SampleAdapter::new(e, cfg.h, cfg.max_gap_s(), Hold::Linear).unwrap();
    (0..n)
        .map(|k| ad.update(k * 10_000, yaw_unwrapped(k)).unwrap().to_f32())
        .collect()
}

/// The paper bank in f64 (no turns within the run: |yaw| < 190 deg but wrapping at +-180,
/// so turns happen; f64 keeps the translation exact to ~1e-13, compared with a tolerance).
/// Every channel equals the law run alone (built from the presets by hand, not by the
/// bank's table), within f64 rounding of the frame translation.
#[test]
fn every_channel_is_its_law_run_alone() {
    let cfg = BankConfig::default();
    let h = cfg.h;
    let n = 1500;
    let mut bank = PaperBank::<f64>::new(&cfg).unwrap();
    let rows: Vec<_> = (0..n)
        .map(|k| bank.update(k * 10_000, yaw(k)).unwrap())
        .collect();
    let ave = AveParams::<f64>::new(&AVE_DEFAULT, h).unwrap();
    let ed = EdParams::<f64>::new(&ED_PAPER, h, EdScheme::Euler).unwrap();
    let ilo = |c| IloParams::<f64, 1>::new(c, h).unwrap();
    let ad = |t| estimators::AdParams::<f64>::new(t, h).unwrap();
    let kf = |out| {
        KalmanParams::<f64>::new(
            &KalmanConfig {
                dt: 0.01,
                q: estimators::KF_DEFAULT.q,
                r: estimators::KF_DEFAULT.r,
            },
            h,
            out,
        )
        .unwrap()
    };
    let expected: Vec<(Channel, Vec<f32>)> = vec![
        (Channel::AveV, alone(Stateful::from_law(ave), n)),
        (
            Channel::AveA,
            alone(Stateful::from_law(Series::new(ave, ave)), n),
        ),
        (Channel::EdV, alone(Stateful::from_law(ed), n)),
        (
            Channel::EdA,
            alone(Stateful::from_law(Series::new(ed, ed)), n),
        ),
        (
            Channel::Ilo1V,
            alone(Stateful::from_law(ilo(&ILO1_TABLE2)), n),
        ),
        (
            Channel::Ilo2V,
            alone(Stateful::from_law(ilo(&ILO2_TABLE2)), n),
        ),
        (
            Channel::Ilo3V,
            alone(Stateful::from_law(ilo(&ILO3_TABLE2)), n),
        ),
        (
            Channel::Ilo2A,
            alone(
                Stateful::from_law(Series::new(ilo(&ILO2_TABLE4), ilo(&ILO2_TABLE4))),
                n,
            ),
        ),
        (
            Channel::AdV,
            alone(Stateful::from_law(ad(AD_VELOCITY_T)), n),
        ),
        (
            Channel::AdA,
            alone(
                Stateful::from_law(Series::new(ad(AD_ACCELERATION_T), ad(AD_ACCELERATION_T))),
                n,
            ),
        ),
        (
            Channel::KfV,
            alone(Stateful::from_law(kf(KalmanOutput::Velocity)), n),
        ),
        (
            Channel::KfA,
            alone(Stateful::from_law(kf(KalmanOutput::Acceleration)), n),
        ),
    ];
    for (ch, want) in expected {
        let mut worst = 0.0f64;
        let mut scale = 0.0f64;
        for (r, w) in rows.iter().zip(&want) {
            worst = worst.max(f64::from(r[ch] - w).abs());
            scale = scale.max(f64::from(*w).abs());
        }
        assert!(scale > 1.0, "{ch:?}: the run exercises it");
        // The ED chatters (sign switching): a 1e-13 frame difference can flip a sign, so it
        // gets the chatter amplitude as tolerance; every other law agrees to rounding.
        let tol = match ch {
            Channel::EdV | Channel::EdA => 0.05 * scale,
            _ => 1e-6 * scale,
        };
        assert!(worst <= tol, "{ch:?}: max diff {worst} (scale {scale})");
    }
}

/// The product bank's channels are the paper bank's same channels, bit for bit (f32 and Fx):
/// the same table rows, whatever else the bank holds.
#[test]
fn product_bank_equals_the_paper_bank_channels() {
    fn run<T: Real>() {
        let cfg = BankConfig::default();
        let mut paper = PaperBank::<T>::new(&cfg).unwrap();
        let mut product = ProductBank::<T>::new(&cfg).unwrap();
        for k in 0..800 {
            // a gap and a new epoch on the way
            let t = if k < 400 {
                k * 10_000
            } else {
                k * 10_000 + 1_000_000
            };
            if k == 600 {
                paper.new_epoch();
                product.new_epoch();
            }
            let a = paper.update(t, yaw(k)).unwrap();
            let b = product.update(t, yaw(k)).unwrap();
            assert_eq!(
                b.channel(ProductChannel::Ilo1V).to_bits(),
                a.channel(Channel::Ilo1V).to_bits()
            );
            assert_eq!(
                b.channel(ProductChannel::KfA).to_bits(),
                a.channel(Channel::KfA).to_bits()
            );
            assert_eq!(b.unwrapped_deg().to_bits(), a.unwrapped_deg().to_bits());
        }
        assert_eq!(paper.reinit_count(), 1);
        assert_eq!(product.reinit_count(), 1);
    }
    run::<f32>();
    run::<Fx>();
}

/// Sharing the series' first stage with the velocity law is exact: a configuration whose
/// acceleration AVE/ED differ from the velocity ones (no sharing) gives, on its velocity
/// channels, the bits of the default configuration (sharing), and its acceleration channels
/// equal a bank whose velocity half was set to the acceleration gains (sharing again).
#[test]
fn shared_first_stage_is_exact() {
    let base = BankConfig::default();
    let mut other = base;
    other.acceleration.ave = AveConfig {
        k: 300.0,
        gamma1: 9000.0,
        delta: DeltaMode::Paper,
    };
    other.acceleration.ed.lambda = 400.0;
    let mut twin = other;
    twin.velocity.ave = other.acceleration.ave;
    twin.velocity.ed = other.acceleration.ed;
    let mut a = PaperBank::<f32>::new(&base).unwrap(); // shared
    let mut b = PaperBank::<f32>::new(&other).unwrap(); // not shared
    let mut c = PaperBank::<f32>::new(&twin).unwrap(); // shared, other gains
    for k in 0..1000 {
        let (oa, ob, oc) = (
            a.update(k * 10_000, yaw(k)).unwrap(),
            b.update(k * 10_000, yaw(k)).unwrap(),
            c.update(k * 10_000, yaw(k)).unwrap(),
        );
        for ch in [Channel::AveV, Channel::EdV] {
            assert_eq!(oa[ch].to_bits(), ob[ch].to_bits(), "{ch:?} at {k}");
        }
        for ch in [Channel::AveA, Channel::EdA] {
            assert_eq!(ob[ch].to_bits(), oc[ch].to_bits(), "{ch:?} at {k}");
        }
    }
}

/// The Kalman tracker as a `Law` is the `Kalman` object's `update(y, n h)`, bit for bit,
/// with intervals of one nominal period and of 1.3 and 4.5 (sub-stepped, the input
/// interpolated from the previous sample).
#[test]
fn kalman_law_is_the_tracker() {
    let cfg = KalmanConfig {
        dt: 0.01,
        q: 1e6,
        r: 0.01,
    };
    let law = KalmanParams::<f32>::new(&cfg, 1e-4, KalmanOutput::Acceleration).unwrap();
    let mut kf = Kalman::<f32>::new(&cfg).unwrap();
    let mut s = law.init(yaw(0));
    kf.reset(yaw(0));
    let h = (100e-6f64) as f32;
    for k in 1..500u64 {
        let n = match k % 7 {
            0 => 130,
            3 => 450,
            _ => 100,
        };
        let out = law.advance(&mut s, yaw(k - 1), yaw(k), n, Hold::Linear);
        kf.update(yaw(k), h * n as f32);
        assert_eq!(out.to_bits(), kf.acceleration().to_bits());
        assert_eq!(law.velocity(&s).to_bits(), kf.velocity().to_bits());
    }
}

/// One parameter set, several states: stepping two states with one `AveParams` equals two
/// independent estimator objects (parameters are read-only).
#[test]
fn one_parameter_set_serves_several_states() {
    let p = AveParams::<f32>::new(&AVE_PAPER, 1e-4).unwrap();
    let (mut s1, mut s2) = (p.init(0.0), p.init(10.0));
    let mut e1 = Stateful::from_law(p);
    let mut e2 = Stateful::from_law(p);
    e1.reset(0.0);
    e2.reset(10.0);
    for k in 0..2000 {
        let y = (k as f32 * 0.001).sin();
        assert_eq!(p.step(&mut s1, y).to_bits(), e1.step(y).to_bits());
        assert_eq!(
            p.step(&mut s2, y + 10.0).to_bits(),
            e2.step(y + 10.0).to_bits()
        );
    }
    // A closed form shares its inner law's state type.
    let ilo = IloParams::<f32, 1>::new(&ILO1_TABLE2, 1e-4).unwrap();
    let cf = ClosedForm::new(ilo, 100, Hold::Linear);
    let mut a = ilo.init(1.0);
    let mut b = cf.init(1.0);
    ilo.advance(&mut a, 1.0, 2.0, 100, Hold::Linear);
    cf.advance(&mut b, 1.0, 2.0, 100, Hold::Linear);
    assert!((a.xhat - b.xhat).abs() < 1e-5);
}

/// Channel names, CSV columns and the CSV header come from the rows: every velocity channel,
/// then every acceleration channel, in row order. The one place the banks' CSV columns are
/// spelled out (the pipeline's header and every test use the banks' own names).
#[test]
fn names_come_from_the_rows() {
    assert_eq!(Channel::COUNT, 14);
    assert_eq!(Channel::ALL.len(), 14);
    // The CSV contract (the pipeline crate's header is built from these names).
    assert_eq!(
        <PaperOutput>::CSV_COLUMNS,
        "ave_v,ilo1_v,ilo2_v,ilo3_v,ad_v,ed_v,kf_v,ave_a,ilo1_a,ilo2_a,ilo3_a,ad_a,ed_a,kf_a"
    );
    for (i, c) in Channel::ALL.iter().enumerate() {
        assert_eq!(c.index(), i);
    }
    for (i, name) in estimators::VELOCITY_NAMES.iter().enumerate() {
        assert_eq!(Channel::VELOCITY[i].name(), format!("{name}_v"));
        assert_eq!(Channel::ACCELERATION[i].name(), format!("{name}_a"));
    }
    assert_eq!(<ProductOutput>::CSV_COLUMNS, "ilo1_v,kf_a");
    assert_eq!(<ProductOutput>::CSV_COLUMNS.to_string(), "ilo1_v,kf_a");
    assert_eq!(ProductChannel::KfA.name(), "kf_a");
    assert_ne!(<ProductOutput>::CSV_COLUMNS, "ilo1_v,kf_a,");
    assert_ne!(<ProductOutput>::CSV_COLUMNS, "ilo1_v");
}

/// `Wrap::None` (pitch) never adds turns: the angle column is the input, and a jump of more
/// than 180 deg is a jump, where `Wrap::Deg180` unwraps it.
#[test]
fn wrap_is_a_per_axis_choice() {
    let pitch = BankConfig {
        wrap: Wrap::None,
        ..BankConfig::default()
    };
    let mut p = PaperBank::<f32>::new(&pitch).unwrap();
    let mut y = PaperBank::<f32>::new(&BankConfig::default()).unwrap();
    for (k, a) in [170.0f32, 179.0, -179.0, -170.0].iter().enumerate() {
        let t = k as u64 * 10_000;
        let op = p.update(t, *a).unwrap();
        let oy = y.update(t, *a).unwrap();
        assert_eq!(op.unwrapped_deg(), *a);
        if k >= 2 {
            assert_eq!(oy.unwrapped_deg(), a + 360.0);
            // the unwrapped stream moves at 800-900 deg/s; the raw one jumps by -358 deg
            assert!(oy[Channel::Ilo1V] > 0.0 && op[Channel::Ilo1V] < 0.0);
        }
    }
}
