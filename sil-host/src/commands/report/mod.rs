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
//! page's tables (no figures), stamped with date, commit and machine, to FILE
//! (docs/results.md in the repository).

mod format;
mod page;
mod sections;
mod stamp;

use std::{
    path::{Path, PathBuf},
    time::Instant,
};

use analyses::{admissible::AdmissibleReport, modes::ModeMap};
use clap::Parser;
use rig::summary::RunSummary;
use serde::Serialize;

use crate::{
    cli::{Cli, Command, ReportArgs, ReportSize},
    commands::bench::TransportFigures,
    commands::{
        self, Done, poincare::summary::Summary as PoincareSummary, simulate::summary::Summary as SimulateSummary,
        sweep::outputs::SweepSummary, zmax::summary::ZmaxSummary,
    },
    error::CliError,
    output::{OutputSet, progress_bar},
};
use sections::{Step, scenario_dir};
use stamp::Stamp;

/// The typed result of one experiment.
#[derive(Debug)]
pub enum Outcome {
    /// `modes`.
    Modes(ModeMap),
    /// `admissible`.
    Admissible(AdmissibleReport),
    /// `simulate`.
    Simulate(SimulateSummary),
    /// `sweep`.
    Sweep(SweepSummary),
    /// `poincare`.
    Poincare(PoincareSummary),
    /// `zmax`.
    Zmax(ZmaxSummary),
    /// `run` and `pil`.
    Run(Box<RunSummary>),
    /// `bench`.
    Bench(Vec<TransportFigures>),
}

impl Outcome {
    /// The command's JSON document (what `--json` prints), for `report.json`.
    fn document(&self, files: &[String]) -> serde_json::Value {
        let v = match self {
            Self::Modes(m) => serde_json::to_value(commands::modes::summary::summary(m, files)),
            Self::Admissible(a) => serde_json::to_value(commands::admissible::summary::json_report(a, files)),
            Self::Simulate(s) => serde_json::to_value(s),
            Self::Sweep(s) => serde_json::to_value(s),
            Self::Poincare(p) => serde_json::to_value(p),
            Self::Zmax(z) => serde_json::to_value(z),
            Self::Run(r) => serde_json::to_value(r),
            Self::Bench(b) => serde_json::to_value(b),
        };
        v.unwrap_or(serde_json::Value::Null)
    }
}

/// What one step produced.
#[derive(Debug)]
pub struct StepResult {
    /// The step's id (its folder).
    pub id: &'static str,
    /// The command line that reproduces it.
    pub command: String,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// The typed result; `None` when the command failed before producing one.
    pub outcome: Option<Outcome>,
    /// Why it failed, if it did.
    pub error: Option<String>,
    /// Files it wrote, relative to the report folder.
    pub files: Vec<String>,
}

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
/// experiment failed, after everything is written.
pub fn run(args: &ReportArgs) -> Result<(), CliError> {
    let scenarios = scenario_dir()
        .ok_or_else(|| CliError::BadInput("cannot find the scenarios/ folder: run `sil-host report` from the repository root".into()))?;
    let sections = sections::sections(args.size, &scenarios);
    let mut out = OutputSet::new(&args.output.out)?;
    let n: usize = sections.iter().map(|s| s.steps.len()).sum();
    let progress = progress_bar(n as u64, "report", "experiments", args.output.json);
    let started = Instant::now();
    let mut results: Vec<Vec<StepResult>> = Vec::new();
    for section in &sections {
        let mut rs = Vec::new();
        for st in &section.steps {
            progress.set_message(st.id);
            rs.push(run_step(out.dir(), st));
            progress.inc(1);
        }
        results.push(rs);
    }
    progress.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();
    let failed = results.iter().flatten().filter(|r| r.error.is_some()).count();
    let size = match args.size {
        ReportSize::Quick => "quick",
        ReportSize::Paper => "paper",
    };
    let stamp = Stamp::now();
    out.write_bytes("report.md", page::render(&sections, &results, size, wall_s, &stamp, true).as_bytes())?;
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
    let index = ReportIndex { size, stamp: &stamp, wall_s, failed, steps };
    let json = out.write_json("report.json", &index)?;
    let dir = out.dir().to_path_buf();
    out.commit()?;
    if let Some(path) = &args.results {
        let text = format!(
            "# Results\n\nGenerated by `sil-host report --size {size} --results {}`; do not edit by hand. \
             The figures and data files are in the report's folder (`{}`).\n\n{}",
            path.display(),
            dir.display(),
            page::render(&sections, &results, size, wall_s, &stamp, false)
        );
        std::fs::write(path, text).map_err(|source| CliError::Io { path: path.clone(), source })?;
    }
    if args.output.json {
        println!("{json}");
    } else {
        println!("report: {n} experiments in {wall_s:.1} s wall, {failed} failed; open {}", dir.join("report.md").display());
    }
    if failed > 0 {
        return Err(CliError::PartFailed(format!("{failed} experiment(s) failed; see {}", dir.join("report.md").display())));
    }
    Ok(())
}

/// Runs one step in this process: its command line parsed by the command line's
/// parser (`--out` its folder, `--json` to keep the terminal quiet), then the
/// command's `execute`.
fn run_step(root: &Path, st: &Step) -> StepResult {
    let dir = root.join(st.id);
    let command = if st.writes {
        format!("sil-host {} --out {}", st.args.join(" "), dir.display())
    } else {
        format!("sil-host {}", st.args.join(" "))
    };
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

/// The command's typed result and its failure after writing, if any.
fn execute(command: Command) -> Result<(Outcome, Option<CliError>), CliError> {
    fn typed<T>(done: Done<T>, wrap: impl FnOnce(T) -> Outcome) -> (Outcome, Option<CliError>) {
        (wrap(done.result), done.failure)
    }
    Ok(match command {
        Command::Modes(a) => typed(commands::modes::execute(&a)?, Outcome::Modes),
        Command::Admissible(a) => typed(commands::admissible::execute(&a)?, Outcome::Admissible),
        Command::Simulate(a) => typed(commands::simulate::execute(&a)?, Outcome::Simulate),
        Command::Sweep(a) => typed(commands::sweep::execute(&a)?, Outcome::Sweep),
        Command::Poincare(a) => typed(commands::poincare::execute(&a)?, Outcome::Poincare),
        Command::Zmax(a) => typed(commands::zmax::execute(&a)?, Outcome::Zmax),
        Command::Run(a) => typed(commands::run::execute(&a)?, |(summary, _)| Outcome::Run(Box::new(summary))),
        Command::Pil(a) => typed(commands::pil::execute(&a)?, |(summary, _)| Outcome::Run(Box::new(summary))),
        Command::Bench(a) => (Outcome::Bench(commands::bench::execute(&a)?), None),
        other => return Err(CliError::BadInput(format!("the report has no page for {other:?}"))),
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
