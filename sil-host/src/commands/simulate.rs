//! `sil-host simulate`: an open-loop run (`u = 0`) of the arm on the belt.
//!
//! Writes under `--out`: `trace.csv` (one row per `--sample-dt`), `events.csv`
//! (every event at its located time), `trace.svg` (`z_t`, `z_n`, `f_n` and the
//! contact mode against time) and `summary.json`. If the simulation fails part
//! way, everything up to the failure is still written (with the error in the
//! summary) and the command exits with code 1.

use std::{io::Write, time::Instant};

use serde::Serialize;
use shared::Params;

use crate::{
    cli::SimulateArgs,
    error::CliError,
    output::{OutputSet, io_err, progress_bar, write_csv},
    plot::{self, Panel, Series, colors},
};
use plant::initial::{self, PaperX0, ProjectionInfo};
use plant::{Counters, Plant, PlantEvent, SimConfig, SimError};

/// One row of `trace.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct TraceRow {
    /// Time, s.
    pub t: f64,
    /// `theta1`, rad.
    pub theta1: f64,
    /// `theta1_dot`, rad/s.
    pub theta1_dot: f64,
    /// `theta2`, rad.
    pub theta2: f64,
    /// `theta2_dot`, rad/s.
    pub theta2_dot: f64,
    /// Tip tangential position `z_t`, m.
    pub z_t: f64,
    /// Tip normal position `z_n`, m.
    pub z_n: f64,
    /// `z_t_dot`, m/s.
    pub z_t_dot: f64,
    /// `z_n_dot`, m/s.
    pub z_n_dot: f64,
    /// Relative tangential velocity `z_r_dot = z_t_dot - v_belt`, m/s.
    pub z_r_dot: f64,
    /// Tangential contact force `f_t`, N.
    pub f_t: f64,
    /// Normal contact force `f_n`, N.
    pub f_n: f64,
    /// Contact mode (`flight`, `sliding`, `sticking`).
    pub mode: &'static str,
    /// Mechanical energy (kinetic + gravity + spring), J.
    pub energy: f64,
}

/// One row of `events.csv`.
#[derive(Debug, Clone, Serialize)]
struct EventRow {
    t: f64,
    kind: &'static str,
    mode_after: &'static str,
    v_n_before: f64,
    v_n_after: f64,
    v_r_before: f64,
    v_r_after: f64,
    impulse_t: f64,
    impulse_n: f64,
    energy_change: f64,
    contact_work: f64,
    resolution: String,
}

impl From<&PlantEvent> for EventRow {
    fn from(e: &PlantEvent) -> Self {
        Self {
            t: e.t,
            kind: e.kind.name(),
            mode_after: e.mode_after.name(),
            v_n_before: e.v_n_before,
            v_n_after: e.v_n_after,
            v_r_before: e.v_r_before,
            v_r_after: e.v_r_after,
            impulse_t: e.impulse[0],
            impulse_n: e.impulse[1],
            energy_change: e.energy_change,
            contact_work: e.contact_work,
            resolution: e
                .resolution
                .map(|r| serde_json::to_value(r).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default())
                .unwrap_or_default(),
        }
    }
}

/// The initial condition as resolved.
#[derive(Debug, Clone, Serialize)]
pub struct InitialCondition {
    /// `x0a`, `x0d`, `x0u` or `custom`.
    pub name: String,
    /// As given: `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and deg/s.
    pub given_deg: [f64; 4],
    /// Where the tip sat relative to the belt and whether it was projected onto it.
    pub projection: ProjectionInfo,
    /// After projection: `[theta1, theta1_dot, theta2, theta2_dot]`, degrees and deg/s.
    pub used_deg: [f64; 4],
    /// Contact mode chosen at t = 0 (after any initial impact).
    pub initial_mode: &'static str,
    /// Events at t = 0 while the initial mode was chosen (e.g. an impact without collision).
    pub startup_events: Vec<&'static str>,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// `ok`, or `failed` with `error`.
    pub status: &'static str,
    /// The error, when the run failed part way.
    pub error: Option<String>,
    /// Parameters used.
    pub params: Params<f64>,
    /// Simulator settings used.
    pub sim: SimConfig,
    /// The initial condition.
    pub initial_condition: InitialCondition,
    /// Requested simulated time, s.
    pub duration_s: f64,
    /// Simulated time reached, s.
    pub simulated_s: f64,
    /// Lift-offs.
    pub lift_offs: u64,
    /// Touchdowns (impacts at touchdown).
    pub touchdowns: u64,
    /// Impacts without collision.
    pub impacts_without_collision: u64,
    /// Sticking phases.
    pub stick_phases: u64,
    /// All event counters.
    pub counters: Counters,
    /// Final state `[theta1, theta1_dot, theta2, theta2_dot]`, rad and rad/s.
    pub final_state: [f64; 4],
    /// Final tip position `[z_t, z_n]`, m.
    pub final_tip: [f64; 2],
    /// Final contact mode.
    pub final_mode: &'static str,
    /// Wall-clock time of the simulation (without writing files), s.
    pub wall_s: f64,
    /// Simulated seconds per wall second.
    pub realtime_factor: f64,
    /// Files written.
    pub files: Vec<String>,
}

/// The initial condition of `--x0` or, when given, `--x0-deg`: its name and
/// `[theta1, theta1_dot, theta2, theta2_dot]` in degrees and degrees per second.
///
/// # Errors
/// [`CliError::BadInput`] for a malformed `--x0-deg`.
pub(crate) fn chosen_initial_condition(x0: PaperX0, x0_deg: Option<&str>) -> Result<(String, [f64; 4]), CliError> {
    Ok(match x0_deg {
        Some(s) => ("custom".to_string(), parse_x0_deg(s)?),
        None => {
            let ic = x0.condition();
            (ic.name.to_string(), ic.deg)
        }
    })
}

/// Parses `--x0-deg th1,th1dot,th2,th2dot`.
pub(crate) fn parse_x0_deg(s: &str) -> Result<[f64; 4], CliError> {
    let bad = || CliError::BadInput(format!("--x0-deg expects four finite numbers th1,th1dot,th2,th2dot (degrees, deg/s), got `{s}`"));
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    match v.as_slice() {
        [a, b, c, d] if v.iter().all(|x| x.is_finite()) => Ok([*a, *b, *c, *d]),
        _ => Err(bad()),
    }
}

/// Checks the run-length options.
fn check_times(duration: f64, sample_dt: f64) -> Result<usize, CliError> {
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

fn trace_row(plant: &Plant, f: [f64; 2]) -> TraceRow {
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

/// Runs `sil-host simulate`.
///
/// # Errors
/// [`CliError::BadInput`]/[`CliError::Param`]/[`CliError::Sim`] (exit 2) for bad
/// options or initial conditions, before anything is written; [`CliError::Sim`]
/// (exit 1) when the simulation fails part way (outputs up to then are written);
/// [`CliError::Io`]/[`CliError::Plot`] when writing fails.
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    // Validate everything before touching the output folder.
    let params = Params::new(args.mu, args.v_belt)?;
    let sim = SimConfig { rtol: args.rtol, atol: args.atol, impact_law: args.impact_law, e_n: args.e_n, ..SimConfig::default() };
    sim.validate()?;
    let steps = check_times(args.duration, args.sample_dt)?;
    let (name, given_deg) = chosen_initial_condition(args.x0, args.x0_deg.as_deref())?;
    let x0 = initial::deg_to_state(given_deg);
    let projection = initial::describe_projection(&params, x0);
    let mut plant = Plant::new(params, sim, x0, 0.0, [0.0, 0.0])?;
    let initial_condition = InitialCondition {
        name,
        given_deg,
        projection,
        used_deg: plant.state().map(f64::to_degrees),
        initial_mode: plant.mode().name(),
        startup_events: plant.startup_events().iter().map(|e| e.kind.name()).collect(),
    };

    let mut out = OutputSet::new(&args.output.out)?;
    let progress = progress_bar(steps as u64, "simulating", "samples", args.output.json);
    let mut trace = Vec::with_capacity(steps + 1);
    let mut events: Vec<PlantEvent> = plant.startup_events().to_vec();
    trace.push(trace_row(&plant, plant.contact_force([0.0, 0.0])));
    let started = Instant::now();
    let mut failure: Option<SimError> = None;
    for k in 0..steps {
        // Advance to an exact multiple of the sample period (no accumulated drift).
        let target = (k + 1) as f64 * args.sample_dt;
        match plant.advance([0.0, 0.0], target - plant.time()) {
            Ok(report) => {
                events.extend_from_slice(&report.events);
                trace.push(trace_row(&plant, report.f));
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
        if k % 256 == 0 {
            progress.set_position(k as u64);
        }
    }
    let wall_s = started.elapsed().as_secs_f64();
    progress.finish_and_clear();

    write_csv(&mut out, "trace.csv", &trace)?;
    // events.csv
    let (tmp, w) = out.create("events.csv")?;
    let mut csv_w = csv::Writer::from_writer(w);
    if events.is_empty() {
        csv_w
            .write_record([
                "t",
                "kind",
                "mode_after",
                "v_n_before",
                "v_n_after",
                "v_r_before",
                "v_r_after",
                "impulse_t",
                "impulse_n",
                "energy_change",
                "contact_work",
                "resolution",
            ])
            .map_err(|e| CliError::Io { path: tmp.clone(), source: e.into() })?;
    }
    for e in &events {
        csv_w.serialize(EventRow::from(e)).map_err(|err| CliError::Io { path: tmp.clone(), source: err.into() })?;
    }
    csv_w.flush().map_err(io_err(&tmp))?;
    // trace.svg
    let svg = out.stage("trace.svg");
    draw_trace(&svg, &params, &initial_condition.name, &trace)?;

    let counters = *plant.counters();
    let simulated_s = plant.time();
    let summary = Summary {
        status: if failure.is_some() { "failed" } else { "ok" },
        error: failure.as_ref().map(|e| e.to_string()),
        params,
        sim,
        initial_condition,
        duration_s: args.duration,
        simulated_s,
        lift_offs: counters.lift_offs,
        touchdowns: counters.touchdowns,
        impacts_without_collision: counters.impacts_without_collision,
        stick_phases: counters.stick_phases,
        counters,
        final_state: plant.state(),
        final_tip: [plant.tip()[0], plant.tip()[1]],
        final_mode: plant.mode().name(),
        wall_s,
        realtime_factor: simulated_s / wall_s.max(1e-9),
        files: ["trace.csv", "events.csv", "trace.svg", "summary.json"].iter().map(|f| out.path(f).display().to_string()).collect(),
    };
    let json = out.write_json("summary.json", &summary)?;
    out.commit()?;

    if args.output.json {
        println!("{json}");
    } else {
        print_human(&summary, events.len());
    }
    match failure {
        Some(e) => Err(CliError::Sim(e)),
        None => Ok(()),
    }
}

fn print_human(s: &Summary, n_events: usize) {
    let ic = &s.initial_condition;
    let mut o = std::io::stdout().lock();
    let _ = writeln!(
        o,
        "open-loop simulation, u = 0: mu = {}, v_belt = {} m/s, impact law {} (e_n = {})",
        s.params.mu,
        s.params.v_belt,
        s.sim.impact_law.name(),
        s.sim.e_n
    );
    let _ = writeln!(
        o,
        "initial condition {} = [{:.2} deg, {:.2} deg/s, {:.2} deg, {:.2} deg/s] (elbow {})",
        ic.name,
        ic.given_deg[0],
        ic.given_deg[1],
        ic.given_deg[2],
        ic.given_deg[3],
        ic.projection.branch.name()
    );
    if ic.projection.projected {
        let _ = writeln!(
            o,
            "  tip was {:.4} mm {} the belt: projected onto it at the same z_t = {:.5} m and elbow branch -> [{:.4} deg, {:.4} deg]",
            ic.projection.height_above_belt.abs() * 1e3,
            if ic.projection.height_above_belt < 0.0 { "inside" } else { "on" },
            ic.projection.tip_given[0],
            ic.used_deg[0],
            ic.used_deg[2]
        );
    }
    let _ = writeln!(
        o,
        "  initial mode: {}{}",
        ic.initial_mode,
        if ic.startup_events.is_empty() { String::new() } else { format!(" (after {} at t = 0)", ic.startup_events.join(", ")) }
    );
    let _ = writeln!(
        o,
        "simulated {:.3} s of {:.3} s in {:.3} s wall ({:.0}x real time)",
        s.simulated_s, s.duration_s, s.wall_s, s.realtime_factor
    );
    let c = &s.counters;
    let _ = writeln!(
        o,
        "events: {n_events} | lift-offs {} | touchdowns {} | impacts without collision {} | stick phases {} | stick-to-slip {} | slip reversals {} | Zeno stops {} | energy-creating impacts {}",
        c.lift_offs,
        c.touchdowns,
        c.impacts_without_collision,
        c.stick_phases,
        c.stick_to_slip,
        c.slip_reversals,
        c.zeno_stops,
        c.energy_gains
    );
    let x = s.final_state;
    let _ = writeln!(
        o,
        "final: mode {}, theta1 = {:.3} deg, theta2 = {:.3} deg, tip = ({:.5}, {:.5}) m",
        s.final_mode,
        x[0].to_degrees(),
        x[2].to_degrees(),
        s.final_tip[0],
        s.final_tip[1]
    );
    if let Some(e) = &s.error {
        let _ = writeln!(o, "FAILED: {e}");
    }
    let _ = writeln!(o, "wrote {}", s.files.join(", "));
}

fn draw_trace(path: &std::path::Path, params: &Params<f64>, name: &str, trace: &[TraceRow]) -> Result<(), CliError> {
    let t_end = trace.last().map_or(1.0, |r| r.t).max(1e-9);
    let col = |f: fn(&TraceRow) -> f64| trace.iter().map(|r| (r.t, f(r))).collect::<Vec<_>>();
    let belt = -params.h;
    let panels = [
        Panel {
            y_label: "z_t (m)",
            series: vec![Series { label: "z_t", points: col(|r| r.z_t), color: colors::BLUE, step: false }],
            y_range: None,
        },
        Panel {
            y_label: "z_n (m)",
            series: vec![
                Series { label: "z_n", points: col(|r| r.z_n), color: colors::ORANGE, step: false },
                Series { label: "belt -H", points: vec![(0.0, belt), (t_end, belt)], color: colors::GREY, step: false },
            ],
            y_range: None,
        },
        Panel {
            y_label: "f_n (N)",
            series: vec![Series { label: "f_n", points: col(|r| r.f_n), color: colors::GREEN, step: false }],
            y_range: None,
        },
        plot::mode_panel(trace.iter().map(|r| (r.t, r.mode))),
    ];
    let title = format!("open loop from {name}: mu = {}, v_belt = {} m/s", params.mu, params.v_belt);
    plot::time_panels(path, &title, (0.0, t_end), &panels)
}
