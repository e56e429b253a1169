//! One smooth segment of the hybrid system: the vector field of a fixed contact
//! mode and the event function that ends it, in the form the
//! `differential-equations` crate integrates (state `[theta1, theta1_dot,
//! theta2, theta2_dot, xi_0, xi_1]`, the `xi` being a continuous-time
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

/// The integrated state: 4 plant states then 2 controller states.
pub type OdeState = [f64; 6];

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
    /// Baumgarte stabilisation rate of the contact constraint, rad/s (0: none).
    pub baumgarte: f64,
    /// Count of model evaluations (vector field and event function), for profiling.
    pub evals: &'a std::cell::Cell<u64>,
}

/// Plant state `(q, q_dot)` of an ODE state.
#[inline]
pub fn split(y: &OdeState) -> (Vector2<f64>, Vector2<f64>) {
    (Vector2::new(y[0], y[2]), Vector2::new(y[1], y[3]))
}

impl<C: Controller + ?Sized> Segment<'_, C> {
    /// Tip dynamics, contact force `[f_t, f_n]` (N) and controller output at `(t, y)`.
    #[inline]
    pub fn evaluate(&self, t: f64, y: &OdeState, xi_dot: &mut [f64; 2]) -> (TipDynamics<f64>, Vector2<f64>, Vector2<f64>) {
        let (q, qd) = split(y);
        let xi = [y[4], y[5]];
        let motor = self.ctrl.torque(t, &[y[0], y[1], y[2], y[3]], &xi, xi_dot);
        let u = Arm::generalised_torque(&Vector2::new(motor[0], motor[1]));
        let td = self.arm.tip_dynamics(&q, &qd, &u);
        let f = match self.phase {
            Phase::Flight => Vector2::zeros(),
            Phase::Sliding(dir) => {
                // Baumgarte (1972): ask for z_n_ddot = -2 w z_n_dot - w^2 (z_n + H) instead of 0,
                // so integration drift off the belt decays instead of accumulating.
                let corr = self.constraint_correction(&td);
                let mut td_c = td;
                td_c.a_free[1] += corr[1];
                sliding_force(&td_c, self.arm.params.mu, dir)
            }
            Phase::Sticking => {
                let corr = self.constraint_correction(&td);
                let mut td_c = td;
                td_c.a_free += corr;
                sticking_force(&td_c)
            }
        };
        (td, f, Vector2::new(motor[0], motor[1]))
    }

    /// Baumgarte's constraint acceleration `[2 w z_r_dot, 2 w z_n_dot + w^2 (z_n + H)]`
    /// (m/s^2): zero on the constraint, so the forces are the exact ones there.
    #[inline]
    fn constraint_correction(&self, td: &TipDynamics<f64>) -> Vector2<f64> {
        let w = self.baumgarte;
        let p = &self.arm.params;
        Vector2::new(2.0 * w * (td.z_dot[0] - p.v_belt), 2.0 * w * td.z_dot[1] + w * w * (td.z[1] + p.h))
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
                let mut scratch = [0.0; 2];
                let (td, _, _) = self.evaluate(t, y, &mut scratch);
                let v_r = td.z_dot[0] - p.v_belt;
                [
                    (Boundary::LiftOff, -td.b() / p.g),
                    (Boundary::PZero, td.p(p.mu, dir) / td.qmat[(1, 1)]),
                    (Boundary::SlipStops, dir.sign::<f64>() * v_r),
                ]
            }
            Phase::Sticking => {
                let mut scratch = [0.0; 2];
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
        let mut xi_dot = [0.0; 2];
        self.evals.set(self.evals.get() + 1);
        let (td, f, _) = self.evaluate(t, y, &mut xi_dot);
        let qdd = match self.phase {
            Phase::Flight => td.qdd_free,
            _ => td.qdd_with_force(&f),
        };
        *dydt = [y[1], qdd[0], y[3], qdd[1], xi_dot[0], xi_dot[1]];
    }
}

/// Output handler that keeps only the latest accepted point (so a solve never
/// grows a trajectory vector), remembers the last accepted step size for the
/// next solve, and locates this segment's event itself.
///
/// Why not the crate's `Event` machinery: its Brent-Dekker search in
/// `differential-equations` 0.7.0 returns wrong roots (a ballistic hop
/// `y'' = -10`, `y(0) = 0`, `y'(0) = 1`, reports `y = 0` at 0.05 s to 0.12 s
/// instead of 0.2 s; see `crate_event_location_is_wrong` in the tests). The
/// detection here is the standard one: a sign change of the event function from
/// positive to non-positive across an accepted step, then a bracketing root
/// search (Illinois regula falsi, safeguarded by bisection) on the
/// step's dense output, to `1e-14 s + 1e-15 |t|`.
pub struct EventLocator<'a, 'b, C: ?Sized> {
    /// The segment (its event function).
    pub segment: &'b Segment<'a, C>,
    /// Largest accepted step size of the solve, s (read by the caller; the next solve's first step).
    pub last_h: &'b std::cell::Cell<f64>,
    /// Event function at the previous accepted point.
    pub g_prev: Option<f64>,
    /// Largest accepted step of this solve, s.
    pub max_h: f64,
    /// The located event `(t, y)`, if any.
    pub hit: &'b std::cell::Cell<Option<(f64, OdeState)>>,
}

impl<C: Controller + ?Sized> differential_equations::solout::Solout<f64, OdeState> for EventLocator<'_, '_, C> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        y_curr: &OdeState,
        y_prev: &OdeState,
        interpolator: &mut I,
        solution: &mut differential_equations::solution::Solution<f64, OdeState>,
    ) -> differential_equations::control::ControlFlag<f64, OdeState>
    where
        I: differential_equations::interpolate::Interpolation<f64, OdeState> + ?Sized,
    {
        use differential_equations::control::ControlFlag;
        if t_curr > t_prev {
            // The largest accepted step: the final step is cut short at the end of the
            // interval, so the last one would underestimate the next interval's step.
            self.max_h = self.max_h.max(t_curr - t_prev);
            self.last_h.set(self.max_h);
        }
        let g_curr = self.segment.nearest_boundary(t_curr, y_curr).1;
        let crossed = matches!(self.g_prev, Some(g) if g > 0.0) && g_curr <= 0.0 && t_curr > t_prev;
        self.g_prev = Some(g_curr);
        solution.t.clear();
        solution.y.clear();
        if crossed {
            let g_a = self.segment.nearest_boundary(t_prev, y_prev).1;
            if let Some((t, y)) = locate_root(self.segment, interpolator, (t_prev, g_a.max(f64::MIN_POSITIVE)), (t_curr, g_curr, *y_curr)) {
                self.hit.set(Some((t, y)));
                solution.push(t, y);
                return ControlFlag::Terminate;
            }
        }
        solution.push(t_curr, *y_curr);
        ControlFlag::Continue
    }
}

/// Illinois regula falsi with bisection safeguard on the dense output:
/// the first zero of the event function in `(a, b]`, given `g(a) > 0 >= g(b)`.
fn locate_root<C, I>(seg: &Segment<'_, C>, interp: &mut I, a: (f64, f64), b: (f64, f64, OdeState)) -> Option<(f64, OdeState)>
where
    C: Controller + ?Sized,
    I: differential_equations::interpolate::Interpolation<f64, OdeState> + ?Sized,
{
    let (mut ta, mut ga) = a;
    let (mut tb, mut gb, mut yb) = b;
    let tol = 1e-14 + 1e-15 * tb.abs();
    let mut side = 0i8;
    for iter in 0..200 {
        if tb - ta <= tol {
            break;
        }
        // Regula falsi point, kept away from the ends; bisect every 4th iteration
        // or when the secant falls outside the bracket.
        let mut t = tb - gb * (tb - ta) / (gb - ga);
        if !(t > ta && t < tb) || iter % 4 == 3 {
            t = 0.5 * (ta + tb);
        }
        let y = interp.interpolate(t).ok()?;
        let g = seg.nearest_boundary(t, &y).1;
        // Illinois rule: an end retained twice in a row has its value halved.
        if g > 0.0 {
            ta = t;
            ga = g;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        } else {
            tb = t;
            gb = g;
            yb = y;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        }
    }
    Some((tb, yb))
}
