//! A NAV440 capture file through the pipeline, as a firmware runs it: bytes in chunks, one CSV
//! line per sample out (the product bank: ILO1 velocity and Kalman acceleration of roll, pitch
//! and yaw). Prints the header, the last line and the counters; exits non-zero if the capture
//! gives no row.
//!
//! `cargo run -p nav440-pipeline --example estimate_capture -- host-tests/data/fig5_a2_100hz.bin`

use estimators::{BankConfig, ConfigError, ProductBank};
use nav440_pipeline::{axis_bank, csv, Axes, Axis, Pipeline};

fn main() -> Result<(), String> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: estimate_capture CAPTURE.bin")?;
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {path}: {e}"))?;
    // The bank of each axis, built once the warm-up has measured the packet period.
    let build = |axis: Axis, cfg: &BankConfig| -> Result<ProductBank<f32>, ConfigError> {
        axis_bank(axis, cfg)
    };
    let mut pipe = Pipeline::new(Axes::ALL, BankConfig::NAV440, build);
    let mut header = String::new();
    csv::write_header::<ProductBank<f32>>(&mut header, Axes::ALL).map_err(|_| "header")?;
    println!("{header}");
    let (mut rows, mut last) = (0u64, String::new());
    // 64-byte chunks, as a UART interrupt would hand them over.
    for chunk in bytes.chunks(64) {
        pipe.feed_csv(chunk, |line| {
            rows += 1;
            last = line.to_string();
        })
        .map_err(|e| format!("bank: {e}"))?;
    }
    pipe.finish_csv(|line| {
        rows += 1;
        last = line.to_string();
    })
    .map_err(|e| format!("bank: {e}"))?;
    print!("{last}");
    let mut summary = String::new();
    pipe.summary(&mut summary, 0, 0).map_err(|_| "summary")?;
    println!("{summary}");
    if rows == 0 {
        return Err(format!("{path}: no row"));
    }
    Ok(())
}
