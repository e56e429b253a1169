//! One trial ([`super`] documentation): a closed loop to one target in the ideal
//! or the sampled setting, its time history ([`TraceRow`]), its outcome
//! ([`Trial`]) and why it stopped ([`StopReason`]).

use std::time::Instant;

use serde::Serialize;

use super::combination::{Combination, Criteria, Setting};
use crate::{
    error::AnalysisError,
    ideal::{self, IdealSetup},
};
use firmware::{ControlLaw, PaperLaws};
use plant::initial::deg_to_state;
use plant::{EventKind, PlantEvent, SimConfig, Validity};
use rig::{RunObserver, Scenario, in_process};

/// Why a trial ended the way it did, in the order checked (the first that applies).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The trajectory violates the model (an energy-creating impact, a friction-cone
    /// violation, an integrator failure): never counted as free of lift-off.
    Invalid,
    /// The tip left the belt: a lift-off, an impact without collision or a sample
    /// in flight (with a lift-off gap: a sample above it). The trial stops there.
    LiftOff,
    /// The sampled firmware latched its safe state (zero torque).
    SafeState,
    /// The run stopped early otherwise: a plant failure, a fault of the ideal law.
    Failure,
    /// No lift-off, but `|z_t - z_t*|` exceeded the reach tolerance in the settle
    /// window: the tip did not get to the target.
    NotReached,
    /// Slid to the target, but `|z_t - z_t*|` exceeded the settle tolerance in the
    /// settle window.
    NotSettled,
    /// Slid to the target and settled: the target is tracked.
    Tracked,
}

impl StopReason {
    /// The name in CSV and JSON: `invalid`, `lift_off`, `safe_state`, `failure`,
    /// `not_reached`, `not_settled` or `tracked`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Invalid => "invalid",
            Self::LiftOff => "lift_off",
            Self::SafeState => "safe_state",
            Self::Failure => "failure",
            Self::NotReached => "not_reached",
            Self::NotSettled => "not_settled",
            Self::Tracked => "tracked",
        }
    }
}

impl std::fmt::Display for StopReason {
    /// [`StopReason::name`].
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
/// One row of a trial's time history (for figures).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TraceRow {
    /// Time, s.
    pub t: f64,
    /// Tip `z_t`, m.
    pub z_t: f64,
    /// Reference `z_t*`, m.
    pub z_t_ref: f64,
    /// Normal force `f_n`, N (true).
    pub f_n: f64,
    /// Motor torque `u1`, N m.
    pub u1: f64,
    /// Motor torque `u2`, N m.
    pub u2: f64,
    /// Contact mode.
    pub mode: &'static str,
    /// Tip height above the belt `z_n + H`, m.
    pub height: f64,
}

// The time history at the limit (`painleve.zmax`'s `limit_traces`): its columns, declared.
tables::declare!(TraceRow { t: f64, z_t: f64, z_t_ref: f64, f_n: f64, u1: f64, u2: f64, mode: str, height: f64 });

/// The outcome of one trial.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// The case.
    pub combination: Combination,
    /// Target `z_t*`, m.
    pub target_z_t: f64,
    /// Why the trial ended the way it did (module docs).
    pub stop: StopReason,
    /// No lift-off, a normal end, no model violation and the tip within
    /// `reach_tol_m` of the target (module docs, 1 to 3): the predicate of `Z_t,sliding`.
    pub slides_to_target: bool,
    /// Slides to the target and settles within `settle_tol_m` (module docs, 1 to 4):
    /// the predicate of the tracking limit.
    pub tracked: bool,
    /// Lift-offs seen: every departure of the tip from the belt up to the trial's
    /// end ([`crate::lift_offs::of`]; a trial stops at the first lift-off or
    /// impact without collision, so mostly 0 or 1).
    pub lift_offs: u64,
    /// Impacts without collision seen.
    pub impacts_without_collision: u64,
    /// Time of the first lift-off or impact without collision, s.
    pub first_lift_off_s: Option<f64>,
    /// Largest `|z_t - z_t*|` over the settle window, m (NaN if the run stopped before it).
    pub settle_error_m: f64,
    /// Why the run stopped early (failure, safe state, law fault), if it did for
    /// another reason than a lift-off.
    pub failure: Option<String>,
    /// Whether `failure` is the firmware's safe state (sampled setting).
    #[serde(skip)]
    pub safe_state: bool,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time of the trial, s.
    pub wall_s: f64,
    /// The plant's validity counters over the trial; a trial with a violation is
    /// never counted as sliding. A plant failure after the first lift-off (the ideal hybrid
    /// law's documented event storm beyond `p = 0`) is not counted: the trial's
    /// answer, a lift-off, is already known.
    pub validity: Validity,
}

impl Trial {
    /// Why the target was not tracked (`None` if it was), in words: `lift-off at
    /// t = .. s`, `impact without collision at ..`, `above the lift-off gap`, the
    /// failure or safe state, the model violation, or `not settled: ..`.
    pub fn why_not(&self) -> Option<String> {
        Some(match self.stop {
            StopReason::Tracked => return None,
            StopReason::Invalid => format!("the trajectory violates the model: {}", self.validity.describe_violations()),
            StopReason::LiftOff => match self.first_lift_off_s {
                Some(t) if self.lift_offs > 0 => format!("lift-off at t = {t:.3} s"),
                Some(t) => format!("impact without collision at t = {t:.3} s"),
                None => "the tip rose above the lift-off gap".to_string(),
            },
            StopReason::SafeState | StopReason::Failure => self.failure.clone().unwrap_or_default(),
            StopReason::NotReached => {
                format!("not reached: |z_t - z_t*| up to {:.2} mm over the settle window", self.settle_error_m * 1e3)
            }
            StopReason::NotSettled => {
                format!("not settled: |z_t - z_t*| up to {:.2} mm over the settle window", self.settle_error_m * 1e3)
            }
        })
    }

    /// Why the tip did not slide to the target (`None` if it did): as
    /// [`Trial::why_not`], `None` for a trial that only failed to settle.
    pub fn why_not_sliding(&self) -> Option<String> {
        if self.slides_to_target { None } else { self.why_not() }
    }
}

fn settle_error(rows: &[TraceRow], target: f64, c: &Criteria) -> f64 {
    let from = c.duration_s - c.settle_window_s - 1e-9;
    let last = rows.last().map_or(0.0, |r| r.t);
    // The sampled run's last record is one period (at most 4 ms) before the end.
    if last < c.duration_s - 0.01 {
        return f64::NAN;
    }
    rows.iter().filter(|r| r.t >= from).map(|r| (r.z_t - target).abs()).fold(0.0, f64::max)
}

/// Runs one trial; returns its outcome and time history. `base` is the scenario the
/// sampled setting starts from (its controller, initial condition, `K'_I` (the
/// paper's: 650 from `x0d`, 0 from `x0u`), target, move time and run length are set
/// here); the ideal setting uses the paper's set-up with `base`'s `mu`, `v_belt` and
/// plant settings. A trial stops at the first lift-off.
///
/// # Errors
/// [`AnalysisError`] for bad input (a target out of reach, an invalid scenario).
pub fn trial(base: &Scenario, combo: Combination, target: f64, c: &Criteria) -> Result<(Trial, Vec<TraceRow>), AnalysisError> {
    trial_law::<PaperLaws>(base, combo, target, c)
}

/// [`trial`] with the firmware running law `L` in the sampled setting (a law
/// of one's own, its `[law]` table in `base`; issue 70). The ideal setting is
/// the paper's laws' continuous-time form: refused for any other law.
///
/// # Errors
/// As [`trial`]; [`AnalysisError::BadInput`] for the ideal setting with a law
/// of one's own.
pub fn trial_law<L: ControlLaw>(
    base: &Scenario,
    combo: Combination,
    target: f64,
    c: &Criteria,
) -> Result<(Trial, Vec<TraceRow>), AnalysisError> {
    let started = Instant::now();
    let (mut trial, rows) = match combo.setting {
        Setting::Ideal if !L::SPEC.name.is_empty() => {
            return Err(AnalysisError::BadInput(format!(
                "the ideal setting is the paper's laws in continuous time; law `{}` runs in the sampled setting only",
                L::SPEC.name
            )));
        }
        Setting::Ideal => ideal_trial(base, combo, target, c)?,
        Setting::Sampled => sampled_trial::<L>(base, combo, target, c)?,
    };
    trial.settle_error_m = settle_error(&rows, target, c);
    let stayed_on = if c.lift_off_gap_m > 0.0 {
        rows.iter().all(|r| r.height <= c.lift_off_gap_m)
    } else {
        trial.lift_offs == 0 && trial.impacts_without_collision == 0 && rows.iter().all(|r| r.mode != "flight")
    };
    let settled = trial.settle_error_m <= c.settle_tol_m;
    let got_there = trial.settle_error_m <= c.reach_tol_m;
    trial.stop = if !trial.validity.is_valid() {
        StopReason::Invalid
    } else if !stayed_on {
        StopReason::LiftOff
    } else if trial.failure.is_some() {
        if trial.safe_state { StopReason::SafeState } else { StopReason::Failure }
    } else if !got_there {
        StopReason::NotReached
    } else if !settled {
        StopReason::NotSettled
    } else {
        StopReason::Tracked
    };
    trial.slides_to_target = matches!(trial.stop, StopReason::NotSettled | StopReason::Tracked);
    trial.tracked = trial.stop == StopReason::Tracked;
    trial.simulated_s = rows.last().map_or(0.0, |r| r.t);
    trial.wall_s = started.elapsed().as_secs_f64();
    Ok((trial, rows))
}

fn empty_trial(combo: Combination, target: f64) -> Trial {
    Trial {
        combination: combo,
        target_z_t: target,
        stop: StopReason::Failure,
        slides_to_target: false,
        tracked: false,
        lift_offs: 0,
        impacts_without_collision: 0,
        first_lift_off_s: None,
        settle_error_m: f64::NAN,
        failure: None,
        safe_state: false,
        simulated_s: 0.0,
        wall_s: 0.0,
        validity: Validity::default(),
    }
}

pub(super) fn sim_config(base: &Scenario) -> SimConfig {
    let p = &base.plant;
    SimConfig { rtol: p.rtol, atol: p.atol, impact_law: p.impact_law, e_n: p.e_n, iwc: p.iwc, singular: p.singular, ..SimConfig::default() }
}

/// The set-up of an ideal trial: the paper's ideal law for `combo` with `base`'s
/// plant (paper Table I, `mu`, `v_belt`, impact law, tolerances), gains (paper
/// eqs. 8 to 11; `K'_I` as the scenario gives it, else the paper's for
/// `combo.x0`) and `f_n*`, the target `target` and `c`'s move and run lengths.
pub fn ideal_setup(base: &Scenario, combo: Combination, target: f64, c: &Criteria) -> IdealSetup {
    let g = &base.controller;
    IdealSetup {
        params: base.plant.params(),
        f_n_ref: g.f_n_ref,
        pid: g.pid,
        hybrid_kp: g.hybrid.kp,
        hybrid_kd: g.hybrid.kd,
        hybrid_ki: g.hybrid_ki(combo.x0),
        move_time_s: c.move_time_s,
        duration_s: c.duration_s,
        sample_dt: base.timing.period().as_secs_f64(),
        stop_at_lift_off: c.lift_off_gap_m == 0.0,
        sim: sim_config(base),
        ..IdealSetup::paper(combo.controller, deg_to_state(combo.x0.condition().deg), target)
    }
}

fn ideal_trial(base: &Scenario, combo: Combination, target: f64, c: &Criteria) -> Result<(Trial, Vec<TraceRow>), AnalysisError> {
    let setup = ideal_setup(base, combo, target, c);
    let run = ideal::simulate(&setup, |_| {}).map_err(AnalysisError::Sim)?;
    let h = setup.params.h;
    let rows = run
        .samples
        .iter()
        .map(|s| TraceRow { t: s.t, z_t: s.z_t, z_t_ref: s.z_t_ref, f_n: s.f_n, u1: s.u1, u2: s.u2, mode: s.mode, height: s.z_n + h })
        .collect();
    let mut t = empty_trial(combo, target);
    t.lift_offs = run.lift_offs;
    t.impacts_without_collision = run.impacts_without_collision;
    t.first_lift_off_s = run.first_lift_off_s;
    let lifted = run.first_lift_off_s.is_some();
    t.validity = Validity::of(&run.counters, &run.ledger, run.error.as_ref().filter(|_| !lifted));
    t.failure = match (&run.error, run.law_fault) {
        (Some(e), _) if !lifted => Some(format!("plant: {e}")),
        (_, Some(f)) if !lifted => Some(format!("law: {f}")),
        _ => None,
    };
    Ok((t, rows))
}

/// The scenario of a sampled trial.
pub fn sampled_scenario(base: &Scenario, combo: Combination, target: f64, c: &Criteria) -> Result<Scenario, AnalysisError> {
    let mut s = base.clone();
    s.name = combo.stem();
    s.controller.kind = combo.controller;
    s.plant.x0 = combo.x0;
    s.controller.hybrid.ki = Some(base.controller.hybrid_ki(combo.x0));
    s.controller.target_z_t = target;
    s.controller.move_time_s = c.move_time_s;
    s.timing.duration_s = c.duration_s;
    // The paper's controller: the board's runaway limits off, as in the sweeps
    // (`Z_t,sliding` is decided at the first lift-off, before any of them would trip).
    s.controller.runaway_limits = false;
    s.validate()?;
    Ok(s)
}

fn sampled_trial<L: ControlLaw>(
    base: &Scenario,
    combo: Combination,
    target: f64,
    c: &Criteria,
) -> Result<(Trial, Vec<TraceRow>), AnalysisError> {
    let s = sampled_scenario(base, combo, target, c)?;
    let mut t = empty_trial(combo, target);
    /// Counts the impacts without collision, notes the first lift-off or impact
    /// without collision and stops there (with a lift-off gap, the heights decide
    /// after the run: no early stop); the lift-offs are every departure from the
    /// belt up to the stop, from the plant's counters (as the ideal trial's).
    struct LiftOffs<'a>(&'a mut Trial, bool, bool);
    impl RunObserver for LiftOffs<'_> {
        fn on_finished(&mut self, validity: &Validity) {
            self.0.validity = *validity;
        }

        fn on_counters(&mut self, counters: &plant::Counters) {
            self.0.lift_offs = crate::lift_offs::of(counters);
        }

        fn on_events(&mut self, events: &[PlantEvent]) {
            for e in events {
                match e.kind {
                    EventKind::LiftOff => {}
                    EventKind::ImpactWithoutCollision => self.0.impacts_without_collision += 1,
                    _ => continue,
                }
                self.0.first_lift_off_s.get_or_insert(e.t);
                self.1 = true;
            }
        }

        fn on_period(&mut self, _k: usize, _n: usize) -> bool {
            !(self.1 && self.2)
        }
    }
    let mut seen = LiftOffs(&mut t, false, c.lift_off_gap_m == 0.0);
    let (records, failure) = in_process::run_law::<L>(&s, &mut seen);
    let lifted = seen.1;
    let h = s.plant.params().h;
    let rows: Vec<TraceRow> = records
        .iter()
        .map(|r| TraceRow {
            t: r.t,
            z_t: r.z_t,
            z_t_ref: r.z_t_ref,
            f_n: r.f_n,
            u1: r.u1_cmd,
            u2: r.u2_cmd,
            mode: r.mode,
            height: r.z_n + h,
        })
        .collect();
    if t.first_lift_off_s.is_none()
        && let Some(r) = records.iter().find(|r| r.lift_off_true)
    {
        t.first_lift_off_s = Some(r.t);
        t.lift_offs = t.lift_offs.max(1);
    }
    if lifted {
        t.validity.integrator_failures = 0;
    }
    if !lifted && let Some(e) = failure {
        t.safe_state = matches!(e, rig::RunError::SafeState { .. });
        t.failure = Some(e.to_string());
    }
    Ok((t, rows))
}
