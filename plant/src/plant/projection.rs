//! Projections of the plant's state onto the contact constraint: the tip onto the
//! belt (position), and the constrained velocity components removed by the
//! smallest kinetic-energy correction (crate docs).

use nalgebra::Vector2;
use shared::{
    ElbowBranch,
    kinematics::{inverse_kinematics, jacobian_trig, tip_position_trig},
};

use super::Plant;
use crate::{
    error::SimError,
    impact::{Impulse, Resolution},
    phase::Phase,
    segment,
};

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
        let trig = self.trig_here();
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
    /// correction is an impulse at the tip, booked in the energy ledger as one;
    /// returns it (`p` in N s, `dv` in m/s, its work on the relative motion in J,
    /// resolution [`Resolution::Projection`]) with the kinetic energy change (J).
    pub(super) fn project_contact_velocity(&mut self, sticking: bool) -> Result<(Impulse, f64), SimError> {
        self.project_velocity_booking(sticking, None)
    }

    /// [`Plant::project_contact_velocity`]; with `e_position`, the energy (J) before
    /// a position projection that has just moved the angles, whose share of the
    /// ledger it books first (as [`Plant::project_position`] does), from the
    /// kinetic energy and the sines and cosines it computes anyway. Keeps the
    /// projected state's energy and sines and cosines for the next interval ([`super::Known`]).
    fn project_velocity_booking(&mut self, sticking: bool, e_position: Option<f64>) -> Result<(Impulse, f64), SimError> {
        let (_, qd) = segment::split(&self.y);
        let trig = self.trig_here();
        let jac = jacobian_trig(self.arm.params.l, &trig);
        let m_inv = self.arm.mass_matrix_inverse_trig(&trig);
        let qm = jac * m_inv * jac.transpose();
        let v = jac * qd;
        // The drift removed: the constrained components of the tip's velocity in the
        // belt's frame (the normal one; the slip too when sticking).
        let drift = Vector2::new(if sticking { v[0] - self.arm.params.v_belt } else { 0.0 }, v[1]);
        let (lambda, drift_energy) = if sticking {
            qm.try_inverse().map_or((Vector2::zeros(), 0.0), |inv| {
                let lambda = inv * -drift;
                (lambda, -0.5 * drift.dot(&lambda))
            })
        } else {
            (Vector2::new(0.0, -v[1] / qm[(1, 1)]), 0.5 * v[1] * v[1] / qm[(1, 1)])
        };
        let dqd = m_inv * (jac.transpose() * lambda);
        // The kinetic energies from the same sines and cosines (`Arm::kinetic_energy` at
        // cos(theta2 - theta1) without its `cos`).
        let m = self.arm.mass_matrix_cos(trig.c2 * trig.c1 + trig.s2 * trig.s1);
        let ke = 0.5 * qd.dot(&(m * qd));
        if let Some(e) = e_position {
            // `Plant::energy` after the position's projection: `ledger::energy`'s kinetic part is `ke`.
            self.ledger.projections_j += crate::ledger::energy_with_kinetic(&self.arm, &trig, &self.y, ke) - e;
        }
        self.y[1] += dqd[0];
        self.y[3] += dqd[1];
        let (_, qd_new) = segment::split(&self.y);
        let ke_new = 0.5 * qd_new.dot(&(m * qd_new));
        let v_new = jac * qd_new;
        let mid = Vector2::new(0.5 * (v[0] + v_new[0]) - self.arm.params.v_belt, 0.5 * (v[1] + v_new[1]));
        let work = lambda.dot(&mid);
        self.book_impulse(lambda, work, ke_new - ke, ke + ke_new);
        self.check_projection(lambda, work, drift, drift_energy);
        let energy = crate::ledger::energy_with_kinetic(&self.arm, &trig, &self.y, ke_new);
        self.known = Some(super::Known { x: [self.y[0], self.y[1], self.y[2], self.y[3]], trig, energy });
        let imp = Impulse {
            p: lambda,
            dv: v_new - v,
            v_n_min: 0.0,
            contact_work: work,
            resolution: Resolution::Projection,
            compression: Default::default(),
        };
        Ok((imp, ke_new - ke))
    }

    /// The ledger's check of a velocity projection (issue 67): it removes the
    /// constraint's drift `drift` (m/s: the tip's velocity in the belt's frame along
    /// the constrained directions) by the impulse `p` (N s), whose work in the
    /// belt's frame is `work` (J). The smallest kinetic-energy correction
    /// dissipates exactly `drift_energy = drift . Q_c^-1 drift / 2` there (J;
    /// `Q_c` the constrained block of `Q = J M^-1 J^T`, paper eq. 3): a projection
    /// that creates energy in the belt's frame, or that changes it by more than
    /// the drift it removes allows, is a violation, counted apart in
    /// [`Ledger::projections_beyond_drift`](crate::Ledger::projections_beyond_drift).
    /// The largest drift removed is kept in
    /// [`Ledger::largest_projection_drift_m_s`](crate::Ledger::largest_projection_drift_m_s).
    /// The allowance is rounding: `1e-6` of `drift_energy`, and `|p|` times 1e-14
    /// (1 + `|drift|`) m/s, the rounding of the velocities the work is taken from.
    /// A projection that pulls the tip (`P_n < 0`) or lies outside the friction cone
    /// is counted in [`Ledger::projections_unphysical`](crate::Ledger::projections_unphysical)
    /// with its energy (issue 81), and is a violation where the drift it removes exceeds
    /// twice [`SimConfig::zeno_velocity`](crate::SimConfig::zeno_velocity) (2e-4 m/s).
    pub(crate) fn check_projection(&mut self, p: Vector2<f64>, work: f64, drift: Vector2<f64>, drift_energy: f64) {
        let mu = self.arm.params.mu;
        let l = &mut self.ledger;
        l.largest_projection_drift_m_s = l.largest_projection_drift_m_s.max(drift.norm());
        // A pull, or friction beyond the cone (issue 81), to 1e-9 of the impulse's size.
        let round = 1e-9 * p.norm();
        if p[1] < -round || p[0].abs() > mu * p[1].max(0.0) + round {
            l.projections_unphysical += 1;
            l.projections_unphysical_j += work.abs();
            // Beyond twice the Zeno rule's own resolution (a bounce below `zeno_velocity`
            // is ended by removing what is left of it, a pull by design, up to 0.1 mm/s
            // measured): no drift the integration leaves is that large, a violation.
            if drift.norm() > 2.0 * self.cfg.zeno_velocity {
                l.violations += 1;
            }
        }
        let slack = 1e-6 * drift_energy + 1e-14 * p.norm() * (1.0 + drift.norm());
        let beyond = work > slack || -work > drift_energy + slack || work.is_nan();
        if beyond {
            l.projections_beyond_drift += 1;
            l.violations += 1;
        }
    }

    /// Projection onto the contact constraint of the current mode (no-op in flight).
    ///
    /// [`Plant::project_position`] then [`Plant::project_contact_velocity`], the
    /// position's share of the ledger booked from the velocity's kinetic energy and
    /// sines and cosines: the same values, two energies and a look-up fewer (issue 56).
    pub(super) fn project_contact(&mut self) -> Result<(), SimError> {
        let sticking = match self.phase {
            Phase::Flight => return Ok(()),
            Phase::Sliding(_) => false,
            Phase::Sticking => true,
        };
        let e = self.energy();
        if let Err(err) = self.project_position_only() {
            self.ledger.projections_j += self.energy() - e;
            return Err(err);
        }
        self.project_velocity_booking(sticking, Some(e)).map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use shared::Params;

    use super::super::{Known, Plant};
    use crate::{
        Hold, NoObserver, SimConfig,
        initial::{X0A, X0D, deg_to_state},
        phase::Phase,
    };

    /// The projection after a solve ([`Plant::project_contact`], from what the solve
    /// left [`Known`]) leaves the same state and books the same ledger, to the bit,
    /// as the position's projection then the velocity's with every energy computed
    /// afresh; and what it leaves known is the energy computed afresh. Over the
    /// contact periods of two open-loop runs, each state moved off the constraint
    /// first (as a step's drift does, and more).
    #[test]
    fn the_projection_from_known_values_is_the_two_projections_to_the_bit() {
        let bits = |y: &[f64]| y.iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
        let mut checked = [0usize; 2];
        for (x0, v_belt) in [(X0A, -0.5), (X0D, 0.3)] {
            let params = Params { v_belt, ..Params::paper() };
            let mut plant = Plant::new(params, SimConfig::default(), deg_to_state(x0.deg), 0.0, [0.0, 0.0]).unwrap();
            for k in 0..3000 {
                plant.advance(&Hold([0.2, -0.1]), 1e-3, &mut NoObserver).unwrap();
                let sticking = match plant.phase {
                    Phase::Flight => continue,
                    Phase::Sliding(_) => false,
                    Phase::Sticking => true,
                };
                let mut fused = plant.clone();
                let drift = 1e-9 * f64::from(k % 7 + 1);
                fused.y[0] += drift;
                fused.y[2] -= 0.5 * drift;
                fused.y[3] += 1e3 * drift;
                fused.known = None;
                let mut apart = fused.clone();
                let x = [fused.y[0], fused.y[1], fused.y[2], fused.y[3]];
                let trig = fused.trig.get(&nalgebra::Vector2::new(x[0], x[2]));
                fused.known = Some(Known { x, trig, energy: fused.energy() });
                fused.project_contact().unwrap();
                apart.project_position().unwrap();
                apart.project_contact_velocity(sticking).unwrap();
                assert_eq!(bits(&fused.y), bits(&apart.y), "state at {} s", plant.t);
                assert_eq!(fused.ledger, apart.ledger, "ledger at {} s", plant.t);
                let known = fused.energy();
                fused.known = None;
                assert_eq!(known.to_bits(), fused.energy().to_bits(), "the kept energy at {} s", plant.t);
                checked[usize::from(sticking)] += 1;
            }
        }
        assert!(checked[0] > 100, "slides checked: {checked:?}");
    }
}
