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
    collections::BTreeMap,
    io::Write,
    path::{Path, PathBuf},
    sync::{
        Arc, Mutex,
        atomic::{AtomicBool, AtomicU64, Ordering},
    },
    time::Instant,
};

use rayon::prelude::*;
use serde::Serialize;

use crate::{
    cli::{MergeArgs, ScenarioArgs, SweepArgs},
    error::CliError,
    output::{OutputSet, progress_bar},
    sweep::{
        figures,
        store::{self, Manifest},
    },
};
use analyses::sweep::{
    Axis, InitialCondition, Shard, SweepController, SweepSpec,
    run::{self, RunRow},
    summary::{self, Results},
};

/// The paper's experiment 3: 10 x 181 grid points, two initial conditions, 300 s each.
const PAPER_GRID_SIMULATED_S: f64 = 10.0 * 181.0 * 2.0 * 300.0;

/// Timing of this invocation.
#[derive(Debug, Clone, Serialize)]
pub struct Timing {
    /// Runs computed by this invocation.
    pub runs_computed: usize,
    /// Worker threads.
    pub threads: usize,
    /// Wall-clock time of the runs, s.
    pub wall_s: f64,
    /// Simulated time of the runs computed, s.
    pub simulated_s: f64,
    /// Simulated seconds per wall second per worker thread.
    pub simulated_s_per_wall_s_per_core: f64,
    /// CPU time (user + system) of the process during the runs, s.
    pub cpu_s: f64,
    /// Simulated seconds per CPU second (what a core does when not shared with
    /// other work: on a loaded machine the wall-clock rate is lower).
    pub simulated_s_per_cpu_s: f64,
    /// The paper's full open-loop grid (3620 runs of 300 s) at this rate on
    /// `threads` cores, s (an extrapolation: the cost per simulated second varies
    /// over the grid, bouncing runs costing most).
    pub paper_grid_projection_s: f64,
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SweepSummary {
    /// `complete`, `incomplete` (runs missing: --limit, or a merge with
    /// --allow-missing) or `interrupted`.
    pub status: &'static str,
    /// The sweep.
    pub spec: SweepSpec,
    /// The part of it in this folder.
    pub shard: Shard,
    /// The initial conditions (before the plant's projection onto the belt).
    pub initial_conditions: Vec<InitialCondition>,
    /// How the initial conditions were treated.
    pub projection_note: &'static str,
    /// Where `theta1_dot_max` and `z_n_max` come from.
    pub maxima_note: &'static str,
    /// Critical `mu`, bands and outcome counts.
    pub results: Results,
    /// This invocation's timing (`None` for a merge).
    pub timing: Option<Timing>,
    /// Runs whose row was already in the journal when this invocation started.
    pub resumed_runs: usize,
    /// Files written.
    pub files: Vec<String>,
}

const PROJECTION_NOTE: &str = "the paper's initial conditions, given in rounded degrees, put the tip a fraction of a millimetre \
     inside the belt; each is projected onto the belt at the same z_t and elbow branch before simulating (height_above_belt is \
     the tip's height as given)";
const MAXIMA_NOTE: &str = "maxima over the continuous trajectory of the record window: both ends of every integrator step, \
     and maxima inside steps located where the slope changes sign and read from the step's 7th-order dense output";

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

fn paper_ic_names(list: &[String]) -> Result<Vec<String>, CliError> {
    let mut out: Vec<String> = Vec::new();
    for item in list {
        let name = match item.trim() {
            "a" | "x0a" => "x0a",
            "d" | "x0d" => "x0d",
            "u" | "x0u" => "x0u",
            "none" | "" => continue,
            other => return Err(CliError::BadInput(format!("--ics: unknown initial condition `{other}` (a, d, u or none)"))),
        };
        if !out.iter().any(|n| n == name) {
            out.push(name.into());
        }
    }
    Ok(out)
}

/// The spec of `sil-host sweep`'s arguments.
///
/// # Errors
/// [`CliError::BadInput`] or [`CliError::Scenario`] (exit 2).
pub fn spec_of(args: &SweepArgs) -> Result<SweepSpec, CliError> {
    let scenario = match args.controller {
        SweepController::None => {
            if args.scenario.is_some() {
                return Err(CliError::BadInput("--scenario is for closed-loop sweeps (--controller hybrid or pid)".into()));
            }
            None
        }
        _ => Some(crate::commands::closed_loop::load_scenario(&ScenarioArgs {
            scenario: args.scenario.clone(),
            controller: None,
            x0: None,
            target_zt: None,
            duration: None,
            seed: None,
        })?),
    };
    let spec = SweepSpec {
        format: analyses::sweep::FORMAT,
        mu: parse_axis("mu", &args.mu, args.mu_step)?,
        v_belt: parse_axis("v-belt", &args.v_belt, args.v_belt_step)?,
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
        paper_ics: paper_ic_names(&args.ics)?,
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
    };
    spec.validate().map_err(CliError::BadInput)?;
    Ok(spec)
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

/// User plus system CPU time of this process so far, s (getrusage).
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage only writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    tv(u.ru_utime) + tv(u.ru_stime)
}

/// Ctrl-C and SIGTERM set a flag the workers check between runs and inside them.
fn stop_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, Arc::clone(&flag));
    }
    flag
}

/// Runs `sil-host sweep`.
///
/// # Errors
/// Bad arguments or a folder holding another sweep (exit 2); an interruption or
/// an I/O failure (exit 1; finished runs are kept in the journal).
pub fn run(args: &SweepArgs) -> Result<(), CliError> {
    let spec = spec_of(args)?;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).map_err(CliError::BadInput)?,
        None => Shard::ALL,
    };
    if args.threads == Some(0) {
        return Err(CliError::BadInput("--threads must be >= 1".into()));
    }
    let manifest = Manifest { spec: spec.clone(), shard };
    store::open(&args.out, &manifest)?;
    let journal = store::read_journal(&args.out, &manifest)?;
    let resumed = journal.rows.len();
    let mut todo = store::missing(&manifest, &journal.rows);
    if let Some(limit) = args.limit {
        todo.truncate(limit);
    }
    let writer = store::Journal::open(&args.out, &journal.rows, journal.dropped_partial_line)?;
    let ics = spec.initial_conditions();
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if !args.json {
        let in_shard = shard.indices(spec.n_runs()).count();
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
    let stop = stop_flag();
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
    let simulated_s = computed as f64 * spec.run_duration();
    let rate = simulated_s / (wall_s.max(1e-9) * threads as f64);
    let timing = Timing {
        runs_computed: computed,
        threads,
        wall_s,
        simulated_s,
        simulated_s_per_wall_s_per_core: rate,
        cpu_s,
        simulated_s_per_cpu_s: simulated_s / cpu_s.max(1e-9),
        paper_grid_projection_s: if rate > 0.0 { PAPER_GRID_SIMULATED_S / (rate * threads as f64) } else { f64::NAN },
    };
    let interrupted = stop.load(Ordering::Relaxed) && computed < todo.len();
    let rows = store::read_journal(&args.out, &manifest)?.rows;
    let summary = finish(&args.out, &manifest, rows, Some(timing), resumed, interrupted)?;
    report(&summary, args.json);
    if interrupted {
        return Err(CliError::Interrupted(format!(
            "{} of {} runs done; run the same command again to resume",
            summary.results.runs,
            summary.results.runs + summary.results.missing
        )));
    }
    Ok(())
}

/// Writes the outputs of the folder from its rows: `sweep.csv`, `summary.json` and
/// the figures (all or nothing, [`OutputSet`]).
fn finish(
    dir: &Path,
    m: &Manifest,
    mut rows: Vec<RunRow>,
    timing: Option<Timing>,
    resumed: usize,
    interrupted: bool,
) -> Result<SweepSummary, CliError> {
    rows.sort_by_key(|r| r.index);
    let missing = store::missing(m, &rows).len();
    let results = summary::results(&m.spec, &rows, missing);
    let mut out = OutputSet::new(dir)?;
    let csv_tmp = out.stage("sweep.csv");
    store::write_rows(&csv_tmp, &rows)?;
    // Figures per impact law and e_n.
    let mut by_case: BTreeMap<(String, u64), Vec<&RunRow>> = BTreeMap::new();
    for r in &rows {
        by_case.entry((r.impact_law.clone(), r.e_n.to_bits())).or_default().push(r);
    }
    let mut files = vec![dir.join("sweep.csv")];
    for law in &m.spec.impact_laws {
        for &e_n in &m.spec.e_n {
            let empty = Vec::new();
            let case_rows = by_case.get(&(law.name().to_string(), e_n.to_bits())).unwrap_or(&empty);
            let suffix = figures::case_suffix(law.name(), e_n);
            let map = format!("map_{suffix}.svg");
            let slices = format!("slices_{suffix}.svg");
            figures::draw_map(&out.stage(&map), &m.spec, law.name(), e_n, case_rows)?;
            figures::draw_slices(&out.stage(&slices), &m.spec, law.name(), e_n, case_rows)?;
            files.push(dir.join(map));
            files.push(dir.join(slices));
        }
    }
    files.push(dir.join("summary.json"));
    let summary = SweepSummary {
        status: if interrupted {
            "interrupted"
        } else if missing > 0 {
            "incomplete"
        } else {
            "complete"
        },
        spec: m.spec.clone(),
        shard: m.shard,
        initial_conditions: m.spec.initial_conditions(),
        projection_note: PROJECTION_NOTE,
        maxima_note: MAXIMA_NOTE,
        results,
        timing,
        resumed_runs: resumed,
        files: files.iter().map(|p| p.display().to_string()).collect(),
    };
    out.write_json("summary.json", &summary)?;
    out.commit()?;
    Ok(summary)
}

fn report(s: &SweepSummary, json: bool) {
    if json {
        println!("{}", serde_json::to_string_pretty(s).unwrap_or_default());
        return;
    }
    let mut o = std::io::stdout().lock();
    let ctrl = match (s.spec.controller, s.spec.ideal) {
        (SweepController::None, _) => "open loop (u = 0)".to_string(),
        (c, true) => format!("closed loop, {} (ideal continuous-time)", c.name()),
        (c, false) => format!("closed loop, {} firmware in-process at the scenario's rate", c.name()),
    };
    let _ = writeln!(
        o,
        "sweep: {}, mu {}..{} ({} values), v_belt {}..{} m/s ({} values), transient {} s + record {} s, {} initial conditions",
        ctrl,
        s.spec.mu.start,
        s.spec.mu.stop,
        s.spec.mu.len(),
        s.spec.v_belt.start,
        s.spec.v_belt.stop,
        s.spec.v_belt.len(),
        s.spec.transient_s,
        s.spec.record_s,
        s.initial_conditions.len()
    );
    for ic in &s.initial_conditions {
        let deg = ic.x0.map(f64::to_degrees);
        let _ = writeln!(
            o,
            "  {}: [{:.4}, {:.1}, {:.4}, {:.1}] deg (elbow {}), tip {:.3} mm {} the belt{}",
            ic.name,
            deg[0],
            deg[1],
            deg[2],
            deg[3],
            ic.branch.name(),
            ic.height_above_belt.abs() * 1e3,
            if ic.height_above_belt < 0.0 { "inside" } else { "above" },
            if ic.height_above_belt <= 1e-12 { ": projected onto it" } else { "" }
        );
    }
    summary::print_table(&mut o, &s.results);
    if let Some(t) = &s.timing
        && t.runs_computed > 0
    {
        let _ = writeln!(
            o,
            "speed: {} runs in {:.1} s on {} threads: {:.0} simulated s per wall s per core ({:.0} per CPU s); a grid of the paper's size (3620 runs x 300 s) would take {:.1} min at this rate",
            t.runs_computed,
            t.wall_s,
            t.threads,
            t.simulated_s_per_wall_s_per_core,
            t.simulated_s_per_cpu_s,
            t.paper_grid_projection_s / 60.0
        );
    }
    let _ = writeln!(o, "status: {}; wrote {}", s.status, s.files.join(", "));
}

/// Runs `sil-host merge`.
///
/// # Errors
/// Folders of different sweeps, conflicting duplicates, missing runs without
/// --allow-missing (exit 2); I/O failures (exit 1).
pub fn merge(args: &MergeArgs) -> Result<(), CliError> {
    let mut first: Option<(PathBuf, Manifest)> = None;
    let mut rows: BTreeMap<usize, (RunRow, PathBuf)> = BTreeMap::new();
    let mut duplicates = 0usize;
    let mut shards = Vec::new();
    for dir in &args.dirs {
        let m = store::read_manifest(dir)?
            .ok_or_else(|| CliError::BadInput(format!("{} has no {}: not a sweep folder", dir.display(), store::MANIFEST)))?;
        if let Some((d0, m0)) = &first {
            if m.spec != m0.spec {
                let diff = store::differences(&Manifest { shard: m.shard, ..m0.clone() }, &m);
                return Err(CliError::BadInput(format!(
                    "{} and {} hold different sweeps: {}",
                    d0.display(),
                    dir.display(),
                    diff.join("; ")
                )));
            }
        } else {
            first = Some((dir.clone(), m.clone()));
        }
        shards.push(m.shard);
        for r in store::read_journal(dir, &m)?.rows {
            match rows.get(&r.index) {
                Some((other, where_)) => {
                    if !store::same_row(other, &r) {
                        return Err(CliError::BadInput(format!(
                            "run {} is in {} and {} with different results",
                            r.index,
                            where_.display(),
                            dir.display()
                        )));
                    }
                    duplicates += 1;
                }
                None => {
                    rows.insert(r.index, (r, dir.clone()));
                }
            }
        }
    }
    let Some((_, m0)) = first else {
        return Err(CliError::BadInput("no folders given".into()));
    };
    let merged = Manifest { spec: m0.spec.clone(), shard: Shard::ALL };
    let rows: Vec<RunRow> = rows.into_values().map(|(r, _)| r).collect();
    let missing = store::missing(&merged, &rows);
    if !missing.is_empty() && !args.allow_missing {
        let ics = merged.spec.initial_conditions();
        let show: Vec<String> = missing
            .iter()
            .take(5)
            .map(|&i| {
                let k = merged.spec.run_at(i);
                let owner = shards.first().map_or(String::new(), |s| format!(", shard {}/{}", i % s.n, s.n));
                format!("run {i} (mu {}, v_belt {}, {}{owner})", k.mu, k.v_belt, ics[k.i_ic].name)
            })
            .collect();
        return Err(CliError::BadInput(format!(
            "{} of {} runs are missing, e.g. {}; give every shard's folder (or --allow-missing)",
            missing.len(),
            merged.spec.n_runs(),
            show.join(", ")
        )));
    }
    if args.dirs.iter().any(|d| d == &args.out) {
        return Err(CliError::BadInput("--out must not be one of the merged folders".into()));
    }
    store::open(&args.out, &merged)?;
    store::write_rows(&args.out.join(store::JOURNAL), &rows)?;
    if !args.json && duplicates > 0 {
        eprintln!("note: {duplicates} runs were in more than one folder (with identical results)");
    }
    let summary = finish(&args.out, &merged, rows, None, 0, false)?;
    report(&summary, args.json);
    Ok(())
}
