//! The bridge across a collapsed event-driven step (docs/plant.md "The bridge"):
//! a stretch of Moreau-Jean time-stepping ([`crate::moreau_jean`]) from the last
//! accepted point, refined until it agrees with itself at half the step, after
//! which the event-driven integration resumes from a consistent state. At the
//! singular point `p = b = 0` it is the rule's resolution ([`SingularRule`]).

use nalgebra::Vector2;
use shared::{Arm, ContactMode, contact::p_of};

use super::{Plant, Sample};
use crate::{
    controller::Controller,
    dop853::{DenseStep, State},
    error::SimError,
    events::{EventKind, PlantEvent},
    ledger::{BELT, DAMPING, MOTORS, SLIP},
    moreau_jean::{ContactSolution, SingularRule, contact_impulse},
    observer::Observer,
    phase::Phase,
    segment::{Boundary, OdeState, STATE_LEN},
};

/// Largest difference of the joint angles (rad) between a bridge and the same
/// bridge at half its step for it to count as converged: 1e-6 rad, 0.2 um at the
/// tip, a few hundredths of the 14-bit encoders' quantum (3.8e-4 rad).
pub const BRIDGE_TOLERANCE: f64 = 1e-6;

/// Largest difference of the joint rates (rad/s) between a bridge and the same
/// bridge at half its step for it to count as converged (issue 53: the angles
/// alone let a bridge end with its velocities first-order wrong). 1e-4 rad/s carried
/// over the 0.18 s of a bounce moves the angles by 1.8e-5 rad, 5 % of the 14-bit
/// encoders' quantum: below what the firmware reads, as [`BRIDGE_TOLERANCE`] is.
pub const BRIDGE_RATE_TOLERANCE: f64 = 1e-4;

/// Smallest step a bridge is refined to, s: below it the bridge has not converged
/// and the run fails ([`SimError::Bridge`]).
pub const BRIDGE_STEP_FLOOR: f64 = 1e-9;

/// Predicted gap (m) at which a bridge step counts the contact as active: the
/// scheme's position drift off the belt (second order in the step, from the
/// curvature of the tip's path) must not end a contact the impulse holds, as a
/// gap of exactly 0 would.
pub const BRIDGE_CONTACT_GAP: f64 = 1e-9;

/// One stretch of time-stepping: the states at the step ends (the first is the
/// start) and the contact solution of the last step.
pub(crate) struct Stretch {
    /// The step, s.
    pub h: f64,
    /// The states at the step ends, the start first.
    pub states: Vec<OdeState>,
    /// The contact solution of the last step.
    pub last: ContactSolution,
    /// Each step's contact mode and mean contact force `P / h` (`[f_t, f_n]`, N; 0 for
    /// a step whose impulse is booked).
    pub forces: Vec<(ContactMode, [f64; 2])>,
    /// Each step's booked impulse: `P` (N s) and the joint velocity change it makes,
    /// `M^-1 J^T P` (rad/s), where `|P|` is at least [`BRIDGE_IMPULSE_LOAD`] `m g h`.
    pub kicks: Vec<Option<(Vector2<f64>, Vector2<f64>)>>,
}

/// The load, in units of `m g`, above which a bridge step's contact impulse `P` is
/// booked as an impulse (a `bridge_impulse` row acting at the step's start) rather than
/// shown as the force `P / h` over the step: the jam's onset load
/// ([`crate::segment::JAM_ONSET_LOAD`], 10), beyond which the plant no longer takes a
/// contact force for a normal reaction. An impact or the slip stopped at the singular
/// point gives `P` of order 1e-2 N s at the bridge's 10 us step (a thousand times the
/// load); a slide through the indeterminate region at a few newtons stays a force. A
/// booked impulse is in the events table, so a ledger rebuilt from the published tables
/// closes across it (issue 81: under `--singular slide` the crossing's impulse,
/// 0.03 to 0.17 J, was in no row).
pub const BRIDGE_IMPULSE_LOAD: f64 = crate::segment::JAM_ONSET_LOAD;

impl Plant {
    /// Crosses a collapsed step by a bridge from the current (last accepted)
    /// state: `why` is [`Boundary::Singular`] or [`Boundary::Collapse`] (or
    /// [`Boundary::Collapse`] again to go on with a slide through the singular
    /// point). The bridge ends after `bridge_length` s or at `t_end`, whichever is
    /// first, and the contact mode is then chosen afresh (`touch`), unless the
    /// singular rule [`SingularRule::Slide`] keeps the tip sliding in the
    /// indeterminate region (`p < 0, b > 0`), where the next loop of `advance`
    /// goes on time-stepping. `obs` sees each step (linear between its ends).
    ///
    /// # Errors
    /// [`SimError::Bridge`] if the bridge does not converge (its angles at two
    /// steps still differ by more than [`BRIDGE_TOLERANCE`] at
    /// [`BRIDGE_STEP_FLOOR`]) or its state is not finite; a failure of the
    /// following mode choice.
    pub(crate) fn bridge<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        why: Boundary,
        t_end: f64,
        obs: &mut dyn Observer,
        events: &mut Vec<PlantEvent>,
    ) -> Result<(), SimError> {
        let (t0, y0) = (self.t, self.y);
        self.slide_trend = None;
        let length = (t_end - t0).min(self.cfg.bridge_length);
        let before = self.rel_velocity();
        let (stretch, residual, tol) = self.converged_stretch(ctrl, t0, &y0, length)?;
        self.ledger.worst_entry_j = self.ledger.worst_entry_j.max(residual.abs());
        self.ledger.worst_ratio = self.ledger.worst_ratio.max(residual.abs() / tol);
        if residual.abs() > tol || residual.is_nan() {
            self.ledger.violations += 1;
        }
        let mode = self.mode();
        obs.on_segment_start(t0, &y0, mode);
        obs.on_attempt();
        let (l, grid) = (self.arm.params.l, self.sampling);
        let mut kicks = Vec::new();
        for (k, pair) in stretch.states.windows(2).enumerate() {
            let t_prev = t0 + k as f64 * stretch.h;
            let t_curr = if k + 2 == stretch.states.len() { t0 + length } else { t_prev + stretch.h };
            // A booked impulse acts at the step's start: the step runs from the kicked state.
            let start = match stretch.kicks[k] {
                Some((p, dv)) => {
                    let mut kicked = pair[0];
                    (kicked[1], kicked[3]) = (kicked[1] + dv[0], kicked[3] + dv[1]);
                    kicks.push(self.bridge_impulse_row(t_prev, &pair[0], &kicked, p, stretch.forces[k].0));
                    kicked
                }
                None => pair[0],
            };
            let mut step = LinearStep::new(t_prev, t_curr, start, pair[1]);
            // The samples `advance_sampling` asks for, linear between the step's ends.
            if let Some(g) = grid {
                let (step_mode, f) = stretch.forces[k];
                while let Some(i) = obs.next_sample()
                    && i <= g.last
                {
                    let ts = i as f64 * g.dt;
                    if !(t_prev < ts && ts <= t_curr) {
                        break;
                    }
                    let y = step.interpolate(ts);
                    let z = shared::kinematics::tip_position(l, &Vector2::new(y[0], y[2]));
                    obs.on_sample(&Sample { t: ts, x: [y[0], y[1], y[2], y[3]], tip: [z[0], z[1]], mode: step_mode, f });
                }
            }
            obs.on_step(&mut step, None, mode);
        }
        let y_end = *stretch.states.last().unwrap_or(&y0);
        obs.on_kept(&y_end, mode);
        self.t = t0 + length;
        self.y = y_end;
        self.last_h = stretch.h;
        self.counters.bridges += 1;
        self.counters.bridged_s += length;
        let first = !self.time_stepping;
        if why == Boundary::Singular {
            self.counters.singular_points += 1;
        }
        let index = events.len();
        if first {
            let kind = if why == Boundary::Singular { EventKind::SingularPoint } else { EventKind::Bridge };
            events.push(PlantEvent {
                t: t0,
                kind,
                mode_after: ContactMode::Flight,
                v_n_before: before[1],
                v_n_after: 0.0,
                v_r_before: before[0],
                v_r_after: 0.0,
                impulse: [0.0; 2],
                energy_change: 0.0,
                contact_work: 0.0,
                resolution: None,
            });
        }
        for row in kicks {
            self.ledger.events_j += row.energy_change;
            events.push(row);
        }
        self.time_stepping = false;
        self.resume(ctrl, stretch.last, events)?;
        if first {
            let after = self.rel_velocity();
            let e = &mut events[index];
            (e.mode_after, e.v_n_after, e.v_r_after) = (self.mode(), after[1], after[0]);
        }
        Ok(())
    }

    /// The `bridge_impulse` row of a bridge step's booked impulse `p` (N s) at `t` (s),
    /// from the step's start `before` to the kicked state `after`: the tip's relative
    /// velocities, the kinetic energy change and the contact work `P . (v- + v+) / 2`
    /// in the belt's frame (J).
    fn bridge_impulse_row(&self, t: f64, before: &OdeState, after: &OdeState, p: Vector2<f64>, mode_after: ContactMode) -> PlantEvent {
        let params = self.arm.params;
        let rel = |y: &OdeState| {
            let q = Vector2::new(y[0], y[2]);
            let v = shared::kinematics::jacobian(params.l, &q) * Vector2::new(y[1], y[3]);
            Vector2::new(v[0] - params.v_belt, v[1])
        };
        let energy = |y: &OdeState| crate::ledger::energy(&self.arm, &self.trig.get(&Vector2::new(y[0], y[2])), y);
        let (b, a) = (rel(before), rel(after));
        PlantEvent {
            t,
            kind: EventKind::BridgeImpulse,
            mode_after,
            v_n_before: b[1],
            v_n_after: a[1],
            v_r_before: b[0],
            v_r_after: a[0],
            impulse: [p[0], p[1]],
            energy_change: energy(after) - energy(before),
            contact_work: p.dot(&((b + a) * 0.5)),
            resolution: Some(crate::impact::Resolution::BridgeStep),
        }
    }

    /// The contact mode after a bridge whose last step took `last`: a slide the
    /// rule keeps through the indeterminate region stays time-stepped; a tip held
    /// on the belt, or on it and not moving away, has its mode chosen by `touch`
    /// (position projected first); otherwise it flies.
    fn resume<C: Controller + ?Sized>(&mut self, ctrl: &C, last: ContactSolution, events: &mut Vec<PlantEvent>) -> Result<(), SimError> {
        let params = self.arm.params;
        let (q, qd) = (Vector2::new(self.y[0], self.y[2]), Vector2::new(self.y[1], self.y[3]));
        if let ContactSolution::Sliding(dir) = last
            && self.cfg.singular == SingularRule::Slide
        {
            let td = self.segment(ctrl).evaluate(self.t, &self.y, &mut [0.0; 2]).0;
            if p_of(&td.qmat, params.mu, dir) < 0.0 && td.b() > 0.0 {
                self.phase = Phase::Sliding(dir);
                self.time_stepping = true;
                return Ok(());
            }
        }
        let z = shared::kinematics::tip_position(params.l, &q);
        let v_n = (shared::kinematics::jacobian(params.l, &q) * qd)[1];
        let gap = z[1] + params.h;
        let on_belt = last.in_contact() || (gap <= 1e-9 && v_n <= self.cfg.zeno_velocity);
        if on_belt {
            self.project_position()?;
            return self.touch(ctrl, events, false);
        }
        if gap < 0.0 {
            self.project_position()?;
        }
        self.phase = Phase::Flight;
        Ok(())
    }

    /// Time-steps `[t0, t0 + length]` from `y0` at the configured bridge step,
    /// halving it until the stretch agrees with the one at half its step
    /// ([`BRIDGE_TOLERANCE`] on the angles, [`BRIDGE_RATE_TOLERANCE`] on the rates at
    /// the end) and its energy balance is within what those tolerances are worth
    /// ([`crate::ledger::bridge_tolerance`]); returns the finer one, with its
    /// balance's residual (J) and tolerance. A bridge that converges in its state
    /// but not in its balance at [`BRIDGE_STEP_FLOOR`] is returned all the same: the
    /// caller counts a ledger violation.
    fn converged_stretch<C: Controller + ?Sized>(
        &self,
        ctrl: &C,
        t0: f64,
        y0: &OdeState,
        length: f64,
    ) -> Result<(Stretch, f64, f64), SimError> {
        let mut n = ((length / self.cfg.bridge_step).ceil() as usize).max(1);
        let mut coarse = self.stretch(ctrl, t0, y0, length, n)?;
        loop {
            let fine = self.stretch(ctrl, t0, y0, length, 2 * n)?;
            let (a, b) = (coarse.states.last().unwrap_or(y0), fine.states.last().unwrap_or(y0));
            let difference = (a[0] - b[0]).abs().max((a[2] - b[2]).abs());
            let rate_difference = (a[1] - b[1]).abs().max((a[3] - b[3]).abs());
            let converged = difference <= BRIDGE_TOLERANCE && rate_difference <= BRIDGE_RATE_TOLERANCE;
            let (residual, tol) = self.bridge_balance(y0, b);
            let at_floor = fine.h / 2.0 < BRIDGE_STEP_FLOOR;
            if converged && (residual.abs() <= tol || at_floor) {
                return Ok((fine, residual, tol));
            }
            if at_floor {
                return Err(SimError::Bridge { t: t0, step: fine.h, difference, rate_difference });
            }
            (coarse, n) = (fine, 2 * n);
        }
    }

    /// The energy balance of a bridge from `y0` to `y1`: its residual `E(y1) -
    /// E(y0) - works` (J) and its tolerance ([`crate::ledger::bridge_tolerance`]).
    fn bridge_balance(&self, y0: &OdeState, y1: &OdeState) -> (f64, f64) {
        use crate::ledger::{self, BELT, DAMPING, MOTORS, SLIP};
        let energy = |y: &OdeState| ledger::energy(&self.arm, &self.trig.get(&Vector2::new(y[0], y[2])), y);
        let (e0, e1) = (energy(y0), energy(y1));
        let works: f64 = [MOTORS, DAMPING, BELT, SLIP].iter().map(|&i| y1[i] - y0[i]).sum();
        let size = [MOTORS, DAMPING, BELT, SLIP].iter().map(|&i| y1[i].abs() + y0[i].abs()).sum::<f64>() + e0.abs() + e1.abs();
        let tr = self.trig.get(&Vector2::new(y1[0], y1[2]));
        let tol = ledger::bridge_tolerance(&self.arm, &tr, y1, BRIDGE_TOLERANCE, BRIDGE_RATE_TOLERANCE, size);
        ((e1 - e0) - works, tol)
    }

    /// `n` Moreau-Jean steps over `[t0, t0 + length]` from `y0` (module docs of
    /// [`crate::moreau_jean`]), the contact problem under the singular rule.
    pub(crate) fn stretch<C: Controller + ?Sized>(
        &self,
        ctrl: &C,
        t0: f64,
        y0: &OdeState,
        length: f64,
        n: usize,
    ) -> Result<Stretch, SimError> {
        let h = length / n as f64;
        let params = self.arm.params;
        let mut states = Vec::with_capacity(n + 1);
        states.push(*y0);
        let mut y = *y0;
        let mut phase = self.phase;
        let mut last = ContactSolution::Inactive;
        let mut forces = Vec::with_capacity(n);
        let mut kicks = Vec::with_capacity(n);
        for k in 0..n {
            let t = t0 + k as f64 * h;
            let (q, qd) = (Vector2::new(y[0], y[2]), Vector2::new(y[1], y[3]));
            let mut xi_dot = [0.0; 2];
            let motor = ctrl.torque_in(phase, t, &[y[0], y[1], y[2], y[3]], &[y[4], y[5]], &mut xi_dot);
            let u = Arm::generalised_torque(&Vector2::new(motor[0], motor[1]));
            let td = self.arm.tip_dynamics_trig(&self.trig.get(&q), &q, &qd, &u);
            let v_free = qd + td.qdd_free * h;
            let v_n = td.z_dot[1];
            let active = td.z[1] + params.h + 0.5 * h * v_n <= BRIDGE_CONTACT_GAP;
            let (v_new, solution, impulse) = if active {
                let tip = td.jac * v_free;
                let target = if v_n < 0.0 { -self.cfg.e_n * v_n } else { 0.0 };
                let rel = Vector2::new(tip[0] - params.v_belt, tip[1]);
                let (p, solution) = contact_impulse(&td.qmat, params.mu, rel, target, self.cfg.singular)
                    .ok_or(SimError::NonFinite { t, mode: "bridge" })?;
                (v_free + td.m_inv * (td.jac.transpose() * p), solution, p)
            } else {
                (v_free, ContactSolution::Inactive, Vector2::zeros())
            };
            phase = match solution {
                ContactSolution::Inactive | ContactSolution::Separation => Phase::Flight,
                ContactSolution::Sticking => Phase::Sticking,
                ContactSolution::Sliding(dir) => Phase::Sliding(dir),
            };
            last = solution;
            let kick = (impulse.norm() >= BRIDGE_IMPULSE_LOAD * params.m * params.g * h)
                .then(|| (impulse, td.m_inv * (td.jac.transpose() * impulse)));
            forces.push((phase_mode(phase), if kick.is_some() { [0.0, 0.0] } else { [impulse[0] / h, impulse[1] / h] }));
            kicks.push(kick);
            let v_mid = (qd + v_new) * 0.5;
            let q_new = q + v_mid * h;
            // The ledger's works of the step's forces over its displacement `h v_mid`:
            // the motors' and the damping's (explicit, at the step's start), the
            // contact impulse's on the tip's mean velocity, split as in segment.rs.
            let damping = -params.sigma * (qd[0] * v_mid[0] + (qd[1] - qd[0]) * (v_mid[1] - v_mid[0]));
            let tip_mid = td.jac * v_mid;
            let belt = params.v_belt * impulse[0];
            let slip = impulse[0] * (tip_mid[0] - params.v_belt) + impulse[1] * tip_mid[1];
            y = [
                q_new[0],
                v_new[0],
                q_new[1],
                v_new[1],
                y[4] + h * xi_dot[0],
                y[5] + h * xi_dot[1],
                y[MOTORS] + h * (u[0] * v_mid[0] + u[1] * v_mid[1]),
                y[DAMPING] + h * damping,
                y[BELT] + belt,
                y[SLIP] + slip,
            ];
            if !y.iter().all(|v| v.is_finite()) {
                return Err(SimError::NonFinite { t: t + h, mode: "bridge" });
            }
            states.push(y);
        }
        Ok(Stretch { h, states, last, forces, kicks })
    }
}

/// The contact mode of a phase.
fn phase_mode(phase: Phase) -> ContactMode {
    match phase {
        Phase::Flight => ContactMode::Flight,
        Phase::Sliding(_) => ContactMode::Sliding,
        Phase::Sticking => ContactMode::Sticking,
    }
}

/// One bridge step as the observers see a step: linear between its ends.
struct LinearStep {
    t: [f64; 2],
    y: [OdeState; 2],
    slope: OdeState,
}

impl LinearStep {
    fn new(t_prev: f64, t_curr: f64, y_prev: OdeState, y_curr: OdeState) -> Self {
        let dt = t_curr - t_prev;
        let slope = std::array::from_fn(|i| if dt > 0.0 { (y_curr[i] - y_prev[i]) / dt } else { 0.0 });
        Self { t: [t_prev, t_curr], y: [y_prev, y_curr], slope }
    }
}

impl DenseStep<STATE_LEN> for LinearStep {
    fn t_prev(&self) -> f64 {
        self.t[0]
    }
    fn t_curr(&self) -> f64 {
        self.t[1]
    }
    fn y_prev(&self) -> &State<STATE_LEN> {
        &self.y[0]
    }
    fn y_curr(&self) -> &State<STATE_LEN> {
        &self.y[1]
    }
    fn f_prev(&self) -> &State<STATE_LEN> {
        &self.slope
    }
    fn f_curr(&self) -> &State<STATE_LEN> {
        &self.slope
    }
    fn interpolate(&mut self, t: f64) -> State<STATE_LEN> {
        let s = t - self.t[0];
        std::array::from_fn(|i| self.y[0][i] + self.slope[i] * s)
    }
}
