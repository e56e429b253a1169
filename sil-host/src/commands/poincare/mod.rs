//! `sil-host poincare`: the one-parameter bifurcation diagram of the open loop
//! (docs/model.md experiment 4, the paper's Fig. 4), with each belt speed classified.
//!
//! Writes under `--out`: `section.csv` (every section point: `v_belt`, crossing
//! time, state), `classes.csv` and `classes.json` (per `v_belt`: class, period,
//! distinct points, Lyapunov estimate, events in the record), `summary.json`
//! (settings, the initial condition and its projection, the bands of equal class,
//! wall time), `bifurcation.svg` (`theta1` at the section against `v_belt`,
//! coloured by class) and `lyapunov.svg` (the exponent against `v_belt`).
//! A belt speed whose simulation fails is written with class `failed` and the
//! command exits with 1 after writing everything.

use crate::commands::Done;
use crate::{
    cli::PoincareArgs,
    error::CliError,
    output::{OutputSet, progress_bar, write_csv},
};

pub mod figures;
mod print;
pub use experiments::poincare::{analyse_grid, failure, section_rows, summary, summary::*, validated};
use figures::*;
use print::*;

/// Runs `sil-host poincare`.
///
/// # Errors
/// [`CliError::BadInput`] or an analysis's bad input, parameter or initial state
/// ([`CliError::Analysis`], exit 2) for bad options or initial conditions, before anything is written; [`CliError::Analysis`]
/// (exit 1) when some belt speed failed (everything is written first);
/// [`CliError::Io`]/[`CliError::Plot`] when writing fails.
pub fn execute(args: &PoincareArgs) -> Result<Done<Summary>, CliError> {
    let (cfg, grid, ic) = validated(args)?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = experiments::pool(threads)?;
    let mut out = OutputSet::new(&args.output.out)?;

    let progress = progress_bar(grid.len() as u64, "poincare", "belt speeds", args.output.json);
    // Ctrl-C or SIGTERM (cancel.rs) stops the grid: the belt speeds being
    // analysed finish, then the command says so and writes nothing (a diagram is
    // of the whole grid); the folder's owner file goes with its lock.
    let stop = crate::cancel::stop_flag();
    let (results, wall_s) = analyse_grid(&pool, &cfg, &grid, &stop, &|| progress.inc(1));
    progress.finish_and_clear();
    if stop.load(std::sync::atomic::Ordering::Relaxed) {
        return Err(CliError::interrupted(format!(
            "poincare stopped after {} of {} belt speeds in {wall_s:.1} s; nothing written (the diagram is of the whole grid: run it again)",
            results.len(),
            grid.len()
        )));
    }

    let section = section_rows(&results);
    write_csv(&mut out, "section.csv", &section)?;
    let rows: Vec<ClassRow> = results.iter().map(ClassRow).collect();
    write_csv(&mut out, "classes.csv", &rows)?;
    let dir = out.dir().to_path_buf();
    let json_err = |name: &str| {
        let path = dir.join(name);
        move |e: serde_json::Error| CliError::Io { path, source: e.into() }
    };
    let classes_json = serde_json::to_string_pretty(&results).map_err(json_err("classes.json"))?;
    out.write_bytes("classes.json", classes_json.as_bytes())?;
    let svg = out.stage_figure("bifurcation.svg")?;
    draw_bifurcation(&svg, &cfg, &ic.name, &results)?;
    let svg = out.stage_figure("lyapunov.svg")?;
    draw_lyapunov(&svg, &cfg, &results)?;

    let files = [
        "section.csv",
        "classes.csv",
        "classes.json",
        "bifurcation.svg",
        "bifurcation.pdf",
        "lyapunov.svg",
        "lyapunov.pdf",
        "summary.json",
    ];
    let files = files
        .iter()
        .filter(|f| ::figures::plot::print::WRITES_PDF || !f.ends_with(".pdf"))
        .map(|f| out.path(f).display().to_string())
        .collect();
    let summary = summary(args, (cfg, &grid, ic), &results, threads, wall_s, files);
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    let failure = failure(&summary, &results);
    let validity = summary.validity;
    Ok(Done { result: summary, files, failure }.strict(args.strict.strict, &validity))
}

/// Runs `sil-host poincare`: [`execute`], then prints the summary (human, or the
/// JSON document with `--json`).
///
/// # Errors
/// As [`execute`]; belt speeds that failed (after writing).
pub fn run(args: &PoincareArgs) -> Result<(), CliError> {
    crate::commands::finish(execute(args)?, args.output.json, |r| r, |r, _| print_human(r))
}
