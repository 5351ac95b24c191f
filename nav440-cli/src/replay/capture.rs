//! Reading a capture: a file or standard input, in chunks of [`READ_CHUNK`] bytes.

use super::*;

/// The capture name that means standard input.
pub const STDIN_NAME: &str = "-";

/// Size of one read from a capture, bytes: every command reads its input in chunks of this
/// size, so its memory does not grow with the capture.
pub const READ_CHUNK: usize = 64 * 1024;

/// `true` if `path` is `-` (standard input).
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == STDIN_NAME
}

/// The name of a capture in messages: its path, or "standard input" for `-`.
pub fn capture_name(path: &Path) -> String {
    if is_stdin(path) {
        "standard input".to_string()
    } else {
        path.display().to_string()
    }
}

/// A capture (file or standard input) read chunk by chunk.
pub struct CaptureReader {
    name: String,
    inner: Box<dyn std::io::Read>,
    bytes: u64,
    /// The size of a regular file, bytes (`None` for standard input, a pipe or a device).
    file_len: Option<u64>,
}

impl std::fmt::Debug for CaptureReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CaptureReader")
            .field("name", &self.name)
            .field("bytes", &self.bytes)
            .finish()
    }
}

/// Opens a capture for reading: a file, or standard input for `-`. A missing or unreadable
/// file is an [`Error::Input`].
pub fn open_capture(path: &Path) -> Result<CaptureReader> {
    let name = capture_name(path);
    let mut file_len = None;
    let inner: Box<dyn std::io::Read> = if is_stdin(path) {
        Box::new(std::io::stdin())
    } else {
        let f = std::fs::File::open(path)
            .map_err(|e| Error::Input(format!("cannot read {name}: {}", io_reason(&e))))?;
        let meta = f.metadata().ok();
        if meta.as_ref().is_some_and(|m| m.is_dir()) {
            return Err(Error::Input(format!("cannot read {name}: is a directory")));
        }
        file_len = meta.filter(|m| m.is_file()).map(|m| m.len());
        Box::new(f)
    };
    Ok(CaptureReader {
        name,
        inner,
        bytes: 0,
        file_len,
    })
}

impl CaptureReader {
    /// The capture's name in messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Reads the next chunk into `buf`: `Ok(None)` at the end of the input. A read failure is an
    /// [`Error::Input`], and so is an input that ends before its first byte ("is empty").
    pub fn next_chunk<'a>(&mut self, buf: &'a mut [u8]) -> Result<Option<&'a [u8]>> {
        loop {
            match self.inner.read(buf) {
                Ok(0) if self.bytes == 0 => {
                    return Err(Error::Input(format!("{} is empty", self.name)))
                }
                Ok(0) => return Ok(None),
                Ok(n) => {
                    self.bytes += n as u64;
                    return Ok(buf.get(..n));
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    return Err(Error::Input(format!(
                        "cannot read {}: {}",
                        self.name,
                        io_reason(&e)
                    )))
                }
            }
        }
    }

    /// Reads the whole input in chunks of [`READ_CHUNK`] bytes, calling `f` on each, until the
    /// end or until `f` returns `Ok(false)` (stop) or an error.
    pub fn for_each_chunk(&mut self, mut f: impl FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        let mut buf = vec![0u8; READ_CHUNK];
        while let Some(chunk) = self.next_chunk(&mut buf)? {
            if !f(chunk)? {
                break;
            }
        }
        Ok(())
    }
}

/// The most a command holds of a capture in memory, bytes (1 GiB): the bytes of a capture read
/// whole ([`read_capture`], `nav440 sim`), or the samples `paper`, `tune` and `plot` keep
/// ([`MAX_SAMPLES`]). Beyond it the command stops with an [`Error::Input`] (exit 3), found
/// while reading: nothing past the cap is read or allocated.
pub const MAX_CAPTURE_BYTES: u64 = 1 << 30;

/// The error for a capture `name` beyond the cap: what was read, the cap, and `hint` (how to
/// stream instead, or how to cut it).
pub(crate) fn too_large(name: &str, what: &str, hint: &str) -> Error {
    Error::Input(format!(
        "{name}: {what} more than {MAX_CAPTURE_BYTES} bytes (1 GiB), the most a command holds in memory; {hint}"
    ))
}

/// Reads a whole capture into memory (file, or standard input for `-`); a missing, unreadable
/// or empty input is an [`Error::Input`], and so is one larger than [`MAX_CAPTURE_BYTES`]
/// (a file's size is checked before reading; a stream is stopped at the cap, with `hint` in
/// the message). The commands that can stream do (see [`CaptureReader`]).
pub fn read_capture(path: &Path, hint: &str) -> Result<Vec<u8>> {
    let mut r = open_capture(path)?;
    let over = |name: &str| too_large(name, "holds", hint);
    if let Some(len) = r.file_len {
        if len > MAX_CAPTURE_BYTES {
            return Err(over(r.name()));
        }
    }
    let mut bytes = Vec::new();
    r.for_each_chunk(|c| {
        if (bytes.len() + c.len()) as u64 > MAX_CAPTURE_BYTES {
            return Err(over(&capture_name(path)));
        }
        bytes.extend_from_slice(c);
        Ok(true)
    })?;
    Ok(bytes)
}

pub(crate) fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => "no such file".to_string(),
        std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
        _ => e.to_string(),
    }
}

/// A byte stream given in chunks: a slice (one chunk) or a [`CaptureReader`].
pub trait IntoChunks<'a> {
    /// Calls `f` on each chunk until the end or until `f` returns `Ok(false)`.
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()>;
}

impl<'a> IntoChunks<'a> for &'a [u8] {
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        f(self).map(|_| ())
    }
}

/// A byte source that pushes its chunks itself (e.g. a serial port read until it closes):
/// `FnChunks(|f| { ...; f(chunk)?; ... })`; it should stop when `f` returns `Ok(false)`.
pub struct FnChunks<F>(pub F);

impl<'a, F> IntoChunks<'a> for FnChunks<F>
where
    F: FnOnce(&mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()>,
{
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        (self.0)(f)
    }
}

impl<'a> IntoChunks<'a> for &'a mut CaptureReader {
    fn chunks(self, f: &mut dyn FnMut(&[u8]) -> Result<bool>) -> Result<()> {
        self.for_each_chunk(f)
    }
}

/// The result of a write to the command's output: a closed pipe (`nav440 ... | head`) sets
/// `closed` and is not an error (the command stops quietly); any other failure is an
/// [`Error::Output`].
pub fn output_result(r: std::io::Result<()>, closed: &mut bool) -> Result<()> {
    match r {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            *closed = true;
            Ok(())
        }
        Err(e) => Err(Error::Output(format!("cannot write output: {e}"))),
        Ok(()) => Ok(()),
    }
}
