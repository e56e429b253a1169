//! The package's functions, one per `sil-host` command: each parses its tokens
//! with the CLI's parser, checks them with the CLI's validation (the command's
//! `prepare`/`plan`/`validated`), computes with the libraries (plant, rig,
//! analyses) on a worker thread without the GIL where it is long, and builds the
//! CLI's summary document and tables in memory (nothing is written).

use std::time::Instant;

use pyo3::{prelude::*, types::PyDict};
use rayon::prelude::*;

use analyses::AnalysisError;
use rig::FirmwareLink;
use sil_host::commands::{self as cmd, Done};
use sil_host::error::CliError;

use crate::cli::{args_of, cli_error};
use crate::convert::{Outcome, points_to_py, rows_to_py, to_py};
use crate::work::{self, Control};

/// The CLI's failure after `--strict` ([`Done::strict`]): the message and exit
/// code of what the CLI would exit with after writing its files.
fn failure_of(failure: Option<CliError>, strict: bool, validity: &plant::Validity) -> (Option<String>, i32) {
    let done = Done { result: (), files: Vec::new(), failure }.strict(strict, validity);
    match done.failure {
        Some(e) => (Some(e.to_string()), e.exit_code()),
        None => (None, 0),
    }
}

/// A rayon pool of `threads` threads, as the CLI builds it.
fn pool(py: Python<'_>, threads: usize) -> PyResult<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| cli_error(py, &CliError::BadInput(format!("cannot start {threads} worker threads: {e}"))))
}

/// `painleve.simulate`: `sil-host simulate`.
#[pyfunction]
#[pyo3(signature = (tokens, progress=None))]
pub fn simulate<'py>(py: Python<'py>, tokens: Vec<String>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use cmd::simulate::{Prepared, sample_step, summary::EventRow, trace_row};
    let args = args_of!(py, "simulate", &tokens, Simulate);
    let Prepared { params, sim, steps, initial_condition, mut plant } = cmd::simulate::prepare(&args).map_err(|e| cli_error(py, &e))?;
    let sample_dt = args.sample_dt;
    let (trace, events, failure, wall_s, plant) = work::run(py, progress.as_ref(), "simulate", "samples", |c: &Control| {
        c.set(0, steps as u64);
        let mut trace = Vec::with_capacity(steps + 1);
        let mut events: Vec<EventRow> = plant.startup_events().iter().map(EventRow::from).collect();
        trace.push(trace_row(&plant, plant.contact_force([0.0, 0.0])));
        let started = Instant::now();
        let mut failure = None;
        for k in 0..steps {
            if c.stopped() {
                break;
            }
            match sample_step(&mut plant, k, sample_dt) {
                Ok(report) => {
                    events.extend(report.events.iter().map(EventRow::from));
                    trace.push(trace_row(&plant, report.f));
                }
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
            c.tick();
        }
        (trace, events, failure, started.elapsed().as_secs_f64(), plant)
    })?;
    let summary =
        cmd::simulate::summary(&args, (params, sim, initial_condition), &plant, failure.as_ref(), wall_s, Vec::new(), events.len());
    let (message, code) = failure_of(failure.map(CliError::Sim), args.strict.strict, &summary.validity);
    Outcome::new(py, "simulate", to_py(py, &summary)?)?
        .table("trace", rows_to_py(py, &trace)?)?
        .table("events", rows_to_py(py, &events)?)?
        .validity(&summary.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.admissible`: `sil-host admissible`.
#[pyfunction]
#[pyo3(signature = (tokens))]
pub fn admissible<'py>(py: Python<'py>, tokens: Vec<String>) -> PyResult<Bound<'py, PyDict>> {
    let args = args_of!(py, "admissible", &tokens, Admissible);
    let report = py.detach(|| cmd::admissible::compute(&args)).map_err(|e| cli_error(py, &e))?;
    let document = cmd::admissible::document(&report, &[]).map_err(|e| cli_error(py, &e))?;
    let document = py.import("json")?.call_method1("loads", (document,))?;
    Outcome::new(py, "admissible", document).map(Outcome::done)
}

/// `painleve.modes`: `sil-host modes`.
#[pyfunction]
#[pyo3(signature = (tokens))]
pub fn modes<'py>(py: Python<'py>, tokens: Vec<String>) -> PyResult<Bound<'py, PyDict>> {
    let args = args_of!(py, "modes", &tokens, Modes);
    let map = py.detach(|| cmd::modes::compute(&args)).map_err(|e| cli_error(py, &e))?;
    let rows: Vec<_> = cmd::modes::summary::csv_rows(&map).collect();
    let curves = |lines: &[Vec<(f64, f64)>]| -> PyResult<Bound<'py, PyAny>> {
        Ok(pyo3::types::PyList::new(py, lines.iter().map(|l| points_to_py(py, l)).collect::<PyResult<Vec<_>>>()?)?.into_any())
    };
    Outcome::new(py, "modes", to_py(py, &cmd::modes::summary::summary(&map, &[]))?)?
        .table("modes", rows_to_py(py, &rows)?)?
        .extra("theta1_deg", numpy::PyArray1::from_slice(py, &map.theta1_deg).into_any())?
        .extra("theta1_dot", numpy::PyArray1::from_slice(py, &map.theta1_dot).into_any())?
        .extra("b_zero", curves(&map.b_zero)?)?
        .extra("zr_zero", curves(&map.zr_zero)?)
        .map(Outcome::done)
}

/// `painleve.poincare`: `sil-host poincare`.
#[pyfunction]
#[pyo3(signature = (tokens, progress=None))]
pub fn poincare<'py>(py: Python<'py>, tokens: Vec<String>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use cmd::poincare::summary::ClassRow;
    let args = args_of!(py, "poincare", &tokens, Poincare);
    let (cfg, grid, ic) = cmd::poincare::validated(&args).map_err(|e| cli_error(py, &e))?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = pool(py, threads)?;
    let (results, wall_s) = work::run(py, progress.as_ref(), "poincare", "belt speeds", |c: &Control| {
        c.set(0, grid.len() as u64);
        let started = Instant::now();
        // Stopped between belt speeds: the speeds not started are left out (and
        // the call raises KeyboardInterrupt).
        let results: Vec<Option<analyses::poincare::PointResult>> = pool.install(|| {
            grid.par_iter()
                .map(|&v| {
                    if c.stopped() {
                        return None;
                    }
                    let r = analyses::poincare::analyse(v, &cfg);
                    c.tick();
                    Some(r)
                })
                .collect()
        });
        (results.into_iter().flatten().collect::<Vec<_>>(), started.elapsed().as_secs_f64())
    })?;
    let section = cmd::poincare::section_rows(&results);
    let classes: Vec<ClassRow> = results.iter().map(ClassRow::from).collect();
    let classes_json = to_py(py, &results)?;
    let summary = cmd::poincare::summary(&args, (cfg, &grid, ic), &results, threads, wall_s, Vec::new());
    let failure = cmd::poincare::failure(&summary, &results);
    let (message, code) = failure_of(failure, args.strict.strict, &summary.validity);
    Outcome::new(py, "poincare", to_py(py, &summary)?)?
        .table("section", rows_to_py(py, &section)?)?
        .table("classes", rows_to_py(py, &classes)?)?
        .extra("classes", classes_json)?
        .validity(&summary.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.sweep`: `sil-host sweep`, in memory (no folder, no journal).
#[pyfunction]
#[pyo3(signature = (tokens, progress=None))]
pub fn sweep<'py>(py: Python<'py>, tokens: Vec<String>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use analyses::sweep::run::RunRow;
    use sil_host::commands::sweep::outputs::{Timing, cpu_seconds, summary_of};
    use sil_host::sweep::store::{Manifest, missing};
    let args = args_of!(py, "sweep", &tokens, Sweep);
    let (spec, shard, threads) = cmd::sweep::plan(&args).map_err(|e| cli_error(py, &e))?;
    let mut todo = shard.indices(&spec);
    if let Some(limit) = args.limit {
        todo.truncate(limit);
    }
    let ics = spec.initial_conditions();
    let pool = pool(py, threads)?;
    let (mut rows, timing) = work::run(py, progress.as_ref(), "sweep", "runs", |c: &Control| {
        c.set(0, todo.len() as u64);
        let started = Instant::now();
        let cpu_start = cpu_seconds();
        let rows: Vec<RunRow> = pool.install(|| {
            todo.par_iter()
                .with_max_len(1)
                .filter_map(|&index| {
                    if c.stopped() {
                        return None;
                    }
                    let key = spec.run_at(index);
                    let row = analyses::sweep::run::simulate(&spec, &key, &ics[key.i_ic], &c.stop);
                    if row.is_some() {
                        c.tick();
                    }
                    row
                })
                .collect()
        });
        let (wall_s, cpu_s) = (started.elapsed().as_secs_f64(), cpu_seconds() - cpu_start);
        let timing = Timing::of(&spec, rows.len(), threads, wall_s, cpu_s);
        (rows, timing)
    })?;
    rows.sort_by_key(|r| r.index);
    let manifest = Manifest { spec, shard };
    let n_missing = missing(&manifest, &rows).len();
    let results = analyses::sweep::summary::results(&manifest.spec, &rows, n_missing);
    let summary = summary_of(&manifest, results, n_missing, Some(timing), 0, false, Vec::new());
    let (message, code) = failure_of(None, args.strict.strict, &summary.results.validity);
    Outcome::new(py, "sweep", to_py(py, &summary)?)?
        .table("sweep", rows_to_py(py, &rows)?)?
        .validity(&summary.results.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.zmax`: `sil-host zmax`.
#[pyfunction]
#[pyo3(signature = (tokens, progress=None))]
pub fn zmax<'py>(py: Python<'py>, tokens: Vec<String>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use analyses::zmax::{max_trials, search_until};
    let args = args_of!(py, "zmax", &tokens, Zmax);
    let started = Instant::now();
    let plan = cmd::zmax::plan(&args).map_err(|e| cli_error(py, &e))?;
    let total: u64 = plan.jobs.iter().map(|(_, b)| u64::from(max_trials(b.0, b.1, args.tol))).sum();
    let tol = args.tol;
    let results = work::run(py, progress.as_ref(), "zmax", "trials", |c: &Control| {
        c.set(0, total);
        plan.jobs
            .par_iter()
            .map(|&(combo, bracket)| {
                let s = search_until(&plan.base, combo, bracket, tol, &plan.criteria, &c.stop, |_| c.tick());
                // A search that ends early (a bracket end decides) frees its share of the bar.
                if let Ok(s) = &s {
                    let unused = u64::from(max_trials(bracket.0, bracket.1, tol)).saturating_sub(s.trials.len() as u64);
                    c.done.fetch_add(unused, std::sync::atomic::Ordering::Relaxed);
                }
                s
            })
            .collect::<Vec<Result<analyses::zmax::Search, AnalysisError>>>()
    })?;
    let searches = results.into_iter().collect::<Result<Vec<_>, _>>().map_err(|e| cli_error(py, &CliError::Analysis(e)))?;
    let summary = cmd::zmax::summary(&args, plan, &searches, started.elapsed().as_secs_f64());
    let traces = PyDict::new(py);
    for s in &searches {
        traces.set_item(s.combination.stem(), rows_to_py(py, &s.limit_trace)?)?;
    }
    let (message, code) = failure_of(None, args.strict.strict, &summary.validity);
    Outcome::new(py, "zmax", to_py(py, &summary)?)?
        .table("zmax", rows_to_py(py, &summary.results)?)?
        .table("trials", rows_to_py(py, &cmd::zmax::trial_rows(&summary))?)?
        .extra("limit_traces", traces.into_any())?
        .validity(&summary.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// Keeps the records of a closed-loop run (`rig::run_loop` hands them back),
/// reports its progress, stops on Ctrl-C, keeps the validity.
struct Observer<'a> {
    control: &'a Control,
    validity: plant::Validity,
}

impl rig::RunObserver for Observer<'_> {
    fn on_period(&mut self, k: usize, n: usize) -> bool {
        if k.is_multiple_of(100) || k == n {
            self.control.set(k as u64, n as u64);
        }
        !self.control.stopped()
    }

    fn on_finished(&mut self, validity: &plant::Validity) {
        self.validity = *validity;
    }
}

/// `painleve.run`: `sil-host run --in-process` (the firmware step linked in,
/// lockstep): the SIL run of `rig::in_process`, its trace kept in memory.
#[pyfunction]
#[pyo3(signature = (tokens, progress=None))]
pub fn run<'py>(py: Python<'py>, tokens: Vec<String>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use rig::{in_process::InProcessLink, stats::RunStats, summary::RunSummary};
    let mut tokens = tokens;
    tokens.insert(0, "--in-process".into());
    let args = args_of!(py, "run", &tokens, Run);
    let (scenario, _) = cmd::run::prepare(&args).map_err(|e| cli_error(py, &e))?;
    let mut link = InProcessLink::new(&scenario).map_err(|e| cli_error(py, &CliError::Run(e)))?;
    let (records, failure, validity, wall_s) = work::run(py, progress.as_ref(), "run", "periods", |c: &Control| {
        c.set(0, scenario.timing.periods());
        let mut observer = Observer { control: c, validity: plant::Validity::default() };
        let started = Instant::now();
        let (records, failure) = rig::run_loop(&scenario, &mut link, &mut observer);
        (records, failure, observer.validity, started.elapsed().as_secs_f64())
    })?;
    let stats = RunStats::of(&records);
    let summary = RunSummary {
        firmware_announcement: link.announcement().cloned(),
        ..RunSummary::from_stats(&scenario, &stats, failure.as_ref(), link.transport(), "lockstep", wall_s, validity)
    };
    let (message, code) = failure_of(failure.map(CliError::Run), args.strict.strict, &validity);
    Outcome::new(py, "run", to_py(py, &summary)?)?
        .table("trace", rows_to_py(py, &records)?)?
        .extra("scenario", to_py(py, &scenario)?)?
        .validity(&validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.sensitivity`: `sil-host sensitivity`.
#[pyfunction]
#[pyo3(signature = (tokens, progress=None))]
pub fn sensitivity<'py>(py: Python<'py>, tokens: Vec<String>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    let args = args_of!(py, "sensitivity", &tokens, Sensitivity);
    let (base, threads) = cmd::sensitivity::prepare(&args).map_err(|e| cli_error(py, &e))?;
    let pool = pool(py, threads)?;
    let size = args.size;
    let (study, wall_s) = work::run(py, progress.as_ref(), "sensitivity", "jobs", |c: &Control| {
        let started = Instant::now();
        let study = pool.install(|| analyses::sensitivity::run(&base, size, &c.stop, &|done, total| c.set(done, total)));
        (study, started.elapsed().as_secs_f64())
    })?;
    let study = study.map_err(|e| cli_error(py, &CliError::Analysis(e)))?;
    let rows = study.rows();
    let validity = study.validity;
    let summary = cmd::sensitivity::Summary { study, base_scenario: base, wall_s, threads, files: Vec::new() };
    let (message, code) = failure_of(None, args.strict.strict, &validity);
    Outcome::new(py, "sensitivity", to_py(py, &summary)?)?
        .table("sensitivity", rows_to_py(py, &rows)?)?
        .validity(&validity)?
        .failure(message, code)
        .map(Outcome::done)
}
