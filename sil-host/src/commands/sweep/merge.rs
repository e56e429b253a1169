//! `sil-host merge`: joins the folders of a sharded sweep into one.

use super::outputs::{finish, report};
use crate::{
    cli::MergeArgs,
    error::CliError,
    folder_lock::FolderLock,
    sweep::store::{self, Manifest},
};
use analyses::sweep::{Shard, SweepSpec, run::RunRow};
use std::{collections::BTreeMap, path::PathBuf};

/// Runs `sil-host merge`.
///
/// # Errors
/// Folders of different sweeps, conflicting duplicates, missing runs without
/// --allow-missing (exit 2, naming a few missing runs, the shards that miss runs
/// and how to finish); `--out` in use by another command ([`CliError::FolderInUse`],
/// exit 2); I/O failures (exit 1).
pub fn merge(args: &MergeArgs) -> Result<(), CliError> {
    let mut first: Option<(PathBuf, Manifest)> = None;
    let mut rows: BTreeMap<usize, (RunRow, PathBuf)> = BTreeMap::new();
    let mut duplicates = 0usize;
    let mut shards = Vec::new();
    for dir in &args.dirs {
        let m = store::read_manifest(dir)?
            .ok_or_else(|| CliError::bad_input(format!("{} has no {}: not a sweep folder", dir.display(), store::MANIFEST)))?;
        if let Some((d0, m0)) = &first {
            if m.spec != m0.spec {
                let diff = store::differences(&Manifest { shard: m.shard, ..m0.clone() }, &m);
                return Err(CliError::bad_input(format!(
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
                        return Err(CliError::bad_input(format!(
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
        return Err(CliError::bad_input("no folders given"));
    };
    let merged = Manifest { spec: m0.spec.clone(), shard: Shard::ALL };
    let rows: Vec<RunRow> = rows.into_values().map(|(r, _)| r).collect();
    let missing = store::missing(&merged, &rows);
    if !missing.is_empty() && !args.allow_missing {
        return Err(CliError::bad_input(missing_message(&merged.spec, &missing, shards.iter().find(|s| s.n > 1))));
    }
    if args.dirs.iter().any(|d| d == &args.out) {
        return Err(CliError::bad_input("--out must not be one of the merged folders"));
    }
    // One writer per folder: a second merge or a sweep into --out is refused.
    let _lock = FolderLock::acquire(&args.out)?;
    store::open(&args.out, &merged)?;
    store::write_rows(&args.out.join(store::JOURNAL), &rows)?;
    if !args.json && duplicates > 0 {
        eprintln!("note: {duplicates} runs were in more than one folder (with identical results)");
    }
    let summary = finish(&args.out, &merged, rows, None, 0, false)?;
    report(&summary, args.json);
    Ok(())
}

/// The error for `missing` runs of `spec`: the first few (with their shard), and
/// with `shard` (the sharding of the folders: its `n` and assignment) the count
/// missing per shard, the list `shards with missing runs: K1,K2` (read by
/// `scripts/sweep-slurm.sh`) and how to re-run them.
fn missing_message(spec: &SweepSpec, missing: &[usize], shard: Option<&Shard>) -> String {
    let ics = spec.initial_conditions();
    let show: Vec<String> = missing
        .iter()
        .take(5)
        .map(|&i| {
            let k = spec.run_at(i);
            let owner = shard.map_or(String::new(), |s| format!(", shard {}/{}", s.owner(spec, i), s.n));
            format!("run {i} (mu {}, v_belt {}, {}{owner})", k.mu, k.v_belt, ics[k.i_ic].name)
        })
        .collect();
    let mut msg = format!("{} of {} runs are missing, e.g. {}", missing.len(), spec.n_runs(), show.join(", "));
    match shard {
        Some(s) => {
            let mut total = vec![0usize; s.n];
            for i in 0..spec.n_runs() {
                total[s.owner(spec, i)] += 1;
            }
            let mut absent: BTreeMap<usize, usize> = BTreeMap::new();
            for &i in missing {
                *absent.entry(s.owner(spec, i)).or_default() += 1;
            }
            let per: Vec<String> = absent.iter().map(|(k, c)| format!("{k}/{} ({c} of {})", s.n, total[*k])).collect();
            let list: Vec<String> = absent.keys().map(usize::to_string).collect();
            msg += &format!(
                "; missing by shard: {}; shards with missing runs: {}. Run each of them again with the sweep's arguments, \
                 --shard K/{} and its folder as --out (it resumes: only its missing runs are computed), then merge again \
                 (or merge with --allow-missing)",
                per.join(", "),
                list.join(","),
                s.n
            );
        }
        None => msg += "; run the sweep again into one of the folders (it resumes), or give every shard's folder (or --allow-missing)",
    }
    msg
}
