//! `nav440 sim`: a simulated NAV440 on TCP or a pseudo-terminal ([`crate::sim`]).

use crate::error::Result;
pub use crate::sim::{Fault, SimArgs as Args};

/// `nav440 sim`: [`sim::run`](crate::sim::run), then one summary line on stderr.
pub fn run(args: &Args) -> Result<()> {
    let s = crate::sim::run(args)?;
    eprintln!(
        "nav440 sim: {} requests, {} power-up packets, {} capture packets ({} bytes recorded){}{}",
        s.requests,
        s.power_up_packets,
        s.packets,
        s.recorded_bytes,
        if s.resets > 0 {
            ", reset mid-stream"
        } else {
            ""
        },
        if s.completed {
            ", capture done: closed"
        } else {
            ", host closed the connection"
        }
    );
    Ok(())
}
