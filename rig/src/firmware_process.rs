//! The firmware process (`sil-host firmware`): the same `firmware` step as the
//! MCU image, behind a board made of iceoryx2 ports. It answers every sensor
//! frame with a command and the step's telemetry until the plant ends the run.
//!
//! Its clock: in lockstep the frame's (simulated) time: a step starts at the
//! newest sample it has seen; the step's wall time is reported in
//! `step_ticks` (ns) but does not advance simulated time. In real time, its own
//! wall clock, re-anchored at every frame it was waiting for (the frame's arrival
//! is the sample tick, as a timer interrupt is on the MCU): a frame that was
//! already queued when it looked is one it is late for, timed from the last
//! anchor. It blocks between frames on the plant's CPU ([`prepare_realtime`]).
//!
//! After a stall (frames queued up while it did not run, in either timing) it
//! answers only the newest frame and counts every period it missed as an overrun
//! (`Event::Missed`), so its count equals the plant's misses (docs/rig.md "Stalls").
//!
//! Before period 0 it answers the plant's handshake frame with its announcement
//! (docs/rig.md "Handshake").
//!
//! Safe state on a lost peer: when no frame has come for `rig.peer_check_s` and
//! iceoryx2's node monitoring says the plant process is dead or gone, the
//! firmware latches `SafeReason::PeerLost`, publishes a zero-torque command and
//! exits with code 3.
//!
//! The loop is `firmware::board::run` over an iceoryx2 board ([`IpcBoard`]), the
//! same event loop the MCU images run.

use std::time::{Duration, Instant};

use firmware::{
    Config, ControlLaw, Event, Firmware, Outcome, PaperLaws, TickClock,
    board::{self, Board, FrozenClock},
};
use shared::{
    time,
    wire::{FirmwareAnnouncement, SensorFrame, WIRE_VERSION, frame_flags},
};

use super::{
    faults::FaultPlan,
    firmware_side::step_start,
    ipc::{FirmwarePorts, PeerState, Role, peer_state},
    realtime::prepare_realtime,
    record::RunError,
    scenario::Scenario,
    setup::firmware_config,
};

/// How long a firmware started by hand waits for its plant to appear, s.
pub const WAIT_FOR_PLANT_S: f64 = 120.0;

/// How the firmware process ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ending {
    /// The plant ended the run.
    EndOfRun {
        /// Frames answered.
        answered: u64,
        /// Overruns the firmware counted.
        overruns: u32,
    },
    /// The plant died or vanished: the firmware latched its safe state.
    PeerLost {
        /// Frames answered before.
        answered: u64,
    },
}

/// A tick counter on the host's monotonic clock, in nanoseconds (wraps every 4.3 s).
#[derive(Debug, Clone, Copy)]
pub struct HostClock {
    origin: Instant,
}

impl Default for HostClock {
    fn default() -> Self {
        Self { origin: Instant::now() }
    }
}

impl TickClock for HostClock {
    fn ticks(&self) -> u32 {
        self.origin.elapsed().as_nanos() as u32
    }
    fn ticks_per_second(&self) -> u32 {
        1_000_000_000
    }
}

/// The step's clock: the host's in real time; frozen in lockstep (simulated
/// time does not advance while the firmware computes; the wall time is
/// reported in `step_ticks` instead).
#[derive(Debug, Clone, Copy)]
enum ProcessClock {
    Host(HostClock),
    Frozen,
}

impl TickClock for ProcessClock {
    fn ticks(&self) -> u32 {
        match self {
            Self::Host(c) => c.ticks(),
            Self::Frozen => FrozenClock.ticks(),
        }
    }
    fn ticks_per_second(&self) -> u32 {
        match self {
            Self::Host(c) => c.ticks_per_second(),
            Self::Frozen => FrozenClock.ticks_per_second(),
        }
    }
}

/// The firmware process's board: frames from the plant's iceoryx2 service,
/// commands and telemetry back (`firmware::board::run` drives it, as it
/// drives the MCU images).
struct IpcBoard<'a> {
    ports: &'a FirmwarePorts,
    rig: &'a str,
    realtime: bool,
    faults: FaultPlan,
    peer_check: Duration,
    started: Instant,
    /// Real time: the wall-clock instant of sample time 0, anchored at the last
    /// frame the firmware was waiting for.
    epoch: Option<Instant>,
    last_seq: Option<u32>,
    answered: u64,
    stalled_at: Option<u32>,
    /// Frames that queued up, in order, and the newest sample time among them.
    batch: std::collections::VecDeque<SensorFrame>,
    newest_us: u64,
    now: time::Instant,
    step_started: Instant,
    ending: Option<Ending>,
    /// What it answers the plant's handshake frame with.
    announcement: FirmwareAnnouncement,
    /// Periods missed in a stall, to count before the newest frame ([`Event::Missed`]).
    missed: u32,
    /// A plant's handshake frame was answered: a plant that is then gone before
    /// its first frame refused this firmware ([`RunError::RefusedByPlant`]).
    greeted: bool,
}

impl IpcBoard<'_> {
    /// Answers a handshake frame ([`frame_flags::HELLO`]) with the announcement;
    /// `false` for any other frame. A plant of another wire version is told ours
    /// (it refuses us) and we say so here; we stay for a plant of our own version.
    fn answer_hello(&mut self, frame: &SensorFrame) -> Result<bool, RunError> {
        if frame.flags & frame_flags::HELLO == 0 {
            return Ok(false);
        }
        if frame.t_us != u64::from(WIRE_VERSION) {
            eprintln!(
                "firmware: the plant on rig `{}` speaks wire version {}, this firmware {WIRE_VERSION}: refused (rebuild both from the same sources)",
                self.rig, frame.t_us
            );
        }
        self.ports.announcement.send(self.announcement).map_err(|e| RunError::Transport(e.to_string()))?;
        self.greeted = true;
        Ok(true)
    }

    /// Waits for frames (and checks on the plant while none come); fills the batch.
    fn wait_for_frames(&mut self) -> Result<Option<Event>, RunError> {
        let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
        // A frame already queued is one the firmware is late for; one it waits for
        // arrives now.
        let queued = self.ports.frames.try_next().map_err(transport)?;
        let was_queued = queued.is_some();
        let waited_from = Instant::now();
        let next = match queued {
            Some(f) => Some(f),
            None => self.ports.frames.next_before(waited_from + self.peer_check).map_err(transport)?,
        };
        if let Some(f) = &next
            && self.answer_hello(f)?
        {
            return Ok(None);
        }
        let Some(first) = next else {
            // No frame for a while: is the plant still there?
            return match peer_state(Role::Plant, self.rig) {
                PeerState::Alive => Ok(None),
                PeerState::Absent if self.last_seq.is_none() => {
                    // Greeted, then gone before any frame: that plant refused us
                    // (issue 84: the process waited out the 120 s, then said "no
                    // plant connected", which was untrue).
                    if self.greeted {
                        return Err(RunError::RefusedByPlant { rig: self.rig.to_string() });
                    }
                    if self.started.elapsed().as_secs_f64() > WAIT_FOR_PLANT_S {
                        return Err(RunError::Transport(format!("no plant connected to rig `{}` within {WAIT_FOR_PLANT_S} s", self.rig)));
                    }
                    Ok(None)
                }
                state => {
                    eprintln!(
                        "firmware: the plant process is {} (no frame for {:.1} s after seq {:?}): safe state, zero torque",
                        if state == PeerState::Dead { "dead" } else { "gone" },
                        self.peer_check.as_secs_f64(),
                        self.last_seq
                    );
                    self.ending = Some(Ending::PeerLost { answered: self.answered });
                    self.now = time::Instant::from_us(0);
                    Ok(Some(Event::PeerLost { seq: self.last_seq.map_or(0, |q| q.wrapping_add(1)) }))
                }
            };
        };
        if self.realtime
            && (!was_queued || self.epoch.is_none())
            && let Some(seen) = Instant::now().checked_sub(Duration::from_micros(first.t_us))
        {
            self.epoch = Some(seen);
        }
        // Injected stall: the process stops (wall clock) at the window's first frame.
        if let Some(d) = self.faults.stall_starting(u64::from(first.seq))
            && self.stalled_at != Some(first.seq)
        {
            self.stalled_at = Some(first.seq);
            std::thread::sleep(Duration::from_secs_f64(d));
        }
        // Everything that queued up meanwhile, in order: in lockstep the firmware's
        // clock is the newest sample, so older frames are answered late.
        self.batch.push_back(first);
        while let Some(f) = self.ports.frames.try_next().map_err(transport)? {
            if !self.answer_hello(&f)? {
                self.batch.push_back(f);
            }
        }
        self.drop_stale();
        self.newest_us = self.batch.iter().map(|f| f.t_us).max().unwrap_or(first.t_us);
        Ok(None)
    }
}

impl IpcBoard<'_> {
    /// After a stall (frames queued up while the process did not run, in either
    /// timing): answers only the newest frame and counts every period between the
    /// last one answered and it as missed, the frames dropped here and any the
    /// queue's safe overflow overwrote alike. The plant counted a deadline miss for
    /// each of those periods, so both counts agree (issue 15). The end of the run
    /// is never dropped.
    fn drop_stale(&mut self) {
        let Some(&newest) = self.batch.back() else { return };
        if self.batch.iter().any(|f| f.flags & frame_flags::END_OF_RUN != 0) {
            return;
        }
        let skipped = match self.last_seq {
            Some(last) => newest.seq.wrapping_sub(last).saturating_sub(1),
            None => (self.batch.len() - 1) as u32,
        };
        // A sequence that went back is the firmware's to judge (a stale frame), not a stall.
        if skipped < u32::MAX / 2 {
            self.missed = self.missed.saturating_add(skipped);
        }
        self.batch.clear();
        self.batch.push_back(newest);
    }
}

impl Board for IpcBoard<'_> {
    type Error = RunError;

    fn next_event(&mut self) -> Result<Event, RunError> {
        loop {
            if self.ending.is_some() {
                return Ok(Event::End);
            }
            if self.missed > 0 {
                return Ok(Event::Missed { periods: std::mem::take(&mut self.missed) });
            }
            if let Some(frame) = self.batch.pop_front() {
                if frame.flags & frame_flags::END_OF_RUN != 0 {
                    return Ok(Event::End);
                }
                let floor = match (self.realtime, self.epoch) {
                    (true, Some(e)) => time::Instant::from_us(e.elapsed().as_micros() as u64),
                    (true, None) => frame.sampled_at(),
                    (false, _) => time::Instant::from_us(self.newest_us),
                };
                self.now = step_start(&self.faults, &frame, floor);
                self.step_started = Instant::now();
                return Ok(Event::Frame(frame));
            }
            if let Some(event) = self.wait_for_frames()? {
                return Ok(event);
            }
        }
    }

    fn now(&self) -> time::Instant {
        self.now
    }

    fn apply<L: ControlLaw>(&mut self, outcome: &Outcome, fw: Option<&Firmware<L>>) -> Result<(), RunError> {
        let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
        let Outcome::Command(command) = outcome else { return Ok(()) };
        if self.ending.is_some() {
            // The peer is lost: the zero-torque command goes out for whoever listens.
            let _ = self.ports.commands.send(*command);
            return Ok(());
        }
        let mut command = *command;
        if !self.realtime {
            command.step_ticks = self.step_started.elapsed().as_nanos() as u32;
        }
        if let Some(fw) = fw {
            self.ports.telemetry.send(fw.telemetry_message(&command)).map_err(transport)?;
        }
        self.ports.commands.send(command).map_err(transport)?;
        self.last_seq = Some(command.seq);
        self.answered += 1;
        Ok(())
    }
}

/// Runs the firmware process of rig `rig` for scenario `s` until the plant ends
/// the run or dies.
///
/// # Errors
/// [`RunError::Firmware`] for a bad configuration, [`RunError::IncompatibleService`]
/// when a service another process created lacks what the firmware needs,
/// [`RunError::Transport`] when iceoryx2 fails or no plant appears within
/// [`WAIT_FOR_PLANT_S`]; [`RunError::RefusedByPlant`] when a plant read the
/// handshake's answer and left before its first frame (it refused this firmware).
pub fn serve(s: &Scenario, rig: &str, realtime: bool) -> Result<Ending, RunError> {
    serve_law::<PaperLaws>(s, rig, realtime)
}

/// [`serve`] with the control law `L`: the firmware process of a law of one's
/// own (its crate's `main`, docs/board.md "Your own law"). The scenario's
/// `[law]` table is bound to what `L` declares ([`crate::law::bind`]); the
/// handshake announces `L`'s declaration, so the plant checks the same table
/// against it.
///
/// # Errors
/// As [`serve`]; [`RunError::Law`] when the scenario's `[law]` table does not
/// fit `L`.
pub fn serve_law<L: ControlLaw>(s: &Scenario, rig: &str, realtime: bool) -> Result<Ending, RunError> {
    let spin = Duration::from_secs_f64(s.rig.spin_us * 1e-6);
    // One firmware per rig, whatever the timing: held until this returns.
    let _lock = super::ipc::RigLock::acquire(super::ipc::Role::Firmware, rig)?;
    if let Some(pid) = super::ipc::live_owner(super::ipc::Role::Firmware, rig) {
        return Err(RunError::RigInUse { rig: rig.to_string(), role: "firmware", pid });
    }
    let ports = FirmwarePorts::open(rig, spin).map_err(super::ipc_link::open_error)?;
    if realtime {
        for w in prepare_realtime(&s.rig).warnings {
            eprintln!("firmware: real-time set-up: {w}");
        }
    }
    let config = Config { law: crate::law::bind(s.law.as_ref(), &crate::law::LawDescription::of(&L::SPEC))?, ..firmware_config(s) };
    let announcement = firmware::announce::announce(&config, &L::SPEC).map_err(crate::handshake::HandshakeError::from)?;
    let mut firmware = Some(Firmware::<L>::with_law(config)?);
    let mut board = IpcBoard {
        ports: &ports,
        rig,
        realtime,
        faults: FaultPlan::new(&s.faults, s.timing.period()),
        peer_check: Duration::from_secs_f64(s.rig.peer_check_s),
        started: Instant::now(),
        epoch: None,
        last_seq: None,
        answered: 0,
        stalled_at: None,
        batch: std::collections::VecDeque::with_capacity(super::ipc::QUEUE_DEPTH),
        newest_us: 0,
        now: time::Instant::from_us(0),
        step_started: Instant::now(),
        ending: None,
        announcement,
        missed: 0,
        greeted: false,
    };
    let clock = if realtime { ProcessClock::Host(HostClock::default()) } else { ProcessClock::Frozen };
    board::run(&mut firmware, &mut board, &clock)?;
    Ok(board
        .ending
        .unwrap_or(Ending::EndOfRun { answered: board.answered, overruns: firmware.as_ref().map_or(0, Firmware::<L>::overruns) }))
}
