//! `painleve._painleve.read_csv` and `read_arrow`: the tables the CLI writes (CSV;
//! `--format arrow`: `trace.arrow`, `events.arrow`), read by the experiments' own
//! readers ([`experiments::table::read`], [`experiments::table::arrow`]) without the
//! GIL, as NumPy arrays; so `painleve.load` needs neither pandas nor pyarrow.
//! Both give a table the column types of its CSV
//! ([`experiments::table::read`]'s rule), so the formats read alike.

use std::path::PathBuf;

use experiments::table::{arrow::read_arrow as arrow, read};
use pyo3::{prelude::*, types::PyDict};

use crate::{
    cli::{cli_error, error},
    convert::table_to_py,
};

/// `read_csv(path)`: the CSV table at `path` as `{column: array}` in the file's
/// order (float64, int64, uint64 and bool NumPy arrays, lists of `str` for text),
/// typed by [`experiments::table::read`]'s rule.
///
/// # Errors
/// `PainleveError` (exit code 2) naming the file, and the line, when it cannot be
/// read, is not UTF-8, ends inside a row (cut off), has a row of another number of
/// cells than its header, or names a column twice.
#[pyfunction]
pub fn read_csv<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let table = py.detach(|| read::read_csv(&path)).map_err(|e| error(py, e.to_string(), 2))?;
    table_to_py(py, table)
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
    let table = py.detach(|| arrow(&path).map(read::as_read_from_csv)).map_err(|e| cli_error(py, &e))?;
    table_to_py(py, table)
}
