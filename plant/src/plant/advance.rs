//! Advancing the plant over an interval ([`Plant::advance`]): the loop over smooth
//! segments and the events that end them (one segment's integration with its
//! retries is `integrate.rs`), and the guard against mode changes that repeat at
//! one instant.

use shared::{ContactMode, model::TipDynamics};

use super::{EndPoint, Plant, Sample, SampleGrid};
use crate::{
    controller::Controller,
    dop853::DenseStep,
    error::SimError,
    events::{PlantEvent, StepReport},
    moreau_jean::SingularRule,
    observer::Observer,
    phase::Phase,
    segment::{self, Boundary, OdeState, STATE_LEN},
};

/// Events at one instant after which the contact is held stuck (crate docs, corner case).
const STALL_LIMIT: usize = 16;

/// Rounding slack on the (dimensionless) event components at the start of a segment.
const START_SLACK: f64 = 1e-12;

/// The `-b/g` within which a slide whose step collapsed at the singular point is at
/// the point itself ([`Plant::at_singular_point`]): issue 53's collapses end with
/// `-b/g` from 1e-10 to 3e-10 (the integration's residue), issue 40's, in the
/// point's neighbourhood, with 3e-3 to 7e-3.
pub const SINGULAR_RESIDUE: f64 = 1e-6;

/// The `p / Q_22` within which a slide's located lift-off is the passage through
/// the singular point ([`Plant::at_simultaneous_crossing`]): the scale below which
/// `f_n = -b/p` is the integration's residue of `b` rather than the slide's force
/// ([`segment::TREND_P`]). An ordinary lift-off, the force declining to 0, has
/// `p / Q_22` of order 0.1 to 1.
pub const SIMULTANEOUS_P: f64 = segment::TREND_P;

impl Plant {
    /// Advances by `dt` (s) under the torque law `ctrl`: [`Hold`](crate::Hold)`(u)` for the
    /// motor torques `u = [u1, u2]` (N m) held constant (zero-order hold, as a
    /// sampled controller drives the arm), or a law evaluated inside the
    /// integration (the paper's continuous-time setting; the report's force then
    /// uses the law's torque at the end of the interval). `obs` sees the
    /// trajectory: every accepted step with its dense output, the start of each
    /// smooth segment, the events ([`Observer`]; [`NoObserver`](crate::NoObserver) for none).
    ///
    /// # Errors
    /// [`SimError::BadStep`], [`SimError::BadTorque`] (a held torque that is not
    /// finite), or a failure during the interval (the plant is then left at the
    /// failure time).
    pub fn advance<C: Controller + ?Sized>(&mut self, ctrl: &C, dt: f64, obs: &mut dyn Observer) -> Result<StepReport, SimError> {
        let events = self.advance_events(ctrl, dt, obs)?;
        let f = match self.phase {
            Phase::Flight => [0.0, 0.0],
            _ => {
                let seg = self.segment(ctrl);
                let f = match ctrl.held() {
                    // Kept for the next interval's start (see `EndPoint`); counted when used there.
                    Some(u) => {
                        // The projection's sines and cosines of these angles, when it left them.
                        let point = seg.point_trig_uncounted(self.t, &self.y, &self.trig_here());
                        let (t, y, phase, cone_relaxed) = (self.t, self.y, self.phase, self.cone_relaxed);
                        self.end_point = Some(EndPoint { t, y, u, phase, cone_relaxed, point });
                        point.f
                    }
                    None => seg.evaluate(self.t, &self.y, &mut [0.0; 2]).1,
                };
                [f[0], f[1]]
            }
        };
        Ok(StepReport { t: self.t, mode: self.mode(), x: self.state(), f, events })
    }

    /// [`Plant::advance_events`] that also samples the trajectory at `t_sample` (s,
    /// strictly inside `(t, t + dt)`) from the ends of the accepted (the quintic Hermite interpolant, [`crate::hermite`])
    /// step that covers it, in the attempt the plant keeps: the SIL loop's
    /// look-ahead (`rig::PeriodLoop`) steps from one zero-order-hold switch to the
    /// next and reads the sensors' sample at `t_k` in between, so no step stops at
    /// `t_k`. An event located at `t_sample` gives the state before it.
    ///
    /// Returns the events and the sample; the sample is `None` when no accepted
    /// step covered `t_sample` (a Moreau–Jean bridge there has no dense output,
    /// docs/plant.md "The bridge"): the caller then advances in two parts.
    ///
    /// # Errors
    /// As [`Plant::advance`]; [`SimError::BadStep`] for a `t_sample` outside the interval.
    pub fn advance_sampled<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        dt: f64,
        t_sample: f64,
        obs: &mut dyn Observer,
    ) -> Result<(Vec<PlantEvent>, Option<Sample>), SimError> {
        if !(t_sample > self.t && t_sample < self.t + dt) {
            return Err(SimError::BadStep(t_sample - self.t));
        }
        // One instant: a grid of one point (its period is the instant itself).
        let grid = SampleGrid { dt: t_sample, next: 1, last: 1, max_step: f64::INFINITY };
        let mut samples = [None];
        self.hermite_samples = true;
        let events = self.advance_sampling(ctrl, dt, grid, &mut samples, obs);
        self.hermite_samples = false;
        let events = events?;
        Ok((events, samples[0]))
    }

    /// [`Plant::advance_events`] that also samples the trajectory at the instants
    /// of `grid` inside `(t, t + dt]`, each from the 7th-order dense output of the
    /// accepted step that covers it (in the attempt the plant keeps), with the steps
    /// capped at `grid.max_step`: `simulate`'s trace with steps the tolerances set
    /// (issue 43) rather than one stop per sample. `out[i]` receives the sample of
    /// `grid.next + i` (`out` holds one slot per instant); an instant no accepted
    /// step covered (a Moreau–Jean bridge there has no dense output, docs/plant.md
    /// "The bridge") is left `None`: the caller then advances in parts.
    ///
    /// # Errors
    /// As [`Plant::advance`]; [`SimError::BadStep`] for a grid whose period is not
    /// finite and positive or whose `out` has another length.
    pub fn advance_sampling<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        dt: f64,
        grid: SampleGrid,
        out: &mut [Option<Sample>],
        obs: &mut dyn Observer,
    ) -> Result<Vec<PlantEvent>, SimError> {
        let n = grid.last.checked_sub(grid.next).map_or(0, |d| d + 1);
        if !(grid.dt.is_finite() && grid.dt > 0.0) || out.len() as u64 != n || grid.max_step.is_nan() || grid.max_step <= 0.0 {
            return Err(SimError::BadStep(grid.dt));
        }
        out.fill(None);
        self.sampling = Some(grid);
        let mut sampler = Sampler { inner: obs, first: grid.next, out, attempt_next: grid.next, kept: grid.next };
        let events = self.advance_events(ctrl, dt, &mut sampler);
        self.sampling = None;
        events
    }

    /// [`Plant::advance`] without its report: the events of the interval only, in
    /// time order (the contact force at its end is not evaluated: the SIL loop's
    /// first part of a period, up to the zero-order-hold switch, needs only these).
    ///
    /// # Errors
    /// As [`Plant::advance`].
    pub fn advance_events<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        dt: f64,
        obs: &mut dyn Observer,
    ) -> Result<Vec<PlantEvent>, SimError> {
        // Kept only for an interval that starts where it was made.
        let end_point = self.end_point.take();
        if let Some(u) = ctrl.held()
            && !u.iter().all(|v| v.is_finite())
        {
            return Err(SimError::BadTorque(u));
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(SimError::BadStep(dt));
        }
        let t_end = self.t + dt;
        let mut events: Vec<PlantEvent> = Vec::new();
        let mut handled = 0usize;
        // Zero-time loops: mode changes that follow each other without time passing.
        let (mut stall_t, mut stalled) = (f64::NAN, 0usize);
        loop {
            let remaining = t_end - self.t;
            if remaining <= 1e-13 * t_end.abs().max(1.0) {
                self.t = t_end;
                break;
            }
            if handled > self.cfg.max_events_per_advance {
                let recent = events
                    .iter()
                    .rev()
                    .take(6)
                    .rev()
                    .map(|e: &PlantEvent| format!("{} at {:.12} s", e.kind.name(), e.t))
                    .collect::<Vec<String>>()
                    .join(", ");
                return Err(SimError::EventStorm { t: self.t, count: self.cfg.max_events_per_advance, recent });
            }
            // A slide through the indeterminate region after a singular point
            // (`SingularRule::Slide`) goes on time-stepped.
            if self.time_stepping {
                self.bridge(ctrl, Boundary::Collapse, t_end, obs, &mut events)?;
                handled += 1;
                continue;
            }
            // A mode must start inside its domain (up to rounding: a slip starting from
            // rest has s v_r = +-1e-16), or it ends at once. One model evaluation gives
            // the event function and the integrator's first stage.
            let (start, (boundary, g0)) = {
                let seg = self.segment(ctrl);
                let start = match &end_point {
                    Some(e) if self.starts_from(e, ctrl) => {
                        seg.count_evaluation();
                        e.point
                    }
                    // The projection's (or the last solve's) sines and cosines of these angles, when it left them.
                    _ => seg.point_trig(self.t, &self.y, &self.trig_here()),
                };
                let nb = segment::nearest(seg.components_of(&start.td, &start.f));
                (start, nb)
            };
            let departing = std::mem::take(&mut self.departing);
            if (g0 < -START_SLACK && self.phase != Phase::Flight) || (!departing && self.flight_starts_into_belt(&start.td)) {
                if self.note_stall(&mut stall_t, &mut stalled, &mut events)? {
                    handled += 1;
                    continue;
                }
                self.cross(ctrl, boundary, &mut events)?;
                handled += 1;
                continue;
            }
            // A relaxed (cone-violating) stick lasts at most to the end of this interval.
            let seg_end = t_end;
            obs.on_segment_start(self.t, &self.y, self.mode());
            let hit = self.integrate(ctrl, seg_end, &start, g0, obs)?;
            self.counters.segments += 1;
            match hit {
                Some(Boundary::Singular) if self.cfg.singular == SingularRule::Leave && self.at_singular_point(ctrl) => {
                    // The step collapsed at the point itself: the crossing decided by the
                    // slide's limit as a located one is (issue 81): arrested (the impact
                    // without collision at p = 0, then the mode chosen from rest; counted
                    // as a singular point too), the jam, or a force that falls to 0,
                    // crossed by a bridge (whose `leave` takes the flight).
                    let crossing = self.segment(ctrl).approach(self.t, &self.y).map(|a| a.crossing(self.slide_trend, false));
                    match crossing.map_or(Boundary::PZero, |c| self.decided(c)) {
                        Boundary::LiftOff => self.bridge(ctrl, Boundary::Singular, t_end, obs, &mut events)?,
                        b => {
                            if b == Boundary::PZero {
                                self.counters.singular_points += 1;
                            }
                            self.cross(ctrl, b, &mut events)?;
                        }
                    }
                    handled += 1;
                }
                Some(b @ (Boundary::Singular | Boundary::Collapse)) => {
                    self.bridge(ctrl, b, t_end, obs, &mut events)?;
                    handled += 1;
                }
                Some(b) => {
                    if !self.note_stall(&mut stall_t, &mut stalled, &mut events)? {
                        match self.at_simultaneous_crossing(ctrl, b) {
                            // The singular rule `slide`: the tip slides on through the
                            // indeterminate region, time-stepped (docs/plant.md "The
                            // singular point").
                            Boundary::PZero if self.cfg.singular == SingularRule::Slide => {
                                self.bridge(ctrl, Boundary::Singular, t_end, obs, &mut events)?
                            }
                            b => self.cross(ctrl, b, &mut events)?,
                        }
                    }
                    handled += 1;
                }
                None => {
                    self.t = t_end;
                    self.project_contact()?;
                    // Solve the contact problem afresh next interval.
                    if self.cone_relaxed {
                        self.cone_relaxed = false;
                        self.in_violation = true;
                    }
                    break;
                }
            }
        }
        self.flush_projection(&mut events);
        // The state after an impact at the very end of the interval belongs to no step.
        obs.on_advanced(self.t, &self.y);
        for e in &events {
            obs.on_event(e);
        }
        Ok(events)
    }

    /// The located event `b` as the crossing it is (issue 81; docs/plant.md "The
    /// singular point"): a slide's located `p = 0`, or its located lift-off (`b = 0`)
    /// with `p / Q_22` within [`SIMULTANEOUS_P`] of 0 (below it `f_n = -b/p` is the
    /// integration's residue, not the slide's force, so the located root alone cannot
    /// say which came first: issue 53's arm has its two roots 2e-10 s apart), is decided
    /// by the slide's own limit ([`segment::Approach::crossing`]): arrested at `p = 0`
    /// ([`Boundary::PZero`]) where the slide is attracted into the point with a finite
    /// force, a lift-off where the force reaches 0 first, the jam ([`Boundary::Jam`])
    /// where it grows without bound. Each use is counted. A `p = 0` located at a
    /// segment's start with `p` well below 0 (a state in the Painlevé region, x0a) and
    /// any other event is itself.
    fn at_simultaneous_crossing<C: Controller + ?Sized>(&mut self, ctrl: &C, b: Boundary) -> Boundary {
        if !matches!(b, Boundary::LiftOff | Boundary::PZero) || !matches!(self.phase, Phase::Sliding(_)) {
            return b;
        }
        let seg = self.segment(ctrl);
        let c = seg.components(self.t, &self.y);
        if c[1].1.abs() > SIMULTANEOUS_P {
            return b;
        }
        let Some(approach) = seg.approach(self.t, &self.y) else { return b };
        self.decided(approach.crossing(self.slide_trend, b == Boundary::LiftOff))
    }

    /// The boundary a crossing decided by the slide's limit is crossed as, counted.
    fn decided(&mut self, crossing: segment::Crossing) -> Boundary {
        match crossing {
            segment::Crossing::Arrested => {
                self.counters.corners_arrested += 1;
                Boundary::PZero
            }
            segment::Crossing::LiftOff => {
                self.counters.corners_lifted_off += 1;
                Boundary::LiftOff
            }
            segment::Crossing::Jam => {
                self.counters.corners_jammed += 1;
                Boundary::Jam
            }
        }
    }

    /// Whether the slide is at the singular point itself: `-b/g` within
    /// [`SINGULAR_RESIDUE`] of 0 (the integration's residue of `b` as `p -> 0`), not
    /// only in its neighbourhood (where the step collapses on the way, issue 40's
    /// cases, a bridge crosses it).
    fn at_singular_point<C: Controller + ?Sized>(&self, ctrl: &C) -> bool {
        let c = self.segment(ctrl).components(self.t, &self.y);
        c[0].1.abs() <= SINGULAR_RESIDUE
    }

    /// Whether `e` is the model at the current time, state and mode under `ctrl`
    /// (a held torque equal to `e`'s, bit for bit).
    fn starts_from<C: Controller + ?Sized>(&self, e: &EndPoint, ctrl: &C) -> bool {
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
        ctrl.held().is_some_and(|u| same(u[0], e.u[0]) && same(u[1], e.u[1]))
            && same(e.t, self.t)
            && e.y.iter().zip(&self.y).all(|(a, b)| same(*a, *b))
            && e.phase == self.phase
            && e.cone_relaxed == self.cone_relaxed
    }

    /// Counts mode changes at one instant; after [`STALL_LIMIT`] of them in contact
    /// (slip starting and stopping at once: the slip acceleration is zero to
    /// rounding in both directions) holds the tip stuck, cone ignored, to the end of
    /// the interval (the documented corner case). Returns whether it did.
    fn note_stall(&mut self, stall_t: &mut f64, stalled: &mut usize, events: &mut Vec<PlantEvent>) -> Result<bool, SimError> {
        if (self.t - *stall_t).abs() <= 1e-12 * self.t.abs().max(1.0) {
            *stalled += 1;
        } else {
            (*stall_t, *stalled) = (self.t, 0);
        }
        if *stalled < STALL_LIMIT || self.phase == Phase::Flight {
            return Ok(false);
        }
        let before = self.rel_velocity();
        self.project_contact_velocity(true)?;
        self.phase = Phase::Sticking;
        self.cone_relaxed = true;
        self.enter_violation(events, before);
        (*stall_t, *stalled) = (f64::NAN, 0);
        Ok(true)
    }

    /// Flight starting on the belt with the tip not moving away (e.g. after `b`
    /// touched 0 without changing sign): the event detection cannot see a crossing
    /// from `z_n + H = 0`, so this is handled as a grazing touchdown at once. `td`:
    /// the tip dynamics at the current state.
    fn flight_starts_into_belt(&self, td: &TipDynamics<f64>) -> bool {
        if self.phase != Phase::Flight {
            return false;
        }
        let height = td.z[1] + self.arm.params.h;
        height <= 1e-12 && (td.z_dot[1] < -self.cfg.zeno_velocity || (td.z_dot[1] <= self.cfg.zeno_velocity && td.b() < 0.0))
    }
}

/// Keeps the samples of the attempts the plant keeps ([`Plant::advance_sampling`]),
/// asks for the next instant, and passes everything on to the caller's observer.
struct Sampler<'o, 's> {
    inner: &'o mut dyn Observer,
    /// The grid index of `out[0]`.
    first: u64,
    out: &'s mut [Option<Sample>],
    /// The next index the current attempt wants (back to `kept` on a new attempt).
    attempt_next: u64,
    /// The next index after the samples of the attempts kept so far.
    kept: u64,
}

impl Observer for Sampler<'_, '_> {
    fn on_segment_start(&mut self, t: f64, y: &OdeState, mode: ContactMode) {
        self.inner.on_segment_start(t, y, mode);
    }

    fn on_attempt(&mut self) {
        // Samples of a discarded attempt are taken again by the next one.
        for s in self.out.iter_mut().skip((self.kept - self.first) as usize) {
            *s = None;
        }
        self.attempt_next = self.kept;
        self.inner.on_attempt();
    }

    fn on_step(&mut self, step: &mut dyn DenseStep<STATE_LEN>, stop: Option<(f64, OdeState)>, mode: ContactMode) {
        self.inner.on_step(step, stop, mode);
    }

    fn next_sample(&self) -> Option<u64> {
        ((self.attempt_next - self.first) < self.out.len() as u64).then_some(self.attempt_next)
    }

    fn on_sample(&mut self, sample: &Sample) {
        if let Some(slot) = self.out.get_mut((self.attempt_next - self.first) as usize) {
            *slot = Some(*sample);
        }
        self.attempt_next += 1;
    }

    fn on_kept(&mut self, y_end: &OdeState, mode: ContactMode) {
        self.kept = self.attempt_next;
        self.inner.on_kept(y_end, mode);
    }

    fn on_advanced(&mut self, t: f64, y: &OdeState) {
        self.inner.on_advanced(t, y);
    }

    fn on_event(&mut self, event: &PlantEvent) {
        self.inner.on_event(event);
    }
}
