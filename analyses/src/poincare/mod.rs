//! One-parameter bifurcation diagram of the open-loop arm (docs/model.md experiment 4,
//! the paper's Fig. 4): for each belt speed `v_belt`, the Poincaré section
//! `theta1_dot = 0` crossed upward, recorded after a transient, and the class of
//! the motion (equilibrium, periodic and its period, chaotic).
//!
//! - Section points: [`section`] locates each crossing inside the
//!   integrator's steps on the dense output (or at the impact whose velocity jump
//!   crosses the section); the point is the state there.
//! - Classification: [`classify`] (period by repetition within a tolerance).
//! - Chaos: the largest Lyapunov exponent of the Poincaré map by two nearby
//!   trajectories with renormalisation ([`lyapunov`]); the map is
//!   [`PlantReturnMap`]: restart the plant at a section point, run to its next
//!   crossing.

pub mod classify;
pub mod lyapunov;
pub mod section;

use std::time::Instant;

use serde::Serialize;
use shared::Params;

use classify::{Class, ClassifyConfig};
use lyapunov::{LyapunovConfig, LyapunovEstimate, ReturnMap};
use plant::{Plant, SimConfig, SimError, Validity};
use section::{Section, SectionCrossing, SectionWatch};

/// Length of one `advance` call while sweeping, s (the section is located inside
/// the integration steps, so this only sets how often the run is checked).
const CHUNK_S: f64 = 1.0;

/// Settings of the analysis of one belt speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PoincareConfig {
    /// Friction coefficient `mu`.
    pub mu: f64,
    /// The arm's parameters (paper Table I); `mu` and each point's `v_belt`
    /// replace its `mu` and `v_belt`.
    pub params: Params<f64>,
    /// Initial state `[theta1, theta1_dot, theta2, theta2_dot]`, rad and rad/s (the
    /// plant projects a tip slightly inside the belt onto it).
    pub x0: [f64; 4],
    /// Simulator settings.
    pub sim: SimConfig,
    /// Transient discarded, s.
    pub transient_s: f64,
    /// Record window after the transient, s.
    pub record_s: f64,
    /// Period detection.
    pub classify: ClassifyConfig,
    /// Lyapunov estimate (`iterations = 0`: none).
    pub lyapunov: LyapunovConfig,
    /// Longest time the return map waits for the next crossing, s.
    pub max_return_s: f64,
    /// Hysteresis of the section, rad/s: a crossing counts only after `theta1_dot`
    /// went below minus this ([`section`]), so rounding noise in
    /// steady sliding is not taken for motion.
    pub section_depth: f64,
}

/// The analysis of one belt speed.
#[derive(Debug, Clone, Serialize)]
pub struct PointResult {
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Section crossings in the record window, in time order.
    #[serde(skip)]
    pub crossings: Vec<SectionCrossing>,
    /// Class of the motion.
    pub class: Class,
    /// Period (section points per period) when periodic.
    pub period: Option<usize>,
    /// Crossings in the record window.
    pub n_crossings: usize,
    /// Distinct section points within the tolerance (counting stops at 1000).
    pub distinct_points: usize,
    /// Largest Lyapunov exponent of the section map, when estimated.
    pub lyapunov: Option<LyapunovEstimate>,
    /// Contact mode at the end of the record.
    pub final_mode: &'static str,
    /// `theta1` at the end of the record, rad.
    pub final_theta1: f64,
    /// Lift-offs in the record window: every departure of the tip from the belt,
    /// bounces included ([`crate::lift_offs::of`]).
    pub lift_offs: u64,
    /// Touchdowns (impacts) in the record window.
    pub touchdowns: u64,
    /// Why the simulation failed, if it did.
    pub error: Option<String>,
    /// The plant's validity counters over the transient and the record (the
    /// Lyapunov estimate's own short runs are not included); a violation makes the
    /// class [`Class::Invalid`].
    pub validity: Validity,
    /// The plant's energy ledger over the same span (docs/plant.md "The energy ledger").
    pub ledger: plant::Ledger,
    /// Wall time of this point, s.
    pub wall_s: f64,
}

/// Section coordinates used to compare points: `[theta1, theta2]`, rad.
pub fn section_coordinates(c: &SectionCrossing) -> [f64; 2] {
    [c.x[0], c.x[2]]
}

/// The Poincaré map of the open-loop plant (`u = 0`): from a state on (or just
/// past) the section `theta1_dot = 0`, a fresh plant (the state projected onto
/// the belt if the tip is on it, the contact mode chosen afresh) runs to its
/// next upward crossing. Crossings within the first microsecond are the start
/// point itself and are skipped.
#[derive(Debug, Clone)]
pub struct PlantReturnMap {
    /// Parameters (the belt speed included).
    pub params: Params<f64>,
    /// Simulator settings.
    pub sim: SimConfig,
    /// Longest wait for the next crossing, s (then: no return).
    pub max_return_s: f64,
    /// Hysteresis of the section, rad/s (see [`PoincareConfig::section_depth`]).
    pub section_depth: f64,
}

impl ReturnMap<4> for PlantReturnMap {
    type Error = SimError;

    fn apply(&mut self, x: &[f64; 4]) -> Result<Option<([f64; 4], f64)>, SimError> {
        let mut plant = Plant::new(self.params, self.sim, *x, 0.0, [0.0, 0.0])?;
        let mut watch = SectionWatch::with_hysteresis(Section::THETA1_DOT, self.section_depth);
        while plant.time() < self.max_return_s {
            plant.advance(&plant::Hold([0.0, 0.0]), (self.max_return_s - plant.time()).min(0.25), &mut watch)?;
            if let Some(c) = watch.crossings().iter().find(|c| c.t > 1e-6) {
                return Ok(Some((c.x, c.t)));
            }
        }
        Ok(None)
    }
}

/// Runs the plant at belt speed `v_belt` and classifies its motion.
///
/// Never fails: a simulation error is reported in [`PointResult::error`] with
/// class [`Class::Failed`] (and whatever was recorded before it).
pub fn analyse(v_belt: f64, cfg: &PoincareConfig) -> PointResult {
    let started = Instant::now();
    let mut result = PointResult {
        v_belt,
        crossings: Vec::new(),
        class: Class::Failed,
        period: None,
        n_crossings: 0,
        distinct_points: 0,
        lyapunov: None,
        final_mode: "",
        final_theta1: f64::NAN,
        lift_offs: 0,
        touchdowns: 0,
        error: None,
        validity: Validity::default(),
        ledger: plant::Ledger::default(),
        wall_s: 0.0,
    };
    match run_into(v_belt, cfg, &mut result) {
        Err(e) => {
            result.class = Class::Failed;
            result.error = Some(e.to_string());
        }
        Ok(()) if !result.validity.is_valid() => {
            result.class = Class::Invalid;
            result.period = None;
        }
        Ok(()) => {}
    }
    result.wall_s = started.elapsed().as_secs_f64();
    result
}

fn run_into(v_belt: f64, cfg: &PoincareConfig, r: &mut PointResult) -> Result<(), SimError> {
    let params = Params { mu: cfg.mu, v_belt, ..cfg.params };
    params.validate()?;
    let mut plant = Plant::new(params, cfg.sim, cfg.x0, 0.0, [0.0, 0.0])?;
    let result = record(&mut plant, params, cfg, r);
    r.validity = plant.validity(result.as_ref().err());
    r.ledger = plant.ledger();
    result
}

/// The transient, the record and its classification, for [`run_into`].
fn record(plant: &mut Plant, params: Params<f64>, cfg: &PoincareConfig, r: &mut PointResult) -> Result<(), SimError> {
    // Transient on exact multiples of the chunk, then the record.
    let mut k = 1.0;
    while plant.time() < cfg.transient_s {
        let target = (k * CHUNK_S).min(cfg.transient_s);
        plant.advance(&plant::Hold([0.0, 0.0]), target - plant.time(), &mut plant::NoObserver)?;
        k += 1.0;
    }
    let before = *plant.counters();
    let end = cfg.transient_s + cfg.record_s;
    let mut watch = SectionWatch::with_hysteresis(Section::THETA1_DOT, cfg.section_depth);
    let mut k = 1.0;
    while plant.time() < end {
        let target = (cfg.transient_s + k * CHUNK_S).min(end);
        let step = plant.advance(&plant::Hold([0.0, 0.0]), target - plant.time(), &mut watch);
        r.crossings.extend(watch.take());
        step?;
        k += 1.0;
    }
    let after = plant.counters();
    r.lift_offs = crate::lift_offs::of(after) - crate::lift_offs::of(&before);
    r.touchdowns = after.touchdowns - before.touchdowns;
    r.final_mode = plant.mode().name();
    r.final_theta1 = plant.state()[0];
    r.n_crossings = r.crossings.len();
    let coords: Vec<[f64; 2]> = r.crossings.iter().map(section_coordinates).collect();
    r.distinct_points = classify::distinct_points(&coords, cfg.classify.tol, 1000);
    let (class, period) = classify::classify(&coords, None, &cfg.classify);
    if class != Class::Equilibrium && class != Class::Settling && cfg.lyapunov.iterations > 0 {
        let x0 = r.crossings[0].x;
        // First separation along the belt: (theta1, theta2) moved so the tip keeps its height.
        let e0 = [x0[2].sin(), 0.0, -x0[0].sin(), 0.0];
        let mut map = PlantReturnMap { params, sim: cfg.sim, max_return_s: cfg.max_return_s, section_depth: cfg.section_depth };
        r.lyapunov = lyapunov::largest_exponent(&mut map, &x0, &e0, &cfg.lyapunov)?;
    }
    (r.class, r.period) = match class {
        Class::Periodic => (class, period),
        Class::Equilibrium | Class::Settling => (class, None),
        _ => classify::classify(&coords, r.lyapunov.map(|l| (l.per_iteration, l.std_error)), &cfg.classify),
    };
    Ok(())
}

/// A run of neighbouring belt speeds with the same class and period.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Band {
    /// Class.
    pub class: Class,
    /// Period, when periodic.
    pub period: Option<usize>,
    /// Smallest belt speed of the band, m/s.
    pub v_belt_min: f64,
    /// Largest belt speed of the band, m/s.
    pub v_belt_max: f64,
    /// Grid points in the band.
    pub points: usize,
}

/// Groups results (sorted by `v_belt`) into bands of equal class and period.
pub fn bands(results: &[PointResult]) -> Vec<Band> {
    let mut out: Vec<Band> = Vec::new();
    for r in results {
        match out.last_mut() {
            Some(b) if b.class == r.class && b.period == r.period => {
                b.v_belt_max = r.v_belt;
                b.points += 1;
            }
            _ => out.push(Band { class: r.class, period: r.period, v_belt_min: r.v_belt, v_belt_max: r.v_belt, points: 1 }),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::initial;

    /// Crossings located inside the integration steps agree with an independent
    /// location: the same trajectory advanced in 1 ms samples, a sign change of
    /// `theta1_dot` between samples bisected on clones of the plant advanced from
    /// the earlier sample (jumps at impacts included). Watching does not change
    /// the trajectory.
    #[test]
    fn located_crossings_agree_with_bisection_on_the_plant() {
        let params = Params::new(0.6, -0.5).unwrap();
        let x0 = initial::deg_to_state(initial::X0A.deg);
        let sim = SimConfig::default();
        let (dt, depth) = (1e-3, 1e-6);
        let mut watched = Plant::new(params, sim, x0, 0.0, [0.0; 2]).unwrap();
        let mut plain = watched.clone();
        let mut watch = SectionWatch::with_hysteresis(Section::THETA1_DOT, depth);
        let mut bisected: Vec<(f64, [f64; 4])> = Vec::new();
        let mut armed = false;
        for k in 1..=3000 {
            let target = k as f64 * dt;
            watched.advance(&plant::Hold([0.0; 2]), target - watched.time(), &mut watch).unwrap();
            let before = plain.clone();
            plain.advance(&plant::Hold([0.0; 2]), target - plain.time(), &mut plant::NoObserver).unwrap();
            let (g0, g1) = (before.state()[1], plain.state()[1]);
            armed |= g0 < -depth;
            if g0 < 0.0 && g1 >= 0.0 && armed {
                let (mut lo, mut hi) = (0.0, plain.time() - before.time());
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    let mut c = before.clone();
                    c.advance(&plant::Hold([0.0; 2]), mid, &mut plant::NoObserver).unwrap();
                    if c.state()[1] < 0.0 { lo = mid } else { hi = mid }
                }
                let mut c = before.clone();
                c.advance(&plant::Hold([0.0; 2]), hi, &mut plant::NoObserver).unwrap();
                bisected.push((before.time() + hi, c.state()));
                armed = false;
            }
            armed |= g1 < -depth;
        }
        assert_eq!(watched.state(), plain.state(), "watching changed the trajectory");
        let located = watch.crossings();
        assert!(located.len() >= 20, "{} crossings", located.len());
        // Both kinds are exercised (at v_belt = -0.5 about 12 of 30 are impact jumps).
        assert!(located.iter().any(|c| c.kind == section::CrossingKind::Jump));
        assert!(located.iter().any(|c| c.kind == section::CrossingKind::Flow));
        assert_eq!(located.len(), bisected.len());
        let (mut dt_max, mut dth_max) = (0.0f64, 0.0f64);
        for (c, (t, x)) in located.iter().zip(&bisected) {
            dt_max = dt_max.max((c.t - t).abs());
            dth_max = dth_max.max((c.x[0] - x[0]).abs());
        }
        // Measured: 1e-14 s and 4e-14 rad.
        assert!(dt_max < 1e-12 && dth_max < 1e-12, "time differs by {dt_max:e} s, theta1 by {dth_max:e} rad");
    }
}
