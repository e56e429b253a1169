//! The simulated arm on the belt ([`Plant`]): its state, construction, accessors
//! and checkpoints. Advancing it is in `advance` (the event loop and the smooth
//! segments), the mode changes at events in `transitions`, the projections onto
//! the contact constraint in `projection` (see the crate docs).

use std::cell::Cell;

use nalgebra::Vector2;
use shared::{
    Arm, ContactMode, Params, SlipDirection,
    kinematics::{JointTrig, jacobian_trig, tip_position_trig},
};

use crate::{
    bounds::{MAX_ANGLE, MAX_RATE, PROJECTION_TOLERANCE},
    config::SimConfig,
    controller::{Controller, Hold},
    dop853::Dop853,
    error::SimError,
    events::{Counters, PlantEvent},
    ledger::Ledger,
    phase::Phase,
    segment::{self, OdeState, Point, Segment},
    trig::TrigCache,
    validity::Validity,
};

mod advance;
pub(crate) mod bridge;
mod impulses;
mod integrate;
mod projection;
mod transitions;

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
    /// Sliding through the indeterminate region after a singular point under
    /// [`SingularRule::Slide`](crate::moreau_jean::SingularRule::Slide): time-stepped
    /// by bridges until the slide leaves it.
    time_stepping: bool,
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
    /// The instants [`Plant::advance_sampling`] samples, while it runs.
    sampling: Option<SampleGrid>,
    /// Whether the samples of [`Plant::advance_sampled`] (the SIL loop's look-ahead)
    /// are being taken: those come from the step's ends ([`crate::hermite`]), the
    /// others (`simulate`'s trace) from the 7th-order dense output.
    hermite_samples: bool,
    /// The energy ledger's entries that are not integrated with the state (its
    /// works are, `y[6..10]`; [`Plant::ledger`] puts them together).
    ledger: Ledger,
    /// The arm's energy at the start, J: the ledger's origin.
    e0: f64,
    /// A flight that leaves the singular point with the residue of `b` (a few
    /// 1e-10 m/s^2 either side of 0) taken as 0: its start is not a grazing
    /// touchdown (docs/plant.md "The singular point").
    departing: bool,
    /// The current slide's normal force on its approach to `p = 0`, N
    /// ([`crate::segment::EventLocator::trend`]), kept from one solve to the
    /// next while the slide goes on (an interval's end can fall in the approach).
    slide_trend: Option<crate::segment::Trend>,
    /// The energy and the sines and cosines at one arm state, for where that state
    /// is met again ([`Known`]).
    known: Option<Known>,
    /// A velocity projection at an event too small for a row of its own (at most
    /// [`crate::segment::ROOT_TOLERANCE`] of relative velocity), waiting to be booked on
    /// the next row at its instant, or as its own row (issue 81).
    pending_projection: Option<PendingProjection>,
}

/// A velocity projection's impulse waiting for its row ([`Plant::pending_projection`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PendingProjection {
    /// Its instant, s.
    pub t: f64,
    /// The tip's relative velocity before it, m/s.
    pub before: Vector2<f64>,
    /// The impulse `[P_t, P_n]`, N s.
    pub p: Vector2<f64>,
    /// Its kinetic energy change, J.
    pub de: f64,
    /// Its contact work, J.
    pub contact_work: f64,
}

/// The arm's energy and the sines and cosines of its angles at one state `x`,
/// kept where they were computed and read again where the plant meets the same
/// state (bit for bit): a solve's last step (the locator's balance) and the
/// projection after it; the projection and the next interval's start (its first
/// evaluation, the locator's first balance). A value cache: each value is a
/// function of `x` alone (the trig cache's values are, [`crate::trig`]), so the
/// plant computes the same bits with or without it (issue 56: three energies and
/// three look-ups of the same angles a control period).
#[derive(Debug, Clone, Copy)]
struct Known {
    /// `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s).
    x: [f64; 4],
    /// The sines and cosines of `x`'s angles.
    trig: JointTrig<f64>,
    /// The energy at `x`, J ([`crate::ledger::energy`]).
    energy: f64,
}

impl Known {
    /// Whether this is the state of `y` (`[theta1, theta1_dot, theta2, theta2_dot, ..]`), to the bit.
    #[inline]
    fn at(&self, y: &[f64]) -> bool {
        self.x.iter().zip(y).all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

/// The instants an advance samples ([`Plant::advance_sampling`]): `k dt` s for `k`
/// in `next..=last` (each computed from `k`, so no drift accumulates), with the
/// integrator's steps capped at `max_step` s meanwhile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleGrid {
    /// The sampling period, s.
    pub dt: f64,
    /// The first sample's index.
    pub next: u64,
    /// The last sample's index.
    pub last: u64,
    /// The largest step while sampling, s (`f64::INFINITY`: the tolerances alone).
    pub max_step: f64,
}

/// The plant at an instant inside an advance, read from the step that covers it
/// ([`Plant::advance_sampled`], [`Plant::advance_sampling`]): what the sensors of the SIL
/// loop sample at `t_k` while the plant steps from one zero-order-hold switch to
/// the next (`rig::PeriodLoop`'s look-ahead).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The instant, s.
    pub t: f64,
    /// `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s): in the SIL loop's
    /// look-ahead ([`Plant::advance_sampled`]) the quintic Hermite interpolant of each
    /// angle from the step's ends ([`crate::hermite::sample`], issue 56), in
    /// [`Plant::advance_sampling`]'s grid DOP853's 7th-order dense output (Hairer,
    /// Nørsett, Wanner I, II.6); where an event ends the step inside it, the dense output.
    pub x: [f64; 4],
    /// Tip position `[z_t, z_n]`, m.
    pub tip: [f64; 2],
    /// The contact mode of the segment that covers the instant.
    pub mode: shared::ContactMode,
    /// Contact force `[f_t, f_n]`, N, of that segment's model at the sample under
    /// the torque then held.
    pub f: [f64; 2],
}

/// What [`Plant::advance`] changes in a plant: a plant restored to it
/// ([`Plant::restore`]) goes on exactly as from the instant it was taken
/// ([`Plant::checkpoint`]), counters included. The model's value caches (the
/// sines and cosines, [`crate::trig`]; [`Known`]) are not kept: their values are
/// functions of the angles alone, so a restored plant computes the same bits with
/// whatever they hold. Small, as the SIL loop takes one every period (issue 56):
/// the end point of an interval, rare there, is kept boxed.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    t: f64,
    y: OdeState,
    phase: Phase,
    cone_relaxed: bool,
    in_violation: bool,
    time_stepping: bool,
    last_h: f64,
    evals: u64,
    counters: Counters,
    end_point: Option<Box<EndPoint>>,
    ledger: Ledger,
    departing: bool,
    slide_trend: Option<crate::segment::Trend>,
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
            y: [x0[0], x0[1], x0[2], x0[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            phase: Phase::Flight,
            cone_relaxed: false,
            in_violation: false,
            time_stepping: false,
            last_h: 2e-4,
            evals: Cell::new(0),
            trig: TrigCache::new(),
            solver: Dop853 { max_steps: cfg.max_steps, h_max: cfg.max_step.unwrap_or(f64::INFINITY), ..Dop853::new(cfg.rtol, cfg.atol) },
            counters: Counters::default(),
            startup_events: Vec::new(),
            end_point: None,
            sampling: None,
            hermite_samples: false,
            ledger: Ledger::default(),
            e0: f64::NAN,
            departing: false,
            slide_trend: None,
            known: None,
            pending_projection: None,
        };
        plant.e0 = plant.energy();
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
            plant.flush_projection(&mut events);
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

    /// `[z_r_dot, z_n_dot]`, m/s.
    fn rel_velocity(&self) -> Vector2<f64> {
        let v = self.tip_velocity();
        Vector2::new(v[0] - self.arm.params.v_belt, v[1])
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

    /// Mechanical energy (kinetic + gravity + spring), J, from the trig cache's
    /// sines and cosines ([`crate::ledger::energy`]; `Arm::kinetic_energy` plus
    /// `Arm::potential_energy` to rounding, without their three `cos` calls: the
    /// projection books its share of the ledger every period of a slide, issue 56).
    pub fn energy(&self) -> f64 {
        match self.known() {
            Some(k) => k.energy,
            None => crate::ledger::energy(&self.arm, &self.trig.get(&Vector2::new(self.y[0], self.y[2])), &self.y),
        }
    }

    /// What is known at the current state ([`Known`]), if anything.
    #[inline]
    fn known(&self) -> Option<Known> {
        self.known.filter(|k| k.at(&self.y))
    }

    /// The sines and cosines of the current angles: known ([`Known`]) or from the trig cache.
    #[inline]
    fn trig_here(&self) -> JointTrig<f64> {
        match self.known() {
            Some(k) => k.trig,
            None => self.trig.get(&Vector2::new(self.y[0], self.y[2])),
        }
    }

    /// Mechanical energy (J) and tip velocity `[z_t_dot, z_n_dot]` (m/s) of the arm
    /// in state `x` (`[theta1, theta1_dot, theta2, theta2_dot]`, rad, rad/s), as
    /// [`Plant::energy`] and [`Plant::tip_velocity`] give them for the plant's own
    /// state: for a [`Sample`] inside an advance.
    ///
    /// The sines and cosines come from the plant's trig cache (the model
    /// evaluations' values, to rounding: [`crate::trig`]), not from `sin_cos` calls:
    /// a trace row's cost (issue 56).
    pub fn energy_and_tip_velocity_of(&self, x: &[f64; 4]) -> (f64, [f64; 2]) {
        let (q, qd) = (Vector2::new(x[0], x[2]), Vector2::new(x[1], x[3]));
        let trig = self.trig.get(&q);
        let v = shared::kinematics::jacobian_trig(self.arm.params.l, &trig) * qd;
        (crate::ledger::energy(&self.arm, &trig, x), [v[0], v[1]])
    }

    /// The energy ledger since creation (docs/plant.md "The energy ledger"): the
    /// works of the motors, the damping, the belt and the contact's slip, the
    /// projections' share, the energy change they explain and what is left.
    pub fn ledger(&self) -> Ledger {
        use crate::ledger::{BELT, DAMPING, MOTORS, SLIP};
        let mut l = self.ledger;
        (l.motors_j, l.damping_j, l.belt_j, l.slip_j) = (self.y[MOTORS], self.y[DAMPING], self.y[BELT], self.y[SLIP]);
        l.energy_change_j = self.energy() - self.e0;
        l.residual_j = l.energy_change_j - (l.motors_j + l.damping_j + l.belt_j + l.slip_j + l.projections_j);
        l
    }

    /// Event counts since creation.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// The validity counters since creation, for a run that ended with `failure`.
    pub fn validity(&self, failure: Option<&SimError>) -> Validity {
        Validity::of(&self.counters, &self.ledger, failure)
    }

    /// Evaluations of the vector field since creation (a cost measure).
    pub fn rhs_evaluations(&self) -> u64 {
        self.evals.get()
    }

    /// The plant's state now, to go back to with [`Plant::restore`] (e.g. after
    /// advancing ahead of a decision that turned out otherwise).
    #[inline]
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            t: self.t,
            y: self.y,
            phase: self.phase,
            cone_relaxed: self.cone_relaxed,
            in_violation: self.in_violation,
            time_stepping: self.time_stepping,
            last_h: self.last_h,
            evals: self.evals.get(),
            counters: self.counters,
            end_point: self.end_point.map(Box::new),
            ledger: self.ledger,
            departing: self.departing,
            slide_trend: self.slide_trend,
        }
    }

    /// Goes back to `c`, a [`Plant::checkpoint`] of this plant: what follows is
    /// bit for bit what would have followed the checkpoint.
    pub fn restore(&mut self, c: Checkpoint) {
        let Checkpoint {
            t,
            y,
            phase,
            cone_relaxed,
            in_violation,
            time_stepping,
            last_h,
            evals,
            counters,
            end_point,
            ledger,
            departing,
            slide_trend,
        } = c;
        (self.t, self.y, self.phase, self.cone_relaxed, self.in_violation, self.time_stepping, self.last_h) =
            (t, y, phase, cone_relaxed, in_violation, time_stepping, last_h);
        self.evals.set(evals);
        (self.counters, self.end_point, self.ledger, self.departing, self.slide_trend) =
            (counters, end_point.map(|e| *e), ledger, departing, slide_trend);
    }

    /// The current slide's approach to the singular point under `ctrl` (`None` outside a slide).
    #[cfg(test)]
    pub(crate) fn approach<C: Controller + ?Sized>(&self, ctrl: &C) -> Option<crate::segment::Approach> {
        self.segment(ctrl).approach(self.t, &self.y)
    }

    pub(crate) fn segment<'a, C: Controller + ?Sized>(&'a self, ctrl: &'a C) -> Segment<'a, C> {
        Segment::new(&self.arm, self.phase, ctrl, self.cone_relaxed, &self.cfg, &self.evals, &self.trig)
    }
}
