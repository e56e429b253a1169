//! `painleve._painleve.read_csv` and `read_arrow`: the tables the CLI writes (CSV;
//! `--format arrow`: `trace.arrow`, `events.arrow`), read by the experiments' own
//! readers ([`experiments::table::read`], [`experiments::table::arrow`]) without the
//! GIL, as NumPy arrays; so `painleve.load` needs neither pandas nor pyarrow.
//! Both give a table the column types of its CSV
//! ([`experiments::table::read`]'s rule), so the formats read alike.

use std::{collections::HashMap, path::PathBuf};

use experiments::table::{Column, Table, arrow::read_arrow as arrow, read};
use numpy::PyArray1;
use pyo3::{
    prelude::*,
    types::{PyDict, PyTuple},
};

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
    coded_to_py(py, table)
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
    coded_to_py(py, table)
}

/// A table read from a file as `{column: array}` ([`table_to_py`]), but each
/// text column as a pair `(values, codes)`: its distinct values (a list of
/// `str`, in order of first appearance) and a uint32 array of indices into them,
/// one per row, which `painleve` turns into a NumPy `str` array
/// (`np.array(values, dtype=str)[codes]`, the array of every cell's text without
/// a Python string per row: a trace's `mode` has three values in 300 000 rows).
fn coded_to_py<'py>(py: Python<'py>, t: Table) -> PyResult<Bound<'py, PyDict>> {
    let (mut text, mut rest) = (Vec::new(), Vec::new());
    for (i, (name, col)) in t.columns.into_iter().enumerate() {
        match col {
            Column::Str(cells) => {
                let mut index: HashMap<String, u32> = HashMap::new();
                let mut values: Vec<String> = Vec::new();
                let codes: Vec<u32> = cells
                    .into_iter()
                    .map(|c| {
                        *index.entry(c).or_insert_with_key(|k| {
                            values.push(k.clone());
                            (values.len() - 1) as u32
                        })
                    })
                    .collect();
                text.push((i, name, values, codes));
            }
            other => rest.push((i, name, other)),
        }
    }
    let d = table_to_py(py, Table { columns: Vec::new() })?;
    let mut rest = rest.into_iter().peekable();
    let mut text = text.into_iter().peekable();
    // In the file's column order.
    loop {
        let next_text = text.peek().map(|(i, ..)| *i);
        let next_rest = rest.peek().map(|(i, ..)| *i);
        match (next_text, next_rest) {
            (Some(a), b) if b.is_none_or(|b| a < b) => {
                let Some((_, name, values, codes)) = text.next() else { break };
                let pair = PyTuple::new(py, [values.into_pyobject(py)?.into_any(), PyArray1::from_vec(py, codes).into_any()])?;
                d.set_item(name, pair)?;
            }
            (_, Some(_)) => {
                let Some((_, name, col)) = rest.next() else { break };
                for (k, v) in table_to_py(py, Table { columns: vec![(name, col)] })?.iter() {
                    d.set_item(k, v)?;
                }
            }
            _ => break,
        }
    }
    Ok(d)
}
