//! Configure a NAV440 over a serial port with `boot::boot`: find the unit at any baud, switch
//! the link to 57600 Bd, select A2 packets at 100 Hz and read the configuration back.
//!
//! The port here is a simulated unit (`nav440_proto::unit::Unit`, the model `nav440 sim` runs)
//! behind an in-memory `embedded-io` port, so the example runs anywhere. On a microcontroller
//! the port is your UART (`embedded_io::Read + ReadReady + Write`, e.g. an `embassy-stm32` or
//! `stm32f4xx-hal` serial port), the delay your HAL's `DelayNs`, and `set_baud` changes the
//! UART's baud rate.
//!
//! `cargo run -p nav440-proto --example configure_unit`

use std::collections::VecDeque;
use std::convert::Infallible;

use nav440_proto::boot::{self, Options, Target};
use nav440_proto::driver::IoDriver;
use nav440_proto::unit::{Quirks, Unit, UnitFields};
use nav440_proto::Baud;

/// The serial line to a unit: what the host writes goes to the unit model, its replies queue
/// up for the host to read.
struct SimulatedUnit {
    unit: Unit,
    to_host: VecDeque<u8>,
    baud: Baud,
}

impl embedded_io::ErrorType for SimulatedUnit {
    type Error = Infallible;
}

impl embedded_io::Read for SimulatedUnit {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        Ok(std::io::Read::read(&mut self.to_host, buf).expect("a VecDeque reads without error"))
    }
}

impl embedded_io::ReadReady for SimulatedUnit {
    fn read_ready(&mut self) -> Result<bool, Infallible> {
        Ok(!self.to_host.is_empty())
    }
}

impl embedded_io::Write for SimulatedUnit {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        let to_host = &mut self.to_host;
        self.unit
            .receive(buf, |response| to_host.extend(response.frames));
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

/// A host delay: really sleeps (on a microcontroller: the HAL's timer delay).
struct StdDelay;

impl embedded_hal::delay::DelayNs for StdDelay {
    fn delay_ns(&mut self, ns: u32) {
        std::thread::sleep(std::time::Duration::from_nanos(u64::from(ns)));
    }
}

/// A2 at 100 Hz at 57600 Bd; checked against the unit's byte budget at compile time.
const TARGET: Target = Target::DEFAULT;
const _: () = assert!(TARGET.fits_budget());

fn main() -> std::process::ExitCode {
    // A unit at its power-up configuration (S1 at 20 Hz at 38400 Bd).
    let port = SimulatedUnit {
        unit: Unit::new(UnitFields::POWER_UP, Quirks::default()),
        to_host: VecDeque::new(),
        baud: Baud::B38400,
    };
    let mut driver = IoDriver::new(port);
    let result = boot::boot(
        &mut driver,
        &TARGET,
        &Options::DEFAULT,
        &mut StdDelay,
        |port, baud| {
            port.baud = baud; // a real UART changes its divider here
            Ok(())
        },
    );
    match result {
        Ok(report) => {
            println!("unit configured: {report:?}");
            let port = driver.release();
            println!(
                "the unit now streams {:?} at {:?}; local port at {:?}",
                port.unit.ram().stream(),
                port.unit.ram().baud(),
                port.baud
            );
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("configure_unit: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
