//! The plant's end of the iceoryx2 transport: it spawns the firmware process (or
//! attaches to one started by hand), exchanges frames and commands in lockstep or
//! paced by the wall clock, measures round trips, jitter and the firmware's step
//! time, and notices a dead or stalled firmware.
//!
//! Lockstep (default, as PX4 SITL): the plant owns time. It publishes frame `k`
//! and waits for the command echoing `k`; the command's `t_sent_us` (simulated
//! time) decides when it takes effect. A late answer is not a deadline miss: the
//! plant waits whatever the host's load, checking every 20 ms that the firmware
//! process lives, and ends the run only when it is dead or made no progress for
//! `rig.stall_limit_s` (saying whether its process is stopped). So a lockstep
//! run's trace never depends on the host. Deadline misses come only from the
//! injected faults (a stall, a dropped or a late command): in a period one of
//! them touches, the plant waits `rig.command_timeout_s`, counts a miss, and
//! gives up after `rig.max_consecutive_timeouts` timeouts in a row.
//!
//! Real time (`--realtime`): frame `k` is published at wall time `t0 + t_k` (or
//! as soon after as the plant gets the core: the difference is the period
//! jitter); a command not back by the next sample instant `t0 + t_{k+1}` (at
//! least half a period after the frame's publication), or sent later than
//! `t_k + Ts` on the firmware's clock (anchored at the frame's arrival, as a
//! timer tick), is a deadline miss; one that is takes effect at `t_k` plus that
//! latency. Both sides judge the same stamp, so they agree. A stalled firmware
//! costs the plant one period per missed period, and is given up after
//! `rig.max_consecutive_timeouts` periods in a row, as in lockstep.
//! Both processes run their loop on one CPU ([`prepare_realtime`]).

use std::{
    io::Write,
    path::Path,
    process::{Child, Command, Stdio},
    time::{Duration, Instant},
};

use shared::{
    Period,
    wire::{FirmwareTelemetry, GroundTruth, SensorFrame, WIRE_VERSION, frame_flags},
};

use super::{
    faults::{FaultPlan, LinkKind},
    handshake::{self, Announced},
    ipc::{IpcError, MonitorCounts, MonitorPolicy, PeerState, PlantPorts, Role, peer_state},
    link::{Exchange, FirmwareLink},
    realtime::{RealtimeSetup, leave_realtime, prepare_realtime},
    record::RunError,
    scenario::Scenario,
    stats::TimingHistogram,
};

/// How long the plant waits for the firmware to connect, s.
pub const CONNECT_TIMEOUT_S: f64 = 20.0;

/// The firmware's process, when the rig spawned it.
#[derive(Debug)]
pub struct Spawned {
    child: Child,
}

/// Wall-clock figures of an iceoryx2 run, one sample per period, in fixed
/// memory (HDR histograms at 3 significant digits: [`TimingHistogram`]).
#[derive(Debug, Clone, Default)]
pub struct LinkTimings {
    /// Round trip: frame published to its command received.
    pub rtt: TimingHistogram,
    /// Real time: frame publication minus its ideal wall time `t0 + t_k`.
    pub jitter: TimingHistogram,
    /// The firmware's own step time (its `step_ticks`, ns ticks on the host).
    pub step: TimingHistogram,
    /// Commands that arrived after their period was given up (late answers).
    pub late_answers: u64,
}

/// The plant's iceoryx2 link to the firmware process.
pub struct IpcLink {
    /// The plant's hold of the rig, for the link's life.
    _lock: super::ipc::RigLock,
    ports: PlantPorts,
    rig: String,
    spawned: Option<Spawned>,
    realtime: bool,
    /// Real time: how the plant's loop was set up (CPU, scheduling).
    pub realtime_setup: Option<RealtimeSetup>,
    spin: Duration,
    period: Period,
    timeout: Duration,
    max_timeouts: u32,
    consecutive_timeouts: u32,
    faults: FaultPlan,
    t0: Option<Instant>,
    k: u64,
    /// Timings measured so far.
    pub timings: LinkTimings,
    /// The firmware's announcement, checked against the scenario (the handshake).
    announced: Option<Announced>,
    /// When the attached firmware's node was last looked up.
    last_peer_check: Option<Instant>,
    /// Lockstep: the frame sent ahead of its exchange ([`FirmwareLink::send_ahead`]),
    /// and when it was published.
    sent_ahead: Option<(u32, Instant)>,
    /// Lockstep: how long a period without an injected fault may wait.
    stall_limit: Duration,
    /// Lockstep: an injected stall began and the firmware has not answered since.
    in_stall: bool,
}

impl IpcLink {
    /// Opens the rig `rig`'s services and, when `firmware_exe` is given, spawns
    /// `firmware_exe firmware --rig RIG --scenario -` with the scenario on its
    /// standard input (and `--realtime` in real time); then waits until the
    /// firmware is connected and has announced its configuration, and then until
    /// `monitors.wait_for` monitors subscribe to `ground_truth` (each wait up to
    /// the scenario's `rig.connect_timeout_s`, [`CONNECT_TIMEOUT_S`] by default).
    ///
    /// # Errors
    /// [`RunError::IncompatibleService`] when a service another process created
    /// lacks what the run needs; [`RunError::Transport`] when the services cannot
    /// be opened, the process cannot be started, or no firmware (or fewer
    /// monitors than asked) connects in time.
    pub fn connect(
        s: &Scenario,
        rig: &str,
        firmware_exe: Option<&Path>,
        realtime: bool,
        monitors: &MonitorPolicy,
    ) -> Result<Self, RunError> {
        LinkKind::Ipc.check(&s.faults)?;
        let spin = Duration::from_secs_f64(s.rig.spin_us * 1e-6);
        // First of all: the plant's lock of the rig (one plant per rig, whatever the timing).
        let lock = super::ipc::RigLock::acquire(Role::Plant, rig)?;
        if let Some(pid) = super::ipc::live_owner(Role::Plant, rig) {
            return Err(RunError::RigInUse { rig: rig.to_string(), role: "plant", pid });
        }
        let ports = PlantPorts::open(rig, spin, monitors).map_err(open_error)?;
        // Before spawning: the firmware process inherits nothing from this thread's
        // set-up, it makes its own from the same scenario.
        let realtime_setup = realtime.then(|| prepare_realtime(&s.rig));
        // A firmware already on the rig (started by hand) would answer the handshake
        // and run the whole scenario while the one spawned here is refused: refuse
        // the run instead, before any period (run `--attach` to use that firmware).
        if firmware_exe.is_some()
            && let Some(pid) = super::ipc::live_owner(Role::Firmware, rig)
        {
            return Err(RunError::RigInUse { rig: rig.to_string(), role: "firmware", pid });
        }
        let spawned = match firmware_exe {
            Some(exe) => Some(spawn(exe, rig, s, realtime)?),
            None => None,
        };
        let mut link = Self {
            _lock: lock,
            ports,
            rig: rig.to_string(),
            spawned,
            realtime,
            realtime_setup,
            spin,
            period: s.timing.period(),
            timeout: Duration::from_secs_f64(s.rig.command_timeout_s),
            max_timeouts: s.rig.max_consecutive_timeouts,
            consecutive_timeouts: 0,
            faults: FaultPlan::new(&s.faults, s.timing.period()),
            t0: None,
            k: 0,
            timings: LinkTimings::default(),
            announced: None,
            last_peer_check: None,
            sent_ahead: None,
            stall_limit: Duration::from_secs_f64(s.rig.stall_limit_s),
            in_stall: false,
        };
        let start = Instant::now();
        let limit = s.rig.connect_timeout_s;
        while !link.ports.firmware_connected() {
            // Attach mode: a firmware not started yet is waited for, like a spawned one
            // still starting; only one that started and died is a failure now.
            let gone = if link.spawned.is_some() {
                link.firmware_gone()
            } else {
                // One look at the node: absent (not started yet) or alive (starting) is waited for.
                match peer_state(Role::Firmware, rig) {
                    PeerState::Dead => Some("died (its iceoryx2 node is dead)".to_string()),
                    PeerState::Alive | PeerState::Absent => None,
                }
            };
            if let Some(what) = gone {
                return Err(RunError::Transport(format!("the firmware process {what} before connecting")));
            }
            if start.elapsed().as_secs_f64() > limit {
                let how = if link.spawned.is_some() {
                    "the spawned firmware process did not connect; see its messages above".to_string()
                } else {
                    format!("start `sil-host firmware --rig {rig}` with the same scenario (attach mode), or raise rig.connect_timeout_s")
                };
                return Err(RunError::Transport(format!("no firmware connected to rig `{rig}` within {limit} s: {how}")));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        link.announced = Some(link.handshake(s, start + Duration::from_secs_f64(limit))?);
        // The answer must have come from the process spawned here: a firmware started
        // by hand between the check above and the spawn holds the rig's firmware node
        // (the spawned one then refuses to start), and is refused here by its pid.
        if let Some(spawned) = &link.spawned {
            let child = i64::from(spawned.child.id());
            if let Some(pid) = super::ipc::live_owner(Role::Firmware, rig).filter(|&pid| pid != child) {
                return Err(RunError::RigInUse { rig: rig.to_string(), role: "firmware", pid });
            }
        }
        link.wait_for_monitors(monitors.wait_for, limit)?;
        Ok(link)
    }

    /// Waits until `count` monitors subscribe to `ground_truth`, up to `limit_s`.
    fn wait_for_monitors(&mut self, count: usize, limit_s: f64) -> Result<(), RunError> {
        if count == 0 {
            return Ok(());
        }
        let service = super::services::service_name(&self.rig, "ground_truth");
        if self.ports.monitors() < count {
            eprintln!("rig: waiting for {count} monitor(s) to subscribe to {service} (up to {limit_s} s)");
        }
        let start = Instant::now();
        while self.ports.monitors() < count {
            if let Some(what) = self.firmware_gone() {
                return Err(RunError::Transport(format!("the firmware process {what} while the rig waited for monitors")));
            }
            if start.elapsed().as_secs_f64() > limit_s {
                return Err(RunError::Transport(format!(
                    "{} of {count} monitor(s) subscribed to {service} within rig.connect_timeout_s = {limit_s} s: start them \
                     (`python3 examples/python/monitor.py --rig {}`), or run without --monitors",
                    self.ports.monitors(),
                    self.rig
                )));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        Ok(())
    }

    /// What monitors cost the run so far (lossless runs: monitors given up, samples dropped).
    pub fn monitor_counts(&self) -> MonitorCounts {
        self.ports.monitor_counts()
    }

    /// The handshake before period 0: asks the connected firmware for its
    /// announcement (a [`frame_flags::HELLO`] frame carrying our wire version,
    /// repeated every 50 ms until it answers or `deadline`) and checks it against
    /// the configuration the scenario asks for ([`handshake::check`]).
    fn handshake(&mut self, s: &Scenario, deadline: Instant) -> Result<Announced, RunError> {
        let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
        let hello = SensorFrame { t_us: u64::from(WIRE_VERSION), flags: frame_flags::HELLO, ..SensorFrame::default() };
        let mut asked: Option<Instant> = None;
        loop {
            if asked.is_none_or(|t| t.elapsed() >= Duration::from_millis(50)) {
                self.ports.frames.send(hello).map_err(transport)?;
                asked = Some(Instant::now());
            }
            if let Some(a) = self.ports.announcements.try_next().map_err(transport)? {
                return Ok(handshake::check(&a, &super::setup::firmware_config(s), &self.rig)?);
            }
            if let Some(what) = self.firmware_gone() {
                return Err(RunError::Transport(format!("the firmware process {what} before announcing its configuration")));
            }
            if Instant::now() >= deadline {
                return Err(RunError::Transport(format!(
                    "the firmware on rig `{}` connected but did not announce its configuration within rig.connect_timeout_s = {} s: \
                     it may be an older build without the handshake (rebuild both sides from the same sources)",
                    self.rig, s.rig.connect_timeout_s
                )));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// The rig's name.
    pub fn rig(&self) -> &str {
        &self.rig
    }

    /// [`Self::firmware_gone`], for a period without an answer. A spawned process
    /// is asked every time (a `waitpid`, microseconds); a firmware started by hand
    /// through iceoryx2's node listing, which reads the node directory and takes
    /// milliseconds, at most every 20 ms of wall time, so a stalled firmware never
    /// costs the plant more than its period per missed period in real time.
    fn firmware_gone_checked(&mut self) -> Option<String> {
        if self.spawned.is_none() {
            let now = Instant::now();
            if self.last_peer_check.is_some_and(|t| now - t < Duration::from_millis(20)) {
                return None;
            }
            self.last_peer_check = Some(now);
        }
        self.firmware_gone()
    }

    /// Whether the firmware process is gone, and how.
    fn firmware_gone(&mut self) -> Option<String> {
        match &mut self.spawned {
            Some(sp) => match sp.child.try_wait() {
                Ok(Some(status)) => Some(format!("exited ({status})")),
                Ok(None) => None,
                Err(e) => Some(format!("cannot be waited for ({e})")),
            },
            None => match peer_state(Role::Firmware, &self.rig) {
                PeerState::Alive => None,
                PeerState::Dead => Some("died (its iceoryx2 node is dead)".into()),
                PeerState::Absent => Some("is gone (no iceoryx2 node)".into()),
            },
        }
    }

    /// Lockstep: whether an injected fault may leave period `k` without its
    /// answer (then the plant waits `rig.command_timeout_s` and counts a miss).
    /// Notes a stall that starts at `k`: its periods stay faulted until the
    /// firmware answers again.
    fn fault_may_miss(&mut self, k: u64) -> bool {
        if self.faults.stall_starting(k).is_some() {
            self.in_stall = true;
        }
        self.in_stall || self.faults.drops_command(k) || self.faults.command_delay(k).as_us() > 0 || self.faults.kills_firmware_at(k)
    }

    /// The firmware's process id (spawned, or the attached firmware's node owner).
    fn firmware_pid(&self) -> Option<i64> {
        match &self.spawned {
            Some(sp) => Some(i64::from(sp.child.id())),
            None => super::ipc::live_owner(Role::Firmware, &self.rig),
        }
    }

    /// Lockstep outside injected faults: waits for the command echoing `seq`
    /// whatever the host's load; `Err` when the firmware is gone or made no
    /// progress for `rig.stall_limit_s`.
    fn wait_for_answer(&mut self, seq: u32, t: f64) -> Result<Option<shared::wire::ActuatorCommand>, RunError> {
        let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
        let start = Instant::now();
        loop {
            let chunk = Instant::now() + Duration::from_millis(20);
            match self.ports.commands.next_before(chunk).map_err(transport)? {
                Some(c) if c.seq == seq => return Ok(Some(c)),
                Some(_) => self.timings.late_answers += 1,
                None => {
                    let k = seq as usize;
                    if let Some(what) = self.firmware_gone() {
                        return Err(RunError::FirmwareLost { k, t, what: format!("the firmware process {what}") });
                    }
                    let waited = start.elapsed();
                    if waited >= self.stall_limit {
                        let stopped = self.firmware_pid().and_then(process_state).is_some_and(|c| c == 'T' || c == 't');
                        return Err(RunError::FirmwareLost {
                            k,
                            t,
                            what: format!(
                                "the firmware made no progress for {:.1} s (rig.stall_limit_s){}",
                                waited.as_secs_f64(),
                                if stopped { ": its process is stopped (SIGSTOP or a debugger); resume it with SIGCONT" } else { "" }
                            ),
                        });
                    }
                }
            }
        }
    }

    /// Publishes `truth` (to monitors) and `frame` (to the firmware); returns when the frame went out.
    fn publish(&self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Instant, RunError> {
        let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
        self.ports.publish_truth(*truth).map_err(transport)?;
        let published = Instant::now();
        self.ports.frames.send(*frame).map_err(transport)?;
        Ok(published)
    }

    fn telemetry_for(&self, seq: u32) -> Result<FirmwareTelemetry, RunError> {
        // Published just before the command: it is there, behind older ones.
        while let Some(t) = self.ports.telemetry.try_next().map_err(|e| RunError::Transport(e.to_string()))? {
            if t.seq == seq {
                return Ok(t);
            }
        }
        Ok(FirmwareTelemetry { seq, z_t_ref: f32::NAN, ..FirmwareTelemetry::default() })
    }
}

/// A service that lacks what the run needs is bad set-up (exit 2); anything else
/// is the transport failing.
pub(crate) fn open_error(e: IpcError) -> RunError {
    match e {
        IpcError::Incompatible(i) => RunError::IncompatibleService(i.to_string()),
        IpcError::Transport(m) => RunError::Transport(format!("iceoryx2: {m}")),
    }
}

fn spawn(exe: &Path, rig: &str, s: &Scenario, realtime: bool) -> Result<Spawned, RunError> {
    let toml = toml::to_string(s).map_err(|e| RunError::Transport(format!("cannot serialise the scenario: {e}")))?;
    let mut cmd = Command::new(exe);
    cmd.args(["firmware", "--rig", rig, "--scenario", "-"]).stdin(Stdio::piped()).stdout(Stdio::null()).stderr(Stdio::inherit());
    if realtime {
        cmd.arg("--realtime");
    }
    let mut child = cmd.spawn().map_err(|e| RunError::Transport(format!("cannot start the firmware process {}: {e}", exe.display())))?;
    let mut stdin = child.stdin.take().ok_or_else(|| RunError::Transport("no stdin to the firmware process".into()))?;
    stdin.write_all(toml.as_bytes()).map_err(|e| RunError::Transport(format!("cannot send the scenario to the firmware process: {e}")))?;
    drop(stdin);
    Ok(Spawned { child })
}

impl FirmwareLink for IpcLink {
    fn transport(&self) -> &'static str {
        "iceoryx2"
    }

    fn switches_at_stamp(&self) -> bool {
        self.realtime
    }

    fn announcement(&self) -> Option<&Announced> {
        self.announced.as_ref()
    }

    fn before_period(&mut self, k: u64) {
        self.k = k;
        if self.faults.kills_firmware_at(k)
            && let Some(sp) = &mut self.spawned
        {
            let _ = sp.child.kill();
        }
    }

    /// Lockstep only: publishes the frame now; [`FirmwareLink::exchange`] then
    /// waits for its answer (its round trip then runs to when the plant takes the
    /// command, after the plant's own work in between).
    fn send_ahead(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<bool, RunError> {
        if self.realtime {
            return Ok(false);
        }
        let published = self.publish(frame, truth)?;
        self.sent_ahead = Some((frame.seq, published));
        Ok(true)
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
        let patient = !self.realtime && !self.fault_may_miss(u64::from(frame.seq));
        let deadline = if self.realtime {
            let t0 = *self.t0.get_or_insert_with(Instant::now);
            let ideal = t0 + Duration::from_micros(frame.sampled_at().as_us());
            sleep_until(ideal, self.spin);
            None
        } else {
            Some(Instant::now() + self.timeout)
        };
        let published = match self.sent_ahead.take() {
            Some((seq, published)) if seq == frame.seq => published,
            _ => self.publish(frame, truth)?,
        };
        if patient && let Some(c) = self.wait_for_answer(frame.seq, truth.t)? {
            self.consecutive_timeouts = 0;
            self.timings.rtt.record(published.elapsed());
            self.timings.step.record_ns(u64::from(c.step_ticks));
            let telemetry = self.telemetry_for(c.seq)?;
            return Ok(Exchange::Answered { command: c, telemetry, at_stamp: false });
        }
        // Real time: the sample instant is the frame's publication (the hardware's
        // timer tick); the plant's own lateness against `t0 + t_k` is period jitter,
        // not the firmware's deadline. The plant stops waiting at the next sample
        // instant `t0 + t_{k+1}`, so a firmware that does not answer never puts it
        // behind the wall clock (one period per missed period at most); if the
        // plant itself published late, the firmware still gets half a period.
        let deadline = deadline.unwrap_or_else(|| {
            let ideal = self.t0.map_or(published, |t0| t0 + Duration::from_micros(frame.sampled_at().as_us()));
            self.timings.jitter.record(published.saturating_duration_since(ideal));
            let ts = Duration::from_micros(self.period.as_us());
            (ideal + ts).max(published + ts / 2)
        });
        loop {
            match self.ports.commands.next_before(deadline).map_err(transport)? {
                Some(c) if c.seq == frame.seq => {
                    let now = Instant::now();
                    self.consecutive_timeouts = 0;
                    self.in_stall = false;
                    self.timings.rtt.record(now - published);
                    self.timings.step.record_ns(u64::from(c.step_ticks));
                    let telemetry = self.telemetry_for(c.seq)?;
                    // Real time: the command's own send stamp (the firmware's clock,
                    // anchored at the frame's arrival) dates it; the plant's own view
                    // (`now`) is late by however long the plant itself was descheduled.
                    return Ok(Exchange::Answered { command: c, telemetry, at_stamp: self.realtime });
                }
                Some(_) => self.timings.late_answers += 1,
                None => break,
            }
        }
        // Nothing this period: a deadline miss, unless the firmware is gone.
        let k = frame.seq as usize;
        if let Some(what) = self.firmware_gone_checked() {
            return Err(RunError::FirmwareLost { k, t: truth.t, what: format!("the firmware process {what}") });
        }
        self.consecutive_timeouts += 1;
        // In both timings: a firmware that does not answer for this many periods in
        // a row is given up (exit 1, the trace kept), stalled or not.
        if self.consecutive_timeouts >= self.max_timeouts {
            let each = if self.realtime {
                format!("one period of {} s of wall time each", self.period.as_secs_f64())
            } else {
                format!("{} s of wall time each", self.timeout.as_secs_f64())
            };
            return Err(RunError::FirmwareLost {
                k,
                t: truth.t,
                what: format!(
                    "no command for {} periods in a row ({each}; rig.max_consecutive_timeouts): the firmware process is stalled",
                    self.consecutive_timeouts
                ),
            });
        }
        Ok(Exchange::NoAnswer)
    }

    fn finish(&mut self, last_seq: u32) {
        let end = SensorFrame { seq: last_seq, flags: frame_flags::END_OF_RUN, ..SensorFrame::default() };
        let _ = self.ports.frames.send(end);
        if let Some(sp) = &mut self.spawned {
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(2) {
                if let Ok(Some(_)) = sp.child.try_wait() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(2));
            }
            let _ = sp.child.kill();
            let _ = sp.child.wait();
        }
    }
}

impl Drop for IpcLink {
    fn drop(&mut self) {
        if let Some(setup) = &self.realtime_setup {
            leave_realtime(setup);
        }
        if let Some(sp) = &mut self.spawned {
            if let Ok(None) = sp.child.try_wait() {
                let _ = sp.child.kill();
            }
            let _ = sp.child.wait();
            // A killed firmware could not remove its lock file: the plant does.
            super::ipc::RigLock::remove_stale(Role::Firmware, &self.rig);
        }
    }
}

/// The state letter of process `pid` (`/proc/PID/stat`'s third field: `R`, `S`,
/// `T` stopped, `t` stopped by a tracer, ...); `None` where there is no procfs.
fn process_state(pid: i64) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name in parentheses may hold spaces: the state follows its ')'.
    stat.rsplit_once(')')?.1.trim_start().chars().next()
}

/// Waits until `when`: the OS sleep to `spin` before, then a spin that yields the
/// core (sleep alone overshoots by the wake-up latency).
fn sleep_until(when: Instant, spin: Duration) {
    let now = Instant::now();
    if when > now + spin {
        std::thread::sleep(when - now - spin);
    }
    while Instant::now() < when {
        std::thread::yield_now();
    }
}
