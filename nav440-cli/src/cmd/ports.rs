//! `nav440 ports`: the serial ports of this machine (`serialport::available_ports`).

use crate::error::{Error, Result};

/// Arguments of `nav440 ports` (none).
#[derive(clap::Args, Debug, Clone)]
pub struct Args {}

/// One line per port, `DEV<TAB>KIND`; a line saying so when there is none (exit 0 either way).
pub fn run(_: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    let ports = serialport::available_ports()
        .map_err(|e| Error::Other(format!("cannot list the serial ports: {e}")))?;
    let lines: Vec<String> = ports.iter().map(line).collect();
    if lines.is_empty() {
        eprintln!(
            "nav440 ports: no serial port found (a USB adapter not plugged in? a pty of \
             `nav440 sim --listen pty` is not listed: use the path it prints)"
        );
    }
    super::stdout_or_file(None, |w| lines.iter().try_for_each(|l| writeln!(w, "{l}")))
}

/// `DEV<TAB>KIND`, e.g. `/dev/ttyUSB0<TAB>usb 0403:6001 FTDI FT232R USB UART serial A1B2C3`.
fn line(p: &serialport::SerialPortInfo) -> String {
    use serialport::SerialPortType;
    let kind = match &p.port_type {
        SerialPortType::UsbPort(u) => {
            let mut s = format!("usb {:04x}:{:04x}", u.vid, u.pid);
            for part in [&u.manufacturer, &u.product].into_iter().flatten() {
                s.push(' ');
                s.push_str(part);
            }
            if let Some(sn) = &u.serial_number {
                s.push_str(" serial ");
                s.push_str(sn);
            }
            s
        }
        SerialPortType::PciPort => "pci".to_string(),
        SerialPortType::BluetoothPort => "bluetooth".to_string(),
        SerialPortType::Unknown => "unknown".to_string(),
    };
    format!("{}\t{kind}", p.port_name)
}
