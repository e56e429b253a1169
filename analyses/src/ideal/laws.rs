//! The ideal laws as torque laws the plant evaluates inside its integration
//! ([`Controller`]): the PID ([`IdealPid`]), the hybrid force/motion law
//! ([`IdealHybrid`]), either of them ([`IdealLaw`]), and why a law cannot produce
//! a torque ([`LawFault`]).

use std::cell::Cell;

use nalgebra::{Matrix2, Vector2};
use serde::Serialize;
use shared::{
    Arm, ElbowBranch, Params, SlipDirection,
    contact::sticking_force,
    kinematics::{inverse_kinematics, jacobian, jdot_qdot, tip_position},
};

use super::reference::Reference;
use plant::{Controller, Phase};

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
    // `pub(super)`: `run::build` sets the gains with struct update syntax.
    pub(super) fault: Cell<Option<LawFault>>,
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
/// continuous time with exact model and contact forces ([`crate::ideal`]'s module docs):
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
    // `pub(super)`: `run::build` sets the gains with struct update syntax.
    pub(super) fault: Cell<Option<LawFault>>,
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
            // The fixed point ([`crate::ideal`]'s module docs); `-b/p` would be 0/0 where p = 0.
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

/// Either ideal law (one type for [`simulate`](super::simulate)).
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
