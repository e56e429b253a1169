//! `painleve._painleve.read_csv` and `read_arrow`: the tables the CLI writes (CSV;
//! `--format arrow`: `trace.arrow`, `events.arrow`), read by the experiments' own
//! readers ([`tables::read`], [`tables::arrow`]) without the
//! GIL, as NumPy arrays; so `painleve.load` needs neither pandas nor pyarrow.
//! Both give a table the column types of its CSV
//! ([`tables::read`]'s rule), so the formats read alike.

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::{
    prelude::*,
    types::{PyDict, PyTuple},
};
use tables::{
    arrow::read_arrow as arrow,
    read::{self, ReadColumn},
};

use crate::{
    cli::{cli_error, error},
    convert::column_to_py,
};

/// `read_csv(path)`: the CSV table at `path` as `{column: array}` in the file's
/// order: float64, int64, uint64 and bool NumPy arrays of shape `(nrows,)`, and
/// each text column as a pair `(values, codes)` ([`coded_to_py`]), typed by
/// [`tables::read`]'s rule; read by [`read::read_csv_coded`] without
/// the GIL (in chunks of lines on rayon's threads), each array's memory the
/// reader's `Vec` (no copy).
///
/// # Errors
/// `PainleveError` (exit code 2) naming the file, and the line, when it cannot be
/// read, is not UTF-8, ends inside a row (cut off), has a row of another number of
/// cells than its header, or names a column twice.
#[pyfunction]
pub fn read_csv<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let columns = py.detach(|| read::read_csv_coded(&path)).map_err(|e| error(py, e.to_string(), 2))?;
    coded_to_py(py, columns)
}

/// `read_arrow(path)`: the Arrow IPC file or stream at `path` as `{column: array}`
/// in the file's order, with the columns [`read_csv`] gives for the same table
/// as CSV ([`read::as_read_from_csv`]: a text column of empty strings is float64
/// NaN; every column of a table without rows is an empty float64 array).
///
/// # Errors
/// `PainleveError` when the file cannot be read, is not an Arrow IPC file (or was
/// cut off before its footer), or has a column of another type than Float64,
/// Int64, Boolean or Utf8; the message names the file.
#[pyfunction]
pub fn read_arrow<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let columns = py
        .detach(|| arrow(&path).map(|t| read::as_read_from_csv(t).columns.into_iter().map(|(name, c)| (name, ReadColumn::of(c))).collect()))
        .map_err(|e| cli_error(py, &e.into()))?;
    coded_to_py(py, columns)
}

/// A table read from a file as `{column: array}` in its order ([`column_to_py`]),
/// but each text column as a pair `(values, codes)`: its distinct values (a list
/// of `str`, in order of first appearance) and a uint32 array of indices into
/// them, one per row, which `painleve` turns into a NumPy `str` array
/// (`np.array(values, dtype=str)[codes]`, the array of every cell's text without
/// a Python string per row: a trace's `mode` has three values in 300 000 rows).
fn coded_to_py(py: Python<'_>, columns: Vec<(String, ReadColumn)>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (name, col) in columns {
        match col {
            ReadColumn::Values(col) => d.set_item(name, column_to_py(py, col)?)?,
            ReadColumn::Text { values, codes } => {
                let pair = PyTuple::new(py, [values.into_pyobject(py)?.into_any(), PyArray1::from_vec(py, codes).into_any()])?;
                d.set_item(name, pair)?;
            }
        }
    }
    Ok(d)
}
