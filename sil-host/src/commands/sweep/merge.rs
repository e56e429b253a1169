//! `sil-host merge`: joins the folders of a sharded sweep into one.

use super::outputs::{finish, report};
use crate::{
    cli::MergeArgs,
    error::CliError,
    sweep::store::{self, Manifest},
};
use analyses::sweep::{Shard, run::RunRow};
use std::{collections::BTreeMap, path::PathBuf};

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
