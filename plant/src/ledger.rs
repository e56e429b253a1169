//! The energy ledger (docs/plant.md "The energy ledger"): along every run,
//! `E(t) - E(0) = W_motors + W_damping + W_belt + W_slip + W_projections`, each
//! term accounted per integration step, per impact and per bridge, and each entry
//! checked against its own tolerance.
//!
//! - `E = T + V` is the arm's mechanical energy (kinetic, gravity and spring; paper
//!   eq. 1's `M`, and the conservative part of `w`), J.
//! - `W_motors` is the work of the motor torques, `int u_gen . q_dot dt` with
//!   `u_gen = [u1 - u2, u2]` (paper eq. 9's generalised torque).
//! - `W_damping` is the joint damping's, `-int sigma (theta1_dot^2 + (theta2_dot -
//!   theta1_dot)^2) dt <= 0` (the non-conservative part of paper eq. 1's `w`).
//! - The contact force does work `f . z_dot` on the tip in the ground frame, split
//!   in two: `W_belt = v_belt int f_t dt` (plus `v_belt P_t` per impulse), the energy
//!   the moving belt puts in, and `W_slip = int f . [z_r_dot, z_n_dot] dt` (plus each
//!   impulse's contact work in the belt's frame), what the contact dissipates (`<= 0`
//!   for Coulomb friction and the energetically consistent impacts).
//! - `W_projections`: the energy the projections onto the contact constraint change
//!   (integration drift removed at a segment's end, a Zeno residue, a stopped slip):
//!   booked, not a violation.
//!
//! The four integrals are integrated by DOP853 with the state (components
//! [`MOTORS`] to [`SLIP`] of the plant's ODE state, outside the error norm, so
//! they set no step), to the method's order. A step whose balance
//! `E(t1) - E(t0) - sum of the works` exceeds [`step_tolerance`] is rejected and
//! taken again smaller; one that cannot be mended (its step collapses) is resolved
//! as any collapse, and a balance left broken is a violation.

use serde::{Deserialize, Serialize};
use shared::{Arm, kinematics::JointTrig};

/// Index of `W_motors` (J) in the plant's ODE state.
pub const MOTORS: usize = 6;
/// Index of `W_damping` (J).
pub const DAMPING: usize = 7;
/// Index of `W_belt` (J).
pub const BELT: usize = 8;
/// Index of `W_slip` (J).
pub const SLIP: usize = 9;

/// A step's balance may miss by this many times the energy that one unit of the
/// integrator's tolerance in each state component is worth ([`step_tolerance`]).
/// DOP853 accepts a step when its 5th-order error estimate is within one unit, so a
/// healthy step's balance misses by a few units at most: 4.8 over 300 s of
/// bouncing from `x0a` at `v_belt = -0.6` (1 906 segments), against 0.09 of 100
/// over issue 53's runs. A factor of 1 rejected 8 healthy steps of that bouncing
/// run (moving its chaotic path); 100 rejects none, and still catches a step across
/// the pole of `-b/p` (issue 53: residuals from 1e-3 J to 84 J, against a tolerance
/// of about 1e-8 J).
pub const STEP_FACTOR: f64 = 100.0;

/// The relative tolerance of an impulse's balance: the kinetic energy change
/// against the impulse's works, both exact at a fixed configuration, differ by the
/// rounding of the laws' piecewise-linear Darboux-Keller phases (about 1e-15 of the
/// energies; 1e-9 leaves six decades for a law's long sequence of phases).
pub const IMPULSE_TOLERANCE: f64 = 1e-9;

/// The arm's mechanical energy `E = T + V` (J) at `y` (`[theta1, theta1_dot,
/// theta2, theta2_dot, ..]`), from the sines and cosines `tr` of its angles.
#[inline]
pub fn energy(arm: &Arm<f64>, tr: &JointTrig<f64>, y: &[f64]) -> f64 {
    energy_with_kinetic(arm, tr, y, kinetic_energy(arm, tr, y))
}

/// The arm's kinetic energy `T = q_dot^T M q_dot / 2` (J) at `y` (`[theta1,
/// theta1_dot, theta2, theta2_dot, ..]`), from the sines and cosines `tr` of its
/// angles: the mass matrix of paper eq. 1 at `cos(theta2 - theta1)`, as
/// `Arm::kinetic_energy`; [`energy`]'s kinetic part, the same bits.
#[inline]
pub fn kinetic_energy(arm: &Arm<f64>, tr: &JointTrig<f64>, y: &[f64]) -> f64 {
    let qd = nalgebra::Vector2::new(y[1], y[3]);
    0.5 * qd.dot(&(arm.mass_matrix_cos(tr.c2 * tr.c1 + tr.s2 * tr.s1) * qd))
}

/// [`energy`] (J) given its kinetic part `t` (J, [`kinetic_energy`] at `y`, or the
/// same expression computed elsewhere): `t` plus gravity's and the spring's
/// potential at `y`'s angles (sines and cosines `tr`), the same bits as [`energy`]
/// for the same `t`.
#[inline]
pub fn energy_with_kinetic(arm: &Arm<f64>, tr: &JointTrig<f64>, y: &[f64], t: f64) -> f64 {
    let p = &arm.params;
    let spring = y[2] - y[0] + p.alpha0;
    t - p.m * p.g * p.l * (1.5 * tr.c1 + 0.5 * tr.c2) + 0.5 * p.k * spring * spring
}

/// The gradient of the arm's energy at `y` (`[theta1, theta1_dot, theta2,
/// theta2_dot, ..]`): `[dE/dtheta1 (J/rad), dE/dtheta1_dot (J s/rad), dE/dtheta2,
/// dE/dtheta2_dot]`, the kinetic coupling's and the potential's angle terms and the
/// momenta `M q_dot`, from the sines and cosines `tr` of its angles.
#[inline]
pub fn energy_gradient(arm: &Arm<f64>, tr: &JointTrig<f64>, y: &[f64]) -> [f64; 4] {
    let p = &arm.params;
    let (d1, d2) = (y[1], y[3]);
    let ml2 = p.m * p.l * p.l;
    let c21 = tr.c2 * tr.c1 + tr.s2 * tr.s1;
    let s21 = tr.s2 * tr.c1 - tr.c2 * tr.s1;
    let spring = y[2] - y[0] + p.alpha0;
    let mgl = p.m * p.g * p.l;
    let coupling = 0.5 * ml2 * s21 * d1 * d2;
    let momenta = arm.mass_matrix_cos(c21) * nalgebra::Vector2::new(d1, d2);
    [coupling + 1.5 * mgl * tr.s1 - p.k * spring, momenta[0], -coupling + 0.5 * mgl * tr.s2 + p.k * spring, momenta[1]]
}

/// The energy (J) that one unit of the integrator's tolerance in each arm state is
/// worth at `y`: `sum_i |dE/dy_i| (atol + rtol |y_i|)` over the angles and rates,
/// times [`STEP_FACTOR`], plus the rounding of the balance's terms (`8 u` of the
/// energies and works involved, `works` their sizes). The tolerance of one step's
/// balance.
#[inline]
pub fn step_tolerance(arm: &Arm<f64>, tr: &JointTrig<f64>, y: &[f64], rtol: f64, atol: f64, works: f64) -> f64 {
    let p = &arm.params;
    let g = energy_gradient(arm, tr, y);
    let sk = |v: f64| atol + rtol * v.abs();
    let unit = g[0].abs() * sk(y[0]) + g[1].abs() * sk(y[1]) + g[2].abs() * sk(y[2]) + g[3].abs() * sk(y[3]);
    let (ml2, mgl, spring) = (p.m * p.l * p.l, p.m * p.g * p.l, y[2] - y[0] + p.alpha0);
    let e_scale = ml2 * (y[1] * y[1] + y[3] * y[3]) + 2.0 * mgl + 0.5 * p.k * spring * spring;
    STEP_FACTOR * unit + 8.0 * f64::EPSILON * (e_scale + works)
}

/// The tolerance of a bridge's balance (J): the energy its convergence tolerances
/// are worth at its end `y`, `angle_tol` (rad) in each angle and `rate_tol` (rad/s)
/// in each rate (the bridge's own accuracy, docs/plant.md "The bridge"), plus the
/// rounding of the terms as [`step_tolerance`].
#[inline]
pub fn bridge_tolerance(arm: &Arm<f64>, tr: &JointTrig<f64>, y: &[f64], angle_tol: f64, rate_tol: f64, works: f64) -> f64 {
    let g = energy_gradient(arm, tr, y);
    (g[0].abs() + g[2].abs()) * angle_tol + (g[1].abs() + g[3].abs()) * rate_tol + 8.0 * f64::EPSILON * works
}

/// The ledger of a run (or its totals): the works since `t0`, the energy change,
/// the balance's residual and the checks (docs/plant.md "The energy ledger").
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Ledger {
    /// `E(t) - E(t0)`, J.
    pub energy_change_j: f64,
    /// `W_motors`, J.
    pub motors_j: f64,
    /// `W_damping`, J (`<= 0`).
    pub damping_j: f64,
    /// `W_belt`: the energy the moving belt put in through the contact force, J.
    pub belt_j: f64,
    /// `W_slip`: the contact's work in the belt's frame, J (what it dissipated, `<= 0`).
    pub slip_j: f64,
    /// `W_projections`: the energy the projections onto the constraint changed, J.
    pub projections_j: f64,
    /// The kinetic energy changes of the impulses the events table books (its
    /// `energy_change` column summed over the rows with an impulse, but the
    /// `energy_gain` rows, which repeat the row before them), J: with the trace's
    /// `E(t) - E(0)`, what the published tables close against (issue 67).
    pub events_j: f64,
    /// Impulses outside the friction cone (`P_n >= 0`, `|P_t| <= mu P_n`, to 1e-9
    /// of their size), each also a violation.
    pub impulses_outside_cone: u64,
    /// Impulses that break their own impact law's relation or bound (Newton's
    /// `v_n+ = -e v_n-`, Poisson's `P_n = (1 + e) P_c`, the energetic law's
    /// `W_r = -e^2 W_c`, friction's work `<= 0` through a Darboux-Keller process,
    /// the slip stopped by a sticking or edge impulse: [`crate::impact::breach`]),
    /// each also a violation (issue 67).
    pub impulses_off_law: u64,
    /// Velocity projections that create energy in the belt's frame or change it by
    /// more than the constraint drift they remove allows (`drift . Q_c^-1 drift /
    /// 2`, docs/plant.md "The energy ledger"), each also a violation (issue 67).
    pub projections_beyond_drift: u64,
    /// Impacts without collision where none is due (issue 81): an impulse at a tip
    /// with no approach velocity (not a projection, not the jam's tangential
    /// impact) where sliding on in the slip's direction was consistent, `p(s) / Q_22`
    /// above the crossing's resolution (1e-6, docs/plant.md "The singular point"), each
    /// also a violation.
    pub impulses_undue: u64,
    /// Velocity projections whose impulse pulls the tip onto the belt (`P_n < 0`
    /// beyond rounding: the tip had drifted off it) or lies outside the friction
    /// cone (`|P_t| > mu P_n`: a stuck tip's slip drift removed with more friction
    /// than the cone gives), issue 81: integration drift removed by an impulse no
    /// contact could give, counted, and a violation only where the drift removed exceeds
    /// twice the Zeno rule's `zeno_velocity` (2e-4 m/s; the Zeno ends leave up to 0.1
    /// mm/s) (their energy is
    /// [`Ledger::projections_unphysical_j`], their largest drift in
    /// [`Ledger::largest_projection_drift_m_s`]).
    pub projections_unphysical: u64,
    /// The energy those projections changed, J (the sum of `|dE|` in the belt's
    /// frame, each at most its drift's `drift . Q_c^-1 drift / 2`).
    pub projections_unphysical_j: f64,
    /// The largest constraint drift a velocity projection removed (the tip's
    /// normal velocity, and its slip when sticking, in the belt's frame), m/s.
    pub largest_projection_drift_m_s: f64,
    /// `energy_change_j` less every work: what the ledger does not explain, J.
    pub residual_j: f64,
    /// The largest residual of one entry (step, impact or bridge), J.
    pub worst_entry_j: f64,
    /// The largest ratio of an accepted entry's residual to its tolerance.
    pub worst_ratio: f64,
    /// The largest energy one event took from the belt (`v_belt P_t`), J.
    pub largest_event_belt_j: f64,
    /// Integration steps rejected by the ledger (and taken again smaller).
    pub refinements: u64,
    /// Entries whose balance refinement could not mend: violations.
    pub violations: u64,
}

impl std::fmt::Display for Ledger {
    /// One line: `E(t) - E(0) = -0.0123 J: motors 0 J, damping -48.3 J, belt
    /// 402 J, slip -354 J, projections 1.8e-7 J; residual 4.2e-9 J (worst entry
    /// 3.1e-11 J, 0.09 of its tolerance); largest belt input in one event 0.107 J;
    /// 267 steps refined`, then `; N projections pulling or outside the cone (E J)` and
    /// `; N VIOLATIONS` where there are.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "E(t) - E(0) = {:.6} J: motors {:.6} J, damping {:.6} J, belt {:.6} J, slip {:.6} J, projections {:.2e} J; \
             residual {:.2e} J (worst entry {:.2e} J, {:.2} of its tolerance); largest belt input in one event {:.4} J; {} steps refined",
            self.energy_change_j,
            self.motors_j,
            self.damping_j,
            self.belt_j,
            self.slip_j,
            self.projections_j,
            self.residual_j,
            self.worst_entry_j,
            self.worst_ratio,
            self.largest_event_belt_j,
            self.refinements
        )?;
        if self.projections_unphysical > 0 {
            write!(
                f,
                "; {} projections pulling or outside the cone ({:.2e} J)",
                self.projections_unphysical, self.projections_unphysical_j
            )?;
        }
        if self.violations > 0 {
            write!(f, "; {} VIOLATIONS", self.violations)?;
        }
        Ok(())
    }
}
