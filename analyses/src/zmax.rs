//! `Z_t,sliding` (docs/model.md experiments 5 and 6): the largest tangential target
//! `z_t*` the tip is driven to with no lift-off (the paper's definition), and apart
//! from it the tracking limit, the largest target also tracked within the settle
//! tolerance; both by bisection on the target.
//!
//! A *trial* runs one closed loop from the initial condition with the target
//! `z_t*` (the quintic move over `move_time_s`, then held) for `duration_s`, in one
//! of two settings:
//! - ideal: the paper's continuous-time laws with exact measurements ([`crate::ideal`]);
//! - sampled: the firmware in-process (1 kHz, quantised sensors and torques,
//!   estimation, docs/hardware.md defaults or a given scenario; [`rig`]).
//!
//! The tip *slides to the target* ([`Trial::slides_to_target`]) when, over the whole run,
//! 1. the plant never leaves the belt: no lift-off event (located exactly, between
//!    samples too), no impact without collision, no sample in flight;
//! 2. the run ends normally (no plant failure, no firmware safe state, no fault of
//!    the ideal law) with no model violation; and
//! 3. the tip gets there: `|z_t - z_t*| <= reach_tol_m` (5 mm, the closed-loop
//!    sweep's [`crate::sweep::run::TARGET_TOL_M`]) at every sample of the last
//!    `settle_window_s` of the run.
//!
//! The target is *tracked* ([`Trial::tracked`]) when, in addition,
//! 4. the tip settles: `|z_t - z_t*| <= settle_tol_m` (1 mm) over the same window.
//!
//! Each trial says why it stopped ([`StopReason`]). `Z_t,sliding` is the largest
//! target the tip slides to (the paper's "largest value of `z_t` such that no
//! lift-off occurs": a value of `z_t` the tip attains, which a PID stopped at the
//! fold of `theta1` does not); the tracking limit is the largest target tracked. A
//! PID whose steady error is about the settle tolerance has a tracking limit far
//! below its lift-off limit; a search reports both ([`Search`]).
//!
//! Each bisection assumes its predicate is true below some target and false above
//! it; it keeps a bracket `[lo, hi]` with `lo` true and `hi` not, halved until
//! `hi - lo <= tol`, and reports `lo` (a target verified). If the lower end of the
//! bracket already fails there is no limit ([`Bisection::LowerFails`]); if the upper
//! end passes the limit is at least that ([`Bisection::UpperReached`]). The tracking
//! bisection runs on `[lo, Z_t,sliding]` and reuses the trials of the first.

mod bisection;
mod combination;
mod trial;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::Serialize;

use crate::error::AnalysisError;
use firmware::{ControlLaw, PaperLaws};
use plant::Plant;
use plant::initial::{PaperX0, deg_to_state};
use rig::Scenario;

pub use bisection::{Bisection, bisect_largest, max_evaluations, max_trials};
pub use combination::{Combination, Criteria, Setting, check_x0, paper_hybrid_ki};
pub use trial::{StopReason, TraceRow, Trial, ideal_setup, sampled_scenario, trial, trial_law};

use trial::sim_config;

/// The default bracket of targets for an initial condition, m: from the initial
/// tip position (projected onto the belt; the target equal to the start) to 1 mm
/// short of the end of the reachable belt (where the arm is straight).
///
/// # Errors
/// [`AnalysisError`] if the plant cannot be set up.
pub fn default_bracket(base: &Scenario, x0: PaperX0) -> Result<(f64, f64), AnalysisError> {
    let params = base.plant.params();
    let plant = Plant::new(params, sim_config(base), deg_to_state(x0.condition().deg), 0.0, [0.0; 2])?;
    let reach = crate::admissible::belt_reach(&params);
    Ok((plant.tip()[0], reach - 1e-3))
}

/// The result of the search for one combination.
#[derive(Debug, Clone, Serialize)]
pub struct Search {
    /// The case.
    pub combination: Combination,
    /// Bracket searched, m.
    pub bracket: (f64, f64),
    /// The `Z_t,sliding` bisection's outcome (predicate [`Trial::slides_to_target`]).
    pub bisection: Bisection,
    /// `Z_t,sliding`, m: the largest target the tip was verified to slide to (the
    /// paper's definition), if any.
    pub z_t_sliding: Option<f64>,
    /// The tracking bisection's outcome (predicate [`Trial::tracked`]), on
    /// `[bracket.0, Z_t,sliding]`; its `hi` is the smallest target found not
    /// tracked, which may be the `Z_t,sliding` bisection's.
    pub tracking: Bisection,
    /// The tracking limit, m: the largest target verified tracked, if any.
    pub z_t_tracking: Option<f64>,
    /// Every trial, in the order run (each target once).
    pub trials: Vec<Trial>,
    /// The time history of the trial at `Z_t,sliding` (the lowest target if the tip
    /// slides to none).
    #[serde(skip)]
    pub limit_trace: Vec<TraceRow>,
    /// Wall-clock time of the search, s.
    pub wall_s: f64,
}

impl Search {
    /// The trial at `target`, m, if the search ran one there.
    pub fn trial_at(&self, target: f64) -> Option<&Trial> {
        self.trials.iter().find(|t| t.target_z_t == target)
    }

    /// The trial that bounds a bisection from above: the smallest target found to
    /// fail (`Found`), or the lower end (`LowerFails`); `None` for `UpperReached`.
    pub fn failing_trial(&self, b: &Bisection) -> Option<&Trial> {
        match *b {
            Bisection::Found { hi, .. } => self.trial_at(hi),
            Bisection::LowerFails { lo, .. } => self.trial_at(lo),
            Bisection::UpperReached { .. } => None,
        }
    }
}

/// Searches `Z_t,sliding` and the tracking limit for one combination on
/// `bracket` to `tol` (m); `on_trial` is called after each trial (progress).
///
/// # Errors
/// [`AnalysisError::BadInput`] for a bad bracket or tolerance; the first trial's bad-input error.
pub fn search(
    base: &Scenario,
    combo: Combination,
    bracket: (f64, f64),
    tol: f64,
    c: &Criteria,
    on_trial: impl FnMut(&Trial),
) -> Result<Search, AnalysisError> {
    search_until(base, combo, bracket, tol, c, &AtomicBool::new(false), on_trial)
}

/// [`search`], stopped before its next trial once `stop` is set (Ctrl-C in an
/// embedding: the Python package): then [`AnalysisError::Interrupted`].
///
/// # Errors
/// As [`search`]; [`AnalysisError::Interrupted`] when stopped.
pub fn search_until(
    base: &Scenario,
    combo: Combination,
    bracket: (f64, f64),
    tol: f64,
    c: &Criteria,
    stop: &AtomicBool,
    on_trial: impl FnMut(&Trial),
) -> Result<Search, AnalysisError> {
    search_law::<PaperLaws>(base, combo, bracket, tol, c, stop, on_trial)
}

/// [`search_until`] with the firmware running law `L` (a law of one's own, its
/// `[law]` table in `base`; the sampled setting only: [`trial::trial_law`]):
/// `Z_t,sliding` and the tracking limit of any law (issue 70).
///
/// # Errors
/// As [`search_until`].
pub fn search_law<L: ControlLaw>(
    base: &Scenario,
    combo: Combination,
    bracket: (f64, f64),
    tol: f64,
    c: &Criteria,
    stop: &AtomicBool,
    mut on_trial: impl FnMut(&Trial),
) -> Result<Search, AnalysisError> {
    let (lo, hi) = bracket;
    check_x0(combo.x0)?;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(AnalysisError::BadInput(format!("bracket [{lo}, {hi}] m must be finite with LO < HI")));
    }
    if !(tol.is_finite() && tol > 0.0) {
        return Err(AnalysisError::BadInput(format!("--tol {tol} m must be finite and > 0")));
    }
    let started = Instant::now();
    let mut trials: Vec<Trial> = Vec::new();
    let mut traces: Vec<Vec<TraceRow>> = Vec::new();
    // One trial per target: the tracking bisection reuses the lift-off one's.
    let mut run = |target: f64| -> Result<Trial, AnalysisError> {
        if let Some(t) = trials.iter().find(|t| t.target_z_t == target) {
            return Ok(t.clone());
        }
        if stop.load(Ordering::Relaxed) {
            return Err(AnalysisError::Interrupted(format!(
                "Z_t,sliding search ({} x0{} {}) stopped after {} trials",
                combo.controller,
                combo.x0,
                combo.setting.name(),
                trials.len()
            )));
        }
        let (t, rows) = trial::trial_law::<L>(base, combo, target, c)?;
        on_trial(&t);
        trials.push(t.clone());
        traces.push(rows);
        Ok(t)
    };
    let bisection = bisect_largest(lo, hi, tol, |target| run(target).map(|t| t.slides_to_target))?;
    let tracking = match bisection {
        Bisection::LowerFails { lo, .. } => Bisection::LowerFails { lo, evaluations: 1 },
        Bisection::Found { lo: top, hi: first_failing, .. } if top == lo => {
            if run(lo)?.tracked {
                Bisection::Found { lo, hi: first_failing, evaluations: 1 }
            } else {
                Bisection::LowerFails { lo, evaluations: 1 }
            }
        }
        Bisection::Found { lo: top, hi: first_failing, .. } => {
            match bisect_largest(lo, top, tol, |target| run(target).map(|t| t.tracked))? {
                Bisection::UpperReached { evaluations, .. } => Bisection::Found { lo: top, hi: first_failing, evaluations },
                other => other,
            }
        }
        Bisection::UpperReached { hi: top, .. } => bisect_largest(lo, top, tol, |target| run(target).map(|t| t.tracked))?,
    };
    let limit = bisection.limit().unwrap_or(lo);
    let limit_trace = trials.iter().position(|t| t.target_z_t == limit).map(|i| traces[i].clone()).unwrap_or_default();
    Ok(Search {
        combination: combo,
        bracket,
        z_t_sliding: bisection.limit(),
        bisection,
        z_t_tracking: tracking.limit(),
        tracking,
        trials,
        limit_trace,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests;
