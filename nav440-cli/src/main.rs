//! `nav440`: replay, synthesise, estimate, reproduce the paper, tune and plot NAV440 captures.
//! The commands live in [`nav440_cli::cmd`], one module each.
//!
//! Exit codes: 0 success; 1 other failure (estimator/encoder error); 2 usage error (bad
//! argument); 3 input file missing, unreadable or empty; 4 input holds no NAV440 frame (or no
//! packet carrying yaw); 5 output could not be written. Every error is one line on stderr.

use clap::Parser;
use nav440_cli::cmd::Cli;
use std::process::ExitCode;

/// Whether standard output was closed when the process started (`nav440 stats F >&-`), so that
/// a command writing there fails (exit 5) instead of losing its output. Rust's runtime opens
/// `/dev/null` read-write in place of a closed standard descriptor before `main`; a shell's
/// redirection to it (`>/dev/null`) is write-only. Read from `/proc/self` (Linux; elsewhere
/// `false`); a deliberate read-write `1<>/dev/null` counts as closed.
fn stdout_closed_at_start() -> bool {
    let to_null =
        std::fs::read_link("/proc/self/fd/1").is_ok_and(|t| t == std::path::Path::new("/dev/null"));
    to_null
        && std::fs::read_to_string("/proc/self/fdinfo/1")
            .ok()
            .and_then(|info| {
                let flags = info.lines().find_map(|l| l.strip_prefix("flags:"))?;
                u32::from_str_radix(flags.trim(), 8).ok()
            })
            // O_ACCMODE == O_RDWR
            .is_some_and(|flags| flags & 0o3 == 0o2)
}

fn main() -> ExitCode {
    nav440_cli::output::set_stdout_closed_at_start(stdout_closed_at_start());
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // --help / --version print normally and exit 0; usage errors exit 2.
            if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                let _ = e.print();
                return ExitCode::from(2);
            }
            if !e.use_stderr() {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // One line: clap's message without its usage/help trailer.
            let text = e.render().to_string();
            let msg: Vec<&str> = text
                .lines()
                .map(str::trim)
                .filter(|l| {
                    !l.is_empty()
                        && !l.starts_with("Usage:")
                        && !l.starts_with("For more information")
                })
                .map(|l| l.strip_prefix("error: ").unwrap_or(l))
                .collect();
            eprintln!("nav440: {} (see `nav440 --help`)", msg.join(" "));
            return ExitCode::from(2);
        }
    };
    match cli.run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("nav440: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
