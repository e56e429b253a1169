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

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::Serialize;

use crate::{
    error::AnalysisError,
    ideal::{self, IdealSetup},
};
use firmware::ControllerKind;
use plant::initial::{PaperX0, deg_to_state};
use plant::{EventKind, Plant, PlantEvent, SimConfig, Validity};
use rig::{RunObserver, Scenario, in_process};

/// Where the controller runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Setting {
    /// Continuous time, exact measurements, no saturation (the paper's).
    Ideal,
    /// The firmware, sampled with quantised sensors and torques (docs/hardware.md).
    Sampled,
}

impl std::fmt::Display for Setting {
    /// [`Setting::name`].
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Setting {
    /// `ideal` or `sampled`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ideal => "ideal",
            Self::Sampled => "sampled",
        }
    }
}

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

/// Z_t,sliding starts from `x0d` or `x0u` (experiments 5 and 6).
///
/// # Errors
/// [`AnalysisError::BadInput`] for `x0a`.
pub fn check_x0(x0: PaperX0) -> Result<(), AnalysisError> {
    match x0 {
        PaperX0::D | PaperX0::U => Ok(()),
        PaperX0::A => Err(AnalysisError::BadInput("--x0 a: Z_t,sliding starts from x0d or x0u (experiments 5 and 6)".into())),
    }
}

/// The paper's `K'_I` of the hybrid law from initial condition `x0`, 1/s:
/// 0 from `x0u`, 650 otherwise (docs/model.md, experiment 6); the default of the
/// scenario key `controller.hybrid.ki` ([`rig::scenario::paper_hybrid_ki`]).
pub fn paper_hybrid_ki(x0: PaperX0) -> f64 {
    rig::scenario::paper_hybrid_ki(x0)
}

/// One of the eight cases of `sil-host zmax --all`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub struct Combination {
    /// The controller.
    pub controller: ControllerKind,
    /// The initial condition.
    pub x0: PaperX0,
    /// Ideal or sampled.
    pub setting: Setting,
}

impl Combination {
    /// All eight: 2 controllers x 2 initial conditions x ideal/sampled.
    pub fn all() -> Vec<Self> {
        let mut v = Vec::new();
        for controller in [ControllerKind::Pid, ControllerKind::Hybrid] {
            for x0 in [PaperX0::D, PaperX0::U] {
                for setting in [Setting::Ideal, Setting::Sampled] {
                    v.push(Self { controller, x0, setting });
                }
            }
        }
        v
    }

    /// A file-name stem, e.g. `pid-x0d-ideal`.
    pub fn stem(&self) -> String {
        format!("{}-x0{}-{}", self.controller.name(), self.x0.letter(), self.setting.name())
    }
}

/// What "slides to the target" and "tracked" mean (module docs) and how long a trial runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Criteria {
    /// Run length, s.
    pub duration_s: f64,
    /// Duration of the move of `z_t*` from the initial tip position to the target, s.
    pub move_time_s: f64,
    /// Largest `|z_t - z_t*|` over the settle window for the tip to count as having
    /// got to the target (`Z_t,sliding`), m.
    pub reach_tol_m: f64,
    /// Largest `|z_t - z_t*|` over the settle window for the target to count as
    /// tracked (the tracking limit), m; at most `reach_tol_m`.
    pub settle_tol_m: f64,
    /// The last part of the run where the tip must be within `settle_tol_m`, s.
    pub settle_window_s: f64,
    /// The lift-off criterion, m: 0 (the default) counts any departure from the belt
    /// (a lift-off event, located exactly); a gap `g > 0` counts the tip as lifted off
    /// only when its height above the belt exceeds `g` at a sample (every control
    /// period; a short hop between samples can be missed), so departures that stay
    /// within `g` are ignored (`sil-host sensitivity`'s lift-off criterion).
    pub lift_off_gap_m: f64,
}

impl Default for Criteria {
    fn default() -> Self {
        Self {
            duration_s: 10.0,
            move_time_s: 2.0,
            reach_tol_m: crate::sweep::run::TARGET_TOL_M,
            settle_tol_m: 1e-3,
            settle_window_s: 1.0,
            lift_off_gap_m: 0.0,
        }
    }
}

impl Criteria {
    /// Checks ranges: finite, `duration_s > move_time_s > 0`, `reach_tol_m >= settle_tol_m > 0`,
    /// `0 < settle_window_s <= duration_s - move_time_s`.
    ///
    /// # Errors
    /// [`AnalysisError::BadInput`] naming the flag.
    pub fn validate(&self) -> Result<(), AnalysisError> {
        let bad = |what: String| Err(AnalysisError::BadInput(what));
        if !(self.move_time_s.is_finite() && self.move_time_s > 0.0) {
            return bad(format!("move time {} s must be finite and > 0", self.move_time_s));
        }
        if !(self.duration_s.is_finite() && self.duration_s > self.move_time_s && self.duration_s <= 1e4) {
            return bad(format!(
                "--duration {} s must be longer than the {} s move (and at most 1e4 s)",
                self.duration_s, self.move_time_s
            ));
        }
        if !(self.lift_off_gap_m.is_finite() && (0.0..=0.1).contains(&self.lift_off_gap_m)) {
            return bad(format!("lift-off gap {} m must be in [0, 0.1]", self.lift_off_gap_m));
        }
        if !(self.settle_tol_m.is_finite() && self.settle_tol_m > 0.0) {
            return bad(format!("--settle-tol {} m must be finite and > 0", self.settle_tol_m));
        }
        if !(self.reach_tol_m.is_finite() && self.reach_tol_m >= self.settle_tol_m) {
            return bad(format!("--reach-tol {} m must be finite and at least --settle-tol ({} m)", self.reach_tol_m, self.settle_tol_m));
        }
        if !(self.settle_window_s.is_finite() && self.settle_window_s > 0.0 && self.settle_window_s <= self.duration_s - self.move_time_s) {
            return bad(format!(
                "--settle-window {} s must be > 0 and at most the run after the move ({} s)",
                self.settle_window_s,
                self.duration_s - self.move_time_s
            ));
        }
        Ok(())
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
    /// Lift-offs seen (stopped at the first one).
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
    let started = Instant::now();
    let (mut trial, rows) = match combo.setting {
        Setting::Ideal => ideal_trial(base, combo, target, c)?,
        Setting::Sampled => sampled_trial(base, combo, target, c)?,
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

fn sim_config(base: &Scenario) -> SimConfig {
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

fn sampled_trial(base: &Scenario, combo: Combination, target: f64, c: &Criteria) -> Result<(Trial, Vec<TraceRow>), AnalysisError> {
    let s = sampled_scenario(base, combo, target, c)?;
    let mut t = empty_trial(combo, target);
    /// Counts the lift-offs and impacts without collision and stops at the first
    /// (with a lift-off gap, the heights decide after the run: no early stop).
    struct LiftOffs<'a>(&'a mut Trial, bool, bool);
    impl RunObserver for LiftOffs<'_> {
        fn on_finished(&mut self, validity: &Validity) {
            self.0.validity = *validity;
        }

        fn on_events(&mut self, events: &[PlantEvent]) {
            for e in events {
                match e.kind {
                    EventKind::LiftOff => self.0.lift_offs += 1,
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
    let (records, failure) = in_process::run(&s, &mut seen);
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

/// The outcome of a bisection for the largest `x` with `ok(x)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum Bisection {
    /// `ok(lo)` and not `ok(hi)` with `hi - lo <= tol`: the limit is `lo`.
    Found {
        /// Largest value found ok.
        lo: f64,
        /// Smallest value found not ok.
        hi: f64,
        /// Evaluations of the predicate.
        evaluations: u32,
    },
    /// The lower end of the bracket is already not ok: no limit in the bracket.
    LowerFails {
        /// The lower end.
        lo: f64,
        /// Evaluations.
        evaluations: u32,
    },
    /// The upper end is ok: the limit is at least `hi`.
    UpperReached {
        /// The upper end.
        hi: f64,
        /// Evaluations.
        evaluations: u32,
    },
}

impl Bisection {
    /// The largest value verified ok (`None` if the lower end fails).
    pub fn limit(&self) -> Option<f64> {
        match *self {
            Self::Found { lo, .. } => Some(lo),
            Self::LowerFails { .. } => None,
            Self::UpperReached { hi, .. } => Some(hi),
        }
    }

    /// The outcome's name in tables: `found`, `lower_fails` or `upper_reached`.
    pub fn outcome_name(&self) -> &'static str {
        match self {
            Self::Found { .. } => "found",
            Self::LowerFails { .. } => "lower_fails",
            Self::UpperReached { .. } => "upper_reached",
        }
    }

    /// Evaluations of the predicate.
    pub fn evaluations(&self) -> u32 {
        match *self {
            Self::Found { evaluations, .. } | Self::LowerFails { evaluations, .. } | Self::UpperReached { evaluations, .. } => evaluations,
        }
    }
}

/// Evaluations [`bisect_largest`] makes on `[lo, hi]` to tolerance `tol` at most.
pub fn max_evaluations(lo: f64, hi: f64, tol: f64) -> u32 {
    2 + ((hi - lo) / tol).log2().ceil().max(0.0) as u32
}

/// Trials a [`search`] on `[lo, hi]` to `tol` runs at most: the lift-off
/// bisection, then the tracking bisection inside its bracket (whose ends it reuses).
pub fn max_trials(lo: f64, hi: f64, tol: f64) -> u32 {
    2 * max_evaluations(lo, hi, tol) - 2
}

/// Bisection for the largest `x` in `[lo, hi]` with `ok(x)`, assuming `ok` is true
/// below a threshold and false above it: `ok(lo)`, then `ok(hi)`, then halving
/// until the bracket is at most `tol` wide (`lo < hi`, `tol > 0`, all finite; the
/// caller checks). For a non-monotone `ok` it returns one switching point.
///
/// # Errors
/// The first error of `ok`.
pub fn bisect_largest<E>(mut lo: f64, mut hi: f64, tol: f64, mut ok: impl FnMut(f64) -> Result<bool, E>) -> Result<Bisection, E> {
    let mut evaluations = 1;
    if !ok(lo)? {
        return Ok(Bisection::LowerFails { lo, evaluations });
    }
    evaluations += 1;
    if ok(hi)? {
        return Ok(Bisection::UpperReached { hi, evaluations });
    }
    while hi - lo > tol {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        evaluations += 1;
        if ok(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Bisection::Found { lo, hi, evaluations })
}

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
        let (t, rows) = trial(base, combo, target, c)?;
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
