//! The brute-force bifurcation diagram over `(v_belt, mu)` (docs/model.md
//! experiments 3 and 7), computed by [`analyses::sweep`]: the settings' check
//! and plan, the loop over the runs both fronts run ([`run_all`]), the sweep's
//! folder ([`store`]: `sweep.json`, the `runs.csv` journal, resume and merge) and
//! its summary ([`summary`]).

use std::{
    sync::{
        Mutex,
        atomic::{AtomicBool, AtomicU64, Ordering},
    },
    time::Instant,
};

use rayon::prelude::*;

use crate::{error::Error, settings::SweepArgs};
use analyses::sweep::{
    Axis, Shard, SweepController, SweepSpec,
    run::{self, RunRow},
};
use plant::initial::PaperX0;

pub mod store;
pub mod summary;
use summary::{Timing, cpu_seconds};

/// The keys a sweep sets per run or by its flags: `--set` of one of them is refused.
const RUN_KEYS: [(&str, &str); 12] = [
    ("plant.mu", "--mu"),
    ("plant.v_belt", "--v-belt"),
    ("plant.x0", "--ics"),
    ("plant.impact_law", "--impact-law"),
    ("plant.e_n", "--e-n"),
    ("plant.rtol", "--rtol"),
    ("plant.atol", "--atol"),
    ("plant.iwc", "--iwc"),
    ("plant.singular", "--singular"),
    ("controller.kind", "--controller"),
    ("controller.mu_hat", "the sweep (mu_hat = each run's mu)"),
    ("timing.duration_s", "--transient and --record"),
];

fn parse_axis(flag: &str, s: &crate::settings::NumberList, step: f64) -> Result<Axis, Error> {
    let axis = match s.0.as_slice() {
        [a] => Axis { start: *a, stop: *a, step },
        [a, b] => Axis { start: *a, stop: *b, step },
        _ => return Err(Error::bad_input(format!("--{flag} expects MIN,MAX or one value (finite numbers), got `{s}`"))),
    };
    Ok(axis)
}

fn paper_ics(list: &[String]) -> Result<Vec<PaperX0>, Error> {
    let mut out = Vec::new();
    for item in list.iter().map(|s| s.trim()).filter(|s| !matches!(*s, "none" | "")) {
        let x =
            PaperX0::parse(item).ok_or_else(|| Error::bad_input(format!("--ics: unknown initial condition `{item}` (a, d, u or none)")))?;
        if !out.contains(&x) {
            out.push(x);
        }
    }
    Ok(out)
}

/// The spec of `sil-host sweep`'s arguments.
///
/// # Errors
/// [`crate::error::Error::Analysis`] or [`crate::error::Error::Analysis`] (exit 2).
pub fn spec_of(args: &SweepArgs) -> Result<SweepSpec, Error> {
    use rig::{overrides, scenario::ScenarioError};
    overrides::check_keys(&args.set, &RUN_KEYS).map_err(ScenarioError::from)?;
    let (scenario, params) = match args.controller {
        SweepController::None => {
            if args.scenario.is_some() {
                return Err(Error::bad_input("--scenario is for closed-loop sweeps (--controller hybrid or pid)"));
            }
            let p = shared::Params::<f64>::paper();
            (None, crate::arm::arm_params(&args.set, "sweep (open loop)", &[], p.mu, p.v_belt)?)
        }
        _ => {
            crate::scenario::refuse_board_overrides(&args.set, "a sweep (the firmware in-process)")?;
            let s = crate::scenario::read_scenario(args.scenario.as_deref(), &args.set)?;
            let params = s.plant.params();
            (Some(s), params)
        }
    };
    let spec = SweepSpec {
        format: analyses::sweep::FORMAT,
        mu: parse_axis("mu", &args.mu, args.mu_step)?,
        v_belt: parse_axis("v-belt", &args.v_belt, args.v_belt_step)?,
        iwc_rules: dedup(args.iwc.iter().copied()),
        impact_laws: dedup(args.impact_law.iter().copied()),
        e_n: {
            let mut v: Vec<f64> = Vec::new();
            for e in &args.e_n {
                if !v.contains(e) {
                    v.push(*e);
                }
            }
            v
        },
        paper_ics: paper_ics(&args.ics)?,
        random_ics: args.random_ics,
        seed: args.seed,
        transient_s: args.transient,
        record_s: args.record,
        controller: args.controller,
        ideal: args.ideal,
        scenario,
        threshold: args.threshold,
        rtol: args.rtol,
        atol: args.atol,
        params,
        mu_hat_factor: 1.0,
        singular: args.singular,
        seeds: args.ensemble.seeds,
        jitter: args.ensemble.jitter(),
    };
    spec.validate().map_err(Error::bad_input)?;
    Ok(spec)
}

/// Checks `sil-host sweep`'s arguments: the sweep's spec ([`spec_of`]), the
/// shard of it to compute (`--shard`, all by default) and the worker threads
/// (`--threads`, one per core by default).
///
/// # Errors
/// [`crate::error::Error::Analysis`] or [`crate::error::Error::Analysis`] (exit 2).
pub fn plan(args: &SweepArgs) -> Result<(SweepSpec, Shard, usize), Error> {
    let spec = spec_of(args)?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).map_err(Error::bad_input)?,
        None => Shard::ALL,
    };
    if args.threads == Some(0) {
        return Err(Error::bad_input("--threads must be >= 1"));
    }
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    Ok((spec, shard, threads))
}

fn dedup<T: PartialEq>(it: impl Iterator<Item = T>) -> Vec<T> {
    let mut v = Vec::new();
    for x in it {
        if !v.contains(&x) {
            v.push(x);
        }
    }
    v
}

/// Runs the runs `todo` (indices into `spec`) on `pool`, handing each finished
/// row to `sink` (in completion order, from the pool's threads). A run not
/// started when `stop` is set is left out, and a run stopped part way gives no
/// row; when `sink` fails, `stop` is set and its first error is returned. Returns
/// the runs finished and this invocation's [`Timing`] on `threads` threads.
///
/// # Errors
/// The first error of `sink`.
pub fn run_all(
    pool: &rayon::ThreadPool,
    spec: &SweepSpec,
    todo: &[usize],
    threads: usize,
    stop: &AtomicBool,
    sink: &(dyn Fn(RunRow) -> Result<(), Error> + Sync),
) -> Result<(usize, Timing), Error> {
    let ics = spec.initial_conditions();
    let failure: Mutex<Option<Error>> = Mutex::new(None);
    let done = AtomicU64::new(0);
    let started = Instant::now();
    let cpu_start = cpu_seconds();
    pool.install(|| {
        todo.par_iter().with_max_len(1).for_each(|&index| {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            let key = spec.run_at(index);
            if let Some(row) = run::simulate(spec, &key, &ics[key.i_ic], stop) {
                if let Err(e) = sink(row) {
                    stop.store(true, Ordering::Relaxed);
                    failure.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
                    return;
                }
                done.fetch_add(1, Ordering::Relaxed);
            }
        });
    });
    let (wall_s, cpu_s) = (started.elapsed().as_secs_f64(), cpu_seconds() - cpu_start);
    if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let computed = done.load(Ordering::Relaxed) as usize;
    Ok((computed, Timing::of(spec, computed, threads, wall_s, cpu_s)))
}
