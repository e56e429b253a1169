//! The run an animation draws: the columns of a `trace.csv` (written by
//! `sil-host simulate` or `sil-host run`) that place the arm and its contact, and
//! the impacts of an `events.csv` (`simulate` only).

use std::path::Path;

use crate::error::Error;

/// An impact of the plant (`events.csv`, a `touchdown` or an
/// `impact_without_collision`): when, and the impulse on the tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Time, s.
    pub t: f64,
    /// Tangential impulse on the tip, N s.
    pub impulse_t: f64,
    /// Normal impulse on the tip, N s.
    pub impulse_n: f64,
}

/// A run sampled in time: one entry per row of its `trace.csv`, every vector of
/// the same length, times ascending.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ArmTrace {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Base joint angle theta1 from the downward vertical, rad.
    pub theta1: Vec<f64>,
    /// Second link's angle theta2 from the downward vertical, rad.
    pub theta2: Vec<f64>,
    /// The tip's tangential position z_t, m.
    pub z_t: Vec<f64>,
    /// The tip's normal position z_n (the belt at `-H`), m.
    pub z_n: Vec<f64>,
    /// Tangential contact force on the tip f_t, N.
    pub f_t: Vec<f64>,
    /// Normal contact force on the tip f_n, N.
    pub f_n: Vec<f64>,
    /// The contact mode (`flight`, `sliding`, `sticking`, ...).
    pub mode: Vec<String>,
    /// The controller's target z_t*, m (a closed-loop `trace.csv`'s `z_t_ref`; `None` in open loop).
    pub z_t_ref: Option<Vec<f64>>,
    /// The impacts, in time order (empty without an `events.csv`).
    pub impacts: Vec<Impact>,
}

impl ArmTrace {
    /// The index of the sample nearest to time `t` (s): the first of two equally
    /// near; 0 for an empty trace.
    pub fn index_at(&self, t: f64) -> usize {
        let i = self.t.partition_point(|s| *s < t);
        match (i.checked_sub(1), self.t.get(i)) {
            (Some(j), Some(after)) if t - self.t[j] <= after - t => j,
            (Some(j), None) => j,
            _ => i,
        }
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether the trace has no sample.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// Reads `trace_csv` (columns `t`, `theta1`, `theta2`, `z_t`, `z_n`, `f_t`,
/// `f_n`, `mode`, and `z_t_ref` if there) and, if given, the impacts of
/// `events_csv` (columns `t`, `kind`, `impulse_t`, `impulse_n`).
///
/// # Errors
/// [`Error::Io`] when a file cannot be read; [`Error::BadInput`] naming the
/// file and line for a missing column, a value that is not a finite number, times
/// that go back, or a trace with no row.
pub fn read(trace_csv: &Path, events_csv: Option<&Path>) -> Result<ArmTrace, Error> {
    let bad = |path: &Path, what: String| Error::bad_input(format!("{}: {what}", path.display()));
    let mut trace = ArmTrace::default();
    let mut refs = Vec::new();
    let table = Table::open(trace_csv, &["t", "theta1", "theta2", "z_t", "z_n", "f_t", "f_n", "mode"], &["z_t_ref"])?;
    for (line, row) in table.rows() {
        let row = row?;
        let num = |k: usize| table.number(&row, k, line);
        let t = num(0)?;
        if trace.t.last().is_some_and(|last| t < *last) {
            return Err(bad(trace_csv, format!("line {line}: time {t} s goes back")));
        }
        trace.t.push(t);
        trace.theta1.push(num(1)?);
        trace.theta2.push(num(2)?);
        trace.z_t.push(num(3)?);
        trace.z_n.push(num(4)?);
        trace.f_t.push(num(5)?);
        trace.f_n.push(num(6)?);
        trace.mode.push(row.get(table.columns[7]).unwrap_or_default().to_string());
        if table.columns.len() > 8 {
            refs.push(num(8)?);
        }
    }
    if trace.is_empty() {
        return Err(bad(trace_csv, "no rows".into()));
    }
    if !refs.is_empty() {
        trace.z_t_ref = Some(refs);
    }
    if let Some(events) = events_csv {
        let table = Table::open(events, &["t", "kind", "impulse_t", "impulse_n"], &[])?;
        for (line, row) in table.rows() {
            let row = row?;
            let kind = row.get(table.columns[1]).unwrap_or_default();
            if kind == "touchdown" || kind == "impact_without_collision" {
                let num = |k: usize| table.number(&row, k, line);
                trace.impacts.push(Impact { t: num(0)?, impulse_t: num(2)?, impulse_n: num(3)? });
            }
        }
    }
    Ok(trace)
}

/// A CSV file and the positions of the columns asked for (the required ones,
/// then those of the optional ones it has).
struct Table {
    path: std::path::PathBuf,
    reader: std::cell::RefCell<csv::Reader<tables::input::BoundedReader<std::fs::File>>>,
    columns: Vec<usize>,
    names: Vec<String>,
}

impl Table {
    fn open(path: &Path, required: &[&str], optional: &[&str]) -> Result<Self, Error> {
        let io = |e: csv::Error| match e.into_kind() {
            csv::ErrorKind::Io(source) => Error::Io { path: path.to_path_buf(), source },
            other => Error::bad_input(format!("{}: {other:?}", path.display())),
        };
        // A regular file within the tables' bound (tables::input, issue 80).
        let file = tables::input::reader(path, tables::input::TABLE).map_err(|e| match e {
            tables::input::InputError::Unreadable { source, .. } => Error::Io { path: path.to_path_buf(), source },
            other => Error::bad_input(other.to_string()),
        })?;
        let mut reader = csv::Reader::from_reader(file);
        let header = reader.headers().map_err(io)?.clone();
        let find = |name: &str| header.iter().position(|h| h == name);
        let mut columns = Vec::new();
        let mut names = Vec::new();
        for name in required {
            let k = find(name).ok_or_else(|| Error::bad_input(format!("{}: no column `{name}`", path.display())))?;
            columns.push(k);
            names.push((*name).to_string());
        }
        for (name, k) in optional.iter().filter_map(|n| find(n).map(|k| (n, k))) {
            columns.push(k);
            names.push((*name).to_string());
        }
        Ok(Self { path: path.to_path_buf(), reader: std::cell::RefCell::new(reader), columns, names })
    }

    /// The records with their line numbers (the header is line 1).
    fn rows(&self) -> impl Iterator<Item = (usize, Result<csv::StringRecord, Error>)> + '_ {
        (2..).map_while(move |line| {
            let mut record = csv::StringRecord::new();
            match self.reader.borrow_mut().read_record(&mut record) {
                Ok(true) => Some((line, Ok(record))),
                Ok(false) => None,
                Err(e) => Some((line, Err(Error::bad_input(format!("{}: line {line}: {e}", self.path.display()))))),
            }
        })
    }

    /// The `k`th asked-for column of `row` (on `line`) as a finite number.
    fn number(&self, row: &csv::StringRecord, k: usize, line: usize) -> Result<f64, Error> {
        let text = row.get(self.columns[k]).unwrap_or_default();
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => {
                Err(Error::bad_input(format!("{}: line {line}: `{}` is `{text}`, not a finite number", self.path.display(), self.names[k])))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_columns_and_the_impacts_and_finds_the_nearest_sample() {
        let dir = tempfile::tempdir().unwrap();
        let trace = dir.path().join("trace.csv");
        let events = dir.path().join("events.csv");
        std::fs::write(
            &trace,
            "t,theta1,x,theta2,z_t,z_n,f_t,f_n,mode\n0.0,0.1,9,0.2,0.3,-0.3,0.0,0.0,flight\n0.001,0.11,9,0.21,0.3,-0.3,-1,2,sliding\n",
        )
        .unwrap();
        std::fs::write(&events, "t,kind,impulse_t,impulse_n\n0.0005,touchdown,-0.2,0.8\n0.0007,lift_off,0,0\n").unwrap();
        let a = read(&trace, Some(&events)).unwrap();
        assert_eq!(a.theta2, [0.2, 0.21]);
        assert_eq!(a.mode, ["flight", "sliding"]);
        assert_eq!(a.impacts, [Impact { t: 0.0005, impulse_t: -0.2, impulse_n: 0.8 }]);
        assert!(a.z_t_ref.is_none());
        assert_eq!((a.index_at(-1.0), a.index_at(0.0004), a.index_at(0.0006), a.index_at(5.0)), (0, 0, 1, 1));
    }

    #[test]
    fn a_missing_column_or_a_bad_number_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let trace = dir.path().join("trace.csv");
        std::fs::write(&trace, "t,theta1\n0,0\n").unwrap();
        assert!(read(&trace, None).unwrap_err().to_string().contains("no column `theta2`"));
        std::fs::write(&trace, "t,theta1,theta2,z_t,z_n,f_t,f_n,mode\n0,0,nan,0,0,0,0,flight\n").unwrap();
        let e = read(&trace, None).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("`theta2` is `nan`"), "{e}");
        assert!(read(&dir.path().join("none.csv"), None).is_err());
    }
}
