//! The bring-up protocol over a serial line (`arm_app::bringup`; docs/board.md
//! "Bring-up"): frames in the PIL wire's framing (postcard, CRC-32C, COBS,
//! `firmware::pil`). [`Client`] is the host's end (`sil-host board`); [`serve`]
//! is the board's end as the board twin runs it, ticking the arm between
//! requests, as the image's idle loop serves them between two ticks.

use std::{
    io::{ErrorKind, Read, Write},
    sync::atomic::{AtomicBool, Ordering},
    time::{Duration, Instant},
};

use arm_app::bringup::{Reply, Request};
use firmware::pil::{FrameBuffer, MAX_FRAME, Push, decode, encode};

use crate::free_arm::{ArmBoard, FreeArm};

/// The host's end of the line.
pub struct Client<S> {
    line: S,
    frames: FrameBuffer,
}

/// The line rate of the reference board's USART1, baud: the PIL link's
/// ([`rig::pil_link::DEFAULT_BAUD`]), the same line.
pub use rig::pil_link::DEFAULT_BAUD;

impl Client<Box<dyn serialport::SerialPort>> {
    /// Opens the serial device `path` (a USB-serial adapter on the board's
    /// USART1, or the board twin's pseudo-terminal) raw 8N1 at `baud`, no flow
    /// control, and drops what was queued before.
    ///
    /// # Errors
    /// A message naming the port and the OS's reason.
    pub fn open(path: &std::path::Path, baud: u32) -> Result<Self, String> {
        let port = rig::pil_link::open_port(path, baud, Duration::from_millis(50))
            .map_err(|why| format!("cannot open the serial port {} at {baud} baud: {why}", path.display()))?;
        Ok(Self::new(port))
    }
}

/// A pseudo-terminal whose master end the board twin serves: `path` is the
/// end a client opens as its serial port.
pub struct Pty {
    /// The twin's end, non-blocking.
    pub master: std::fs::File,
    /// Held open so that the master's reads wait (`WouldBlock`) rather than
    /// fail (`EIO`) while no client has the port open.
    _slave: std::fs::File,
    /// The slave's path (`/dev/pts/N`).
    pub path: std::path::PathBuf,
}

impl Pty {
    /// Opens a pseudo-terminal, raw (no echo, no line editing), its master
    /// non-blocking.
    ///
    /// # Errors
    /// A message with the OS's reason.
    pub fn open() -> Result<Self, String> {
        use std::os::fd::FromRawFd;
        let (mut master, mut slave) = (-1, -1);
        // SAFETY: openpty writes the two descriptors only (no name buffer, default settings).
        let rc = unsafe { libc::openpty(&mut master, &mut slave, std::ptr::null_mut(), std::ptr::null(), std::ptr::null()) };
        if rc != 0 {
            return Err(format!("cannot open a pseudo-terminal: {}", std::io::Error::last_os_error()));
        }
        // SAFETY: two fresh descriptors that nothing else owns.
        let (master_f, slave_f) = unsafe { (std::fs::File::from_raw_fd(master), std::fs::File::from_raw_fd(slave)) };
        // SAFETY: plain termios and fcntl calls on descriptors we own.
        unsafe {
            let mut t: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(slave, &mut t) == 0 {
                libc::cfmakeraw(&mut t);
                libc::tcsetattr(slave, libc::TCSANOW, &t);
            }
            let flags = libc::fcntl(master, libc::F_GETFL);
            libc::fcntl(master, libc::F_SETFL, flags | libc::O_NONBLOCK);
        }
        let path = std::fs::read_link(format!("/proc/self/fd/{slave}")).map_err(|e| format!("cannot name the pseudo-terminal: {e}"))?;
        Ok(Self { master: master_f, _slave: slave_f, path })
    }
}

impl<S: Read + Write> Client<S> {
    /// A client on `line` (a serial port, or a pseudo-terminal's end), whose reads
    /// time out (a read that times out returns `TimedOut` or `WouldBlock`).
    pub fn new(line: S) -> Self {
        Self { line, frames: FrameBuffer::default() }
    }

    /// Sends `request` and waits up to `timeout` for its reply; frames that do
    /// not decode (line noise, a reply to an earlier request that timed out) are
    /// skipped.
    ///
    /// # Errors
    /// A message naming what failed: the write, the read, or no reply in time.
    pub fn request(&mut self, request: &Request, timeout: Duration) -> Result<Reply, String> {
        self.request_until(request, timeout, |_| true)
    }

    /// As [`Client::request`], skipping the replies `wanted` refuses: the first
    /// request of a session (`Hello`) skips replies still on their way to an
    /// earlier client that was killed mid-command (one request, one reply, in
    /// order: they all come before this request's).
    ///
    /// # Errors
    /// As [`Client::request`].
    pub fn request_until(&mut self, request: &Request, timeout: Duration, wanted: impl Fn(&Reply) -> bool) -> Result<Reply, String> {
        let mut buf = [0u8; MAX_FRAME];
        let bytes = encode(request, &mut buf).map_err(|e| format!("encode {request:?}: {e:?}"))?;
        // A lone terminator first ends whatever partial frame is on the line.
        self.line.write_all(&[0]).and_then(|()| self.line.write_all(bytes)).map_err(|e| format!("write: {e}"))?;
        self.line.flush().map_err(|e| format!("write: {e}"))?;
        let until = Instant::now() + timeout;
        let mut byte = [0u8; 64];
        while Instant::now() < until {
            let n = match self.line.read(&mut byte) {
                Ok(0) => return Err("the line was closed (board unplugged?)".into()),
                Ok(n) => n,
                Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted) => continue,
                Err(e) => return Err(format!("read: {e}")),
            };
            for &b in &byte[..n] {
                if let Push::Frame(f) = self.frames.push(b)
                    && let Ok(reply) = decode::<Reply>(f)
                    && wanted(&reply)
                {
                    return Ok(reply);
                }
            }
        }
        Err(format!("no reply to {request:?} within {} s (is the board powered and on this port?)", timeout.as_secs_f64()))
    }
}

/// The most reply bytes kept for a client that does not read (64 KiB: some
/// 3 000 replies); beyond it the oldest are dropped.
pub const OUTBOX_LIMIT: usize = 64 * 1024;

/// Writes what `line` takes of `outbox` now; drops the oldest bytes beyond
/// [`OUTBOX_LIMIT`].
///
/// # Errors
/// A message when the line fails otherwise than by being full.
fn flush_what_fits(line: &mut impl Write, outbox: &mut std::collections::VecDeque<u8>) -> Result<(), String> {
    while !outbox.is_empty() {
        let (front, _) = outbox.as_slices();
        match line.write(front) {
            Ok(0) => break,
            Ok(n) => {
                outbox.drain(..n);
            }
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => break,
            // The other end not open (a client gone): nobody to reply to.
            Err(e) if e.raw_os_error() == Some(libc::EIO) => {
                outbox.clear();
                break;
            }
            Err(e) => return Err(format!("write: {e}")),
        }
    }
    if outbox.len() > OUTBOX_LIMIT {
        let excess = outbox.len() - OUTBOX_LIMIT;
        outbox.drain(..excess);
    }
    Ok(())
}

/// Serves the bring-up protocol on `line` for `arm`, one tick per period of
/// wall time (the board's period at that tick, [`FreeArm::period_s`]: a
/// `configure` of another rate changes the pace), until `stop` is set or the line is closed. Requests are
/// answered between ticks. `line` must not block on reads (a pseudo-terminal
/// master in non-blocking mode). A client that writes faster than it reads is
/// served what the line takes (the rest waits, up to [`OUTBOX_LIMIT`] bytes).
///
/// # Errors
/// A message when the line fails or the plant fails.
pub fn serve<B: ArmBoard>(arm: &mut FreeArm<B>, line: &mut (impl Read + Write), stop: &AtomicBool) -> Result<(), String> {
    let mut next = Instant::now();
    let mut byte = [0u8; 256];
    // Replies the line has not taken yet (a client that writes faster than it
    // reads fills the pseudo-terminal): kept up to OUTBOX_LIMIT, then the oldest
    // are dropped, as a UART drops what nobody reads.
    let mut outbox: std::collections::VecDeque<u8> = std::collections::VecDeque::new();
    while !stop.load(Ordering::Relaxed) {
        let ts = Duration::from_secs_f64(arm.period_s());
        arm.tick().map_err(|e| e.to_string())?;
        let mut received = Vec::new();
        loop {
            let n = match line.read(&mut byte) {
                Ok(0) => return Ok(()),
                Ok(n) => n,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted | ErrorKind::TimedOut) => break,
                // A pseudo-terminal whose other end is not open reads EIO.
                Err(e) if e.raw_os_error() == Some(libc::EIO) => break,
                Err(e) => return Err(format!("read: {e}")),
            };
            received.extend_from_slice(&byte[..n]);
        }
        outbox.extend(arm.line(&received));
        flush_what_fits(line, &mut outbox)?;
        next += ts;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    Ok(())
}
