//! The paper's controllers in its own setting: continuous time, exact
//! measurements, no saturation (docs/model.md experiments 5 and 6), as torque laws the
//! plant evaluates inside its integration ([`Controller`]), and a closed-loop run
//! of them ([`simulate`]).
//!
//! - [`IdealPid`]: paper eq. 8 on `q' = [theta1, theta2 - theta1]`, the reference
//!   `q'*` from inverse kinematics of `z* = [z_t*, -H]` on the initial elbow branch;
//!   its integrators are the plant's controller states `xi` (rad s).
//! - [`IdealHybrid`]: paper eqs. 9 to 11,
//!   `u = w + c + M J^-1 (-J_dot q_dot + i_x a_v) + J^T (-i_x f_t - i_y a_f)`, with
//!   the exact contact force of the plant's current phase; its force integral
//!   `int (f_n* - f_n) dt` (N s) is `xi_0`.
//!
//! The firmware runs the same laws sampled, in `f32` (`firmware::law`); the model
//! terms (`M`, `w`, `c`, `J`, `J_dot q_dot`, the contact forces) come from
//! `shared`, and the gains from the firmware's defaults (`firmware::Config`), so
//! the two settings differ only by sampling, quantisation and estimation (the
//! tests check that both laws give the same torque at the same state).
//!
//! Exact contact force in the hybrid law. In sliding the law's torque depends on
//! `f_t`, which depends on the torque (through `b`); the fixed point is
//! `f_n = a_f`, `f_t = -mu s a_f` (`s = sign z_r_dot`): with it
//! `b = -p a_f`, so the tip stays on the belt exactly while `p > 0` and `a_f > 0`
//! (the decoupling the paper designs for). In flight the exact force is zero. In
//! sticking the fixed point is degenerate (the law cancels whatever tangential
//! force there is), so the law there compensates the friction of slip in the
//! direction of `z_r_dot` (positive at rest), and its force integral uses the
//! plant's sticking force. The phase comes from the plant ([`Controller::torque_in`]).
//!
//! Consequence (a property of the ideal law, seen in the tests): the ideal hybrid
//! controller lifts off exactly where the tip reaches a configuration with `p = 0`
//! (the end of the admissible range of paper Table II). Beyond it, in contact
//! `b = -p a_f > 0` (the tip leaves) and in flight the law pushes it back with
//! `a_f`, with no time passing in between: the plant then stops with an
//! [`SimError::EventStorm`] (lift-off and Zeno stop at one instant), or holds the
//! tip in its documented corner case. Runs that only need the first lift-off stop
//! there ([`IdealSetup::stop_at_lift_off`]); [`IdealRun::first_lift_off_s`] is set
//! either way.

use std::cell::Cell;

use nalgebra::{Matrix2, Vector2};
use serde::Serialize;
use shared::{
    Arm, ElbowBranch, Params, SlipDirection,
    contact::sticking_force,
    kinematics::{inverse_kinematics, jacobian, jdot_qdot, tip_position},
};

use firmware::ControllerKind;
use plant::{Controller, Counters, EventKind, Phase, Plant, SimConfig, SimError};
use rig::scenario::{HybridSection, PidSection};

/// One point of the tangential reference: `z_t*` (m), `z_t_dot*` (m/s), `z_t_ddot*` (m/s^2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RefPoint {
    /// `z_t*`, m.
    pub pos: f64,
    /// `z_t_dot*`, m/s.
    pub vel: f64,
    /// `z_t_ddot*`, m/s^2.
    pub acc: f64,
}

/// The tangential reference `z_t*(t)` of the firmware (`firmware::reference::Quintic`),
/// in `f64`: the minimum-jerk quintic `s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5`
/// (Flash and Hogan 1985) from `start` to `target` (m) over `duration` (s, > 0),
/// then held at the target. Negative times give the start.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reference {
    /// Start of the move, m.
    pub start: f64,
    /// Target `z_t*`, m.
    pub target: f64,
    /// Duration of the move, s.
    pub duration: f64,
}

impl Reference {
    /// The reference at time `t` (s).
    pub fn at(&self, t: f64) -> RefPoint {
        let d = self.target - self.start;
        if t >= self.duration {
            return RefPoint { pos: self.target, vel: 0.0, acc: 0.0 };
        }
        let tau = if t > 0.0 { t / self.duration } else { 0.0 };
        let t2 = tau * tau;
        let s = t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2);
        let ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
        let dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2);
        RefPoint { pos: self.start + d * s, vel: d * ds / self.duration, acc: d * dds / (self.duration * self.duration) }
    }
}

/// Why an ideal law cannot produce a torque at a state (it then outputs zero
/// torque, the firmware's safe state, and remembers the first fault).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LawFault {
    /// `J` is singular (straight arm, `|sin(theta2 - theta1)| < 1e-9`): `J^-1` does not exist.
    #[error("singular Jacobian (straight arm) at t = {t} s")]
    Singular {
        /// Time, s.
        t: f64,
    },
    /// The reference tip position has no inverse kinematics.
    #[error("reference z_t* = {z_t} m is out of reach at t = {t} s")]
    Unreachable {
        /// Time, s.
        t: f64,
        /// The reference, m.
        z_t: f64,
    },
    /// A torque or state is NaN or infinite.
    #[error("non-finite value at t = {t} s")]
    NonFinite {
        /// Time, s.
        t: f64,
    },
}

/// Smallest `|sin(theta2 - theta1)| = |det J| / l^2` the laws invert `J` at.
const SINGULAR_SIN: f64 = 1e-9;

fn split(x: &[f64; 4]) -> (Vector2<f64>, Vector2<f64>) {
    (Vector2::new(x[0], x[2]), Vector2::new(x[1], x[3]))
}

/// `J(q)^-1` (rad/m), or [`LawFault::Singular`].
fn jacobian_inverse(l: f64, q: &Vector2<f64>, t: f64) -> Result<(Matrix2<f64>, Matrix2<f64>), LawFault> {
    let jac = jacobian(l, q);
    if (q[1] - q[0]).sin().abs() < SINGULAR_SIN {
        return Err(LawFault::Singular { t });
    }
    let inv = jac.try_inverse().ok_or(LawFault::Singular { t })?;
    Ok((jac, inv))
}

/// The PID of docs/model.md experiment 5 (paper eq. 8) in continuous time:
/// `u_i = K_P,i e_i + K_I,i xi_i + K_D,i e_dot_i`, `e = q'* - q'`,
/// `q' = [theta1, theta2 - theta1]`, `xi_dot = e`; `u = [u1, u2]` are the motor
/// torques (N m). `q'*` is the inverse kinematics of `[z_t*(t), -H]` on `branch`
/// and `q'*_dot` comes from `J(q*)^-1 [z_t_dot*, 0]`. No saturation, no anti-windup
/// (the paper's setting).
#[derive(Debug, Clone)]
pub struct IdealPid {
    /// The arm (the plant's parameters).
    pub arm: Arm<f64>,
    /// Elbow branch of the inverse kinematics (the initial condition's).
    pub branch: ElbowBranch,
    /// The tangential reference.
    pub reference: Reference,
    /// `K_P` per joint of `q'`, N m/rad.
    pub kp: [f64; 2],
    /// `K_I`, N m/(rad s).
    pub ki: [f64; 2],
    /// `K_D`, N m s/rad.
    pub kd: [f64; 2],
    fault: Cell<Option<LawFault>>,
}

impl IdealPid {
    /// The paper's PID (`K_P,1 = 200`, `K_I,1 = 25`, `K_D,1 = 2`, joint-2 gains 0:
    /// the firmware's default gains) for an arm with `params` on `branch`.
    pub fn paper(params: Params<f64>, branch: ElbowBranch, reference: Reference) -> Self {
        let g = firmware::Config::default().pid;
        let f = |v: [f32; 2]| [f64::from(v[0]), f64::from(v[1])];
        Self { arm: Arm::new(params), branch, reference, kp: f(g.kp), ki: f(g.ki), kd: f(g.kd), fault: Cell::new(None) }
    }

    /// Motor torques `[u1, u2]` (N m) and `xi_dot = e` (rad) at time `t` (s), state
    /// `x` (rad, rad/s) and integrals `xi` (rad s).
    ///
    /// # Errors
    /// [`LawFault::Unreachable`] (reference out of reach), [`LawFault::Singular`]
    /// (straight-arm reference), [`LawFault::NonFinite`].
    pub fn evaluate(&self, t: f64, x: &[f64; 4], xi: &[f64; 2]) -> Result<([f64; 2], [f64; 2]), LawFault> {
        let p = &self.arm.params;
        let r = self.reference.at(t);
        let q_ref =
            inverse_kinematics(p.l, &Vector2::new(r.pos, -p.h), self.branch).map_err(|_| LawFault::Unreachable { t, z_t: r.pos })?;
        let (_, j_inv) = jacobian_inverse(p.l, &q_ref, t)?;
        let qd_ref = j_inv * Vector2::new(r.vel, 0.0);
        let (q, qd) = split(x);
        let prime = |v: Vector2<f64>| [v[0], v[1] - v[0]];
        let (qr, qm, qdr, qdm) = (prime(q_ref), prime(q), prime(qd_ref), prime(qd));
        let mut u = [0.0; 2];
        let mut e = [0.0; 2];
        for i in 0..2 {
            e[i] = qr[i] - qm[i];
            u[i] = self.kp[i] * e[i] + self.ki[i] * xi[i] + self.kd[i] * (qdr[i] - qdm[i]);
        }
        if u.iter().chain(e.iter()).all(|v| v.is_finite()) { Ok((u, e)) } else { Err(LawFault::NonFinite { t }) }
    }

    /// The first fault met during a run (the law output zero torque then).
    pub fn fault(&self) -> Option<LawFault> {
        self.fault.get()
    }
}

impl Controller for IdealPid {
    fn torque(&self, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        match self.evaluate(t, x, xi) {
            Ok((u, e)) => {
                *xi_dot = e;
                u
            }
            Err(f) => safe(&self.fault, f, xi_dot),
        }
    }
}

/// Zero torque and frozen integrators after a fault; remembers the first one.
fn safe(cell: &Cell<Option<LawFault>>, fault: LawFault, xi_dot: &mut [f64; 2]) -> [f64; 2] {
    if cell.get().is_none() {
        cell.set(Some(fault));
    }
    *xi_dot = [0.0; 2];
    [0.0; 2]
}

/// One evaluation of the ideal hybrid law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HybridOutput {
    /// Motor torques `[u1, u2] = [u_0 + u_1, u_1]`, N m.
    pub motor: [f64; 2],
    /// `a_v`, m/s^2 (paper eq. 10).
    pub a_v: f64,
    /// `a_f`, N (paper eq. 11).
    pub a_f: f64,
    /// The friction term the law compensates, N (the exact `f_t` in sliding).
    pub f_t_hat: f64,
    /// The plant's contact force `[f_t, f_n]` (N) in the given phase under `motor`.
    pub f: [f64; 2],
    /// `d/dt int (f_n* - f_n) dt = f_n* - f_n`, N.
    pub xi_dot: f64,
}

/// The hybrid force/motion law of docs/model.md experiment 6 (paper eqs. 9 to 11) in
/// continuous time with exact model and contact forces (module docs):
/// `u = w + c + M J^-1 (-J_dot q_dot + i_x a_v) + J^T (-i_x f_t - i_y a_f)`,
/// `a_v = z_t_ddot* + K'_P (z_t* - z_t) + K'_D (z_t_dot* - z_t_dot)`,
/// `a_f = f_n* + K'_I xi_0`, `xi_0_dot = f_n* - f_n`. No saturation.
#[derive(Debug, Clone)]
pub struct IdealHybrid {
    /// The arm (the plant's parameters; the law's model is exact).
    pub arm: Arm<f64>,
    /// The tangential reference.
    pub reference: Reference,
    /// `f_n*`, N.
    pub f_n_ref: f64,
    /// `K'_P`, 1/s^2.
    pub kp: f64,
    /// `K'_D`, 1/s.
    pub kd: f64,
    /// `K'_I`, 1/s.
    pub ki: f64,
    fault: Cell<Option<LawFault>>,
}

impl IdealHybrid {
    /// The paper's hybrid law (`K'_P = K'_D = 900`: the firmware's defaults) with
    /// `K'_I = ki` (the paper: 650 from `x0d`, 0 from `x0u`) and `f_n* = f_n_ref` (N).
    pub fn paper(params: Params<f64>, reference: Reference, f_n_ref: f64, ki: f64) -> Self {
        let g = firmware::Config::default().hybrid;
        Self { arm: Arm::new(params), reference, f_n_ref, kp: f64::from(g.kp), kd: f64::from(g.kd), ki, fault: Cell::new(None) }
    }

    /// The law at time `t` (s), state `x` (rad, rad/s), force integral `xi[0]` (N s),
    /// with the tip in contact phase `phase` (which sets the exact contact force).
    ///
    /// # Errors
    /// [`LawFault::Singular`] when `J` is singular (straight arm), [`LawFault::NonFinite`].
    pub fn evaluate(&self, phase: Phase, t: f64, x: &[f64; 4], xi: &[f64; 2]) -> Result<HybridOutput, LawFault> {
        let p = &self.arm.params;
        let (q, qd) = split(x);
        let (jac, j_inv) = jacobian_inverse(p.l, &q, t)?;
        let z = tip_position(p.l, &q);
        let z_dot = jac * qd;
        let r = self.reference.at(t);
        let a_v = r.acc + self.kp * (r.pos - z[0]) + self.kd * (r.vel - z_dot[0]);
        let a_f = self.f_n_ref + self.ki * xi[0];
        let f_t_hat = match phase {
            Phase::Flight => 0.0,
            Phase::Sliding(dir) => -p.mu * dir.sign::<f64>() * a_f,
            Phase::Sticking => -p.mu * SlipDirection::of(z_dot[0] - p.v_belt).sign::<f64>() * a_f,
        };
        let wc = self.arm.w(&q, &qd) + self.arm.c(&q, &qd);
        let s = jdot_qdot(p.l, &q, &qd);
        let u_gen = wc + self.arm.mass_matrix(&q) * j_inv * (Vector2::new(a_v, 0.0) - s) + jac.transpose() * Vector2::new(-f_t_hat, -a_f);
        let f = match phase {
            Phase::Flight => Vector2::zeros(),
            // The fixed point (module docs); `-b/p` would be 0/0 where p = 0.
            Phase::Sliding(_) => Vector2::new(f_t_hat, a_f),
            Phase::Sticking => sticking_force(&self.arm.tip_dynamics(&q, &qd, &u_gen)),
        };
        let motor = [u_gen[0] + u_gen[1], u_gen[1]];
        let out = HybridOutput { motor, a_v, a_f, f_t_hat, f: [f[0], f[1]], xi_dot: self.f_n_ref - f[1] };
        if motor.iter().chain(out.f.iter()).all(|v| v.is_finite()) && a_f.is_finite() { Ok(out) } else { Err(LawFault::NonFinite { t }) }
    }

    /// The contact phase a state looks like when the plant does not say (the
    /// [`Controller::torque`] path): sliding in the direction of `z_r_dot` with the
    /// tip within 1 nm of the belt and not leaving it faster than 1 um/s, else flight.
    pub fn phase_from_geometry(&self, x: &[f64; 4]) -> Phase {
        let p = &self.arm.params;
        let (q, qd) = split(x);
        let z = tip_position(p.l, &q);
        let z_dot = jacobian(p.l, &q) * qd;
        if z[1] + p.h <= 1e-9 && z_dot[1] <= 1e-6 { Phase::Sliding(SlipDirection::of(z_dot[0] - p.v_belt)) } else { Phase::Flight }
    }

    /// The first fault met during a run (the law output zero torque then).
    pub fn fault(&self) -> Option<LawFault> {
        self.fault.get()
    }
}

impl Controller for IdealHybrid {
    fn torque(&self, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        self.torque_in(self.phase_from_geometry(x), t, x, xi, xi_dot)
    }

    fn torque_in(&self, phase: Phase, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        match self.evaluate(phase, t, x, xi) {
            Ok(out) => {
                *xi_dot = [out.xi_dot, 0.0];
                out.motor
            }
            Err(f) => safe(&self.fault, f, xi_dot),
        }
    }
}

/// Either ideal law (one type for [`simulate`]).
#[derive(Debug, Clone)]
pub enum IdealLaw {
    /// [`IdealPid`].
    Pid(IdealPid),
    /// [`IdealHybrid`].
    Hybrid(IdealHybrid),
}

impl IdealLaw {
    /// The first fault met (the law output zero torque from then on where it persists).
    pub fn fault(&self) -> Option<LawFault> {
        match self {
            Self::Pid(c) => c.fault(),
            Self::Hybrid(c) => c.fault(),
        }
    }
}

impl Controller for IdealLaw {
    fn torque(&self, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        match self {
            Self::Pid(c) => c.torque(t, x, xi, xi_dot),
            Self::Hybrid(c) => c.torque(t, x, xi, xi_dot),
        }
    }

    fn torque_in(&self, phase: Phase, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        match self {
            Self::Pid(c) => c.torque_in(phase, t, x, xi, xi_dot),
            Self::Hybrid(c) => c.torque_in(phase, t, x, xi, xi_dot),
        }
    }
}

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
    /// Lift-offs (the tip leaving the belt, after a bounce or an impact without collision too).
    pub lift_offs: u64,
    /// Impacts without collision (the Painlevé paradox resolved).
    pub impacts_without_collision: u64,
    /// Time of the first lift-off or impact without collision, s.
    pub first_lift_off_s: Option<f64>,
    /// The plant's event counts.
    pub counters: Counters,
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
    run.lift_offs = c.lift_offs;
    run.impacts_without_collision = c.impacts_without_collision;
    run.counters = c;
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

#[cfg(test)]
mod tests;
