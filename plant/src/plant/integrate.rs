//! Integrating one smooth segment ([`Plant::advance`]'s inner step): one solve of
//! the current mode with its event located and the samples asked for on its dense
//! output, and the retries with capped steps of a solve that misses its event.

use super::{Plant, Sample};
use crate::{
    controller::Controller,
    dop853::{Control, Dop853, SolveError},
    error::SimError,
    observer::Observer,
    phase::Phase,
    segment::{Boundary, EventLocator, OdeState, Point},
};

/// The end of one solve: end time, state, the boundary hit (if any), and the event
/// function at the last accepted point (0 at a hit; see `Plant::solve_segment`).
type SegmentEnd = (f64, OdeState, Option<Boundary>, f64);

impl Plant {
    /// Integrates the current mode from `self.t` towards `t_end`; returns the
    /// boundary hit, if any (the state is then at the event). `start` is the model
    /// at the current state and `g0` the event function there.
    ///
    /// An event is detected as a sign change of the event function between two
    /// accepted steps, starting from its value at `t0`. A segment that starts
    /// on its boundary (flight right after a bounce: `z_n + H = 0`) would miss a
    /// return that fits inside the first step, so the first step is kept inside the
    /// hop (`h0 <= v_n / |b|`, half the ballistic hop time). As a last guard, a
    /// segment that ends outside its domain without an event is integrated again
    /// with steps capped at 1/64 of the interval and at most 1 ms, then 10 us, and
    /// fails if that still misses it.
    pub(super) fn integrate<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        t_end: f64,
        start: &Point,
        g0: f64,
        obs: &mut dyn Observer,
    ) -> Result<Option<Boundary>, SimError> {
        let remaining = t_end - self.t;
        // The integrator's floor is 10 |t| u: a step proposed at it (after a solve
        // whose steps shrank towards a jam) would fail at once.
        let floor = 100.0 * f64::EPSILON * self.t.abs();
        let mut h0 = self.last_h.max(floor).min(remaining);
        if self.phase == Phase::Flight {
            let td = &start.td;
            let height = td.z[1] + self.arm.params.h;
            if height < 1e-9 && td.z_dot[1] > 0.0 && td.b() < 0.0 {
                // No shorter than the integrator can take at this t (its floor is
                // 10 |t| u): a flight shorter than that ends at the first step's
                // touchdown, located inside it (e.g. after a jam's kick).
                h0 = h0.min(td.z_dot[1] / -td.b()).max(floor.min(remaining));
            }
        }
        // Retries cap the steps at 1/64 of the interval, and also at 1 ms then 10 us:
        // over a long interval (open-loop runs advance by seconds) 1/64 of it can
        // still hold a whole excursion out of the domain and back, e.g. a slip from
        // rest that stops again within milliseconds.
        for h_max in [f64::INFINITY, (remaining / 64.0).min(1e-3), (remaining / 64.0).min(1e-5)] {
            obs.on_attempt();
            let (t1, y1, boundary, g_end) = self.solve_segment(ctrl, t_end, h0.min(h_max), h_max, start, g0, obs)?;
            if boundary.is_none() && g_end < -1e-9 {
                // Missed crossing: retry with capped steps.
                continue;
            }
            obs.on_kept(&y1, self.mode());
            self.t = t1;
            self.y = y1;
            return Ok(boundary);
        }
        Err(SimError::MissedEvent { t: self.t, mode: self.mode().name() })
    }

    /// One solve over `[self.t, t_end]`, stopping at the first event (the plant's
    /// time and state are left unchanged; `last_h` takes the step the integrator
    /// proposes next). Returns the end time and state (the event's, if one was
    /// located), the boundary hit (if any), and the event function at the last
    /// accepted point (0 at a hit; `Plant::integrate` retries a solve that ends
    /// outside its domain without one). `obs` sees every accepted step, with its
    /// dense output, up to the event ([`Observer::on_step`]).
    #[allow(clippy::too_many_arguments)]
    fn solve_segment<C: Controller + ?Sized>(
        &mut self,
        ctrl: &C,
        t_end: f64,
        h0: f64,
        h_max: f64,
        start: &Point,
        g0: f64,
        obs: &mut dyn Observer,
    ) -> Result<SegmentEnd, SimError> {
        let cap = self.sampling.map_or(f64::INFINITY, |g| g.max_step);
        let solver = Dop853 { h_max: h_max.min(self.solver.h_max).min(cap), ..self.solver };
        let mode = self.mode();
        let seg = self.segment(ctrl);
        let mut locator = EventLocator::new(&seg, g0);
        locator.trend = self.slide_trend;
        // The start's energy, when the projection (or the last solve) left it.
        if let Some(k) = self.known() {
            locator.e_prev = k.energy;
        }
        let (grid, hermite) = (self.sampling, self.hermite_samples);
        let solved = solver.solve(&seg, self.t, &self.y, Some(&start.dydt), t_end, h0, |step| {
            let control = locator.on_step(step);
            if control == Control::Reject {
                return control;
            }
            // The samples `advance_sampling` asks for: each from the step that covers
            // it, up to the event that ends the segment inside it.
            if let Some(g) = grid {
                let end = locator.hit.map_or(step.t_curr(), |(t, _)| t);
                while let Some(k) = obs.next_sample()
                    && k <= g.last
                {
                    let ts = k as f64 * g.dt;
                    if !(step.t_prev() < ts && ts <= end) {
                        break;
                    }
                    // The look-ahead's sample from the step's ends (`crate::hermite`): no
                    // model evaluation, where the 7th-order dense output takes three. A
                    // step that an event ends inside has its dense output already (the
                    // root search's), and its end lies past the event, outside the mode.
                    let y = match locator.hit {
                        Some((t, y)) if t.to_bits() == ts.to_bits() => y,
                        None if hermite => crate::hermite::sample(&*step, ts),
                        _ => step.interpolate(ts),
                    };
                    // The tip's position from the evaluation's (`tip_position_trig`, the same bits).
                    let (td, f, _) = seg.evaluate(ts, &y, &mut [0.0; 2]);
                    let z = td.z;
                    obs.on_sample(&Sample { t: ts, x: [y[0], y[1], y[2], y[3]], tip: [z[0], z[1]], mode, f: [f[0], f[1]] });
                }
            }
            obs.on_step(step, locator.hit, mode);
            control
        });
        let (rejected, worst, trend) = (locator.rejected, locator.worst, locator.trend);
        let (locator_end, last) = ((locator.g_prev, locator.hit), locator.last);
        // The last accepted point's energy and sines and cosines, for its projection.
        if let Some((_, y)) = last
            && locator.hit.is_none()
        {
            self.known = Some(super::Known { x: [y[0], y[1], y[2], y[3]], trig: locator.trig_last, energy: locator.e_prev });
        }
        self.slide_trend = trend;
        self.ledger.refinements += rejected;
        self.ledger.worst_entry_j = self.ledger.worst_entry_j.max(worst.0);
        self.ledger.worst_ratio = self.ledger.worst_ratio.max(worst.1);
        let solved = match solved {
            Ok(s) => s,
            // The step size collapsed: at the dynamic jam before f_n reached jam_load m g
            // (resolved from the last accepted point, the solve's start if it accepted
            // none, where the slide was already jamming), at the singular point, or
            // elsewhere (both crossed by a Moreau-Jean bridge from that point).
            Err(SolveError::StepSizeTooSmall { .. })
                if let (t1, y1) = last.unwrap_or((self.t, self.y))
                    && y1.iter().all(|v| v.is_finite()) =>
            {
                let seg = self.segment(ctrl);
                let boundary = if seg.jamming(t1, &y1, trend.map(|t| t.f_n)) {
                    self.counters.jams_at_collapse += 1;
                    Boundary::Jam
                } else if seg.near_singular(t1, &y1, trend.map(|t| t.f_n)) {
                    Boundary::Singular
                } else {
                    Boundary::Collapse
                };
                return Ok((t1, y1, Some(boundary), 0.0));
            }
            Err(e) => return Err(SimError::Integrator { t: self.t, message: e.to_string() }),
        };
        let (g_end, hit) = locator_end;
        self.last_h = solved.h_next;
        if let Some((t1, y1)) = hit {
            if !y1.iter().all(|v| v.is_finite()) {
                return Err(SimError::NonFinite { t: t1, mode: self.mode().name() });
            }
            let boundary = self.segment(ctrl).nearest_boundary(t1, &y1).0;
            return Ok((t1, y1, Some(boundary), 0.0));
        }
        if !solved.y.iter().all(|v| v.is_finite()) {
            return Err(SimError::NonFinite { t: t_end, mode: self.mode().name() });
        }
        Ok((t_end, solved.y, None, g_end))
    }
}
