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

use std::time::Instant;

use crate::commands::Done;
use crate::{
    cli::ZmaxArgs,
    error::CliError,
    output::{OutputSet, progress_bar, write_csv},
};

pub mod figures;
mod print;
pub use experiments::zmax::{Plan, plan, run_searches, summary, summary::*, trial_rows};
use figures::*;
use print::*;

/// Runs `sil-host zmax`.
///
/// # Errors
/// Bad input (exit 2, nothing written); I/O or plotting failures (exit 1).
pub fn execute(args: &ZmaxArgs) -> Result<Done<ZmaxSummary>, CliError> {
    let started = Instant::now();
    // Check every set-up before the output folder is touched.
    let plan = plan(args)?;
    crate::commands::warn(experiments::scenario::board_tables_note(&plan.base, "zmax (the firmware in-process, or the ideal law)"));
    let total = plan.max_trials(args.tol);
    let progress = progress_bar(total, "Z_t,sliding", "trials", args.output.json);
    // Every search runs to its end (a signal ends the process, cancel.rs).
    let never = std::sync::atomic::AtomicBool::new(false);
    let searches = run_searches(&plan, args.tol, &never, &|n| progress.inc(n));
    progress.finish_and_clear();
    let searches = searches?;

    let mut out = OutputSet::new(&args.output.out)?;
    let n_nominal = plan.jobs.len();
    let summary = summary(args, plan, &searches, f64::NAN);
    write_csv(&mut out, "zmax.csv", &summary.results)?;
    write_csv(&mut out, "trials.csv", &trial_rows(&summary))?;
    if !summary.seeds.is_empty() {
        write_csv(&mut out, "zmax_seeds.csv", &summary.seeds)?;
    }
    // The figures of the nominal searches (seed 0); the seeds' are in zmax_seeds.csv.
    for s in searches.iter().take(n_nominal) {
        let path = out.stage_figure(&format!("zmax-{}.svg", s.combination.stem()))?;
        draw(&path, s)?;
    }
    let summary = ZmaxSummary { wall_s: started.elapsed().as_secs_f64(), ..summary };
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    let validity = summary.validity;
    Ok(Done::ok(summary, files).strict(args.strict.strict, &validity))
}

/// Runs `sil-host zmax`: [`execute`], then prints the table (or the JSON
/// document with `--json`).
///
/// # Errors
/// As [`execute`].
pub fn run(args: &ZmaxArgs) -> Result<(), CliError> {
    crate::commands::finish(execute(args)?, args.output.json, |r| r, print_table)
}
