//! One run of a sweep: a grid point and an initial condition, a transient, then
//! the record window in which the paper's indicator is measured.
//!
//! Open loop (`u = 0`) the plant takes its own integrator steps: it is advanced
//! in [`CHUNK_S`] intervals only to check for an interruption between them.
//! Closed loop, the firmware step runs in-process, sampled as on the MCU, through
//! the SIL rig's [`PeriodLoop`] (sensors, quantisation, zero-order hold, the
//! scenario's delay); with `--ideal`, the paper's continuous-time law with exact
//! measurements ([`crate::ideal`]) is evaluated inside the plant's integration,
//! which again takes its own steps (advanced in [`CHUNK_S`] intervals), with the
//! same references, gains and `f_n*` as the scenario's.
//!
//! Measured over the record window:
//! - `theta1_dot_max`, the paper's indicator, and `z_n_max`, the highest tip
//!   position: maxima over the continuous trajectory, taken inside the
//!   integrator's steps ([`plant::Extrema`]), not at samples;
//! - lift-offs: every time the tip leaves the belt (a lift-off from sliding or
//!   sticking, an impact without collision into flight, or a bounce at touchdown);
//!   touchdowns and impacts without collision are counted too.

use std::sync::atomic::{AtomicBool, Ordering};

use shared::Params;

use super::extrema::ExtremaWatch;
use super::{InitialCondition, RunKey, SweepController, SweepSpec};
use crate::ideal::{self, IdealLaw, IdealSetup};
use plant::{Counters, Plant, SimConfig, SimError};
use plant::{Hold, NoObserver, Observer};
use rig::{InProcessLink, PeriodLoop, RunSetup, Scenario};

pub use super::outcome::{Outcome, RunRow, TARGET_TOL_M};

/// Open loop: the length of the intervals the plant is advanced by, s (a Ctrl-C
/// is noticed between them).
pub const CHUNK_S: f64 = 10.0;

/// Closed loop: control periods between checks for a Ctrl-C.
const PERIODS_PER_CHECK: usize = 1000;

/// Lift-offs in `c`: every departure from the belt ([`crate::lift_offs::of`]).
fn lift_offs(c: &Counters) -> u64 {
    crate::lift_offs::of(c)
}

/// Simulates run `key` from initial condition `ic`. Returns `None` when `stop` was
/// set before the run finished (nothing is recorded for it).
pub fn simulate(spec: &SweepSpec, key: &RunKey, ic: &InitialCondition, stop: &AtomicBool) -> Option<RunRow> {
    let draw = spec.draw(key.seed);
    let jittered = jittered_start(spec, ic, draw.d_start_m);
    let ic = &jittered;
    let params = Params::<f64> { mu: key.mu + draw.d_mu, v_belt: key.v_belt, ..spec.params };
    let sim = SimConfig {
        rtol: spec.rtol,
        atol: spec.atol,
        impact_law: key.impact_law,
        e_n: key.e_n,
        iwc: key.iwc,
        singular: spec.singular,
        ..SimConfig::default()
    };
    let mut row = RunRow {
        index: key.index,
        impact_law: key.impact_law.name().into(),
        e_n: key.e_n,
        iwc: key.iwc,
        mu: key.mu,
        v_belt: key.v_belt,
        ic: ic.name.clone(),
        seed: key.seed,
        outcome: Outcome::Failed,
        theta1_dot_over_threshold: false,
        theta1_dot_max: f64::NAN,
        t_theta1_dot_max: f64::NAN,
        lift_offs: 0,
        touchdowns: 0,
        impacts_without_collision: 0,
        z_n_max: f64::NAN,
        tip_height_max: f64::NAN,
        final_mode: String::new(),
        target_error_m: f64::NAN,
        lift_offs_transient: 0,
        rhs_evaluations: 0,
        energy_gains: 0,
        newton_fallbacks: 0,
        poisson_fallbacks: 0,
        cone_violations: 0,
        zeno_stops: 0,
        jams: 0,
        integrator_failures: 0,
        ledger_violations: 0,
        belt_j: 0.0,
        slip_j: 0.0,
        ledger_residual_j: 0.0,
        largest_event_belt_j: 0.0,
        error: String::new(),
    };
    let built = match (spec.ideal, closed_loop_scenario(spec, key, ic)) {
        (true, Some(s)) => ideal::build(&ideal_setup(&s, ic, sim)).map(|(p, law)| (p, Some(law))),
        _ => Plant::new(params, sim, ic.x0, 0.0, [0.0, 0.0]).map(|p| (p, None)),
    };
    let (mut plant, law) = match built {
        Ok(p) => p,
        Err(e) => {
            row.error = e.to_string();
            return Some(row);
        }
    };
    // The maxima over the record window (from its start on).
    let mut watch: Option<ExtremaWatch> = None;
    let ended = match (spec.controller, &law) {
        (SweepController::None, _) => windows(spec, &mut plant, stop, &mut watch, |p, dt, o| p.advance(&Hold([0.0, 0.0]), dt, o).map(drop)),
        (_, Some(law)) => windows(spec, &mut plant, stop, &mut watch, |p, dt, o| p.advance(law, dt, o).map(drop)),
        _ => closed_loop(spec, key, ic, &mut plant, stop, &mut watch),
    };
    let ended = match (ended, law.as_ref().and_then(IdealLaw::fault)) {
        (Ended::Done(start), Some(fault)) => {
            Ended::Stopped { start, error: format!("ideal law: {fault}"), safe_state: true, sim_failed: false }
        }
        (e, _) => e,
    };
    let (start, error, sim_failed) = match ended {
        Ended::Interrupted => return None,
        Ended::Done(start) => (start, None, false),
        Ended::Stopped { start, error, safe_state, sim_failed } => (start, Some((error, safe_state)), sim_failed),
    };
    let v = plant.validity(None);
    row.energy_gains = v.energy_gains;
    row.newton_fallbacks = v.newton_fallbacks;
    row.poisson_fallbacks = v.poisson_fallbacks;
    row.cone_violations = v.cone_violations;
    row.zeno_stops = v.zeno_stops;
    row.integrator_failures = u64::from(sim_failed);
    let ledger = plant.ledger();
    row.ledger_violations = ledger.violations;
    (row.belt_j, row.slip_j, row.ledger_residual_j) = (ledger.belt_j, ledger.slip_j, ledger.residual_j);
    row.largest_event_belt_j = ledger.largest_event_belt_j;
    let end = *plant.counters();
    row.jams = end.jams;
    row.lift_offs_transient = start.map_or(lift_offs(&end), |s| lift_offs(&s));
    row.rhs_evaluations = plant.rhs_evaluations();
    row.final_mode = plant.mode().name().into();
    if let Some(s) = start {
        row.lift_offs = lift_offs(&end) - lift_offs(&s);
        row.touchdowns = end.touchdowns - s.touchdowns;
        row.impacts_without_collision = end.impacts_without_collision - s.impacts_without_collision;
    }
    if let Some(e) = watch.as_ref().map(ExtremaWatch::extrema) {
        row.theta1_dot_max = e.theta1_dot_max;
        row.t_theta1_dot_max = e.t_theta1_dot_max;
        row.z_n_max = e.z_n_max;
        row.tip_height_max = e.z_n_max + params.h;
        row.theta1_dot_over_threshold = e.theta1_dot_max > spec.threshold;
    }
    let stopped = error.as_ref().map(|(_, safe)| *safe);
    let target = closed_loop_scenario(spec, key, ic).map(|s| s.controller.target_z_t);
    if let (Some(z_t_ref), None) = (target, &error) {
        row.target_error_m = (plant.tip()[0] - z_t_ref).abs();
    }
    row.outcome = match target {
        None => Outcome::of(stopped, &row.validity(), row.theta1_dot_over_threshold, row.lift_offs, plant.mode()),
        Some(_) => Outcome::of_closed_loop(stopped, &row.validity(), row.lift_offs, row.target_error_m, plant.mode()),
    };
    if let Some((e, _)) = error {
        row.error = e;
    }
    Some(row)
}

/// How a run's simulation ended; `start` holds the counters at the start of the
/// record window (`None` if it was not reached).
enum Ended {
    Done(Option<Counters>),
    /// `sim_failed`: the plant's integrator or event handling failed.
    Stopped {
        start: Option<Counters>,
        error: String,
        safe_state: bool,
        sim_failed: bool,
    },
    Interrupted,
}

/// Advances `plant` by `duration` s in [`CHUNK_S`] intervals with `advance(plant, dt)`.
fn advance_by(
    plant: &mut Plant,
    duration: f64,
    stop: &AtomicBool,
    obs: &mut dyn Observer,
    advance: &mut impl FnMut(&mut Plant, f64, &mut dyn Observer) -> Result<(), plant::SimError>,
) -> Result<bool, SimError> {
    let t_end = plant.time() + duration;
    while t_end - plant.time() > 1e-12 * t_end.max(1.0) {
        if stop.load(Ordering::Relaxed) {
            return Ok(false);
        }
        let dt = (t_end - plant.time()).min(CHUNK_S);
        advance(plant, dt, obs)?;
    }
    Ok(true)
}

/// The transient then the record window, the plant taking its own steps under a
/// torque law inside `advance` (zero torque, or an ideal controller).
fn windows(
    spec: &SweepSpec,
    plant: &mut Plant,
    stop: &AtomicBool,
    watch: &mut Option<ExtremaWatch>,
    mut advance: impl FnMut(&mut Plant, f64, &mut dyn Observer) -> Result<(), plant::SimError>,
) -> Ended {
    match advance_by(plant, spec.transient_s, stop, &mut NoObserver, &mut advance) {
        Ok(true) => {}
        Ok(false) => return Ended::Interrupted,
        Err(e) => return Ended::Stopped { start: None, error: e.to_string(), safe_state: false, sim_failed: e.is_integrator_failure() },
    }
    let w = watch.insert(ExtremaWatch::start(plant.time(), plant.state(), plant.arm().params.l));
    let start = Some(*plant.counters());
    match advance_by(plant, spec.record_s, stop, w, &mut advance) {
        Ok(true) => Ended::Done(start),
        Ok(false) => Ended::Interrupted,
        Err(e) => Ended::Stopped { start, error: e.to_string(), safe_state: false, sim_failed: e.is_integrator_failure() },
    }
}

/// The ideal (continuous-time) set-up of a closed-loop run's scenario `s`: its
/// plant's parameters, controller, reference (`z_t*`, move time), `f_n*` and
/// gains (paper eqs. 8 to 11), from `ic`.
fn ideal_setup(s: &Scenario, ic: &InitialCondition, sim: SimConfig) -> IdealSetup {
    let g = &s.controller;
    IdealSetup {
        controller: g.kind,
        x0: ic.x0,
        params: s.plant.params(),
        target_z_t: g.target_z_t,
        move_time_s: g.move_time_s,
        duration_s: s.timing.duration_s,
        f_n_ref: g.f_n_ref,
        pid: g.pid,
        hybrid_kp: g.hybrid.kp,
        hybrid_kd: g.hybrid.kd,
        // `closed_loop_scenario` has set it for the run's initial condition.
        hybrid_ki: g.hybrid_ki(s.plant.x0),
        sample_dt: s.timing.period().as_secs_f64(),
        stop_at_lift_off: false,
        sim,
    }
}

/// Initial condition `ic` with its tip moved by `d_z_t` m along the belt: the
/// arm placed on the belt at `z_t + d_z_t` by inverse kinematics at the same
/// elbow branch, at rest (the sweep's initial conditions are at rest); `ic`
/// itself for `d_z_t = 0` (and, unchanged, if the moved tip is out of reach,
/// which [`SweepSpec::validate`]'s bound on the jitter rules out).
pub fn jittered_start(spec: &SweepSpec, ic: &InitialCondition, d_z_t: f64) -> InitialCondition {
    if d_z_t == 0.0 {
        return ic.clone();
    }
    let l = spec.params.l;
    let tip = shared::kinematics::tip_position(l, &nalgebra::Vector2::new(ic.x0[0], ic.x0[2]));
    let target = nalgebra::Vector2::new(tip[0] + d_z_t, -spec.params.h);
    match shared::kinematics::inverse_kinematics(l, &target, ic.branch) {
        Ok(q) => InitialCondition { x0: [q[0], 0.0, q[1], 0.0], height_above_belt: 0.0, ..ic.clone() },
        Err(_) => ic.clone(),
    }
}

/// Applies seed `draw` to a closed-loop scenario: the sensor-noise seed moved by
/// its offset, `f_n*` and the command delay by theirs (`mu` and the start are
/// the run's, set by [`closed_loop_scenario`] and [`jittered_start`]).
pub fn apply_draw(s: &mut Scenario, draw: &super::Draw) {
    s.sensors.seed = s.sensors.seed.wrapping_add(draw.noise_seed_offset);
    s.controller.f_n_ref += draw.d_f_n_ref_n;
    s.timing.delta_s += draw.d_delay_s;
}

/// The scenario of a closed-loop run: the spec's, with the run's plant (its
/// `mu`, `v_belt`, impact law, `e_n`, IWC rule, tolerances), the controller asked for, the
/// firmware's friction estimate `mu_hat = mu` (the paper's controller knows `mu`),
/// the run's length, and, unless the scenario gives `controller.hybrid.ki`, the
/// paper's `K'_I`: 0 from an elbow-up initial condition, 650 otherwise (the
/// paper's gains from `x0u` and `x0d`, docs/model.md experiment 6). The arm's
/// parameters (paper Table I) are the scenario's, which the sweep's spec
/// records in [`SweepSpec::params`]. The run's seed ([`RunKey::seed`]) adds its
/// draw: `mu` (and `mu_hat` with it), the noise seed, `f_n*`, the delay ([`apply_draw`]).
pub fn closed_loop_scenario(spec: &SweepSpec, key: &RunKey, ic: &InitialCondition) -> Option<Scenario> {
    let mut s = spec.scenario.clone()?;
    let draw = spec.draw(key.seed);
    let mu = key.mu + draw.d_mu;
    apply_draw(&mut s, &draw);
    s.plant.mu = mu;
    s.plant.v_belt = key.v_belt;
    s.plant.impact_law = key.impact_law;
    s.plant.e_n = key.e_n;
    s.plant.iwc = key.iwc;
    s.plant.rtol = spec.rtol;
    s.plant.atol = spec.atol;
    s.controller.kind = spec.controller.kind()?;
    s.controller.mu_hat = mu * spec.mu_hat_factor;
    if s.controller.hybrid.ki.is_none() {
        let x0 = if ic.branch == shared::ElbowBranch::Up { plant::initial::PaperX0::U } else { plant::initial::PaperX0::D };
        s.controller.hybrid.ki = Some(rig::scenario::paper_hybrid_ki(x0));
    }
    s.timing.duration_s = spec.run_duration();
    // The paper's experiments run the paper's controller: the board's runaway
    // limits off (they stop a loop that whips the arm, where the paper's
    // persistent bouncing is the result; docs/analyses.md, docs/board.md
    // "Runaway limits").
    s.controller.runaway_limits = false;
    Some(s)
}

fn closed_loop(
    spec: &SweepSpec,
    key: &RunKey,
    ic: &InitialCondition,
    plant: &mut Plant,
    stop: &AtomicBool,
    watch: &mut Option<ExtremaWatch>,
) -> Ended {
    let Some(s) = closed_loop_scenario(spec, key, ic) else {
        return Ended::Stopped { start: None, error: "closed loop without a scenario".into(), safe_state: false, sim_failed: false };
    };
    // The run's set-up, its plant unused: the sweep steps its own, at the grid's initial state.
    let link_and_setup = RunSetup::new(s).and_then(|setup| Ok((InProcessLink::new(&setup)?, setup)));
    let (mut link, setup) = match link_and_setup {
        Ok(l) => l,
        Err(e) => return Ended::Stopped { start: None, error: e.to_string(), safe_state: false, sim_failed: false },
    };
    let mut periods = PeriodLoop::new(&setup, plant);
    let n = periods.periods_in(spec.run_duration());
    let k_record = periods.periods_in(spec.transient_s);
    let mut start = None;
    for k in 0..n {
        if k == k_record {
            *watch = Some(ExtremaWatch::start(plant.time(), plant.state(), plant.arm().params.l));
            start = Some(*plant.counters());
        }
        if k % PERIODS_PER_CHECK == 0 && stop.load(Ordering::Relaxed) {
            return Ended::Interrupted;
        }
        let obs: &mut dyn Observer = match watch.as_mut() {
            Some(w) => w,
            None => &mut NoObserver,
        };
        if let Err(f) = periods.period(plant, &mut link, &mut (), obs) {
            let safe_state = matches!(f.error, rig::record::RunError::SafeState { .. });
            let sim_failed = matches!(&f.error, rig::record::RunError::Sim(e) if e.is_integrator_failure());
            return Ended::Stopped { start, error: f.error.to_string(), safe_state, sim_failed };
        }
    }
    Ended::Done(start)
}
