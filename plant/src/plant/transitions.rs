//! The discrete transitions of the plant at an event (crate docs): touchdown with
//! its impact and the Zeno rule, lift-off, `p` reaching 0, the choice of the
//! contact mode of a tip on the belt (sticking, sliding in a consistent direction,
//! flight), the impact without collision of the Painlevé paradox, the cone-violating
//! stick of the corner case, and the events and counts each one reports.

use nalgebra::Vector2;
use shared::{
    ContactMode, SlipDirection,
    contact::{classify_slipping, sliding_force, sticking_is_consistent},
};

use super::{PendingProjection, Plant};
use crate::{
    controller::Controller,
    error::SimError,
    events::{EventKind, PlantEvent},
    impact::{self, Resolution},
    phase::Phase,
    segment::{self, Boundary},
};

/// Why a contact mode is being (re)chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Entry {
    /// The initial state, or a tip that reached the belt with no normal velocity.
    Settle,
    /// After a touchdown (an impact that left the tip on the belt, or a grazing
    /// contact): a departure is a lift-off.
    Landed,
    /// Sliding reached `z_r_dot = 0`.
    SlipStopped,
    /// Sticking reached the cone's edge.
    ConeEdge,
}

impl Plant {
    /// Handles the crossing of a mode boundary at the current time.
    pub(super) fn cross<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        boundary: Boundary,
        events: &mut Vec<PlantEvent>,
    ) -> Result<(), SimError> {
        self.cone_relaxed = false;
        // A new slide, if any, has its own approach to p = 0.
        self.slide_trend = None;
        let result = self.cross_inner(ctrl, boundary, events);
        // An episode of cone violation ends when another mode is chosen.
        if !self.cone_relaxed {
            self.in_violation = false;
        }
        result
    }

    fn cross_inner<C: Controller + ?Sized>(&mut self, ctrl: &C, boundary: Boundary, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        match boundary {
            Boundary::Touchdown => {
                self.project_position()?;
                self.touch(ctrl, events, false)
            }
            Boundary::LiftOff => {
                let before = self.rel_velocity();
                self.phase = Phase::Flight;
                self.counters.lift_offs += 1;
                self.push_event(events, EventKind::LiftOff, before, None, 0.0);
                Ok(())
            }
            Boundary::PZero => {
                self.counters.p_zero += 1;
                let before = self.rel_velocity();
                // At the singular point (a located `p = 0`, `p` within the crossing's
                // resolution of 0) the edge impulse every IWC rule tends to; a segment
                // that starts with `p` well below 0 (the initial state in the Painlevé
                // region, x0a) has the law's IWC.
                let at_point = self.segment(ctrl).components(self.t, &self.y)[1].1.abs() <= super::advance::SIMULTANEOUS_P;
                self.push_event(events, EventKind::PZero, before, None, 0.0);
                self.project_contact()?;
                self.impact_without_collision_at(ctrl, events, at_point)
            }
            Boundary::Jam => {
                self.project_contact()?;
                self.resolve_jam(ctrl, events)
            }
            Boundary::SlipStops => {
                self.project_contact()?;
                self.enter_contact(ctrl, Entry::SlipStopped, events)
            }
            Boundary::ConeEdge => {
                self.project_contact()?;
                self.enter_contact(ctrl, Entry::ConeEdge, events)
            }
            // Crossed by a bridge in `advance`, never here: no mode's components name them.
            Boundary::Singular | Boundary::Collapse => {
                Err(SimError::Integrator { t: self.t, message: "a collapsed step reached the mode change (internal)".into() })
            }
        }
    }

    /// The tip is on the belt (position projected): impact if approaching, flight if
    /// separating, otherwise choose the contact mode. `initial`: the plant's initial
    /// state (a departure from it is not a lift-off).
    pub(super) fn touch<C: Controller + ?Sized>(&mut self, ctrl: &C, events: &mut Vec<PlantEvent>, initial: bool) -> Result<(), SimError> {
        let before = self.rel_velocity();
        let v_n = before[1];
        if v_n > self.cfg.zeno_velocity {
            self.phase = Phase::Flight;
            return Ok(());
        }
        let mut landing = None;
        if v_n < -self.cfg.zeno_velocity {
            let (q, _) = segment::split(&self.y);
            let qm = self.arm.q_matrix(&q);
            let imp = impact::touchdown(&qm, self.arm.params.mu, before[0], v_n, self.cfg.impact_law, self.cfg.e_n)
                .map_err(|source| SimError::Impact { t: self.t, source })?;
            let de = self.apply_impulse(&imp);
            self.counters.touchdowns += 1;
            let after = self.rel_velocity();
            if after[1] > self.cfg.zeno_velocity {
                self.phase = Phase::Flight;
                self.counters.bounces += 1;
                self.push_event(events, EventKind::Touchdown, before, Some(&imp), de);
                self.check_impact(events, &imp, &qm, de, before);
                return Ok(());
            }
            // The tip stays on the belt: the row records the mode chosen below, not
            // the flight it ended (as a Zeno end's does).
            landing = Some(events.len());
            self.push_event(events, EventKind::Touchdown, before, Some(&imp), de);
            self.check_impact(events, &imp, &qm, de, before);
        }
        // Grazing contact or the end of a bounce sequence: remove what is left of
        // the normal velocity and stay on the belt. A residue at rounding level (a
        // plastic impact leaves ~1e-17 m/s) is removed without counting a Zeno stop.
        let residual = self.rel_velocity();
        let mut zeno = None;
        if residual[1] != 0.0 {
            let rounding = 1e-12 + 1e-9 * before.norm();
            if residual[1].abs() > rounding {
                self.counters.zeno_stops += 1;
                zeno = Some(events.len());
            }
            let (imp, de) = self.project_contact_velocity(false)?;
            if zeno.is_some() {
                self.push_event(events, EventKind::ZenoEnded, residual, Some(&imp), de);
            }
        }
        // A departure is a lift-off after a real arrival (an impact, or a residue the
        // Zeno rule removed); not from the initial state, nor after a zero-velocity
        // "touchdown" of a tip that never left the belt (flight starting into it).
        let landed = !initial && (v_n < -self.cfg.zeno_velocity || zeno.is_some());
        let entry = if landed { Entry::Landed } else { Entry::Settle };
        let chosen = self.enter_contact(ctrl, entry, events);
        // The Zeno event and a touchdown that stays on the belt record the mode chosen after them.
        for i in [landing, zeno].into_iter().flatten() {
            events[i].mode_after = self.mode();
        }
        chosen
    }

    /// Chooses the contact mode of a tip on the belt with `z_n_dot = 0` (docs/model.md's
    /// table, plus sticking), resolving the paradox by an impact without collision.
    fn enter_contact<C: Controller + ?Sized>(&mut self, ctrl: &C, entry: Entry, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        let was_sliding = matches!(self.phase, Phase::Sliding(_));
        let previous_dir = self.slip_direction();
        let mut before = self.rel_velocity();
        let mu = self.arm.params.mu;
        let at_rest = before[0].abs() <= self.cfg.v_stick || matches!(entry, Entry::SlipStopped | Entry::ConeEdge);
        if at_rest {
            // Start from exactly zero slip, so that the chosen mode starts inside its domain
            // (its own row when it stops more than a located event leaves; the mode's
            // row below then starts from the projected velocity).
            self.project_at_event(true, events)?;
            before = self.rel_velocity();
        }
        self.phase = Phase::Sticking; // evaluate sticking forces
        let (td, f_stick, _) = self.segment(ctrl).evaluate(self.t, &self.y, &mut [0.0; 2]);
        let dir = if at_rest {
            if entry != Entry::ConeEdge && sticking_is_consistent(&f_stick, mu) {
                self.project_at_event(true, events)?;
                self.phase = Phase::Sticking;
                self.counters.stick_phases += 1;
                self.push_event(events, EventKind::SlipToStick, before, None, 0.0);
                return Ok(());
            }
            // Slip from rest: a direction whose sliding solution accelerates the
            // slip that way (consistent), preferring the one the sticking force points to.
            let preferred = SlipDirection::of(-f_stick[0]);
            let consistent = |s: SlipDirection| {
                if !(td.p(mu, s) > 0.0 && td.b() < 0.0) {
                    return false;
                }
                let f = sliding_force(&td, mu, s);
                let acc = td.a_free[0] + td.qmat[(0, 0)] * f[0] + td.qmat[(0, 1)] * f[1];
                s.sign::<f64>() * acc > 0.0
            };
            // At the cone's edge the sliding force in the preferred direction equals the
            // sticking force, so the slip acceleration is exactly 0 there and its sign
            // comes from the trend: the edge is crossed, take that direction (standard
            // stick-to-slip) unless sliding that way is itself inconsistent (p <= 0).
            let edge = entry == Entry::ConeEdge && td.p(mu, preferred) > 0.0 && td.b() < 0.0;
            let choice = if edge { Some(preferred) } else { [preferred, preferred.reversed()].into_iter().find(|&s| consistent(s)) };
            match choice {
                Some(s) => s,
                None if td.b() < 0.0 => {
                    // Neither sticking nor slipping is consistent and the tip is pressed
                    // on the belt: hold it stuck, cone ignored, until lift-off or the end of the
                    // interval, then solve the contact problem again (crate docs, corner case).
                    self.project_at_event(true, events)?;
                    self.phase = Phase::Sticking;
                    self.cone_relaxed = true;
                    self.enter_violation(events, before);
                    return Ok(());
                }
                None => preferred,
            }
        } else {
            SlipDirection::of(before[0])
        };
        match classify_slipping(td.b(), td.p(mu, dir)) {
            ContactMode::Sliding => {
                self.phase = Phase::Sliding(dir);
                match entry {
                    Entry::ConeEdge => {
                        self.counters.stick_to_slip += 1;
                        self.push_event(events, EventKind::StickToSlip, before, None, 0.0);
                    }
                    Entry::SlipStopped if was_sliding && previous_dir != Some(dir) => {
                        self.counters.slip_reversals += 1;
                        self.push_event(events, EventKind::SlipReversal, before, None, 0.0);
                    }
                    _ => {}
                }
                Ok(())
            }
            ContactMode::Flight | ContactMode::Indeterminate => {
                self.phase = Phase::Flight;
                if entry != Entry::Settle || was_sliding {
                    // Leaving the belt after a touchdown, a stop of the slip or from
                    // sliding: a lift-off (a departure from the initial state is not).
                    self.counters.lift_offs += 1;
                    self.push_event(events, EventKind::LiftOff, before, None, 0.0);
                }
                Ok(())
            }
            _ if !at_rest => {
                self.phase = Phase::Sliding(dir);
                self.impact_without_collision(ctrl, events)
            }
            _ => {
                // No slip to stop and no consistent force: documented corner case.
                self.project_at_event(true, events)?;
                self.phase = Phase::Sticking;
                self.cone_relaxed = true;
                self.enter_violation(events, before);
                Ok(())
            }
        }
    }

    /// Starts (or continues) a cone-violating stick; reported once per episode.
    /// Not at `mu = 0`: with no friction there is no cone to leave. There `p =
    /// Q22 > 0`, so the inconsistent mode cannot occur, and the only way here is a
    /// tip at rest whose slip acceleration is zero to rounding in both directions
    /// (an equilibrium): held, it needs no tangential force, a frictionless rest
    /// (issue 39: 17 of 240 fuzzed runs at `mu = 0` were flagged INVALID for it).
    pub(super) fn enter_violation(&mut self, events: &mut Vec<PlantEvent>, before: Vector2<f64>) {
        if self.arm.params.mu == 0.0 {
            return;
        }
        if !self.in_violation {
            self.in_violation = true;
            self.counters.cone_violations += 1;
            self.push_event(events, EventKind::ConeViolation, before, None, 0.0);
        }
    }

    /// The Painlevé resolution: an impact without collision from sliding.
    fn impact_without_collision<C: Controller + ?Sized>(&mut self, ctrl: &C, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        self.impact_without_collision_at(ctrl, events, false)
    }

    /// [`Plant::impact_without_collision`]; `at_p_zero`: at the singular point
    /// (a slide that reached `p = b = 0`), with the edge impulse every IWC rule
    /// tends to there ([`impact::at_p_zero`]), else the law's and the IWC rule's.
    fn impact_without_collision_at<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        events: &mut Vec<PlantEvent>,
        at_p_zero: bool,
    ) -> Result<(), SimError> {
        let before = self.rel_velocity();
        let (q, _) = segment::split(&self.y);
        let qm = self.arm.q_matrix(&q);
        let mu = self.arm.params.mu;
        let imp = match at_p_zero.then(|| impact::at_p_zero(&qm, mu, before[0])) {
            Some(Ok(imp)) => Ok(imp),
            _ => impact::without_collision(&qm, mu, before[0], self.cfg.impact_law, self.cfg.e_n, self.cfg.iwc),
        }
        .map_err(|source| SimError::Impact { t: self.t, source })?;
        let de = self.apply_impulse(&imp);
        self.counters.impacts_without_collision += 1;
        let after = self.rel_velocity();
        if after[1] > self.cfg.zeno_velocity {
            self.phase = Phase::Flight;
            self.counters.lift_offs += 1;
            self.push_event(events, EventKind::ImpactWithoutCollision, before, Some(&imp), de);
            self.check_impact(events, &imp, &qm, de, before);
            return Ok(());
        }
        self.push_event(events, EventKind::ImpactWithoutCollision, before, Some(&imp), de);
        self.check_impact(events, &imp, &qm, de, before);
        self.project_at_event(false, events)?;
        // The slip has been stopped (v_r = 0): choose stick or slip from rest.
        self.enter_contact(ctrl, Entry::SlipStopped, events)
    }

    /// The dynamic jam (`f_n` up to `jam_load m g` as `p -> 0+` with `b < 0`): the
    /// tangential impact ([`impact::jam`]) stops the slip, then the contact mode is
    /// chosen from rest, or the tip leaves the belt if the impulse left it moving off.
    fn resolve_jam<C: Controller + ?Sized>(&mut self, ctrl: &C, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        let before = self.rel_velocity();
        let (q, _) = segment::split(&self.y);
        let qm = self.arm.q_matrix(&q);
        let imp = impact::jam(&qm, self.arm.params.mu, before[0]).map_err(|source| SimError::Impact { t: self.t, source })?;
        let de = self.apply_impulse(&imp);
        self.counters.jams += 1;
        let after = self.rel_velocity();
        self.push_event(events, EventKind::Jam, before, Some(&imp), de);
        self.check_impact(events, &imp, &qm, de, before);
        if after[1] > self.cfg.zeno_velocity {
            self.phase = Phase::Flight;
            self.counters.lift_offs += 1;
            return Ok(());
        }
        self.project_at_event(false, events)?;
        self.enter_contact(ctrl, Entry::SlipStopped, events)
    }

    /// A velocity projection at an event ([`Plant::project_contact_velocity`];
    /// `sticking`: the slip too), reported as a `velocity_projection` row with its
    /// impulse and energy change when it moves the tip's relative velocity by more
    /// than a located event leaves ([`segment::ROOT_TOLERANCE`], 1e-6 m/s: the
    /// residue of a slip stop or of an impulse at `p` near 0), so that every
    /// impulse the ledger books at an event beyond that is in the table (issue 67).
    ///
    /// A smaller projection with an impulse is booked too (issue 81): on the next row
    /// pushed at the same instant that has no impulse of its own (a `slip_to_stick`,
    /// a `lift_off`), which then carries it with resolution `projection`, or else as
    /// its own `velocity_projection` row ([`Plant::flush_projection`]).
    fn project_at_event(&mut self, sticking: bool, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        let before = self.rel_velocity();
        let (imp, de) = self.project_contact_velocity(sticking)?;
        if (self.rel_velocity() - before).norm() > segment::ROOT_TOLERANCE {
            self.flush_projection(events);
            self.push_event(events, EventKind::VelocityProjection, before, Some(&imp), de);
        } else if imp.p != Vector2::zeros() || de != 0.0 {
            if self.pending_projection.is_some_and(|p| p.t != self.t) {
                self.flush_projection(events);
            }
            let pending = self.pending_projection.get_or_insert(PendingProjection {
                t: self.t,
                before,
                p: Vector2::zeros(),
                de: 0.0,
                contact_work: 0.0,
            });
            pending.p += imp.p;
            pending.de += de;
            pending.contact_work += imp.contact_work;
        }
        Ok(())
    }

    /// Books a pending projection ([`Plant::project_at_event`]) as its own
    /// `velocity_projection` row at its instant.
    pub(crate) fn flush_projection(&mut self, events: &mut Vec<PlantEvent>) {
        if let Some(p) = self.pending_projection.take() {
            self.ledger.events_j += p.de;
            let after = self.rel_velocity();
            events.push(PlantEvent {
                t: p.t,
                kind: EventKind::VelocityProjection,
                mode_after: self.mode(),
                v_n_before: p.before[1],
                v_n_after: after[1],
                v_r_before: p.before[0],
                v_r_after: after[0],
                impulse: [p.p[0], p.p[1]],
                energy_change: p.de,
                contact_work: p.contact_work,
                resolution: Some(Resolution::Projection),
            });
        }
    }
}
