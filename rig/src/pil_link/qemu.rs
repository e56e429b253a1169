//! QEMU running the PIL image: spawning `qemu-system-arm` on the
//! `netduinoplus2` machine with the byte stream over the semihosting FIFOs or a
//! Unix socket, reading its outputs (the defmt log, its own messages), and
//! watching it: whether it exited, and why it is gone (its own exit, the
//! scenario's `kill_firmware` fault, or a signal from outside the run).

use std::{
    io::{BufRead, BufReader},
    os::unix::net::{UnixListener, UnixStream},
    path::{Path, PathBuf},
    process::{Child, Command, ExitStatus, Stdio},
    sync::{Arc, Mutex},
    thread::JoinHandle,
    time::{Duration, Instant},
};

use super::{
    defmt_log::{LogLine, LogSink, decode_defmt, table_of},
    pipe::{Pipe, open_fifo},
    target::QemuLink,
};
use crate::record::RunError;

/// QEMU's instruction-count shift: one instruction per `2^ICOUNT_SHIFT` ns of
/// virtual time (`-icount shift=0`: 1 ns each).
pub const ICOUNT_SHIFT: u32 = 0;

/// QEMU running the image, and the readers of its outputs.
pub(super) struct Qemu {
    child: Child,
    /// The socket or FIFOs made for it, removed on drop.
    files: Vec<PathBuf>,
    stderr: Arc<Mutex<String>>,
    log_thread: Option<JoinHandle<Result<(), String>>>,
    exit: Option<ExitStatus>,
    /// The rig killed it for the scenario's `kill_firmware` fault.
    killed_by_fault: bool,
}

/// A path prefix of our own in the user's private folder
/// ([`crate::private_files::runtime_dir`]: no other user can plant a link or a
/// FIFO at these names; Unix socket paths are short).
fn temp_prefix() -> Result<PathBuf, RunError> {
    use std::sync::atomic::{AtomicU32, Ordering};
    static N: AtomicU32 = AtomicU32::new(0);
    let dir = crate::private_files::runtime_dir().map_err(|e| RunError::private_folder("the PIL link's folder", &e))?;
    // What a killed PIL run left (its FIFOs or socket).
    crate::private_files::remove_dead_pid_files(&dir, "painleve-pil-");
    Ok(dir.join(format!("painleve-pil-{}-{}", std::process::id(), N.fetch_add(1, Ordering::Relaxed))))
}

/// `prefix` with `ext` appended (`/tmp/x` and `.up`: `/tmp/x.up`).
fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut p = prefix.as_os_str().to_owned();
    p.push(ext);
    PathBuf::from(p)
}

/// `path` written as one value of a QEMU option (`,` doubled).
pub(super) fn qemu_opt_value(path: &Path) -> Result<String, String> {
    let s = path.to_str().ok_or_else(|| format!("{}: not UTF-8", path.display()))?;
    Ok(s.replace(',', ",,"))
}

impl Qemu {
    /// Starts QEMU on `image` with the byte stream over `link`: for the USART,
    /// waits up to `boot` for it to connect to the plant's socket; for the
    /// semihosting FIFOs, makes and opens them first (the handshake then waits
    /// for the image). Its defmt lines go to `log` (and `on_log`).
    pub(super) fn spawn(
        image: &Path,
        qemu: &Path,
        link: QemuLink,
        boot: Duration,
        log: &Arc<Mutex<Vec<LogLine>>>,
        on_log: Option<LogSink>,
    ) -> Result<(Self, Pipe), RunError> {
        let table = table_of(image)?;
        let prefix = temp_prefix()?;
        let mut cmd = Command::new(qemu);
        cmd.args(["-machine", "netduinoplus2", "-cpu", "cortex-m4", "-nographic", "-monitor", "none"])
            .args(["-icount", &format!("shift={ICOUNT_SHIFT}")]);
        let (files, listener, fifo) = match link {
            QemuLink::Usart => {
                let socket = with_ext(&prefix, ".sock");
                let _ = std::fs::remove_file(&socket);
                let listener =
                    UnixListener::bind(&socket).map_err(|e| RunError::Transport(format!("cannot listen on {}: {e}", socket.display())))?;
                cmd.args(["-semihosting-config", "enable=on,target=native"])
                    .arg("-chardev")
                    .arg(format!("socket,id=plant,path={}", socket.display()))
                    .args(["-serial", "chardev:plant"]);
                (vec![socket], Some(listener), None)
            }
            QemuLink::Semihosting => {
                let files = vec![with_ext(&prefix, ".down"), with_ext(&prefix, ".up")];
                let opened = qemu_opt_value(&prefix).and_then(|arg| {
                    // The image opens `.up` to write first: our read end is open by then.
                    let down = open_fifo(&files[0], true)?;
                    let up = open_fifo(&files[1], false)?;
                    Ok((arg, down, up))
                });
                let (arg, down, up) = opened.map_err(|e| {
                    files.iter().for_each(|f| drop(std::fs::remove_file(f)));
                    RunError::Transport(e)
                })?;
                // `pil-fifo PREFIX` is the image's semihosting command line (args joined by a space).
                cmd.args(["-semihosting-config", &format!("enable=on,target=native,arg=pil-fifo,arg={arg}")]).args(["-serial", "null"]);
                (files, None, Some(Pipe::Fifo { down, up }))
            }
        };
        let child = cmd.arg("-kernel").arg(image).stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn();
        let mut child = match child {
            Ok(c) => c,
            Err(e) => {
                files.iter().for_each(|f| drop(std::fs::remove_file(f)));
                let hint = if e.kind() == std::io::ErrorKind::NotFound { " (install it: apt-get install -y qemu-system-arm)" } else { "" };
                return Err(RunError::Transport(format!("cannot start {}: {e}{hint}", qemu.display())));
            }
        };
        // Readers of QEMU's two outputs: the defmt log (binary) and its own messages.
        let log_thread = child.stdout.take().map(|stdout| {
            let log = Arc::clone(log);
            std::thread::spawn(move || decode_defmt(&table, stdout, &log, on_log.as_deref()))
        });
        let stderr = Arc::new(Mutex::new(String::new()));
        if let Some(err) = child.stderr.take() {
            let sink = Arc::clone(&stderr);
            std::thread::spawn(move || {
                for line in BufReader::new(err).lines().map_while(Result::ok) {
                    if let Ok(mut s) = sink.lock() {
                        s.push_str(&line);
                        s.push('\n');
                    }
                }
            });
        }
        let mut q = Self { child, files, stderr, log_thread, exit: None, killed_by_fault: false };
        let (Some(listener), None) = (listener, &fifo) else {
            return Ok((q, fifo.expect("the FIFO link made its pipe")));
        };
        let accepted = accept_before(&listener, &mut q.child, Instant::now() + boot);
        q.remove_files();
        match accepted {
            Ok(stream) => Ok((q, Pipe::Socket(stream))),
            Err(what) => {
                q.kill();
                Err(RunError::Transport(format!("QEMU did not connect to the plant's socket: {what}{}", q.stderr_tail())))
            }
        }
    }

    /// Removes the socket or FIFOs from the file system (once QEMU has them open).
    pub(super) fn remove_files(&mut self) {
        self.files.drain(..).for_each(|f| drop(std::fs::remove_file(f)));
    }

    /// QEMU's process id.
    pub(super) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Kills QEMU for the scenario's `kill_firmware` fault (not reaped: the link
    /// sees its silence first, then [`Self::exited_within`] its exit).
    pub(super) fn kill_for_fault(&mut self) {
        self.killed_by_fault = true;
        let _ = self.child.kill();
    }

    /// QEMU's exit status, once it has been seen to exit.
    pub(super) fn exit_status(&self) -> Option<ExitStatus> {
        self.exit
    }

    /// Kills QEMU (if it still runs) and reaps it.
    fn kill(&mut self) {
        if self.exited().is_none() {
            let _ = self.child.kill();
            self.exit = self.child.wait().ok();
        }
    }

    /// QEMU's exit status, if it has exited.
    fn exited(&mut self) -> Option<ExitStatus> {
        if self.exit.is_none()
            && let Ok(Some(status)) = self.child.try_wait()
        {
            self.exit = Some(status);
        }
        self.exit
    }

    /// QEMU's exit status, waiting up to `within` for it: a QEMU that was killed
    /// closes its pipes before the kernel reports its exit, so the link sees the
    /// silence first.
    pub(super) fn exited_within(&mut self, within: Duration) -> Option<ExitStatus> {
        let until = Instant::now() + within;
        while self.exited().is_none() && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(5));
        }
        self.exited()
    }

    /// Why QEMU is gone, from its exit status: its own exit, the scenario's
    /// `kill_firmware` fault, or a signal from outside the rig.
    pub(super) fn describe_exit(&self, status: ExitStatus) -> String {
        use std::os::unix::process::ExitStatusExt;
        match status.signal() {
            Some(_) if self.killed_by_fault => format!(": QEMU was killed by the scenario's kill_firmware fault ({status})"),
            Some(_) => format!(": QEMU was killed ({status}) by something outside this run (a user, a job scheduler, the OOM killer)"),
            None => format!(": QEMU exited ({status})"),
        }
    }

    /// `; QEMU said: <its last lines>` or nothing.
    pub(super) fn stderr_tail(&self) -> String {
        let text = self.stderr.lock().map(|s| s.trim().to_string()).unwrap_or_default();
        if text.is_empty() {
            return String::new();
        }
        let lines: Vec<&str> = text.lines().collect();
        format!("; QEMU said: {}", lines[lines.len().saturating_sub(3)..].join(" | "))
    }

    /// Waits up to `within` for QEMU to exit by itself, then kills it; joins the
    /// log reader (a corrupt stream becomes an error line of `log`).
    pub(super) fn wind_down(&mut self, within: Duration, log: &Mutex<Vec<LogLine>>) {
        let start = Instant::now();
        while self.exited().is_none() && start.elapsed() < within {
            std::thread::sleep(Duration::from_millis(2));
        }
        self.kill();
        if let Some(t) = self.log_thread.take()
            && let Ok(Err(e)) = t.join()
            && let Ok(mut l) = log.lock()
        {
            l.push(LogLine { timestamp: None, level: "error".into(), message: format!("sil-host: {e}") });
        }
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        self.kill();
        self.remove_files();
    }
}

/// Accepts QEMU's connection, or says why not by `deadline`.
fn accept_before(listener: &UnixListener, child: &mut Child, deadline: Instant) -> Result<UnixStream, String> {
    listener.set_nonblocking(true).map_err(|e| e.to_string())?;
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream.set_nonblocking(false).map_err(|e| e.to_string())?;
                return Ok(stream);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(e.to_string()),
        }
        if let Ok(Some(status)) = child.try_wait() {
            return Err(format!("QEMU exited ({status})"));
        }
        if Instant::now() >= deadline {
            return Err("timed out".into());
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}
