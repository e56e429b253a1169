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
//! Both processes run their loop on one CPU ([`prepare_realtime`](crate::realtime::prepare_realtime)).

//!
//! The link's parts: `connect.rs` (spawn or attach, the monitors, the handshake),
//! `exchange.rs` (each period's frame and command, in lockstep or real time) and
//! `process.rs` (the firmware's process: started, alive, stopped, ended).

mod connect;
mod exchange;
mod process;

use std::{process::Child, time::Duration, time::Instant};

use shared::Period;

use super::{
    faults::FaultPlan,
    handshake::Announced,
    ipc::{MonitorCounts, PlantPorts},
    realtime::RealtimeSetup,
    stats::TimingHistogram,
};

pub use connect::CONNECT_TIMEOUT_S;
pub(crate) use connect::open_error;

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
    /// Lockstep: the frame sent ahead of its exchange ([`FirmwareLink::send_ahead`](crate::link::FirmwareLink::send_ahead)),
    /// and when it was published.
    sent_ahead: Option<(u32, Instant)>,
    /// Lockstep: how long a period without an injected fault may wait.
    stall_limit: Duration,
    /// Lockstep: an injected stall began and the firmware has not answered since.
    in_stall: bool,
}

impl IpcLink {
    /// What monitors cost the run so far (lossless runs: monitors given up, samples dropped).
    pub fn monitor_counts(&self) -> MonitorCounts {
        self.ports.monitor_counts()
    }

    /// The rig's name.
    pub fn rig(&self) -> &str {
        &self.rig
    }
}
