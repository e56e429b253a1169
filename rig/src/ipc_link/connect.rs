//! Connecting the link ([`IpcLink::connect`]): the rig's lock and services, the
//! firmware spawned or attached, the monitors waited for, and the handshake
//! before period 0.

use std::{
    path::Path,
    time::{Duration, Instant},
};

use shared::wire::{SensorFrame, WIRE_VERSION, frame_flags};

use super::{IpcLink, LinkTimings, process::spawn};
use crate::{
    faults::LinkKind,
    handshake::{self, Announced},
    ipc::{IpcError, MonitorPolicy, PeerState, PlantPorts, Role, peer_state},
    realtime::prepare_realtime,
    record::RunError,
    setup::RunSetup,
};

/// How long the plant waits for the firmware to connect, s.
pub const CONNECT_TIMEOUT_S: f64 = 20.0;

impl IpcLink {
    /// Opens the rig `rig`'s services for run `setup` and, when `firmware_exe` is given, spawns
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
        setup: &RunSetup,
        rig: &str,
        firmware_exe: Option<&Path>,
        realtime: bool,
        monitors: &MonitorPolicy,
    ) -> Result<Self, RunError> {
        let s = setup.scenario();
        LinkKind::Ipc.check(&s.faults)?;
        let spin = Duration::from_secs_f64(s.rig.spin_us * 1e-6);
        // First of all: the plant's lock of the rig (one plant per rig, whatever the timing).
        let lock = crate::ipc::RigLock::acquire(Role::Plant, rig)?;
        if let Some(pid) = crate::ipc::live_owner(Role::Plant, rig) {
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
            && let Some(pid) = crate::ipc::live_owner(Role::Firmware, rig)
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
            faults: setup.faults().clone(),
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
        link.announced = Some(link.handshake(setup, start + Duration::from_secs_f64(limit))?);
        // The answer must have come from the process spawned here: a firmware started
        // by hand between the check above and the spawn holds the rig's firmware node
        // (the spawned one then refuses to start), and is refused here by its pid.
        if let Some(spawned) = &link.spawned {
            let child = i64::from(spawned.child.id());
            if let Some(pid) = crate::ipc::live_owner(Role::Firmware, rig).filter(|&pid| pid != child) {
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
        let service = crate::services::service_name(&self.rig, "ground_truth");
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

    /// The handshake before period 0: asks the connected firmware for its
    /// announcement (a [`frame_flags::HELLO`] frame carrying our wire version,
    /// repeated every 50 ms until it answers or `deadline`) and checks it against
    /// the configuration the scenario asks for ([`handshake::check`]).
    fn handshake(&mut self, setup: &RunSetup, deadline: Instant) -> Result<Announced, RunError> {
        let transport = |e: crate::ipc::IpcError| RunError::Transport(e.to_string());
        let hello = SensorFrame { t_us: u64::from(WIRE_VERSION), flags: frame_flags::HELLO, ..SensorFrame::default() };
        let mut asked: Option<Instant> = None;
        loop {
            if asked.is_none_or(|t| t.elapsed() >= Duration::from_millis(50)) {
                self.ports.frames.send(hello).map_err(transport)?;
                asked = Some(Instant::now());
            }
            if let Some(a) = self.ports.announcements.try_next().map_err(transport)? {
                return Ok(handshake::check(&a, setup.firmware(), setup.scenario().law.as_ref(), &self.rig)?);
            }
            if let Some(what) = self.firmware_gone() {
                return Err(RunError::Transport(format!("the firmware process {what} before announcing its configuration")));
            }
            if Instant::now() >= deadline {
                return Err(RunError::Transport(format!(
                    "the firmware on rig `{}` connected but did not announce its configuration within rig.connect_timeout_s = {} s: \
                     it may be an older build without the handshake (rebuild both sides from the same sources)",
                    self.rig,
                    setup.scenario().rig.connect_timeout_s
                )));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
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
