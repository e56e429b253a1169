//! The impulses of the plant's transitions: applying a tip impulse to the joint
//! velocities, booking it in the energy ledger with its works, checking it (the
//! cone, energy, the contact's own laws) and reporting it as an event.

use nalgebra::Vector2;
use shared::SlipDirection;

use super::Plant;
use crate::{
    events::{EventKind, PlantEvent},
    impact::{self, Impulse, Resolution},
    segment,
};

impl Plant {
    /// Applies a tip impulse: `q_dot += M^-1 J^T P`; returns the kinetic energy change
    /// (J), booked in the energy ledger with the impulse's works.
    pub(super) fn apply_impulse(&mut self, imp: &Impulse) -> f64 {
        let (q, qd) = segment::split(&self.y);
        let before = self.arm.kinetic_energy(&q, &qd);
        let jac = shared::kinematics::jacobian(self.arm.params.l, &q);
        let dqd = self.arm.mass_matrix_inverse(&q) * (jac.transpose() * imp.p);
        self.y[1] += dqd[0];
        self.y[3] += dqd[1];
        let (q, qd) = segment::split(&self.y);
        let after = self.arm.kinetic_energy(&q, &qd);
        self.book_impulse(imp.p, imp.contact_work, after - before, before + after);
        after - before
    }

    /// Books an impulse `p = [P_t, P_n]` (N s) at the tip in the energy ledger: the
    /// belt's work `v_belt P_t` and the work in the belt's frame `rel_work` (J), and
    /// checks that they explain the kinetic energy change `de` (J; `ke` the kinetic
    /// energies' sum, the rounding's scale). At a fixed configuration `T = v Q^-1 v / 2`
    /// for the tip velocity `v`, so `dT = int v . dP` exactly, whatever the law.
    pub(super) fn book_impulse(&mut self, p: Vector2<f64>, rel_work: f64, de: f64, ke: f64) {
        use crate::ledger::{BELT, SLIP};
        let belt = self.arm.params.v_belt * p[0];
        self.y[BELT] += belt;
        self.y[SLIP] += rel_work;
        self.ledger.largest_event_belt_j = self.ledger.largest_event_belt_j.max(belt);
        let residual = (de - (belt + rel_work)).abs();
        let tol = crate::ledger::IMPULSE_TOLERANCE * (ke + belt.abs() + rel_work.abs()) + 1e-15;
        self.ledger.worst_entry_j = self.ledger.worst_entry_j.max(residual);
        self.ledger.worst_ratio = self.ledger.worst_ratio.max(residual / tol);
        if residual > tol || residual.is_nan() {
            self.ledger.violations += 1;
        }
    }

    /// Counts a law's fallback to the energetic one, reports an impact whose
    /// contact work is positive (it created energy: a broken law, never expected),
    /// and holds the impulse (`before`: the relative velocity before it, m/s) to the
    /// ledger's checks (issue 67): in the friction cone, and keeping its own law's
    /// relation and bound ([`impact::breach`]); each failure is a violation.
    pub(crate) fn check_impact(
        &mut self,
        events: &mut Vec<PlantEvent>,
        imp: &Impulse,
        qm: &nalgebra::Matrix2<f64>,
        de: f64,
        before: Vector2<f64>,
    ) {
        match imp.resolution {
            Resolution::NewtonFallback => self.counters.newton_fallbacks += 1,
            Resolution::PoissonFallback => self.counters.poisson_fallbacks += 1,
            _ => {}
        }
        // The same rounding allowance the laws' fallback uses.
        if imp.contact_work > impact::work_tolerance(qm, before[0], before[1]) {
            self.counters.energy_gains += 1;
            self.counters.max_energy_gain = self.counters.max_energy_gain.max(imp.contact_work);
            events.push(self.make_event(EventKind::EnergyGain, before, Some(imp), de));
            // The ledger's own check of the impulse (issue 67): the contact must
            // not create energy in the belt's frame, whatever the law.
            self.ledger.violations += 1;
        }
        // And the impulse must lie in the friction cone (Coulomb's law for an
        // impulse: `P_n >= 0`, `|P_t| <= mu P_n`), to rounding of its size.
        if !impulse_in_cone(imp.p, self.arm.params.mu) {
            self.ledger.violations += 1;
            self.ledger.impulses_outside_cone += 1;
        }
        // And it must keep its own law's relation and bound (Newton's `v_n+ = -e
        // v_n-`, Poisson's `P_n = (1 + e) P_c`, the energetic `W_r = -e^2 W_c`,
        // friction's work `<= 0` through the process, ...: `impact::breach`).
        if impact::breach(imp, qm, self.arm.params.mu, self.cfg.e_n, before).is_some() {
            self.ledger.violations += 1;
            self.ledger.impulses_off_law += 1;
        }
        // And it must be due (issue 81): an impulse at a tip with no approach velocity
        // (an impact without collision) only where sliding on in the slip's direction is
        // inconsistent, `p(s) <= 0`, the Painlevé region, or at the singular point, to the
        // crossing's resolution. The jam's tangential impact (`p > 0`, the force grown
        // without bound) and a projection are due elsewhere.
        let no_approach = before[1].abs() <= self.cfg.zeno_velocity;
        if no_approach && !matches!(imp.resolution, Resolution::Projection | Resolution::TangentialImpact) {
            let p = shared::slip::p_of(qm, self.arm.params.mu, SlipDirection::of(before[0]));
            if p > super::advance::SIMULTANEOUS_P * qm[(1, 1)] {
                self.ledger.violations += 1;
                self.ledger.impulses_undue += 1;
            }
        }
    }

    pub(super) fn make_event(&self, kind: EventKind, before: Vector2<f64>, imp: Option<&Impulse>, de: f64) -> PlantEvent {
        let after = self.rel_velocity();
        PlantEvent {
            t: self.t,
            kind,
            mode_after: self.mode(),
            v_n_before: before[1],
            v_n_after: after[1],
            v_r_before: before[0],
            v_r_after: after[0],
            impulse: imp.map_or([0.0; 2], |i| [i.p[0], i.p[1]]),
            energy_change: de,
            contact_work: imp.map_or(0.0, |i| i.contact_work),
            resolution: imp.map(|i| i.resolution),
        }
    }

    /// Pushes an event row; one with an impulse adds its kinetic energy change to
    /// the ledger's [`Ledger::events_j`](crate::ledger::Ledger::events_j), the sum
    /// of the table's `energy_change` (issue 67; an `energy_gain` row, which
    /// repeats the impulse of the row before it, is pushed apart).
    pub(super) fn push_event(
        &mut self,
        events: &mut Vec<PlantEvent>,
        kind: EventKind,
        before: Vector2<f64>,
        imp: Option<&Impulse>,
        de: f64,
    ) {
        // A pending projection at this instant rides on a row with no impulse of its own
        // (an `energy_gain` or `cone_violation` row is a report, not a booking).
        let carries = imp.is_none() && !matches!(kind, EventKind::EnergyGain | EventKind::ConeViolation);
        match self.pending_projection {
            Some(p) if carries && p.t == self.t => {
                self.pending_projection = None;
                self.ledger.events_j += p.de;
                let mut row = self.make_event(kind, before, None, p.de);
                (row.impulse, row.contact_work, row.resolution) = ([p.p[0], p.p[1]], p.contact_work, Some(Resolution::Projection));
                events.push(row);
                return;
            }
            Some(_) => self.flush_projection(events),
            None => {}
        }
        if imp.is_some() {
            self.ledger.events_j += de;
        }
        events.push(self.make_event(kind, before, imp, de));
    }
}

/// Whether an impulse `p = [P_t, P_n]` (N s) lies in the friction cone of
/// coefficient `mu`: `P_n >= 0` and `|P_t| <= mu P_n`, each to `1e-9` of the
/// impulse's size (rounding of the laws' closed forms and Darboux-Keller sums).
pub(crate) fn impulse_in_cone(p: Vector2<f64>, mu: f64) -> bool {
    let slack = 1e-9 * p.norm();
    p[1] >= -slack && p[0].abs() <= mu * p[1] + slack
}
