//! The plant simulator: the arm on the moving belt as an event-driven hybrid
//! system (docs/model.md; paper eqs. 1 to 7), in `f64`.
//!
//! Modes: flight, sliding (`f_n = -b/p`, Coulomb friction opposing the slip),
//! sticking (`z_r_dot = 0`, `f = -Q^-1 a_free` while `|f_t| <= mu f_n`). Each
//! mode is a smooth ODE integrated by DOP853, the Dormand-Prince 8(5,3) method of
//! Hairer, Nørsett and Wanner ("Solving Ordinary Differential Equations I",
//! sec. II.10; [`dop853`], allocation-free on the fixed-size state): its 7th-order
//! dense output locates events two orders more accurately than Dormand-Prince
//! 5(4)'s. The events that end a mode are located on the dense output by a
//! bracketing root search ([`segment::EventLocator`], to 1e-14 s + 1e-15 |t|):
//! touchdown (`z_n = -H`), lift-off (`f_n` reaching 0, i.e. `b = 0` while sliding),
//! `p` reaching 0 while sliding, slip-to-stick (`z_r_dot = 0`), stick-to-slip
//! (`|f_t| = mu f_n`).
//!
//! Discrete transitions:
//! - touchdown: an impact ([`impact::touchdown`]); the tip flies off again if its
//!   normal velocity after the impact exceeds `zeno_velocity`, otherwise the bounce
//!   sequence is ended (*Zeno rule*: the remaining normal velocity is removed, a
//!   completely inelastic last impact, and the tip stays in contact);
//! - in contact with `z_n_dot = 0` the mode follows docs/model.md's table; the
//!   indeterminate case resolves to flight; the inconsistent case (the Painlevé
//!   paradox) is an impact without collision ([`impact::without_collision`]);
//! - every impact is checked for energy: the contact may never create energy
//!   (the work of the impulse on the tip's motion relative to the belt must be
//!   `<= 0`; the arm's kinetic energy itself may grow, fed by the moving belt);
//!   a violation is reported as an [`EventKind::EnergyGain`] event and counted.
//!
//! In contact the state is projected back onto the constraint (`z_n = -H` at the
//! same `z_t` and elbow branch, `z_n_dot = 0`, and `z_r_dot = 0` in sticking) at
//! the end of every segment, so integration error cannot drift the tip into or
//! off the belt.
//!
//! Slip from rest (after slip-to-stick fails or at stick-to-slip) goes in a
//! *consistent* direction: one whose sliding solution accelerates the slip that
//! way, preferring the direction the sticking force points to.
//!
//! Corner case: at rest relative to the belt with no consistent contact force
//! (sticking force outside the cone and no consistent slip, the tip pressed on the
//! belt), or when the contact mode keeps switching at one instant (slip starting
//! and stopping at once because the slip acceleration is zero to rounding), the tip
//! is held stuck with the cone ignored until lift-off or the end of the current
//! `advance` interval, then the contact problem is solved again; one
//! [`EventKind::ConeViolation`] is reported per episode.
#![warn(missing_docs)]

pub mod dop853;
pub mod impact;
pub mod initial;
pub mod observer;
pub mod segment;
pub mod trig;
pub mod validity;

use std::cell::Cell;

use nalgebra::Vector2;
use serde::Serialize;
use shared::{
    Arm, ContactMode, ElbowBranch, IkError, ParamError, Params, SlipDirection,
    contact::{classify_slipping, sliding_force, sticking_is_consistent},
    kinematics::{inverse_kinematics, jacobian_trig, tip_position_trig},
    model::TipDynamics,
};

use dop853::Dop853;
use impact::{ImpactError, ImpactLaw, Impulse, IwcRule, Resolution};
pub use observer::{NoObserver, Observer};
pub use segment::Phase;
use segment::{Boundary, EventLocator, OdeState, Point, Segment};
use trig::TrigCache;
pub use validity::Validity;

/// A torque law the plant evaluates inside the integration.
///
/// The zero-order hold of a sampled controller is [`Hold`]; the paper's ideal
/// setting (a continuous-time controller with exact measurements) implements this
/// trait directly, with up to two internal states `xi` (e.g. integrators)
/// integrated alongside the plant.
pub trait Controller {
    /// Motor torques `[u1, u2]` (N m, base joint and elbow) at time `t` (s), plant state
    /// `x = [theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s) and internal states
    /// `xi`; writes `d xi / dt` into `xi_dot` (left zero for a stateless law).
    ///
    /// The contact force depends on the torque (through `b`), so a law that needs
    /// it computes it from the shared model itself (`shared::contact`).
    fn torque(&self, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2];

    /// As [`Controller::torque`], told the contact phase the plant integrates in
    /// (flight, sliding in a direction, or sticking): what a law with exact contact
    /// measurements knows (e.g. the paper's hybrid law, whose friction term is the
    /// true `f_t`, zero in flight). The plant always calls this one; the default
    /// ignores the phase.
    fn torque_in(&self, phase: Phase, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        let _ = phase;
        self.torque(t, x, xi, xi_dot)
    }

    /// The torques `[u1, u2]` (N m) if this law holds them constant over the
    /// interval (a zero-order hold, [`Hold`]), for [`Plant::advance`]'s check.
    fn held(&self) -> Option<[f64; 2]> {
        None
    }
}

/// Zero-order hold: motor torques `[u1, u2]` (N m) held constant over the interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hold(pub [f64; 2]);

impl Controller for Hold {
    #[inline]
    fn torque(&self, _t: f64, _x: &[f64; 4], _xi: &[f64; 2], _xi_dot: &mut [f64; 2]) -> [f64; 2] {
        self.0
    }

    fn held(&self) -> Option<[f64; 2]> {
        Some(self.0)
    }
}

/// Numerical and modelling settings of the simulator (scenario parameters).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Relative tolerance of the integrator (DOP853, [`dop853::Dop853::rtol`]).
    pub rtol: f64,
    /// Absolute tolerance of the integrator (rad, rad/s; [`dop853::Dop853::atol`]).
    pub atol: f64,
    /// Impact law at touchdown and for impacts without collision.
    pub impact_law: ImpactLaw,
    /// Restitution coefficient `e_n` in [0, 1] (Newton's, Poisson's or Stronge's energetic
    /// coefficient, per `impact_law`).
    pub e_n: f64,
    /// What an impact without collision leaves behind ([`impact::IwcRule`]).
    pub iwc: IwcRule,
    /// Relative tangential speed (m/s) below which the tip counts as at rest on the belt.
    pub v_stick: f64,
    /// Zeno rule: a bounce whose normal velocity after impact is below this (m/s)
    /// ends the bounce sequence; the tip stays in contact.
    pub zeno_velocity: f64,
    /// Baumgarte stabilisation rate of the contact constraint in sliding and
    /// sticking, rad/s (Baumgarte 1972; 0 disables it). The correction vanishes on
    /// the constraint, so it changes the contact force only by the drift it removes.
    pub baumgarte: f64,
    /// Events allowed in one `advance` before it fails with [`SimError::EventStorm`]
    /// (a guard against a hang; never reached in normal runs).
    pub max_events_per_advance: usize,
    /// Integrator steps allowed in one smooth segment.
    pub max_steps: usize,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            rtol: 1e-9,
            atol: 1e-11,
            impact_law: ImpactLaw::Newton,
            e_n: 0.2,
            iwc: IwcRule::Restitution,
            v_stick: 1e-9,
            zeno_velocity: 1e-4,
            baumgarte: 50.0,
            max_events_per_advance: 100_000,
            max_steps: 100_000_000,
        }
    }
}

impl SimConfig {
    /// Checks ranges: tolerances finite and in (0, 0.1]; `e_n` in [0, 1];
    /// `v_stick`, `zeno_velocity` finite and >= 0; limits > 0.
    ///
    /// # Errors
    /// [`SimError::BadConfig`] naming the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |name: &'static str, value: f64, expected: &'static str| Err(SimError::BadConfig { name, value, expected });
        for (name, v) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(v.is_finite() && (1e-14..=0.1).contains(&v)) {
                return bad(name, v, "a value in [1e-14, 0.1] (below 1e-14 a step cannot meet it in f64)");
            }
        }
        if !(self.e_n.is_finite() && (0.0..=1.0).contains(&self.e_n)) {
            return bad("e_n", self.e_n, "a value in [0, 1]");
        }
        for (name, v) in [("v_stick", self.v_stick), ("zeno_velocity", self.zeno_velocity), ("baumgarte", self.baumgarte)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, v, "a finite value >= 0");
            }
        }
        if self.max_events_per_advance == 0 || self.max_steps == 0 {
            return bad("max_events_per_advance/max_steps", 0.0, "a positive count");
        }
        Ok(())
    }
}

/// Errors of the plant simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A physical parameter is out of range.
    #[error(transparent)]
    Params(#[from] ParamError),
    /// A simulator setting is out of range.
    #[error("setting `{name}` = {value} is out of range: expected {expected}")]
    BadConfig {
        /// Field of [`SimConfig`].
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// The initial state is not finite.
    #[error("initial state {0:?} is not finite")]
    NonFiniteInitialState([f64; 4]),
    /// The initial state is finite but not a state of the arm: an angle beyond
    /// [`MAX_ANGLE`] or a rate beyond [`MAX_RATE`].
    #[error(
        "initial state {0:?} (rad, rad/s) is not a state of the arm: angles within +-{MAX_ANGLE} rad (10 turns), rates within +-{MAX_RATE} rad/s"
    )]
    NonPhysicalInitialState([f64; 4]),
    /// The initial tip position is below the belt by more than the projection tolerance.
    #[error(
        "initial tip is {depth_mm:.3} mm below the belt (z_n = {z_n:.6} m, belt at -H = {belt:.6} m); at most {tolerance_mm} mm is projected onto it"
    )]
    BelowBelt {
        /// Penetration, mm.
        depth_mm: f64,
        /// Tip normal position, m.
        z_n: f64,
        /// Belt height `-H`, m.
        belt: f64,
        /// Largest penetration projected onto the belt, mm.
        tolerance_mm: f64,
    },
    /// A tip position has no inverse kinematics.
    #[error(transparent)]
    Unreachable(#[from] IkError),
    /// A time step is negative or not finite.
    #[error("time step {0} s must be finite and >= 0")]
    BadStep(f64),
    /// A torque is not finite.
    #[error("torque {0:?} N m is not finite")]
    BadTorque([f64; 2]),
    /// The integrator failed.
    #[error("integrator failed at t = {t} s: {message}")]
    Integrator {
        /// Time, s.
        t: f64,
        /// The integrator's message.
        message: String,
    },
    /// The state became NaN or infinite.
    #[error("state is not finite at t = {t} s (mode {mode})")]
    NonFinite {
        /// Time, s.
        t: f64,
        /// Mode at the time.
        mode: &'static str,
    },
    /// An impact could not be resolved.
    #[error("impact at t = {t} s: {source}")]
    Impact {
        /// Time, s.
        t: f64,
        /// Why.
        source: ImpactError,
    },
    /// A segment ended outside its mode without the event being located, even with small steps.
    #[error("event missed at t = {t} s in mode {mode}: the segment left its domain between steps")]
    MissedEvent {
        /// Start of the segment, s.
        t: f64,
        /// The mode.
        mode: &'static str,
    },
    /// Too many events in one `advance` (a hang guard).
    #[error("more than {count} events in one interval at t = {t} s: accumulating events the Zeno rule did not end (last: {recent})")]
    EventStorm {
        /// Time, s.
        t: f64,
        /// The limit.
        count: usize,
        /// The last few events, for diagnosis.
        recent: String,
    },
}

impl SimError {
    /// Whether the run failed in the integrator or the event handling (as opposed
    /// to bad input): counted as [`Validity::integrator_failures`].
    pub fn is_integrator_failure(&self) -> bool {
        matches!(
            self,
            Self::Integrator { .. } | Self::NonFinite { .. } | Self::Impact { .. } | Self::MissedEvent { .. } | Self::EventStorm { .. }
        )
    }

    /// Whether the error comes from the caller's input (parameters, settings,
    /// initial state), as opposed to a failure during the run.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            Self::Params(_)
                | Self::BadConfig { .. }
                | Self::NonFiniteInitialState(_)
                | Self::NonPhysicalInitialState(_)
                | Self::BelowBelt { .. }
                | Self::Unreachable(_)
                | Self::BadStep(_)
                | Self::BadTorque(_)
        )
    }
}

/// What happened at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventKind {
    /// The tip reached the belt with normal velocity `v_n_before < 0` and an impact followed.
    Touchdown,
    /// The normal reaction vanished; the tip leaves the belt.
    LiftOff,
    /// `p` reached 0 while sliding with `b < 0` (the reaction would grow without bound).
    PZero,
    /// An impact without collision from an inconsistent sliding state.
    ImpactWithoutCollision,
    /// The slip stopped and the tip sticks to the belt.
    SlipToStick,
    /// The slip stopped and resumed the other way.
    SlipReversal,
    /// The friction force reached the cone's edge; the tip starts to slip.
    StickToSlip,
    /// The Zeno rule ended a bounce sequence (or a grazing touchdown): the tip stays in contact.
    ZenoEnded,
    /// An impact created energy at the contact (positive contact work; reported, not corrected).
    EnergyGain,
    /// At rest on the belt with no consistent contact force (see the module docs).
    ConeViolation,
}

impl EventKind {
    /// snake_case name, as in `events.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Touchdown => "touchdown",
            Self::LiftOff => "lift_off",
            Self::PZero => "p_zero",
            Self::ImpactWithoutCollision => "impact_without_collision",
            Self::SlipToStick => "slip_to_stick",
            Self::SlipReversal => "slip_reversal",
            Self::StickToSlip => "stick_to_slip",
            Self::ZenoEnded => "zeno_ended",
            Self::EnergyGain => "energy_gain",
            Self::ConeViolation => "cone_violation",
        }
    }
}

/// An event with its exact time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlantEvent {
    /// Time, s.
    pub t: f64,
    /// What happened.
    pub kind: EventKind,
    /// Mode after the event.
    pub mode_after: ContactMode,
    /// Tip normal velocity before the event, m/s.
    pub v_n_before: f64,
    /// Tip normal velocity after the event, m/s.
    pub v_n_after: f64,
    /// Relative tangential velocity before the event, m/s.
    pub v_r_before: f64,
    /// Relative tangential velocity after the event, m/s.
    pub v_r_after: f64,
    /// Impulse `[P_t, P_n]` (N s) if the event is an impact, else zero.
    pub impulse: [f64; 2],
    /// Change of the arm's kinetic energy across the event, J (0 if not an impact;
    /// may be positive: the moving belt can feed the arm).
    pub energy_change: f64,
    /// Work of the contact impulse on the relative motion, J (<= 0 for an admissible
    /// impact; see [`impact::Impulse::contact_work`]).
    pub contact_work: f64,
    /// How the impulse was obtained, for impacts.
    pub resolution: Option<Resolution>,
}

/// Counts of events since the plant was created.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Counters {
    /// Lift-offs (the tip leaving the belt after being in contact, including after an IWC or a bounce).
    pub lift_offs: u64,
    /// Touchdowns with an impact.
    pub touchdowns: u64,
    /// Touchdowns after which the tip flew off again at once (a bounce: the tip
    /// leaves the belt without a `lift_offs` event).
    pub bounces: u64,
    /// Impacts without collision.
    pub impacts_without_collision: u64,
    /// Times `p` reached 0 while sliding.
    pub p_zero: u64,
    /// Sticking phases entered.
    pub stick_phases: u64,
    /// Stick-to-slip transitions.
    pub stick_to_slip: u64,
    /// Slip reversals.
    pub slip_reversals: u64,
    /// Bounce sequences ended by the Zeno rule: a touchdown that left (or arrived
    /// with) a normal velocity below `zeno_velocity` but above rounding, removed.
    pub zeno_stops: u64,
    /// Impacts whose contact work was positive (energy created at the contact):
    /// 0 unless an impact law is broken, since the laws fall back to the energetic one.
    pub energy_gains: u64,
    /// Newton impacts whose impulse would have created energy, resolved by the
    /// energetic law instead ([`impact::Resolution::NewtonFallback`]).
    pub newton_fallbacks: u64,
    /// Poisson impacts whose impulse would have created energy, resolved by the
    /// energetic law instead ([`impact::Resolution::PoissonFallback`]).
    pub poisson_fallbacks: u64,
    /// Largest positive contact work in one impact, J.
    pub max_energy_gain: f64,
    /// Cone violations (module docs).
    pub cone_violations: u64,
    /// Smooth segments integrated.
    pub segments: u64,
}

/// What `advance` reports about one interval.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepReport {
    /// Time at the end of the interval, s.
    pub t: f64,
    /// Contact mode at the end.
    pub mode: ContactMode,
    /// State `[theta1, theta1_dot, theta2, theta2_dot]` at the end (rad, rad/s).
    pub x: [f64; 4],
    /// Contact force `[f_t, f_n]` at the end (N), under the interval's torque.
    pub f: [f64; 2],
    /// Events in the interval, in time order.
    pub events: Vec<PlantEvent>,
}

/// Why a contact mode is being (re)chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Entry {
    /// The initial state, or a tip that reached the belt with no normal velocity.
    Settle,
    /// After a touchdown (an impact that left the tip on the belt, or a grazing
    /// contact): a departure is a lift-off.
    Landed,
    /// Sliding reached `z_r_dot = 0`.
    SlipStopped,
    /// Sticking reached the cone's edge.
    ConeEdge,
}

/// The simulated arm on the belt.
#[derive(Debug, Clone)]
pub struct Plant {
    arm: Arm<f64>,
    cfg: SimConfig,
    t: f64,
    y: OdeState,
    phase: Phase,
    cone_relaxed: bool,
    in_violation: bool,
    /// First step of the next solve, s: the step the controller proposed last.
    last_h: f64,
    evals: Cell<u64>,
    /// Sines and cosines of the joint angles, reused between nearby evaluations.
    trig: TrigCache,
    solver: Dop853,
    counters: Counters,
    startup_events: Vec<PlantEvent>,
    /// The model at the end of the last interval under a held torque (see [`EndPoint`]).
    end_point: Option<EndPoint>,
}

/// What [`Plant::advance`] changes in a plant: a plant restored to it
/// ([`Plant::restore`]) goes on exactly as from the instant it was taken
/// ([`Plant::checkpoint`]), counters and the model's caches included.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    t: f64,
    y: OdeState,
    phase: Phase,
    cone_relaxed: bool,
    in_violation: bool,
    last_h: f64,
    evals: u64,
    trig: TrigCache,
    counters: Counters,
    end_point: Option<EndPoint>,
}

/// The model at the end of an interval, under the held torque `u` (N m) of that
/// interval: the report's contact force came from it, and the next interval, when
/// it starts from the same time, state and mode under the same held torque (the
/// first part of the next control period holds the last command), starts from it
/// instead of evaluating the model again. The values are those a new evaluation
/// would give, to the bit: the model is a function of these keys (the sine and
/// cosine cache gives the same values for the same angles, whatever happened in
/// between at those angles).
#[derive(Debug, Clone, Copy)]
struct EndPoint {
    t: f64,
    y: OdeState,
    u: [f64; 2],
    phase: Phase,
    cone_relaxed: bool,
    point: Point,
}

/// The end of one solve: time, state, boundary hit, event function at the last
/// accepted point, and the tracked maxima (see `Plant::solve_segment`).
type SegmentEnd = (f64, OdeState, Option<Boundary>, f64);

/// Events at one instant after which the contact is held stuck (module docs, corner case).
const STALL_LIMIT: usize = 16;

/// Rounding slack on the (dimensionless) event components at the start of a segment.
const START_SLACK: f64 = 1e-12;

/// Largest initial joint angle magnitude, rad (10 turns): beyond it the state is refused.
pub const MAX_ANGLE: f64 = 20.0 * std::f64::consts::PI;

/// Largest initial joint rate magnitude, rad/s.
pub const MAX_RATE: f64 = 1e3;

/// Largest initial penetration of the tip into the belt that is projected onto it, m.
pub const PROJECTION_TOLERANCE: f64 = 1e-3;

impl Plant {
    /// A plant at time `t0` (s) in state `x0 = [theta1, theta1_dot, theta2, theta2_dot]`
    /// (rad, rad/s), under motor torques `u0` (N m) for choosing the initial mode.
    ///
    /// A tip up to [`PROJECTION_TOLERANCE`] inside the belt is projected onto it (same
    /// `z_t`, same elbow branch); on the belt the normal velocity decides: approaching
    /// gives an impact, separating gives flight, zero gives the contact mode of docs/model.md.
    ///
    /// # Errors
    /// [`SimError::Params`], [`SimError::BadConfig`], [`SimError::NonFiniteInitialState`],
    /// [`SimError::BelowBelt`], [`SimError::Unreachable`], or an impact failure.
    pub fn new(params: Params<f64>, cfg: SimConfig, x0: [f64; 4], t0: f64, u0: [f64; 2]) -> Result<Self, SimError> {
        params.validate()?;
        cfg.validate()?;
        if !x0.iter().all(|v| v.is_finite()) || !t0.is_finite() {
            return Err(SimError::NonFiniteInitialState(x0));
        }
        // Finite but not a state of the arm: angles beyond a few turns lose their
        // precision in f64 trigonometry, and rates beyond this are no motion of it.
        if x0[0].abs() > MAX_ANGLE || x0[2].abs() > MAX_ANGLE || x0[1].abs() > MAX_RATE || x0[3].abs() > MAX_RATE {
            return Err(SimError::NonPhysicalInitialState(x0));
        }
        if !u0.iter().all(|v| v.is_finite()) {
            return Err(SimError::BadTorque(u0));
        }
        let mut plant = Self {
            arm: Arm::new(params),
            cfg,
            t: t0,
            y: [x0[0], x0[1], x0[2], x0[3], 0.0, 0.0],
            phase: Phase::Flight,
            cone_relaxed: false,
            in_violation: false,
            last_h: 2e-4,
            evals: Cell::new(0),
            trig: TrigCache::new(),
            solver: Dop853 { max_steps: cfg.max_steps, ..Dop853::new(cfg.rtol, cfg.atol) },
            counters: Counters::default(),
            startup_events: Vec::new(),
            end_point: None,
        };
        let z = plant.tip();
        let belt = -params.h;
        let depth = belt - z[1];
        if depth > PROJECTION_TOLERANCE {
            return Err(SimError::BelowBelt { depth_mm: depth * 1e3, z_n: z[1], belt, tolerance_mm: PROJECTION_TOLERANCE * 1e3 });
        }
        if depth >= -1e-12 {
            plant.project_position()?;
            let ctrl = Hold(u0);
            let mut events = Vec::new();
            plant.touch(&ctrl, &mut events, true)?;
            plant.startup_events = events;
        }
        Ok(plant)
    }

    /// Events at `t0` while the initial mode was chosen (e.g. an impact without
    /// collision from an inconsistent initial state), in order.
    pub fn startup_events(&self) -> &[PlantEvent] {
        &self.startup_events
    }

    /// The arm (its parameters and model).
    pub fn arm(&self) -> &Arm<f64> {
        &self.arm
    }

    /// The simulator settings.
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Current state `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s).
    pub fn state(&self) -> [f64; 4] {
        [self.y[0], self.y[1], self.y[2], self.y[3]]
    }

    /// Internal states of a continuous-time controller (see [`Controller`]).
    pub fn controller_state(&self) -> [f64; 2] {
        [self.y[4], self.y[5]]
    }

    /// Sets the internal states of a continuous-time controller.
    pub fn set_controller_state(&mut self, xi: [f64; 2]) {
        self.y[4..6].copy_from_slice(&xi);
    }

    /// Current contact mode (flight, sliding or sticking).
    pub fn mode(&self) -> ContactMode {
        match self.phase {
            Phase::Flight => ContactMode::Flight,
            Phase::Sliding(_) => ContactMode::Sliding,
            Phase::Sticking => ContactMode::Sticking,
        }
    }

    /// The phase the integrator runs in (the contact mode with its slip direction).
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Slip direction while sliding.
    pub fn slip_direction(&self) -> Option<SlipDirection> {
        match self.phase {
            Phase::Sliding(d) => Some(d),
            _ => None,
        }
    }

    /// Tip position `[z_t, z_n]`, m.
    pub fn tip(&self) -> Vector2<f64> {
        tip_position_trig(self.arm.params.l, &self.trig.get(&Vector2::new(self.y[0], self.y[2])))
    }

    /// Tip velocity `[z_t_dot, z_n_dot]`, m/s.
    pub fn tip_velocity(&self) -> Vector2<f64> {
        let (q, qd) = segment::split(&self.y);
        jacobian_trig(self.arm.params.l, &self.trig.get(&q)) * qd
    }

    /// Contact force `[f_t, f_n]` (N) in the current mode under motor torques `u` (N m).
    pub fn contact_force(&self, u: [f64; 2]) -> [f64; 2] {
        self.contact_force_with(&Hold(u))
    }

    /// Contact force `[f_t, f_n]` (N) in the current mode under the torque law `ctrl`
    /// (evaluated at the current time, state and controller states).
    pub fn contact_force_with<C: Controller + ?Sized>(&self, ctrl: &C) -> [f64; 2] {
        let (_, f, _) = self.segment(ctrl).evaluate(self.t, &self.y, &mut [0.0; 2]);
        [f[0], f[1]]
    }

    /// Mechanical energy (kinetic + gravity + spring), J.
    pub fn energy(&self) -> f64 {
        let (q, qd) = segment::split(&self.y);
        self.arm.kinetic_energy(&q, &qd) + self.arm.potential_energy(&q)
    }

    /// Event counts since creation.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// The validity counters since creation, for a run that ended with `failure`.
    pub fn validity(&self, failure: Option<&SimError>) -> Validity {
        Validity::of(&self.counters, failure)
    }

    /// Evaluations of the vector field since creation (a cost measure).
    pub fn rhs_evaluations(&self) -> u64 {
        self.evals.get()
    }

    /// The plant's state now, to go back to with [`Plant::restore`] (e.g. after
    /// advancing ahead of a decision that turned out otherwise).
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            t: self.t,
            y: self.y,
            phase: self.phase,
            cone_relaxed: self.cone_relaxed,
            in_violation: self.in_violation,
            last_h: self.last_h,
            evals: self.evals.get(),
            trig: self.trig.clone(),
            counters: self.counters,
            end_point: self.end_point,
        }
    }

    /// Goes back to `c`, a [`Plant::checkpoint`] of this plant: what follows is
    /// bit for bit what would have followed the checkpoint.
    pub fn restore(&mut self, c: Checkpoint) {
        let Checkpoint { t, y, phase, cone_relaxed, in_violation, last_h, evals, trig, counters, end_point } = c;
        (self.t, self.y, self.phase, self.cone_relaxed, self.in_violation, self.last_h) = (t, y, phase, cone_relaxed, in_violation, last_h);
        self.evals.set(evals);
        (self.trig, self.counters, self.end_point) = (trig, counters, end_point);
    }

    /// Advances by `dt` (s) under the torque law `ctrl`: [`Hold`]`(u)` for the
    /// motor torques `u = [u1, u2]` (N m) held constant (zero-order hold, as a
    /// sampled controller drives the arm), or a law evaluated inside the
    /// integration (the paper's continuous-time setting; the report's force then
    /// uses the law's torque at the end of the interval). `obs` sees the
    /// trajectory: every accepted step with its dense output, the start of each
    /// smooth segment, the events ([`Observer`]; [`NoObserver`] for none).
    ///
    /// # Errors
    /// [`SimError::BadStep`], [`SimError::BadTorque`] (a held torque that is not
    /// finite), or a failure during the interval (the plant is then left at the
    /// failure time).
    pub fn advance<C: Controller + ?Sized>(&mut self, ctrl: &C, dt: f64, obs: &mut dyn Observer) -> Result<StepReport, SimError> {
        let events = self.advance_events(ctrl, dt, obs)?;
        let f = match self.phase {
            Phase::Flight => [0.0, 0.0],
            _ => {
                let seg = self.segment(ctrl);
                let f = match ctrl.held() {
                    // Kept for the next interval's start (see `EndPoint`); counted when used there.
                    Some(u) => {
                        let point = seg.point_uncounted(self.t, &self.y);
                        let (t, y, phase, cone_relaxed) = (self.t, self.y, self.phase, self.cone_relaxed);
                        self.end_point = Some(EndPoint { t, y, u, phase, cone_relaxed, point });
                        point.f
                    }
                    None => seg.evaluate(self.t, &self.y, &mut [0.0; 2]).1,
                };
                [f[0], f[1]]
            }
        };
        Ok(StepReport { t: self.t, mode: self.mode(), x: self.state(), f, events })
    }

    /// [`Plant::advance`] without its report: the events of the interval only, in
    /// time order (the contact force at its end is not evaluated: the SIL loop's
    /// first part of a period, up to the zero-order-hold switch, needs only these).
    ///
    /// # Errors
    /// As [`Plant::advance`].
    pub fn advance_events<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        dt: f64,
        obs: &mut dyn Observer,
    ) -> Result<Vec<PlantEvent>, SimError> {
        // Kept only for an interval that starts where it was made.
        let end_point = self.end_point.take();
        if let Some(u) = ctrl.held()
            && !u.iter().all(|v| v.is_finite())
        {
            return Err(SimError::BadTorque(u));
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(SimError::BadStep(dt));
        }
        let t_end = self.t + dt;
        let mut events: Vec<PlantEvent> = Vec::new();
        let mut handled = 0usize;
        // Zero-time loops: mode changes that follow each other without time passing.
        let (mut stall_t, mut stalled) = (f64::NAN, 0usize);
        loop {
            let remaining = t_end - self.t;
            if remaining <= 1e-13 * t_end.abs().max(1.0) {
                self.t = t_end;
                break;
            }
            if handled > self.cfg.max_events_per_advance {
                let recent = events
                    .iter()
                    .rev()
                    .take(6)
                    .rev()
                    .map(|e: &PlantEvent| format!("{} at {:.12} s", e.kind.name(), e.t))
                    .collect::<Vec<String>>()
                    .join(", ");
                return Err(SimError::EventStorm { t: self.t, count: self.cfg.max_events_per_advance, recent });
            }
            // A mode must start inside its domain (up to rounding: a slip starting from
            // rest has s v_r = +-1e-16), or it ends at once. One model evaluation gives
            // the event function and the integrator's first stage.
            let (start, (boundary, g0)) = {
                let seg = self.segment(ctrl);
                let start = match &end_point {
                    Some(e) if self.starts_from(e, ctrl) => {
                        seg.count_evaluation();
                        e.point
                    }
                    _ => seg.point(self.t, &self.y),
                };
                let nb = segment::nearest(seg.components_of(&start.td, &start.f));
                (start, nb)
            };
            if (g0 < -START_SLACK && self.phase != Phase::Flight) || self.flight_starts_into_belt(&start.td) {
                if self.note_stall(&mut stall_t, &mut stalled, &mut events)? {
                    handled += 1;
                    continue;
                }
                self.cross(ctrl, boundary, &mut events)?;
                handled += 1;
                continue;
            }
            // A relaxed (cone-violating) stick lasts at most to the end of this interval.
            let seg_end = t_end;
            obs.on_segment_start(self.t, &self.y, self.mode());
            let hit = self.integrate(ctrl, seg_end, &start, g0, obs)?;
            self.counters.segments += 1;
            match hit {
                Some(b) => {
                    if !self.note_stall(&mut stall_t, &mut stalled, &mut events)? {
                        self.cross(ctrl, b, &mut events)?;
                    }
                    handled += 1;
                }
                None => {
                    self.t = t_end;
                    self.project_contact()?;
                    // Solve the contact problem afresh next interval.
                    if self.cone_relaxed {
                        self.cone_relaxed = false;
                        self.in_violation = true;
                    }
                    break;
                }
            }
        }
        // The state after an impact at the very end of the interval belongs to no step.
        obs.on_advanced(self.t, &self.y);
        for e in &events {
            obs.on_event(e);
        }
        Ok(events)
    }

    /// Whether `e` is the model at the current time, state and mode under `ctrl`
    /// (a held torque equal to `e`'s, bit for bit).
    fn starts_from<C: Controller + ?Sized>(&self, e: &EndPoint, ctrl: &C) -> bool {
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
        ctrl.held().is_some_and(|u| same(u[0], e.u[0]) && same(u[1], e.u[1]))
            && same(e.t, self.t)
            && e.y.iter().zip(&self.y).all(|(a, b)| same(*a, *b))
            && e.phase == self.phase
            && e.cone_relaxed == self.cone_relaxed
    }

    /// Counts mode changes at one instant; after [`STALL_LIMIT`] of them in contact
    /// (slip starting and stopping at once: the slip acceleration is zero to
    /// rounding in both directions) holds the tip stuck, cone ignored, to the end of
    /// the interval (the documented corner case). Returns whether it did.
    fn note_stall(&mut self, stall_t: &mut f64, stalled: &mut usize, events: &mut Vec<PlantEvent>) -> Result<bool, SimError> {
        if (self.t - *stall_t).abs() <= 1e-12 * self.t.abs().max(1.0) {
            *stalled += 1;
        } else {
            (*stall_t, *stalled) = (self.t, 0);
        }
        if *stalled < STALL_LIMIT || self.phase == Phase::Flight {
            return Ok(false);
        }
        let before = self.rel_velocity();
        self.project_contact_velocity(true)?;
        self.phase = Phase::Sticking;
        self.cone_relaxed = true;
        self.enter_violation(events, before);
        (*stall_t, *stalled) = (f64::NAN, 0);
        Ok(true)
    }

    /// Flight starting on the belt with the tip not moving away (e.g. after `b`
    /// touched 0 without changing sign): the event detection cannot see a crossing
    /// from `z_n + H = 0`, so this is handled as a grazing touchdown at once. `td`:
    /// the tip dynamics at the current state.
    fn flight_starts_into_belt(&self, td: &TipDynamics<f64>) -> bool {
        if self.phase != Phase::Flight {
            return false;
        }
        let height = td.z[1] + self.arm.params.h;
        height <= 1e-12 && (td.z_dot[1] < -self.cfg.zeno_velocity || (td.z_dot[1] <= self.cfg.zeno_velocity && td.b() < 0.0))
    }

    fn segment<'a, C: Controller + ?Sized>(&'a self, ctrl: &'a C) -> Segment<'a, C> {
        Segment::new(&self.arm, self.phase, ctrl, self.cone_relaxed, self.cfg.baumgarte, &self.evals, &self.trig)
    }

    /// Integrates the current mode from `self.t` towards `t_end`; returns the
    /// boundary hit, if any (the state is then at the event). `start` is the model
    /// at the current state and `g0` the event function there.
    ///
    /// An event is detected as a sign change of the event function between two
    /// accepted steps, starting from its value at `t0`. A segment that starts
    /// on its boundary (flight right after a bounce: `z_n + H = 0`) would miss a
    /// return that fits inside the first step, so the first step is kept inside the
    /// hop (`h0 <= v_n / |b|`, half the ballistic hop time). As a last guard, a
    /// segment that ends outside its domain without an event is integrated again
    /// with steps capped at 1/64 of the interval and at most 1 ms, then 10 us, and
    /// fails if that still misses it.
    fn integrate<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        t_end: f64,
        start: &Point,
        g0: f64,
        obs: &mut dyn Observer,
    ) -> Result<Option<Boundary>, SimError> {
        let remaining = t_end - self.t;
        let mut h0 = self.last_h.min(remaining);
        if self.phase == Phase::Flight {
            let td = &start.td;
            let height = td.z[1] + self.arm.params.h;
            if height < 1e-9 && td.z_dot[1] > 0.0 && td.b() < 0.0 {
                h0 = h0.min(td.z_dot[1] / -td.b());
            }
        }
        // Retries cap the steps at 1/64 of the interval, and also at 1 ms then 10 us:
        // over a long interval (open-loop runs advance by seconds) 1/64 of it can
        // still hold a whole excursion out of the domain and back, e.g. a slip from
        // rest that stops again within milliseconds.
        for h_max in [f64::INFINITY, (remaining / 64.0).min(1e-3), (remaining / 64.0).min(1e-5)] {
            obs.on_attempt();
            let (t1, y1, boundary, g_end) = self.solve_segment(ctrl, t_end, h0.min(h_max), h_max, start, g0, obs)?;
            if boundary.is_none() && g_end < -1e-9 {
                // Missed crossing: retry with capped steps.
                continue;
            }
            obs.on_kept(&y1, self.mode());
            self.t = t1;
            self.y = y1;
            return Ok(boundary);
        }
        Err(SimError::MissedEvent { t: self.t, mode: self.mode().name() })
    }

    /// One solve over `[self.t, t_end]`, stopping at the first event (the plant's
    /// state is left unchanged). Returns the end time and state, the boundary hit (if
    /// any), the event function at the last accepted point, and the tracked maxima
    /// updated over the solve (kept only if the solve is). A section `scan`, if
    /// given, sees every accepted step up to the event.
    #[allow(clippy::too_many_arguments)]
    fn solve_segment<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        t_end: f64,
        h0: f64,
        h_max: f64,
        start: &Point,
        g0: f64,
        obs: &mut dyn Observer,
    ) -> Result<SegmentEnd, SimError> {
        let solver = Dop853 { h_max, ..self.solver };
        let mode = self.mode();
        let seg = self.segment(ctrl);
        let mut locator = EventLocator { segment: &seg, g_prev: g0, hit: None };
        let solved = solver
            .solve(&seg, self.t, &self.y, Some(&start.dydt), t_end, h0, |step| {
                let control = locator.on_step(step);
                obs.on_step(step, locator.hit, mode);
                control
            })
            .map_err(|e| SimError::Integrator { t: self.t, message: e.to_string() })?;
        let (g_end, hit) = (locator.g_prev, locator.hit);
        self.last_h = solved.h_next;
        if let Some((t1, y1)) = hit {
            if !y1.iter().all(|v| v.is_finite()) {
                return Err(SimError::NonFinite { t: t1, mode: self.mode().name() });
            }
            let boundary = self.segment(ctrl).nearest_boundary(t1, &y1).0;
            return Ok((t1, y1, Some(boundary), 0.0));
        }
        if !solved.y.iter().all(|v| v.is_finite()) {
            return Err(SimError::NonFinite { t: t_end, mode: self.mode().name() });
        }
        Ok((t_end, solved.y, None, g_end))
    }

    /// Handles the crossing of a mode boundary at the current time.
    fn cross<C: Controller + ?Sized>(&mut self, ctrl: &C, boundary: Boundary, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        self.cone_relaxed = false;
        let result = self.cross_inner(ctrl, boundary, events);
        // An episode of cone violation ends when another mode is chosen.
        if !self.cone_relaxed {
            self.in_violation = false;
        }
        result
    }

    fn cross_inner<C: Controller + ?Sized>(&mut self, ctrl: &C, boundary: Boundary, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        match boundary {
            Boundary::Touchdown => {
                self.project_position()?;
                self.touch(ctrl, events, false)
            }
            Boundary::LiftOff => {
                let before = self.rel_velocity();
                self.phase = Phase::Flight;
                self.counters.lift_offs += 1;
                self.push_event(events, EventKind::LiftOff, before, None, 0.0);
                Ok(())
            }
            Boundary::PZero => {
                self.counters.p_zero += 1;
                let before = self.rel_velocity();
                self.push_event(events, EventKind::PZero, before, None, 0.0);
                self.project_contact()?;
                self.impact_without_collision(ctrl, events)
            }
            Boundary::SlipStops => {
                self.project_contact()?;
                self.enter_contact(ctrl, Entry::SlipStopped, events)
            }
            Boundary::ConeEdge => {
                self.project_contact()?;
                self.enter_contact(ctrl, Entry::ConeEdge, events)
            }
        }
    }

    /// The tip is on the belt (position projected): impact if approaching, flight if
    /// separating, otherwise choose the contact mode. `initial`: the plant's initial
    /// state (a departure from it is not a lift-off).
    fn touch<C: Controller + ?Sized>(&mut self, ctrl: &C, events: &mut Vec<PlantEvent>, initial: bool) -> Result<(), SimError> {
        let before = self.rel_velocity();
        let v_n = before[1];
        if v_n > self.cfg.zeno_velocity {
            self.phase = Phase::Flight;
            return Ok(());
        }
        if v_n < -self.cfg.zeno_velocity {
            let (q, _) = segment::split(&self.y);
            let qm = self.arm.q_matrix(&q);
            let imp = impact::touchdown(&qm, self.arm.params.mu, before[0], v_n, self.cfg.impact_law, self.cfg.e_n)
                .map_err(|source| SimError::Impact { t: self.t, source })?;
            let de = self.apply_impulse(&imp);
            self.counters.touchdowns += 1;
            let after = self.rel_velocity();
            if after[1] > self.cfg.zeno_velocity {
                self.phase = Phase::Flight;
                self.counters.bounces += 1;
                self.push_event(events, EventKind::Touchdown, before, Some(&imp), de);
                self.check_impact(events, &imp, &qm, de, before);
                return Ok(());
            }
            self.push_event(events, EventKind::Touchdown, before, Some(&imp), de);
            self.check_impact(events, &imp, &qm, de, before);
        }
        // Grazing contact or the end of a bounce sequence: remove what is left of
        // the normal velocity and stay on the belt. A residue at rounding level (a
        // plastic impact leaves ~1e-17 m/s) is removed without counting a Zeno stop.
        let residual = self.rel_velocity();
        let mut zeno = None;
        if residual[1] != 0.0 {
            let rounding = 1e-12 + 1e-9 * before.norm();
            if residual[1].abs() > rounding {
                self.counters.zeno_stops += 1;
                zeno = Some(events.len());
            }
            self.project_contact_velocity(false)?;
            if zeno.is_some() {
                self.push_event(events, EventKind::ZenoEnded, residual, None, 0.0);
            }
        }
        // A departure is a lift-off after a real arrival (an impact, or a residue the
        // Zeno rule removed); not from the initial state, nor after a zero-velocity
        // "touchdown" of a tip that never left the belt (flight starting into it).
        let landed = !initial && (v_n < -self.cfg.zeno_velocity || zeno.is_some());
        let entry = if landed { Entry::Landed } else { Entry::Settle };
        let chosen = self.enter_contact(ctrl, entry, events);
        // The Zeno event records the mode chosen after it.
        if let Some(i) = zeno {
            events[i].mode_after = self.mode();
        }
        chosen
    }

    /// Chooses the contact mode of a tip on the belt with `z_n_dot = 0` (docs/model.md's
    /// table, plus sticking), resolving the paradox by an impact without collision.
    fn enter_contact<C: Controller + ?Sized>(&mut self, ctrl: &C, entry: Entry, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        let was_sliding = matches!(self.phase, Phase::Sliding(_));
        let previous_dir = self.slip_direction();
        let before = self.rel_velocity();
        let mu = self.arm.params.mu;
        let at_rest = before[0].abs() <= self.cfg.v_stick || matches!(entry, Entry::SlipStopped | Entry::ConeEdge);
        if at_rest {
            // Start from exactly zero slip, so that the chosen mode starts inside its domain.
            self.project_contact_velocity(true)?;
        }
        self.phase = Phase::Sticking; // evaluate sticking forces
        let (td, f_stick, _) = self.segment(ctrl).evaluate(self.t, &self.y, &mut [0.0; 2]);
        let dir = if at_rest {
            if entry != Entry::ConeEdge && sticking_is_consistent(&f_stick, mu) {
                self.project_contact_velocity(true)?;
                self.phase = Phase::Sticking;
                self.counters.stick_phases += 1;
                self.push_event(events, EventKind::SlipToStick, before, None, 0.0);
                return Ok(());
            }
            // Slip from rest: a direction whose sliding solution accelerates the
            // slip that way (consistent), preferring the one the sticking force points to.
            let preferred = SlipDirection::of(-f_stick[0]);
            let consistent = |s: SlipDirection| {
                if !(td.p(mu, s) > 0.0 && td.b() < 0.0) {
                    return false;
                }
                let f = sliding_force(&td, mu, s);
                let acc = td.a_free[0] + td.qmat[(0, 0)] * f[0] + td.qmat[(0, 1)] * f[1];
                s.sign::<f64>() * acc > 0.0
            };
            // At the cone's edge the sliding force in the preferred direction equals the
            // sticking force, so the slip acceleration is exactly 0 there and its sign
            // comes from the trend: the edge is crossed, take that direction (standard
            // stick-to-slip) unless sliding that way is itself inconsistent (p <= 0).
            let edge = entry == Entry::ConeEdge && td.p(mu, preferred) > 0.0 && td.b() < 0.0;
            let choice = if edge { Some(preferred) } else { [preferred, preferred.reversed()].into_iter().find(|&s| consistent(s)) };
            match choice {
                Some(s) => s,
                None if td.b() < 0.0 => {
                    // Neither sticking nor slipping is consistent and the tip is pressed
                    // on the belt: hold it stuck for a short dwell, then re-evaluate.
                    self.project_contact_velocity(true)?;
                    self.phase = Phase::Sticking;
                    self.cone_relaxed = true;
                    self.enter_violation(events, before);
                    return Ok(());
                }
                None => preferred,
            }
        } else {
            SlipDirection::of(before[0])
        };
        match classify_slipping(td.b(), td.p(mu, dir)) {
            ContactMode::Sliding => {
                self.phase = Phase::Sliding(dir);
                match entry {
                    Entry::ConeEdge => {
                        self.counters.stick_to_slip += 1;
                        self.push_event(events, EventKind::StickToSlip, before, None, 0.0);
                    }
                    Entry::SlipStopped if was_sliding && previous_dir != Some(dir) => {
                        self.counters.slip_reversals += 1;
                        self.push_event(events, EventKind::SlipReversal, before, None, 0.0);
                    }
                    _ => {}
                }
                Ok(())
            }
            ContactMode::Flight | ContactMode::Indeterminate => {
                self.phase = Phase::Flight;
                if entry != Entry::Settle || was_sliding {
                    // Leaving the belt after a touchdown, a stop of the slip or from
                    // sliding: a lift-off (a departure from the initial state is not).
                    self.counters.lift_offs += 1;
                    self.push_event(events, EventKind::LiftOff, before, None, 0.0);
                }
                Ok(())
            }
            _ if !at_rest => {
                self.phase = Phase::Sliding(dir);
                self.impact_without_collision(ctrl, events)
            }
            _ => {
                // No slip to stop and no consistent force: documented corner case.
                self.project_contact_velocity(true)?;
                self.phase = Phase::Sticking;
                self.cone_relaxed = true;
                self.enter_violation(events, before);
                Ok(())
            }
        }
    }

    /// Starts (or continues) a cone-violating stick; reported once per episode.
    fn enter_violation(&mut self, events: &mut Vec<PlantEvent>, before: Vector2<f64>) {
        if !self.in_violation {
            self.in_violation = true;
            self.counters.cone_violations += 1;
            self.push_event(events, EventKind::ConeViolation, before, None, 0.0);
        }
    }

    /// The Painlevé resolution: an impact without collision from sliding.
    fn impact_without_collision<C: Controller + ?Sized>(&mut self, ctrl: &C, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        let before = self.rel_velocity();
        let (q, _) = segment::split(&self.y);
        let qm = self.arm.q_matrix(&q);
        let imp = impact::without_collision(&qm, self.arm.params.mu, before[0], self.cfg.impact_law, self.cfg.e_n, self.cfg.iwc)
            .map_err(|source| SimError::Impact { t: self.t, source })?;
        let de = self.apply_impulse(&imp);
        self.counters.impacts_without_collision += 1;
        let after = self.rel_velocity();
        if after[1] > self.cfg.zeno_velocity {
            self.phase = Phase::Flight;
            self.counters.lift_offs += 1;
            self.push_event(events, EventKind::ImpactWithoutCollision, before, Some(&imp), de);
            self.check_impact(events, &imp, &qm, de, before);
            return Ok(());
        }
        self.push_event(events, EventKind::ImpactWithoutCollision, before, Some(&imp), de);
        self.check_impact(events, &imp, &qm, de, before);
        self.project_contact_velocity(false)?;
        // The slip has been stopped (v_r = 0): choose stick or slip from rest.
        self.enter_contact(ctrl, Entry::SlipStopped, events)
    }

    /// Applies a tip impulse: `q_dot += M^-1 J^T P`; returns the kinetic energy change (J).
    fn apply_impulse(&mut self, imp: &Impulse) -> f64 {
        let (q, qd) = segment::split(&self.y);
        let before = self.arm.kinetic_energy(&q, &qd);
        let jac = shared::kinematics::jacobian(self.arm.params.l, &q);
        let dqd = self.arm.mass_matrix_inverse(&q) * (jac.transpose() * imp.p);
        self.y[1] += dqd[0];
        self.y[3] += dqd[1];
        let (q, qd) = segment::split(&self.y);
        self.arm.kinetic_energy(&q, &qd) - before
    }

    /// Counts a law's fallback to the energetic one, and reports an impact whose
    /// contact work is positive (it created energy: a broken law, never expected).
    fn check_impact(&mut self, events: &mut Vec<PlantEvent>, imp: &Impulse, qm: &nalgebra::Matrix2<f64>, de: f64, before: Vector2<f64>) {
        match imp.resolution {
            Resolution::NewtonFallback => self.counters.newton_fallbacks += 1,
            Resolution::PoissonFallback => self.counters.poisson_fallbacks += 1,
            _ => {}
        }
        // The same rounding allowance the laws' fallback uses.
        if imp.contact_work > impact::work_tolerance(qm, before[0], before[1]) {
            self.counters.energy_gains += 1;
            self.counters.max_energy_gain = self.counters.max_energy_gain.max(imp.contact_work);
            events.push(self.make_event(EventKind::EnergyGain, before, Some(imp), de));
        }
    }

    /// `[z_r_dot, z_n_dot]`, m/s.
    fn rel_velocity(&self) -> Vector2<f64> {
        let v = self.tip_velocity();
        Vector2::new(v[0] - self.arm.params.v_belt, v[1])
    }

    fn make_event(&self, kind: EventKind, before: Vector2<f64>, imp: Option<&Impulse>, de: f64) -> PlantEvent {
        let after = self.rel_velocity();
        PlantEvent {
            t: self.t,
            kind,
            mode_after: self.mode(),
            v_n_before: before[1],
            v_n_after: after[1],
            v_r_before: before[0],
            v_r_after: after[0],
            impulse: imp.map_or([0.0; 2], |i| [i.p[0], i.p[1]]),
            energy_change: de,
            contact_work: imp.map_or(0.0, |i| i.contact_work),
            resolution: imp.map(|i| i.resolution),
        }
    }

    fn push_event(&self, events: &mut Vec<PlantEvent>, kind: EventKind, before: Vector2<f64>, imp: Option<&Impulse>, de: f64) {
        events.push(self.make_event(kind, before, imp, de));
    }

    /// Puts the tip exactly on the belt at the same `z_t` and elbow branch,
    /// keeping the angles on the same turn.
    ///
    /// The usual drift after an interval (well under a micrometre) is removed by one
    /// Newton step on `z(q) = [z_t, -H]`, whose error is quadratic in the step:
    /// with the step at most `1e-8` rad it is below rounding, the same result as
    /// the inverse kinematics (used otherwise) without its `acos` and `atan2`.
    fn project_position(&mut self) -> Result<(), SimError> {
        let (q, _) = segment::split(&self.y);
        let l = self.arm.params.l;
        let trig = self.trig.get(&q);
        let z = tip_position_trig(l, &trig);
        let gap = z[1] + self.arm.params.h;
        if gap == 0.0 {
            return Ok(());
        }
        // J dq = [0, -gap]: dq = J^-1 [0, -gap] (Cramer).
        let jac = jacobian_trig(l, &trig);
        let det = jac[(0, 0)] * jac[(1, 1)] - jac[(0, 1)] * jac[(1, 0)];
        let dq = [jac[(0, 1)] * gap / det, -jac[(0, 0)] * gap / det];
        if dq[0].abs().max(dq[1].abs()) <= 1e-8 {
            self.y[0] += dq[0];
            self.y[2] += dq[1];
            return Ok(());
        }
        let target = Vector2::new(z[0], -self.arm.params.h);
        let q_new = inverse_kinematics(l, &target, ElbowBranch::of(&q))?;
        let tau = std::f64::consts::TAU;
        self.y[0] = q_new[0] + tau * ((q[0] - q_new[0]) / tau).round();
        self.y[2] = q_new[1] + tau * ((q[1] - q_new[1]) / tau).round();
        Ok(())
    }

    /// Removes the constrained velocity components by the smallest kinetic-energy
    /// correction: `z_n_dot -> 0`, and `z_r_dot -> 0` too when `sticking`.
    fn project_contact_velocity(&mut self, sticking: bool) -> Result<(), SimError> {
        let (q, qd) = segment::split(&self.y);
        let trig = self.trig.get(&q);
        let jac = jacobian_trig(self.arm.params.l, &trig);
        let m_inv = self.arm.mass_matrix_inverse_trig(&trig);
        let qm = jac * m_inv * jac.transpose();
        let v = jac * qd;
        let lambda = if sticking {
            qm.try_inverse().map(|inv| inv * Vector2::new(self.arm.params.v_belt - v[0], -v[1])).unwrap_or_else(Vector2::zeros)
        } else {
            Vector2::new(0.0, -v[1] / qm[(1, 1)])
        };
        let dqd = m_inv * (jac.transpose() * lambda);
        self.y[1] += dqd[0];
        self.y[3] += dqd[1];
        Ok(())
    }

    /// Projection onto the contact constraint of the current mode (no-op in flight).
    fn project_contact(&mut self) -> Result<(), SimError> {
        match self.phase {
            Phase::Flight => Ok(()),
            Phase::Sliding(_) => {
                self.project_position()?;
                self.project_contact_velocity(false)
            }
            Phase::Sticking => {
                self.project_position()?;
                self.project_contact_velocity(true)
            }
        }
    }
}

#[cfg(test)]
mod tests;
