//! `painleve._painleve.read_csv`, `read_arrow` and `read_mcap`: the tables the CLI
//! writes (CSV; `--format arrow`: `trace.arrow`, `events.arrow`; `--format mcap`:
//! `trace.mcap`), read by the `tables` crate's readers ([`tables::read::read_csv`]
//! with the declarations of the tables the project writes, [`experiments::DECLARED`];
//! [`tables::arrow::read_arrow_batch`]; [`tables::mcap::read_mcap`])
//! without the GIL into one Arrow record batch, whose arrays go to NumPy with
//! their own types: float64 and int64 arrays share the Arrow buffers (no copy),
//! flags are copied into a bool array (Arrow packs them in bits), and text comes
//! coded by its distinct values ([`tables::arrow::coded`]); so `painleve.load`
//! needs neither pandas nor pyarrow.

use std::path::PathBuf;

use arrow_array::{Array, ArrayRef, BooleanArray, Float64Array, Int64Array, RecordBatch, StringArray};
use numpy::{PyArray1, ndarray::ArrayView1};
use pyo3::{
    prelude::*,
    types::{PyDict, PyTuple},
};

use crate::cli::{cli_error, error};

/// `read_csv(path)`: the CSV table at `path` as `{column: array}` in the file's
/// order, of the types its declaration gives when its header is that of a table
/// the project writes (else the types arrow-csv infers; [`tables::read`]):
/// float64, int64 and bool NumPy arrays of shape `(nrows,)`, and each text column
/// as a pair `(values, codes)` ([`batch_to_py`]).
///
/// # Errors
/// `PainleveError` (exit code 2) naming the file, and the line, when it cannot be
/// read, is not UTF-8, ends inside a row (cut off), has a row of another number of
/// cells than its header, a cell not of its column's type, or names a column twice.
#[pyfunction]
pub fn read_csv<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let columns = py
        .detach(|| tables::read::read_csv(&path, experiments::DECLARED).map(|b| columns_of(&b)))
        .map_err(|e| error(py, e.to_string(), 2))?;
    batch_to_py(py, columns.map_err(|e| error(py, format!("cannot read {}: {e}", path.display()), 2))?)
}

/// `read_arrow(path)`: the Arrow IPC file or stream at `path` as `{column: array}`
/// in the file's order, each column of the file's own type (float64, int64,
/// bool, text as [`read_csv`] gives it): the table's CSV read by [`read_csv`]
/// gives the same columns.
///
/// # Errors
/// `PainleveError` when the file cannot be read, is not an Arrow IPC file (or was
/// cut off before its footer), or has a column of another type than Float64,
/// Int64, Boolean or Utf8; the message names the file.
#[pyfunction]
pub fn read_arrow<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let columns = py.detach(|| tables::arrow::read_arrow_batch(&path).map(|b| columns_of(&b))).map_err(|e| cli_error(py, &e.into()))?;
    batch_to_py(py, columns.map_err(|e| error(py, format!("cannot read {}: {e}", path.display()), 1))?)
}

/// `read_mcap(path)`: the tables of an MCAP file the CLI wrote (`--format mcap`),
/// read by [`tables::mcap::read_mcap`] without the GIL, as a list of
/// `(name, {column: array})` in the order of the file's table metadata, each
/// column of its declared type as [`read_csv`] gives it (float64 and int64 arrays
/// over Arrow buffers, bool arrays, text coded by its distinct values). A file
/// cut off (a run killed while writing) gives its whole chunks.
///
/// # Errors
/// `PainleveError` naming the file when it cannot be read, is not MCAP, holds no
/// table of sil-host, a table's channel is not protobuf (a file written before
/// issue 55) or a message is not the one its channel's schema describes.
#[pyfunction]
pub fn read_mcap<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Vec<(String, Bound<'py, PyDict>)>> {
    let tables = py
        .detach(|| {
            tables::mcap::read_mcap(&path).map(|tables| {
                tables
                    .into_iter()
                    .map(|(name, table)| {
                        let arrays = table.columns.into_iter().map(|(n, c)| (n, tables::arrow::array_of(c)));
                        let batch = RecordBatch::try_from_iter(arrays).map_err(|e| e.to_string());
                        (name, batch.and_then(|b| columns_of(&b)))
                    })
                    .collect::<Vec<_>>()
            })
        })
        .map_err(|e| cli_error(py, &e.into()))?;
    tables
        .into_iter()
        .map(|(name, columns)| {
            let columns = columns.map_err(|e| error(py, format!("cannot read {}: table {name}: {e}", path.display()), 1))?;
            Ok((name, batch_to_py(py, columns)?))
        })
        .collect()
}

/// `read_text(path, kind)`: the text of a file of a command's folder, read as
/// `tables::input` reads every input: a regular file only, within the bound of
/// `kind`: `"document"` (a JSON document such as `summary.json`:
/// `tables::input::SUMMARY`, 64 MiB) or `"log"` (`defmt.log`, `report.md`:
/// `tables::input::LOG`, 1 GiB; bytes that are not UTF-8 replaced by U+FFFD).
///
/// # Errors
/// `PainleveError` (exit code 2) naming the file, what it is and the bound: a
/// FIFO, a device, a directory, a file over its bound, one that cannot be
/// read; a `document` that is not UTF-8; an unknown `kind`.
#[pyfunction]
pub fn read_text(py: Python<'_>, path: PathBuf, kind: &str) -> PyResult<String> {
    match kind {
        "document" => py.detach(|| tables::input::read_to_string(&path, tables::input::SUMMARY)),
        "log" => py.detach(|| tables::input::read(&path, tables::input::LOG).map(|b| String::from_utf8_lossy(&b).into_owned())),
        _ => return Err(error(py, format!("read_text: kind `{kind}` is none of document, log"), 2)),
    }
    .map_err(|e| error(py, e.to_string(), 2))
}

/// `declared_tables()`: the declarations of the tables the project writes as CSV
/// ([`experiments::DECLARED`]), each a pair `(names, kinds)`: its column names in
/// order and their kinds (`f64`, `int`, `bool`, `str`), what [`read_csv`]
/// matches a file's header against.
#[pyfunction]
pub fn declared_tables() -> Vec<(Vec<&'static str>, Vec<&'static str>)> {
    experiments::DECLARED.iter().map(|d| (d.names.to_vec(), d.kinds.iter().map(|k| k.name()).collect())).collect()
}

/// The memory of an Arrow array handed to NumPy: the NumPy array's base object,
/// which keeps the Arrow buffer alive as long as the array (and its views) live.
#[pyclass(frozen, module = "painleve._painleve")]
struct ArrowMemory(#[allow(dead_code)] ArrayRef);

/// A column of a record batch ready for NumPy, prepared without the GIL.
enum PyColumn {
    /// Float64 or Int64: the Arrow array, shared.
    Shared(ArrayRef),
    /// Boolean: one byte per flag.
    Bool(Vec<bool>),
    /// Utf8: the distinct values, in order of first appearance, and each row's index into them.
    Text(Vec<String>, ArrayRef),
}

/// The columns of `batch` (columns of Float64, Int64, Boolean or Utf8 without
/// nulls, what the readers give) ready for NumPy: text coded by its distinct values.
///
/// # Errors
/// A column of another type, or text that cannot be coded (more than 2^32 values).
fn columns_of(batch: &RecordBatch) -> Result<Vec<(String, PyColumn)>, String> {
    let schema = batch.schema();
    let mut out = Vec::with_capacity(batch.num_columns());
    for (field, array) in schema.fields().iter().zip(batch.columns()) {
        let any = array.as_any();
        let column = if any.is::<Float64Array>() || any.is::<Int64Array>() {
            PyColumn::Shared(array.clone())
        } else if let Some(a) = any.downcast_ref::<BooleanArray>() {
            PyColumn::Bool(a.values().iter().collect())
        } else if let Some(a) = any.downcast_ref::<StringArray>() {
            let coded = tables::arrow::coded(a).map_err(|e| format!("column `{}`: {e}", field.name()))?;
            let values = coded
                .values()
                .as_any()
                .downcast_ref::<StringArray>()
                .map(|v| v.iter().map(|s| s.unwrap_or_default().to_string()).collect());
            PyColumn::Text(values.unwrap_or_default(), std::sync::Arc::new(coded.keys().clone()))
        } else {
            return Err(format!("column `{}` is {}, not Float64, Int64, Boolean or Utf8", field.name(), array.data_type()));
        };
        out.push((field.name().clone(), column));
    }
    Ok(out)
}

/// The NumPy array of shape `(n,)` over the values of the primitive Arrow array
/// `array` (float64, int64, or the uint32 codes of text), sharing its memory.
fn shared<'py, T: numpy::Element>(py: Python<'py>, values: &[T], array: ArrayRef) -> PyResult<Bound<'py, PyAny>> {
    let view = ArrayView1::from(values);
    let owner = Bound::new(py, ArrowMemory(array))?;
    // SAFETY: `owner` holds the Arrow array (its `Arc`'d buffer), so the memory
    // `view` points into lives as long as the NumPy array whose base it becomes;
    // an Arrow buffer is never reallocated.
    Ok(unsafe { PyArray1::borrow_from_array(&view, owner.into_any()) }.into_any())
}

/// A table read from a file as `{column: array}` in its order: float64 and int64
/// NumPy arrays over the Arrow buffers, bool arrays, and each text column as a
/// pair `(values, codes)`: its distinct values (a list of `str`, in order of
/// first appearance) and a uint32 array of indices into them, one per row, which
/// `painleve` turns into a NumPy `str` array (`np.array(values, dtype=str)[codes]`,
/// the array of every cell's text without a Python string per row: a trace's
/// `mode` has three values in 300 000 rows).
fn batch_to_py(py: Python<'_>, columns: Vec<(String, PyColumn)>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (name, column) in columns {
        let value = match column {
            PyColumn::Shared(array) => {
                if let Some(a) = array.as_any().downcast_ref::<Float64Array>() {
                    shared(py, a.values(), array.clone())?
                } else if let Some(a) = array.as_any().downcast_ref::<Int64Array>() {
                    shared(py, a.values(), array.clone())?
                } else {
                    continue;
                }
            }
            PyColumn::Bool(v) => PyArray1::from_vec(py, v).into_any(),
            PyColumn::Text(values, codes) => {
                let keys = codes.as_any().downcast_ref::<arrow_array::UInt32Array>().map(|k| &k.values()[..]);
                let codes_py = shared(py, keys.unwrap_or(&[]), codes.clone())?;
                PyTuple::new(py, [values.into_pyobject(py)?.into_any(), codes_py])?.into_any()
            }
        };
        d.set_item(name, value)?;
    }
    Ok(d)
}
