//! The firmware's pipeline, the embedded twin of `host-tests`' replay (`nav440 estimate`):
//! bytes -> `nav440_proto::Parser` -> `Packet::decode` -> `Packet::yaw_sample` ->
//! `ItowClock` (time in us since the first sample) -> `estimators::YawBank` ([`crate::Bank`], the paper's
//! presets, `BankConfig::default()`: h = 1e-4 s, linear hold) -> one CSV row per sample,
//! formatted by `estimators::csv` exactly as the host does.
//!
//! A sample the bank rejects (time not increasing, non-finite yaw) yields no row and is
//! counted, as on the host.

use estimators::BankConfig;
use nav440_proto::{ItowClock, Packet, Parser};

use crate::Bank;

/// Longest CSV row: 17 fields of at most ~16 characters plus separators.
pub const ROW_CAPACITY: usize = 512;

/// One formatted CSV row (with its trailing newline).
pub type Row = heapless::String<ROW_CAPACITY>;

/// The CSV header, identical to `nav440 estimate`'s.
pub const CSV_HEADER: &str = "t,yaw,yaw_rate,ave_v,ilo1_v,ilo2_v,ilo3_v,ad_v,ed_v,kf_v,ave_a,ilo1_a,ilo2_a,ilo3_a,ad_a,ed_a,kf_a\n";

/// Counters reported at the end of a run.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counters {
    /// Packets that carried a yaw sample with a usable time stamp.
    pub samples: u64,
    /// Rows written.
    pub rows: u64,
    /// Samples rejected by the bank.
    pub rejected: u64,
    /// Packets that failed to decode (CRC was fine, content was not).
    pub decode_errors: u64,
    /// Rows that did not fit the row buffer (never expected; counted, not hidden).
    pub format_errors: u64,
}

/// Parser + clock + bank.
pub struct Pipeline {
    parser: Parser,
    clock: ItowClock,
    bank: Bank,
    counters: Counters,
}

/// The bank could not be built from the default configuration.
#[derive(Debug)]
pub struct ConfigError(pub estimators::ConfigError);

impl Pipeline {
    /// A pipeline with the bank presets of `nav440 estimate` (`BankConfig::default()`).
    pub fn new() -> Result<Self, ConfigError> {
        let cfg = BankConfig::default();
        Ok(Self {
            parser: Parser::new(),
            clock: ItowClock::new(),
            bank: Bank::new(&cfg).map_err(ConfigError)?,
            counters: Counters::default(),
        })
    }

    /// Feeds received bytes; `emit` gets every CSV row (newline-terminated) in order.
    pub fn feed(&mut self, bytes: &[u8], mut emit: impl FnMut(&str)) {
        let Self {
            parser,
            clock,
            bank,
            counters,
        } = self;
        parser.feed(bytes, |frame| {
            let packet = match Packet::decode(frame) {
                Ok(p) => p,
                Err(_) => {
                    counters.decode_errors += 1;
                    return;
                }
            };
            let Some(sample) = packet.yaw_sample() else {
                return;
            };
            let Some(t_us) = clock.update(sample.time) else {
                return;
            };
            counters.samples += 1;
            let Ok(out) = bank.update(t_us, sample.yaw_deg) else {
                counters.rejected += 1;
                return;
            };
            let mut row = Row::new();
            let ok = estimators::csv::write_row(&mut row, t_us, sample.yaw_rate_deg_s, &out)
                .is_ok()
                && (row.ends_with('\n') || row.push('\n').is_ok());
            if ok {
                counters.rows += 1;
                emit(row.as_str());
            } else {
                counters.format_errors += 1;
            }
        });
    }

    /// Parser statistics (bytes, frames, CRC errors, skipped bytes).
    pub fn parser_stats(&self) -> &nav440_proto::Stats {
        self.parser.stats()
    }

    /// Pipeline counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
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
        write!(
            w,
            "bytes={} frames={} crc_errors={} skipped={} decode_errors={} samples={} rows={} rejected={} format_errors={} uart_overruns={} uart_stalls={}",
            s.bytes, s.frames, s.crc_errors, s.skipped_bytes, c.decode_errors, c.samples, c.rows, c.rejected, c.format_errors, uart_overruns, uart_stalls
        )
    }
}
