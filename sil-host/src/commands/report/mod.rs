//! `sil-host report`: every experiment of docs/model.md at a size that finishes in
//! minutes, gathered in one Markdown page (`report.md`) with every figure and
//! table, so a researcher sees the whole reproduction at once.
//!
//! Each experiment is a command line, exactly as a user would type it (the page
//! gives it); the report parses it with the command line's own parser and calls
//! the command's `execute` in this process, which returns the typed result the
//! page is drawn from. Its files go to a folder of their own next to the page. A
//! failed experiment does not stop the others; the page says what failed and
//! why, and the command exits 1 at the end. `--results FILE` also writes the
//! page, stamped with date, commit and machine, to FILE (docs/results.md in the
//! repository) with its figures copied to `figures/` beside it
//! ([`results_page`]).

pub mod animations;
mod captions;
mod closed_loop;
mod experiments;
mod format;
mod outcome;
mod page;
mod paper;
mod results_page;
mod runs;
mod sections;
mod stamp;

use std::{
    path::{Path, PathBuf},
    sync::{
        atomic::{AtomicBool, Ordering},
        mpsc::{self, RecvTimeoutError},
    },
    time::{Duration, Instant},
};

use clap::Parser;
use serde::Serialize;

use crate::{
    cli::{Cli, Command, ReportArgs, ReportSize},
    commands::{self, Done},
    error::CliError,
    output::{OutputSet, progress_bar},
};
use outcome::{Outcome, StepResult};
use sections::{Step, scenario_dir};
use stamp::Stamp;

/// One step of `report.json`.
#[derive(Debug, Serialize)]
struct StepJson<'a> {
    id: &'a str,
    command: &'a str,
    ok: bool,
    error: Option<&'a str>,
    wall_s: f64,
    files: &'a [String],
    result: serde_json::Value,
}

/// `report.json`: the index of the page.
#[derive(Debug, Serialize)]
struct ReportIndex<'a> {
    size: &'static str,
    seeds: usize,
    stamp: &'a Stamp,
    wall_s: f64,
    failed: usize,
    steps: Vec<StepJson<'a>>,
}

/// Runs `sil-host report`.
///
/// # Errors
/// [`CliError::BadInput`] when the scenario folder is missing; [`CliError::Io`]
/// when the report cannot be written; [`CliError::PartFailed`] (exit 1) when an
/// experiment failed, after everything is written; [`CliError::Analysis`]
/// (exit 130 or 143) when Ctrl-C or SIGTERM stopped it, after the page is written
/// with the experiments that finished (`--results` is then not written).
pub fn run(args: &ReportArgs) -> Result<(), CliError> {
    let scenarios = scenario_dir()
        .ok_or_else(|| CliError::bad_input("cannot find the scenarios/ folder: run `sil-host report` from the repository root"))?;
    if !(1..=analyses::sweep::ensemble::MAX_SEEDS).contains(&args.seeds) {
        return Err(CliError::bad_input(format!("--seeds must be in 1..={}, got {}", analyses::sweep::ensemble::MAX_SEEDS, args.seeds)));
    }
    let sections = sections::sections(args.size, &scenarios, args.seeds);
    let mut out = OutputSet::new(&args.output.out)?;
    let n: usize = sections.iter().map(|s| s.steps.len()).sum();
    let progress = progress_bar(n as u64, "report", "experiments", args.output.json);
    let started = Instant::now();
    // One stop flag for the whole report: a signal stops the experiment running and
    // every one after it, and the page is written with what finished.
    let stop = crate::cancel::stop_flag();
    let mut results: Vec<Vec<StepResult>> = Vec::new();
    for section in &sections {
        let mut rs = Vec::new();
        for st in &section.steps {
            progress.set_message(st.id);
            rs.push(if stop.load(Ordering::Relaxed) {
                StepResult::not_run(out.dir(), st, "not run: the report was interrupted (Ctrl-C or SIGTERM)")
            } else {
                run_step_until_stopped(out.dir(), st, &stop)
            });
            progress.inc(1);
        }
        results.push(rs);
    }
    progress.finish_and_clear();
    let interrupted = stop.load(Ordering::Relaxed);
    if !interrupted {
        animations::animate(out.dir(), &mut results);
    }
    let wall_s = started.elapsed().as_secs_f64();
    let failed = results.iter().flatten().filter(|r| r.error.is_some()).count();
    let size = match args.size {
        ReportSize::Quick => "quick",
        ReportSize::Paper => "paper",
    };
    let stamp = Stamp::now();
    let page = page::Page { out: out.dir(), figure_prefix: "", data: true };
    let options = format!("--size {size} --seeds {}", args.seeds);
    let (report_md, _) = page::render(&sections, &results, &options, wall_s, &stamp, page);
    out.write_bytes("report.md", report_md.as_bytes())?;
    let steps = results
        .iter()
        .flatten()
        .map(|r| StepJson {
            id: r.id,
            command: &r.command,
            ok: r.error.is_none(),
            error: r.error.as_deref(),
            wall_s: r.wall_s,
            files: &r.files,
            result: r.outcome.as_ref().map_or(serde_json::Value::Null, |o| o.document(&r.files)),
        })
        .collect();
    let index = ReportIndex { size, seeds: args.seeds, stamp: &stamp, wall_s, failed, steps };
    let json = out.write_json("report.json", &index)?;
    let dir = out.dir().to_path_buf();
    out.commit()?;
    if interrupted {
        let finished = results.iter().flatten().filter(|r| r.error.is_none()).count();
        let results_note = if args.results.is_some() { "; --results was not written" } else { "" };
        return Err(CliError::interrupted(format!(
            "{finished} of {n} experiments finished; the page lists them: {}{results_note}",
            dir.join("report.md").display()
        )));
    }
    if let Some(path) = &args.results {
        results_page::write(path, &dir, &sections, &results, &options, wall_s, &stamp)?;
    }
    if args.output.json {
        outln!("{json}");
    } else {
        outln!("report: {n} experiments in {wall_s:.1} s wall, {failed} failed; open {}", dir.join("report.md").display());
    }
    if failed > 0 {
        return Err(CliError::PartFailed(format!("{failed} experiment(s) failed; see {}", dir.join("report.md").display())));
    }
    let mut validity = plant::Validity::default();
    for v in results.iter().flatten().filter_map(|r| r.outcome.as_ref().and_then(Outcome::validity)) {
        validity.add(&v);
    }
    if !validity.is_valid() {
        eprintln!("report: results violate the model: {} (the page lists them)", validity.describe_violations());
    }
    Done::ok((), Vec::new()).strict(args.strict.strict, &validity).into_result()
}

/// How long an experiment gets after a stop signal to finish cleanly: those
/// that check the stop flag (sweeps, the sensitivity study, closed-loop runs) end
/// within a period or a run and write what they finished; the others (pure
/// computations that write only at their end) are abandoned, so the report
/// stops within a second either way.
const GRACE: Duration = Duration::from_millis(500);

/// [`run_step`] on a thread of its own, while this one watches `stop`: the step's
/// result, or, once `stop` is set and [`GRACE`] has passed, a result that says
/// the step was abandoned (the thread goes on until the process exits).
fn run_step_until_stopped(root: &Path, st: &Step, stop: &AtomicBool) -> StepResult {
    let (tx, rx) = mpsc::channel();
    let (dir, step) = (root.to_path_buf(), st.clone());
    let started = Instant::now();
    let spawned = std::thread::Builder::new().name(format!("report {}", st.id)).spawn(move || {
        let _ = tx.send(run_step(&dir, &step));
    });
    if let Err(e) = spawned {
        return StepResult::not_run(root, st, &format!("cannot start a thread for it: {e}"));
    }
    loop {
        match rx.recv_timeout(Duration::from_millis(20)) {
            Ok(r) => return r,
            Err(RecvTimeoutError::Disconnected) => {
                return StepResult::not_run(root, st, "the experiment panicked (a bug: please report it with its command line)");
            }
            Err(RecvTimeoutError::Timeout) if stop.load(Ordering::Relaxed) => {
                return rx.recv_timeout(GRACE).unwrap_or_else(|_| {
                    let why =
                        format!("interrupted after {:.1} s (Ctrl-C or SIGTERM): abandoned unfinished", started.elapsed().as_secs_f64());
                    StepResult::not_run(root, st, &why)
                });
            }
            Err(RecvTimeoutError::Timeout) => {}
        }
    }
}

/// Runs one step in this process: its command line parsed by the command line's
/// parser (`--out` its folder, `--json` to keep the terminal quiet), then the
/// command's `execute`.
fn run_step(root: &Path, st: &Step) -> StepResult {
    let dir = root.join(st.id);
    let command = command_line(root, st);
    let started = Instant::now();
    let out = if st.writes { vec!["--out".to_string(), dir.display().to_string()] } else { vec![] };
    let argv = std::iter::once("sil-host".to_string()).chain(st.args.iter().cloned()).chain(out).chain(["--json".to_string()]);
    let (outcome, error) = match Cli::try_parse_from(argv) {
        Ok(cli) => match execute(cli.command) {
            Ok((outcome, failure)) => (Some(outcome), failure.map(|e| e.to_string())),
            Err(e) => (None, Some(e.to_string())),
        },
        Err(e) => (None, Some(e.to_string())),
    };
    StepResult { id: st.id, command, wall_s: started.elapsed().as_secs_f64(), outcome, error, files: files_in(root, &dir) }
}

/// The command line that reproduces step `st` of the report in `root`.
fn command_line(root: &Path, st: &Step) -> String {
    if st.writes {
        format!("sil-host {} --out {}", st.args.join(" "), root.join(st.id).display())
    } else {
        format!("sil-host {}", st.args.join(" "))
    }
}

/// The command's typed result and its failure after writing, if any.
fn execute(command: Command) -> Result<(Outcome, Option<CliError>), CliError> {
    fn typed<T>(done: Done<T>, wrap: impl FnOnce(T) -> Outcome) -> (Outcome, Option<CliError>) {
        (wrap(done.result), done.failure)
    }
    Ok(match command {
        Command::Modes(a) => typed(commands::modes::execute(&a)?, Outcome::Modes),
        Command::Admissible(a) => typed(commands::admissible::execute(&a)?, Outcome::Admissible),
        Command::Simulate(a) => typed(commands::simulate::execute(&a)?, |s| Outcome::Simulate(Box::new(s))),
        Command::Sweep(a) => typed(commands::sweep::execute(&a)?, |s| Outcome::Sweep(Box::new(s))),
        Command::Poincare(a) => typed(commands::poincare::execute(&a)?, |p| Outcome::Poincare(Box::new(p))),
        Command::Zmax(a) => typed(commands::zmax::execute(&a)?, |z| Outcome::Zmax(Box::new(z))),
        Command::Run(a) => typed(commands::run::execute(&a)?, |(summary, _)| Outcome::Run(Box::new(summary))),
        Command::Pil(a) => typed(commands::pil::execute(&a)?, |(summary, _)| Outcome::Run(Box::new(summary))),
        Command::Bench(a) => (Outcome::Bench(commands::bench::execute(&a)?), None),
        Command::Sensitivity(a) => typed(commands::sensitivity::execute(&a)?, |s| Outcome::Sensitivity(Box::new(s))),
        other => return Err(CliError::bad_input(format!("the report has no page for {other:?}"))),
    })
}

/// Files of `dir`, relative to `root`, sorted (hidden and partial files left out).
fn files_in(root: &Path, dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && !p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')))
        .filter_map(|p| p.strip_prefix(root).ok().map(PathBuf::from))
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}
