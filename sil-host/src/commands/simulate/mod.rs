//! `sil-host simulate`: an open-loop run (`u = 0`) of the arm on the belt.
//!
//! Writes under `--out`: `trace.csv` (one row per `--sample-dt`), `events.csv`
//! (every event at its located time), `trace.svg` (`z_t`, `z_n`, `f_n` and the
//! contact mode against time) and `summary.json`; with `--format arrow` the two
//! tables are `trace.arrow` and `events.arrow` (Arrow IPC, the same columns). If the simulation fails part
//! way, everything up to the failure is still written (with the error in the
//! summary) and the command exits with code 1.

use std::time::Instant;

use crate::commands::Done;
use crate::{
    cli::SimulateArgs,
    error::CliError,
    output::{OutputSet, progress_bar},
    table_out::TableOut,
};
use plant::initial::{self, PaperX0};
use plant::{Plant, SimConfig, SimError};

pub mod figures;
pub mod summary;
use figures::*;
use summary::*;

/// The initial condition of `--x0` or, when given, `--x0-deg`: its name and
/// `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and degrees per second.
///
/// # Errors
/// [`CliError::BadInput`] for a malformed `--x0-deg`.
pub fn chosen_initial_condition(x0: PaperX0, x0_deg: Option<&str>) -> Result<(String, [f64; 4]), CliError> {
    Ok(match x0_deg {
        Some(s) => ("custom".to_string(), parse_x0_deg(s)?),
        None => {
            let ic = x0.condition();
            (ic.name.to_string(), ic.deg)
        }
    })
}

/// Parses `--x0-deg th1,th1dot,th2,th2dot`.
///
/// # Errors
/// [`CliError::BadInput`] unless it is four finite numbers.
pub fn parse_x0_deg(s: &str) -> Result<[f64; 4], CliError> {
    let bad = || CliError::BadInput(format!("--x0-deg expects four finite numbers th1,th1dot,th2,th2dot (degrees, deg/s), got `{s}`"));
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    match v.as_slice() {
        [a, b, c, d] if v.iter().all(|x| x.is_finite()) => Ok([*a, *b, *c, *d]),
        _ => Err(bad()),
    }
}

/// Checks the run-length options (`--duration`, `--sample-dt`) and returns the
/// number of samples after the first, `round(duration / sample_dt)` (at least 1).
///
/// # Errors
/// [`CliError::BadInput`] naming the option.
pub fn check_times(duration: f64, sample_dt: f64) -> Result<usize, CliError> {
    if !(duration.is_finite() && duration > 0.0 && duration <= 1e6) {
        return Err(CliError::BadInput(format!("--duration must be in (0, 1e6] s, got {duration}")));
    }
    if !(sample_dt.is_finite() && sample_dt > 0.0 && sample_dt <= duration) {
        return Err(CliError::BadInput(format!("--sample-dt must be in (0, duration] s, got {sample_dt}")));
    }
    let n = (duration / sample_dt).round();
    if n > 5e7 {
        return Err(CliError::BadInput(format!("--duration / --sample-dt gives {n} trace rows (at most 5e7); raise --sample-dt")));
    }
    Ok((n as usize).max(1))
}

/// The `trace.csv` row of the plant's current state, with the contact force `f`
/// (`[f_t, f_n]`, N) of the step that led there.
pub fn trace_row(plant: &Plant, f: [f64; 2]) -> TraceRow {
    let x = plant.state();
    let z = plant.tip();
    let v = plant.tip_velocity();
    TraceRow {
        t: plant.time(),
        theta1: x[0],
        theta1_dot: x[1],
        theta2: x[2],
        theta2_dot: x[3],
        z_t: z[0],
        z_n: z[1],
        z_t_dot: v[0],
        z_n_dot: v[1],
        z_r_dot: v[0] - plant.arm().params.v_belt,
        f_t: f[0],
        f_n: f[1],
        mode: plant.mode().name(),
        energy: plant.energy(),
    }
}

/// A simulation checked and set up, before anything is written: what
/// [`prepare`] returns.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The arm's parameters (paper Table I with `--set`, `--mu`, `--v-belt`).
    pub params: shared::Params<f64>,
    /// The simulator's settings.
    pub sim: SimConfig,
    /// Samples after the first ([`check_times`]).
    pub steps: usize,
    /// The initial condition as given and as used.
    pub initial_condition: InitialCondition,
    /// The plant at `t = 0` (projected onto the belt, initial mode chosen).
    pub plant: Plant,
}

/// Checks `sil-host simulate`'s options and sets the plant up at `t = 0`.
///
/// # Errors
/// [`CliError::BadInput`]/[`CliError::Param`]/[`CliError::Sim`]/[`CliError::Scenario`]
/// (exit 2) for bad options or initial conditions.
pub fn prepare(args: &SimulateArgs) -> Result<Prepared, CliError> {
    let params = super::arm_params(&args.set, "simulate", &[], args.mu, args.v_belt)?;
    let sim = SimConfig {
        rtol: args.rtol,
        atol: args.atol,
        impact_law: args.impact_law,
        e_n: args.e_n,
        iwc: args.iwc,
        max_step: args.max_step,
        singular: args.singular,
        ..SimConfig::default()
    };
    sim.validate()?;
    let steps = check_times(args.duration, args.sample_dt)?;
    let (name, given_deg) = chosen_initial_condition(args.x0, args.x0_deg.as_deref())?;
    let x0 = initial::deg_to_state(given_deg);
    let projection = initial::describe_projection(&params, x0);
    let plant = Plant::new(params, sim, x0, 0.0, [0.0, 0.0])?;
    let initial_condition = InitialCondition {
        name,
        given_deg,
        projection,
        used_deg: plant.state().map(f64::to_degrees),
        initial_mode: plant.mode().name(),
        startup_events: plant.startup_events().iter().map(|e| e.kind.name()).collect(),
    };
    Ok(Prepared { params, sim, steps, initial_condition, plant })
}

/// Advances the open loop (`u = 0`) to sample `k + 1`, at exactly
/// `(k + 1) sample_dt` s (no accumulated drift): one row of `trace.csv`.
///
/// # Errors
/// The plant's [`SimError`] when the step fails.
pub fn sample_step(plant: &mut Plant, k: usize, sample_dt: f64) -> Result<plant::StepReport, SimError> {
    let target = (k + 1) as f64 * sample_dt;
    plant.advance(&plant::Hold([0.0, 0.0]), target - plant.time(), &mut plant::NoObserver)
}

/// `summary.json` of a simulation that ended with `plant` (after `failure`, if it
/// failed), which took `wall_s` s and wrote `files` with `events` events.
pub fn summary(
    args: &SimulateArgs,
    prepared: (shared::Params<f64>, SimConfig, InitialCondition),
    plant: &Plant,
    failure: Option<&SimError>,
    wall_s: f64,
    files: Vec<String>,
    events: usize,
) -> Summary {
    let (params, sim, initial_condition) = prepared;
    let counters = *plant.counters();
    let simulated_s = plant.time();
    Summary {
        status: if failure.is_some() { "failed" } else { "ok" },
        error: failure.map(|e| e.to_string()),
        params,
        sim,
        initial_condition,
        duration_s: args.duration,
        simulated_s,
        lift_offs: counters.lift_offs,
        touchdowns: counters.touchdowns,
        impacts_without_collision: counters.impacts_without_collision,
        stick_phases: counters.stick_phases,
        validity: plant.validity(failure),
        counters,
        final_state: plant.state(),
        final_tip: [plant.tip()[0], plant.tip()[1]],
        final_mode: plant.mode().name(),
        wall_s,
        realtime_factor: simulated_s / wall_s.max(1e-9),
        files,
        events,
    }
}

/// Runs `sil-host simulate`.
///
/// # Errors
/// [`CliError::BadInput`]/[`CliError::Param`]/[`CliError::Sim`] (exit 2) for bad
/// options or initial conditions, before anything is written; [`CliError::Sim`]
/// (exit 1) when the simulation fails part way (outputs up to then are written);
/// [`CliError::Io`]/[`CliError::Plot`] when writing fails.
pub fn execute(args: &SimulateArgs) -> Result<Done<Summary>, CliError> {
    // Validate everything before touching the output folder.
    let Prepared { params, sim, steps, initial_condition, mut plant } = prepare(args)?;

    let mut out = OutputSet::new(&args.output.out)?;
    let progress = progress_bar(steps as u64, "simulating", "samples", args.output.json);
    // Streamed: rows and events go to their files as they come, the figure keeps
    // a decimated copy; nothing grows with the run but the files. CSV rows are
    // formatted and written by a thread of their own (fastcsv::CsvThread) while
    // the simulation goes on; Arrow rows are batched (arrow_table::ArrowFile).
    let mut trace = TableOut::<TraceRow>::create(&mut out, "trace", args.format)?;
    let mut events = TableOut::<EventRow>::create(&mut out, "events", args.format)?;
    let mut curves = TraceCurves::default();
    let mut n_events = plant.startup_events().len();
    events.send(plant.startup_events().iter().map(EventRow::from).collect())?;
    let row = trace_row(&plant, plant.contact_force([0.0, 0.0]));
    curves.push(&row);
    trace.send(vec![row])?;
    // The simulation's own wall time, without writing files: rows wait in a
    // chunk of at most CHUNK samples (bounded memory) while the clock runs.
    const CHUNK: usize = 1024;
    let mut rows: Vec<TraceRow> = Vec::with_capacity(CHUNK);
    let mut new_events: Vec<EventRow> = Vec::new();
    let mut wall = std::time::Duration::ZERO;
    let mut failure: Option<SimError> = None;
    // Ctrl-C or SIGTERM: stop at the next chunk, write what was simulated.
    let stop = crate::cancel::stop_flag();
    let mut stopped = false;
    let mut k = 0;
    while k < steps && failure.is_none() {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            stopped = true;
            break;
        }
        let started = Instant::now();
        let end = steps.min(k + CHUNK);
        while k < end {
            match sample_step(&mut plant, k, args.sample_dt) {
                Ok(report) => {
                    new_events.extend(report.events.iter().map(EventRow::from));
                    rows.push(trace_row(&plant, report.f));
                }
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
            k += 1;
        }
        wall += started.elapsed();
        n_events += new_events.len();
        new_events = events.send(new_events)?;
        for row in &rows {
            curves.push(row);
        }
        rows = trace.send(rows)?;
        progress.set_position(k as u64);
    }
    let wall_s = wall.as_secs_f64();
    progress.finish_and_clear();
    trace.finish()?;
    events.finish()?;
    // trace.svg
    let svg = out.stage("trace.svg");
    draw_trace(&svg, &params, &initial_condition.name, &curves)?;

    let tables = [args.format.file("trace"), args.format.file("events")];
    let files = tables.iter().map(String::as_str).chain(["trace.svg", "summary.json"]).map(|f| out.path(f).display().to_string()).collect();
    let mut summary = summary(args, (params, sim, initial_condition), &plant, failure.as_ref(), wall_s, files, n_events);
    let interrupted = stopped.then(|| {
        format!("simulate stopped by a signal at t = {} s of {} s; the outputs up to then are written", summary.simulated_s, args.duration)
    });
    if let Some(why) = &interrupted {
        summary.status = "stopped";
        summary.error = Some(why.clone());
    }
    out.write_json("summary.json", &summary)?;
    let files = out.commit()?;
    let validity = summary.validity;
    let failure = failure.map(CliError::Sim).or(interrupted.map(CliError::Interrupted));
    Ok(Done { result: summary, files, failure }.strict(args.strict.strict, &validity))
}

/// Runs `sil-host simulate`: [`execute`], then prints the summary (human, or the
/// JSON document with `--json`).
///
/// # Errors
/// As [`execute`]; a simulation that failed part way (after writing).
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let done = execute(args)?;
    if args.output.json {
        crate::commands::print_json(&done.result)?;
    } else {
        print_human(&done.result);
    }
    done.into_result()
}
