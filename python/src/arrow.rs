//! `painleve._painleve.read_arrow`: an Arrow IPC table the CLI wrote
//! (`--format arrow`: `trace.arrow`, `events.arrow`), read by the experiments'
//! own reader ([`experiments::table::arrow`]), so `painleve.load` needs no pyarrow.

use std::path::PathBuf;

use experiments::table::arrow::read_arrow as read;
use pyo3::{prelude::*, types::PyDict};

use crate::{cli::cli_error, convert::table_to_py};

/// `read_arrow(path)`: the Arrow IPC file at `path` as `{column: array}` in the
/// file's order (float64, int64 and bool NumPy arrays, lists of `str` for text),
/// the columns `painleve.read_csv` gives for the same table as CSV.
///
/// # Errors
/// `PainleveError` when the file cannot be read, is not an Arrow IPC file (or was
/// cut off before its footer), or has a column of another type than Float64,
/// Int64, Boolean or Utf8; the message names the file.
#[pyfunction]
pub fn read_arrow<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let table = py.detach(|| read(&path)).map_err(|e| cli_error(py, &e))?;
    table_to_py(py, table)
}
