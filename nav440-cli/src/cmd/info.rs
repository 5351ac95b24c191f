//! `nav440 info`: who the unit on a serial port is (ID and VR packets) and what it streams
//! ([`crate::serial::identify`]); changes nothing on the unit.

use nav440_proto::PacketRate;

use crate::error::Result;
use crate::serial::{angle_types, carries_angles, identify, Identity, LinkArgs};

/// Arguments of `nav440 info`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(flatten)]
    pub(crate) link: LinkArgs,
    /// Print one JSON object instead of the text lines.
    #[arg(long)]
    json: bool,
}

/// `nav440 info`: finds the unit, reads its settings, asks for its ID and VR; prints them.
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    let id = identify(&a.link)?;
    let text = if a.json {
        json(&a.link.port, &id).to_string()
    } else {
        text(&a.link.port, &id)
    };
    super::stdout_or_file(None, |w| writeln!(w, "{text}"))
}

/// The rate a divider names, e.g. `100 Hz`, `quiet (polled)`, `divider 7 (undefined)`.
fn rate_text(divider: u16) -> String {
    match PacketRate::from_divider(divider) {
        Some(PacketRate::Quiet) => "quiet (polled)".to_string(),
        Some(r) => format!("{} Hz", r.hz()),
        None => format!("divider {divider} (undefined)"),
    }
}

/// What `live` and the firmware can do with the unit's output.
fn angles_text(id: &Identity) -> String {
    if carries_angles(id.packet) {
        format!("yes: {} carries roll, pitch and yaw", id.packet)
    } else {
        format!(
            "not in {}; `nav440 live` and the firmware set an angle packet ({}), which a \
             VG440, AHRS440 or NAV440 streams and an IMU440 NAKs",
            id.packet,
            angle_types()
        )
    }
}

fn text(port: &str, id: &Identity) -> String {
    [
        format!("port:          {port}"),
        format!("serial number: {}", id.serial_number),
        format!("part number:   {}", id.model),
        format!("firmware:      {}", id.version_text()),
        format!(
            "baud:          {} Bd (answered at {} Bd)",
            id.unit_baud.bits_per_second(),
            id.found_at.bits_per_second()
        ),
        format!(
            "output:        {} at {}",
            id.packet,
            rate_text(id.rate_divider)
        ),
        format!("angles:        {}", angles_text(id)),
    ]
    .join("\n")
}

fn json(port: &str, id: &Identity) -> serde_json::Value {
    let [major, minor, patch, stage, build] = id.version;
    serde_json::json!({
        "port": port,
        "serial_number": id.serial_number,
        "model": id.model,
        "version": format!("{major}.{minor}.{patch}"),
        "version_stage": stage,
        "version_build": build,
        "found_at": id.found_at.bits_per_second(),
        "unit_baud": id.unit_baud.bits_per_second(),
        "packet": id.packet.to_string(),
        "rate_divider": id.rate_divider,
        "carries_angles": carries_angles(id.packet),
        "ping_retries": id.ping_retries,
    })
}
