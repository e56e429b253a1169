//! The byte stream to the image and the PIL frames on it: QEMU's USART socket,
//! its semihosting FIFOs or a serial port, each read with a timeout, and the
//! frames ([`firmware::pil`]: postcard, CRC-32, COBS) cut out of what arrives.

use std::{
    io::{Read, Write},
    os::unix::net::UnixStream,
    path::{Path, PathBuf},
    time::{Duration, Instant},
};

use firmware::pil::{self, Downlink, MAX_FRAME, Uplink, WireError};

use super::target::BAUD_RANGE;
use crate::record::RunError;

/// The byte stream to the image, with a read timeout.
pub(super) enum Pipe {
    /// QEMU's `-chardev socket`, connected to our listener.
    Socket(UnixStream),
    /// The semihosting FIFOs: `down` (ours to write, opened read-write so it
    /// opens before QEMU's end and never blocks), `up` (ours to read); both
    /// non-blocking, waited on with `poll`.
    Fifo { down: std::fs::File, up: std::fs::File },
    /// A serial device.
    Serial { port: Box<dyn serialport::SerialPort>, path: PathBuf, baud: u32 },
}

/// Opens the serial device `path` raw 8N1 at `baud`, no flow control, reads
/// timing out after `timeout`, and drops what was queued before (bytes of a
/// previous run or session). The PIL link and the bring-up client share it.
///
/// # Errors
/// The reason, without the port's name (the caller names it).
pub fn open_port(path: &Path, baud: u32, timeout: Duration) -> Result<Box<dyn serialport::SerialPort>, String> {
    let name = path.to_str().ok_or_else(|| "the path is not UTF-8".to_string())?;
    let port = serialport::new(name, baud)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(timeout)
        .open()
        .map_err(|e| e.to_string())?;
    let _ = port.clear(serialport::ClearBuffer::Input);
    Ok(port)
}

/// What one read of a [`Pipe`] gave.
pub(super) enum Got {
    /// Bytes (at least one).
    Bytes(usize),
    /// Nothing within the wait.
    Nothing,
}

impl Pipe {
    /// Opens `path` raw 8N1 at `baud`, no flow control, and drops what was
    /// queued before (bytes of a previous run).
    pub(super) fn open_serial(path: &Path, baud: u32) -> Result<Self, RunError> {
        let cannot = |why: String| RunError::Transport(format!("cannot open the serial port {} at {baud} baud: {why}", path.display()));
        if !BAUD_RANGE.contains(&baud) {
            return Err(cannot(format!("outside {}..={} baud", BAUD_RANGE.start(), BAUD_RANGE.end())));
        }
        let port = open_port(path, baud, Duration::from_millis(100)).map_err(cannot)?;
        Ok(Self::Serial { port, path: path.to_path_buf(), baud })
    }

    /// What the pipe is, for error messages.
    pub(super) fn name(&self) -> String {
        match self {
            Self::Socket(_) => "QEMU's USART socket".into(),
            Self::Fifo { .. } => "QEMU's semihosting FIFO".into(),
            Self::Serial { path, .. } => format!("the serial port {}", path.display()),
        }
    }

    /// Reads what arrives within `wait`.
    ///
    /// # Errors
    /// The pipe closed (QEMU exited, the serial device hung up or vanished) or failed.
    pub(super) fn read_within(&mut self, buf: &mut [u8], wait: Duration) -> Result<Got, String> {
        let wait = wait.max(Duration::from_millis(1));
        let got = match self {
            Self::Socket(s) => s.set_read_timeout(Some(wait)).and_then(|()| s.read(buf)),
            Self::Fifo { up, .. } => read_fifo_within(up, buf, wait),
            Self::Serial { port, .. } => port.set_timeout(wait).map_err(std::io::Error::from).and_then(|()| port.read(buf)),
        };
        match got {
            Ok(0) => Err(match self {
                Self::Socket(_) => "QEMU closed the USART socket".into(),
                Self::Fifo { .. } => "QEMU closed its semihosting FIFO".into(),
                Self::Serial { path, .. } => format!("the serial port {} closed (unplugged?)", path.display()),
            }),
            Ok(n) => Ok(Got::Bytes(n)),
            Err(e)
                if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted) =>
            {
                Ok(Got::Nothing)
            }
            // serialport reports a hang-up (POLLHUP: a USB adapter unplugged) as a broken pipe.
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe && matches!(self, Self::Serial { .. }) => {
                Err(format!("{} hung up (unplugged?)", self.name()))
            }
            Err(e) => Err(format!("reading {}: {e}", self.name())),
        }
    }

    /// Writes all of `bytes`, waiting at most `timeout` for room on a serial line.
    pub(super) fn write_all(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), String> {
        let done = match self {
            Self::Socket(s) => s.write_all(bytes),
            // Non-blocking: a full pipe (64 KiB the image has not read) is an error, not a hang.
            Self::Fifo { down, .. } => down.write_all(bytes),
            Self::Serial { port, .. } => port.set_timeout(timeout).map_err(std::io::Error::from).and_then(|()| port.write_all(bytes)),
        };
        let (name, serial) = (self.name(), matches!(self, Self::Serial { .. }));
        done.map_err(|e| match e.kind() {
            std::io::ErrorKind::TimedOut => format!("cannot write to {name}: no room within {} s", timeout.as_secs_f64()),
            std::io::ErrorKind::WouldBlock => format!("cannot write to {name}: full (the image reads nothing)"),
            _ if serial => format!("cannot write to {name}: {e} (unplugged?)"),
            _ => format!("cannot write to {name}: {e}"),
        })
    }
}

/// Makes the FIFO `path` (mode 0600) and opens it non-blocking, read-only or
/// read-write (a FIFO opened read-write on Linux opens without waiting for the
/// other end and never blocks a writer's open).
pub(super) fn open_fifo(path: &Path, read_write: bool) -> Result<std::fs::File, String> {
    use std::os::unix::{ffi::OsStrExt, fs::OpenOptionsExt};
    let _ = std::fs::remove_file(path);
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).map_err(|e| e.to_string())?;
    // SAFETY: `c` is a valid NUL-terminated path for the call's duration.
    if unsafe { libc::mkfifo(c.as_ptr(), 0o600) } != 0 {
        return Err(format!("cannot make the FIFO {}: {}", path.display(), std::io::Error::last_os_error()));
    }
    std::fs::OpenOptions::new()
        .read(true)
        .write(read_write)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| format!("cannot open the FIFO {}: {e}", path.display()))
}

/// Reads what arrives on the FIFO `up` within `wait` (`poll`, then a
/// non-blocking read): `Ok(0)` once QEMU closed its end (the pipe hangs up only
/// after a writer came and went, so a QEMU still booting is just silent).
fn read_fifo_within(up: &mut std::fs::File, buf: &mut [u8], wait: Duration) -> std::io::Result<usize> {
    use std::os::fd::AsRawFd;
    let mut fd = libc::pollfd { fd: up.as_raw_fd(), events: libc::POLLIN, revents: 0 };
    let ms = libc::c_int::try_from(wait.as_millis().max(1)).unwrap_or(libc::c_int::MAX);
    // SAFETY: one valid pollfd for the call's duration.
    let n = unsafe { libc::poll(&mut fd, 1, ms) };
    if n < 0 {
        return Err(std::io::Error::last_os_error());
    }
    if n == 0 {
        return Err(std::io::ErrorKind::TimedOut.into());
    }
    // POLLHUP without data reads as the end of file (0) below.
    up.read(buf)
}

/// What [`FramedPipe::recv_before`] got.
pub(super) enum Received {
    /// A message.
    Msg(Uplink),
    /// A frame that does not decode (damaged, or not ours).
    Undecodable(WireError),
    /// Nothing by the deadline.
    Nothing,
}

/// Why [`FramedPipe::recv_before`] got no frame.
pub(super) enum RecvError {
    /// The pipe closed (QEMU exited, the serial device hung up or vanished) or
    /// failed: what happened, for the caller to explain.
    Pipe(String),
    /// The other end sends bytes without frame terminators: the whole message.
    NotFrames(String),
}

/// A [`Pipe`] with the bytes read from it that do not yet make a whole frame.
pub(super) struct FramedPipe {
    /// The byte stream.
    pub(super) pipe: Pipe,
    inbox: Vec<u8>,
}

impl FramedPipe {
    /// `pipe`, nothing read yet.
    pub(super) fn new(pipe: Pipe) -> Self {
        Self { pipe, inbox: Vec::new() }
    }

    /// Writes all of `bytes`, waiting at most `timeout` for room on a serial line.
    ///
    /// # Errors
    /// [`RunError::Transport`] when the pipe is full, closed or failed.
    pub(super) fn write(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), RunError> {
        self.pipe.write_all(bytes, timeout).map_err(RunError::Transport)
    }

    /// Frames `msg` and writes it, as [`Self::write`].
    ///
    /// # Errors
    /// [`RunError::Transport`] when it cannot be framed or written.
    pub(super) fn send(&mut self, msg: &Downlink, timeout: Duration) -> Result<(), RunError> {
        let mut buf = [0u8; MAX_FRAME];
        let frame = pil::encode(msg, &mut buf).map_err(|e| RunError::Transport(format!("cannot frame {msg:?}: {e}")))?;
        self.write(frame, timeout)
    }

    /// The next frame from the image, or [`Received::Nothing`] at `deadline`.
    ///
    /// # Errors
    /// [`RecvError::Pipe`] when the pipe closed or failed, [`RecvError::NotFrames`]
    /// when the other end sends bytes without frame terminators.
    pub(super) fn recv_before(&mut self, deadline: Instant) -> Result<Received, RecvError> {
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(end) = self.inbox.iter().position(|&b| b == 0) {
                let mut frame: Vec<u8> = self.inbox.drain(..=end).collect();
                frame.pop();
                if frame.is_empty() {
                    continue;
                }
                return Ok(match pil::decode::<Uplink>(&mut frame) {
                    Ok(m) => Received::Msg(m),
                    Err(e) => Received::Undecodable(e),
                });
            }
            if self.inbox.len() > 16 * MAX_FRAME {
                return Err(RecvError::NotFrames(format!(
                    "{} carries bytes that are not PIL frames (another program on the line, or the wrong baud?)",
                    self.pipe.name()
                )));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(Received::Nothing);
            }
            match self.pipe.read_within(&mut chunk, deadline - now) {
                Ok(Got::Bytes(n)) => self.inbox.extend_from_slice(&chunk[..n]),
                Ok(Got::Nothing) => {}
                Err(what) => return Err(RecvError::Pipe(what)),
            }
        }
    }
}
