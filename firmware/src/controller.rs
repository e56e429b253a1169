//! The firmware's state across periods ([`Firmware`]) and its two halves: its
//! life outside the step (`lifecycle`: made, reset, put in the safe state) and
//! the per-period step (`step`: decode and check the frame, estimate, detect
//! lift-off, run the control law, saturate and encode, monitor deadlines, and
//! hold the safe state).

use shared::{Arm, ElbowBranch, kinematics::JointTrig, model::ArmTerms};

use crate::{
    belt_check::BeltMonitor,
    chatter::ChatterMonitor,
    config::Config,
    consistency::{ConsistencyMonitor, FrictionSignMonitor, InnovationMonitor},
    decode::EncoderScale,
    estimator::AngleTracker,
    liftoff::LiftOffDetector,
    reference::Quintic,
    runaway::{RunawayMonitor, RunawayRule},
    tracking::{TrackingMonitor, TrackingRule},
    wiring::{WiringMonitor, WiringRule},
};

mod lifecycle;
mod safe_reason;
mod step;
mod telemetry;

pub use safe_reason::SafeReason;
pub use telemetry::Telemetry;

#[derive(Debug, Clone, Copy)]
struct Started {
    seq0: u32,
    last_seq: u32,
    trackers: [AngleTracker; 2],
    quintic: Quintic,
    force_ramp: Quintic,
    branch: ElbowBranch,
    /// Sines and cosines of the trackers' angles as the last step left them: the
    /// next step's prediction starts from those angles (two `sin_cos` saved).
    trig: JointTrig<f32>,
}

/// The firmware's state across periods, running control law `L`: any
/// [`crate::ControlLaw`] (the paper's two are [`crate::PaperLaws`], made by
/// [`Firmware::new`]; another law by [`Firmware::with_law`]). Fixed size, no heap.
/// Its methods are in `lifecycle` and `step`; the struct names no law, so the
/// law's trait may name it (its sealed hook) without a cycle between files.
#[derive(Debug, Clone)]
pub struct Firmware<L> {
    cfg: Config,
    arm: Arm<f32>,
    /// The arm's constant factors, folded once per configuration (not every step).
    terms: ArmTerms<f32>,
    /// The encoders' count range and angle per count, derived once.
    scale: EncoderScale,
    started: Option<Started>,
    liftoff: LiftOffDetector,
    consistency: ConsistencyMonitor,
    innovation: InnovationMonitor,
    friction_sign: FrictionSignMonitor,
    /// The belt speed reading's plausibility ([`crate::belt_check`]).
    belt: BeltMonitor,
    /// The friction sign check's confirmation at this rate, periods.
    friction_confirm: u16,
    runaway: RunawayMonitor,
    /// The runaway limits at this rate, derived once.
    runaway_rule: RunawayRule,
    wiring: WiringMonitor,
    /// The wiring check at this rate, derived once.
    wiring_rule: WiringRule,
    tracking: TrackingMonitor,
    /// A law that chatters ([`crate::chatter`]).
    chatter: ChatterMonitor,
    /// The hybrid law's tracking check at this rate and gains, derived once.
    tracking_rule: TrackingRule,
    /// The hybrid law's last disturbance bound `D`, m/s^2 ([`crate::tracking`]).
    disturbance: f32,
    /// The control law and its state.
    law: L,
    last_codes: [i16; 2],
    applied: [f32; 2],
    last_saturated: bool,
    consecutive_bad: u16,
    consecutive_misses: u16,
    overruns: u32,
    safe: Option<SafeReason>,
    telemetry: Telemetry,
    /// The period in seconds, `f32`, derived once from `cfg.period`.
    dt: f32,
    /// `1 / dt`, 1/s: the rate of a step that follows its predecessor (no gap).
    rate: f32,
    /// The friction estimate's filter gain per period, `mu_estimate::gain(dt)`.
    mu_gain: f32,
    /// `1 / move_time_s`, 1/s, for the first frame's move.
    move_rate: f32,
    /// The force ramp's duration (`force_ramp_s`, at least 1 ns), s, and its inverse, 1/s.
    ramp: (f32, f32),
    /// The observer's gains for `cfg` (at angle 0): the first frame's trackers
    /// start from it, so no step pays for the `expf` of the gains.
    tracker: AngleTracker,
}
