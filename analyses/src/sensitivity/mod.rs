//! The sensitivity study (`sil-host sensitivity`): the paper's headline results
//! recomputed under each choice the paper leaves open, one at a time from the
//! defaults (docs/model.md "What the paper leaves open"; docs/analyses.md
//! "Sensitivity").
//!
//! Choices ([`Choice`]): the impact law and `e_n`; the IWC rule; the hybrid law's
//! friction compensation; the reference's move time; the lift-off criterion; and
//! for the sampled firmware the control rate, the encoder resolution, the
//! load-cell noise, the mismatch of its friction estimate `mu_hat`, its torque
//! limit and the delay from sampling to the command.
//!
//! Headline results ([`ChoiceResult`]):
//! - open loop (the brute-force sweep of experiment 3 from `x0a` and `x0d`): the
//!   critical `mu` per initial condition, the belt-speed extent of persistent
//!   bouncing at `mu = 0.6` from `x0a`, and whether `x0d` ever bounces;
//! - `Z_t,sliding` (experiments 5 and 6) for the four paper cases (PID and hybrid
//!   from `x0d` and `x0u`), ideal and sampled;
//! - how the hybrid closed loop (experiment 7, the sampled firmware from `x0d` at
//!   `mu = 0.6`) ends over the belt speeds: lift-offs above the lift-off criterion
//!   (and how high), the safe state, the target not reached.
//!
//! A choice that does not enter a result (the controller's settings in open loop,
//! the sampled firmware's in the ideal setting, the hybrid law's friction term for
//! the PID) leaves it uncomputed (`None`): its value is the default's.
//!
//! The lift-off criterion counts a departure only when the tip rises above a gap:
//! for the sweeps from the highest tip position over the record window (taken
//! inside the integrator's steps), for `Z_t,sliding` from the samples
//! ([`crate::zmax::Criteria::lift_off_gap_m`]).

mod choices;
mod results;
mod size;

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use crate::error::AnalysisError;
use crate::sweep::{
    Axis, SweepController, SweepSpec,
    run::{self, RunRow},
};
use crate::zmax::{self, Combination, Criteria, Setting};
use plant::{Validity, initial::PaperX0};
use rig::scenario::Scenario;

pub use self::choices::{Choice, Dimension, Knobs, choices};
pub use self::results::{ChoiceResult, ClosedLoop, OpenLoop, Row, Study, Zmax};
use self::results::{closed_results, open_results};
pub use self::size::{Grids, Size};

/// A unit of work: one sweep run, or one `Z_t,sliding` search.
enum Job {
    Sweep { spec: usize, index: usize },
    Search(usize),
}

/// Runs the study from `base` (the sampled setting's scenario and the arm's
/// parameters: the embedded default unless the caller gives another) at `size`,
/// the closed-loop sweeps over `seeds` sensor-noise seeds per belt speed
/// ([`crate::sweep::ensemble`]; the open loop and the `Z_t,sliding` searches run
/// once), in parallel on the current rayon pool; `progress(done, total)` after
/// each job; `stop` ends it early (an [`AnalysisError::Interrupted`]).
///
/// # Errors
/// [`AnalysisError`] for a base scenario the study cannot use, `seeds` outside
/// `1..=MAX_SEEDS`, or when stopped.
pub fn run(
    base: &Scenario,
    size: Size,
    seeds: usize,
    stop: &AtomicBool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Study, AnalysisError> {
    base.validate()?;
    if !(1..=crate::sweep::ensemble::MAX_SEEDS).contains(&seeds) {
        return Err(AnalysisError::BadInput(format!("--seeds must be in 1..={}, got {seeds}", crate::sweep::ensemble::MAX_SEEDS)));
    }
    let grids = size.grids();
    let choices = choices(base);
    for c in &choices {
        c.knobs.scenario(base).validate()?;
    }
    // Distinct sweeps: the open loop per (law, e_n, IWC); the closed loop per choice.
    let mut specs: Vec<SweepSpec> = Vec::new();
    let mut open_of = vec![None; choices.len()];
    let mut closed_of = vec![None; choices.len()];
    for (i, c) in choices.iter().enumerate() {
        if c.dimension.in_open_loop() {
            let spec = open_spec(base, &grids, &c.knobs);
            let at = specs.iter().position(|s| *s == spec).unwrap_or_else(|| {
                specs.push(spec);
                specs.len() - 1
            });
            open_of[i] = Some(at);
        }
        let spec = SweepSpec { seeds, ..closed_spec(base, &grids, &c.knobs) };
        let at = specs.iter().position(|s| *s == spec).unwrap_or_else(|| {
            specs.push(spec);
            specs.len() - 1
        });
        closed_of[i] = Some(at);
    }
    let mut jobs: Vec<Job> = Vec::new();
    for (s, spec) in specs.iter().enumerate() {
        jobs.extend((0..spec.n_runs()).map(|index| Job::Sweep { spec: s, index }));
    }
    // Distinct searches: the defaults of every dimension (and any other choice that
    // gives the same knobs) share one search per case.
    let mut wanted: Vec<(Knobs, Combination)> = Vec::new();
    let mut search_of: Vec<Vec<usize>> = vec![Vec::new(); choices.len()];
    for (i, c) in choices.iter().enumerate() {
        for combination in combinations(c) {
            let at = wanted.iter().position(|w| *w == (c.knobs, combination)).unwrap_or_else(|| {
                wanted.push((c.knobs, combination));
                wanted.len() - 1
            });
            search_of[i].push(at);
        }
    }
    jobs.extend((0..wanted.len()).map(Job::Search));
    // The costly jobs first, so that the pool ends together.
    jobs.sort_by_key(|j| match j {
        Job::Search(_) => 0,
        Job::Sweep { spec, .. } => usize::from(specs[*spec].controller == SweepController::None) + 1,
    });
    let total = jobs.len() as u64;
    let done = std::sync::atomic::AtomicU64::new(0);
    let ics: Vec<_> = specs.iter().map(SweepSpec::initial_conditions).collect();
    enum Out {
        Row(usize, RunRow),
        Search(usize, Zmax),
    }
    let outs: Vec<Result<Out, AnalysisError>> = jobs
        .par_iter()
        .with_max_len(1)
        .filter_map(|job| {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            let out = match job {
                Job::Sweep { spec, index } => {
                    let key = specs[*spec].run_at(*index);
                    run::simulate(&specs[*spec], &key, &ics[*spec][key.i_ic], stop).map(|r| Ok(Out::Row(*spec, r)))
                }
                Job::Search(w) => {
                    let (knobs, combination) = &wanted[*w];
                    Some(search(base, &grids, knobs, *combination).map(|z| Out::Search(*w, z)))
                }
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            out
        })
        .collect();
    if stop.load(Ordering::Relaxed) {
        return Err(AnalysisError::Interrupted("sensitivity study stopped".into()));
    }
    let mut rows: Vec<Vec<RunRow>> = vec![Vec::new(); specs.len()];
    let mut found: Vec<Option<Zmax>> = vec![None; wanted.len()];
    for o in outs {
        match o? {
            Out::Row(s, r) => rows[s].push(r),
            Out::Search(w, z) => found[w] = Some(z),
        }
    }
    let mut validity = Validity::default();
    let results: Vec<ChoiceResult> = choices
        .into_iter()
        .enumerate()
        .map(|(i, choice)| {
            let gap = choice.knobs.lift_off_gap_m;
            let open_loop = open_of[i].map(|s| open_results(&specs[s], &rows[s], gap));
            let closed_loop = closed_of[i].map(|s| closed_results(&rows[s], gap, seeds));
            // In Combination::all()'s order, as combinations() gives them.
            let zmax = search_of[i].iter().filter_map(|&w| found[w].clone()).collect();
            ChoiceResult { choice, open_loop, zmax, closed_loop }
        })
        .collect();
    for r in &rows {
        for row in r {
            validity.add(&row.validity());
        }
    }
    for z in found.iter().flatten() {
        validity.add(&z.validity);
    }
    Ok(Study { size, grids, defaults: Knobs::default(), results, validity, seeds })
}

/// The `Z_t,sliding` cases a choice enters.
fn combinations(c: &Choice) -> Vec<Combination> {
    Combination::all()
        .into_iter()
        .filter(|k| c.dimension.in_controller(k.controller))
        .filter(|k| k.setting == Setting::Sampled || c.dimension.in_ideal())
        .collect()
}

fn open_spec(base: &Scenario, g: &Grids, k: &Knobs) -> SweepSpec {
    SweepSpec {
        mu: g.mu,
        v_belt: g.v_belt,
        iwc_rules: vec![k.iwc],
        impact_laws: vec![k.impact_law],
        e_n: vec![k.e_n],
        singular: k.singular,
        paper_ics: vec![PaperX0::A, PaperX0::D],
        transient_s: g.open_windows_s.0,
        record_s: g.open_windows_s.1,
        rtol: base.plant.rtol,
        atol: base.plant.atol,
        params: base.plant.params(),
        ..SweepSpec::paper()
    }
}

fn closed_spec(base: &Scenario, g: &Grids, k: &Knobs) -> SweepSpec {
    let mu = base.plant.mu;
    SweepSpec {
        mu: Axis { start: mu, stop: mu, step: 0.1 },
        v_belt: g.closed_v_belt,
        iwc_rules: vec![k.iwc],
        impact_laws: vec![k.impact_law],
        e_n: vec![k.e_n],
        paper_ics: vec![PaperX0::D],
        transient_s: g.closed_windows_s.0,
        record_s: g.closed_windows_s.1,
        controller: SweepController::Hybrid,
        scenario: Some(k.scenario(base)),
        rtol: base.plant.rtol,
        atol: base.plant.atol,
        params: base.plant.params(),
        mu_hat_factor: 1.0 + k.mu_hat_mismatch,
        singular: k.singular,
        ..SweepSpec::paper()
    }
}

fn search(base: &Scenario, g: &Grids, k: &Knobs, combination: Combination) -> Result<Zmax, AnalysisError> {
    let s = k.scenario(base);
    let c = Criteria {
        duration_s: g.zmax_duration_s.max(k.move_time_s + 2.0),
        move_time_s: k.move_time_s,
        lift_off_gap_m: k.lift_off_gap_m,
        ..Criteria::default()
    };
    let bracket = zmax::default_bracket(&s, combination.x0)?;
    let found = zmax::search(&s, combination, bracket, g.zmax_tol_m, &c, |_| {})?;
    let mut validity = Validity::default();
    for t in &found.trials {
        validity.add(&t.validity);
    }
    Ok(Zmax {
        combination,
        z_t_sliding: found.z_t_sliding,
        outcome: found.bisection.outcome_name(),
        stop_above: found.failing_trial(&found.bisection).map(|t| t.stop),
        missed_by_m: found.failing_trial(&found.bisection).filter(|t| t.stop == zmax::StopReason::NotReached).map(|t| t.settle_error_m),
        z_t_tracking: found.z_t_tracking,
        tracking_outcome: found.tracking.outcome_name(),
        tracking_stop_above: found.failing_trial(&found.tracking).map(|t| t.stop),
        validity,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::ControllerKind;

    #[test]
    fn choices_enter_only_the_results_they_change() {
        let all = choices(&Scenario::default_scenario());
        let rate = all.iter().find(|c| c.dimension == Dimension::Rate && !c.is_default).unwrap();
        assert!(!rate.dimension.in_open_loop());
        assert!(combinations(rate).iter().all(|k| k.setting == Setting::Sampled));
        let friction = all.iter().find(|c| c.dimension == Dimension::Friction && !c.is_default).unwrap();
        assert!(combinations(friction).iter().all(|k| k.controller == ControllerKind::Hybrid && k.setting == Setting::Sampled));
        let law = all.iter().find(|c| c.dimension == Dimension::ImpactLaw).unwrap();
        assert_eq!(combinations(law).len(), 8);
    }
}
