//! The firmware's pipeline, the embedded twin of `host-tests`' replay (`nav440 estimate`):
//! bytes -> `nav440_proto::Parser` -> `Packet::decode` -> `Packet::yaw_sample` ->
//! `nav440_proto::TimeBase` (time in us since the first sample; time faults discarded or
//! turned into new epochs, and counted) -> `estimators::YawBank` ([`crate::Bank`],
//! the paper's presets, `BankConfig::default()`: h = 1e-4 s, linear hold) -> one CSV row per
//! sample, formatted by `estimators::csv` exactly as the host does.
//!
//! Nominal sample period: the bank precomputes its closed-form maps and Kalman gains for the
//! packet rate (`BankConfig::sample_period_s`). It is set by `estimators::period`, the one
//! causal rule shared with `nav440 estimate`: the upper median of the intervals between the
//! first [`WARMUP_SAMPLES`] samples (`us as f32 * 1e-6`). A streaming firmware cannot build the
//! bank before it knows that period, so it holds back those first samples, then builds the bank
//! and runs them and all later ones through it; rows are only delayed by the warm-up (0.16 s
//! at 100 Hz). `nav440 estimate` reads the same first samples of the capture, so both build
//! the same bank for every capture, also one whose rate changes after the warm-up. A capture
//! shorter than the warm-up is decided at its end ([`Pipeline::finish`]) from the intervals it
//! has (none: the default 0.01 s).
//!
//! Time faults follow `nav440_proto::TimeBase` (the same code as the host's
//! `replay::SampleReader`): an impossible or single bad stamp costs its own sample only, a
//! confirmed backward jump starts a new epoch (`YawBank::new_epoch`), GPSITOW samples in a
//! timeITOW stream are ignored; each is counted. A sample the bank rejects (non-finite or
//! out-of-range yaw) yields no row and is counted, as on the host. See docs/RELIABILITY.md.

use estimators::period::PeriodEstimator;
use estimators::BankConfig;
use nav440_proto::{Packet, Parser, TimeBase, TimeFaults, Timed};

use crate::Bank;

/// Longest CSV row: 17 fields of at most ~16 characters plus separators.
pub const ROW_CAPACITY: usize = 512;

/// One formatted CSV row (with its trailing newline).
pub type Row = heapless::String<ROW_CAPACITY>;

/// The CSV header line (`estimators::csv::HEADER`, as `nav440 estimate` prints it).
pub const CSV_HEADER: &str = estimators::csv::HEADER;

/// Samples held back to measure the packet period before the bank is built (0.16 s at 100 Hz):
/// `estimators::period::WARMUP_SAMPLES`, the samples the period rule reads.
pub const WARMUP_SAMPLES: usize = estimators::period::WARMUP_SAMPLES;

/// Counters reported at the end of a run. Every counter saturates (the `u64` ones would need
/// 5e9 years at 100 Hz to wrap; they use saturating adds all the same). Invariants at the end
/// of a run: `yaw_packets = samples + time faults' discarded + duplicates` (plus one sample
/// still held by the time base before `finish`), and `samples = rows + rejected +
/// format_errors` once the bank runs.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counters {
    /// Samples with a usable time stamp, released by the time base to the bank (held warm-up
    /// samples included).
    pub samples: u64,
    /// Rows written (one per sample the bank accepted).
    pub rows: u64,
    /// Samples rejected by the bank (non-finite or out-of-range yaw).
    pub rejected: u64,
    /// CRC-valid frames that failed to decode (a known type with a wrong length).
    pub decode_errors: u64,
    /// Rows that did not fit the row buffer (never expected; counted, not hidden).
    pub format_errors: u64,
    /// Decoded packets that carry yaw (A0/A1/A2/N0/N1/B1), before the time rules.
    pub yaw_packets: u64,
    /// Gaps longer than the gap rule: the bank re-initialised (`YawBank::reinit_count`).
    pub gaps: u32,
}

/// The bank could not be built (from the defaults, or for the measured packet period).
#[derive(Debug)]
pub struct ConfigError(pub estimators::ConfigError);

/// A timed yaw sample waiting for the bank.
#[derive(Clone, Copy, Debug)]
struct Sample {
    t_us: u64,
    yaw_deg: f32,
    rate_deg_s: f32,
    new_epoch: bool,
}

impl Sample {
    fn from_timed(t: Timed<(f32, f32)>) -> Self {
        Self {
            t_us: t.t_us,
            yaw_deg: t.payload.0,
            rate_deg_s: t.payload.1,
            new_epoch: t.new_epoch,
        }
    }
}

/// The bank and what it needs to run, before and after the warm-up.
#[allow(
    clippy::large_enum_variant,
    reason = "no heap to box into; the warm-up buffer and the bank share the same RAM"
)]
enum Stage {
    /// Collecting the first samples.
    Warmup(heapless::Vec<Sample, WARMUP_SAMPLES>),
    /// Running.
    Running(Bank),
    /// The bank could not be built for the measured period.
    Failed(estimators::ConfigError),
}

/// Parser + clock + bank.
pub struct Pipeline {
    parser: Parser,
    clock: TimeBase<(f32, f32)>,
    cfg: BankConfig,
    stage: Stage,
    counters: Counters,
}

/// Runs one sample through the bank and emits its row.
#[inline(never)]
fn run_sample(bank: &mut Bank, counters: &mut Counters, s: Sample, emit: &mut dyn FnMut(&str)) {
    if s.new_epoch {
        bank.new_epoch();
    }
    let res = bank.update(s.t_us, s.yaw_deg);
    counters.gaps = bank.reinit_count();
    let Ok(out) = res else {
        counters.rejected = counters.rejected.saturating_add(1);
        return;
    };
    let mut row = Row::new();
    let ok = estimators::csv::write_row(&mut row, s.t_us, s.rate_deg_s, &out).is_ok()
        && (row.ends_with('\n') || row.push('\n').is_ok());
    if ok {
        counters.rows = counters.rows.saturating_add(1);
        emit(row.as_str());
    } else {
        counters.format_errors = counters.format_errors.saturating_add(1);
    }
}

/// Builds a bank (one out-of-line copy of the constructor for both callers: it is large).
#[inline(never)]
fn build_bank(cfg: &BankConfig) -> Result<Bank, estimators::ConfigError> {
    Bank::new(cfg)
}

/// Ends the warm-up: builds the bank for the measured period and runs the held samples.
/// (The bank is written straight into `stage` to keep few copies of it on the stack.)
#[inline(never)]
fn start(
    cfg: &BankConfig,
    stage: &mut Stage,
    counters: &mut Counters,
    emit: &mut impl FnMut(&str),
) {
    let Stage::Warmup(held) = stage else {
        return;
    };
    let held = held.clone();
    let cfg = PeriodEstimator::from_times(held.iter().map(|s| s.t_us)).apply(*cfg);
    *stage = match build_bank(&cfg) {
        Ok(bank) => Stage::Running(bank),
        Err(e) => Stage::Failed(e),
    };
    if let Stage::Running(bank) = stage {
        for s in &held {
            run_sample(bank, counters, *s, emit);
        }
    }
}

/// One sample released by the time base: into the warm-up buffer or through the bank.
fn take_sample(
    cfg: &BankConfig,
    stage: &mut Stage,
    counters: &mut Counters,
    s: Sample,
    emit: &mut impl FnMut(&str),
) {
    counters.samples = counters.samples.saturating_add(1);
    let warmup_done = match stage {
        Stage::Running(bank) => {
            run_sample(bank, counters, s, emit);
            false
        }
        Stage::Warmup(held) => {
            // Cannot fail: the warm-up ends as soon as the buffer is full.
            let _ = held.push(s);
            held.is_full()
        }
        Stage::Failed(_) => false,
    };
    if warmup_done {
        start(cfg, stage, counters, emit);
    }
}

impl Pipeline {
    /// A pipeline with the bank presets of `nav440 estimate` (`BankConfig::default()`),
    /// checked here once so that a bad configuration fails at start.
    pub fn new() -> Result<Self, ConfigError> {
        let cfg = BankConfig::default();
        build_bank(&cfg).map_err(ConfigError)?;
        Ok(Self {
            parser: Parser::new(),
            clock: TimeBase::new(),
            cfg,
            stage: Stage::Warmup(heapless::Vec::new()),
            counters: Counters::default(),
        })
    }

    /// Feeds received bytes; `emit` gets every CSV row (newline-terminated) in order.
    /// Fails if the bank cannot be built for the measured packet period (then `nav440
    /// estimate` fails too); later calls fail the same way.
    pub fn feed(&mut self, bytes: &[u8], mut emit: impl FnMut(&str)) -> Result<(), ConfigError> {
        let Self {
            parser,
            clock,
            cfg,
            stage,
            counters,
        } = self;
        parser.feed(bytes, |frame| {
            let packet = match Packet::decode(frame) {
                Ok(p) => p,
                Err(_) => {
                    counters.decode_errors = counters.decode_errors.saturating_add(1);
                    return;
                }
            };
            let Some(sample) = packet.yaw_sample() else {
                return;
            };
            counters.yaw_packets = counters.yaw_packets.saturating_add(1);
            for t in clock.update(sample.time, (sample.yaw_deg, sample.yaw_rate_deg_s)) {
                take_sample(cfg, stage, counters, Sample::from_timed(t), &mut emit);
            }
        });
        match &self.stage {
            Stage::Failed(e) => Err(ConfigError(*e)),
            _ => Ok(()),
        }
    }

    /// End of a finite input: runs a capture shorter than the warm-up.
    pub fn finish(&mut self, mut emit: impl FnMut(&str)) -> Result<(), ConfigError> {
        if let Some(t) = self.clock.finish() {
            take_sample(
                &self.cfg,
                &mut self.stage,
                &mut self.counters,
                Sample::from_timed(t),
                &mut emit,
            );
        }
        start(&self.cfg, &mut self.stage, &mut self.counters, &mut emit);
        match &self.stage {
            Stage::Failed(e) => Err(ConfigError(*e)),
            _ => Ok(()),
        }
    }

    /// Parser statistics (bytes, frames, CRC errors, skipped bytes).
    pub fn parser_stats(&self) -> &nav440_proto::Stats {
        self.parser.stats()
    }

    /// Pipeline counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// Time-stamp faults so far (`nav440_proto::TimeBase`).
    pub fn time_faults(&self) -> &TimeFaults {
        self.clock.faults()
    }

    /// Writes the one-line summary of all counters (`key=value` pairs) into `w`.
    pub fn summary(
        &self,
        w: &mut impl core::fmt::Write,
        uart_overruns: u32,
        uart_stalls: u32,
    ) -> core::fmt::Result {
        let s = self.parser.stats();
        let c = &self.counters;
        let f = self.clock.faults();
        write!(
            w,
            "bytes={} frames={} crc_errors={} skipped={} decode_errors={} samples={} rows={} rejected={} format_errors={} uart_overruns={} uart_stalls={}",
            s.bytes, s.frames, s.crc_errors, s.skipped_bytes, c.decode_errors, c.samples, c.rows, c.rejected, c.format_errors, uart_overruns, uart_stalls
        )?;
        write!(
            w,
            " yaw_packets={} impossible={} bad_backward={} bad_forward={} backward_jumps={} kind_switches={} other_kind={} duplicates={} gaps={}",
            c.yaw_packets, f.impossible, f.bad_backward, f.bad_forward, f.backward_jumps, f.kind_switches, f.other_kind, f.duplicates, c.gaps
        )
    }
}
