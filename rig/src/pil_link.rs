//! The processor-in-the-loop bridge: the MCU image (`boards/stm32f405/src/bin/pil.rs`)
//! runs in QEMU's `netduinoplus2` (an STM32F405) or on a board, and this link
//! joins its USART1 to the rig's lockstep loop, so the plant, the scenarios and
//! the outputs are those of the SIL rig.
//!
//! Two transports carry the same byte stream ([`PilTarget`]):
//! - **QEMU** (PIL): `qemu-system-arm -machine netduinoplus2 -icount shift=0 ...
//!   -kernel IMAGE`, the bytes through one of two paths ([`QemuLink`]):
//!   - **semihosting FIFOs** (the default): the link makes two named pipes
//!     `PREFIX.down` and `PREFIX.up` and passes `pil-fifo PREFIX` as QEMU's
//!     semihosting command line; the image reads and writes them with
//!     semihosting calls, a whole frame per call (a median 7 600 periods per
//!     wall second on a shared 2-core machine, against 290 through the USART;
//!     docs/measurements.md);
//!   - **the emulated USART1**: the link listens on a Unix socket and QEMU's
//!     `-chardev socket,path=SOCK -serial chardev:plant` joins it to USART1.
//!     QEMU's USART model takes a byte only once the image has read the last
//!     one, one emulator main-loop turn and two thread hand-overs per byte: 300
//!     to 450 periods per wall second. It exercises the board's USART driver.
//!
//!   Either way the image's defmt log arrives on QEMU's standard output
//!   (semihosting) and is decoded here with `defmt-decoder` from the image's own ELF.
//! - **A serial port** (hardware in the loop): the board's USART1 at 2 Mbaud
//!   through a USB-serial adapter (docs/hardware.md "Reference board"), raw 8N1,
//!   no flow control. Nothing is spawned and no log is captured: a board logs
//!   defmt over RTT to a debug probe (probe-rs).
//!
//! Over either, one protocol implementation speaks [`firmware::pil`] (postcard,
//! CRC-32, COBS): a lone `0x00` (it ends any partial frame left on the line),
//! [`Downlink::Hello`] until the image says [`Uplink::Hello`] (a board may have
//! booted long before the port was opened), the protocol version check, the
//! configuration, then each period's frame and its answer.
//!
//! Lockstep: the plant owns time and the image's step starts at the frame's
//! sample time, so the command's `t_sent_us` (the image's own clock) decides when
//! it takes effect, as in-process. Wall time only guards against a hung or dead
//! image: no answer within the answer timeout, QEMU exiting, its socket closing
//! or the serial port going away end the run with [`RunError::FirmwareLost`],
//! never a hang.

use std::{
    io::{BufRead, BufReader, Read, Write},
    ops::RangeInclusive,
    os::unix::net::{UnixListener, UnixStream},
    path::{Path, PathBuf},
    process::{Child, Command, ExitStatus, Stdio},
    sync::{Arc, Mutex},
    thread::JoinHandle,
    time::{Duration, Instant},
};

use firmware::pil::{self, Downlink, MAX_FRAME, StepClock, Uplink, WireError};
use serde::Serialize;
use shared::wire::{GroundTruth, SensorFrame};

use super::{
    envelope::Envelope,
    faults::{FaultPlan, LinkKind},
    record::RunError,
    rig::{Exchange, FirmwareLink},
    scenario::Scenario,
    setup::firmware_config,
    stats::CountDistribution,
    summary::{CountUnit, PilFigures},
};

/// QEMU's instruction-count shift: one instruction per `2^ICOUNT_SHIFT` ns of
/// virtual time (`-icount shift=0`: 1 ns each).
pub const ICOUNT_SHIFT: u32 = 0;

/// Core clock of the reference board, Hz (docs/hardware.md: 168 MHz): the clock the
/// step budget is counted in.
pub const CORE_HZ: f64 = 168e6;

/// Budget of a control step at the default 1 kHz rate: 5 % of 1 ms at 168 MHz
/// (docs/hardware.md "Budgets"), 8400 cycles, or instructions under QEMU (each at
/// least one cycle). Other rates: [`step_budget`].
pub const STEP_BUDGET_INSTRUCTIONS: f64 = 8_400.0;

/// Budget of a control step at `rate_hz` (Hz): 5 % of the control period at
/// 168 MHz, in cycles on silicon and in instructions under QEMU (a lower bound
/// of cycles); [`STEP_BUDGET_INSTRUCTIONS`] at 1 kHz, 840 at 10 kHz. Not finite
/// for a rate that is not positive.
pub fn step_budget(rate_hz: f64) -> f64 {
    // 168e6 / 1000 / 20 is exactly 8400 (0.05 * ... would round).
    CORE_HZ / rate_hz / 20.0
}

/// Baud rate of the reference board's PIL link (USART1 at 2 Mbaud).
pub const DEFAULT_BAUD: u32 = 2_000_000;

/// Baud rates a serial link may be opened at: from the slowest common rate to
/// what fast USB-serial adapters reach.
pub const BAUD_RANGE: RangeInclusive<u32> = 9_600..=12_000_000;

/// How often the handshake asks again for the image's Hello (a board may miss
/// the first ask while a USB-serial adapter settles; QEMU's pseudo-terminal
/// notices its reader up to a second late).
const HELLO_EVERY: Duration = Duration::from_millis(200);

/// How the bytes reach an image under QEMU. The frames, their checks and the
/// image's instruction counts are the same over both (`tests/tests/pil.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum QemuLink {
    /// Two host FIFOs the image reads and writes through semihosting, a whole
    /// frame per call: the fast path (real time at 1 kHz and beyond).
    #[default]
    Semihosting,
    /// The emulated USART1 on a Unix socket (`-chardev socket`): one byte per
    /// emulator main-loop turn, about 0.4x real time at 1 kHz; it runs the
    /// board's USART driver.
    Usart,
}

/// Where the image runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PilTarget {
    /// Spawn QEMU's `netduinoplus2` on an image.
    Qemu {
        /// The PIL image (ELF for thumbv7em-none-eabihf).
        image: PathBuf,
        /// The QEMU executable (`qemu-system-arm`).
        qemu: PathBuf,
        /// How the bytes reach the image.
        link: QemuLink,
    },
    /// Whatever answers at the other end of a serial device: a board flashed with
    /// the PIL image (hardware in the loop), or QEMU's `-serial pty`.
    Serial {
        /// The device (`/dev/ttyUSB0`, `/dev/ttyACM0`, a pseudo-terminal).
        path: PathBuf,
        /// Line rate, baud (8N1, no flow control); see [`BAUD_RANGE`].
        baud: u32,
    },
}

impl PilTarget {
    /// How the bytes travel: `qemu-semihosting`, `qemu-socket` (the emulated
    /// USART) or `serial` (`summary.json`'s `pil.transport`).
    pub fn transport(&self) -> &'static str {
        match self {
            Self::Qemu { link: QemuLink::Semihosting, .. } => "qemu-semihosting",
            Self::Qemu { link: QemuLink::Usart, .. } => "qemu-socket",
            Self::Serial { .. } => "serial",
        }
    }
}

/// Where the image runs and how long to wait for it.
#[derive(Debug, Clone)]
pub struct PilOptions {
    /// QEMU on an image, or a serial port.
    pub target: PilTarget,
    /// Wall time the image gets to connect, boot (or answer Hello) and accept
    /// the configuration, s; positive.
    pub boot_timeout_s: f64,
    /// Wall time the image gets to answer one frame before it counts as hung, s; positive.
    pub answer_timeout_s: f64,
    /// Keep every period's tick counts ([`PilCounts::step_ticks`], 8 bytes a
    /// period: short runs that compare them period by period); off, the counts
    /// are summarised in fixed memory only.
    pub keep_ticks: bool,
}

impl PilOptions {
    /// QEMU on `image` over the semihosting FIFOs, with `qemu-system-arm` from
    /// `PATH` and 20 s / 5 s timeouts.
    pub fn new(image: impl Into<PathBuf>) -> Self {
        Self::for_target(PilTarget::Qemu { image: image.into(), qemu: "qemu-system-arm".into(), link: QemuLink::Semihosting })
    }

    /// The serial device `path` at `baud`, with 20 s / 5 s timeouts.
    pub fn serial(path: impl Into<PathBuf>, baud: u32) -> Self {
        Self::for_target(PilTarget::Serial { path: path.into(), baud })
    }

    /// `target` with 20 s / 5 s timeouts.
    pub fn for_target(target: PilTarget) -> Self {
        Self { target, boot_timeout_s: 20.0, answer_timeout_s: 5.0, keep_ticks: false }
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

/// What the image measured, one sample per answered frame, in its tick unit:
/// exact distributions and decimated series against time in fixed memory, and
/// every sample only when asked ([`PilOptions::keep_ticks`]).
#[derive(Debug, Clone)]
pub struct PilCounts {
    /// Answered frames.
    pub answers: u64,
    /// `step_ticks` of each command ([`firmware::Firmware::step`]'s own time): their distribution.
    pub step: CountDistribution,
    /// The frame's time (decoding: COBS, CRC, postcard; plus the step): its distribution.
    pub frame: CountDistribution,
    /// `step_ticks` against the frame's sample time `t_k` (s), decimated ([`Envelope`]) for figures.
    pub step_series: Envelope,
    /// Frame ticks against `t_k` (s), decimated for figures.
    pub frame_series: Envelope,
    /// Every `step_ticks`, in period order; empty unless [`PilOptions::keep_ticks`].
    pub step_ticks: Vec<u32>,
    /// Every frame's ticks, in period order; empty unless [`PilOptions::keep_ticks`].
    pub frame_ticks: Vec<u32>,
    keep_ticks: bool,
    /// The image's tick rate (its `Hello`), Hz.
    pub ticks_per_second: u32,
    /// What its ticks count (its `Hello`): emulated SysTick or DWT cycles
    /// (`EmulatedSysTick` until the Hello arrives).
    pub clock: StepClock,
}

impl Default for PilCounts {
    fn default() -> Self {
        Self {
            answers: 0,
            step: CountDistribution::default(),
            frame: CountDistribution::default(),
            step_series: Envelope::new(),
            frame_series: Envelope::new(),
            step_ticks: Vec::new(),
            frame_ticks: Vec::new(),
            keep_ticks: false,
            ticks_per_second: 0,
            clock: StepClock::EmulatedSysTick,
        }
    }
}

impl PilCounts {
    /// Adds one answer's counts, of the frame sampled at `t` (s).
    pub fn record(&mut self, t: f64, step_ticks: u32, frame_ticks: u32) {
        self.answers += 1;
        self.step.record(step_ticks);
        self.frame.record(frame_ticks);
        self.step_series.push(t, f64::from(step_ticks));
        self.frame_series.push(t, f64::from(frame_ticks));
        if self.keep_ticks {
            self.step_ticks.push(step_ticks);
            self.frame_ticks.push(frame_ticks);
        }
    }

    /// Instructions retired per tick under `-icount shift=ICOUNT_SHIFT`: QEMU's
    /// SysTick runs at the core clock of *virtual* time, and virtual time is
    /// `2^shift` ns per instruction. Meaningful for [`StepClock::EmulatedSysTick`] only.
    pub fn instructions_per_tick(&self) -> f64 {
        1e9 / (self.ticks_per_second.max(1) as f64 * (1u64 << ICOUNT_SHIFT) as f64)
    }

    /// The unit of the counts: instructions (emulated) or cycles (silicon).
    pub fn unit(&self) -> CountUnit {
        CountUnit::of(self.clock)
    }

    /// Counts of [`Self::unit`] per tick: [`Self::instructions_per_tick`] under
    /// QEMU, 1 for DWT cycles (one tick is one cycle).
    pub fn counts_per_tick(&self) -> f64 {
        match self.clock {
            StepClock::EmulatedSysTick => self.instructions_per_tick(),
            StepClock::DwtCycles | StepClock::Simulated => 1.0,
        }
    }
}

/// Refuses the faults `target` cannot inject ([`LinkKind::check`]).
///
/// # Errors
/// [`RunError::Unsupported`] naming the fault and why.
pub fn check_faults(s: &Scenario, target: &PilTarget) -> Result<(), RunError> {
    let kind = match target {
        PilTarget::Qemu { .. } => LinkKind::PilQemu,
        PilTarget::Serial { .. } => LinkKind::PilSerial,
    };
    kind.check(&s.faults)
}

/// The byte stream to the image, with a read timeout.
enum Pipe {
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
enum Got {
    /// Bytes (at least one).
    Bytes(usize),
    /// Nothing within the wait.
    Nothing,
}

impl Pipe {
    /// Opens `path` raw 8N1 at `baud`, no flow control, and drops what was
    /// queued before (bytes of a previous run).
    fn open_serial(path: &Path, baud: u32) -> Result<Self, RunError> {
        let cannot = |why: String| RunError::Transport(format!("cannot open the serial port {} at {baud} baud: {why}", path.display()));
        if !BAUD_RANGE.contains(&baud) {
            return Err(cannot(format!("outside {}..={} baud", BAUD_RANGE.start(), BAUD_RANGE.end())));
        }
        let port = open_port(path, baud, Duration::from_millis(100)).map_err(cannot)?;
        Ok(Self::Serial { port, path: path.to_path_buf(), baud })
    }

    /// What the pipe is, for error messages.
    fn name(&self) -> String {
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
    fn read_within(&mut self, buf: &mut [u8], wait: Duration) -> Result<Got, String> {
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
    fn write_all(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), String> {
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

/// QEMU running the image, and the readers of its outputs.
struct Qemu {
    child: Child,
    /// The socket or FIFOs made for it, removed on drop.
    files: Vec<PathBuf>,
    stderr: Arc<Mutex<String>>,
    log_thread: Option<JoinHandle<Result<(), String>>>,
    exit: Option<ExitStatus>,
    /// The rig killed it for the scenario's `kill_firmware` fault.
    killed_by_fault: bool,
}

/// A path prefix of our own in the temporary folder (Unix socket paths are short).
fn temp_prefix() -> PathBuf {
    use std::sync::atomic::{AtomicU32, Ordering};
    static N: AtomicU32 = AtomicU32::new(0);
    std::env::temp_dir().join(format!("painleve-pil-{}-{}", std::process::id(), N.fetch_add(1, Ordering::Relaxed)))
}

/// `prefix` with `ext` appended (`/tmp/x` and `.up`: `/tmp/x.up`).
fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut p = prefix.as_os_str().to_owned();
    p.push(ext);
    PathBuf::from(p)
}

/// Makes the FIFO `path` (mode 0600) and opens it non-blocking, read-only or
/// read-write (a FIFO opened read-write on Linux opens without waiting for the
/// other end and never blocks a writer's open).
fn open_fifo(path: &Path, read_write: bool) -> Result<std::fs::File, String> {
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

/// `path` written as one value of a QEMU option (`,` doubled).
fn qemu_opt_value(path: &Path) -> Result<String, String> {
    let s = path.to_str().ok_or_else(|| format!("{}: not UTF-8", path.display()))?;
    Ok(s.replace(',', ",,"))
}

impl Qemu {
    /// Starts QEMU on `image` with the byte stream over `link`: for the USART,
    /// waits up to `boot` for it to connect to the plant's socket; for the
    /// semihosting FIFOs, makes and opens them first (the handshake then waits
    /// for the image). Its defmt lines go to `log` (and `on_log`).
    fn spawn(
        image: &Path,
        qemu: &Path,
        link: QemuLink,
        boot: Duration,
        log: &Arc<Mutex<Vec<LogLine>>>,
        on_log: Option<LogSink>,
    ) -> Result<(Self, Pipe), RunError> {
        let elf = std::fs::read(image).map_err(|e| RunError::Transport(format!("cannot read the PIL image {}: {e}", image.display())))?;
        let table = defmt_decoder::Table::parse(&elf)
            .map_err(|e| RunError::Transport(format!("{}: not a defmt image: {e}", image.display())))?
            .ok_or_else(|| RunError::Transport(format!("{}: no defmt table (is it the `pil` image?)", image.display())))?;
        let prefix = temp_prefix();
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
    fn remove_files(&mut self) {
        self.files.drain(..).for_each(|f| drop(std::fs::remove_file(f)));
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
    fn exited_within(&mut self, within: Duration) -> Option<ExitStatus> {
        let until = Instant::now() + within;
        while self.exited().is_none() && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(5));
        }
        self.exited()
    }

    /// Why QEMU is gone, from its exit status: its own exit, the scenario's
    /// `kill_firmware` fault, or a signal from outside the rig.
    fn describe_exit(&self, status: ExitStatus) -> String {
        use std::os::unix::process::ExitStatusExt;
        match status.signal() {
            Some(_) if self.killed_by_fault => format!(": QEMU was killed by the scenario's kill_firmware fault ({status})"),
            Some(_) => format!(": QEMU was killed ({status}) by something outside this run (a user, a job scheduler, the OOM killer)"),
            None => format!(": QEMU exited ({status})"),
        }
    }

    /// `; QEMU said: <its last lines>` or nothing.
    fn stderr_tail(&self) -> String {
        let text = self.stderr.lock().map(|s| s.trim().to_string()).unwrap_or_default();
        if text.is_empty() {
            return String::new();
        }
        let lines: Vec<&str> = text.lines().collect();
        format!("; QEMU said: {}", lines[lines.len().saturating_sub(3)..].join(" | "))
    }

    /// Waits up to `within` for QEMU to exit by itself, then kills it; joins the
    /// log reader (a corrupt stream becomes an error line of `log`).
    fn wind_down(&mut self, within: Duration, log: &Mutex<Vec<LogLine>>) {
        let start = Instant::now();
        while self.exited().is_none() && start.elapsed() < within {
            std::thread::sleep(Duration::from_millis(2));
        }
        self.kill();
        if let Some(t) = self.log_thread.take()
            && let Ok(Err(e)) = t.join()
            && let Ok(mut l) = log.lock()
        {
            l.push(LogLine { level: "error".into(), message: format!("sil-host: {e}") });
        }
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        self.kill();
        self.remove_files();
    }
}

/// What [`PilLink::recv_before`] got.
enum Received {
    /// A message.
    Msg(Uplink),
    /// A frame that does not decode (damaged, or not ours).
    Undecodable(WireError),
    /// Nothing by the deadline.
    Nothing,
}

/// The link to the image, in QEMU or at the end of a serial port.
pub struct PilLink {
    pipe: Pipe,
    /// Present when the link spawned QEMU.
    qemu: Option<Qemu>,
    inbox: Vec<u8>,
    answer_timeout: Duration,
    faults: FaultPlan,
    log: Arc<Mutex<Vec<LogLine>>>,
    /// What the image measured so far.
    pub counts: PilCounts,
}

impl std::fmt::Debug for PilLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("PilLink");
        d.field("pipe", &self.pipe.name());
        if let Some(q) = &self.qemu {
            d.field("qemu_pid", &q.child.id());
        }
        d.finish_non_exhaustive()
    }
}

/// A positive, finite number of seconds as a duration.
fn seconds(what: &str, s: f64) -> Result<Duration, RunError> {
    match Duration::try_from_secs_f64(s) {
        Ok(d) if s > 0.0 => Ok(d),
        _ => Err(RunError::Transport(format!("{what} {s} s: must be a positive number of seconds"))),
    }
}

impl PilLink {
    /// Reaches the image (spawns QEMU on it, or opens the serial port), makes it
    /// say Hello, checks its protocol version and configures it for the scenario;
    /// `on_log` sees every defmt line as it arrives (QEMU only: a board logs over
    /// RTT, not over this link).
    ///
    /// # Errors
    /// [`RunError::Unsupported`] for a fault the target cannot inject
    /// ([`check_faults`]); [`RunError::Transport`] for a timeout that is not a
    /// positive number of seconds, a missing image or one without a defmt table,
    /// QEMU that cannot start or does not connect, a serial port that cannot be
    /// opened, no Hello within `boot_timeout_s`, another protocol version, or a
    /// configuration rejected or not answered.
    pub fn start(s: &Scenario, opts: &PilOptions, on_log: Option<LogSink>) -> Result<Self, RunError> {
        check_faults(s, &opts.target)?;
        let boot = seconds("boot timeout", opts.boot_timeout_s)?;
        let answer_timeout = seconds("answer timeout", opts.answer_timeout_s)?;
        let log = Arc::new(Mutex::new(Vec::new()));
        let (pipe, qemu) = match &opts.target {
            PilTarget::Qemu { image, qemu, link } => {
                let (q, pipe) = Qemu::spawn(image, qemu, *link, boot, &log, on_log)?;
                (pipe, Some(q))
            }
            PilTarget::Serial { path, baud } => (Pipe::open_serial(path, *baud)?, None),
        };
        let mut link = Self {
            pipe,
            qemu,
            inbox: Vec::new(),
            answer_timeout,
            faults: FaultPlan::new(&s.faults, s.timing.period()),
            log,
            counts: PilCounts { keep_ticks: opts.keep_ticks, ..PilCounts::default() },
        };
        link.handshake(s, boot)?;
        Ok(link)
    }

    /// Hello, the version check and the configuration (the same over either pipe).
    fn handshake(&mut self, s: &Scenario, boot: Duration) -> Result<(), RunError> {
        let deadline = Instant::now() + boot;
        // A lone terminator ends whatever partial frame a previous bridge left
        // in the image's buffer (the image ignores an empty frame).
        self.write(&[0])?;
        let mut ask_at = Instant::now();
        loop {
            let now = Instant::now();
            if now >= deadline {
                let what = match self.pipe {
                    Pipe::Fifo { .. } => {
                        "the image did not say Hello on the semihosting FIFOs (an image older than this sil-host? rebuild it: cargo build-pil)"
                    }
                    _ => "the image did not say Hello",
                };
                return Err(self.lost_or(what, boot));
            }
            if now >= ask_at {
                self.send(&Downlink::Hello)?;
                ask_at = now + HELLO_EVERY;
            }
            match self.recv_before(ask_at.min(deadline))? {
                Received::Msg(Uplink::Hello { protocol, ticks_per_second, clock }) => {
                    if protocol != pil::PROTOCOL_VERSION {
                        return Err(RunError::Transport(format!(
                            "the image speaks PIL protocol {protocol}, this sil-host {}: rebuild {}",
                            pil::PROTOCOL_VERSION,
                            if self.qemu.is_some() { "the image" } else { "and flash the image" }
                        )));
                    }
                    self.counts.ticks_per_second = ticks_per_second;
                    self.counts.clock = clock;
                    // The image has both FIFOs open before its Hello: their names can go.
                    if let Some(q) = &mut self.qemu {
                        q.remove_files();
                    }
                    break;
                }
                // Answers, Garbled or broken frames of a previous run still on the line.
                Received::Msg(_) | Received::Undecodable(_) | Received::Nothing => {}
            }
        }
        let configure = Downlink::Configure(firmware_config(s));
        self.send(&configure)?;
        let deadline = Instant::now() + boot;
        // A `Garbled` here is a frame damaged before the image's USART was up (QEMU
        // delivers the socket's first bytes as soon as it connects) or our
        // configuration damaged on the line: the configuration is sent again (it
        // is idempotent: a fresh firmware), a bounded number of times.
        let mut resends = 0;
        loop {
            match self.recv_before(deadline)? {
                Received::Msg(Uplink::Garbled) | Received::Undecodable(_) if resends < 3 => {
                    resends += 1;
                    self.send(&configure)?;
                }
                Received::Msg(Uplink::Configured) => return Ok(()),
                Received::Msg(Uplink::Rejected) => {
                    return Err(RunError::Transport(format!("the image rejected the configuration{}", self.log_tail())));
                }
                // The image answers every Hello we asked for before it reads the configuration.
                Received::Msg(Uplink::Hello { .. }) => {}
                Received::Msg(other) => return Err(RunError::Transport(format!("unexpected answer to the configuration: {other:?}"))),
                Received::Undecodable(e) => {
                    return Err(RunError::Transport(format!("the answer to the configuration does not decode: {e}")));
                }
                Received::Nothing => return Err(self.lost_or("no answer to the configuration", boot)),
            }
        }
    }

    /// The defmt lines decoded so far (always empty over a serial port).
    pub fn log(&self) -> Vec<LogLine> {
        self.log.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// Whether this link captures the image's defmt log (QEMU's semihosting
    /// output); a board over a serial port logs over RTT instead.
    pub fn captures_log(&self) -> bool {
        self.qemu.is_some()
    }

    /// QEMU's exit status, once it has exited; always `None` over a serial port.
    pub fn exit_status(&self) -> Option<ExitStatus> {
        self.qemu.as_ref().and_then(|q| q.exit)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), RunError> {
        let timeout = self.answer_timeout;
        self.pipe.write_all(bytes, timeout).map_err(RunError::Transport)
    }

    fn send(&mut self, msg: &Downlink) -> Result<(), RunError> {
        let mut buf = [0u8; MAX_FRAME];
        let frame = pil::encode(msg, &mut buf).map_err(|e| RunError::Transport(format!("cannot frame {msg:?}: {e}")))?;
        self.write(frame)
    }

    /// The next frame from the image, or [`Received::Nothing`] at `deadline`.
    ///
    /// # Errors
    /// [`RunError::Transport`] when the pipe closed or failed, or the other end
    /// sends bytes without frame terminators.
    fn recv_before(&mut self, deadline: Instant) -> Result<Received, RunError> {
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
                return Err(RunError::Transport(format!(
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
                Err(what) => return Err(RunError::Transport(format!("{what}{}", self.why_pipe_failed()))),
            }
        }
    }

    /// `what` within `waited`, plus whatever explains it.
    fn lost_or(&mut self, what: &str, waited: Duration) -> RunError {
        RunError::Transport(format!("{what} within {} s{}", waited.as_secs_f64(), self.why_gone()))
    }

    /// What explains a silent image: QEMU's exit, its messages and the image's
    /// last log lines; for a serial port, what to check on the board.
    fn why_gone(&mut self) -> String {
        let tail = self.log_tail();
        match (&mut self.qemu, &self.pipe) {
            (Some(q), _) => {
                let state = match q.exited_within(Duration::from_millis(500)) {
                    Some(status) => q.describe_exit(status),
                    None => ": QEMU still runs (the image hangs?)".into(),
                };
                format!("{state}{}{tail}", q.stderr_tail())
            }
            (None, Pipe::Serial { path, baud, .. }) => format!(
                ": nothing from {} (is the board powered, flashed with the PIL image of protocol {} and wired to it at {baud} baud?)",
                path.display(),
                pil::PROTOCOL_VERSION
            ),
            (None, Pipe::Socket(_) | Pipe::Fifo { .. }) => tail,
        }
    }

    /// What explains a pipe that closed or failed: QEMU's state and messages; a
    /// serial port's error says it all.
    fn why_pipe_failed(&mut self) -> String {
        if self.qemu.is_some() { self.why_gone() } else { String::new() }
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
        match self.pipe {
            Pipe::Socket(_) | Pipe::Fifo { .. } => "pil-qemu",
            Pipe::Serial { .. } => "pil-serial",
        }
    }

    fn before_period(&mut self, k: u64) {
        // Only QEMU can be killed: `start` refuses the fault over a serial port.
        if self.faults.kills_firmware_at(k)
            && let Some(q) = &mut self.qemu
        {
            q.killed_by_fault = true;
            let _ = q.child.kill();
        }
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let k = frame.seq as usize;
        let start_delay_us = u32::try_from(self.faults.command_delay(u64::from(frame.seq)).as_us()).unwrap_or(u32::MAX);
        let lost = |what: String| RunError::FirmwareLost { k, t: truth.t, what };
        if let Err(e) = self.send(&Downlink::Frame { frame: *frame, start_delay_us }) {
            return Err(lost(format!("{e}{}", self.why_pipe_failed())));
        }
        let deadline = Instant::now() + self.answer_timeout;
        loop {
            match self.recv_before(deadline).map_err(|e| lost(e.to_string()))? {
                Received::Msg(Uplink::Answer { command, telemetry, frame_ticks }) if command.seq == frame.seq => {
                    self.counts.record(truth.t, command.step_ticks, frame_ticks);
                    return Ok(Exchange::Answered { command, telemetry, at_stamp: false });
                }
                Received::Msg(Uplink::Answer { .. }) => {} // an answer to an older frame: cannot happen in lockstep
                // Before the first answer: the handshake's leftovers (a configuration
                // sent again after a `Garbled` is answered twice; every one of them
                // reached the image before frame 0, so the firmware is the configured one).
                Received::Msg(Uplink::Configured | Uplink::Hello { .. }) if self.counts.answers == 0 => {}
                Received::Msg(other) => return Err(lost(format!("the image answered frame {k} with {other:?}{}", self.log_tail()))),
                Received::Undecodable(e) => return Err(lost(format!("the image's answer to frame {k} does not decode: {e}"))),
                Received::Nothing => {
                    let waited = self.answer_timeout.as_secs_f64();
                    return Err(lost(format!("no answer within {waited} s of wall time{}", self.why_gone())));
                }
            }
        }
    }

    /// Sends End. QEMU then exits by itself (it gets 3 s, then is killed) and
    /// the log reader is joined; a board logs its figures and waits for the next
    /// configuration, so nothing is awaited.
    fn finish(&mut self, _last_seq: u32) {
        let _ = self.send(&Downlink::End);
        if let Some(q) = &mut self.qemu {
            q.wind_down(Duration::from_secs(3), &self.log);
        }
    }
}

/// What [`measure_rate`] measured: how fast a PIL run goes in wall time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PilRate {
    /// `summary.json`'s `pil.transport` of the run: `qemu-semihosting`, `qemu-socket` or `serial`.
    pub transport: &'static str,
    /// Periods run (all of the scenario's).
    pub periods: usize,
    /// Wall time from spawning QEMU (or opening the port) to the image configured, s.
    pub start_s: f64,
    /// Wall time of the periods, from the first frame sent to the last record, s.
    pub loop_s: f64,
    /// `periods / loop_s`: periods per wall second (1000 is real time at 1 kHz).
    pub periods_per_s: f64,
}

/// Runs the whole scenario `s` in PIL over `opts` (lockstep, nothing written,
/// the image's log dropped) and measures its speed in wall time: the figure
/// `sil-host pil` prints as periods per wall second, without the files. For the
/// default scenario (10 000 periods at 1 kHz) see [`measure_default_rate`].
///
/// # Errors
/// As [`PilLink::start`]; the run's own failure ([`RunError::FirmwareLost`] and
/// the rest) when it stopped before its end.
pub fn measure_rate(s: &Scenario, opts: &PilOptions) -> Result<PilRate, RunError> {
    /// Notes when each record is made.
    struct LastRecord(Option<Instant>);
    impl super::rig::RunObserver for LastRecord {
        fn on_record(&mut self, _record: &super::record::PeriodRecord) {
            self.0 = Some(Instant::now());
        }
    }
    let t0 = Instant::now();
    let mut link = PilLink::start(s, opts, None)?;
    let started = Instant::now();
    let mut last = LastRecord(None);
    let (periods, failure) = super::rig::stream_loop(s, &mut link, &mut last);
    if let Some(e) = failure {
        return Err(e);
    }
    let loop_s = last.0.map_or(0.0, |t| (t - started).as_secs_f64());
    Ok(PilRate {
        transport: opts.target.transport(),
        periods,
        start_s: (started - t0).as_secs_f64(),
        loop_s,
        periods_per_s: if loop_s > 0.0 { periods as f64 / loop_s } else { 0.0 },
    })
}

/// [`measure_rate`] on the default scenario (hybrid from x0d, 1 kHz) cut to
/// `periods` periods (10 000: the whole default run), the image at `image` in
/// `qemu-system-arm` from `PATH` over `link`. `sil-host bench`'s PIL figure:
/// `measure_default_rate(&default_image(), 10_000, QemuLink::Semihosting)`.
///
/// # Errors
/// As [`measure_rate`]; [`RunError::Transport`] for `periods` 0.
pub fn measure_default_rate(image: &Path, periods: u32, link: QemuLink) -> Result<PilRate, RunError> {
    if periods == 0 {
        return Err(RunError::Transport("a PIL rate needs at least one period".into()));
    }
    let mut s = Scenario::default_scenario();
    s.timing.duration_s = f64::from(periods) / s.timing.rate_hz;
    let target = PilTarget::Qemu { image: image.to_path_buf(), qemu: "qemu-system-arm".into(), link };
    measure_rate(&s, &PilOptions::for_target(target))
}

/// The default place of the PIL image: the `mcu` profile's output next to this
/// executable's target folder (`target/thumbv7em-none-eabihf/qemu/pil`), else in
/// the workspace this `sil-host` was built from.
pub fn default_image() -> PathBuf {
    let rel = Path::new("thumbv7em-none-eabihf/qemu/pil");
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
pub const BUILD_HINT: &str = "cargo build-pil (= cargo build -p board-stm32f405 --profile qemu --target thumbv7em-none-eabihf --no-default-features --features qemu --bin pil)";

/// Where a board's log goes, for the summary and the human output: it is not on
/// the PIL link.
pub const BOARD_LOG_NOTE: &str = "not captured over a serial port: a board logs defmt over RTT to a debug probe (read it with `probe-rs attach --chip STM32F405RGTx <image ELF>`)";

impl PilFigures {
    /// The figures of a run's `counts` at `rate_hz` (Hz) over `target`; `log` is
    /// the image's defmt log when the link captured it, `exit` QEMU's exit status.
    pub fn new(target: &PilTarget, counts: &PilCounts, rate_hz: f64, log: Option<&[LogLine]>, exit: Option<String>) -> Self {
        let per_tick = counts.counts_per_tick();
        let step = counts.step.spread(per_tick);
        let budget = step_budget(rate_hz);
        let (image, shift, serial_port, baud) = match target {
            PilTarget::Qemu { image, .. } => (Some(image.display().to_string()), Some(ICOUNT_SHIFT), None, None),
            PilTarget::Serial { path, baud } => (None, None, Some(path.display().to_string()), Some(*baud)),
        };
        Self {
            transport: target.transport(),
            serial_port,
            baud,
            image,
            qemu_icount_shift: shift,
            ticks_per_second: counts.ticks_per_second,
            step_clock: counts.clock,
            count_unit: counts.unit(),
            counts_per_tick: per_tick,
            step_counts: step,
            frame_counts: counts.frame.spread(per_tick),
            step_budget: budget,
            within_budget: step.worst <= budget,
            worst_step_period_share: step.worst / (CORE_HZ / rate_hz),
            qemu_exit: exit,
            defmt_log: match log {
                Some(_) => "defmt.log (decoded from QEMU's semihosting output)".into(),
                None => BOARD_LOG_NOTE.into(),
            },
            defmt_lines: log.map(<[LogLine]>::len),
            defmt_warnings: log.map(|l| l.iter().filter(|l| l.level == "warn" || l.level == "error").count()),
        }
    }
}

#[cfg(test)]
mod tests;
