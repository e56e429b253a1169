//! The firmware process (`sil-host firmware`): the same `firmware` step as the
//! MCU image, behind a board made of iceoryx2 ports. It answers every sensor
//! frame with a command and the step's telemetry until the plant ends the run.
//!
//! Its clock: in lockstep the frame's (simulated) time: a step starts at the
//! newest sample it has seen, so frames that piled up while it was stalled are
//! answered late and counted as overruns; the step's wall time is reported in
//! `step_ticks` (ns) but does not advance simulated time. In real time, its own
//! wall clock, re-anchored at every frame it was waiting for (the frame's arrival
//! is the sample tick, as a timer interrupt is on the MCU): a frame that was
//! already queued when it looked is one it is late for, timed from the last
//! anchor. It blocks between frames on the plant's CPU ([`prepare_realtime`]).
//!
//! Safe state on a lost peer: when no frame has come for `rig.peer_check_s` and
//! iceoryx2's node monitoring says the plant process is dead or gone, the
//! firmware latches [`SafeReason::PeerLost`], publishes a zero-torque command and
//! exits with code 3.

use std::time::{Duration, Instant};

use firmware::{SafeReason, TickClock, board::FrozenClock};
use shared::wire::{SensorFrame, frame_flags};

use super::{
    faults::FaultPlan,
    firmware_side::FirmwareSide,
    ipc::{FirmwarePorts, PeerState, Role, peer_state, prepare_realtime},
    record::RunError,
    scenario::Scenario,
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

/// Runs the firmware process of rig `rig` for scenario `s` until the plant ends
/// the run or dies.
///
/// # Errors
/// [`RunError::Firmware`] for a bad configuration, [`RunError::Transport`] when
/// iceoryx2 fails or no plant appears within [`WAIT_FOR_PLANT_S`].
pub fn serve(s: &Scenario, rig: &str, realtime: bool) -> Result<Ending, RunError> {
    let transport = |e: super::ipc::IpcError| RunError::Transport(e.to_string());
    let spin = Duration::from_secs_f64(s.rig.spin_us * 1e-6);
    let ports = FirmwarePorts::open(rig, spin).map_err(transport)?;
    if realtime {
        for w in prepare_realtime(&s.rig).warnings {
            eprintln!("firmware: real-time set-up: {w}");
        }
    }
    let mut side = FirmwareSide::new(s)?;
    let faults = FaultPlan::new(&s.faults, 1.0 / s.timing.rate_hz);
    let peer_check = Duration::from_secs_f64(s.rig.peer_check_s);
    let clock = HostClock::default();
    let started = Instant::now();
    // Real time: the wall-clock instant of sample time 0, anchored at the last
    // frame the firmware was waiting for.
    let mut epoch: Option<Instant> = None;
    let mut last_seq: Option<u32> = None;
    let mut answered = 0u64;
    let mut stalled_at: Option<u32> = None;
    let mut batch: Vec<SensorFrame> = Vec::with_capacity(super::ipc::QUEUE_DEPTH);
    loop {
        // A frame already queued is one the firmware is late for; one it waits for
        // arrives now.
        let queued = ports.frames.try_next().map_err(transport)?;
        let was_queued = queued.is_some();
        let waited_from = Instant::now();
        let next = match queued {
            Some(f) => Some(f),
            None => ports.frames.next_before(waited_from + peer_check).map_err(transport)?,
        };
        let Some(first) = next else {
            // No frame for a while: is the plant still there?
            match peer_state(Role::Plant, rig) {
                PeerState::Alive => continue,
                PeerState::Absent if last_seq.is_none() => {
                    if started.elapsed().as_secs_f64() > WAIT_FOR_PLANT_S {
                        return Err(RunError::Transport(format!("no plant connected to rig `{rig}` within {WAIT_FOR_PLANT_S} s")));
                    }
                    continue;
                }
                state => {
                    let fw = side.firmware_mut();
                    fw.enter_safe_state(SafeReason::PeerLost);
                    let seq = last_seq.map_or(0, |q| q.wrapping_add(1));
                    let cmd = fw.safe_command(seq, 0);
                    let _ = ports.commands.send(cmd);
                    eprintln!(
                        "firmware: the plant process is {} (no frame for {:.1} s after seq {:?}): safe state, zero torque",
                        if state == PeerState::Dead { "dead" } else { "gone" },
                        peer_check.as_secs_f64(),
                        last_seq
                    );
                    return Ok(Ending::PeerLost { answered });
                }
            }
        };
        if realtime
            && (!was_queued || epoch.is_none())
            && let Some(seen) = Instant::now().checked_sub(Duration::from_micros(first.t_us))
        {
            epoch = Some(seen);
        }
        // Injected stall: the process stops (wall clock) at the window's first frame.
        if let Some(d) = faults.stall_starting(first.t_us as f64 * 1e-6)
            && stalled_at != Some(first.seq)
        {
            stalled_at = Some(first.seq);
            std::thread::sleep(Duration::from_secs_f64(d));
        }
        // Everything that queued up meanwhile, in order: in lockstep the firmware's
        // clock is the newest sample, so older frames are answered late.
        batch.clear();
        batch.push(first);
        while let Some(f) = ports.frames.try_next().map_err(transport)? {
            batch.push(f);
        }
        let newest_us = batch.iter().map(|f| f.t_us).max().unwrap_or(first.t_us);
        for &frame in &batch {
            if frame.flags & frame_flags::END_OF_RUN != 0 {
                return Ok(Ending::EndOfRun { answered, overruns: side.firmware().overruns() });
            }
            let (command, telemetry) = if realtime {
                let now_us = epoch.map_or(frame.t_us, |e| e.elapsed().as_micros() as u64);
                side.answer(&frame, now_us, &clock)
            } else {
                let t = Instant::now();
                let (mut c, tel) = side.answer(&frame, newest_us, &FrozenClock);
                c.step_ticks = t.elapsed().as_nanos() as u32;
                (c, tel)
            };
            ports.telemetry.send(telemetry).map_err(transport)?;
            ports.commands.send(command).map_err(transport)?;
            last_seq = Some(frame.seq);
            answered += 1;
        }
    }
}
