//! The embassy-stm32 firmware for the STM32F405 (e.g. the Netduino Plus 2 or any STM32F405RG
//! board), with feature `stm32f411` the NUCLEO-F411RE, with feature `stm32l475` the
//! B-L475E-IOT01A Discovery kit (STM32L475VG): embassy-executor, embassy-stm32 and
//! embassy-time.
//!
//! 1. `embassy_stm32::init` with the chip's clock configuration ([`chip::config`]): a 16 MHz
//!    system clock on every chip (the F4s' HSI with no PLL; on the L475 the PLL from the 4 MHz
//!    MSI), checked against what the HAL reports. embassy-time ticks from SysTick
//!    (`systick-timer`, 1 kHz interrupt) at that clock.
//! 2. The NAV440 on USART1 ([`chip`]'s pins, AF7) as a `BufferedUart`, interrupt-driven,
//!    starting at the unit's factory default of 38400 Bd.
//! 3. `nav440_proto::boot::boot_async` over `nav440_proto::driver::AsyncDriver` configures the
//!    unit to [`TARGET`] (A2 at 100 Hz at 57600 Bd), its reply time-outs through
//!    `embassy_time::Delay`, the baud switch through `BufferedUart::set_baudrate`. A failed
//!    boot is retried every second, one `boot failed` message per attempt.
//! 4. Every byte after the read-back goes through `nav440_pipeline` with the product bank
//!    (`estimators::AdaptiveProductBank`: ILO1 velocity and Kalman acceleration per axis,
//!    starting with the `BankConfig::NAV440` gains for the measured packet rate, then
//!    following the measured noise and the motion's jerk), as firmware-example's
//!    `bank-product` image and `nav440 estimate --bank product` do, and through the
//!    pipeline's stream watchdog (armed after every configuration, polled every
//!    [`POLL_MS`] ms while no byte arrives). A silence or a frame of another type (a unit
//!    reset) sends the firmware back to step 3, as firmware-example's real-board profile does.
//!
//! Output: defmt messages over defmt-rtt (probe-rs reads them), see [`out`]:
//!
//! * `header {=str}` once, the channels of each axis: `angle_deg,` then the bank's CSV
//!   columns (`ilo1_v,kf_a`);
//! * `row {=u64} {=[?]}` per sample: the sample time (us since the first sample), then
//!   per axis (roll, pitch, yaw) the unwrapped angle (deg) and the bank's two channels, nine
//!   `f32`; an axis without an estimate in that row (near gimbal lock) is NaN;
//! * firmware-example's `firmware: ...` messages (`nav440_pipeline::report`): the stream
//!   faults (`stream silent: ...`, `time stamps frozen: ...`, `packet rate differs ...`,
//!   `unit reset mid-stream: ...`), the period change, and every 10 s of stream `counters
//!   after N s of stream:` with the counters line (also after a UART error). In that line
//!   `uart_overruns` counts the UART's receive errors, `unit_bytes` the bytes received;
//!   `uart_stalls` and `stack_peak` are 0 (the `BufferedUart` never pauses reception, and the
//!   stack is not painted).
//!
//! Build: `cargo build -p firmware-embassy --release --target thumbv7em-none-eabihf` (add
//! `--no-default-features --features stm32f411` or `stm32l475` for the other boards); `cargo
//! xtask embassy-stm32` lints, builds and checks the images' memory maps and runs the L475
//! image on QEMU's `b-l475e-iot01a`. Flash: `cargo xtask flash
//! target/thumbv7em-none-eabihf/release/firmware-embassy` (probe-rs).
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

use embassy_executor::Spawner;
use embassy_stm32::usart::{self, BufferedUart};
use embassy_stm32::{bind_interrupts, peripherals};
use embassy_time::{with_timeout, Delay, Duration, Instant, Timer};
use nav440_pipeline::report::{self, Flow};
use nav440_proto::boot::{self, Options, Target};
use nav440_proto::driver::AsyncDriver;
use nav440_proto::Baud;
use systick_timer::SystickDriver;

mod out;

bind_interrupts!(struct Irqs {
    USART1 => usart::BufferedInterruptHandler<peripherals::USART1>;
});

/// The configuration the firmware gives the unit: A2 at 100 Hz at 57600 Bd, checked against
/// the unit's byte budget at compile time.
const TARGET: Target = Target::DEFAULT;
const _: () = assert!(
    TARGET.fits_budget(),
    "TARGET exceeds the unit's byte budget"
);

/// Local UART rate before the search (the NAV440's factory default; the search tries all).
const POWER_UP_BAUD: u32 = 38_400;

/// Longest wait for received bytes before the watchdog's silence check, ms (the silence
/// limit is 500 ms at 100 Hz).
const POLL_MS: u64 = 10;

/// The watchdog's clock: milliseconds since start (embassy-time, wrapping).
fn now_ms() -> u32 {
    Instant::now().as_millis() as u32
}

/// System clock (HCLK, SysTick's source) of every chip's [`chip::config`], Hz.
const SYSCLK_HZ: u32 = 16_000_000;

/// SysTick interrupts per second: the time driver's resolution for wake-ups (1 ms).
const SYSTICK_HZ: u32 = 1_000;

embassy_time_driver::time_driver_impl!(
    static TIME: SystickDriver<4> = SystickDriver::new(SYSCLK_HZ as u64, SYSCLK_HZ / SYSTICK_HZ - 1)
);

#[cortex_m_rt::exception]
fn SysTick() {
    TIME.systick_interrupt();
}

/// What differs between the chips besides USART1's pins: the clocks and the board name.
#[cfg(any(feature = "stm32f405", feature = "stm32f411"))]
mod chip {
    /// 16 MHz from the HSI, no PLL (the HAL's default on the STM32F4).
    pub fn config() -> embassy_stm32::Config {
        embassy_stm32::Config::default()
    }

    /// The board name in the ELF (NUL-terminated), as firmware-example's images carry it:
    /// `cargo xtask flash` and the memory-map check read the chip from it.
    #[cfg(feature = "stm32f405")]
    #[no_mangle]
    #[used]
    pub static NAV440_BOARD: [u8; 10] = *b"stm32f405\0";

    /// The board name in the ELF of the NUCLEO-F411RE image.
    #[cfg(feature = "stm32f411")]
    #[no_mangle]
    #[used]
    pub static NAV440_BOARD: [u8; 14] = *b"nucleo-f411re\0";
}

/// The STM32L475VG of the B-L475E-IOT01A.
#[cfg(feature = "stm32l475")]
mod chip {
    use embassy_stm32::rcc::{Pll, PllMul, PllPreDiv, PllRDiv, PllSource, Sysclk};

    /// 16 MHz from the PLL: MSI 4 MHz / 1 x 32 = 128 MHz VCO, / 8 on the R output. At
    /// 16 MHz in voltage range 1 the flash needs no wait state.
    pub fn config() -> embassy_stm32::Config {
        let mut c = embassy_stm32::Config::default();
        c.rcc.pll = Some(Pll {
            source: PllSource::MSI,
            prediv: PllPreDiv::DIV1,
            mul: PllMul::MUL32,
            divp: None,
            divq: None,
            divr: Some(PllRDiv::DIV8),
        });
        c.rcc.sys = Sysclk::PLL1_R;
        c
    }

    /// The board name in the ELF (NUL-terminated).
    #[no_mangle]
    #[used]
    pub static NAV440_BOARD: [u8; 15] = *b"b-l475e-iot01a\0";
}

#[embassy_executor::main]
async fn main(_spawner: Spawner) {
    let p = embassy_stm32::init(chip::config());
    let sys = embassy_stm32::rcc::clocks(&p.RCC).sys.to_hertz();
    if sys.map(|h| h.0) != Some(SYSCLK_HZ) {
        defmt::panic!("system clock {} Hz, expected {=u32}", sys, SYSCLK_HZ);
    }
    let Some(mut core) = cortex_m::Peripherals::take() else {
        defmt::panic!("the core peripherals are taken")
    };
    TIME.start(&mut core.SYST);
    defmt::println!(
        "firmware: embassy-stm32 up, USART1 at {=u32} Bd",
        POWER_UP_BAUD
    );

    let mut config = usart::Config::default();
    config.baudrate = POWER_UP_BAUD;
    // USART1's pins (AF7): the F4 boards' PA10/PA9, the B-L475E-IOT01A's PB7/PB6.
    #[cfg(feature = "stm32l475")]
    let (rx, tx) = (p.PB7, p.PB6);
    #[cfg(not(feature = "stm32l475"))]
    let (rx, tx) = (p.PA10, p.PA9);
    let mut tx_buf = [0u8; 64];
    let mut rx_buf = [0u8; 512];
    let mut uart = match BufferedUart::new(p.USART1, rx, tx, &mut tx_buf, &mut rx_buf, Irqs, config)
    {
        Ok(u) => u,
        Err(e) => defmt::panic!("USART1 configuration rejected: {}", e),
    };

    let mut pipe = out::pipeline();
    let mut first = true;
    // Receive errors and bytes received so far (the counters line).
    let mut uart_errors = 0u32;
    let mut received = 0u64;
    loop {
        // ANCHOR: boot
        let mut driver = AsyncDriver::new(uart);
        let report = loop {
            // The local UART follows the unit; `ConfigError` is not the UART's error type.
            let set_baud = |u: &mut BufferedUart<'_>, b: Baud| {
                u.set_baudrate(b.bits_per_second()).map_err(|e| {
                    defmt::error!("set_baudrate({=u32}): {}", b.bits_per_second(), e);
                    usart::Error::Framing
                })
            };
            match boot::boot_async(
                &mut driver,
                &TARGET,
                &Options::DEFAULT,
                &mut Delay,
                set_baud,
            )
            .await
            {
                Ok(report) => break report,
                Err(e) => defmt::println!("firmware: boot failed: {}", e),
            }
            Timer::after_secs(1).await;
        };
        // ANCHOR_END: boot
        defmt::println!(
            "firmware: unit configured: {} at {=u32} Bd (unit was at {=u32} Bd); boot_frames={=u32}",
            TARGET.packet,
            report.baud.bits_per_second(),
            report.unit_baud.bits_per_second(),
            report.unsolicited_frames,
        );
        if first {
            out::header();
            first = false;
        }
        pipe.watch(TARGET.packet, TARGET.rate, now_ms());
        let mut pending = [0u8; nav440_proto::MAX_FRAME];
        let n = driver.pending_bytes().len().min(pending.len());
        pending[..n].copy_from_slice(&driver.pending_bytes()[..n]);
        uart = driver.release();
        received += n as u64;
        let mut go = process(&mut pipe, &pending[..n], uart_errors, received);
        let mut buf = [0u8; 64];
        while go {
            match with_timeout(
                Duration::from_millis(POLL_MS),
                embedded_io_async::Read::read(&mut uart, &mut buf),
            )
            .await
            {
                Ok(Ok(n)) => {
                    received += n as u64;
                    go = process(&mut pipe, &buf[..n], uart_errors, received);
                }
                Ok(Err(e)) => {
                    uart_errors = uart_errors.saturating_add(1);
                    defmt::println!("firmware: UART error: {}", e);
                    report::summary(&pipe, uart_errors, 0, received, 0);
                }
                // Nothing within POLL_MS: the silence check below.
                Err(_) => {}
            }
            // A silent unit (reported) is configured again.
            go = go && !report::silence(&mut pipe, now_ms());
        }
    }
}

/// Feeds received bytes through the pipeline and its watch (`nav440_pipeline::report::feed`:
/// rows, and every stream fault as it is seen); prints the counters every 10 s of stream.
/// `false`: the unit reset (a frame of another type): configure it again.
fn process(pipe: &mut out::Pipeline, bytes: &[u8], uart_errors: u32, received: u64) -> bool {
    let flow = match report::feed(pipe, bytes, now_ms(), &mut out::row) {
        Ok(f) => f,
        Err(e) => defmt::panic!("bank: {}", e),
    };
    match flow {
        Flow::Go => true,
        Flow::Counters(stream_s) => {
            report::periodic(stream_s);
            report::summary(pipe, uart_errors, 0, received, 0);
            true
        }
        Flow::Reset => false,
    }
}
