//! The firmware's output as defmt messages: no text formatting on the MCU.
//!
//! * [`header`]: once per run, the estimated axes (`AXES`, as a bit mask roll=1, pitch=2,
//!   yaw=4); the host writes the CSV header line of `nav440 estimate --axis ...` from it.
//! * [`row`]: one message per sample, `row {=u64} {=[?]}`: the sample time (us since the
//!   first sample), then one [`AxisOut`] per estimated axis (roll, pitch, yaw order): a
//!   flag byte (bit 0: a reference rate is present), the unwrapped angle (deg, f32), its f64
//!   residual (deg, 0 while f32 holds the angle), the reference rate (deg/s, f32; 0 when
//!   absent) and the 14 channel values (`estimators::Channel` order, f32).
//! * diagnostics and counters: `firmware: ...` messages (see `main.rs`).
//!
//! The host (`cargo xtask qemu/demo/unit`, through `defmt-decoder` and the ELF's defmt table)
//! turns each `row` message back into the exact `f32`/`f64` bits and formats the line with
//! `nav440_pipeline::csv`, so the CSV equals `nav440 estimate`'s byte for byte.
//!
//! Transport: `defmt-semihosting` (frames on the semihosting stdout) on the emulated boards,
//! `defmt-rtt` on the real board (`board-stm32f405` without `semihosting-log`), read by
//! probe-rs.

use crate::pipeline::AXES;
use estimators::Channel;
use nav440_pipeline::{AxisRow, Row};

/// Marker of the row message (the host finds it in the ELF's defmt table).
pub const ROW_TAG: &str = "row";

/// One axis of a [`row`] message (see the module doc for the fields).
pub struct AxisOut<'a>(pub &'a AxisRow);

impl defmt::Format for AxisOut<'_> {
    fn format(&self, f: defmt::Formatter<'_>) {
        let o = &self.0.out;
        let v = &o.values;
        const _: () = assert!(Channel::COUNT == 14, "AxisOut sends 14 channel values");
        defmt::write!(
            f,
            "{=u8} {=f32} {=f64} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32} {=f32}",
            u8::from(self.0.reference_deg_s.is_some()),
            o.yaw_unwrapped_deg,
            o.yaw_residual_deg,
            self.0.reference_deg_s.unwrap_or(0.0),
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5],
            v[6],
            v[7],
            v[8],
            v[9],
            v[10],
            v[11],
            v[12],
            v[13]
        );
    }
}

/// Sends the header message: the axes of the rows (bit mask roll=1, pitch=2, yaw=4).
pub fn header() {
    let mut mask = 0u8;
    for a in AXES.iter() {
        mask |= 1 << a.index();
    }
    defmt::println!("header {=u8}", mask);
}

/// Sends one sample's row message.
pub fn row(r: &Row) {
    let mut axes: heapless::Vec<AxisOut<'_>, 3> = heapless::Vec::new();
    for a in r.axes.iter().flatten() {
        // Cannot fail: at most three axes.
        let _ = axes.push(AxisOut(a));
    }
    defmt::println!("row {=u64} {=[?]}", r.t_us, axes.as_slice());
}

/// Sends the end-of-run counters: the `key=value` line of `nav440_pipeline::Pipeline::summary`
/// (same keys, same order) followed by `unit_bytes` and `stack_peak` (bytes).
pub fn summary(
    pipe: &crate::pipeline::Pipeline,
    uart_overruns: u32,
    uart_stalls: u32,
    unit_bytes: u64,
    stack_peak: usize,
) {
    let s = pipe.front().parser_stats();
    let fc = pipe.front().counters();
    let c = pipe.estimation().counters();
    let f = pipe.front().time_faults();
    defmt::println!(
        "firmware: bytes={=u64} frames={=u64} crc_errors={=u64} skipped={=u64} decode_errors={=u64} samples={=u64} rows={=u64} rejected={=u64} format_errors={=u64} uart_overruns={=u32} uart_stalls={=u32} yaw_packets={=u64} impossible={=u32} bad_backward={=u32} bad_forward={=u32} backward_jumps={=u32} kind_switches={=u32} other_kind={=u32} duplicates={=u32} gaps={=u32} bit_failed={=u64} bit_flag={=str} bit_hardware_error={=u64} bit_com_error={=u64} bit_software_error={=u64} bit_last=0x{=u16:04x} unit_bytes={=u64} stack_peak={=usize}",
        s.bytes,
        s.frames,
        s.crc_errors,
        s.skipped_bytes,
        fc.decode_errors,
        c.samples,
        c.rows,
        c.rejected.total(),
        pipe.format_errors(),
        uart_overruns,
        uart_stalls,
        fc.attitude_packets,
        f.impossible,
        f.bad_backward,
        f.bad_forward,
        f.backward_jumps,
        f.kind_switches,
        f.other_kind,
        f.duplicates,
        c.gaps,
        fc.bit.failed,
        nav440_pipeline::bit::FAILURE_FLAG,
        fc.bit.hardware_error,
        fc.bit.com_error,
        fc.bit.software_error,
        fc.bit.last_word,
        unit_bytes,
        stack_peak
    );
}
