//! Rust values into Python: JSON-like documents (the CLI's `summary.json` types,
//! through serde) into dicts and lists, tables into dicts of NumPy arrays, and the
//! result dict every function returns to `painleve`'s Python layer.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::{
    exceptions::PyRuntimeError,
    prelude::*,
    types::{PyDict, PyList, PyString},
};
use serde::Serialize;
use std::collections::HashMap;

use tables::{Column, ColumnRows, Table};

/// Any serialisable value as Python objects, through its JSON text (what the
/// CLI writes to its JSON files, in its fields' order), read by Python's `json`.
pub fn to_py<'py, T: Serialize + ?Sized>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| PyRuntimeError::new_err(format!("cannot convert a result: {e}")))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A table as `{column: array}`: float64, int64, uint64 or bool NumPy arrays, and
/// lists of `str` for text columns (the Python layer makes them NumPy string arrays).
pub fn table_to_py<'py>(py: Python<'py>, t: Table) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, col) in t.columns {
        d.set_item(name, column_to_py(py, col)?)?;
    }
    Ok(d)
}

/// A column as a NumPy array of shape `(n,)` (float64, int64, uint64 or bool; the
/// `Vec` becomes the array's memory, no copy), or a list of `str` for text.
pub fn column_to_py<'py>(py: Python<'py>, col: Column) -> PyResult<Bound<'py, PyAny>> {
    Ok(match col {
        Column::F64(v) => PyArray1::from_vec(py, v).into_any(),
        Column::I64(v) => PyArray1::from_vec(py, v).into_any(),
        Column::U64(v) => PyArray1::from_vec(py, v).into_any(),
        Column::Bool(v) => PyArray1::from_vec(py, v).into_any(),
        Column::Str(v) => {
            // One Python string per distinct value (a mode, a kind: a few per
            // column), shared by its rows.
            let mut seen: HashMap<String, Bound<'py, PyString>> = HashMap::new();
            let items = v.into_iter().map(|s| seen.entry(s).or_insert_with_key(|k| PyString::new(py, k)).clone()).collect::<Vec<_>>();
            PyList::new(py, items)?.into_any()
        }
    })
}

/// Rows of a type that derives `serde::Serialize` as a table dict ([`Table::of_rows`], [`table_to_py`]).
pub fn rows_to_py<'py, 'a, T: Serialize + 'a>(py: Python<'py>, rows: impl IntoIterator<Item = &'a T>) -> PyResult<Bound<'py, PyDict>> {
    let t = Table::of_rows(rows).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    table_to_py(py, t)
}

/// Rows of a type that declares its columns (the long tables: the traces and
/// events) as a table dict ([`Table::of_columns`], [`table_to_py`]).
pub fn columns_to_py<'py, T: ColumnRows>(py: Python<'py>, rows: &[T]) -> Bound<'py, PyDict> {
    // Only fails on a dict's `set_item`, which cannot fail for str keys.
    table_to_py(py, Table::of_columns(rows)).unwrap_or_else(|_| PyDict::new(py))
}

/// Points `(x, y)` as an `(n, 2)` float64 array.
pub fn points_to_py<'py>(py: Python<'py>, points: &[(f64, f64)]) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f64> = points.iter().flat_map(|&(x, y)| [x, y]).collect();
    Ok(PyArray1::from_vec(py, flat).reshape([points.len(), 2])?.into_any())
}

/// The dict a function returns to the Python layer (`painleve.Result`):
/// `command`, `summary` (the CLI's summary document), `tables` (name: columns,
/// named as the CLI's CSV files without `.csv`), `extras`, `validity` (the
/// validity counters summed over everything simulated, or `None` for the
/// analyses that simulate nothing), `violations` (the model violations in
/// words, `None` when valid), `failure` (the CLI's error message when it would
/// exit 1 after writing, else `None`) and `exit_code` (the CLI's: 0 or 1).
pub struct Outcome<'py> {
    dict: Bound<'py, PyDict>,
    tables: Bound<'py, PyDict>,
    extras: Bound<'py, PyDict>,
}

impl<'py> Outcome<'py> {
    /// An outcome of `command` with its summary.
    pub fn new(py: Python<'py>, command: &str, summary: Bound<'py, PyAny>) -> PyResult<Self> {
        let (dict, tables, extras) = (PyDict::new(py), PyDict::new(py), PyDict::new(py));
        dict.set_item("command", command)?;
        dict.set_item("summary", summary)?;
        dict.set_item("tables", &tables)?;
        dict.set_item("extras", &extras)?;
        dict.set_item("validity", py.None())?;
        dict.set_item("violations", py.None())?;
        dict.set_item("failure", py.None())?;
        dict.set_item("exit_code", 0)?;
        Ok(Self { dict, tables, extras })
    }

    /// Adds the table `name`.
    pub fn table(self, name: &str, table: Bound<'py, PyDict>) -> PyResult<Self> {
        self.tables.set_item(name, table)?;
        Ok(self)
    }

    /// Adds the extra `name`.
    pub fn extra(self, name: &str, value: Bound<'py, PyAny>) -> PyResult<Self> {
        self.extras.set_item(name, value)?;
        Ok(self)
    }

    /// Sets the validity counters.
    pub fn validity(self, v: &plant::Validity) -> PyResult<Self> {
        let py = self.dict.py();
        self.dict.set_item("validity", to_py(py, v)?)?;
        if !v.is_valid() {
            self.dict.set_item("violations", v.describe_violations())?;
        }
        Ok(self)
    }

    /// Sets the failure (the CLI would exit with `exit_code` after writing).
    pub fn failure(self, message: Option<String>, exit_code: i32) -> PyResult<Self> {
        if let Some(m) = message {
            self.dict.set_item("failure", m)?;
            self.dict.set_item("exit_code", exit_code)?;
        }
        Ok(self)
    }

    /// The dict.
    pub fn done(self) -> Bound<'py, PyDict> {
        self.dict
    }
}
