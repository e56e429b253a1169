//! The outputs of `sil-host zmax` other than the figures: the rows of `zmax.csv` and `trials.csv`, `summary.json` and the human table.

use analyses::zmax::Setting;
use analyses::zmax::{Criteria, Trial};
use firmware::ControllerKind;
use plant::{Validity, initial::PaperX0};
use rig::scenario::Scenario;
use serde::Serialize;
use std::io::Write;

/// One row of `zmax.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxRow {
    /// `pid` or `hybrid`.
    pub controller: ControllerKind,
    /// `d` or `u`.
    pub x0: PaperX0,
    /// `ideal` or `sampled`.
    pub setting: Setting,
    /// `found`, `lower_fails` or `upper_reached`.
    pub outcome: &'static str,
    /// `Z_t,sliding`, m (empty when the lower end already fails).
    pub z_t_sliding_m: Option<f64>,
    /// Smallest target found to fail, m (empty unless found).
    pub first_failing_m: Option<f64>,
    /// Why that target (or, for `lower_fails`, the lower end) failed.
    pub why_failing: Option<String>,
    /// Bracket searched, m.
    pub bracket_lo_m: f64,
    /// Bracket searched, m.
    pub bracket_hi_m: f64,
    /// End of the admissible range (`p = 0` on the belt, `z_r_dot > 0`) on the
    /// initial condition's elbow branch, m (paper Table II).
    pub p_zero_end_m: Option<f64>,
    /// Where `theta1` is largest along the belt on the initial condition's branch, m
    /// (empty if at the end of the bracket): the PID acts on `theta1` alone, and
    /// `theta1*(z_t*)` past this fold is also the `theta1` of a point before it.
    pub theta1_fold_m: Option<f64>,
    /// Trials run.
    pub trials: u32,
    /// Trials whose trajectory violated the model (never counted as reached).
    pub invalid_trials: u32,
    /// Wall-clock time of the search, s.
    pub wall_s: f64,
}

/// The gains of `sil-host zmax`'s trials (paper eqs. 8 to 11), ideal and sampled alike.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxGains {
    /// PID gains per joint (eq. 8).
    pub pid: rig::scenario::PidSection,
    /// `K'_P`, 1/s^2 (eq. 10).
    pub hybrid_kp: f64,
    /// `K'_D`, 1/s (eq. 10).
    pub hybrid_kd: f64,
    /// `K'_I` from `x0d`, 1/s (eq. 11).
    pub hybrid_ki_x0d: f64,
    /// `K'_I` from `x0u`, 1/s (eq. 11).
    pub hybrid_ki_x0u: f64,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxSummary {
    /// One row per case.
    pub results: Vec<ZmaxRow>,
    /// Every trial of every case.
    pub trials: Vec<Trial>,
    /// The criteria of a trial.
    pub criteria: Criteria,
    /// Bisection tolerance, m.
    pub tol_m: f64,
    /// What a trial checks.
    pub definition: &'static str,
    /// The paper's figures (docs/model.md gives none).
    pub paper: &'static str,
    /// The base scenario of the sampled setting (its target, run length, controller
    /// and initial condition are set per trial).
    pub base_scenario: Scenario,
    /// Validity counters summed over every trial.
    pub validity: Validity,
    /// The plant's parameters of every trial (paper Table I, `mu`, `v_belt`; SI,
    /// radians), from the base scenario.
    pub plant_params: shared::Params<f64>,
    /// The gains of every trial (paper eqs. 8 to 11), `K'_I` resolved per
    /// initial condition.
    pub gains: ZmaxGains,
    /// Wall-clock time of the whole command, s.
    pub wall_s: f64,
}

pub(crate) const DEFINITION: &str = "z_t* is reached with no lift-off when, over the whole run (the quintic move of z_t* over move_time_s, then held until duration_s): \
the tip never leaves the belt (no lift-off event, located exactly between samples too; no impact without collision; no sample in flight); \
the run ends normally (no plant failure, firmware safe state or ideal-law fault) with no model violation (energy-creating impact, friction-cone violation); and |z_t - z_t*| <= settle_tol_m at every sample of the last settle_window_s. \
Z_t,sliding is the largest target verified reached by bisection on [lo, hi] to tol_m; lower_fails: lo already fails (no limit); upper_reached: the limit is at least hi.";

pub(crate) const PAPER: &str = "docs/model.md gives no value for Z_t,sliding: these are ours.";

/// A flat row of `trials.csv`.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct TrialRow {
    pub(crate) controller: ControllerKind,
    pub(crate) x0: PaperX0,
    pub(crate) setting: Setting,
    pub(crate) target_z_t_m: f64,
    pub(crate) reached: bool,
    pub(crate) lift_offs: u64,
    pub(crate) impacts_without_collision: u64,
    pub(crate) first_lift_off_s: Option<f64>,
    pub(crate) settle_error_m: f64,
    pub(crate) failure: Option<String>,
    pub(crate) simulated_s: f64,
    pub(crate) wall_s: f64,
    pub(crate) energy_gains: u64,
    pub(crate) newton_fallbacks: u64,
    pub(crate) poisson_fallbacks: u64,
    pub(crate) cone_violations: u64,
    pub(crate) zeno_stops: u64,
    pub(crate) integrator_failures: u64,
}

impl From<&Trial> for TrialRow {
    fn from(t: &Trial) -> Self {
        Self {
            controller: t.combination.controller,
            x0: t.combination.x0,
            setting: t.combination.setting,
            target_z_t_m: t.target_z_t,
            reached: t.reached,
            lift_offs: t.lift_offs,
            impacts_without_collision: t.impacts_without_collision,
            first_lift_off_s: t.first_lift_off_s,
            settle_error_m: t.settle_error_m,
            failure: t.failure.clone(),
            simulated_s: t.simulated_s,
            wall_s: t.wall_s,
            energy_gains: t.validity.energy_gains,
            newton_fallbacks: t.validity.newton_fallbacks,
            poisson_fallbacks: t.validity.poisson_fallbacks,
            cone_violations: t.validity.cone_violations,
            zeno_stops: t.validity.zeno_stops,
            integrator_failures: t.validity.integrator_failures,
        }
    }
}

pub(crate) fn print_table(s: &ZmaxSummary, written: &[std::path::PathBuf]) {
    let mut o = std::io::stdout().lock();
    let c = &s.criteria;
    let _ = writeln!(
        o,
        "Z_t,sliding (docs/model.md experiments 5 and 6): largest z_t* reached with no lift-off; mu {}, v_belt {} m/s, move {} s, run {} s, settle within {} mm over the last {} s, bisection to {} mm",
        s.base_scenario.plant.mu,
        s.base_scenario.plant.v_belt,
        c.move_time_s,
        c.duration_s,
        c.settle_tol_m * 1e3,
        c.settle_window_s,
        s.tol_m * 1e3
    );
    let _ = writeln!(
        o,
        "{:<8} {:<4} {:<8} {:>16} {:>15} {:>13} {:>16} {:>7} {:>8}",
        "control", "x0", "setting", "Z_t,sliding (m)", "first fail (m)", "p = 0 at (m)", "theta1 max at (m)", "trials", "wall (s)"
    );
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    for r in &s.results {
        let z = match r.outcome {
            "lower_fails" => format!("< {:.4}", r.bracket_lo_m),
            "upper_reached" => format!(">= {:.4}", r.bracket_hi_m),
            _ => f(r.z_t_sliding_m),
        };
        let _ = writeln!(
            o,
            "{:<8} {:<4} {:<8} {:>16} {:>15} {:>13} {:>16} {:>7} {:>8.2}",
            r.controller,
            format!("x0{}", r.x0),
            r.setting,
            z,
            f(r.first_failing_m),
            f(r.p_zero_end_m),
            f(r.theta1_fold_m),
            r.trials,
            r.wall_s
        );
    }
    for r in &s.results {
        if let Some(why) = &r.why_failing {
            let _ = writeln!(o, "{} x0{} {}: first failing target {}", r.controller, r.x0, r.setting, why);
        }
    }
    let _ = writeln!(
        o,
        "p = 0 at: end of the admissible range on the branch (paper Table II); theta1 max at: the fold of theta1 along the belt, which the PID (on theta1 alone) cannot pass"
    );
    let _ = writeln!(o, "{}", s.paper);
    let _ = writeln!(o, "validity (all trials): {}", s.validity);
    let invalid: u32 = s.results.iter().map(|r| r.invalid_trials).sum();
    if invalid > 0 {
        let _ = writeln!(o, "INVALID: {invalid} trials violate the model (counted as not reached; trials.csv lists them)");
    }
    let _ = writeln!(
        o,
        "wall time {:.1} s; wrote {}",
        s.wall_s,
        written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
}
