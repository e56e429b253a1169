//! The long tables as Arrow IPC files (`--format arrow`): `trace.arrow`,
//! `events.arrow`, the columns and values of the CSV tables they replace, typed.
//!
//! The Arrow IPC *file* format (also called Feather v2; Apache Arrow columnar
//! format 1.0, metadata version 5, no compression) is what pandas
//! (`pandas.read_feather`, with pyarrow), polars (`polars.read_ipc`), pyarrow
//! (`pyarrow.ipc.open_file`), R's `arrow` and DuckDB load directly, without
//! parsing text: a 300 s trace at 1 ms is 34 MB against 66 MB of CSV, and
//! written without formatting a single float. Writing and reading are the
//! `arrow-ipc` crate's; this module maps the rows onto its columns.
//!
//! Columns: the row type's declaration ([`schema`]): `f64` fields are `Float64`
//! (the value's bits, NaN and infinities included), text `Utf8`, flags
//! `Boolean`, integers `Int64`; none is nullable. Rows go out in record batches
//! of at most [`BATCH_ROWS`] rows ([`ArrowFile`]; [`StreamedArrowFile`] as the caller flushes), so a writer
//! holds at most one batch in memory however long the run. [`read_arrow_batch`]
//! reads a file (or stream, or a file cut off before its footer) back as one record batch (the Python package hands its
//! arrays to NumPy), [`read_arrow`] as a [`Table`].

use std::{path::Path, sync::Arc};

#[cfg(feature = "read")]
use arrow_array::{Array, DictionaryArray, RecordBatch, types::UInt32Type};
use arrow_array::{ArrayRef, BooleanArray, Float64Array, Int64Array, StringArray};
use arrow_schema::{ArrowError, DataType, Field, Schema};

#[cfg(feature = "read")]
use crate::Table;
use crate::{Column, declared::Declaration, declared::Kind, error::Error};

#[cfg(feature = "read")]
mod read;
#[cfg(all(test, feature = "read"))]
mod tests;
mod write;

#[cfg(feature = "read")]
pub use read::{read_arrow, read_arrow_batch};
pub use write::{ArrowFile, ArrowThread, StreamedArrowFile};

/// Rows per record batch: 64 Ki rows (about 7 MB of a 14-column trace).
pub const BATCH_ROWS: usize = 1 << 16;

/// The error of an Arrow file being written, as the CLI reports it: the file and what failed.
pub(crate) fn arrow_err(path: &Path) -> impl Fn(ArrowError) -> Error + '_ {
    move |e| Error::Io { path: path.to_path_buf(), source: arrow_io(e) }
}

/// The error of an Arrow file being read, as the CLI reports it: the file and what failed.
#[cfg(feature = "read")]
pub(crate) fn arrow_read_err(path: &Path) -> impl Fn(ArrowError) -> Error + '_ {
    move |e| Error::Unreadable { path: path.to_path_buf(), source: arrow_io(e) }
}

/// An Arrow error as an I/O error: the OS's own, or the Arrow error's words.
fn arrow_io(e: ArrowError) -> std::io::Error {
    match e {
        ArrowError::IoError(_, io) => io,
        other => std::io::Error::other(other.to_string()),
    }
}

/// The Arrow type of a column of kind `kind`: `Float64`, `Utf8`, `Boolean` or `Int64`.
pub fn data_type(kind: Kind) -> DataType {
    match kind {
        Kind::F64 => DataType::Float64,
        Kind::Str => DataType::Utf8,
        Kind::Bool => DataType::Boolean,
        Kind::Int => DataType::Int64,
    }
}

/// The Arrow schema of a declared table: one non-nullable field per column, in
/// order, of its kind's type ([`data_type`]).
pub fn schema(declaration: Declaration) -> Schema {
    let field = |(name, kind): (&&str, &Kind)| Field::new(*name, data_type(*kind), false);
    Schema::new(declaration.names.iter().zip(declaration.kinds).map(field).collect::<Vec<_>>())
}

/// A column as an Arrow array (the values move; strings are copied once).
pub fn array_of(c: Column) -> ArrayRef {
    match c {
        Column::F64(v) => Arc::new(Float64Array::from(v)),
        Column::I64(v) => Arc::new(Int64Array::from(v)),
        Column::Bool(v) => Arc::new(BooleanArray::from(v)),
        Column::Str(v) => Arc::new(StringArray::from_iter_values(v)),
    }
}

/// `batch` with its columns as the tables carry them, without null: a null
/// float is NaN, a null text `""`. A null integer or flag is an error (`Err`:
/// the column and the 0-based row) when `strict`; otherwise the integer column
/// becomes floats (NaN there) and the flag column text (`true`, `false`, `""`),
/// as a reader of an undeclared CSV file types them. Any type other than
/// `Float64`, `Int64`, `Boolean`, `Utf8` is an error. The fields of the result
/// are not nullable.
///
/// # Errors
/// `(column, Some(row), message)` for a refused null, `(column, None, message)`
/// for a refused type.
#[cfg(feature = "read")]
pub(crate) fn settle(batch: &RecordBatch, strict: bool) -> Result<RecordBatch, (String, Option<usize>, String)> {
    let mut fields = Vec::with_capacity(batch.num_columns());
    let mut arrays = Vec::with_capacity(batch.num_columns());
    for (field, array) in batch.schema().fields().iter().zip(batch.columns()) {
        let name = field.name();
        let first_null = || (0..array.len()).find(|&i| array.is_null(i));
        let array: ArrayRef = match array.data_type() {
            DataType::Float64 | DataType::Utf8 | DataType::Int64 | DataType::Boolean if array.null_count() == 0 => array.clone(),
            DataType::Float64 => {
                let a = array.as_any().downcast_ref::<Float64Array>().ok_or_else(|| bad_type(name, array))?;
                Arc::new(Float64Array::from_iter_values(a.iter().map(|x| x.unwrap_or(f64::NAN))))
            }
            DataType::Utf8 => {
                let a = array.as_any().downcast_ref::<StringArray>().ok_or_else(|| bad_type(name, array))?;
                Arc::new(StringArray::from_iter_values(a.iter().map(|s| s.unwrap_or(""))))
            }
            DataType::Int64 | DataType::Boolean if strict => {
                let what = if *array.data_type() == DataType::Int64 { "integer" } else { "flag" };
                return Err((name.clone(), first_null(), format!("an empty cell (null) in the {what} column `{name}`")));
            }
            DataType::Int64 => {
                let a = array.as_any().downcast_ref::<Int64Array>().ok_or_else(|| bad_type(name, array))?;
                Arc::new(Float64Array::from_iter_values(a.iter().map(|x| x.map_or(f64::NAN, |i| i as f64))))
            }
            DataType::Boolean => {
                let a = array.as_any().downcast_ref::<BooleanArray>().ok_or_else(|| bad_type(name, array))?;
                Arc::new(StringArray::from_iter_values(a.iter().map(|b| b.map_or("", |b| if b { "true" } else { "false" }))))
            }
            _ => return Err(bad_type(name, array)),
        };
        fields.push(Field::new(name, array.data_type().clone(), false));
        arrays.push(array);
    }
    RecordBatch::try_new_with_options(
        Arc::new(Schema::new(fields)),
        arrays,
        &arrow_array::RecordBatchOptions::new().with_row_count(Some(batch.num_rows())),
    )
    .map_err(|e| (String::new(), None, e.to_string()))
}

/// The error of a column of a type the tables never hold.
#[cfg(feature = "read")]
fn bad_type(name: &str, array: &ArrayRef) -> (String, Option<usize>, String) {
    (name.to_string(), None, format!("column `{name}` is {}, not Float64, Int64, Boolean or Utf8", array.data_type()))
}

/// The [`Table`] of a record batch whose columns are `Float64`, `Int64`,
/// `Boolean` or `Utf8`, each without null (what [`read_arrow_batch`] and
/// [`crate::read::read_csv`] give): its columns in order, the values copied.
///
/// # Errors
/// The message naming the column of another type or with nulls.
#[cfg(feature = "read")]
pub fn table_of(batch: &RecordBatch) -> Result<Table, String> {
    let mut columns = Vec::with_capacity(batch.num_columns());
    for (field, array) in batch.schema().fields().iter().zip(batch.columns()) {
        let name = field.name();
        if array.null_count() > 0 {
            return Err(format!("column `{name}` has nulls"));
        }
        let any = array.as_any();
        let column = if let Some(a) = any.downcast_ref::<Float64Array>() {
            Column::F64(a.values().to_vec())
        } else if let Some(a) = any.downcast_ref::<Int64Array>() {
            Column::I64(a.values().to_vec())
        } else if let Some(a) = any.downcast_ref::<BooleanArray>() {
            Column::Bool(a.values().iter().collect())
        } else if let Some(a) = any.downcast_ref::<StringArray>() {
            Column::Str(a.iter().map(|s| s.unwrap_or_default().to_string()).collect())
        } else {
            return Err(bad_type(name, array).2);
        };
        columns.push((name.clone(), column));
    }
    Ok(Table { columns })
}

/// A text column coded by its distinct values (Arrow's dictionary encoding, by
/// `arrow-cast`): the keys, one per row, index the values, the distinct texts in
/// order of first appearance. What the Python package turns into a NumPy `str`
/// array without a Python string per row (a trace's `mode` has three values in
/// 300 000 rows).
///
/// # Errors
/// The cast's error (more than 2^32 distinct values).
#[cfg(feature = "read")]
pub fn coded(text: &StringArray) -> Result<DictionaryArray<UInt32Type>, ArrowError> {
    let dictionary = DataType::Dictionary(Box::new(DataType::UInt32), Box::new(DataType::Utf8));
    let cast = arrow_cast::cast(text, &dictionary)?;
    cast.as_any()
        .downcast_ref::<DictionaryArray<UInt32Type>>()
        .cloned()
        .ok_or_else(|| ArrowError::CastError("text to a dictionary of u32 keys".into()))
}
