//! The pipeline with the product bank (`estimators::ProductBank`: ILO1 velocity and Kalman
//! acceleration), checked against values known independently of the code under test:
//!
//! * a synthetic stream of A2 packets with yaw turning at a constant 30 deg/s: after a
//!   second the ILO1 velocity is 30 deg/s and the Kalman acceleration about 0;
//! * a bundled capture: every row's `ilo1_v` and `kf_a` are bit for bit the paper bank's
//!   `ilo1_v` and `kf_a` (the same two estimators with the same gains), and the time, angle
//!   and reference rate are the paper pipeline's, for f32 and fixed point, on every axis;
//! * the CSV lines of `Pipeline::feed_csv` are the header's 5 columns.

use estimators::EstimatorOutput as _;
use estimators::{
    Bank, BankConfig, BankOutput, Channel, ConfigError, Fx, NativeSqrt, PaperRows, ProductBank,
    ProductChannel, ProductRows, Real, Rows,
};
use nav440_pipeline::{axis_bank, csv, Axes, Axis, Pipeline, Row};
use nav440_proto::{encode_frame, A2Fields, PacketType};

/// `n` A2 packets at 100 Hz, level, yaw = `rate` deg/s * t with r = `rate` deg/s.
fn turning(n: u32, rate: f64) -> Vec<u8> {
    let mut bytes = Vec::new();
    for k in 0..n {
        let yaw = rate * 0.01 * f64::from(k);
        let yaw = (yaw + 180.0).rem_euclid(360.0) - 180.0;
        let p = A2Fields {
            yaw_true: (yaw * 65536.0 / 360.0).round() as i16,
            rate_z: (rate.to_radians() * 65536.0 / (7.0 * std::f64::consts::PI)).round() as i16,
            time_itow: 1000 + 10 * k,
            ..Default::default()
        };
        let mut frame = [0u8; 64];
        let len = encode_frame(PacketType::A2, &p.payload(), &mut frame).unwrap();
        bytes.extend_from_slice(&frame[..len]);
    }
    bytes
}

/// Every row of `bytes` through a pipeline of banks of rows `R` (`N` channels, number type
/// `T`) on `axes`.
fn rows<R: Rows<T, NativeSqrt>, const N: usize, T: Real>(
    bytes: &[u8],
    axes: Axes,
) -> Vec<Row<BankOutput<R, N>>> {
    let build = |axis: Axis, cfg: &BankConfig| -> Result<Bank<R, N, T>, ConfigError> {
        axis_bank(axis, cfg)
    };
    let mut pipe = Pipeline::new(axes, BankConfig::NAV440, build);
    let mut out = Vec::new();
    pipe.feed(bytes, &mut |r| out.push(r.map(BankOutput::to_f32)))
        .unwrap();
    pipe.finish(&mut |r| out.push(r.map(BankOutput::to_f32)))
        .unwrap();
    out
}

fn capture() -> Vec<u8> {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../host-tests/data/fig5_a2_100hz.bin"
    );
    std::fs::read(p).expect("bundled capture")
}

#[test]
fn product_bank_tracks_a_constant_rate() {
    let bytes = turning(300, 30.0);
    let rows = rows::<ProductRows, 2, f32>(&bytes, Axes::only(Axis::Yaw));
    assert_eq!(rows.len(), 300);
    for r in &rows[200..] {
        let a = r.axis(Axis::Yaw).unwrap();
        assert!(a.reference_deg_s.is_some_and(|x| (x - 30.0).abs() < 0.01));
        let v = a.out[ProductChannel::Ilo1V];
        let acc = a.out[ProductChannel::KfA];
        assert!((v - 30.0).abs() < 0.5, "t = {} us: ilo1_v = {v}", r.t_us);
        assert!(acc.abs() < 20.0, "t = {} us: kf_a = {acc}", r.t_us);
    }
    // The mean acceleration over the last second is 0 within the quantisation noise.
    let mean: f32 = rows[200..]
        .iter()
        .map(|r| r.axis(Axis::Yaw).unwrap().out[ProductChannel::KfA])
        .sum::<f32>()
        / 100.0;
    assert!(mean.abs() < 2.0, "mean kf_a {mean}");
    // The unwrapped angle crosses +-180 deg without a jump: 299 * 0.3 = 89.7 deg at the end
    // (the A2 yaw is quantised to 360/65536 deg).
    let last = rows[299].axis(Axis::Yaw).unwrap().out.unwrapped_deg();
    assert!((last - 89.7).abs() < 0.01, "{last}");
}

/// The product bank's channels are the paper bank's ILO1 velocity and Kalman acceleration
/// rows: the same values, bit for bit, sample for sample.
fn same_as_paper<T: Real>(axes: Axes) {
    let bytes = capture();
    let paper = rows::<PaperRows, 14, T>(&bytes, axes);
    let product = rows::<ProductRows, 2, T>(&bytes, axes);
    assert!(paper.len() > 1000, "{} rows", paper.len());
    assert_eq!(paper.len(), product.len());
    let mut moving = 0;
    for (p, q) in paper.iter().zip(&product) {
        assert_eq!(p.t_us, q.t_us);
        for axis in Axis::ALL {
            let (Some(a), Some(b)) = (p.axis(axis), q.axis(axis)) else {
                assert!(p.axis(axis).is_none() && q.axis(axis).is_none());
                continue;
            };
            assert_eq!(a.reference_deg_s, b.reference_deg_s);
            assert_eq!(a.out.unwrapped_deg(), b.out.unwrapped_deg());
            assert_eq!(a.out.residual_deg(), b.out.residual_deg());
            let v = (a.out[Channel::Ilo1V], b.out[ProductChannel::Ilo1V]);
            let acc = (a.out[Channel::KfA], b.out[ProductChannel::KfA]);
            assert_eq!(v.0.to_bits(), v.1.to_bits(), "{axis:?} t={} ilo1_v", p.t_us);
            assert_eq!(
                acc.0.to_bits(),
                acc.1.to_bits(),
                "{axis:?} t={} kf_a",
                p.t_us
            );
            if v.0.abs() > 1.0 {
                moving += 1;
            }
        }
    }
    // Not a comparison of zeros: the capture moves.
    assert!(moving > 500, "{moving}");
}

#[test]
fn product_rows_are_the_paper_rows_f32() {
    same_as_paper::<f32>(Axes::only(Axis::Yaw));
    same_as_paper::<f32>(Axes::ALL);
}

#[test]
fn product_rows_are_the_paper_rows_fixed_point() {
    same_as_paper::<Fx>(Axes::ALL);
}

#[test]
fn product_csv_lines() {
    let bytes = turning(50, 30.0);
    let build =
        |axis: Axis, cfg: &BankConfig| -> Result<ProductBank<Fx>, _> { axis_bank(axis, cfg) };
    let mut pipe = Pipeline::new(Axes::ALL, BankConfig::NAV440, build);
    let mut header = String::new();
    csv::write_header::<ProductBank<Fx>>(&mut header, Axes::ALL).unwrap();
    assert_eq!(
        header,
        "t,roll,roll_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_rate,yaw_ilo1_v,yaw_kf_a"
    );
    let mut lines = Vec::new();
    pipe.feed_csv(&bytes, |l| lines.push(l.to_string()))
        .unwrap();
    pipe.finish_csv(|l| lines.push(l.to_string())).unwrap();
    assert_eq!(lines.len(), 50);
    assert_eq!(pipe.format_errors(), 0);
    for l in &lines {
        assert!(l.ends_with('\n'));
        assert_eq!(l.trim_end().split(',').count(), 13, "{l}");
    }
    // The first row initialises every bank: angles 0, values 0, the reference rates 0 but
    // yaw's (30 deg/s to the A2 rate's resolution, 7 pi / 65536 rad/s).
    let f: Vec<&str> = lines[0].trim_end().split(',').collect();
    assert_eq!(
        f[..10],
        ["0.0000", "0", "0", "0", "0", "0", "0", "0", "0", "0"]
    );
    let yaw_rate: f32 = f[10].parse().unwrap();
    assert!((yaw_rate - 30.0).abs() < 0.01, "{yaw_rate}");
    assert_eq!(f[11..], ["0", "0"]);
    // Later rows: yaw's ilo1_v approaches 30 deg/s.
    let last: Vec<f32> = lines[49]
        .trim_end()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert!((last[11] - 30.0).abs() < 1.0, "{}", lines[49]);
    // A const context can size a buffer from the bank type.
    const BYTES: usize = 4 * <ProductBank<Fx> as estimators::EstimatorBank>::CHANNELS;
    assert_eq!([0u8; BYTES].len(), 8);
}

/// The banks' two inputs agree: a capture's samples as the front end gives them (the packet's
/// integers, `Sample::angles_raw`, fed with `update_scaled`) and the same samples rebuilt from
/// their degrees (`Sample::new`: no integers, fed with `update`) give the same rows bit for
/// bit, paper and product banks, `f32` and `Fx`, every axis. Setting an angle drops the
/// integers, so an edited sample is never fed the packet's angle.
#[test]
fn integer_and_degree_angles_give_the_same_rows() {
    use nav440_pipeline::{Estimation, Frontend, Sample};
    fn rows_of<R: Rows<T, NativeSqrt>, const N: usize, T: Real>(
        samples: &[Sample],
    ) -> Vec<Row<BankOutput<R, N, T>>> {
        let build = |axis: Axis, cfg: &BankConfig| -> Result<Bank<R, N, T>, ConfigError> {
            axis_bank(axis, cfg)
        };
        let mut est = Estimation::new(Axes::ALL, BankConfig::NAV440, build);
        let mut out = Vec::new();
        for s in samples {
            est.push(*s, &mut |r| out.push(*r)).unwrap();
        }
        est.finish(&mut |r| out.push(*r)).unwrap();
        out
    }
    let mut packets = Vec::new();
    let mut front = Frontend::new();
    front.feed(&capture(), |s| packets.push(s));
    front.finish(|s| packets.push(s));
    assert!(packets.iter().all(|s| s.angles_raw().is_some()));
    let degrees: Vec<Sample> = packets
        .iter()
        .map(|s| Sample::new(s.t_us, s.angles_deg(), s.rates_deg_s, s.new_epoch))
        .collect();
    assert_eq!(
        rows_of::<ProductRows, 2, Fx>(&packets),
        rows_of::<ProductRows, 2, Fx>(&degrees)
    );
    assert_eq!(
        rows_of::<PaperRows, 14, Fx>(&packets),
        rows_of::<PaperRows, 14, Fx>(&degrees)
    );
    assert_eq!(
        rows_of::<ProductRows, 2, f32>(&packets),
        rows_of::<ProductRows, 2, f32>(&degrees)
    );
    let mut edited = packets[0];
    edited.set_angle_deg(Axis::Yaw, 1.0);
    assert_eq!(edited.angles_raw(), None);
    assert_eq!(edited.angle(Axis::Yaw), 1.0);
}
