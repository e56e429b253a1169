//! The processor-in-the-loop bridge: the MCU image (`firmware/src/bin/pil.rs`)
//! runs in QEMU's `netduinoplus2` (an STM32F405) and this link joins its USART1
//! to the rig's lockstep loop, so the plant, the scenarios and the outputs are
//! those of the SIL rig.
//!
//! The link listens on a Unix socket, starts `qemu-system-arm -machine
//! netduinoplus2 -icount shift=0 ... -chardev socket,path=SOCK -serial
//! chardev:plant -kernel IMAGE`, and speaks the framed protocol of
//! [`firmware::pil`] (postcard, CRC-32, COBS) over the socket: it configures the
//! image with the scenario's firmware configuration, then sends each period's
//! frame and waits for the answer. The image's defmt log arrives on QEMU's
//! standard output (semihosting) and is decoded here with `defmt-decoder` from the
//! image's own ELF.
//!
//! Lockstep: the plant owns time and the image's step starts at the frame's
//! sample time, so the command's `t_sent_us` (the image's own clock) decides when
//! it takes effect, as in-process. Wall time only guards against a hung or dead
//! QEMU: no answer within the answer timeout, QEMU exiting or its socket closing
//! end the run with [`RunError::FirmwareLost`], never a hang.

use std::{
    io::{BufRead, BufReader, Read, Write},
    os::unix::net::{UnixListener, UnixStream},
    path::{Path, PathBuf},
    process::{Child, Command, Stdio},
    sync::{Arc, Mutex},
    thread::JoinHandle,
    time::{Duration, Instant},
};

use firmware::pil::{self, Downlink, MAX_FRAME, Uplink};
use serde::Serialize;
use shared::wire::{GroundTruth, SensorFrame};

use super::{
    faults::{FaultKind, FaultPlan},
    record::RunError,
    rig::{Exchange, FirmwareLink},
    scenario::Scenario,
    setup::firmware_config,
};

/// QEMU's instruction-count shift: one instruction per `2^ICOUNT_SHIFT` ns of
/// virtual time (`-icount shift=0`: 1 ns each).
pub const ICOUNT_SHIFT: u32 = 0;

/// Instruction budget of a control step: 5 % of a 1 kHz period at 168 MHz
/// (HARDWARE.md "Budgets"), as instructions (each at least one cycle).
pub const STEP_BUDGET_INSTRUCTIONS: f64 = 8_400.0;

/// Where to find QEMU and the image, and how long to wait for them.
#[derive(Debug, Clone)]
pub struct PilOptions {
    /// The PIL image (ELF for thumbv7em-none-eabihf).
    pub image: PathBuf,
    /// The QEMU executable (`qemu-system-arm`).
    pub qemu: PathBuf,
    /// Wall time QEMU gets to connect, boot and accept the configuration, s.
    pub boot_timeout_s: f64,
    /// Wall time the image gets to answer one frame before it counts as hung, s.
    pub answer_timeout_s: f64,
}

impl PilOptions {
    /// The options for `image`, with `qemu-system-arm` from `PATH` and 20 s / 5 s timeouts.
    pub fn new(image: impl Into<PathBuf>) -> Self {
        Self { image: image.into(), qemu: "qemu-system-arm".into(), boot_timeout_s: 20.0, answer_timeout_s: 5.0 }
    }
}

/// One decoded line of the image's defmt log.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LogLine {
    /// `trace`, `debug`, `info`, `warn`, `error` (or `println`).
    pub level: String,
    /// The formatted message.
    pub message: String,
}

/// Called for every defmt line as it arrives (on the log reader's thread).
pub type LogSink = Box<dyn Fn(&LogLine) + Send>;

/// What the image measured, one sample per answered frame, in its tick unit.
#[derive(Debug, Clone, Default)]
pub struct PilCounts {
    /// `step_ticks` of each command: [`firmware::Firmware::step`]'s own time.
    pub step_ticks: Vec<u32>,
    /// The frame's time: decoding (COBS, CRC, postcard) plus the step.
    pub frame_ticks: Vec<u32>,
    /// The image's tick rate (its `Hello`), Hz.
    pub ticks_per_second: u32,
}

impl PilCounts {
    /// Instructions retired per tick under `-icount shift=ICOUNT_SHIFT`: QEMU's
    /// SysTick runs at the core clock of *virtual* time, and virtual time is
    /// `2^shift` ns per instruction.
    pub fn instructions_per_tick(&self) -> f64 {
        1e9 / (self.ticks_per_second.max(1) as f64 * (1u64 << ICOUNT_SHIFT) as f64)
    }
}

/// Median, 99th percentile and worst of a sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub worst: f64,
}

impl Spread {
    /// The spread of `samples` scaled by `scale`; zeros when empty.
    pub fn of(samples: &[u32], scale: f64) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let mut v = samples.to_vec();
        v.sort_unstable();
        let at = |q: f64| v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)] as f64 * scale;
        Self { median: at(0.5), p99: at(0.99), worst: v[v.len() - 1] as f64 * scale }
    }
}

/// The link to the image in QEMU.
pub struct PilLink {
    child: Child,
    stream: UnixStream,
    socket: PathBuf,
    inbox: Vec<u8>,
    answer_timeout: Duration,
    faults: FaultPlan,
    log: Arc<Mutex<Vec<LogLine>>>,
    log_thread: Option<JoinHandle<Result<(), String>>>,
    qemu_stderr: Arc<Mutex<String>>,
    exit: Option<std::process::ExitStatus>,
    /// What the image measured so far.
    pub counts: PilCounts,
}

impl std::fmt::Debug for PilLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PilLink").field("socket", &self.socket).field("pid", &self.child.id()).finish_non_exhaustive()
    }
}

/// A socket path of our own in the temporary folder (Unix socket paths are short).
fn socket_path() -> PathBuf {
    use std::sync::atomic::{AtomicU32, Ordering};
    static N: AtomicU32 = AtomicU32::new(0);
    std::env::temp_dir().join(format!("painleve-pil-{}-{}.sock", std::process::id(), N.fetch_add(1, Ordering::Relaxed)))
}

impl PilLink {
    /// Starts QEMU on the image, waits for it to boot and configures it for the
    /// scenario; `on_log` sees every defmt line as it arrives.
    ///
    /// # Errors
    /// [`RunError::Unsupported`] for a `stall` fault (it acts on a host process);
    /// [`RunError::Transport`] when the image is missing or has no defmt table,
    /// QEMU cannot start, does not connect or boot within `boot_timeout_s`, speaks
    /// another protocol version, or rejects the configuration.
    pub fn start(s: &Scenario, opts: &PilOptions, on_log: Option<LogSink>) -> Result<Self, RunError> {
        if let Some(f) = s.faults.iter().find(|f| f.kind == FaultKind::Stall) {
            return Err(RunError::Unsupported(format!(
                "fault {:?} stalls a host process: not available in PIL (kill_firmware is)",
                f.kind
            )));
        }
        let elf = std::fs::read(&opts.image)
            .map_err(|e| RunError::Transport(format!("cannot read the PIL image {}: {e}", opts.image.display())))?;
        let table = defmt_decoder::Table::parse(&elf)
            .map_err(|e| RunError::Transport(format!("{}: not a defmt image: {e}", opts.image.display())))?
            .ok_or_else(|| RunError::Transport(format!("{}: no defmt table (is it the `pil` image?)", opts.image.display())))?;
        let socket = socket_path();
        let _ = std::fs::remove_file(&socket);
        let listener =
            UnixListener::bind(&socket).map_err(|e| RunError::Transport(format!("cannot listen on {}: {e}", socket.display())))?;
        let child = Command::new(&opts.qemu)
            .args(["-machine", "netduinoplus2", "-cpu", "cortex-m4", "-nographic", "-monitor", "none"])
            .args(["-icount", &format!("shift={ICOUNT_SHIFT}")])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-chardev")
            .arg(format!("socket,id=plant,path={}", socket.display()))
            .args(["-serial", "chardev:plant", "-kernel"])
            .arg(&opts.image)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = match child {
            Ok(c) => c,
            Err(e) => {
                let _ = std::fs::remove_file(&socket);
                let hint = if e.kind() == std::io::ErrorKind::NotFound { " (install it: apt-get install -y qemu-system-arm)" } else { "" };
                return Err(RunError::Transport(format!("cannot start {}: {e}{hint}", opts.qemu.display())));
            }
        };
        // Readers of QEMU's two outputs: the defmt log (binary) and its own messages.
        let log = Arc::new(Mutex::new(Vec::new()));
        let stdout = child.stdout.take().ok_or_else(|| RunError::Transport("no stdout from QEMU".into()))?;
        let log_thread = {
            let log = Arc::clone(&log);
            Some(std::thread::spawn(move || decode_defmt(&table, stdout, &log, on_log.as_deref())))
        };
        let qemu_stderr = Arc::new(Mutex::new(String::new()));
        if let Some(stderr) = child.stderr.take() {
            let sink = Arc::clone(&qemu_stderr);
            std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                    if let Ok(mut s) = sink.lock() {
                        s.push_str(&line);
                        s.push('\n');
                    }
                }
            });
        }
        let boot = Duration::from_secs_f64(opts.boot_timeout_s);
        let accepted = accept_before(&listener, &mut child, Instant::now() + boot);
        let _ = std::fs::remove_file(&socket);
        let stream = match accepted {
            Ok(stream) => stream,
            Err(what) => {
                let _ = child.kill();
                let _ = child.wait();
                let err = qemu_stderr.lock().map(|s| s.trim().to_string()).unwrap_or_default();
                return Err(RunError::Transport(format!("QEMU did not connect to the plant's socket: {what}{}", tail(&err))));
            }
        };
        let mut link = Self {
            child,
            stream,
            socket,
            inbox: Vec::new(),
            answer_timeout: Duration::from_secs_f64(opts.answer_timeout_s),
            faults: FaultPlan::new(&s.faults, 1.0 / s.timing.rate_hz),
            log,
            log_thread,
            qemu_stderr,
            exit: None,
            counts: PilCounts::default(),
        };
        let boot_deadline = Instant::now() + boot;
        match link.recv_before(boot_deadline)? {
            Some(Uplink::Hello { protocol, ticks_per_second }) if protocol == pil::PROTOCOL_VERSION => {
                link.counts.ticks_per_second = ticks_per_second;
            }
            Some(Uplink::Hello { protocol, .. }) => {
                return Err(RunError::Transport(format!(
                    "the image speaks PIL protocol {protocol}, this sil-host {}: rebuild the image",
                    pil::PROTOCOL_VERSION
                )));
            }
            Some(other) => return Err(RunError::Transport(format!("the image did not start with Hello but {other:?}"))),
            None => return Err(link.lost_or("the image did not say Hello", opts.boot_timeout_s)),
        }
        link.send(&Downlink::Configure(firmware_config(s)))?;
        match link.recv_before(boot_deadline)? {
            Some(Uplink::Configured) => Ok(link),
            Some(Uplink::Rejected) => Err(RunError::Transport(format!("the image rejected the configuration{}", link.log_tail()))),
            Some(other) => Err(RunError::Transport(format!("unexpected answer to the configuration: {other:?}"))),
            None => Err(link.lost_or("no answer to the configuration", opts.boot_timeout_s)),
        }
    }

    /// The defmt lines decoded so far.
    pub fn log(&self) -> Vec<LogLine> {
        self.log.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// QEMU's exit status, once it has exited.
    pub fn exit_status(&self) -> Option<std::process::ExitStatus> {
        self.exit
    }

    fn send(&mut self, msg: &Downlink) -> Result<(), RunError> {
        let mut buf = [0u8; MAX_FRAME];
        let frame = pil::encode(msg, &mut buf).map_err(|e| RunError::Transport(format!("cannot frame {msg:?}: {e}")))?;
        self.stream.write_all(frame).map_err(|e| RunError::Transport(format!("cannot write to QEMU's USART socket: {e}")))
    }

    /// The next message from the image, or `None` at `deadline`.
    ///
    /// # Errors
    /// [`RunError::Transport`] when the socket closed (QEMU exited) or failed, or
    /// a message from the image does not decode.
    fn recv_before(&mut self, deadline: Instant) -> Result<Option<Uplink>, RunError> {
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(end) = self.inbox.iter().position(|&b| b == 0) {
                let mut frame: Vec<u8> = self.inbox.drain(..=end).collect();
                frame.pop();
                if frame.is_empty() {
                    continue;
                }
                return pil::decode::<Uplink>(&mut frame)
                    .map(Some)
                    .map_err(|e| RunError::Transport(format!("a message from the image does not decode: {e}")));
            }
            if self.inbox.len() > 16 * MAX_FRAME {
                return Err(RunError::Transport("the image sends bytes that are not frames".into()));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            let wait = (deadline - now).max(Duration::from_millis(1));
            self.stream.set_read_timeout(Some(wait)).map_err(|e| RunError::Transport(e.to_string()))?;
            match self.stream.read(&mut chunk) {
                Ok(0) => return Err(RunError::Transport(format!("QEMU closed the USART socket{}", self.why_gone()))),
                Ok(n) => self.inbox.extend_from_slice(&chunk[..n]),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(RunError::Transport(format!("reading QEMU's USART socket: {e}"))),
            }
        }
    }

    /// `what` plus whatever explains it: QEMU's exit, its messages, the image's last log lines.
    fn lost_or(&mut self, what: &str, waited_s: f64) -> RunError {
        RunError::Transport(format!("{what} within {waited_s} s{}", self.why_gone()))
    }

    fn why_gone(&mut self) -> String {
        let mut out = String::new();
        if let Ok(Some(status)) = self.child.try_wait() {
            self.exit = Some(status);
            out.push_str(&format!(": QEMU exited ({status})"));
        } else {
            out.push_str(": QEMU still runs (the image hangs?)");
        }
        let err = self.qemu_stderr.lock().map(|s| s.trim().to_string()).unwrap_or_default();
        out.push_str(&tail(&err));
        out.push_str(&self.log_tail());
        out
    }

    fn log_tail(&self) -> String {
        let log = self.log();
        if log.is_empty() {
            return String::new();
        }
        let last: Vec<String> = log.iter().rev().take(3).rev().map(|l| format!("[{}] {}", l.level, l.message)).collect();
        format!("; image log: {}", last.join(" | "))
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

/// `: <last lines of text>` or nothing.
fn tail(text: &str) -> String {
    if text.is_empty() {
        return String::new();
    }
    let lines: Vec<&str> = text.lines().collect();
    format!("; QEMU said: {}", lines[lines.len().saturating_sub(3)..].join(" | "))
}

/// Decodes the defmt stream from QEMU's standard output until it closes.
fn decode_defmt(
    table: &defmt_decoder::Table,
    mut out: impl Read,
    log: &Mutex<Vec<LogLine>>,
    on_log: Option<&(dyn Fn(&LogLine) + Send)>,
) -> Result<(), String> {
    let mut decoder = table.new_stream_decoder();
    let mut chunk = [0u8; 1024];
    loop {
        let n = out.read(&mut chunk).map_err(|e| e.to_string())?;
        if n == 0 {
            return Ok(());
        }
        decoder.received(&chunk[..n]);
        loop {
            match decoder.decode() {
                Ok(frame) => {
                    let line = LogLine {
                        level: frame.level().map_or("println", |l| l.as_str()).to_string(),
                        message: frame.display_message().to_string(),
                    };
                    if let Some(f) = on_log {
                        f(&line);
                    }
                    if let Ok(mut l) = log.lock() {
                        l.push(line);
                    }
                }
                Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                Err(defmt_decoder::DecodeError::Malformed) => {
                    return Err("the defmt stream is corrupt (an image built from other sources?)".into());
                }
            }
        }
    }
}

impl FirmwareLink for PilLink {
    fn transport(&self) -> &'static str {
        "pil-qemu"
    }

    fn before_period(&mut self, _k: usize, t: f64) {
        if self.faults.kills_firmware_at(t) {
            let _ = self.child.kill();
        }
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let k = frame.seq as usize;
        let start_delay_us = (self.faults.command_delay(truth.t) * 1e6).round() as u32;
        let lost = |what: String| RunError::FirmwareLost { k, t: truth.t, what };
        self.send(&Downlink::Frame { frame: *frame, start_delay_us }).map_err(|e| lost(format!("{e}{}", self.why_gone())))?;
        let deadline = Instant::now() + self.answer_timeout;
        loop {
            match self.recv_before(deadline).map_err(|e| lost(e.to_string()))? {
                Some(Uplink::Answer { command, telemetry, frame_ticks }) if command.seq == frame.seq => {
                    self.counts.step_ticks.push(command.step_ticks);
                    self.counts.frame_ticks.push(frame_ticks);
                    return Ok(Exchange::Answered { command, telemetry, at_stamp: false });
                }
                Some(Uplink::Answer { .. }) => {} // an answer to an older frame: cannot happen in lockstep
                Some(other) => return Err(lost(format!("the image answered frame {k} with {other:?}{}", self.log_tail()))),
                None => {
                    let waited = self.answer_timeout.as_secs_f64();
                    return Err(lost(format!("no answer within {waited} s of wall time{}", self.why_gone())));
                }
            }
        }
    }

    fn finish(&mut self, _last_seq: u32) {
        let _ = self.send(&Downlink::End);
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(3) {
            if let Ok(Some(status)) = self.child.try_wait() {
                self.exit = Some(status);
                break;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        if self.exit.is_none() {
            let _ = self.child.kill();
            self.exit = self.child.wait().ok();
        }
        if let Some(t) = self.log_thread.take()
            && let Ok(Err(e)) = t.join()
            && let Ok(mut l) = self.log.lock()
        {
            l.push(LogLine { level: "error".into(), message: format!("sil-host: {e}") });
        }
    }
}

impl Drop for PilLink {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
        let _ = std::fs::remove_file(&self.socket);
    }
}

/// The default place of the PIL image: the `mcu` profile's output next to this
/// executable's target folder (`target/thumbv7em-none-eabihf/mcu/pil`), else in
/// the workspace this `sil-host` was built from.
pub fn default_image() -> PathBuf {
    let rel = Path::new("thumbv7em-none-eabihf/mcu/pil");
    if let Ok(exe) = std::env::current_exe()
        && let Some(target) = exe.parent().and_then(Path::parent)
    {
        let p = target.join(rel);
        if p.exists() {
            return p;
        }
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target").join(rel)
}

/// How to build the image (for error messages).
pub const BUILD_HINT: &str = "cargo build -p firmware --profile mcu --target thumbv7em-none-eabihf --bin pil";
