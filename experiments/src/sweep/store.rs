//! A sweep's folder: `sweep.json` (the [`Manifest`]: spec and shard), the
//! `runs.csv` journal (one row per finished run, appended and flushed as each run
//! finishes, in completion order), and the final outputs written from it.
//!
//! Resume: a sweep started again with the same arguments and `--out` reads the
//! journal, drops a last line cut short by a kill (every complete row ends with a
//! newline), and computes only the runs not in it. A folder whose manifest differs
//! is refused, naming the differing settings.

use std::{
    collections::BTreeMap,
    fs::{File, OpenOptions},
    os::unix::fs::OpenOptionsExt,
    path::{Path, PathBuf},
    sync::Mutex,
};

use serde::{Deserialize, Serialize};

use crate::{error::Error, error::io_err};
use analyses::sweep::{Shard, SweepSpec, run::RunRow};

/// File name of the manifest.
pub const MANIFEST: &str = "sweep.json";
/// File name of the journal.
pub const JOURNAL: &str = "runs.csv";

/// `sweep.json`: what the folder's runs belong to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The sweep.
    pub spec: SweepSpec,
    /// The part of it this folder computes ([`Shard::ALL`] for a whole or merged sweep).
    pub shard: Shard,
}

/// Reads `dir/sweep.json`, if there is one.
///
/// # Errors
/// [`crate::error::Error::Analysis`] when it cannot be read, is not a manifest of this
/// version, holds an invalid spec or names an impossible shard;
/// [`crate::error::Error::BadInput`] for one that is not a regular file or is over
/// [`tables::input::SWEEP_MANIFEST`]'s bound.
pub fn read_manifest(dir: &Path) -> Result<Option<Manifest>, Error> {
    let path = dir.join(MANIFEST);
    let text = match tables::input::read_to_string(&path, tables::input::SWEEP_MANIFEST) {
        Ok(t) => t,
        Err(e) if e.is_not_found() => return Ok(None),
        Err(e) => return Err(e.into()),
    };
    let m: Manifest = serde_json::from_str(&text).map_err(|e| {
        Error::bad_input(format!("{} is not a sweep manifest of this version (format {}): {e}", path.display(), analyses::sweep::FORMAT))
    })?;
    m.spec.validate().map_err(|e| Error::bad_input(format!("{}: {e}", path.display())))?;
    if m.shard.n == 0 || m.shard.k >= m.shard.n {
        return Err(Error::bad_input(format!("{}: shard {}/{} is not one of 0/1 .. (N-1)/N", path.display(), m.shard.k, m.shard.n)));
    }
    Ok(Some(m))
}

/// Writes `dir/sweep.json` (through a temporary file and a rename).
///
/// # Errors
/// [`Error::Io`].
pub fn write_manifest(dir: &Path, m: &Manifest) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    let path = dir.join(MANIFEST);
    let tmp = dir.join(format!(".{MANIFEST}.partial"));
    let json = serde_json::to_string_pretty(m).map_err(|e| Error::Io { path: path.clone(), source: e.into() })?;
    // Made new, never through a link left at its name (rig::private_files).
    rig::private_files::write_new(&tmp, json.as_bytes()).map_err(io_err(&tmp))?;
    std::fs::rename(&tmp, &path).map_err(io_err(&path))
}

/// The top-level settings where two manifests differ, as `name: a vs b`.
pub fn differences(a: &Manifest, b: &Manifest) -> Vec<String> {
    let (va, vb) = (serde_json::to_value(a).unwrap_or_default(), serde_json::to_value(b).unwrap_or_default());
    let mut out = Vec::new();
    let mut compare = |prefix: &str, x: &serde_json::Value, y: &serde_json::Value| {
        if let (Some(x), Some(y)) = (x.as_object(), y.as_object()) {
            for (k, xv) in x {
                let yv = y.get(k).unwrap_or(&serde_json::Value::Null);
                if xv != yv {
                    let show = |v: &serde_json::Value| {
                        let s = v.to_string();
                        if s.len() > 60 { format!("{}...", &s[..57]) } else { s }
                    };
                    out.push(format!("{prefix}{k}: {} vs {}", show(xv), show(yv)));
                }
            }
        }
    };
    compare("", &va["spec"], &vb["spec"]);
    if a.shard != b.shard {
        let show =
            |s: &Shard| format!("{}/{}{}", s.k, s.n, if s.n > 1 { format!(" ({:?})", s.assignment).to_lowercase() } else { String::new() });
        out.push(format!("shard: {} vs {}", show(&a.shard), show(&b.shard)));
    }
    out
}

/// Prepares `dir` for the sweep `m`: creates it with its manifest, or checks that
/// the manifest already there is the same.
///
/// # Errors
/// [`crate::error::Error::Analysis`] when the folder holds another sweep (naming the
/// differing settings); [`Error::Io`].
pub fn open(dir: &Path, m: &Manifest) -> Result<(), Error> {
    match read_manifest(dir)? {
        Some(existing) if existing == *m => Ok(()),
        Some(existing) => Err(Error::bad_input(format!(
            "{} holds a different sweep; resuming needs the same arguments (use another --out, or delete the folder). Differences (folder vs now): {}",
            dir.display(),
            differences(&existing, m).join("; ")
        ))),
        None => {
            if dir.join(JOURNAL).exists() {
                return Err(Error::bad_input(format!("{} has a {JOURNAL} but no {MANIFEST}: not a sweep folder", dir.display())));
            }
            write_manifest(dir, m)
        }
    }
}

/// What [`read_journal`] found.
#[derive(Debug, Default)]
pub struct JournalContents {
    /// The rows, in file order, without duplicates (the first kept).
    pub rows: Vec<RunRow>,
    /// A last line cut short (by a kill) was dropped.
    pub dropped_partial_line: bool,
    /// Rows repeated with the same index (identical ones; ignored).
    pub duplicates: usize,
}

/// Reads `dir/runs.csv` of sweep `m` (empty if there is none). A last line without
/// its newline is dropped; every row must be a run of `m` (its index in the shard,
/// its parameters those of that index).
///
/// # Errors
/// [`crate::error::Error::Analysis`] for a row that does not parse or does not belong, or a
/// repeated index with different results; [`crate::error::Error::BadInput`] for a
/// journal that is not a regular file or is over
/// [`tables::input::SWEEP_JOURNAL`]'s bound; [`Error::Io`].
pub fn read_journal(dir: &Path, m: &Manifest) -> Result<JournalContents, Error> {
    let path = dir.join(JOURNAL);
    let mut bytes = match tables::input::read(&path, tables::input::SWEEP_JOURNAL) {
        Ok(b) => b,
        Err(e) if e.is_not_found() => return Ok(JournalContents::default()),
        Err(tables::input::InputError::Unreadable { source, .. }) => return Err(Error::Io { path, source }),
        Err(e) => return Err(e.into()),
    };
    let mut out = JournalContents::default();
    if !bytes.is_empty() && bytes.last() != Some(&b'\n') {
        let keep = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        bytes.truncate(keep);
        out.dropped_partial_line = true;
    }
    let ics = m.spec.initial_conditions();
    let n_runs = m.spec.n_runs();
    let mut seen: BTreeMap<usize, usize> = BTreeMap::new();
    let mut reader = csv::ReaderBuilder::new().from_reader(bytes.as_slice());
    for (line, rec) in reader.deserialize::<RunRow>().enumerate() {
        let bad = |what: String| Error::bad_input(format!("{} row {}: {what}", path.display(), line + 1));
        let row = rec.map_err(|e| bad(format!("does not parse: {e}")))?;
        if row.index >= n_runs || !m.shard.owns(&m.spec, row.index) {
            return Err(bad(format!("run {} is not part of this sweep (shard {}/{}, {n_runs} runs)", row.index, m.shard.k, m.shard.n)));
        }
        let key = m.spec.run_at(row.index);
        if row.mu != key.mu
            || row.v_belt != key.v_belt
            || row.e_n != key.e_n
            || row.impact_law != key.impact_law.name()
            || row.ic != ics[key.i_ic].name
        {
            return Err(bad(format!("run {} has other parameters than this sweep's", row.index)));
        }
        match seen.get(&row.index) {
            Some(&at) => {
                if !same_row(&out.rows[at], &row) {
                    return Err(bad(format!("run {} appears twice with different results", row.index)));
                }
                out.duplicates += 1;
            }
            None => {
                seen.insert(row.index, out.rows.len());
                out.rows.push(row);
            }
        }
    }
    Ok(out)
}

/// Rows equal field by field, NaN equal to NaN.
pub fn same_row(a: &RunRow, b: &RunRow) -> bool {
    let f = |x: f64, y: f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
    a.index == b.index
        && a.outcome == b.outcome
        && a.theta1_dot_over_threshold == b.theta1_dot_over_threshold
        && a.ledger_violations == b.ledger_violations
        && f(a.belt_j, b.belt_j)
        && f(a.slip_j, b.slip_j)
        && f(a.ledger_residual_j, b.ledger_residual_j)
        && f(a.largest_event_belt_j, b.largest_event_belt_j)
        && f(a.theta1_dot_max, b.theta1_dot_max)
        && f(a.t_theta1_dot_max, b.t_theta1_dot_max)
        && f(a.z_n_max, b.z_n_max)
        && a.lift_offs == b.lift_offs
        && a.touchdowns == b.touchdowns
        && a.impacts_without_collision == b.impacts_without_collision
        && a.final_mode == b.final_mode
        && a.lift_offs_transient == b.lift_offs_transient
        && a.rhs_evaluations == b.rhs_evaluations
        && a.iwc == b.iwc
        && a.validity() == b.validity()
        && a.error == b.error
}

/// Writes `rows` as a CSV file at `path` (through a temporary file and a rename).
///
/// # Errors
/// [`Error::Io`].
pub fn write_rows(path: &Path, rows: &[RunRow]) -> Result<(), Error> {
    write_table(path, rows)
}

/// Writes `rows` as CSV (serde's columns, a header line) to `path`, through a
/// temporary file renamed over it.
///
/// # Errors
/// [`Error::Io`].
pub fn write_table<R: serde::Serialize>(path: &Path, rows: &[R]) -> Result<(), Error> {
    let tmp = path.with_file_name(format!(".{}.partial", path.file_name().and_then(|n| n.to_str()).unwrap_or("rows.csv")));
    {
        // Made new, never through a link left at its name (rig::private_files).
        let mut w = csv::Writer::from_writer(rig::private_files::create_new(&tmp).map_err(io_err(&tmp))?);
        for r in rows {
            w.serialize(r).map_err(|e| Error::Io { path: tmp.clone(), source: e.into() })?;
        }
        w.flush().map_err(io_err(&tmp))?;
    }
    std::fs::rename(&tmp, path).map_err(io_err(path))
}

/// The journal open for appending, shared by the worker threads.
pub struct Journal {
    path: PathBuf,
    writer: Mutex<csv::Writer<File>>,
}

impl Journal {
    /// Opens `dir/runs.csv` for appending, first rewriting it with `existing` rows
    /// when `rewrite` (a partial last line was dropped); writes the header into a
    /// new file.
    ///
    /// # Errors
    /// [`Error::Io`].
    pub fn open(dir: &Path, existing: &[RunRow], rewrite: bool) -> Result<Self, Error> {
        let path = dir.join(JOURNAL);
        if rewrite {
            write_rows(&path, existing)?;
        }
        let fresh = std::fs::metadata(&path).map(|m| m.len() == 0).unwrap_or(true);
        // Not through a link planted at its name (ELOOP: refused).
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
            .open(&path)
            .map_err(io_err(&path))?;
        let writer = csv::WriterBuilder::new().has_headers(fresh).from_writer(file);
        Ok(Self { path, writer: Mutex::new(writer) })
    }

    /// Appends `row` and flushes it to the file.
    ///
    /// # Errors
    /// [`Error::Io`].
    pub fn append(&self, row: &RunRow) -> Result<(), Error> {
        let mut w = self.writer.lock().unwrap_or_else(|p| p.into_inner());
        w.serialize(row).map_err(|e| Error::Io { path: self.path.clone(), source: e.into() })?;
        // Flushes the csv buffer into the (unbuffered) file: one write per row.
        w.flush().map_err(io_err(&self.path))
    }
}

/// The indices of `m`'s runs (in its shard) not in `rows`, ascending.
pub fn missing(m: &Manifest, rows: &[RunRow]) -> Vec<usize> {
    let done: std::collections::HashSet<usize> = rows.iter().map(|r| r.index).collect();
    m.shard.indices(&m.spec).into_iter().filter(|i| !done.contains(i)).collect()
}
