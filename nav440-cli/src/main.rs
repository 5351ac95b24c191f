//! `nav440`: replay, synthesise, estimate, reproduce the paper, tune and plot NAV440 captures.
//! The commands live in [`nav440_cli::cmd`], one module each.
//!
//! Exit codes: 0 success; 1 other failure (estimator/encoder error); 2 usage error (bad
//! argument); 3 input file missing, unreadable or empty; 4 input holds no NAV440 frame (or no
//! packet carrying yaw); 5 output could not be written. Every error is one line on stderr.

use clap::Parser;
use nav440_cli::cmd::Cli;
use std::process::ExitCode;

/// Before `main` (and before Rust's runtime puts `/dev/null` in place of a closed standard
/// descriptor): whether standard output is closed (`nav440 stats F >&-`), so that a command
/// writing there fails (exit 5) instead of losing its output.
#[ctor::ctor]
fn stdout_at_start() {
    use std::os::fd::BorrowedFd;
    // SAFETY: descriptor 1 is only duplicated (F_DUPFD_CLOEXEC), never closed or used for
    // I/O here; a closed descriptor gives EBADF.
    let fd = unsafe { BorrowedFd::borrow_raw(1) };
    nav440_cli::output::set_stdout_closed_at_start(fd.try_clone_to_owned().is_err());
}

fn main() -> ExitCode {
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
