//! A closed-loop run of an ideal law: its set-up, the plant and the law built
//! from it, and the sampled run.

use nalgebra::Vector2;
use serde::Serialize;
use shared::{ElbowBranch, Params, SlipDirection, kinematics::inverse_kinematics};

use super::{
    laws::{IdealHybrid, IdealLaw, IdealPid, LawFault},
    reference::Reference,
};
use firmware::ControllerKind;
use plant::{Controller, Counters, EventKind, Phase, Plant, SimConfig, SimError};
use rig::scenario::{HybridSection, PidSection};

/// A closed-loop run of an ideal controller (a scenario-like set-up).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IdealSetup {
    /// The controller.
    pub controller: ControllerKind,
    /// Initial state `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s); a tip
    /// up to 1 mm inside the belt is projected onto it (same `z_t` and branch).
    pub x0: [f64; 4],
    /// The plant's parameters (paper Table I, `mu`, `v_belt`); the ideal laws
    /// model the arm exactly with them.
    pub params: Params<f64>,
    /// Tangential target `z_t*`, m.
    pub target_z_t: f64,
    /// Duration of the quintic move from the initial tip position, s (> 0).
    pub move_time_s: f64,
    /// Run length, s.
    pub duration_s: f64,
    /// `f_n*`, N (hybrid).
    pub f_n_ref: f64,
    /// PID gains (paper eq. 8), per joint of `q' = [theta1, theta2 - theta1]`.
    pub pid: PidSection,
    /// `K'_P`, 1/s^2 (hybrid, paper eq. 10).
    pub hybrid_kp: f64,
    /// `K'_D`, 1/s (hybrid, paper eq. 10).
    pub hybrid_kd: f64,
    /// `K'_I`, 1/s (hybrid, paper eq. 11).
    pub hybrid_ki: f64,
    /// Sampling period of the trace, s (the law itself is continuous).
    pub sample_dt: f64,
    /// Stop at the first lift-off or impact without collision.
    pub stop_at_lift_off: bool,
    /// Simulator settings.
    pub sim: SimConfig,
}

impl IdealSetup {
    /// The paper's set-up of experiments 5 and 6: paper Table I with `mu = 0.6`,
    /// `v_belt = -0.4 m/s`, `f_n* = 10 N`, the paper's gains (eqs. 8 to 11) with
    /// `K'_I` = 650 from an elbow-down initial state (`x0d`) and 0 from an
    /// elbow-up one (`x0u`), a 2 s move, 10 s, sampled every 1 ms.
    pub fn paper(controller: ControllerKind, x0: [f64; 4], target_z_t: f64) -> Self {
        let down = ElbowBranch::of(&Vector2::new(x0[0], x0[2])) == ElbowBranch::Down;
        let hybrid = HybridSection::default();
        Self {
            controller,
            x0,
            params: Params::paper(),
            target_z_t,
            move_time_s: 2.0,
            duration_s: 10.0,
            f_n_ref: 10.0,
            pid: PidSection::default(),
            hybrid_kp: hybrid.kp,
            hybrid_kd: hybrid.kd,
            hybrid_ki: if down { 650.0 } else { 0.0 },
            sample_dt: 1e-3,
            stop_at_lift_off: false,
            sim: SimConfig::default(),
        }
    }
}

/// One sample of an ideal run (a row of a trace).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IdealSample {
    /// Time, s.
    pub t: f64,
    /// `theta1`, rad.
    pub theta1: f64,
    /// `theta2`, rad.
    pub theta2: f64,
    /// Tip `z_t`, m.
    pub z_t: f64,
    /// Tip `z_n`, m.
    pub z_n: f64,
    /// Reference `z_t*`, m.
    pub z_t_ref: f64,
    /// Contact force `f_t`, N.
    pub f_t: f64,
    /// Contact force `f_n`, N.
    pub f_n: f64,
    /// Motor torque `u1`, N m.
    pub u1: f64,
    /// Motor torque `u2`, N m.
    pub u2: f64,
    /// Contact mode (`flight`, `sliding`, `sticking`).
    pub mode: &'static str,
}

/// The outcome of [`simulate`].
#[derive(Debug)]
pub struct IdealRun {
    /// One sample per `sample_dt`, from `t = 0`.
    pub samples: Vec<IdealSample>,
    /// Lift-offs: every departure of the tip from the belt (from contact, after an
    /// impact without collision, at a bounce: [`crate::lift_offs::of`]).
    pub lift_offs: u64,
    /// Impacts without collision (the Painlevé paradox resolved).
    pub impacts_without_collision: u64,
    /// Time of the first lift-off or impact without collision, s.
    pub first_lift_off_s: Option<f64>,
    /// The plant's event counts.
    pub counters: Counters,
    /// The plant's energy ledger (docs/plant.md "The energy ledger").
    pub ledger: plant::Ledger,
    /// The first fault of the law (it output zero torque then).
    pub law_fault: Option<LawFault>,
    /// Why the run stopped early (the samples up to then are kept).
    pub error: Option<SimError>,
}

impl IdealRun {
    /// Whether the tip never left the belt: no lift-off, no impact without collision,
    /// no flight sample.
    pub fn no_lift_off(&self) -> bool {
        self.lift_offs == 0 && self.impacts_without_collision == 0 && self.samples.iter().all(|s| s.mode != "flight")
    }
}

/// Builds the plant and the law of a set-up (the law's reference starts at the
/// projected initial tip position).
///
/// # Errors
/// [`SimError`] for bad parameters, settings or initial state, a target out of
/// reach ([`SimError::Unreachable`]), a non-positive move time or sample period
/// ([`SimError::BadStep`]).
pub fn build(setup: &IdealSetup) -> Result<(Plant, IdealLaw), SimError> {
    let params = setup.params;
    params.validate()?;
    for v in [setup.move_time_s, setup.sample_dt] {
        if !(v.is_finite() && v > 0.0) {
            return Err(SimError::BadStep(v));
        }
    }
    if !(setup.duration_s.is_finite() && setup.duration_s >= 0.0) {
        return Err(SimError::BadStep(setup.duration_s));
    }
    let pid = &setup.pid;
    let gains = [
        ("f_n_ref", setup.f_n_ref),
        ("pid.kp[0]", pid.kp[0]),
        ("pid.kp[1]", pid.kp[1]),
        ("pid.ki[0]", pid.ki[0]),
        ("pid.ki[1]", pid.ki[1]),
        ("pid.kd[0]", pid.kd[0]),
        ("pid.kd[1]", pid.kd[1]),
        ("hybrid_kp", setup.hybrid_kp),
        ("hybrid_kd", setup.hybrid_kd),
        ("hybrid_ki", setup.hybrid_ki),
    ];
    for (name, v) in gains {
        if !(v.is_finite() && v >= 0.0) {
            return Err(SimError::BadConfig { name, value: v, expected: "a finite value >= 0" });
        }
    }
    let probe = Plant::new(params, setup.sim, setup.x0, 0.0, [0.0; 2])?;
    let x = probe.state();
    let q = Vector2::new(x[0], x[2]);
    let branch = ElbowBranch::of(&q);
    inverse_kinematics(params.l, &Vector2::new(setup.target_z_t, -params.h), branch)?;
    let reference = Reference { start: probe.tip()[0], target: setup.target_z_t, duration: setup.move_time_s };
    let law = match setup.controller {
        ControllerKind::Pid => IdealLaw::Pid(IdealPid { kp: pid.kp, ki: pid.ki, kd: pid.kd, ..IdealPid::paper(params, branch, reference) }),
        ControllerKind::Hybrid => IdealLaw::Hybrid(IdealHybrid {
            kp: setup.hybrid_kp,
            kd: setup.hybrid_kd,
            ..IdealHybrid::paper(params, reference, setup.f_n_ref, setup.hybrid_ki)
        }),
    };
    // Choose the initial contact mode under the law's own initial torque.
    let phase = if probe.mode() == shared::ContactMode::Flight { probe.phase() } else { Phase::Sliding(SlipDirection::Positive) };
    let phase = match (phase, probe.tip_velocity()[0] - params.v_belt) {
        (Phase::Sliding(_), v_r) => Phase::Sliding(SlipDirection::of(v_r)),
        (p, _) => p,
    };
    let u0 = law.torque_in(phase, 0.0, &x, &[0.0; 2], &mut [0.0; 2]);
    let plant = Plant::new(params, setup.sim, setup.x0, 0.0, u0)?;
    Ok((plant, law))
}

/// Runs an ideal controller in closed loop for `setup.duration_s`, sampling every
/// `setup.sample_dt`; `on_sample(t)` is called after each sample (progress).
///
/// # Errors
/// As [`build`]. A failure during the run is returned in [`IdealRun::error`] with
/// the samples up to it.
pub fn simulate(setup: &IdealSetup, mut on_sample: impl FnMut(f64)) -> Result<IdealRun, SimError> {
    let (mut plant, law) = build(setup)?;
    let n = (setup.duration_s / setup.sample_dt).round() as usize;
    let mut run = IdealRun {
        samples: Vec::with_capacity(n + 1),
        lift_offs: 0,
        impacts_without_collision: 0,
        first_lift_off_s: None,
        counters: Counters::default(),
        ledger: plant::Ledger::default(),
        law_fault: None,
        error: None,
    };
    let note = |run: &mut IdealRun, events: &[plant::PlantEvent]| {
        for e in events {
            if matches!(e.kind, EventKind::LiftOff | EventKind::ImpactWithoutCollision) && run.first_lift_off_s.is_none() {
                run.first_lift_off_s = Some(e.t);
            }
        }
    };
    note(&mut run, plant.startup_events());
    run.samples.push(sample(&plant, &law));
    for k in 1..=n {
        let dt = k as f64 * setup.sample_dt - plant.time();
        match plant.advance(&law, dt, &mut plant::NoObserver) {
            Ok(report) => note(&mut run, &report.events),
            Err(e) => {
                // The plant stops at the failure: events of the interval are lost, the counts are not.
                let c = plant.counters();
                if run.first_lift_off_s.is_none() && (c.lift_offs > 0 || c.impacts_without_collision > 0) {
                    run.first_lift_off_s = Some(plant.time());
                }
                run.error = Some(e);
                break;
            }
        }
        run.samples.push(sample(&plant, &law));
        on_sample(plant.time());
        let c = plant.counters();
        if setup.stop_at_lift_off && (c.lift_offs > 0 || c.impacts_without_collision > 0 || plant.mode() == shared::ContactMode::Flight) {
            break;
        }
    }
    let c = *plant.counters();
    run.lift_offs = crate::lift_offs::of(&c);
    run.impacts_without_collision = c.impacts_without_collision;
    run.counters = c;
    run.ledger = plant.ledger();
    run.law_fault = law.fault();
    Ok(run)
}

fn sample(plant: &Plant, law: &IdealLaw) -> IdealSample {
    let (t, x) = (plant.time(), plant.state());
    let z = plant.tip();
    let xi = plant.controller_state();
    let u = law.torque_in(plant.phase(), t, &x, &xi, &mut [0.0; 2]);
    let f = plant.contact_force_with(law);
    let z_t_ref = match law {
        IdealLaw::Pid(c) => c.reference.at(t).pos,
        IdealLaw::Hybrid(c) => c.reference.at(t).pos,
    };
    IdealSample {
        t,
        theta1: x[0],
        theta2: x[2],
        z_t: z[0],
        z_n: z[1],
        z_t_ref,
        f_t: f[0],
        f_n: f[1],
        u1: u[0],
        u2: u[1],
        mode: plant.mode().name(),
    }
}
