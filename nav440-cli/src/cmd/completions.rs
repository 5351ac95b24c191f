//! `nav440 completions`: the shell completion script.

use crate::error::Result;

/// Arguments of `nav440 completions`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The shell: bash, zsh, fish, elvish or powershell.
    #[arg(value_enum)]
    shell: clap_complete::Shell,
}

/// Prints the completion script of [`super::Cli`] for the shell on stdout.
pub fn run(a: &Args) -> Result<()> {
    crate::output::check_stdout()?;
    // Generated into memory first: clap_complete panics on a write error, and a closed pipe
    // must stay a silent success as for every other command.
    let mut script = Vec::new();
    let mut cmd = <super::Cli as clap::CommandFactory>::command();
    clap_complete::generate(a.shell, &mut cmd, "nav440", &mut script);
    super::stdout_or_file(None, |w| w.write_all(&script))
}
