//! The CSV row (moved here from the estimators crate's tests with `csv`): header per
//! CONTRACT.md, `t` with 4 decimals from integer microseconds, every other value Display of
//! its f32; the expected texts are written by hand.

use estimators::PaperOutput;
use nav440_pipeline::{csv, Axes, Axis, AxisRow, Row};

fn row(t_us: u64, reference: Option<f32>, out: PaperOutput) -> Row {
    let mut axes = [None; 3];
    axes[Axis::Yaw.index()] = Some(AxisRow {
        reference_deg_s: reference,
        out,
    });
    Row { t_us, axes }
}

#[test]
fn csv_row_format() {
    assert_eq!(
        csv::HEADER,
        format!("t,yaw,yaw_rate,{}", <PaperOutput>::CSV_COLUMNS)
    );
    let out = <PaperOutput>::new(
        -361.5,
        0.0,
        [
            1.0,
            0.1,
            -2.5,
            1e-7,
            3.4028235e38,
            0.0,
            12.25,
            -0.0,
            1.5,
            2.0,
            3.0,
            4.0,
            5.0,
            6.0,
        ],
    );
    let yaw = Axes::only(Axis::Yaw);
    let mut s = String::new();
    csv::write_row(&mut s, &row(1_234_567, Some(99.5), out), yaw).unwrap();
    assert_eq!(
        s,
        "1.2346,-361.5,99.5,1,0.1,-2.5,0.0000001,340282350000000000000000000000000000000,0,12.25,-0,1.5,2,3,4,5,6"
    );
    let mut s = String::new();
    csv::write_row(
        &mut s,
        &row(35_000_000_049, Some(0.0), <PaperOutput>::default()),
        yaw,
    )
    .unwrap();
    assert!(s.starts_with("35000.0000,0,0,"), "{s}");
    assert_eq!(s.matches(',').count(), 16);
    // No reference (near gimbal lock): an empty field.
    let mut s = String::new();
    csv::write_row(&mut s, &row(0, None, <PaperOutput>::default()), yaw).unwrap();
    assert!(s.starts_with("0.0000,0,,0,"), "{s}");
    // All axes: t + 3 x 16 fields; an axis the row lacks gives 16 empty fields.
    let mut s = String::new();
    csv::write_row(
        &mut s,
        &row(0, Some(1.0), <PaperOutput>::default()),
        Axes::ALL,
    )
    .unwrap();
    assert_eq!(s.matches(',').count(), 48);
    // roll and pitch: 2 x 16 empty fields, then yaw's angle 0 and reference 1.
    let want = format!("0.0000{},0,1,0,", ",".repeat(32));
    assert!(s.starts_with(&want), "{s}");
}
