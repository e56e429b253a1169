//! One smooth segment of the hybrid system: the vector field of a fixed contact
//! mode and the event function that ends it, in the form the plant's DOP853
//! ([`super::dop853`]) integrates (state `[theta1, theta1_dot, theta2,
//! theta2_dot, xi_0, xi_1]`, the `xi` being a continuous-time controller's
//! internal states), and the location of that event on the dense output.

use std::cell::Cell;

use nalgebra::Vector2;
use shared::{
    Arm,
    contact::{sliding_force, sticking_force},
    kinematics::{JointTrig, tip_position_trig},
    model::{ArmTerms, TipDynamics},
};

pub use crate::phase::Phase;
use crate::{controller::Controller, dop853::OdeSystem, trig::TrigCache};

mod approach;
mod locate;

pub use approach::{Approach, Crossing, HELD_P};
pub use locate::{EventLocator, ROOT_TOLERANCE, TREND_P, Trend, illinois_root};

/// Components of the plant's integrated state.
pub const STATE_LEN: usize = 10;

/// Components the integrator's error norm measures: the arm's four states and the
/// controller's two. The energy ledger's four works ([`crate::ledger`]) follow them,
/// integrated with the same stages but setting no step.
pub const NORM_LEN: usize = 6;

/// The integrated state: 4 plant states, 2 controller states, then the energy
/// ledger's works `W_motors`, `W_damping`, `W_belt`, `W_slip` (J, [`crate::ledger`]).
pub type OdeState = super::dop853::State<STATE_LEN>;

/// Which boundary of the current phase an event function component crossed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Boundary {
    /// Flight: the tip reached the belt.
    Touchdown,
    /// Sliding or sticking: the normal reaction reached 0 (`b = 0` while sliding).
    LiftOff,
    /// Sliding: `p` reached 0 with the reaction finite (`b` reaching 0 with it, the
    /// controlled corner): an impact without collision follows.
    PZero,
    /// Sliding: the normal reaction reached `jam_load` times `m g` as `p -> 0+` with
    /// `b < 0` (the dynamic jam): a tangential impact follows.
    Jam,
    /// Sliding: the relative velocity reached 0.
    SlipStops,
    /// Sliding: the step size collapsed at the singular point `p = 0, b = 0`
    /// approached with a finite normal force ([`Segment::near_singular`]): a
    /// Moreau-Jean bridge crosses it under the singular rule.
    Singular,
    /// Any mode: the step size collapsed elsewhere: a Moreau-Jean bridge crosses it.
    Collapse,
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
    /// The jam threshold on `f_n / (m g)` ([`crate::config::SimConfig::jam_load`]).
    pub jam_load: f64,
    /// The integrator's tolerances ([`crate::config::SimConfig::rtol`], [`crate::config::SimConfig::atol`]): the ledger's scale.
    pub rtol: f64,
    /// See [`Segment::rtol`].
    pub atol: f64,
    /// Count of model evaluations (vector field and event function), for profiling.
    pub evals: &'a Cell<u64>,
    /// Sines and cosines of the joint angles (shared with the plant's projections).
    pub trig: &'a TrigCache,
    /// The nearest boundary at the end of the last accepted step, keyed by `(t, y)`
    /// (the FSAL stage computes the tip dynamics there; the event function reuses them).
    end: Cell<Option<StepEnd>>,
    /// The arm's constant factors, folded once for the segment's evaluations.
    terms: ArmTerms<f64>,
}

/// `(t, y)`, the event components there and the normal force (N; see
/// [`Segment::nearest_boundary`], [`Segment::end_components`]).
type StepEnd = (f64, OdeState, [(Boundary, f64); 4], f64);

/// The model at one point `(t, y)` of a segment.
#[derive(Debug, Clone, Copy)]
pub struct Point {
    /// Tip dynamics under the segment's torque law (paper eqs. 2 to 7).
    pub td: TipDynamics<f64>,
    /// Contact force `[f_t, f_n]` of the mode, N.
    pub f: Vector2<f64>,
    /// The vector field `dy/dt` (rad/s, rad/s^2, the controller's `xi_dot`, and the
    /// powers of the ledger's works, W).
    pub dydt: OdeState,
}

/// Plant state `(q, q_dot)` of an ODE state.
#[inline]
pub fn split(y: &OdeState) -> (Vector2<f64>, Vector2<f64>) {
    (Vector2::new(y[0], y[2]), Vector2::new(y[1], y[3]))
}

impl<'a, C: Controller + ?Sized> Segment<'a, C> {
    /// The segment of mode `phase` of `arm` under torque law `ctrl`; `cone_relaxed`
    /// and `trig` as the fields, `baumgarte` and `jam_load` from `cfg`; `evals` counts
    /// model evaluations.
    pub fn new(
        arm: &'a Arm<f64>,
        phase: Phase,
        ctrl: &'a C,
        cone_relaxed: bool,
        cfg: &crate::config::SimConfig,
        evals: &'a Cell<u64>,
        trig: &'a TrigCache,
    ) -> Self {
        Self {
            arm,
            phase,
            ctrl,
            cone_relaxed,
            baumgarte: cfg.baumgarte,
            jam_load: cfg.jam_load,
            rtol: cfg.rtol,
            atol: cfg.atol,
            evals,
            trig,
            end: Cell::new(None),
            terms: arm.terms(),
        }
    }

    /// Tip dynamics, contact force `[f_t, f_n]` (N) and controller output at `(t, y)`.
    #[inline]
    pub fn evaluate(&self, t: f64, y: &OdeState, xi_dot: &mut [f64; 2]) -> (TipDynamics<f64>, Vector2<f64>, Vector2<f64>) {
        let (q, _) = split(y);
        self.evaluate_body(t, y, xi_dot, &self.trig.get(&q))
    }

    /// [`Segment::evaluate`] with `trig`, the sines and cosines of `y`'s angles
    /// (the trig cache's values for them, or the same values kept elsewhere).
    #[inline]
    pub fn evaluate_trig(
        &self,
        t: f64,
        y: &OdeState,
        xi_dot: &mut [f64; 2],
        trig: &JointTrig<f64>,
    ) -> (TipDynamics<f64>, Vector2<f64>, Vector2<f64>) {
        self.evaluate_body(t, y, xi_dot, trig)
    }

    #[inline(always)]
    fn evaluate_body(
        &self,
        t: f64,
        y: &OdeState,
        xi_dot: &mut [f64; 2],
        trig: &JointTrig<f64>,
    ) -> (TipDynamics<f64>, Vector2<f64>, Vector2<f64>) {
        let (q, qd) = split(y);
        let xi = [y[4], y[5]];
        let motor = self.ctrl.torque_in(self.phase, t, &[y[0], y[1], y[2], y[3]], &xi, xi_dot);
        let u = Arm::generalised_torque(&Vector2::new(motor[0], motor[1]));
        let mut td = self.terms.tip_dynamics_trig(trig, &q, &qd, &u);
        // The corrected free acceleration is applied in place and then restored (not on
        // a copy: a copy of the tip dynamics was a tenth of an evaluation's cost).
        let f = match self.phase {
            Phase::Flight => Vector2::zeros(),
            Phase::Sliding(dir) => {
                // Baumgarte (1972): ask for z_n_ddot = -2 w z_n_dot - w^2 (z_n + H) instead of 0,
                // so integration drift off the belt decays instead of accumulating.
                let corr = self.constraint_correction(&td);
                let b = td.a_free[1];
                td.a_free[1] += corr[1];
                let f = sliding_force(&td, self.arm.params.mu, dir);
                td.a_free[1] = b;
                f
            }
            Phase::Sticking => {
                let corr = self.constraint_correction(&td);
                let a = td.a_free;
                td.a_free += corr;
                let f = sticking_force(&td);
                td.a_free = a;
                f
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

    /// The vector field and what it is made of at `(t, y)` (one model evaluation,
    /// counted in `evals`).
    #[inline]
    pub fn point(&self, t: f64, y: &OdeState) -> Point {
        self.count_evaluation();
        self.point_uncounted(t, y)
    }

    /// Counts one model evaluation in `evals` (one made earlier and used now).
    #[inline]
    pub fn count_evaluation(&self) {
        self.evals.set(self.evals.get() + 1);
    }

    /// [`Segment::point`] without counting it.
    #[inline]
    pub fn point_uncounted(&self, t: f64, y: &OdeState) -> Point {
        let mut xi_dot = [0.0; 2];
        let ev = self.evaluate(t, y, &mut xi_dot);
        self.point_of(y, ev, xi_dot)
    }

    /// [`Segment::point`]'s vector field alone, written into `dydt` (not counted):
    /// the same expressions, so the same bits, without the rest of the [`Point`]
    /// (the tip dynamics' 18 values and the force, built and copied out at every
    /// stage, and the products only they need, such as `Q`'s first row while
    /// sliding): what the integrator's stages ask for.
    #[inline(never)]
    pub fn dydt_uncounted(&self, t: f64, y: &OdeState, dydt: &mut OdeState) {
        let mut xi_dot = [0.0; 2];
        let ev = self.evaluate(t, y, &mut xi_dot);
        *dydt = self.point_of(y, ev, xi_dot).dydt;
    }

    /// [`Segment::point`] with `trig`, the sines and cosines of `y`'s angles (as
    /// [`Segment::evaluate_trig`]); counted in `evals`.
    #[inline]
    pub fn point_trig(&self, t: f64, y: &OdeState, trig: &JointTrig<f64>) -> Point {
        self.count_evaluation();
        self.point_trig_uncounted(t, y, trig)
    }

    /// [`Segment::point_trig`] without counting it.
    #[inline]
    pub fn point_trig_uncounted(&self, t: f64, y: &OdeState, trig: &JointTrig<f64>) -> Point {
        let mut xi_dot = [0.0; 2];
        let ev = self.evaluate_trig(t, y, &mut xi_dot, trig);
        self.point_of(y, ev, xi_dot)
    }

    /// The point at `y` from the model's evaluation there (`(td, f, motor)` and
    /// the controller's `xi_dot`, as [`Segment::evaluate`] gives them).
    #[inline(always)]
    fn point_of(&self, y: &OdeState, (td, f, motor): (TipDynamics<f64>, Vector2<f64>, Vector2<f64>), xi_dot: [f64; 2]) -> Point {
        let p = &self.arm.params;
        let (d1, d2) = (y[1], y[3]);
        // The ledger's powers (crate::ledger): the motors' `u_gen . q_dot`, the joint
        // damping's, and the contact force's on the tip, the belt's part `v_belt f_t`
        // and the part in the belt's frame `f . [z_r_dot, z_n_dot]`.
        let motors = (motor[0] - motor[1]) * d1 + motor[1] * d2;
        let damping = -p.sigma * (d1 * d1 + (d2 - d1) * (d2 - d1));
        let (qdd, belt, slip) = match self.phase {
            Phase::Flight => (td.qdd_free, 0.0, 0.0),
            _ => (td.qdd_with_force(&f), p.v_belt * f[0], f[0] * (td.z_dot[0] - p.v_belt) + f[1] * td.z_dot[1]),
        };
        Point { td, f, dydt: [d1, qdd[0], d2, qdd[1], xi_dot[0], xi_dot[1], motors, damping, belt, slip] }
    }

    /// The arm's mechanical energy at `y`, J ([`crate::ledger::energy`]).
    #[inline]
    pub fn energy(&self, y: &OdeState) -> f64 {
        let (q, _) = split(y);
        crate::ledger::energy(self.arm, &self.trig.get(&q), y)
    }

    /// The energy balance of the stretch from `y0` (energy `e0`) to `y1` (energy
    /// `e1`): its residual `e1 - e0 - sum of the works` (J) and its tolerance
    /// ([`crate::ledger::step_tolerance`] at `y1`).
    #[inline]
    pub fn balance(&self, y0: &OdeState, e0: f64, y1: &OdeState, e1: f64) -> (f64, f64) {
        let (q, _) = split(y1);
        self.balance_with(&self.trig.get(&q), y0, e0, y1, e1)
    }

    /// The energy at `y1` (J, [`Segment::energy`]) and the balance of the stretch
    /// from `y0` (energy `e0`) to it ([`Segment::balance`]): `(e1, residual,
    /// tolerance)`, the same values from one look-up of `y1`'s sines and cosines
    /// (a step's check, issue 56).
    #[inline]
    pub fn energy_and_balance(&self, y0: &OdeState, e0: f64, y1: &OdeState) -> (f64, f64, f64) {
        let (e1, residual, tol, _) = self.energy_and_balance_trig(y0, e0, y1);
        (e1, residual, tol)
    }

    /// [`Segment::energy_and_balance`] and the sines and cosines of `y1`'s angles
    /// it looked up (for the plant's projection at `y1`, `crate::plant::Known`).
    #[inline]
    pub fn energy_and_balance_trig(&self, y0: &OdeState, e0: f64, y1: &OdeState) -> (f64, f64, f64, JointTrig<f64>) {
        let (q, _) = split(y1);
        let tr = self.trig.get(&q);
        let e1 = crate::ledger::energy(self.arm, &tr, y1);
        let (residual, tol) = self.balance_with(&tr, y0, e0, y1, e1);
        (e1, residual, tol, tr)
    }

    /// [`Segment::balance`] with `tr`, the sines and cosines of `y1`'s angles.
    #[inline(always)]
    fn balance_with(&self, tr: &JointTrig<f64>, y0: &OdeState, e0: f64, y1: &OdeState, e1: f64) -> (f64, f64) {
        use crate::ledger::{BELT, DAMPING, MOTORS, SLIP};
        let works = [MOTORS, DAMPING, BELT, SLIP].map(|i| y1[i] - y0[i]);
        let residual = (e1 - e0) - (works[0] + works[1] + works[2] + works[3]);
        let size = [MOTORS, DAMPING, BELT, SLIP].iter().map(|&i| y1[i].abs() + y0[i].abs()).sum::<f64>();
        let tol = crate::ledger::step_tolerance(self.arm, tr, y1, self.rtol, self.atol, size + e0.abs() + e1.abs());
        (residual, tol)
    }

    /// The event components (each positive inside the phase), normalised to be
    /// dimensionless: flight `(z_n + H)/l`; sliding `-b/g`, `p/Q_22`, `s v_r / (1 m/s)`,
    /// `1 - f_n / (jam_load m g)`; sticking `f_n/(m g)`, `(mu f_n - |f_t|)/(m g)`.
    pub fn components(&self, t: f64, y: &OdeState) -> [(Boundary, f64); 4] {
        match self.phase {
            Phase::Flight => {
                // Only the tip's height: no need for the dynamics.
                let (q, _) = split(y);
                let z = tip_position_trig(self.arm.params.l, &self.trig.get(&q));
                self.flight_components(z[1])
            }
            _ => {
                let (td, f, _) = self.evaluate(t, y, &mut [0.0; 2]);
                self.components_of(&td, &f)
            }
        }
    }

    /// Whether a slide at `(t, y)` is running into the dynamic jam: `p > 0`, `b < 0`
    /// and a normal reaction of at least [`JAM_ONSET_LOAD`] times `m g`: the slide's
    /// trend `trend_f_n` (N, [`EventLocator::trend`]) where known, else `f_n =
    /// -b/p` at the point. Where the step size collapses there before `f_n` reaches
    /// `jam_load m g`, the plant resolves the jam from the last accepted point
    /// (docs/plant.md "The jam corner").
    pub fn jamming(&self, t: f64, y: &OdeState, trend_f_n: Option<f64>) -> bool {
        if !matches!(self.phase, Phase::Sliding(_)) {
            return false;
        }
        let (c, f_n) = self.end_components(t, y);
        let f_n = trend_f_n.unwrap_or(f_n);
        c[0].1 > 0.0 && c[1].1 > 0.0 && f_n >= JAM_ONSET_LOAD * self.arm.params.m * self.arm.params.g
    }

    /// Whether a slide at `(t, y)` is at the singular point `p = 0, b = 0` with a
    /// finite normal force: `p / Q_22` and `-b / g` both at most
    /// [`SINGULAR_NEIGHBOURHOOD`] (each small on its own scale) and the normal force
    /// (the trend `trend_f_n` where known, as [`Segment::jamming`]) below
    /// [`JAM_ONSET_LOAD`] times `m g` (else it is the jam). Where the step size
    /// collapses there, the plant crosses the point under the singular rule
    /// (docs/plant.md "The singular point").
    pub fn near_singular(&self, t: f64, y: &OdeState, trend_f_n: Option<f64>) -> bool {
        if !matches!(self.phase, Phase::Sliding(_)) {
            return false;
        }
        let (c, f_n) = self.end_components(t, y);
        let f_n = trend_f_n.unwrap_or(f_n);
        c[0].1 <= SINGULAR_NEIGHBOURHOOD && c[1].1 <= SINGULAR_NEIGHBOURHOOD && f_n < JAM_ONSET_LOAD * self.arm.params.m * self.arm.params.g
    }

    /// [`Segment::components`] from the tip dynamics and contact force at the point.
    #[inline]
    pub fn components_of(&self, td: &TipDynamics<f64>, f: &Vector2<f64>) -> [(Boundary, f64); 4] {
        let p = &self.arm.params;
        match self.phase {
            Phase::Flight => self.flight_components(td.z[1]),
            Phase::Sliding(dir) => {
                let v_r = td.z_dot[0] - p.v_belt;
                [
                    (Boundary::LiftOff, -td.b() / p.g),
                    (Boundary::PZero, td.p(p.mu, dir) / td.qmat[(1, 1)]),
                    (Boundary::SlipStops, dir.sign::<f64>() * v_r),
                    (Boundary::Jam, 1.0 - f[1] / (self.jam_load * p.m * p.g)),
                ]
            }
            Phase::Sticking => {
                let scale = p.m * p.g;
                let cone = if self.cone_relaxed { f64::INFINITY } else { (p.mu * f[1] - f[0].abs()) / scale };
                [
                    (Boundary::LiftOff, f[1] / scale),
                    (Boundary::ConeEdge, cone),
                    (Boundary::ConeEdge, f64::INFINITY),
                    (Boundary::ConeEdge, f64::INFINITY),
                ]
            }
        }
    }

    #[inline]
    fn flight_components(&self, z_n: f64) -> [(Boundary, f64); 4] {
        let p = &self.arm.params;
        let g = (z_n + p.h) / p.l;
        [
            (Boundary::Touchdown, g),
            (Boundary::Touchdown, f64::INFINITY),
            (Boundary::Touchdown, f64::INFINITY),
            (Boundary::Touchdown, f64::INFINITY),
        ]
    }

    /// The component closest to its boundary, and its value.
    pub fn nearest_boundary(&self, t: f64, y: &OdeState) -> (Boundary, f64) {
        nearest(self.end_components(t, y).0)
    }

    /// The event components at `(t, y)` and the normal force there (N), from the
    /// last step's end when `(t, y)` is it (no evaluation), else evaluated.
    pub fn end_components(&self, t: f64, y: &OdeState) -> ([(Boundary, f64); 4], f64) {
        if let Some((te, ye, components, f_n)) = self.end.get()
            && te.to_bits() == t.to_bits()
            && ye.iter().zip(y).all(|(a, b)| a.to_bits() == b.to_bits())
        {
            return (components, f_n);
        }
        match self.phase {
            Phase::Flight => (self.components(t, y), 0.0),
            _ => {
                let (td, f, _) = self.evaluate(t, y, &mut [0.0; 2]);
                (self.components_of(&td, &f), f[1])
            }
        }
    }
}

/// The component closest to its boundary (the smallest).
#[inline]
pub fn nearest(components: [(Boundary, f64); 4]) -> (Boundary, f64) {
    components.into_iter().fold((Boundary::Touchdown, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
}

impl<C: Controller + ?Sized> OdeSystem<STATE_LEN> for Segment<'_, C> {
    const NORM_LEN: usize = NORM_LEN;
    /// The ledger's works are quadratures: [`Segment::point`] never reads them.
    const READ_LEN: usize = NORM_LEN;

    #[inline]
    fn rhs(&self, t: f64, y: &OdeState, dydt: &mut OdeState) {
        self.count_evaluation();
        self.dydt_uncounted(t, y, dydt);
    }

    /// Also keeps the nearest boundary at the step's end for [`Segment::nearest_boundary`].
    #[inline]
    fn rhs_step_end(&self, t: f64, y: &OdeState, dydt: &mut OdeState) {
        let pt = self.point(t, y);
        *dydt = pt.dydt;
        self.end.set(Some((t, *y, self.components_of(&pt.td, &pt.f), pt.f[1])));
    }
}

/// The normal reaction, in units of `m g`, above which a slide whose step size
/// collapses with `p > 0` and `b < 0` is taken to be the dynamic jam ([`Segment::jamming`]):
/// ten times the arm's weight, far above any steady slide of the paper's experiments
/// (`f_n* = 10 N` is about 8.5 `m g`) and far below where the collapse happens (at
/// 1e4 to 1e6 `m g` in the cases of issue 24's search).
pub const JAM_ONSET_LOAD: f64 = 10.0;

/// How close to the singular point `p = 0, b = 0` a slide whose step collapses
/// counts as at it ([`Segment::near_singular`]): `p / Q_22` and `-b / g` both at
/// most 0.05. Issue 40's failures collapsed with `p / Q_22` about 1e-3 and `-b/g`
/// 3e-3 to 7e-3; a steady slide of the experiments has `-b/g` near 1.
pub const SINGULAR_NEIGHBOURHOOD: f64 = 0.05;
