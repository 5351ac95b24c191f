//! Output files and standard output: what the commands write, and the rules that keep every
//! existing file intact until a command has succeeded (docs/RELIABILITY-STREAM.md, "No file is lost").
//!
//! * An output file is written to a temporary file in its own directory
//!   (`.NAME.XXXXXX.nav440-tmp`, the `tempfile` crate) and renamed over the destination only
//!   when the command succeeded ([`OutputFile::commit`]); a command that fails, at any point,
//!   leaves the destination as it was and removes the temporary file. An existing destination
//!   keeps its permissions; a symbolic link is followed (its target is replaced). A
//!   destination that exists and is not a regular file (`/dev/null`, a FIFO) is written in
//!   place.
//! * An output that is one of the command's inputs (same device and inode, the `same-file`
//!   crate) is refused before anything is read or written ([`check_not_input`], exit 2).
//! * `-` means standard output for every command that takes an output path.
//! * A standard output that was closed when the process started (`>&-`) is an output error
//!   (exit 5) for every command that writes to it ([`check_stdout`]): Rust's runtime puts
//!   `/dev/null` in place of a closed descriptor, which would lose the output without a word.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// The output path that means standard output.
pub const STDOUT_NAME: &str = "-";

/// `true` if `path` is `-` (standard output).
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == STDOUT_NAME
}

/// The name of an output in messages.
pub fn output_name(path: &Path) -> String {
    if is_stdout(path) {
        "standard output".to_string()
    } else {
        path.display().to_string()
    }
}

static STDOUT_CLOSED_AT_START: AtomicBool = AtomicBool::new(false);

/// Records that file descriptor 1 was closed when the process started (the `nav440` binary
/// tells at the start of `main`: Rust's runtime has put `/dev/null` in its place then).
pub fn set_stdout_closed_at_start(closed: bool) {
    STDOUT_CLOSED_AT_START.store(closed, Ordering::Relaxed);
}

/// An output error if standard output was closed when the process started: what the command
/// writes there would be lost.
pub fn check_stdout() -> Result<()> {
    if STDOUT_CLOSED_AT_START.load(Ordering::Relaxed) {
        Err(Error::Output(
            "cannot write standard output: it is closed (Bad file descriptor)".into(),
        ))
    } else {
        Ok(())
    }
}

/// Refuses (usage error, exit 2) an output file that is one of `inputs` (same device and
/// inode; `-` on either side is never the same file). Runs before anything is read or written.
pub fn check_not_input(flag: &str, output: &Path, inputs: &[&Path]) -> Result<()> {
    if is_stdout(output) {
        return Ok(());
    }
    for input in inputs {
        if crate::replay::is_stdin(input) {
            continue;
        }
        if same_file::is_same_file(output, input).unwrap_or(false) {
            return Err(Error::Usage(format!(
                "{flag} {} is the input {}: refusing to overwrite it (write to another file)",
                output.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// Checks that two outputs of one command are not the same file, nor both standard output.
pub fn check_distinct(a: (&str, &Path), b: (&str, &Path)) -> Result<()> {
    let same = if is_stdout(a.1) || is_stdout(b.1) {
        is_stdout(a.1) && is_stdout(b.1)
    } else {
        a.1 == b.1 || same_file::is_same_file(a.1, b.1).unwrap_or(false)
    };
    if same {
        Err(Error::Usage(format!(
            "{} and {} name the same output {}",
            a.0,
            b.0,
            output_name(a.1)
        )))
    } else {
        Ok(())
    }
}

enum Sink {
    /// A temporary file in the destination's directory, renamed over it on commit.
    Temp(std::io::BufWriter<tempfile::NamedTempFile>),
    /// A destination that exists and is not a regular file (a device, a FIFO).
    InPlace(std::io::BufWriter<std::fs::File>),
    /// Standard output (`-`).
    Stdout(std::io::BufWriter<std::io::Stdout>),
}

/// An output of a command: a file written through a temporary file and renamed at
/// [`commit`](Self::commit), or standard output for `-`. Dropped without a commit, it leaves
/// the destination unchanged (and removes its temporary file).
pub struct OutputFile {
    dest: PathBuf,
    sink: Sink,
}

impl std::fmt::Debug for OutputFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OutputFile")
            .field("dest", &self.dest)
            .finish_non_exhaustive()
    }
}

impl OutputFile {
    /// Prepares the output `dest` (`-`: standard output): creates the temporary file in its
    /// directory. Nothing at `dest` changes until [`commit`](Self::commit). An output error
    /// (exit 5) names `dest` when the directory cannot take a file.
    pub fn create(dest: &Path) -> Result<Self> {
        if is_stdout(dest) {
            check_stdout()?;
            return Ok(OutputFile {
                dest: dest.to_path_buf(),
                sink: Sink::Stdout(std::io::BufWriter::new(std::io::stdout())),
            });
        }
        let err =
            |e: std::io::Error| Error::Output(format!("cannot write {}: {e}", dest.display()));
        // A symbolic link is followed: its target is what gets replaced.
        let target = match std::fs::canonicalize(dest) {
            Ok(t) => t,
            Err(_) => dest.to_path_buf(),
        };
        let sink = match std::fs::metadata(&target) {
            Ok(m) if m.is_dir() => {
                return Err(Error::Output(format!(
                    "cannot write {}: is a directory",
                    dest.display()
                )))
            }
            Ok(m) if !m.is_file() => Sink::InPlace(std::io::BufWriter::new(
                std::fs::OpenOptions::new()
                    .write(true)
                    .open(&target)
                    .map_err(err)?,
            )),
            existing => {
                let dir = match target.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                let name = target
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let prefix = format!(".{name}.");
                let mut b = tempfile::Builder::new();
                b.prefix(&prefix).suffix(".nav440-tmp");
                // An existing file keeps its permissions; a new one gets 0666 less the umask,
                // as `File::create` would give it.
                #[cfg(unix)]
                let perms = match &existing {
                    Ok(m) => m.permissions(),
                    Err(_) => std::os::unix::fs::PermissionsExt::from_mode(0o666),
                };
                #[cfg(unix)]
                b.permissions(perms.clone());
                let tmp = b.tempfile_in(&dir).map_err(err)?;
                #[cfg(unix)]
                if existing.is_ok() {
                    // The umask narrowed the mode the temporary file was created with.
                    tmp.as_file().set_permissions(perms).map_err(err)?;
                }
                #[cfg(not(unix))]
                let _ = existing;
                return Ok(OutputFile {
                    dest: target,
                    sink: Sink::Temp(std::io::BufWriter::new(tmp)),
                });
            }
        };
        Ok(OutputFile { dest: target, sink })
    }

    /// `true` if this output is standard output.
    pub fn is_stdout(&self) -> bool {
        matches!(self.sink, Sink::Stdout(_))
    }

    /// Flushes the output, syncs a file to disk and renames the temporary file over the
    /// destination. An output error names the destination.
    pub fn commit(self) -> Result<()> {
        let dest = self.dest;
        let err =
            |e: std::io::Error| Error::Output(format!("cannot write {}: {e}", dest.display()));
        match self.sink {
            Sink::Stdout(mut w) => match w.flush() {
                // A closed pipe (`| head`) stops the command quietly, as everywhere.
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
                r => r.map_err(|e| Error::Output(format!("cannot write output: {e}"))),
            },
            Sink::InPlace(mut w) => w.flush().map_err(err),
            Sink::Temp(w) => {
                let tmp = w.into_inner().map_err(|e| err(e.into_error()))?;
                tmp.as_file().sync_all().map_err(err)?;
                tmp.persist(&dest).map(drop).map_err(|e| err(e.error))
            }
        }
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.sink {
            Sink::Temp(w) => w.write(buf),
            Sink::InPlace(w) => w.write(buf),
            Sink::Stdout(w) => w.write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.sink {
            Sink::Temp(w) => w.flush(),
            Sink::InPlace(w) => w.flush(),
            Sink::Stdout(w) => w.flush(),
        }
    }
}

/// Writes `bytes` to the output `dest` (`-`: standard output) through [`OutputFile`].
pub fn write_output(dest: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = OutputFile::create(dest)?;
    match f.write_all(bytes) {
        Err(e) if f.is_stdout() && e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(()),
        r => r.map_err(|e| Error::Output(format!("cannot write {}: {e}", output_name(dest))))?,
    }
    f.commit()
}

/// Checks, without changing anything, that the file `p` can be written later (`record`
/// writes it as the bytes arrive, so it is opened only once the unit answered): an existing
/// file is opened for appending and closed (its contents are kept), for a missing one the
/// directory must take a new file (a temporary file is created there and removed). `-`
/// checks standard output. The error is the one writing would give (exit 5).
pub fn check_writable(p: &Path) -> Result<()> {
    if is_stdout(p) {
        return check_stdout();
    }
    let err = |e: std::io::Error| Error::Output(format!("cannot write {}: {e}", p.display()));
    match std::fs::metadata(p) {
        Ok(m) if m.is_dir() => Err(Error::Output(format!(
            "cannot write {}: is a directory",
            p.display()
        ))),
        Ok(_) => std::fs::OpenOptions::new()
            .append(true)
            .open(p)
            .map(drop)
            .map_err(err),
        Err(_) => OutputFile::create(p).map(drop),
    }
}
