//! Projections of the plant's state onto the contact constraint: the tip onto the
//! belt (position), and the constrained velocity components removed by the
//! smallest kinetic-energy correction (crate docs).

use nalgebra::Vector2;
use shared::{
    ElbowBranch,
    kinematics::{inverse_kinematics, jacobian_trig, tip_position_trig},
};

use super::Plant;
use crate::{error::SimError, phase::Phase, segment};

impl Plant {
    /// Puts the tip exactly on the belt at the same `z_t` and elbow branch,
    /// keeping the angles on the same turn.
    ///
    /// The usual drift after an interval (well under a micrometre) is removed by one
    /// Newton step on `z(q) = [z_t, -H]`, whose error is quadratic in the step:
    /// with the step at most `1e-8` rad it is below rounding, the same result as
    /// the inverse kinematics (used otherwise) without its `acos` and `atan2`.
    pub(super) fn project_position(&mut self) -> Result<(), SimError> {
        let e = self.energy();
        let moved = self.project_position_only();
        self.ledger.projections_j += self.energy() - e;
        moved
    }

    fn project_position_only(&mut self) -> Result<(), SimError> {
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
    /// correction: `z_n_dot -> 0`, and `z_r_dot -> 0` too when `sticking`. The
    /// correction is an impulse at the tip, booked in the energy ledger as one.
    pub(super) fn project_contact_velocity(&mut self, sticking: bool) -> Result<(), SimError> {
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
        // The kinetic energies from the same sines and cosines (`Arm::kinetic_energy` at
        // cos(theta2 - theta1) without its `cos`).
        let m = self.arm.mass_matrix_cos(trig.c2 * trig.c1 + trig.s2 * trig.s1);
        let ke = 0.5 * qd.dot(&(m * qd));
        self.y[1] += dqd[0];
        self.y[3] += dqd[1];
        let (_, qd_new) = segment::split(&self.y);
        let ke_new = 0.5 * qd_new.dot(&(m * qd_new));
        let v_new = jac * qd_new;
        let mid = Vector2::new(0.5 * (v[0] + v_new[0]) - self.arm.params.v_belt, 0.5 * (v[1] + v_new[1]));
        self.book_impulse(lambda, lambda.dot(&mid), ke_new - ke, ke + ke_new);
        Ok(())
    }

    /// Projection onto the contact constraint of the current mode (no-op in flight).
    pub(super) fn project_contact(&mut self) -> Result<(), SimError> {
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
