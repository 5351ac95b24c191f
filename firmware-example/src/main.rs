//! Firmware example: configures a NAV440 on UART0, then NAV440 bytes -> parser -> estimator
//! bank -> one defmt `row` message per sample; diagnostics and counters are defmt messages
//! too (`firmware_example::out`). Transport: semihosting stdout under QEMU, RTT on the real
//! board; `cargo xtask qemu/demo/unit` decode the frames into the CSV of `nav440 estimate`.
//!
//! # Boot and run (unit mode, the default)
//! 1. The UARTs and SysTick (1 kHz time base) start (the stack was painted by the reset
//!    handler, cortex-m-rt's `paint-stack`): the NAV440 UART's receive interrupt is the first
//!    interrupt.
//! 2. `nav440_proto::boot::boot` configures the unit to [`TARGET`] (A2 at 100 Hz at
//!    57600 Bd, checked against the unit's byte budget at compile time): find it (ping at
//!    57600, 38400, 19200, 9600 Bd), switch the baud, set type and rate, read them back. The
//!    firmware has no protocol code: it passes its UART, its SysTick delay and a baud-change
//!    callback. Frames received while configuring are counted (`boot_frames`), not estimated.
//! 3. Estimation starts with the first byte after the read-back reply.
//! 4. End of a run under QEMU: the harness (`cargo xtask unit`) counts the bytes the unit
//!    sent and, once the unit has closed the connection, sends `N4EN` + that count (u32 LE) on
//!    the control channel (UART1 / USART2); the firmware stops after exactly that many bytes
//!    have been read from the NAV440 UART and processed, prints its counters and exits 0.
//!    The rule depends on byte counts only, never on the host's speed.
//!
//! Every failure sends one `firmware: ...` message and exits with a documented
//! status ([`Status`]); on a real board (`board::RETRY_FOREVER`) a failed boot is
//! retried forever, one diagnostic line per attempt.
//!
//! # Replay mode (`cargo xtask qemu FILE`)
//! With `replay` on the semihosting command line the firmware does not talk to a unit: the
//! stream on UART0 starts with `N4LP` and the capture's length (u32 LE), and the firmware
//! processes exactly that many bytes. A stream without the prefix is refused (status 1).
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicBool, Ordering};
use cortex_m_rt::entry;
use embedded_io::{Read as _, ReadReady as _};
use firmware_example::uart::{Board, Control, EndMessage, Uart0};
use firmware_example::{board, host, log, out, pipeline, time};
use nav440_pipeline::report::{self, Flow};
use nav440_proto::boot::{self, BootError, Options, Report, Target};
use nav440_proto::driver::{IoDriver, Timing};
use nav440_proto::Baud;

/// The configuration the firmware gives the unit: A2 at 100 Hz at 57600 Bd.
pub const TARGET: Target = Target::DEFAULT;
// 37 B x 100 Hz = 3700 B/s must fit 0.81 x 57600 / 10 = 4665 B/s: checked when compiling.
const _: () = assert!(
    TARGET.fits_budget(),
    "TARGET exceeds the unit's byte budget"
);

/// Local UART rate before the search (the NAV440's factory default; the search tries all).
const POWER_UP_BAUD: u32 = 38_400;

/// Magic at the start of a finite input (replay mode).
const LENGTH_MAGIC: [u8; 4] = *b"N4LP";

/// Exit statuses under QEMU (the firmware's semihosting exit code becomes QEMU's and
/// `cargo xtask unit`'s).
#[derive(Clone, Copy)]
#[repr(u32)]
pub enum Status {
    /// Every byte the unit sent was processed.
    Ok = 0,
    /// Panic, HardFault, bank configuration rejected, bad replay input, serial port error,
    /// bad control message.
    Internal = 1,
    /// The unit did not answer (no ping reply at any baud, or a request unanswered).
    NoAnswer = 2,
    /// The unit rejected a configuration request (NAK, or accepted only some fields).
    Rejected = 3,
    /// The read-back (GF) does not show the configuration that was set, or the unit's first
    /// GF holds a value the protocol does not define.
    WrongReadBack = 4,
    /// After configuration the unit sent frames of another type: it reset (or was
    /// reconfigured by someone else) mid-stream.
    UnitReset = 5,
}

fn fail(status: Status) -> ! {
    host::exit_code(status as u32)
}

/// The exit status of a boot failure.
fn boot_status<E>(e: &BootError<E>) -> Status {
    match e {
        BootError::NoAnswer { .. } => Status::NoAnswer,
        BootError::Nak { .. } | BootError::NotAccepted { .. } => Status::Rejected,
        BootError::WrongReadBack { .. } | BootError::UndefinedValue { .. } => Status::WrongReadBack,
        BootError::Serial(_) | BootError::WriteZero | BootError::Encode(_) => Status::Internal,
    }
}

#[entry]
fn main() -> ! {
    log::init();
    let Some(core) = cortex_m::Peripherals::take() else {
        defmt::println!("firmware: core peripherals already taken");
        fail(Status::Internal)
    };
    let Some(board) = Board::take(POWER_UP_BAUD) else {
        defmt::println!("firmware: UARTs already taken");
        fail(Status::Internal)
    };
    if let Err(e) = pipeline::check() {
        defmt::println!("firmware: bank configuration rejected: {}", e);
        fail(Status::Internal)
    }
    let mut pipe = pipeline::new();
    let Board {
        nav: uart,
        control,
        core_clock_hz,
    } = board;
    if replay_requested() {
        replay(uart, &mut pipe)
    }
    // The time base of the boot's time-outs (replay mode needs none).
    let mut delay = time::start(core.SYST, core_clock_hz);
    let mut uart = uart;
    let mut control = control;
    // The bytes the driver read past the read-back reply, refilled by each configuration.
    let mut pending = Pending::new();
    loop {
        let (configured, report) = configure(uart, &mut delay, &mut pending);
        // Returns after a silence, or a unit reset on the real-board profile: configure the
        // unit again.
        uart = stream(configured, &mut control, &mut pipe, &report, &pending);
    }
}

/// `replay` is on the semihosting command line (`cargo xtask qemu FILE`). Out of line (as
/// [`replay`]): its buffer is not in `main`'s frame.
#[inline(never)]
fn replay_requested() -> bool {
    // A real board always talks to a unit (and a probe may not serve the call).
    if !board::REPLAY {
        return false;
    }
    let mut buf = [0u8; 96];
    host::cmdline(&mut buf)
        .split(|&b| b == b' ')
        .any(|w| w == b"replay")
}

/// Bytes the driver had read past the read-back reply (at most one frame).
type Pending = heapless::Vec<u8, { nav440_proto::MAX_FRAME }>;

/// Runs the boot sequence until it succeeds (real board) or fails once (QEMU: exits).
/// Out of line: its frame (driver, boot state, error text) is not live while estimating.
#[inline(never)]
fn configure(uart: Uart0, delay: &mut time::Delay, pending: &mut Pending) -> (Uart0, Report) {
    let mut driver = IoDriver::new(uart);
    driver.set_timing(Timing {
        reply_timeout_ms: board::REPLY_TIMEOUT_MS,
        ..Timing::DEFAULT
    });
    let mut attempt: u32 = 0;
    loop {
        attempt += 1;
        let r = boot::boot(
            &mut driver,
            &TARGET,
            &Options::DEFAULT,
            delay,
            |uart: &mut Uart0, b: Baud| {
                uart.set_baud(b.bits_per_second())
                    .map_err(firmware_example::uart::Error::from)
            },
        );
        match r {
            Ok(report) => {
                pending.clear();
                // Cannot fail: the driver holds at most one frame's bytes.
                let _ = pending.extend_from_slice(driver.pending_bytes());
                let (uart, _) = driver.into_parts();
                return (uart, report);
            }
            Err(e) => {
                // The error's diagnostic text, the same as its `Display` (rendered by the
                // host from defmt: no `core::fmt` in the image).
                defmt::println!("firmware: boot attempt {=u32} failed: {}", attempt, e);
                if !board::RETRY_FOREVER {
                    fail(boot_status(&e))
                }
                // Real board: one attempt (and one diagnostic line) per second at most.
                embedded_hal::delay::DelayNs::delay_ms(delay, board::RETRY_PAUSE_MS);
            }
        }
    }
}

/// Estimation from the first byte after the read-back until the end message's count (then
/// exits). Returns the UART only when the unit reset mid-stream on the real-board profile
/// (under QEMU's mps2 boards a reset ends the run with [`Status::UnitReset`]).
#[inline(never)]
fn stream(
    mut uart: Uart0,
    control: &mut Control,
    pipe: &mut pipeline::Pipeline,
    report: &Report,
    pending: &[u8],
) -> Uart0 {
    defmt::println!(
        "firmware: unit configured: {=str} at {} Hz at {} Bd (found at {} Bd, unit was at {} Bd streaming {=str} with rate divider {}, {} ping retries); boot_frames={} boot_skipped={} boot_ms={}",
        TARGET.packet.name(),
        100 / TARGET.rate.divider().max(1),
        report.baud.bits_per_second(),
        report.found_at.bits_per_second(),
        report.unit_baud.bits_per_second(),
        report.initial_packet.name(),
        report.initial_rate_divider,
        report.ping_retries,
        report.unsolicited_frames,
        report.skipped_bytes,
        time::now_ms(),
    );
    // Only `main`'s thread touches it (a load/store pair: thumbv6m has no atomic swap).
    if !HEADER_PRINTED.load(Ordering::Relaxed) {
        HEADER_PRINTED.store(true, Ordering::Relaxed);
        print_header();
    }
    // The pipeline's stream watchdog, armed for the configured stream (its periodic counters
    // count stream time across re-configurations).
    pipe.watch(TARGET.packet, TARGET.rate, time::now_ms());
    // Feeds the pipeline and its watch (every fault printed as it is seen): `Flow::Reset` when
    // the bytes show a unit reset (the chunk is estimated first; the rest is the new power-up
    // stream: frames the pipeline does not estimate, or a cut frame it skips).
    let process = |pipe: &mut pipeline::Pipeline, bytes: &[u8]| -> Flow {
        let flow = report::feed(pipe, bytes, time::now_ms(), &mut out::row)
            .unwrap_or_else(|e| bank_failed(&e));
        #[cfg(feature = "self-tune")]
        self_tune_report(pipe);
        if flow == Flow::Reset && !board::RETRY_FOREVER {
            fail(Status::UnitReset)
        }
        flow
    };
    // Ends `stream` (re-configuration) or prints the periodic counters.
    let after = |pipe: &pipeline::Pipeline, uart: &Uart0, flow: Flow| -> bool {
        match flow {
            Flow::Go => true,
            Flow::Reset => false,
            Flow::Counters(stream_s) => {
                report::periodic(stream_s);
                out::summary(pipe, uart, uart.bytes_read());
                true
            }
        }
    };
    let flow = process(pipe, pending);
    if !after(pipe, &uart, flow) {
        return uart;
    }
    let mut end = EndMessage::default();
    let mut total: Option<u64> = None;
    let mut buf = [0u8; 64];
    loop {
        let read = uart.bytes_read();
        if let Some(n) = total {
            if read >= n {
                break;
            }
        }
        if uart.read_ready().unwrap_or(false) {
            let room = total.map_or(buf.len() as u64, |n| n - read);
            let want = (buf.len() as u64).min(room) as usize;
            let n = match uart.read(buf.get_mut(..want).unwrap_or(&mut [])) {
                Ok(n) => n,
                Err(e) => {
                    defmt::println!("firmware: UART error: {}", e);
                    fail(Status::Internal)
                }
            };
            let flow = process(pipe, buf.get(..n).unwrap_or(&[]));
            if !after(pipe, &uart, flow) {
                return uart;
            }
        } else if let Some(message) = total.is_none().then(|| end.poll(control)).flatten() {
            let n = message.unwrap_or_else(|bytes| {
                defmt::println!(
                    "firmware: bad control message {=[u8]:02x} (expected N4EN + u32 LE byte count)",
                    bytes
                );
                fail(Status::Internal)
            });
            if n < read {
                defmt::println!(
                    "firmware: control channel says the unit sent {=u64} bytes, but {=u64} were received",
                    n,
                    read
                );
                fail(Status::Internal)
            }
            defmt::println!(
                "firmware: control channel: the unit sent {=u64} bytes ({=u64} received so far)",
                n,
                read
            );
            total = Some(n);
        } else if total.is_none() && report::silence(pipe, time::now_ms()) {
            // The unit went silent with the link open (reported): configure it again (a boot
            // that fails ends the run under QEMU and is retried with a pause on a real board).
            return uart;
        } else {
            // Woken by the next received byte or the 1 ms tick.
            cortex_m::asm::wfi();
        }
    }
    finish(pipe, &uart, total.unwrap_or(0))
}

/// Sends the header message (the estimated axes, `pipeline::AXES`): the host writes the CSV
/// header line from it.
fn print_header() {
    out::header();
}

/// The CSV header has been printed (once per run, also across re-configurations).
static HEADER_PRINTED: AtomicBool = AtomicBool::new(false);

/// Ends a finite input: the held warm-up, the counters line, exit 0.
fn finish(pipe: &mut pipeline::Pipeline, uart: &Uart0, unit_bytes: u64) -> ! {
    // An epoch shorter than the warm-up is measured at the end of the input.
    if let Err(e) = report::finish(pipe, &mut out::row) {
        bank_failed(&e);
    }
    let dropped = pipe.front().counters().end_dropped_bytes;
    if dropped > 0 {
        defmt::println!(
            "firmware: the input ends inside a frame: end_dropped={=u64} bytes did not complete a frame and are dropped",
            dropped
        );
    }
    #[cfg(feature = "adaptive-gains")]
    adaptive_summary(pipe);
    #[cfg(feature = "self-tune")]
    {
        self_tune_report(pipe);
        self_tune_summary(pipe);
    }
    out::summary(pipe, uart, unit_bytes);
    host::exit(true)
}

/// With `adaptive-gains`: one line per axis, how many times its gains changed, the noise
/// variance (deg^2) the current gains are for and whether the schedule runs off the rate it
/// was tuned at (1, `AdaptiveBank::period_fits` false; else 0); `{axis}_retunes` and
/// `{axis}_schedule_off_rate` are counters for `xtask`.
#[cfg(feature = "adaptive-gains")]
fn adaptive_summary(pipe: &pipeline::Pipeline) {
    for axis in pipeline::AXES.iter() {
        if let Some(b) = pipe.estimation().bank(axis) {
            defmt::println!(
                "firmware: adaptive gains, {=str}: {=str}_retunes={=u32} gain_level_deg2={=f32} {=str}_schedule_off_rate={=u32}",
                axis.name(),
                axis.name(),
                b.retune_count(),
                b.gain_level(),
                axis.name(),
                u32::from(!b.period_fits())
            );
        }
    }
}

/// How many settlings of each axis's self-tuning bank were reported (only `main`'s thread
/// touches them: load/store pairs, thumbv6m has no atomic read-modify-write).
#[cfg(feature = "self-tune")]
static SETTLES_REPORTED: [core::sync::atomic::AtomicU32; 3] =
    [const { core::sync::atomic::AtomicU32::new(0) }; 3];

/// With `self-tune`: one line for each new settling of an axis's bank, the gains it settled at
/// (`nav440 estimate --self-tune` prints where each axis ended on stderr).
#[cfg(feature = "self-tune")]
fn self_tune_report(pipe: &pipeline::Pipeline) {
    for axis in pipeline::AXES.iter() {
        let Some(b) = pipe.estimation().bank(axis) else {
            continue;
        };
        let reported = &SETTLES_REPORTED[axis.index()];
        if b.settle_count() == reported.load(Ordering::Relaxed) {
            continue;
        }
        reported.store(b.settle_count(), Ordering::Relaxed);
        if let Some(s) = b.settled() {
            defmt::println!(
                "firmware: self-tune: {=str}: ILO1 settled at wn={=f32} rad/s zeta={=f32} (K1 {=f32}, L {=f32} 1/s, K2 {=f32}; window MSE {=f32} (deg/s)^2 against the rate) after {=u32} moves",
                axis.name(),
                s.wn_rad_s,
                s.zeta,
                s.ilo1.k1,
                s.ilo1.l,
                s.ilo1.k2,
                s.mse,
                s.moves
            );
        }
    }
}

/// With `self-tune`: one line per axis at the end, where its gains are; `{axis}_moves` and
/// `{axis}_settles` are counters for `xtask`.
#[cfg(feature = "self-tune")]
fn self_tune_summary(pipe: &pipeline::Pipeline) {
    for axis in pipeline::AXES.iter() {
        if let Some(b) = pipe.estimation().bank(axis) {
            let (wn, zeta) = b.gains();
            defmt::println!(
                "firmware: self-tune, {=str}: wn={=f32} rad/s zeta={=f32} {=str}_moves={=u32} {=str}_settles={=u32}",
                axis.name(),
                wn as f32,
                zeta as f32,
                axis.name(),
                b.move_count(),
                axis.name(),
                b.settle_count()
            );
        }
    }
}

/// The bank cannot run at the measured packet period: report and exit with status 1 (as
/// `nav440 estimate` fails on the same capture).
fn bank_failed(e: &pipeline::ConfigError) -> ! {
    defmt::println!(
        "firmware: bank configuration rejected for this capture's packet period: {}",
        e
    );
    fail(Status::Internal)
}

/// Replay mode: `N4LP` + length, then exactly that many capture bytes (see the module doc).
#[inline(never)]
fn replay(mut uart: Uart0, pipe: &mut pipeline::Pipeline) -> ! {
    let mut prefix = [0u8; 8];
    read_prefix(&mut uart, &mut prefix);
    let (magic, len) = prefix.split_at(4);
    if magic != LENGTH_MAGIC {
        defmt::println!(
            "firmware: input does not start with the N4LP length prefix (got {=[u8]:02x}); use `cargo xtask qemu FILE`",
            magic
        );
        fail(Status::Internal)
    }
    let mut remaining = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
    print_header();
    let mut buf = [0u8; 64];
    while remaining > 0 {
        let want = remaining.min(buf.len());
        let n = uart.read(&mut buf[..want]).unwrap_or(0);
        // No watch is armed in replay mode: only the period change is reported.
        if let Err(e) = report::feed(pipe, &buf[..n], 0, &mut out::row) {
            bank_failed(&e);
        }
        remaining -= n;
    }
    let replayed = uart.bytes_read().saturating_sub(8);
    finish(pipe, &uart, replayed)
}

/// Reads the length prefix byte by byte through the `embedded_hal_nb::serial::Read` side of
/// the driver (the capture itself goes through `embedded_io::Read`), polling: 8 bytes, once.
fn read_prefix(uart: &mut Uart0, buf: &mut [u8]) {
    for slot in buf.iter_mut() {
        *slot = loop {
            match embedded_hal_nb::serial::Read::read(uart) {
                Ok(b) => break b,
                Err(nb::Error::WouldBlock) => cortex_m::asm::wfi(),
                Err(nb::Error::Other(e)) => {
                    defmt::println!("firmware: UART error: {}", e);
                    fail(Status::Internal)
                }
            }
        };
    }
}
