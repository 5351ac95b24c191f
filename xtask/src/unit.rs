//! `cargo xtask unit`: the firmware in QEMU with its NAV440 UART connected to a unit that
//! listens on TCP (the `nav440 sim` simulator, or any program speaking the protocol).
//!
//! QEMU serves the board's first two UARTs on unix sockets (`server=on,wait=on`: the guest
//! starts only once both are connected). This relay connects to them and to the unit:
//! * firmware -> unit: every byte the firmware transmits (its commands), as it comes;
//! * unit -> firmware: every byte the unit sends, counted, starting once the firmware has
//!   transmitted its first byte (its UART is enabled by then: QEMU's STM32 USART drops bytes
//!   that arrive earlier; the unit's bytes wait in the TCP buffer, none is lost or skipped);
//! * when the unit closes the connection, the relay sends `N4EN` + the byte count (u32 LE)
//!   on the second UART (the control channel): the firmware stops after exactly that many
//!   bytes, so where a run ends never depends on the host's speed.
//!
//! The firmware's semihosting stdout (the estimate CSV) and stderr (diagnostics, counters)
//! are QEMU's; its exit status is QEMU's exit code. A `uart-rows` image's third UART (UART2 on
//! the mps2 boards: the rows as framed binary messages) goes to a file ([`run_with_rows`]).

use crate::qemu::{self, Board};
use std::io::{Read, Write};
use std::net::{Shutdown, TcpStream, ToSocketAddrs};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread;
use std::time::{Duration, Instant};

/// Magic of the control channel's end message.
pub const END_MAGIC: &[u8; 4] = b"N4EN";

/// The end message for a unit that sent `bytes` bytes.
pub fn end_message(bytes: u64) -> Result<[u8; 8], String> {
    let n = u32::try_from(bytes).map_err(|_| "the unit sent more than 4 GiB".to_owned())?;
    let mut m = [0u8; 8];
    m[..4].copy_from_slice(END_MAGIC);
    m[4..].copy_from_slice(&n.to_le_bytes());
    Ok(m)
}

/// `tcp:HOST:PORT` -> `HOST:PORT`.
pub fn parse_connect(s: &str) -> Result<String, String> {
    let rest = s
        .strip_prefix("tcp:")
        .ok_or_else(|| format!("`{s}`: expected tcp:HOST:PORT"))?;
    let (host, port) = rest
        .rsplit_once(':')
        .ok_or_else(|| format!("`{s}`: expected tcp:HOST:PORT"))?;
    if host.is_empty() || port.parse::<u16>().is_err() {
        return Err(format!("`{s}`: expected tcp:HOST:PORT with a port 0-65535"));
    }
    Ok(rest.to_owned())
}

/// What one unit run produced.
pub struct UnitRun {
    /// QEMU's (the firmware's) exit status.
    pub status: ExitStatus,
    /// The firmware's stdout (empty when inherited).
    pub stdout: String,
    /// The firmware's stderr and QEMU's messages, plus the relay's summary line.
    pub stderr: String,
    /// The firmware's output bytes as QEMU passed them on (its defmt frames), unless longer
    /// than the reader keeps.
    pub raw: Option<Vec<u8>>,
    /// Bytes the unit sent.
    pub unit_bytes: u64,
    /// Wall time.
    pub elapsed: Duration,
}

impl UnitRun {
    /// The exit code (`None` if QEMU was killed by a signal).
    pub fn code(&self) -> Option<i32> {
        self.status.code()
    }
}

/// Connects to a unix socket that QEMU is about to create, retrying for up to `wait`.
fn connect_unix(
    path: &Path,
    wait: Duration,
    qemu: &mut std::process::Child,
) -> Result<UnixStream, String> {
    let start = Instant::now();
    loop {
        match UnixStream::connect(path) {
            Ok(s) => return Ok(s),
            Err(e) => {
                if let Ok(Some(status)) = qemu.try_wait() {
                    return Err(format!(
                        "QEMU exited ({status}) before {} was served",
                        path.display()
                    ));
                }
                if start.elapsed() > wait {
                    return Err(format!("cannot connect to QEMU's {}: {e}", path.display()));
                }
                thread::sleep(Duration::from_millis(20));
            }
        }
    }
}

/// Connects to the unit, retrying while it refuses (not listening yet) for up to `wait`.
fn connect_unit(addr: &str, wait: Duration) -> Result<TcpStream, String> {
    let start = Instant::now();
    loop {
        let addrs: Vec<_> = addr
            .to_socket_addrs()
            .map_err(|e| format!("cannot resolve `{addr}`: {e}"))?
            .collect();
        let mut last = None;
        for a in &addrs {
            match TcpStream::connect_timeout(a, Duration::from_secs(2)) {
                Ok(s) => return Ok(s),
                Err(e) => last = Some(e),
            }
        }
        if start.elapsed() > wait {
            return Err(format!(
                "cannot connect to the unit at {addr}: {}",
                last.map_or("no address".to_owned(), |e| e.to_string())
            ));
        }
        thread::sleep(Duration::from_millis(50));
    }
}

/// A one-shot "go" flag the firmware->unit relay raises at the firmware's first byte.
#[derive(Default)]
struct Gate {
    open: Mutex<bool>,
    cv: Condvar,
}

impl Gate {
    fn open(&self) {
        if let Ok(mut g) = self.open.lock() {
            *g = true;
            self.cv.notify_all();
        }
    }

    /// Waits until open or `stop` is set (checked every 100 ms).
    fn wait(&self, stop: &AtomicBool) -> bool {
        let Ok(mut g) = self.open.lock() else {
            return false;
        };
        while !*g {
            if stop.load(Ordering::Relaxed) {
                return false;
            }
            g = match self.cv.wait_timeout(g, Duration::from_millis(100)) {
                Ok((g, _)) => g,
                Err(_) => return false,
            };
        }
        true
    }
}

/// Socket path for `tag` (unix socket paths are limited to ~108 bytes: use the temp dir if
/// the work dir is too deep).
fn socket_path(dir: &Path, tag: &str) -> PathBuf {
    let name = format!(
        "n4-{tag}-{}-{}.sock",
        std::process::id(),
        crate::qemu::run_number()
    );
    let p = dir.join(&name);
    if p.as_os_str().len() < 100 {
        p
    } else {
        std::env::temp_dir().join(name)
    }
}

/// Runs `elf` on `board` connected to the unit at `addr` (`HOST:PORT`); `inherit_stdout`
/// streams the CSV to this process's stdout instead of collecting it. QEMU is killed after
/// `timeout`.
pub fn run(
    board: &Board,
    elf: &Path,
    addr: &str,
    work: &Path,
    inherit_stdout: bool,
    timeout: Duration,
) -> Result<UnitRun, String> {
    run_with_rows(board, elf, addr, work, inherit_stdout, timeout, None)
}

/// [`run`], with the board's third UART (a `uart-rows` image's output UART, UART2 on the mps2
/// boards) written to the file `rows` (QEMU's `-chardev file`; complete once QEMU has exited).
pub fn run_with_rows(
    board: &Board,
    elf: &Path,
    addr: &str,
    work: &Path,
    inherit_stdout: bool,
    timeout: Duration,
    rows: Option<&Path>,
) -> Result<UnitRun, String> {
    let s0 = socket_path(work, "u0");
    let s1 = socket_path(work, "u1");
    let _ = std::fs::remove_file(&s0);
    let _ = std::fs::remove_file(&s1);
    let mut args = qemu::base_args(board, elf, &[]);
    args.extend([
        "-chardev".to_owned(),
        format!("socket,id=u0,path={},server=on,wait=on", s0.display()),
        "-serial".to_owned(),
        "chardev:u0".to_owned(),
        "-chardev".to_owned(),
        format!("socket,id=u1,path={},server=on,wait=on", s1.display()),
        "-serial".to_owned(),
        "chardev:u1".to_owned(),
    ]);
    if let Some(rows) = rows {
        // QEMU gives its `-serial` options to the UARTs in order: this one is the third.
        args.extend([
            "-chardev".to_owned(),
            format!("file,id=u2,path={}", rows.display()),
            "-serial".to_owned(),
            "chardev:u2".to_owned(),
        ]);
    }
    eprintln!("+ qemu-system-arm {}", args.join(" "));
    let start = Instant::now();
    let mut child = Command::new("qemu-system-arm")
        .args(&args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
    // The firmware's stdout: defmt frames decoded into CSV + diagnostics, or text.
    let table = crate::defmt_out::table(elf)?;
    let out_reader = child
        .stdout
        .take()
        .map(|s| crate::defmt_out::spawn_reader(s, table, inherit_stdout));
    let mut err_pipe = child.stderr.take().ok_or("QEMU stderr not piped")?;
    let err_reader = thread::spawn(move || {
        let mut all = Vec::new();
        let _ = err_pipe.read_to_end(&mut all);
        String::from_utf8_lossy(&all).into_owned()
    });
    let kill = |child: &mut std::process::Child| {
        let _ = child.kill();
        let _ = child.wait();
    };
    let setup = (|| {
        let u0 = connect_unix(&s0, Duration::from_secs(20), &mut child)?;
        let u1 = connect_unix(&s1, Duration::from_secs(20), &mut child)?;
        let unit = connect_unit(addr, Duration::from_secs(20))?;
        Ok::<_, String>((u0, u1, unit))
    })();
    let _ = std::fs::remove_file(&s0);
    let _ = std::fs::remove_file(&s1);
    let (u0, u1, unit) = match setup {
        Ok(x) => x,
        Err(e) => {
            kill(&mut child);
            return Err(e);
        }
    };
    let _ = unit.set_nodelay(true);
    let stop = Arc::new(AtomicBool::new(false));
    let gate = Arc::new(Gate::default());
    let count = Arc::new(AtomicU64::new(0));

    // Firmware -> unit.
    let fw_to_unit = {
        let (mut from, mut to) = (
            u0.try_clone().map_err(|e| e.to_string())?,
            unit.try_clone().map_err(|e| e.to_string())?,
        );
        let gate = Arc::clone(&gate);
        thread::spawn(move || {
            let mut buf = [0u8; 4096];
            loop {
                match from.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        gate.open();
                        if to.write_all(&buf[..n]).is_err() {
                            break;
                        }
                    }
                }
            }
            let _ = to.shutdown(Shutdown::Write);
        })
    };
    // Unit -> firmware, counted; then the end message on the control channel.
    let unit_to_fw = {
        let (mut from, mut to) = (
            unit.try_clone().map_err(|e| e.to_string())?,
            u0.try_clone().map_err(|e| e.to_string())?,
        );
        let (gate, stop, count) = (Arc::clone(&gate), Arc::clone(&stop), Arc::clone(&count));
        // A clone: the original stays open until QEMU has exited (QEMU drops the bytes it has
        // not read yet when the socket hangs up).
        let mut u1 = u1.try_clone().map_err(|e| e.to_string())?;
        thread::spawn(move || -> Result<bool, String> {
            if !gate.wait(&stop) {
                return Ok(false);
            }
            let mut buf = [0u8; 4096];
            loop {
                match from.read(&mut buf) {
                    // Closed (or reset) by the unit: the stream is complete. (Also the way
                    // this thread is stopped once QEMU has exited.)
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        if to.write_all(&buf[..n]).is_err() {
                            // QEMU is gone (the firmware exited).
                            return Ok(false);
                        }
                        count.fetch_add(n as u64, Ordering::Relaxed);
                    }
                }
            }
            if stop.load(Ordering::Relaxed) {
                return Ok(false);
            }
            let m = end_message(count.load(Ordering::Relaxed))?;
            if std::env::var_os("XTASK_UNIT_DEBUG").is_some() {
                eprintln!("xtask: the unit closed the connection; sending {m:02x?} on the control channel");
            }
            // A failed write means QEMU has already exited (the firmware ended first).
            Ok(u1.write_all(&m).is_ok())
        })
    };
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if start.elapsed() > timeout => {
                stop.store(true, Ordering::Relaxed);
                kill(&mut child);
                let _ = unit.shutdown(Shutdown::Both);
                let diag = out_reader
                    .map(|h| h.join().unwrap_or_default().diag)
                    .unwrap_or_default();
                let stderr = diag + &err_reader.join().unwrap_or_default();
                return Err(format!(
                    "the firmware did not finish within {} s (QEMU killed; the unit sent {} bytes); its stderr:\n{stderr}",
                    timeout.as_secs(),
                    count.load(Ordering::Relaxed)
                ));
            }
            Ok(None) => thread::sleep(Duration::from_millis(10)),
            Err(e) => return Err(format!("waiting for QEMU: {e}")),
        }
    };
    stop.store(true, Ordering::Relaxed);
    let _ = unit.shutdown(Shutdown::Both);
    let _ = u0.shutdown(Shutdown::Both);
    drop(u1);
    let _ = fw_to_unit.join();
    let ended = unit_to_fw.join().unwrap_or(Ok(false))?;
    let crate::defmt_out::Read {
        stdout,
        diag,
        raw,
        raw_cut,
    } = out_reader
        .map(|h| h.join().unwrap_or_default())
        .unwrap_or_default();
    let qemu_stderr: String = err_reader
        .join()
        .unwrap_or_default()
        .lines()
        .filter(|l| !l.contains("QEMU waiting for connection"))
        .map(|l| format!("{l}\n"))
        .collect();
    let mut stderr = diag + &qemu_stderr;
    let unit_bytes = count.load(Ordering::Relaxed);
    stderr.push_str(&format!(
        "xtask: the unit sent {unit_bytes} bytes{}; firmware exit status {}\n",
        if ended {
            " and closed the connection"
        } else {
            " (connection still open when the firmware ended)"
        },
        status.code().map_or("killed".to_owned(), |c| c.to_string())
    ));
    Ok(UnitRun {
        status,
        stdout,
        stderr,
        raw: (!raw_cut).then_some(raw),
        unit_bytes,
        elapsed: start.elapsed(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn end_message_is_magic_and_le_count() {
        assert_eq!(
            end_message(0x0102_0304),
            Ok([b'N', b'4', b'E', b'N', 4, 3, 2, 1])
        );
        assert!(end_message(1 << 32).is_err());
    }

    #[test]
    fn connect_address_is_checked() {
        assert_eq!(
            parse_connect("tcp:127.0.0.1:5000"),
            Ok("127.0.0.1:5000".into())
        );
        assert_eq!(parse_connect("tcp:localhost:1"), Ok("localhost:1".into()));
        assert!(parse_connect("127.0.0.1:5000").is_err());
        assert!(parse_connect("tcp:127.0.0.1").is_err());
        assert!(parse_connect("tcp::5000").is_err());
        assert!(parse_connect("tcp:h:99999").is_err());
    }
}
