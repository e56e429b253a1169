//! One smooth segment of the hybrid system: the vector field of a fixed contact
//! mode and the event function that ends it, in the form the
//! `differential-equations` crate integrates (state `[theta1, theta1_dot,
//! theta2, theta2_dot, xi_0..xi_3]`, the `xi` being a continuous-time
//! controller's internal states).

use differential_equations::prelude::*;
use nalgebra::Vector2;
use shared::{
    Arm, SlipDirection,
    contact::{sliding_force, sticking_force},
    kinematics::tip_position,
    model::TipDynamics,
};

use super::Controller;

/// The integrated state: 4 plant states then 4 controller states.
pub type OdeState = [f64; 8];

/// Contact mode the integrator runs in (the plant's discrete state).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Off the belt: `f = 0`.
    Flight,
    /// Slipping on the belt in a fixed direction: `f_n = -b/p`, `f_t = -mu s f_n`.
    Sliding(SlipDirection),
    /// Carried by the belt: `z_ddot = 0`, `f = -Q^-1 a_free`.
    Sticking,
}

/// Which boundary of the current phase an event function component crossed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Boundary {
    /// Flight: the tip reached the belt.
    Touchdown,
    /// Sliding or sticking: the normal reaction reached 0 (`b = 0` while sliding).
    LiftOff,
    /// Sliding: `p` reached 0 with `b < 0` (the reaction grows without bound).
    PZero,
    /// Sliding: the relative velocity reached 0.
    SlipStops,
    /// Sticking: the friction force reached the cone's edge.
    ConeEdge,
}

/// A mode's vector field and event function at fixed parameters.
pub struct Segment<'a, C: ?Sized> {
    /// The arm.
    pub arm: &'a Arm<f64>,
    /// The mode.
    pub phase: Phase,
    /// The torque law (zero-order hold or a continuous-time controller).
    pub ctrl: &'a C,
    /// In sticking, ignore the cone (documented corner case: no consistent contact at rest).
    pub cone_relaxed: bool,
}

/// Plant state `(q, q_dot)` of an ODE state.
#[inline]
pub fn split(y: &OdeState) -> (Vector2<f64>, Vector2<f64>) {
    (Vector2::new(y[0], y[2]), Vector2::new(y[1], y[3]))
}

impl<C: Controller + ?Sized> Segment<'_, C> {
    /// Tip dynamics, contact force `[f_t, f_n]` (N) and controller output at `(t, y)`.
    #[inline]
    pub fn evaluate(&self, t: f64, y: &OdeState, xi_dot: &mut [f64; 4]) -> (TipDynamics<f64>, Vector2<f64>, Vector2<f64>) {
        let (q, qd) = split(y);
        let xi = [y[4], y[5], y[6], y[7]];
        let motor = self.ctrl.torque(t, &[y[0], y[1], y[2], y[3]], &xi, xi_dot);
        let u = Arm::generalised_torque(&Vector2::new(motor[0], motor[1]));
        let td = self.arm.tip_dynamics(&q, &qd, &u);
        let f = match self.phase {
            Phase::Flight => Vector2::zeros(),
            Phase::Sliding(dir) => sliding_force(&td, self.arm.params.mu, dir),
            Phase::Sticking => sticking_force(&td),
        };
        (td, f, Vector2::new(motor[0], motor[1]))
    }

    /// The event components (each positive inside the phase), normalised to be
    /// dimensionless: flight `(z_n + H)/l`; sliding `-b/g`, `p/Q_22`, `s v_r / (1 m/s)`;
    /// sticking `f_n/(m g)`, `(mu f_n - |f_t|)/(m g)`.
    pub fn components(&self, t: f64, y: &OdeState) -> [(Boundary, f64); 3] {
        let p = &self.arm.params;
        match self.phase {
            Phase::Flight => {
                let (q, _) = split(y);
                let z = tip_position(p.l, &q);
                let g = (z[1] + p.h) / p.l;
                [(Boundary::Touchdown, g), (Boundary::Touchdown, f64::INFINITY), (Boundary::Touchdown, f64::INFINITY)]
            }
            Phase::Sliding(dir) => {
                let mut scratch = [0.0; 4];
                let (td, _, _) = self.evaluate(t, y, &mut scratch);
                let v_r = td.z_dot[0] - p.v_belt;
                [
                    (Boundary::LiftOff, -td.b() / p.g),
                    (Boundary::PZero, td.p(p.mu, dir) / td.qmat[(1, 1)]),
                    (Boundary::SlipStops, dir.sign::<f64>() * v_r),
                ]
            }
            Phase::Sticking => {
                let mut scratch = [0.0; 4];
                let (_, f, _) = self.evaluate(t, y, &mut scratch);
                let scale = p.m * p.g;
                let cone = if self.cone_relaxed { f64::INFINITY } else { (p.mu * f[1] - f[0].abs()) / scale };
                [(Boundary::LiftOff, f[1] / scale), (Boundary::ConeEdge, cone), (Boundary::ConeEdge, f64::INFINITY)]
            }
        }
    }

    /// The component closest to its boundary.
    pub fn nearest_boundary(&self, t: f64, y: &OdeState) -> (Boundary, f64) {
        self.components(t, y).into_iter().fold((Boundary::Touchdown, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
    }
}

impl<C: Controller + ?Sized> ODE<f64, OdeState> for Segment<'_, C> {
    fn diff(&self, t: f64, y: &OdeState, dydt: &mut OdeState) {
        let mut xi_dot = [0.0; 4];
        let (td, f, _) = self.evaluate(t, y, &mut xi_dot);
        let qdd = match self.phase {
            Phase::Flight => td.qdd_free,
            _ => td.qdd_with_force(&f),
        };
        *dydt = [y[1], qdd[0], y[3], qdd[1], xi_dot[0], xi_dot[1], xi_dot[2], xi_dot[3]];
    }
}

impl<C: Controller + ?Sized> Event<f64, OdeState> for Segment<'_, C> {
    fn config(&self) -> EventConfig {
        EventConfig::new(CrossingDirection::Negative, Some(1))
    }

    fn event(&self, t: f64, y: &OdeState) -> f64 {
        self.nearest_boundary(t, y).1
    }
}

/// Output handler that keeps only the latest accepted point (so a solve never
/// grows a trajectory vector; the event wrapper appends the event point after it)
/// and remembers the last accepted step size for the next solve.
pub struct LastPoint<'a> {
    /// Last accepted step size, s (read by the caller after the solve).
    pub last_h: &'a std::cell::Cell<f64>,
}

impl differential_equations::solout::Solout<f64, OdeState> for LastPoint<'_> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        y_curr: &OdeState,
        _y_prev: &OdeState,
        _interpolator: &mut I,
        solution: &mut differential_equations::solution::Solution<f64, OdeState>,
    ) -> differential_equations::control::ControlFlag<f64, OdeState>
    where
        I: differential_equations::interpolate::Interpolation<f64, OdeState> + ?Sized,
    {
        if t_curr > t_prev {
            self.last_h.set(t_curr - t_prev);
        }
        solution.t.clear();
        solution.y.clear();
        solution.push(t_curr, *y_curr);
        differential_equations::control::ControlFlag::Continue
    }
}
