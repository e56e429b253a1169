//! `sil-host zmax`: `Z_t,sliding` (docs/model.md experiments 5 and 6), the largest
//! tangential target the tip reaches with no lift-off, by bisection
//! ([`analyses::zmax`] defines the trial and the criteria), for the PID and the hybrid
//! controller from `x0d` and `x0u`, ideal (the paper's setting) or sampled (the
//! firmware in-process). `--all` runs the eight cases in parallel (rayon).
//!
//! Writes `zmax.csv` (one row per case), `trials.csv` (every trial), `summary.json`
//! and one figure per case, `zmax-<controller>-x0<d|u>-<setting>.svg`: the time
//! history of the run at the limit (tip position and reference, normal force,
//! torques, contact mode).

use std::{io::Write, time::Instant};

use rayon::prelude::*;
use serde::Serialize;

use crate::{
    cli::ZmaxArgs,
    error::CliError,
    output::{OutputSet, progress_bar, write_csv},
    plot,
};
use analyses::admissible::{p_on_belt, positive_intervals};
use analyses::zmax::{
    Bisection, Combination, Criteria, Search, Setting, Trial, default_bracket, max_evaluations, sampled_scenario, search,
};
use plant::initial::PaperX0;
use rig::scenario::Scenario;

/// One row of `zmax.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct ZmaxRow {
    /// `pid` or `hybrid`.
    pub controller: &'static str,
    /// `d` or `u`.
    pub x0: &'static str,
    /// `ideal` or `sampled`.
    pub setting: &'static str,
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
    /// Wall-clock time of the search, s.
    pub wall_s: f64,
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
    /// Wall-clock time of the whole command, s.
    pub wall_s: f64,
}

const DEFINITION: &str = "z_t* is reached with no lift-off when, over the whole run (the quintic move of z_t* over move_time_s, then held until duration_s): \
the tip never leaves the belt (no lift-off event, located exactly between samples too; no impact without collision; no sample in flight); \
the run ends normally (no plant failure, firmware safe state or ideal-law fault); and |z_t - z_t*| <= settle_tol_m at every sample of the last settle_window_s. \
Z_t,sliding is the largest target verified reached by bisection on [lo, hi] to tol_m; lower_fails: lo already fails (no limit); upper_reached: the limit is at least hi.";

const PAPER: &str = "docs/model.md gives no value for Z_t,sliding: these are ours.";

fn combinations(args: &ZmaxArgs) -> Vec<Combination> {
    if args.all {
        return Combination::all();
    }
    let (controller, x0) = (args.controller, args.x0);
    let setting = if args.ideal { Setting::Ideal } else { Setting::Sampled };
    vec![Combination { controller, x0, setting }]
}

fn base_scenario(args: &ZmaxArgs) -> Result<Scenario, CliError> {
    match &args.scenario {
        Some(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| CliError::BadInput(format!("cannot read scenario {}: {e}", path.display())))?;
            Ok(Scenario::from_toml(&text)?)
        }
        None => Ok(Scenario::default_scenario()),
    }
}

/// End of the admissible range on the initial condition's branch, `z_r_dot > 0`.
fn p_zero_end(base: &Scenario, x0: PaperX0, bracket: (f64, f64)) -> Option<f64> {
    let mut params = shared::Params::<f64>::paper();
    params.mu = base.plant.mu;
    params.v_belt = base.plant.v_belt;
    let arm = shared::Arm::new(params);
    let branch = x0.branch();
    let p = |z| p_on_belt(&arm, z, branch, shared::SlipDirection::Positive);
    positive_intervals(p, bracket.0, bracket.1 + 1e-3 - 1e-9, 20_000, 1e-9).iter().find(|i| i.hi_is_root).map(|i| i.hi)
}

/// The `z_t` (m) of the largest `theta1` on the belt on the initial condition's
/// branch, by a scan of 20 000 steps over the bracket; `None` at an end of it.
fn theta1_fold(x0: PaperX0, bracket: (f64, f64)) -> Option<f64> {
    let params = shared::Params::<f64>::paper();
    let branch = x0.branch();
    let n = 20_000;
    let z_at = |i: usize| bracket.0 + (bracket.1 - bracket.0) * i as f64 / n as f64;
    let theta1 = |z: f64| {
        shared::kinematics::inverse_kinematics(params.l, &nalgebra::Vector2::new(z, -params.h), branch).map_or(f64::NEG_INFINITY, |q| q[0])
    };
    let best = (0..=n).max_by(|&a, &b| theta1(z_at(a)).total_cmp(&theta1(z_at(b))))?;
    (best > 0 && best < n).then(|| z_at(best))
}

/// Runs `sil-host zmax`.
///
/// # Errors
/// Bad input (exit 2, nothing written); I/O or plotting failures (exit 1).
pub fn run(args: &ZmaxArgs) -> Result<(), CliError> {
    let started = Instant::now();
    let base = base_scenario(args)?;
    let criteria = Criteria {
        duration_s: args.duration,
        move_time_s: base.controller.move_time_s,
        settle_tol_m: args.settle_tol,
        settle_window_s: args.settle_window,
    };
    criteria.validate()?;
    if !(args.tol.is_finite() && args.tol > 0.0) {
        return Err(CliError::BadInput(format!("--tol {} m must be finite and > 0", args.tol)));
    }
    let combos = combinations(args);
    for c in &combos {
        analyses::zmax::check_x0(c.x0)?;
    }
    // Check every set-up before the output folder is touched.
    let mut jobs = Vec::new();
    for combo in combos {
        let bracket = match &args.bracket {
            Some(s) => super::parse_range("bracket", s)?,
            None => default_bracket(&base, combo.x0)?,
        };
        sampled_scenario(&base, combo, bracket.1, &criteria)?;
        analyses::ideal::build(&analyses::ideal::IdealSetup {
            target_z_t: bracket.1,
            ..analyses::ideal::IdealSetup::paper(combo.controller, plant::initial::deg_to_state(combo.x0.condition().deg), bracket.0)
        })
        .map_err(CliError::Sim)?;
        jobs.push((combo, bracket));
    }
    let total: u64 = jobs.iter().map(|(_, b)| u64::from(max_evaluations(b.0, b.1, args.tol))).sum();
    let progress = progress_bar(total, "Z_t,sliding", "trials", args.output.json);
    let results: Vec<Result<Search, analyses::AnalysisError>> = jobs
        .par_iter()
        .map(|&(combo, bracket)| {
            let s = search(&base, combo, bracket, args.tol, &criteria, |_| progress.inc(1));
            // A search that ends early (a bracket end decides) frees its share of the bar.
            if let Ok(s) = &s {
                progress.inc(u64::from(max_evaluations(bracket.0, bracket.1, args.tol).saturating_sub(s.bisection.evaluations())));
            }
            s
        })
        .collect();
    progress.finish_and_clear();
    let searches = results.into_iter().collect::<Result<Vec<_>, _>>()?;

    let mut out = OutputSet::new(&args.output.out)?;
    let rows: Vec<ZmaxRow> = searches
        .iter()
        .map(|s| {
            let (outcome, first_failing, failing_target) = match s.bisection {
                Bisection::Found { hi, .. } => ("found", Some(hi), Some(hi)),
                Bisection::LowerFails { lo, .. } => ("lower_fails", None, Some(lo)),
                Bisection::UpperReached { .. } => ("upper_reached", None, None),
            };
            let why_failing = failing_target.and_then(|x| s.trials.iter().find(|t| t.target_z_t == x)).and_then(Trial::why_not);
            ZmaxRow {
                controller: s.combination.controller.name(),
                x0: s.combination.x0.letter(),
                setting: s.combination.setting.name(),
                outcome,
                z_t_sliding_m: s.z_t_sliding,
                first_failing_m: first_failing,
                why_failing,
                bracket_lo_m: s.bracket.0,
                bracket_hi_m: s.bracket.1,
                p_zero_end_m: p_zero_end(&base, s.combination.x0, s.bracket),
                theta1_fold_m: theta1_fold(s.combination.x0, s.bracket),
                trials: s.trials.len() as u32,
                wall_s: s.wall_s,
            }
        })
        .collect();
    write_csv(&mut out, "zmax.csv", &rows)?;
    let trials: Vec<Trial> = searches.iter().flat_map(|s| s.trials.iter().cloned()).collect();
    write_csv(&mut out, "trials.csv", &trials.iter().map(TrialRow::from).collect::<Vec<_>>())?;
    for s in &searches {
        let path = out.stage(&format!("zmax-{}.svg", s.combination.stem()));
        draw(&path, s)?;
    }
    let summary = ZmaxSummary {
        results: rows,
        trials,
        criteria,
        tol_m: args.tol,
        definition: DEFINITION,
        paper: PAPER,
        base_scenario: base,
        wall_s: started.elapsed().as_secs_f64(),
    };
    let json = out.write_json("summary.json", &summary)?;
    let written = out.commit()?;
    if args.output.json {
        println!("{json}");
    } else {
        print_table(&summary, &written);
    }
    Ok(())
}

/// A flat row of `trials.csv`.
#[derive(Debug, Clone, Serialize)]
struct TrialRow {
    controller: &'static str,
    x0: &'static str,
    setting: &'static str,
    target_z_t_m: f64,
    reached: bool,
    lift_offs: u64,
    impacts_without_collision: u64,
    first_lift_off_s: Option<f64>,
    settle_error_m: f64,
    failure: Option<String>,
    simulated_s: f64,
    wall_s: f64,
}

impl From<&Trial> for TrialRow {
    fn from(t: &Trial) -> Self {
        Self {
            controller: t.combination.controller.name(),
            x0: t.combination.x0.letter(),
            setting: t.combination.setting.name(),
            target_z_t_m: t.target_z_t,
            reached: t.reached,
            lift_offs: t.lift_offs,
            impacts_without_collision: t.impacts_without_collision,
            first_lift_off_s: t.first_lift_off_s,
            settle_error_m: t.settle_error_m,
            failure: t.failure.clone(),
            simulated_s: t.simulated_s,
            wall_s: t.wall_s,
        }
    }
}

fn print_table(s: &ZmaxSummary, written: &[std::path::PathBuf]) {
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
    let _ = writeln!(
        o,
        "wall time {:.1} s; wrote {}",
        s.wall_s,
        written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
}

fn draw(path: &std::path::Path, s: &Search) -> Result<(), CliError> {
    let rows = &s.limit_trace;
    let t_end = rows.last().map_or(1.0, |r| r.t).max(1e-9);
    let samples: Vec<plot::HistorySample> = rows
        .iter()
        .map(|r| plot::HistorySample { t: r.t, z_t: r.z_t, z_t_ref: r.z_t_ref, f_n: r.f_n, u: [r.u1, r.u2], mode: r.mode })
        .collect();
    let panels = plot::history_panels(&samples, false);
    let c = &s.combination;
    let what = match s.bisection {
        Bisection::Found { lo, hi, .. } => format!("at the limit z_t* = {lo:.4} m (fails at {hi:.4} m)"),
        Bisection::LowerFails { lo, .. } => format!("lifts off already at the lowest target {lo:.4} m"),
        Bisection::UpperReached { hi, .. } => format!("reaches the highest target {hi:.4} m"),
    };
    let title = format!("Z_t,sliding: {} from x0{}, {}: {what}", c.controller.name(), c.x0.letter(), c.setting.name());
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
