//! Bank slots (`Pipeline::with_slots`): the number of slots changes the RAM, never the rows.
//! Property checked on a bundled capture: a one-slot yaw pipeline gives exactly the rows of the
//! three-slot pipeline (`Pipeline::new`) on yaw, and one slot for all axes keeps the first axis
//! in CSV order (roll).

use estimators::{BankConfig, ConfigError, NativeSqrt, PaperBank};
use nav440_pipeline::{axis_bank, Axes, Axis, Pipeline, Row};

fn build(axis: Axis, cfg: &BankConfig) -> Result<PaperBank<f32, NativeSqrt>, ConfigError> {
    axis_bank(axis, cfg)
}

type Build = fn(Axis, &BankConfig) -> Result<PaperBank<f32, NativeSqrt>, ConfigError>;

fn capture() -> Vec<u8> {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../host-tests/data/fig5_a2_100hz_corrupt.bin"
    );
    std::fs::read(p).expect("bundled capture")
}

/// Every row of `bytes` through `pipe`.
fn rows<const N: usize>(
    pipe: &mut Pipeline<PaperBank<f32, NativeSqrt>, ConfigError, Build, N>,
    bytes: &[u8],
) -> Vec<Row> {
    let mut out = Vec::new();
    pipe.feed(bytes, &mut |r| out.push(*r)).unwrap();
    pipe.finish(&mut |r| out.push(*r)).unwrap();
    out
}

#[test]
fn one_slot_gives_the_rows_of_three() {
    let bytes = capture();
    let yaw = Axes::only(Axis::Yaw);
    let mut three: Pipeline<_, _, Build> = Pipeline::new(yaw, BankConfig::default(), build);
    let mut one: Pipeline<_, _, Build, 1> = Pipeline::with_slots(yaw, BankConfig::default(), build);
    let a = rows(&mut three, &bytes);
    let b = rows(&mut one, &bytes);
    assert!(a.len() > 400, "{} rows", a.len());
    assert_eq!(a, b);
    assert!(b
        .iter()
        .all(|r| r.axis(Axis::Yaw).is_some() && r.axis(Axis::Roll).is_none()));
    assert!(one.estimation().bank(Axis::Yaw).is_some());
    assert!(one.estimation().bank(Axis::Roll).is_none());
}

#[test]
fn one_slot_keeps_the_first_axis() {
    let one: Pipeline<_, _, Build, 1> =
        Pipeline::with_slots(Axes::ALL, BankConfig::default(), build);
    assert_eq!(one.estimation().axes(), Axes::only(Axis::Roll));
    let two: Pipeline<_, _, Build, 2> = Pipeline::with_slots(
        Axes::only(Axis::Pitch).with(Axis::Yaw),
        BankConfig::default(),
        build,
    );
    assert_eq!(
        two.estimation().axes(),
        Axes::only(Axis::Pitch).with(Axis::Yaw)
    );
}
