//! `sil-host sweep` (the brute-force bifurcation diagram, docs/model.md experiments 3
//! and 7) and `sil-host merge` (joining a sharded sweep). See [`crate::sweep`].
//!
//! Files in the sweep's folder: `sweep.json` (the spec and shard, checked on
//! resume), `runs.csv` (the journal, one flushed row per finished run, in
//! completion order), and, written at the end of every invocation from the
//! journal: `sweep.csv` (the same rows by run index: identical for an
//! uninterrupted, a resumed and a merged sweep), `summary.json`, and per impact
//! law and `e_n` the figures `map_<law>_e<e_n>.svg` and `slices_<law>_e<e_n>.svg`.

use std::sync::atomic::Ordering;

use crate::commands::Done;
use crate::{cli::SweepArgs, error::CliError, folder_lock::FolderLock, output::progress_bar};
use analyses::sweep::run::RunRow;
pub use experiments::sweep::{plan, run_all, spec_of, store, store::Manifest, summary::*};

pub mod merge;
pub mod outputs;
use outputs::*;

/// Runs `sil-host sweep`.
///
/// # Errors
/// Bad arguments, a folder holding another sweep, or a folder another command
/// writes into ([`CliError::FolderInUse`]) (exit 2); an interruption or
/// an I/O failure (exit 1; finished runs are kept in the journal).
pub fn execute(args: &SweepArgs) -> Result<Done<SweepSummary>, CliError> {
    let (spec, shard, threads) = plan(args)?;
    if let Some(s) = &spec.scenario {
        crate::commands::warn(experiments::scenario::board_tables_note(s, "a sweep (the firmware in-process)"));
    }
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

    let pool = experiments::pool(threads)?;
    let stop = crate::cancel::stop_flag();
    let progress = progress_bar(todo.len() as u64, "sweep", "runs", args.json);
    let sink = |row: RunRow| {
        writer.append(&row)?;
        progress.inc(1);
        Ok(())
    };
    let ran = run_all(&pool, &spec, &todo, threads, &stop, &sink);
    progress.finish_and_clear();
    drop(writer);
    let (computed, timing) = ran?;
    let interrupted = stop.load(Ordering::Relaxed) && computed < todo.len();
    let rows = store::read_journal(&args.out, &manifest)?.rows;
    let summary = finish(&args.out, &manifest, rows, Some(timing), resumed, interrupted)?;
    let failure = interrupted.then(|| {
        CliError::interrupted(format!(
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
