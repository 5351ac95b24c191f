//! Instruction-count benchmark, run by `cargo xtask bench` under `qemu -icount shift=6`.
//!
//! Prints tab-separated lines on the host's stdout (semihosting):
//! * `instr <label> <instructions per unit> <unit>` - unit `sample` (one 10 ms NAV440 sample =
//!   100 steps of h = 1e-4 s for a stepped law), `byte` (parser) or `call`;
//! * `ram <label> <bytes>` - `core::mem::size_of` of each estimator's state.
//!
//! Also the link to the unit: `transmit` (per byte written through the UART's
//! `embedded_io::Write`, QEMU's UART drains at once with `-serial none`) and `boot sequence`
//! (per call of `nav440_proto::boot::boot` from a unit at its power-up configuration, S1 at
//! 20 Hz at 38400 Bd, to A2 at 100 Hz at 57600 Bd: ping, GF, SF baud, ping, SF type/rate, GF).
//! The boot runs over [`ScriptPort`], which hands back the unit's replies (recorded once from
//! the `nav440_proto::unit` model, not measured) as soon as each request is flushed: the
//! figure is the firmware's own work (driver, parser, encoding), without waiting.
//!
//! Each region is timed with two SysTick reads ([`Counter`]); the counter overhead (an empty
//! region) is subtracted. Inputs are a yaw signal of the Fig. 5 kind (sine sweep in degrees)
//! sampled at 100 Hz, after a warm-up so that steady-state code paths are measured.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m_rt::entry;
use estimators::{
    advance_by_steps, Ad, AdParams, Ave, AveParams, BankConfig, ClosedForm, Ed, EdParams,
    Estimator, Hold, Ilo, IloParams, Kalman, KalmanConfig, PaperBank, ProductBank, Real, Series,
    Stateful, Wrap,
};
use firmware_example::{cycles::Counter, host, uart::Board, BankSqrt, Num};

/// The paper bank as the firmware runs it (also with `adaptive-gains`, whose bank is measured
/// separately below).
type Bank = PaperBank<Num, BankSqrt>;
use heapless::String;
use nav440_proto::boot::{Options, Target};
use nav440_proto::driver::IoDriver;
use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::{encode_frame, ItowClock, PacketType, Parser};

/// Steps per sample: h = 1e-4 s, 100 Hz samples (the paper's step).
const STEPS: u32 = 100;
/// Sample period, us.
const DT_US: u64 = 10_000;
/// Measured samples per estimator (after [`WARMUP`]).
const SAMPLES: u32 = 50;
/// Warm-up samples.
const WARMUP: u32 = 20;

/// Test yaw at sample `k`, degrees (wrapped to +-180 only where the bank is fed).
fn yaw(k: u32) -> f32 {
    let t = k as f32 * 0.01;
    // Polynomial stand-in for a smooth sweep (no libm needed in the harness): a triangle-ish
    // back-and-forth of +-90 deg with a 4 s period.
    let p = t % 4.0;
    let x = if p < 2.0 { p - 1.0 } else { 3.0 - p };
    90.0 * x * (1.5 - 0.5 * x * x)
}

fn line(kind: &str, label: &str, value: f32, unit: &str) {
    let mut s: String<96> = String::new();
    use core::fmt::Write as _;
    let _ = if unit.is_empty() {
        writeln!(s, "{kind}\t{label}\t{value}")
    } else {
        writeln!(s, "{kind}\t{label}\t{value}\t{unit}")
    };
    host::stdout(s.as_bytes());
}

fn ram(label: &str, bytes: usize) {
    line("ram", label, bytes as f32, "");
}

/// Per-sample instructions of `advance(estimator, previous sample, new sample)` over
/// `SAMPLES` samples of 100 steps each, after `WARMUP` samples.
fn measure_samples<E: Estimator<Num>>(
    c: &Counter,
    overhead: u64,
    label: &str,
    mut e: E,
    advance: impl Fn(&mut E, Num, Num) -> Num,
) {
    let mut total = 0u64;
    let mut prev = Num::from_f32(yaw(0));
    e.reset(prev);
    for k in 1..=(WARMUP + SAMPLES) {
        let y = Num::from_f32(yaw(k));
        let (n, out) = c.measure(|| advance(black_box(&mut e), black_box(prev), black_box(y)));
        black_box(out);
        if k > WARMUP {
            total += n.saturating_sub(overhead);
        }
        prev = y;
    }
    line("instr", label, total as f32 / SAMPLES as f32, "sample");
}

/// Per-sample instructions of `Estimator::advance` (closed form where the law has one).
fn per_sample<E: Estimator<Num>>(c: &Counter, overhead: u64, label: &str, e: E) {
    measure_samples(c, overhead, label, e, |e, p, y| {
        e.advance(p, y, STEPS, Hold::Linear)
    });
}

/// Same as [`per_sample`] but always stepping (explicit Euler, the paper's method), even for
/// laws that have a closed form.
fn per_sample_stepped<E: Estimator<Num>>(c: &Counter, overhead: u64, label: &str, e: E) {
    measure_samples(c, overhead, label, e, |e, p, y| {
        advance_by_steps(e, p, y, STEPS, Hold::Linear)
    });
}

/// A2 frame `k` (100 Hz) into `out`: yaw from [`yaw`], roll and pitch proportional to it (so
/// every axis moves and the Euler reference is not the level case), fixed body rates, a
/// healthy BIT word. Returns the frame length.
fn a2_frame(k: u32, out: &mut [u8]) -> usize {
    let y = yaw(k);
    let wrapped = if y > 180.0 { y - 360.0 } else { y };
    let counts = |deg: f32| (deg * (65536.0 / 360.0)) as i32 as i16;
    let payload = nav440_proto::A2Fields {
        roll: counts(wrapped * 0.5),
        pitch: counts(wrapped * 0.3),
        yaw_true: counts(wrapped),
        rate_x: 100,
        rate_y: -50,
        rate_z: 200,
        time_itow: 1000 + 10 * k,
        bit: 0x0002,
        ..Default::default()
    }
    .payload();
    encode_frame(PacketType::A2, &payload, out).unwrap_or_else(|_| fail("an A2 frame"))
}

/// Mean instructions of `run` per A2 frame ([`a2_frame`] `k`) over [`SAMPLES`] frames after
/// `warm` unmeasured ones; `check` gets each run's result, outside the measurement.
fn frames_mean<R>(
    c: &Counter,
    overhead: u64,
    warm: u32,
    mut run: impl FnMut(&[u8]) -> R,
    mut check: impl FnMut(R),
) -> f32 {
    let mut total = 0u64;
    for k in 0..(warm + SAMPLES) {
        let mut buf = [0u8; 64];
        let n = a2_frame(k, &mut buf);
        let frame = buf.get(..n).unwrap_or_default();
        let (m, res) = c.measure(|| run(frame));
        check(res);
        if k >= warm {
            total += m.saturating_sub(overhead);
        }
    }
    total as f32 / SAMPLES as f32
}

/// Mean instructions per A2 frame through the firmware's whole pipeline with the rate column
/// `R` (`pipeline::new_with`: parser, attitude and BIT, clock, one bank per axis of
/// `pipeline::AXES`, `R`'s rates, the defmt row message) with its stream watchdog armed for A2
/// at 100 Hz (`Pipeline::feed_watched`, as the firmware streams), after the period warm-up and
/// [`WARMUP`] more frames.
fn pipeline_frames<R: nav440_pipeline::Reference>(c: &Counter, overhead: u64) -> f32 {
    let mut pipe = firmware_example::pipeline::new_with::<R>();
    pipe.watch(
        nav440_proto::PacketType::A2,
        nav440_proto::PacketRate::Hz100,
        0,
    );
    let warm = nav440_pipeline::period::WARMUP_SAMPLES as u32 + WARMUP;
    let mut rows = 0u32;
    let per_frame = frames_mean(
        c,
        overhead,
        warm,
        |frame| {
            black_box(&mut pipe).feed_watched(
                black_box(frame),
                0,
                &mut |row| {
                    firmware_example::out::row(black_box(row));
                    rows += 1;
                },
                &mut |e| {
                    black_box(e);
                },
            )
        },
        |res| {
            if res.is_err() {
                fail("the pipeline run");
            }
        },
    );
    if rows < SAMPLES {
        fail("a row per pipeline frame");
    }
    per_frame
}

/// Instructions per A2 frame through the firmware's whole pipeline ([`pipeline_frames`]) with
/// the Euler reference and without it (the body rates, feature `no-reference`), and its parts.
fn pipeline_per_frame(c: &Counter, overhead: u64) {
    if firmware_example::pipeline::check().is_err() {
        fail("the pipeline")
    }
    line(
        "instr",
        "pipeline, A2 frame: parse+clock+AXES banks+Euler+defmt row+watch",
        pipeline_frames::<nav440_pipeline::EulerReference>(c, overhead),
        "sample",
    );
    line(
        "instr",
        "pipeline without reference, A2 frame: body rates, no Euler",
        pipeline_frames::<nav440_pipeline::BodyRates>(c, overhead),
        "sample",
    );
    let warm = nav440_pipeline::period::WARMUP_SAMPLES as u32 + WARMUP;
    // Its parts: the front end alone (parser, attitude packet, BIT, clock) and the Euler
    // reference rates of one sample (soft-float trigonometry without an FPU).
    let mut front = nav440_pipeline::Frontend::new();
    let per_frame = frames_mean(
        c,
        overhead,
        warm,
        |frame| {
            black_box(&mut front).feed(black_box(frame), |s| {
                black_box(s);
            })
        },
        |()| {},
    );
    line(
        "instr",
        "pipeline front end, A2 frame: parse+attitude+BIT+clock",
        per_frame,
        "sample",
    );
    let mut euler_total = 0u64;
    for k in 0..SAMPLES {
        let roll = 10.0 + k as f32 * 0.1;
        let (m, r) = c.measure(|| {
            nav440_pipeline::euler::euler_rates_deg(
                black_box(roll),
                black_box(20.0),
                black_box([1.0, 2.0, 3.0]),
            )
        });
        black_box(r);
        euler_total += m.saturating_sub(overhead);
    }
    line(
        "instr",
        "Euler reference rates (three axes)",
        euler_total as f32 / SAMPLES as f32,
        "sample",
    );
}

/// Square roots executed (counted by [`Counting`]).
static SQRTS: AtomicU32 = AtomicU32::new(0);

/// The firmware's square root, counting its calls (for the cycle estimate: `VSQRT.F32` takes
/// 14 cycles on a Cortex-M4F, far from the average instruction).
#[derive(Clone, Copy, Debug, Default)]
struct Counting;

impl estimators::SqrtFn<Num> for Counting {
    fn sqrt(x: Num) -> Num {
        SQRTS.store(SQRTS.load(Ordering::Relaxed) + 1, Ordering::Relaxed);
        <BankSqrt as estimators::SqrtFn<Num>>::sqrt(x)
    }
}

/// Square roots per sample of `e` (100 steps) or of a bank, printed as `sqrt` lines.
fn sqrt_count_stepped<E: Estimator<Num>>(label: &str, mut e: E) {
    let mut prev = Num::from_f32(yaw(0));
    e.reset(prev);
    SQRTS.store(0, Ordering::Relaxed);
    for k in 1..=SAMPLES {
        let y = Num::from_f32(yaw(k));
        black_box(advance_by_steps(&mut e, prev, y, STEPS, Hold::Linear));
        prev = y;
    }
    line(
        "sqrt",
        label,
        SQRTS.load(Ordering::Relaxed) as f32 / SAMPLES as f32,
        "sample",
    );
}

/// Test angles of the three axes at sample `k`, deg: roll and yaw sweeps of +-90 deg (out of
/// phase), pitch +-30 deg.
fn angles(k: u32) -> [f32; 3] {
    [yaw(k + 100), yaw(k + 50) / 3.0, yaw(k)]
}

/// Per-sample instructions of one `update` of each of three banks (roll, pitch, yaw) at
/// 100 Hz (`$banks`: an array of three banks of one type).
macro_rules! three_axes_per_sample {
    ($c:expr, $overhead:expr, $label:expr, $banks:expr) => {{
        let [b0, b1, b2] = &mut $banks;
        let mut total = 0;
        for k in 0..(WARMUP + SAMPLES) {
            let [r, p, y] = angles(k);
            let t_us = u64::from(k) * DT_US;
            let (n, ok) = $c.measure(|| {
                let o0 = black_box(b0.update(t_us, r));
                let o1 = black_box(b1.update(t_us, p));
                let o2 = black_box(b2.update(t_us, y));
                o0.is_ok() && o1.is_ok() && o2.is_ok()
            });
            if !ok {
                fail("a three-axis run without rejected samples");
            }
            if k >= WARMUP {
                total += n.saturating_sub($overhead);
            }
        }
        line("instr", $label, total as f32 / SAMPLES as f32, "sample");
    }};
}

/// Per-sample instructions of a whole bank's `update` at 100 Hz.
fn bank_per_sample<S: estimators::SqrtFn<Num>>(
    c: &Counter,
    overhead: u64,
    label: &str,
    bank: Option<PaperBank<Num, S>>,
) {
    let Some(mut bank) = bank else {
        fail("PaperBank")
    };
    let mut total = 0;
    let mut csv_total = 0;
    for k in 0..(WARMUP + SAMPLES) {
        let y = yaw(k);
        let wrapped = if y > 180.0 { y - 360.0 } else { y };
        let t_us = u64::from(k) * DT_US;
        let (n, r) = c.measure(|| {
            black_box(black_box(&mut bank).update(black_box(t_us), black_box(wrapped)))
        });
        if r.is_err() {
            fail("a bank run without rejected samples")
        }
        // The output stage of the firmware: one defmt row message per sample with the axes
        // of `pipeline::AXES` (the firmware's bank's output on each: its cost depends on the
        // channel count, not on the values), encoded and handed to the defmt transport
        // (semihosting: the host side of each write is not counted).
        let axis = nav440_pipeline::AxisRow {
            reference_deg_s: Some(y),
            out: firmware_example::Output::default(),
        };
        let mut row = nav440_pipeline::Row {
            t_us,
            axes: [None; 3],
        };
        for a in firmware_example::pipeline::AXES.iter() {
            row.axes[a.index()] = Some(axis);
        }
        let (m, ()) = c.measure(|| firmware_example::out::row(black_box(&row)));
        if k >= WARMUP {
            total += n.saturating_sub(overhead);
            csv_total += m.saturating_sub(overhead);
        }
    }
    line("instr", label, total as f32 / SAMPLES as f32, "sample");
    if label == "whole bank" {
        line(
            "instr",
            "defmt row message (output stage, AXES axes)",
            csv_total as f32 / SAMPLES as f32,
            "sample",
        );
    }
}

/// The gain schedule of `nav440 tune host-tests/data/fig5_a2_100hz.bin --schedule
/// 0.001,0.01,0.1,0.5,1 --rust` (docs/ADAPTIVE-GAINS.md), the firmware's copy
/// (`src/gains/schedule_fig5.rs`).
mod schedule {
    include!("../gains/schedule_fig5.rs");
}

/// The noise-adaptive bank (`estimators::AdaptiveBank`): per-sample instructions of
/// `observe_rate` and `update` with the gains held (the noise and jerk estimates' cost over the
/// whole bank), and per call
/// of `retune` (interpolating the schedule and rebuilding every law's coefficients), which
/// the bank does at most twice per `AdaptiveConfig::retune_every` samples (once at the tick,
/// once early when the motion picks up).
fn adaptive_bank(c: &mut Counter, overhead: u64, cfg: &BankConfig) {
    use estimators::{AdaptiveBank, AdaptiveConfig, GainSchedule};
    let sched = GainSchedule::new(&schedule::SCHEDULE).and_then(|s| {
        s.with_records(
            schedule::SCHEDULE_PERIOD_S,
            schedule::SCHEDULE_TUNED_JERK,
            schedule::SCHEDULE_TUNED_ACCELERATION,
        )
    });
    let Ok(sched) = sched else {
        fail("the gain schedule")
    };
    let held = AdaptiveConfig {
        retune_every: u32::MAX,
        ..AdaptiveConfig::DEFAULT
    };
    let Ok(mut bank) = AdaptiveBank::<Num, BankSqrt>::new(cfg, &sched, &held) else {
        fail("AdaptiveBank")
    };
    let (mut total, mut held) = (0u64, 0u32);
    for k in 0..(WARMUP + SAMPLES) {
        let y = yaw(k);
        let wrapped = if y > 180.0 { y - 360.0 } else { y };
        let t_us = u64::from(k) * DT_US;
        // The rate the pipeline gives the bank (here the angle's backward difference, deg/s):
        // the motion's jerk estimate.
        let rate = (y - yaw(k.saturating_sub(1))) * 1e6 / DT_US as f32;
        let before = bank.retune_count();
        let (n, r) = c.measure(|| {
            let b = black_box(&mut bank);
            b.observe_rate(t_us, black_box(rate));
            black_box(b.update(t_us, wrapped))
        });
        if r.is_err() {
            fail("an adaptive bank run without rejected samples");
        }
        // A sample on which the motion picked up and the bank retuned early is a gain change
        // (measured below), not a held sample.
        if k >= WARMUP && bank.retune_count() == before {
            total += n.saturating_sub(overhead);
            held += 1;
        }
    }
    line(
        "instr",
        "adaptive bank, gains held (noise and jerk estimates)",
        total as f32 / held.max(1) as f32,
        "sample",
    );
    // Per call of `retune`, alternating between two noise variances (deg^2).
    let mut retunes = |a: f32, b: f32, label: &str| {
        let mut total = 0u64;
        for k in 0..SAMPLES {
            let v = if k % 2 == 0 { a } else { b };
            let (n, ()) = c.measure_long(|| black_box(&mut bank).retune(black_box(v)));
            total += n.saturating_sub(overhead);
        }
        line("instr", label, total as f32 / SAMPLES as f32, "call");
    };
    // Two points between levels: every call interpolates and rebuilds.
    retunes(0.02, 0.3, "adaptive bank retune (interpolate + rebuild)");
    // Two points near one level (0.01 deg^2): the observers keep their gains and their
    // closed-form maps are reused; the AD's T and the tracker's noise are re-blended.
    retunes(
        0.02,
        0.03,
        "adaptive bank retune, same observer level (AD + Kalman rebuilt)",
    );
    ram(
        "AdaptiveBank (bank + schedule + noise and jerk estimates)",
        core::mem::size_of::<AdaptiveBank<Num, BankSqrt>>(),
    );
}

fn fail(what: &str) -> ! {
    host::stderr(format_args!("bench: cannot build {what}\n"));
    host::exit(false)
}

/// Most requests of one boot sequence (without time-outs: 6).
const SCRIPT_REPLIES: usize = 12;
/// Bytes of one reply (reply + possible NAK).
const REPLY_BYTES: usize = 2 * nav440_proto::MAX_FRAME;

/// Replies in request order: the `k`-th flush of the port makes the `k`-th reply readable.
struct Script {
    replies: heapless::Vec<heapless::Vec<u8, REPLY_BYTES>, SCRIPT_REPLIES>,
}

/// A serial port for the boot bench: writes are taken whole; `flush` (the end of a request)
/// queues the next scripted reply; reads return it. With `unit` set, the replies come from
/// the unit model instead and are recorded into the script.
struct ScriptPort<'s> {
    script: &'s mut Script,
    unit: Option<Unit>,
    next: usize,
    rx: heapless::Deque<u8, REPLY_BYTES>,
    request: heapless::Vec<u8, 300>,
}

impl embedded_io::ErrorType for ScriptPort<'_> {
    type Error = core::convert::Infallible;
}

impl embedded_io::Read for ScriptPort<'_> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.rx.pop_front() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        Ok(n)
    }
}

impl embedded_io::ReadReady for ScriptPort<'_> {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.rx.is_empty())
    }
}

impl embedded_io::Write for ScriptPort<'_> {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        if self.unit.is_some() {
            let _ = self.request.extend_from_slice(buf);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), Self::Error> {
        if let Some(unit) = self.unit.as_mut() {
            let mut reply = heapless::Vec::<u8, REPLY_BYTES>::new();
            unit.receive(&self.request, |r| {
                let _ = reply.extend_from_slice(r.frames);
            });
            self.request.clear();
            let _ = self.script.replies.push(reply);
        }
        if let Some(reply) = self.script.replies.get(self.next) {
            for &b in reply {
                let _ = self.rx.push_back(b);
            }
        }
        self.next += 1;
        Ok(())
    }
}

/// A delay that returns at once (the scripted replies never make the driver wait).
struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

/// Runs the boot sequence over a [`ScriptPort`]; `Ok` if it configured the unit.
fn boot_once(script: &mut Script, unit: Option<Unit>) -> bool {
    let port = ScriptPort {
        script,
        unit,
        next: 0,
        rx: heapless::Deque::new(),
        request: heapless::Vec::new(),
    };
    let mut driver = IoDriver::new(port);
    nav440_proto::boot::boot(
        &mut driver,
        &Target::DEFAULT,
        &Options::DEFAULT,
        &mut NoDelay,
        |_, _| Ok(()),
    )
    .is_ok()
}

#[entry]
fn main() -> ! {
    let Some(p) = cortex_m::Peripherals::take() else {
        fail("peripherals")
    };
    let mut c = Counter::new(p.SYST);
    let overhead = c.overhead();
    let cfg = BankConfig::default();
    let h = cfg.h;
    let v = cfg.velocity;
    let a = cfg.acceleration;

    let ave = Ave::<Num>::new(&v.ave, h).unwrap_or_else(|_| fail("AVE"));
    let ilo = |g| Ilo::<Num, 1>::new(g, h).unwrap_or_else(|_| fail("ILO"));
    let ad = |t| Ad::<Num>::new(t, h).unwrap_or_else(|_| fail("AD"));
    let ed = Ed::<Num>::new(&v.ed, h).unwrap_or_else(|_| fail("ED"));

    // Velocity estimators, explicit Euler, 100 steps per sample.
    per_sample_stepped(&c, overhead, "AVE (Euler x100)", ave);
    per_sample_stepped(&c, overhead, "ILO1 (Euler x100)", ilo(&v.ilo[0]));
    per_sample_stepped(&c, overhead, "AD T=0.01 (Euler x100)", ad(v.ad_t));
    per_sample_stepped(&c, overhead, "ED (Euler x100)", ed);
    if core::any::type_name::<BankSqrt>() != core::any::type_name::<estimators::NativeSqrt>() {
        let ed_fw = Ed::<Num, BankSqrt>::new(&v.ed, h).unwrap_or_else(|_| fail("ED"));
        per_sample_stepped(&c, overhead, "ED, VSQRT (Euler x100)", ed_fw);
        per_sample_stepped(
            &c,
            overhead,
            "ED-ED, VSQRT (Euler x100)",
            Series::of(&ed_fw, &ed_fw),
        );
    }
    // Acceleration: series of two, explicit Euler.
    per_sample_stepped(&c, overhead, "AVE-AVE (Euler x100)", Series::of(&ave, &ave));
    per_sample_stepped(
        &c,
        overhead,
        "ILO1-ILO1 T4 (Euler x100)",
        Series::of(&ilo(&a.ilo[0]), &ilo(&a.ilo[0])),
    );
    per_sample_stepped(
        &c,
        overhead,
        "AD-AD T=0.1 (Euler x100)",
        Series::of(&ad(a.ad_t), &ad(a.ad_t)),
    );
    per_sample_stepped(&c, overhead, "ED-ED (Euler x100)", Series::of(&ed, &ed));
    // The bank's two stepped rows as the bank runs them: velocity law and series in one
    // interval loop (`VelAcc`, shared first stage) through `Law::advance` (for `Fx` the
    // integer kernels of `estimators::fxk`), over one 0.01 s sample interval: 100
    // steps of h, but for `Fx` the AVE row's 50 steps of 2h (`Real::AVE_STEP_FACTOR`).
    let (pa, pe) = (*ave.law(), *ed.law());
    let ave_row = Stateful::from_law(estimators::VelAcc::new(pa, pa, pa, true));
    per_sample(
        &c,
        overhead,
        "AVE + AVE-AVE row (bank, per 0.01 s)",
        ave_row,
    );
    let ed_row = Stateful::from_law(estimators::VelAcc::new(pe, pe, pe, true));
    per_sample(&c, overhead, "ED + ED-ED row (bank, per 0.01 s)", ed_row);
    // Linear laws through their exact 100-step map (what the bank uses).
    per_sample(
        &c,
        overhead,
        "ILO1 (closed form)",
        ClosedForm::of(&ilo(&v.ilo[0]), STEPS, Hold::Linear),
    );
    per_sample(
        &c,
        overhead,
        "AD T=0.01 (closed form)",
        ClosedForm::of(&ad(v.ad_t), STEPS, Hold::Linear),
    );
    per_sample(
        &c,
        overhead,
        "ILO1-ILO1 T4 (closed form)",
        ClosedForm::of(
            &Series::of(&ilo(&a.ilo[0]), &ilo(&a.ilo[0])),
            STEPS,
            Hold::Linear,
        ),
    );
    per_sample(
        &c,
        overhead,
        "AD-AD T=0.1 (closed form)",
        ClosedForm::of(&Series::of(&ad(a.ad_t), &ad(a.ad_t)), STEPS, Hold::Linear),
    );
    // Kalman tracker: one predict/update per sample.
    {
        let kcfg = KalmanConfig {
            dt: cfg.sample_period_s,
            q: v.kf.q,
            r: v.kf.r,
        };
        let mut kf = Kalman::<Num>::new(&kcfg).unwrap_or_else(|_| fail("Kalman"));
        kf.reset(Num::from_f32(yaw(0)));
        let dt = Num::from_f32(0.01);
        let mut total = 0;
        for k in 1..=(WARMUP + SAMPLES) {
            let y = Num::from_f32(yaw(k));
            let (n, ()) = c.measure(|| {
                let kf = black_box(&mut kf);
                kf.update(black_box(y), black_box(dt));
                black_box(kf.velocity());
            });
            if k > WARMUP {
                total += n.saturating_sub(overhead);
            }
        }
        line(
            "instr",
            "Kalman (1 update)",
            total as f32 / SAMPLES as f32,
            "sample",
        );
    }

    // The whole bank as the firmware runs it (unwrap, adapter, 14 estimators), and with the
    // portable libm square root if the firmware uses VSQRT.
    bank_per_sample(&c, overhead, "whole bank", Bank::new(&cfg).ok());
    // Three axes: roll and yaw wrap at +-180 deg, pitch does not.
    let pitch_cfg = BankConfig {
        wrap: Wrap::None,
        ..cfg
    };
    {
        let make = |c: &BankConfig| Bank::new(c).unwrap_or_else(|_| fail("PaperBank"));
        let mut banks = [make(&cfg), make(&pitch_cfg), make(&cfg)];
        three_axes_per_sample!(c, overhead, "paper bank, 3 axes", banks);
    }
    {
        let make = |c: &BankConfig| {
            ProductBank::<Num, BankSqrt>::new(c).unwrap_or_else(|_| fail("ProductBank"))
        };
        let mut banks = [make(&cfg), make(&pitch_cfg), make(&cfg)];
        three_axes_per_sample!(c, overhead, "product bank, 3 axes", banks);
    }
    if core::any::type_name::<BankSqrt>() != core::any::type_name::<estimators::NativeSqrt>() {
        // VSQRT count per sample, for the cycle estimate.
        let ed_c = Ed::<Num, Counting>::new(&v.ed, h).unwrap_or_else(|_| fail("ED"));
        sqrt_count_stepped("ED, VSQRT (Euler x100)", ed_c);
        sqrt_count_stepped("ED-ED, VSQRT (Euler x100)", Series::of(&ed_c, &ed_c));
        let mut counted =
            PaperBank::<Num, Counting>::new(&cfg).unwrap_or_else(|_| fail("PaperBank"));
        SQRTS.store(0, Ordering::Relaxed);
        for k in 0..SAMPLES {
            let y = yaw(k);
            let wrapped = if y > 180.0 { y - 360.0 } else { y };
            let _ = black_box(counted.update(u64::from(k) * DT_US, wrapped));
        }
        line(
            "sqrt",
            "whole bank",
            SQRTS.load(Ordering::Relaxed) as f32 / SAMPLES as f32,
            "sample",
        );
        bank_per_sample(
            &c,
            overhead,
            "whole bank, libm sqrtf",
            PaperBank::<Num>::new(&cfg).ok(),
        );
    }

    // The whole pipeline as the firmware runs it (pipeline::AXES: all three axes).
    pipeline_per_frame(&c, overhead);
    // Building one axis's bank as the pipeline does after the warm-up (the firmware's preset
    // at its nominal period): the time the stream waits for each bank, once per start and
    // per period change (below 2^24 SysTick ticks, about 10 million instructions).
    let mut total = 0u64;
    for _ in 0..3 {
        let (n, r) = c.measure_long(firmware_example::pipeline::check);
        if r.is_err() {
            fail("the firmware's bank")
        }
        total += n.saturating_sub(overhead);
    }
    line(
        "instr",
        "bank construction, one axis",
        total as f32 / 3.0,
        "call",
    );
    adaptive_bank(&mut c, overhead, &BankConfig::NAV440);

    // Parser per byte: a stream of A2 frames (the capture's packet type), and the CRC alone.
    let mut stream = [0u8; 37 * 64];
    let mut len = 0;
    for k in 0..64u32 {
        let mut payload = [0u8; 30];
        for (i, b) in payload.iter_mut().enumerate() {
            *b = (k as u8)
                .wrapping_mul(31)
                .wrapping_add(i as u8)
                .wrapping_mul(7);
        }
        match stream
            .get_mut(len..)
            .map(|out| encode_frame(PacketType::A2, &payload, out))
        {
            Some(Ok(n)) => len += n,
            _ => fail("the parser input"),
        }
    }
    let bytes = stream.get(..len).unwrap_or_default();
    let mut parser = Parser::new();
    let mut frames = 0u32;
    let (n, ()) = c.measure(|| black_box(&mut parser).feed(black_box(bytes), |_| frames += 1));
    if frames != 64 {
        fail("64 frames from the parser input");
    }
    line(
        "instr",
        "parser",
        n.saturating_sub(overhead) as f32 / len as f32,
        "byte",
    );
    let (n, crc) = c.measure(|| nav440_proto::crc16(black_box(bytes)));
    black_box(crc);
    line(
        "instr",
        "CRC-16 alone (baseline)",
        n.saturating_sub(overhead) as f32 / len as f32,
        "byte",
    );

    // The link to the unit: the boot sequence and transmitting.
    let mut script = Script {
        replies: heapless::Vec::new(),
    };
    if !boot_once(
        &mut script,
        Some(Unit::new(UnitFields::POWER_UP, Quirks::default())),
    ) {
        fail("the boot sequence against the unit model");
    }
    let (n, ok) = c.measure(|| boot_once(black_box(&mut script), None));
    if !ok {
        fail("the scripted boot sequence");
    }
    line(
        "instr",
        "boot sequence (S1 38400 -> A2 100Hz 57600)",
        n.saturating_sub(overhead) as f32,
        "call",
    );
    let Some(mut board) = Board::take(38_400) else {
        fail("the UART")
    };
    let request = [0x55u8; 64];
    let (n, r) =
        c.measure(|| embedded_io::Write::write_all(black_box(&mut board.nav), black_box(&request)));
    if r.is_err() {
        fail("transmit");
    }
    line(
        "instr",
        "transmit (embedded_io::Write)",
        n.saturating_sub(overhead) as f32 / request.len() as f32,
        "byte",
    );

    // RAM (state size) per estimator and of the pipeline parts.
    ram("AVE", core::mem::size_of::<Ave<Num>>());
    ram("ILO (D=1)", core::mem::size_of::<Ilo<Num, 1>>());
    ram(
        "ILO (D=1) closed form",
        core::mem::size_of::<Stateful<ClosedForm<IloParams<Num, 1>>>>(),
    );
    ram("AD", core::mem::size_of::<Ad<Num>>());
    ram(
        "AD closed form",
        core::mem::size_of::<Stateful<ClosedForm<AdParams<Num>>>>(),
    );
    ram("ED", core::mem::size_of::<Ed<Num>>());
    ram("Kalman", core::mem::size_of::<Kalman<Num>>());
    ram(
        "AVE-AVE",
        core::mem::size_of::<Stateful<Series<AveParams<Num>, AveParams<Num>>>>(),
    );
    ram(
        "ILO-ILO closed form",
        core::mem::size_of::<Stateful<ClosedForm<Series<IloParams<Num, 1>, IloParams<Num, 1>>>>>(),
    );
    ram(
        "AD-AD closed form",
        core::mem::size_of::<Stateful<ClosedForm<Series<AdParams<Num>, AdParams<Num>>>>>(),
    );
    ram(
        "ED-ED",
        core::mem::size_of::<Stateful<Series<EdParams<Num>, EdParams<Num>>>>(),
    );
    ram("PaperBank (whole bank)", core::mem::size_of::<Bank>());
    ram(
        "ProductBank (one axis)",
        core::mem::size_of::<ProductBank<Num, BankSqrt>>(),
    );
    ram(
        "Pipeline (firmware: parser, clock, banks of pipeline::AXES)",
        core::mem::size_of::<firmware_example::pipeline::Pipeline>(),
    );
    ram("Parser", core::mem::size_of::<Parser>());
    ram("ItowClock", core::mem::size_of::<ItowClock>());
    ram(
        "UART RX queue",
        core::mem::size_of::<
            heapless::spsc::Queue<u8, { firmware_example::uart::RX_QUEUE_BYTES + 1 }>,
        >(),
    );
    host::exit(true)
}
