//! The link to the image ([`PilLink`], a [`FirmwareLink`]): reaching it (QEMU
//! spawned on it, or a serial port opened), the handshake (Hello, the protocol
//! version, the configuration), then each period's frame and its answer, and
//! what explains an image that went silent.

use std::{
    process::ExitStatus,
    sync::{Arc, Mutex},
    time::{Duration, Instant},
};

use firmware::pil::{self, Downlink, Uplink};
use shared::wire::{GroundTruth, SensorFrame};

use super::{
    counts::PilCounts,
    defmt_log::{self, LogLine, LogSink},
    pipe::{FramedPipe, Pipe, Received, RecvError},
    qemu::Qemu,
    target::{PilOptions, PilTarget, check_faults},
};
use crate::{
    faults::FaultPlan,
    law::LawDescription,
    link::{Exchange, FirmwareLink},
    record::RunError,
    setup::RunSetup,
};

/// How often the handshake asks again for the image's Hello (a board may miss
/// the first ask while a USB-serial adapter settles; QEMU's pseudo-terminal
/// notices its reader up to a second late).
const HELLO_EVERY: Duration = Duration::from_millis(200);

/// The link to the image, in QEMU or at the end of a serial port.
pub struct PilLink {
    pipe: FramedPipe,
    /// Present when the link spawned QEMU.
    qemu: Option<Qemu>,
    answer_timeout: Duration,
    faults: FaultPlan,
    log: Arc<Mutex<Vec<LogLine>>>,
    /// What the image measured so far.
    pub counts: PilCounts,
}

impl std::fmt::Debug for PilLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("PilLink");
        d.field("pipe", &self.pipe.pipe.name());
        if let Some(q) = &self.qemu {
            d.field("qemu_pid", &q.pid());
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
    pub fn start(setup: &RunSetup, opts: &PilOptions, on_log: Option<LogSink>) -> Result<Self, RunError> {
        check_faults(setup.scenario(), &opts.target)?;
        let boot = seconds("boot timeout", opts.boot_timeout_s)?;
        let answer_timeout = seconds("answer timeout", opts.answer_timeout_s)?;
        // The law the image runs, from its ELF (`PAINLEVE_LAW_SPEC`; a board's:
        // the one flashed, if given), to bind the scenario's `[law]` table with:
        // checked before QEMU starts, and held to the image's own digest in its
        // Hello before the configuration goes.
        let law = match &opts.target {
            // A missing image is QEMU's start to report (its own message).
            PilTarget::Qemu { image, .. } if image.is_file() => LawDescription::declared_by(image)?,
            PilTarget::Serial { elf: Some(elf), .. } => LawDescription::declared_by(elf)?,
            PilTarget::Qemu { .. } | PilTarget::Serial { elf: None, .. } => LawDescription::paper(),
        };
        setup.firmware_for(&law)?;
        let log = Arc::new(Mutex::new(Vec::new()));
        let (pipe, qemu) = match &opts.target {
            PilTarget::Qemu { image, qemu, link } => {
                let (q, pipe) = Qemu::spawn(image, qemu, *link, boot, &log, on_log)?;
                (pipe, Some(q))
            }
            PilTarget::Serial { path, baud, .. } => (Pipe::open_serial(path, *baud)?, None),
        };
        let mut link = Self {
            pipe: FramedPipe::new(pipe),
            qemu,
            answer_timeout,
            faults: setup.faults().clone(),
            log,
            counts: PilCounts { keep_ticks: opts.keep_ticks, ..PilCounts::default() },
        };
        link.handshake(&setup.firmware_for(&law)?, law.digest(), boot)?;
        Ok(link)
    }

    /// Hello, the version check and the configuration (the same over either pipe).
    fn handshake(&mut self, config: &firmware::Config, law_digest: u32, boot: Duration) -> Result<(), RunError> {
        let deadline = Instant::now() + boot;
        // A lone terminator ends whatever partial frame a previous bridge left
        // in the image's buffer (the image ignores an empty frame).
        self.write(&[0])?;
        let mut ask_at = Instant::now();
        loop {
            let now = Instant::now();
            if now >= deadline {
                let what = match self.pipe.pipe {
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
                Received::Msg(Uplink::Hello { protocol, ticks_per_second, clock, law_digest: runs }) => {
                    if protocol != pil::PROTOCOL_VERSION {
                        return Err(RunError::Transport(format!(
                            "the image speaks PIL protocol {protocol}, this sil-host {}: rebuild {}",
                            pil::PROTOCOL_VERSION,
                            if self.qemu.is_some() { "the image" } else { "and flash the image" }
                        )));
                    }
                    if runs != law_digest {
                        return Err(RunError::Transport(format!(
                            "the image runs another control law than the one {} declares (digest {runs:08x}, not {law_digest:08x}): {}",
                            if self.qemu.is_some() { "its ELF" } else { "the ELF given (--image) or, without one, the paper's laws" },
                            if self.qemu.is_some() { "rebuild the image" } else { "give the ELF that was flashed, or flash this one" }
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
        let configure = Downlink::Configure(*config);
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
        self.qemu.as_ref().and_then(Qemu::exit_status)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), RunError> {
        self.pipe.write(bytes, self.answer_timeout)
    }

    fn send(&mut self, msg: &Downlink) -> Result<(), RunError> {
        self.pipe.send(msg, self.answer_timeout)
    }

    /// The next frame from the image, or [`Received::Nothing`] at `deadline`.
    ///
    /// # Errors
    /// [`RunError::Transport`] when the pipe closed or failed, or the other end
    /// sends bytes without frame terminators.
    fn recv_before(&mut self, deadline: Instant) -> Result<Received, RunError> {
        self.pipe.recv_before(deadline).map_err(|e| match e {
            RecvError::NotFrames(what) => RunError::Transport(what),
            RecvError::Pipe(what) => RunError::Transport(format!("{what}{}", self.why_pipe_failed())),
        })
    }

    /// `what` within `waited`, plus whatever explains it.
    fn lost_or(&mut self, what: &str, waited: Duration) -> RunError {
        RunError::Transport(format!("{what} within {} s{}", waited.as_secs_f64(), self.why_gone()))
    }

    /// What explains a silent image: QEMU's exit, its messages and the image's
    /// last log lines; for a serial port, what to check on the board.
    fn why_gone(&mut self) -> String {
        let tail = self.log_tail();
        match (&mut self.qemu, &self.pipe.pipe) {
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
        defmt_log::tail(&self.log())
    }
}

impl FirmwareLink for PilLink {
    fn transport(&self) -> &'static str {
        match self.pipe.pipe {
            Pipe::Socket(_) | Pipe::Fifo { .. } => "pil-qemu",
            Pipe::Serial { .. } => "pil-serial",
        }
    }

    fn before_period(&mut self, k: u64) {
        // Only QEMU can be killed: `start` refuses the fault over a serial port.
        if self.faults.kills_firmware_at(k)
            && let Some(q) = &mut self.qemu
        {
            q.kill_for_fault();
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
