//! The `firmware: ...` defmt messages of a device that runs the pipeline with its stream
//! watchdog (feature `defmt`): one implementation, so that every firmware of the workspace
//! (firmware-example's images, its embassy example, firmware-embassy) reports the same
//! faults with the same text, decoded on the host from the ELF's defmt table.
//!
//! * [`feed`]: bytes through [`Pipeline::feed_watched`]; each stream fault the watch reports
//!   ([`crate::watch::Event`]) is one line at the frame where it is seen ([`fault`], and
//!   `unit reset mid-stream: ...` for a frame of another type), a period change one line after
//!   the chunk ([`period_change`]); the caller gets what to do next ([`Flow`]).
//! * [`silence`]: the watch's silence check, one line when the stream went silent.
//! * [`periodic`] and [`summary`]: the periodic counters (`counters after N s of stream:`
//!   and the `key=value` counters line, which also ends a finite run).
//!
//! What the device does then (configure the unit again, exit with a status) is its own.

use crate::watch::Event;
use crate::{Pipeline, Row};
use estimators::EstimatorBank;

/// What a device does after a chunk of bytes ([`feed`]); the largest of the chunk's events
/// counts (`Reset` > `Counters` > `Go`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Flow {
    /// Go on reading.
    Go,
    /// Another [`crate::watch::COUNTER_INTERVAL_S`] s of stream: print the counters
    /// ([`periodic`], [`summary`]), then go on.
    Counters(u32),
    /// A frame of another type than the configured one: the unit reset (or was reconfigured);
    /// configure it again (or end the run).
    Reset,
}

/// Feeds `bytes` received at `now_ms` through `pipe` and its armed watch
/// ([`Pipeline::feed_watched`]), `emit` getting every row. Prints every stream fault at once
/// ([`fault`]; a frame of another type as `unit reset mid-stream: T frame received after
/// configuring C (N bytes estimated)`, N the bytes parsed before this chunk) and, after the
/// chunk, a change of the nominal period ([`period_change`]). Fails as
/// [`Pipeline::feed`] does (no line printed then).
pub fn feed<
    B: EstimatorBank,
    E: Clone,
    F: FnMut(crate::Axis, &estimators::BankConfig) -> Result<B, E>,
    const N: usize,
    R: crate::Reference,
    D: crate::Decoder,
>(
    pipe: &mut Pipeline<B, E, F, N, R, D>,
    bytes: &[u8],
    now_ms: u32,
    emit: &mut dyn FnMut(&Row<B::Output>),
) -> Result<Flow, E> {
    let changes = pipe.estimation().counters().period_changes;
    let estimated = pipe.front().parser_stats().bytes;
    let mut flow = Flow::Go;
    pipe.feed_watched(bytes, now_ms, emit, &mut |e| match e {
        Event::ForeignType { got, configured } => {
            defmt::println!(
                "firmware: unit reset mid-stream: {=str} frame received after configuring {=str} ({=u64} bytes estimated)",
                got.name(),
                configured.name(),
                estimated
            );
            flow = Flow::Reset;
        }
        Event::Periodic { stream_s } => flow = flow.max(Flow::Counters(stream_s)),
        other => fault(&other),
    })?;
    period_change(pipe, changes);
    Ok(flow)
}

/// [`Pipeline::finish`] (the end of a finite input: the held sample, an epoch shorter than the
/// warm-up), then [`period_change`].
pub fn finish<
    B: EstimatorBank,
    E: Clone,
    F: FnMut(crate::Axis, &estimators::BankConfig) -> Result<B, E>,
    const N: usize,
    R: crate::Reference,
    D: crate::Decoder,
>(
    pipe: &mut Pipeline<B, E, F, N, R, D>,
    emit: &mut dyn FnMut(&Row<B::Output>),
) -> Result<(), E> {
    let changes = pipe.estimation().counters().period_changes;
    pipe.finish(emit)?;
    period_change(pipe, changes);
    Ok(())
}

/// Checks `pipe`'s watch for silence at `now_ms` ([`Pipeline::poll_watch`]); a silence is
/// printed ([`fault`]: `stream silent: ...; configuring the unit again`) and returns `true`
/// (once per silence): the device configures the unit again.
pub fn silence<
    B: EstimatorBank,
    E: Clone,
    F: FnMut(crate::Axis, &estimators::BankConfig) -> Result<B, E>,
    const N: usize,
    R: crate::Reference,
    D: crate::Decoder,
>(
    pipe: &mut Pipeline<B, E, F, N, R, D>,
    now_ms: u32,
) -> bool {
    match pipe.poll_watch(now_ms) {
        Some(e) => {
            fault(&e);
            true
        }
        None => false,
    }
}

/// The one-line message of a watch event, at the moment it is seen.
pub fn fault(e: &Event) {
    match *e {
        Event::Silence {
            silent_ms,
            limit_ms,
        } => defmt::println!(
            "firmware: stream silent: no complete frame for {=u32} ms (limit {=u32} ms); configuring the unit again",
            silent_ms,
            limit_ms
        ),
        Event::Frozen { frames, stamp_ms } => defmt::println!(
            "firmware: time stamps frozen: {=u32} frames in a row stamped {=u32} ms",
            frames,
            stamp_ms
        ),
        Event::Thawed { frames } => defmt::println!(
            "firmware: time stamps advance again after {=u32} frames with one stamp",
            frames
        ),
        Event::RateMismatch {
            measured_us,
            configured_us,
        } => defmt::println!(
            "firmware: packet rate differs from the configuration: a period of {=u32} us measured, {=u32} us configured",
            measured_us,
            configured_us
        ),
        Event::ForeignType { got, configured } => defmt::println!(
            "firmware: {=str} frame received, {=str} configured",
            got.name(),
            configured.name()
        ),
        Event::Periodic { stream_s } => {
            defmt::println!("firmware: {=u32} s of stream", stream_s)
        }
    }
}

/// Reports a new time epoch at another packet rate while it happens (a unit reset or re-boot
/// at another rate: the pipeline measured the period on the epoch's first samples and rebuilt
/// the banks for it) when `pipe`'s count of period changes
/// ([`crate::Counters::period_changes`]) has moved past `before`.
pub fn period_change<
    B: EstimatorBank,
    E: Clone,
    F: FnMut(crate::Axis, &estimators::BankConfig) -> Result<B, E>,
    const N: usize,
    R: crate::Reference,
    D: crate::Decoder,
>(
    pipe: &Pipeline<B, E, F, N, R, D>,
    before: u32,
) {
    if pipe.estimation().counters().period_changes != before {
        defmt::println!(
            "firmware: new time epoch at another packet rate: nominal sample period now {=u32} us; banks rebuilt",
            pipe.estimation()
                .period_us()
                .map_or(0, |us| u32::try_from(us).unwrap_or(u32::MAX))
        );
    }
}

/// The line before the periodic counters ([`Flow::Counters`]): `counters after N s of
/// stream:`; [`summary`] follows.
pub fn periodic(stream_s: u32) {
    defmt::println!("firmware: counters after {=u32} s of stream:", stream_s);
}

/// Sends the counters: the `key=value` line of [`Pipeline::summary`] (same keys, same order)
/// followed by `unit_bytes` (bytes the unit sent, or received so far) and `stack_peak` (the
/// stack's high-water mark, bytes).
pub fn summary<
    B: EstimatorBank,
    E: Clone,
    F: FnMut(crate::Axis, &estimators::BankConfig) -> Result<B, E>,
    const N: usize,
    R: crate::Reference,
    D: crate::Decoder,
>(
    pipe: &Pipeline<B, E, F, N, R, D>,
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
        "firmware: bytes={=u64} frames={=u64} crc_errors={=u64} skipped={=u64} decode_errors={=u64} samples={=u64} rows={=u64} rejected={=u64} format_errors={=u64} uart_overruns={=u32} uart_stalls={=u32} yaw_packets={=u64} impossible={=u32} bad_backward={=u32} bad_forward={=u32} backward_jumps={=u32} kind_switches={=u32} other_kind={=u32} duplicates={=u32} gaps={=u32} near_lock={=u64} lock_passes={=u32} bit_failed={=u64} bit_flag={=str} bit_hardware_error={=u64} bit_com_error={=u64} bit_software_error={=u64} bit_last=0x{=u16:04x} unit_bytes={=u64} stack_peak={=usize}",
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
        c.near_lock,
        c.lock_passes,
        fc.bit.failed,
        crate::bit::FAILURE_FLAG,
        fc.bit.hardware_error,
        fc.bit.com_error,
        fc.bit.software_error,
        fc.bit.last_word,
        unit_bytes,
        stack_peak
    );
}
