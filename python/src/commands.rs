//! The package's functions, one per experiment (and `sil-host` command): each
//! builds the experiment's settings ([`experiments::settings`]) from the keyword
//! arguments given (`crate::cli::settings`),
//! checks them with the experiment's own check (`prepare`/`plan`/`validated`),
//! runs the experiment's loop ([`experiments`]: one copy, the command line's too)
//! on a worker thread without the GIL where it is long, and builds the summary
//! document and tables in memory (nothing is written).

use std::time::Instant;

use pyo3::{prelude::*, types::PyDict};

use experiments::run_observer::{Gather, KeepFrames, RunSink};
use experiments::{self as cmd, Done, Error as CliError, settings::*};
use figures::trace_page::{PageInfo, TracePage};
use rig::FirmwareLink;

use crate::cli::{cli_error, settings};
use crate::convert::{Outcome, columns_to_py, points_to_py, rows_to_py, to_py};
use crate::recording::Recording;
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

/// Warns with `note`, if any, as a `painleve.PainleveWarning` (the CLI prints it
/// as `warning: ...` on standard error).
///
/// # Errors
/// The warning raised as an exception (warnings filtered to `error`).
pub(crate) fn warn(py: Python<'_>, note: Option<String>) -> PyResult<()> {
    let Some(note) = note else { return Ok(()) };
    let category = py.import("painleve._result")?.getattr("PainleveWarning")?;
    let message = std::ffi::CString::new(note).unwrap_or_default();
    PyErr::warn(py, &category, &message, 2)
}

/// A rayon pool of `threads` threads ([`experiments::pool`]).
fn pool(py: Python<'_>, threads: usize) -> PyResult<rayon::ThreadPool> {
    experiments::pool(threads).map_err(|e| cli_error(py, &e))
}

/// `painleve.simulate`: `sil-host simulate`.
#[pyfunction]
#[pyo3(signature = (given, progress=None))]
pub fn simulate<'py>(py: Python<'py>, given: Bound<'py, PyDict>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use cmd::simulate::{OpenLoop, summary::TraceRow};
    let args: SimulateArgs = settings(py, "simulate", &given)?;
    let prepared = cmd::simulate::prepare(&args).map_err(|e| cli_error(py, &e))?;
    let (params, sim, initial_condition) = (prepared.params, prepared.sim, prepared.initial_condition.clone());
    let (trace, events, batches, failure, wall_s, plant) = work::run(py, progress.as_ref(), "simulate", "samples", |c: &Control| {
        let (mut open_loop, row, mut events) = OpenLoop::start(prepared, args.sample_dt);
        c.set(0, open_loop.steps as u64);
        let mut trace: Vec<TraceRow> = Vec::with_capacity(open_loop.steps + 1);
        trace.push(row);
        // Where the command line's batches to trace.mcap end (the first sample
        // with the start-up events, then a chunk at a time): Result.write_mcap's bytes.
        let mut batches = vec![(trace.len(), events.len())];
        let started = Instant::now();
        let mut failure = None;
        // Ctrl-C is seen between the loop's chunks (OpenLoop::CHUNK_S s of samples).
        while !open_loop.finished() && failure.is_none() && !c.stopped() {
            failure = open_loop.advance(open_loop.k + 1, &mut trace, &mut events).err();
            batches.push((trace.len(), events.len()));
            c.set(open_loop.k as u64, open_loop.steps as u64);
        }
        (trace, events, batches, failure, started.elapsed().as_secs_f64(), open_loop.plant)
    })?;
    // The page, as `sil-host simulate` writes it (`trace.html`): the same rows and
    // events into the same builder, so the same bytes.
    let page = (!args.no_page).then(|| {
        let impact_law = format!("{:?}", sim.impact_law).to_lowercase();
        let mut page = TracePage::new(PageInfo::open_loop(&params, &initial_condition.name, &impact_law, sim.e_n));
        events.iter().for_each(|e| page.event(e.into()));
        trace.iter().for_each(|r| page.push(&r.into()));
        page.html()
    });
    let geometry = arm_view::ArmGeometry::of(&params);
    let summary =
        cmd::simulate::summary(&args, (params, sim, initial_condition), &plant, failure.as_ref(), wall_s, Vec::new(), events.len());
    let (message, code) = failure_of(failure.map(CliError::from), args.strict.strict, &summary.validity);
    let (trace_py, events_py) = (columns_to_py(py, &trace), columns_to_py(py, &events));
    let recording = Recording::open_loop(geometry, trace, events, batches);
    Outcome::new(py, "simulate", to_py(py, &summary)?)?
        .table("trace", trace_py)?
        .table("events", events_py)?
        .extra("page", page.into_pyobject(py)?.into_any())?
        .extra("recording", Py::new(py, recording)?.into_any().into_bound(py))?
        .validity(&summary.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.admissible`: `sil-host admissible`.
#[pyfunction]
#[pyo3(signature = (given))]
pub fn admissible<'py>(py: Python<'py>, given: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let args: AdmissibleArgs = settings(py, "admissible", &given)?;
    let report = py.detach(|| cmd::admissible::compute(&args)).map_err(|e| cli_error(py, &e))?;
    let document = cmd::admissible::document(&report, &[]).map_err(|e| cli_error(py, &e))?;
    let document = py.import("json")?.call_method1("loads", (document,))?;
    Outcome::new(py, "admissible", document).map(Outcome::done)
}

/// `painleve.modes`: `sil-host modes`.
#[pyfunction]
#[pyo3(signature = (given))]
pub fn modes<'py>(py: Python<'py>, given: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let args: ModesArgs = settings(py, "modes", &given)?;
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
#[pyo3(signature = (given, progress=None))]
pub fn poincare<'py>(py: Python<'py>, given: Bound<'py, PyDict>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use cmd::poincare::summary::ClassRow;
    let args: PoincareArgs = settings(py, "poincare", &given)?;
    let (cfg, grid, ic) = cmd::poincare::validated(&args).map_err(|e| cli_error(py, &e))?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = pool(py, threads)?;
    // Stopped between belt speeds: the speeds not started are left out (and
    // the call raises KeyboardInterrupt).
    let (results, wall_s) = work::run(py, progress.as_ref(), "poincare", "belt speeds", |c: &Control| {
        c.set(0, grid.len() as u64);
        cmd::poincare::analyse_grid(&pool, &cfg, &grid, &c.stop, &|| c.tick())
    })?;
    let section = cmd::poincare::section_rows(&results);
    let classes: Vec<ClassRow> = results.iter().map(ClassRow).collect();
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
#[pyo3(signature = (given, progress=None))]
pub fn sweep<'py>(py: Python<'py>, given: Bound<'py, PyDict>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use analyses::sweep::run::RunRow;
    use cmd::sweep::{
        store::{Manifest, missing},
        summary::summary_of,
    };
    let args: SweepArgs = settings(py, "sweep", &given)?;
    let (spec, shard, threads) = cmd::sweep::plan(&args).map_err(|e| cli_error(py, &e))?;
    if let Some(s) = &spec.scenario {
        warn(py, cmd::scenario::board_tables_note(s, "a sweep (the firmware in-process)"))?;
    }
    let mut todo = shard.indices(&spec);
    if let Some(limit) = args.limit {
        todo.truncate(limit);
    }
    let pool = pool(py, threads)?;
    let (rows, ran) = work::run(py, progress.as_ref(), "sweep", "runs", |c: &Control| {
        c.set(0, todo.len() as u64);
        let rows = std::sync::Mutex::new(Vec::with_capacity(todo.len()));
        let sink = |row: RunRow| {
            rows.lock().unwrap_or_else(|p| p.into_inner()).push(row);
            c.tick();
            Ok(())
        };
        let ran = cmd::sweep::run_all(&pool, &spec, &todo, threads, &c.stop, &sink);
        (rows.into_inner().unwrap_or_else(|p| p.into_inner()), ran)
    })?;
    let (_, timing) = ran.map_err(|e| cli_error(py, &e))?;
    let mut rows = rows;
    rows.sort_by_key(|r| r.index);
    let manifest = Manifest { spec, shard };
    let n_missing = missing(&manifest, &rows).len();
    let results = analyses::sweep::summary::results(&manifest.spec, &rows, n_missing);
    // The cells over their seeds (always: one seed gives fractions of 0 or 1 out of 1).
    let cells = analyses::sweep::cells::of(&manifest.spec, &rows);
    let several = (manifest.spec.seeds > 1).then_some(cells.as_slice());
    let summary = summary_of(&manifest, results, n_missing, Some(timing), 0, false, Vec::new()).with_cells(several);
    let (message, code) = failure_of(None, args.strict.strict, &summary.results.validity);
    Outcome::new(py, "sweep", to_py(py, &summary)?)?
        .table("sweep", rows_to_py(py, &rows)?)?
        .table("cells", rows_to_py(py, &cells)?)?
        .validity(&summary.results.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.zmax`: `sil-host zmax`.
#[pyfunction]
#[pyo3(signature = (given, progress=None))]
pub fn zmax<'py>(py: Python<'py>, given: Bound<'py, PyDict>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    let args: ZmaxArgs = settings(py, "zmax", &given)?;
    let started = Instant::now();
    let plan = cmd::zmax::plan(&args).map_err(|e| cli_error(py, &e))?;
    warn(py, cmd::scenario::board_tables_note(&plan.base, "zmax (the firmware in-process, or the ideal law)"))?;
    let total = plan.max_trials(args.tol);
    let searches = work::run(py, progress.as_ref(), "zmax", "trials", |c: &Control| {
        c.set(0, total);
        cmd::zmax::run_searches(&plan, args.tol, &c.stop, &|n| {
            c.done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        })
    })?;
    let searches = searches.map_err(|e| cli_error(py, &CliError::from(e)))?;
    let n_nominal = plan.jobs.len();
    let summary = cmd::zmax::summary(&args, plan, &searches, started.elapsed().as_secs_f64());
    let traces = PyDict::new(py);
    for s in searches.iter().take(n_nominal) {
        traces.set_item(s.combination.stem(), rows_to_py(py, &s.limit_trace)?)?;
    }
    let (message, code) = failure_of(None, args.strict.strict, &summary.validity);
    Outcome::new(py, "zmax", to_py(py, &summary)?)?
        .table("zmax", rows_to_py(py, &summary.results)?)?
        .table("trials", rows_to_py(py, &cmd::zmax::trial_rows(&summary))?)?
        .table("zmax_seeds", rows_to_py(py, &summary.seeds)?)?
        .extra("limit_traces", traces.into_any())?
        .validity(&summary.validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// Keeps the frames of a closed-loop run (`rig::run_loop` hands the records
/// back), reports its progress, stops on Ctrl-C; the validity, ledger and page
/// are [`Gather`]'s, as `sil-host run`'s.
struct Progress<'a> {
    control: &'a Control,
    /// Every period's frame and answer (`frames.csv` of `sil-host run`).
    frames: KeepFrames,
}

impl RunSink for Progress<'_> {
    fn period(&mut self, k: usize, n: usize) -> bool {
        if k.is_multiple_of(100) || k == n {
            self.control.set(k as u64, n as u64);
        }
        !self.control.stopped()
    }

    fn answer(&mut self, frame: &shared::wire::SensorFrame, truth: &shared::wire::GroundTruth, exchange: &rig::Exchange) {
        self.frames.answer(frame, truth, exchange);
    }
}

/// `painleve.run`: `sil-host run --in-process` (the firmware step linked in,
/// lockstep): the SIL run of `rig::in_process`, its trace kept in memory.
#[pyfunction]
#[pyo3(signature = (given, progress=None))]
pub fn run<'py>(py: Python<'py>, given: Bound<'py, PyDict>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    use rig::{in_process::InProcessLink, stats::RunStats, summary::RunSummary};
    let given = given.copy()?;
    given.set_item("in_process", true)?;
    let args: RunArgs = settings(py, "run", &given)?;
    let (setup, link) = cmd::run::prepare(&args).map_err(|e| cli_error(py, &e))?;
    let scenario = &setup.scenario().clone();
    warn(py, cmd::scenario::board_tables_note(scenario, link.without_board()))?;
    let mut link = InProcessLink::new(&setup).map_err(|e| cli_error(py, &CliError::from(e)))?;
    // The page, as `sil-host run` gathers it (its records and events as they come).
    let page = (!args.no_page).then(|| TracePage::new(PageInfo::closed_loop(setup.scenario(), link.transport())));
    let link_in_loop = &mut link;
    // The run moves to the worker (its plant is `Send`, not `Sync`).
    let (records, failure, (validity, ledger), wall_s, (page, frames)) =
        work::run(py, progress.as_ref(), "run", "periods", move |c: &Control| {
            c.set(0, setup.scenario().timing.periods());
            let mut observer = Gather::new(Progress { control: c, frames: KeepFrames::default() }, page);
            let started = Instant::now();
            let (records, failure) = rig::run_loop(&setup, link_in_loop, &mut observer);
            let wall_s = started.elapsed().as_secs_f64();
            (records, failure, (observer.validity, observer.ledger), wall_s, (observer.page.map(TracePage::html), observer.sink.frames.0))
        })?;
    let stats = RunStats::of(&records);
    let summary = RunSummary {
        firmware_announcement: link.announcement().cloned(),
        ledger,
        ..RunSummary::from_stats(scenario, &stats, failure.as_ref(), link.transport(), "lockstep", wall_s, validity)
    };
    let (message, code) = failure_of(failure.map(CliError::from), args.strict.strict, &validity);
    let (trace_py, frames_py) = (columns_to_py(py, &records), columns_to_py(py, &frames));
    let recording =
        Recording::closed_loop(arm_view::ArmGeometry::of(&rig::setup::plant_params(scenario)), scenario.law_in_words(), records, frames);
    Outcome::new(py, "run", to_py(py, &summary)?)?
        .table("trace", trace_py)?
        .table("frames", frames_py)?
        .extra("scenario", to_py(py, scenario)?)?
        .extra("page", page.into_pyobject(py)?.into_any())?
        .extra("recording", Py::new(py, recording)?.into_any().into_bound(py))?
        .validity(&validity)?
        .failure(message, code)
        .map(Outcome::done)
}

/// `painleve.sensitivity`: `sil-host sensitivity`.
#[pyfunction]
#[pyo3(signature = (given, progress=None))]
pub fn sensitivity<'py>(py: Python<'py>, given: Bound<'py, PyDict>, progress: Option<Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyDict>> {
    let args: SensitivityArgs = settings(py, "sensitivity", &given)?;
    let (base, threads) = cmd::sensitivity::prepare(&args).map_err(|e| cli_error(py, &e))?;
    warn(py, cmd::scenario::board_tables_note(&base, "the sensitivity study (the firmware in-process)"))?;
    let pool = pool(py, threads)?;
    let (size, seeds) = (args.size, args.seeds);
    let (study, wall_s) = work::run(py, progress.as_ref(), "sensitivity", "jobs", |c: &Control| {
        let started = Instant::now();
        let study = pool.install(|| analyses::sensitivity::run(&base, size, seeds, &c.stop, &|done, total| c.set(done, total)));
        (study, started.elapsed().as_secs_f64())
    })?;
    let study = study.map_err(|e| cli_error(py, &CliError::from(e)))?;
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
