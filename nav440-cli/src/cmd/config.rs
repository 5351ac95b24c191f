//! `nav440 config`: configure a unit on a serial port ([`crate::serial`]).

use crate::error::Result;
use crate::serial::{open_and_boot, report_json, PortArgs};

/// Arguments of `nav440 config`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(flatten)]
    pub(crate) port: PortArgs,
}

/// `nav440 config`: the boot sequence; the report as one JSON object on stdout.
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    let (_, report, t) = open_and_boot(&a.port)?;
    let json = report_json(&a.port.link.port, &report, &t);
    super::stdout_or_file(None, |w| writeln!(w, "{json}"))
}
