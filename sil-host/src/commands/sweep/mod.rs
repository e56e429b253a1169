//! `sil-host sweep` (the brute-force bifurcation diagram, docs/model.md experiments 3
//! and 7) and `sil-host merge` (joining a sharded sweep). See [`crate::sweep`].
//!
//! Files in the sweep's folder: `sweep.json` (the spec and shard, checked on
//! resume), `runs.csv` (the journal, one flushed row per finished run, in
//! completion order), and, written at the end of every invocation from the
//! journal: `sweep.csv` (the same rows by run index: identical for an
//! uninterrupted, a resumed and a merged sweep), `summary.json`, and per impact
//! law and `e_n` the figures `map_<law>_e<e_n>.svg` and `slices_<law>_e<e_n>.svg`.

use std::{
    sync::{
        Mutex,
        atomic::{AtomicU64, Ordering},
    },
    time::Instant,
};

use rayon::prelude::*;

use crate::commands::Done;
use crate::{
    cli::SweepArgs,
    error::CliError,
    folder_lock::FolderLock,
    output::progress_bar,
    sweep::store::{self, Manifest},
};
use analyses::sweep::{
    Axis, Shard, SweepController, SweepSpec,
    run::{self},
};
use plant::initial::PaperX0;

pub mod merge;
pub mod outputs;
use outputs::*;

fn parse_axis(flag: &str, s: &str, step: f64) -> Result<Axis, CliError> {
    let bad = || CliError::BadInput(format!("--{flag} expects MIN,MAX or one value (finite numbers), got `{s}`"));
    let vals: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    let axis = match vals.as_slice() {
        [a] => Axis { start: *a, stop: *a, step },
        [a, b] => Axis { start: *a, stop: *b, step },
        _ => return Err(bad()),
    };
    Ok(axis)
}

fn paper_ics(list: &[String]) -> Result<Vec<PaperX0>, CliError> {
    let mut out = Vec::new();
    for item in list.iter().map(|s| s.trim()).filter(|s| !matches!(*s, "none" | "")) {
        let x = PaperX0::parse(item)
            .ok_or_else(|| CliError::BadInput(format!("--ics: unknown initial condition `{item}` (a, d, u or none)")))?;
        if !out.contains(&x) {
            out.push(x);
        }
    }
    Ok(out)
}

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

/// The spec of `sil-host sweep`'s arguments.
///
/// # Errors
/// [`CliError::BadInput`] or [`CliError::Scenario`] (exit 2).
pub fn spec_of(args: &SweepArgs) -> Result<SweepSpec, CliError> {
    use rig::{overrides, scenario::ScenarioError};
    overrides::check_keys(&args.set, &RUN_KEYS).map_err(ScenarioError::from)?;
    let (scenario, params) = match args.controller {
        SweepController::None => {
            if args.scenario.is_some() {
                return Err(CliError::BadInput("--scenario is for closed-loop sweeps (--controller hybrid or pid)".into()));
            }
            let p = shared::Params::<f64>::paper();
            (None, crate::commands::arm_params(&args.set, "sweep (open loop)", &[], p.mu, p.v_belt)?)
        }
        _ => {
            let s = crate::commands::closed_loop::read_scenario(args.scenario.as_deref(), &args.set)?;
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
    };
    spec.validate().map_err(CliError::BadInput)?;
    Ok(spec)
}

/// Checks `sil-host sweep`'s arguments: the sweep's spec ([`spec_of`]), the
/// shard of it to compute (`--shard`, all by default) and the worker threads
/// (`--threads`, one per core by default).
///
/// # Errors
/// [`CliError::BadInput`] or [`CliError::Scenario`] (exit 2).
pub fn plan(args: &SweepArgs) -> Result<(SweepSpec, Shard, usize), CliError> {
    let spec = spec_of(args)?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).map_err(CliError::BadInput)?,
        None => Shard::ALL,
    };
    if args.threads == Some(0) {
        return Err(CliError::BadInput("--threads must be >= 1".into()));
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

/// Runs `sil-host sweep`.
///
/// # Errors
/// Bad arguments, a folder holding another sweep, or a folder another command
/// writes into ([`CliError::FolderInUse`]) (exit 2); an interruption or
/// an I/O failure (exit 1; finished runs are kept in the journal).
pub fn execute(args: &SweepArgs) -> Result<Done<SweepSummary>, CliError> {
    let (spec, shard, threads) = plan(args)?;
    // One writer per folder, from before the manifest is read to the last figure:
    // a second sweep started into the same --out is refused here (exit 2), and the
    // first finishes unharmed.
    let _lock = FolderLock::acquire(&args.out)?;
    let mut manifest = Manifest { spec: spec.clone(), shard };
    // A shard folder of an earlier version (modulo assignment) resumes as it began.
    if let Some(existing) = store::read_manifest(&args.out)?
        && existing.spec == spec
        && (existing.shard.k, existing.shard.n) == (shard.k, shard.n)
    {
        manifest.shard = existing.shard;
    }
    let shard = manifest.shard;
    store::open(&args.out, &manifest)?;
    let journal = store::read_journal(&args.out, &manifest)?;
    let resumed = journal.rows.len();
    let mut todo = store::missing(&manifest, &journal.rows);
    if let Some(limit) = args.limit {
        todo.truncate(limit);
    }
    let writer = store::Journal::open(&args.out, &journal.rows, journal.dropped_partial_line)?;
    let ics = spec.initial_conditions();
    if !args.json {
        let in_shard = shard.indices(&spec).len();
        eprintln!(
            "sweep of {} runs{} in {}: {resumed} done already{}, computing {} on {threads} threads",
            in_shard,
            if shard.n > 1 { format!(" (shard {}/{} of {})", shard.k, shard.n, spec.n_runs()) } else { String::new() },
            args.out.display(),
            if journal.dropped_partial_line { " (a cut-off last line was dropped)" } else { "" },
            todo.len()
        );
    }

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| CliError::BadInput(format!("cannot start {threads} threads: {e}")))?;
    let stop = crate::cancel::stop_flag();
    let progress = progress_bar(todo.len() as u64, "sweep", "runs", args.json);
    let failure: Mutex<Option<CliError>> = Mutex::new(None);
    let done = AtomicU64::new(0);
    let started = Instant::now();
    let cpu_start = cpu_seconds();
    pool.install(|| {
        todo.par_iter().with_max_len(1).for_each(|&index| {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            let key = spec.run_at(index);
            if let Some(row) = run::simulate(&spec, &key, &ics[key.i_ic], &stop) {
                if let Err(e) = writer.append(&row) {
                    stop.store(true, Ordering::Relaxed);
                    failure.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
                    return;
                }
                done.fetch_add(1, Ordering::Relaxed);
                progress.inc(1);
            }
        });
    });
    let wall_s = started.elapsed().as_secs_f64();
    let cpu_s = cpu_seconds() - cpu_start;
    progress.finish_and_clear();
    drop(writer);
    if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let computed = done.load(Ordering::Relaxed) as usize;
    let timing = Timing::of(&spec, computed, threads, wall_s, cpu_s);
    let interrupted = stop.load(Ordering::Relaxed) && computed < todo.len();
    let rows = store::read_journal(&args.out, &manifest)?.rows;
    let summary = finish(&args.out, &manifest, rows, Some(timing), resumed, interrupted)?;
    let failure = interrupted.then(|| {
        CliError::Interrupted(format!(
            "{} of {} runs done; run the same command again to resume",
            summary.results.runs,
            summary.results.runs + summary.results.missing
        ))
    });
    let files = summary.files.iter().map(std::path::PathBuf::from).collect();
    let validity = summary.results.validity;
    Ok(Done { result: summary, files, failure }.strict(args.strict.strict, &validity))
}

/// Runs `sil-host sweep`: [`execute`], then prints the summary (human, or the
/// JSON document with `--json`).
///
/// # Errors
/// As [`execute`]; an interrupted sweep (what was computed is kept).
pub fn run(args: &SweepArgs) -> Result<(), CliError> {
    let done = execute(args)?;
    report(&done.result, args.json);
    done.into_result()
}
