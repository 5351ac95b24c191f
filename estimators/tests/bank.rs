//! The YawBank on a smooth hand-rotation-like yaw profile.
use estimators::{BankConfig, Fx, Real, YawBank};

/// yaw = 70 sin(pi t) + 10 sin(2.6 pi t + 1) deg: within +-80 deg, rate within +-300 deg/s,
/// acceleration within +-1400 deg/s^2.
fn truth(t: f64) -> (f64, f64, f64) {
    use std::f64::consts::PI;
    let (w1, w2) = (PI, 2.6 * PI);
    (
        70.0 * (w1 * t).sin() + 10.0 * (w2 * t + 1.0).sin(),
        70.0 * w1 * (w1 * t).cos() + 10.0 * w2 * (w2 * t + 1.0).cos(),
        -70.0 * w1 * w1 * (w1 * t).sin() - 10.0 * w2 * w2 * (w2 * t + 1.0).sin(),
    )
}

fn run<T: Real>(cfg: &BankConfig, seconds: f64) -> ([f64; 7], [f64; 7]) {
    let mut bank = YawBank::<T>::new(cfg).unwrap();
    let mut sv = [0.0; 7];
    let mut sa = [0.0; 7];
    let mut cnt = 0.0;
    let n = (seconds * 100.0) as u64;
    for k in 0..=n {
        let t = k as f64 * 0.01;
        let (y, v, a) = truth(t);
        let out = bank.update(k * 10_000, y as f32).unwrap();
        if t >= 2.0 {
            for i in 0..7 {
                sv[i] += (f64::from(out.vel[i]) - v).powi(2);
                sa[i] += (f64::from(out.acc[i]) - a).powi(2);
            }
            cnt += 1.0;
        }
    }
    (sv.map(|s| (s / cnt).sqrt()), sa.map(|s| (s / cnt).sqrt()))
}

#[test]
fn print_rms() {
    let cfg = BankConfig::default();
    let (v, a) = run::<f32>(&cfg, 6.0);
    println!("f32 vel rms {v:?}\nf32 acc rms {a:?}");
    let (v, a) = run::<Fx>(&cfg, 6.0);
    println!("fx vel rms {v:?}\nfx acc rms {a:?}");
}
