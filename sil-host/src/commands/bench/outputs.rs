//! The analyses' figures, measured through the commands themselves (their
//! `execute`, into a scratch folder): `simulate` 300 s with its 1 ms trace (CSV,
//! then Arrow IPC) and with 1 s samples, and
//! the closed-loop hybrid sweep of the paper's grid (experiment 7: x0d, 10 mu x
//! 181 v_belt, 300 s per run), estimated from one balanced shard.

use std::time::Instant;

use clap::Parser;

use crate::bench::figure::{Figure, Goal, median};
use crate::{
    cli::{BenchArgs, Cli, Command},
    error::CliError,
};

/// Target of `simulate` 300 s with its 1 ms trace, wall seconds (issue 16).
pub const SIMULATE_TARGET_S: f64 = 0.1;
/// Target of `simulate` 300 s with its 1 ms trace as an Arrow IPC file, wall
/// seconds (issue 26: a columnar format).
pub const SIMULATE_ARROW_TARGET_S: f64 = 0.05;
/// Target of `simulate` 300 s with 1 s samples, wall seconds (issue 26: 500 times
/// faster than an event-driven SciPy peer, 12.6 s on the reference machine).
pub const SIMULATE_SPARSE_TARGET_S: f64 = 0.02;
/// Target of the ratio of the 1 s-sample run to the 1 ms-trace run (issue 81: 1 s samples
/// cost at most a quarter of the 1 ms trace).
pub const SPARSE_RATIO_TARGET: f64 = 0.25;
/// The SciPy peer's time for the sparse case, s (issue 26's measurement), for the ratio.
pub const SCIPY_PEER_S: f64 = 12.6;
/// Target of the closed-loop hybrid sweep of the paper's grid, wall seconds (issue 16).
pub const SWEEP_TARGET_S: f64 = 180.0;

/// The simulate command the figure times (issue 16's case: the bouncing arm).
pub const SIMULATE_ARGS: [&str; 10] = ["simulate", "--x0", "a", "--v-belt", "-0.5", "--e-n", "0.2", "--duration", "300", "--json"];

/// The same case with its tables as Arrow IPC files (`trace.arrow`, `events.arrow`).
pub const SIMULATE_ARROW_ARGS: [&str; 12] =
    ["simulate", "--x0", "a", "--v-belt", "-0.5", "--e-n", "0.2", "--duration", "300", "--format", "arrow", "--json"];

/// The same case with 1 s samples: the tolerance, not the samples, sets the steps.
pub const SIMULATE_SPARSE_ARGS: [&str; 12] =
    ["simulate", "--x0", "a", "--v-belt", "-0.5", "--e-n", "0.2", "--duration", "300", "--sample-dt", "1", "--json"];

/// The sweep command the figure times (experiment 7; the default grid and window).
pub const SWEEP_ARGS: [&str; 6] = ["sweep", "--controller", "hybrid", "--ics", "d", "--json"];

/// `sil-host ARGS --out DIR` parsed as the command line would be.
fn parse(args: &[&str], out: &std::path::Path) -> Result<Command, CliError> {
    let out = out.to_string_lossy();
    let argv = std::iter::once("sil-host").chain(args.iter().copied()).chain(["--out", &out]);
    Cli::try_parse_from(argv).map(|c| c.command).map_err(|e| CliError::bad_input(format!("bench: {e}")))
}

fn scratch() -> Result<tempfile::TempDir, CliError> {
    tempfile::tempdir().map_err(|e| CliError::Io { path: std::env::temp_dir(), source: e })
}

/// `sil-host ARGS --out DIR`, `--repeat` times into fresh folders: the wall times
/// and the size of the last trace file (`trace` with the extension `ext`), bytes.
fn time_simulate(args: &BenchArgs, argv: &[&str], ext: &str) -> Result<(Vec<f64>, u64), CliError> {
    let mut times = Vec::new();
    let mut bytes = 0;
    for _ in 0..args.repeat {
        let dir = scratch()?;
        let Command::Simulate(sim) = parse(argv, dir.path())? else {
            unreachable!("the bench's simulate arguments are a simulate command")
        };
        let t = Instant::now();
        let done = crate::commands::simulate::execute(&sim)?;
        times.push(t.elapsed().as_secs_f64());
        done.into_result()?;
        bytes = std::fs::metadata(dir.path().join(format!("trace.{ext}"))).map_or(0, |m| m.len());
    }
    Ok((times, bytes))
}

/// The figure `id` of `simulate` 300 s with its 1 ms trace as `trace.EXT`
/// (`kind` describes the format in the note), against `target` s.
fn traced_figure(args: &BenchArgs, id: &'static str, argv: &[&str], ext: &str, kind: &str, target: f64) -> Result<Figure, CliError> {
    let (times, bytes) = time_simulate(args, argv, ext)?;
    let name = format!("simulate 300 s from x0a, v_belt -0.5, 1 ms trace.{ext}");
    Ok(Figure::measured(id, "simulate", name, median(&times), "s", target, Goal::AtMost)
        .note(format!(
            "{} runs of `sil-host {} --out DIR`; trace.{ext} {:.1} MB{kind}, every file and figure written",
            times.len(),
            argv.join(" "),
            bytes as f64 / 1e6
        ))
        .with_runs(times))
}

/// `simulate` 300 s with its 1 ms trace as CSV, then as Arrow IPC (with the feature
/// `formats`), then with 1 s samples, `--repeat` times each into fresh folders:
/// median wall times.
///
/// # Errors
/// The simulation failing (exit 1); a scratch folder that cannot be made.
pub fn simulate(args: &BenchArgs) -> Result<Vec<Figure>, CliError> {
    let traced = traced_figure(args, "simulate_300s", &SIMULATE_ARGS, "csv", "", SIMULATE_TARGET_S)?;
    // The Arrow writer is the feature `formats`'s: without it, the CSV and sparse figures alone.
    let columnar = if cfg!(feature = "formats") {
        Some(traced_figure(args, "simulate_300s_arrow", &SIMULATE_ARROW_ARGS, "arrow", " (Arrow IPC)", SIMULATE_ARROW_TARGET_S)?)
    } else {
        None
    };
    let (times, _) = time_simulate(args, &SIMULATE_SPARSE_ARGS, "csv")?;
    let m = median(&times);
    let name = "simulate 300 s from x0a, v_belt -0.5, 1 s samples";
    let sparse = Figure::measured("simulate_300s_sparse", "simulate", name, m, "s", SIMULATE_SPARSE_TARGET_S, Goal::AtMost)
        .note(format!("{} runs of `sil-host {} --out DIR`", times.len(), SIMULATE_SPARSE_ARGS.join(" ")))
        .note(format!(
            "{:.0} times faster than the event-driven SciPy peer's {SCIPY_PEER_S} s (issue 26, measured on this machine class; target 500)",
            SCIPY_PEER_S / m
        ))
        .with_runs(times);
    // Issue 81: what 1 s samples save over the 1 ms trace, one path (the same steps: the
    // arm's step cap, not the samples, sets them, docs/architecture.md "The contract on
    // the path"), so only the trace's rows and their writing.
    let ratio = match (sparse.value, traced.value) {
        (Some(s), Some(t)) if t > 0.0 => Figure::measured("simulate_300s_sparse_ratio", "simulate", "simulate 300 s: 1 s samples over the 1 ms trace", s / t, "ratio", SPARSE_RATIO_TARGET, Goal::AtMost)
            .note(format!("the medians above: {s:.4} s over {t:.4} s"))
            .note("one path whatever the sampling (the 2 ms step cap of the paper's arm sets the steps): the ratio is the trace's rows and their writing; without the cap, --max-step 1e3, the steps are fewer and the path leaves the reference at 2.90 s instead of 4.68 s"),
        _ => Figure::skipped("simulate_300s_sparse_ratio", "simulate", "simulate 300 s: 1 s samples over the 1 ms trace", "ratio", SPARSE_RATIO_TARGET, Goal::AtMost, "a median is missing".into()),
    };
    Ok([Some(traced), columnar, Some(sparse), Some(ratio)].into_iter().flatten().collect())
}

/// The closed-loop hybrid sweep: shard 0 of N, N chosen so that it holds about
/// `--sweep-runs` runs (balanced: an equal share of every `mu` row), timed and
/// scaled to the whole grid; `--sweep-runs` at least the grid's size runs it whole.
///
/// # Errors
/// A run failing (exit 1); a scratch folder that cannot be made.
pub fn sweep(args: &BenchArgs) -> Result<Figure, CliError> {
    let dir = scratch()?;
    let Command::Sweep(whole) = parse(&SWEEP_ARGS, dir.path())? else { unreachable!("SWEEP_ARGS is a sweep command") };
    let total = crate::commands::sweep::spec_of(&whole)?.n_runs();
    let shards = total.div_ceil(args.sweep_runs.clamp(1, total.max(1))).max(1);
    let mut sweep = whole;
    if shards > 1 {
        sweep.shard = Some(format!("0/{shards}"));
    }
    let t = Instant::now();
    let done = crate::commands::sweep::execute(&sweep)?;
    let wall = t.elapsed().as_secs_f64();
    let computed = done.result.timing.as_ref().map_or(0, |t| t.runs_computed);
    let threads = done.result.timing.as_ref().map_or(0, |t| t.threads);
    done.into_result()?;
    let estimate = if computed == 0 { f64::NAN } else { wall * total as f64 / computed as f64 };
    let name = "closed-loop hybrid sweep, paper grid from x0d";
    let how = if shards > 1 {
        format!("estimated from shard 0/{shards}: {computed} of {total} runs in {wall:.1} s on {threads} threads")
    } else {
        format!("all {total} runs in {wall:.1} s on {threads} threads")
    };
    Ok(Figure::measured("sweep_hybrid", "sweep", name, estimate, "s", SWEEP_TARGET_S, Goal::AtMost)
        .note(format!("{how} (`sil-host {} --out DIR`)", SWEEP_ARGS.join(" ")))
        .note(format!("{:.3} s per run per thread", wall * threads as f64 / computed.max(1) as f64)))
}
