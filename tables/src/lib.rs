//! The project's tables, one layer for every format: rows become columns once
//! ([`Table`], [`Column`]), and the Arrow files ([`arrow`]) and the Python
//! package's NumPy arrays read those columns; CSV ([`csv`]) is written row by row
//! from the same row types, with the same columns in the same order; MCAP
//! ([`mcap`]) splits a table's columns into signal groups, a channel each.
//!
//! Two ways from rows to a [`Table`]: the long tables' row types (`trace`,
//! `events`, the closed-loop trace) declare their columns with [`csv_row!`]
//! ([`ColumnRows`], typed, no per-cell dispatch); any other row type that derives
//! `serde::Serialize` goes through [`Table::of_rows`] ([`rows`], the cells the
//! `csv` crate would write). [`read`] reads a CSV table back, with the column
//! types a reader of the file sees (and gives an Arrow table the same types).
//!
//! Feature `files` (on by default): the Arrow and MCAP files and the CSV reader.
//! Without it the crate holds the declarations, the rows-to-columns layer and the
//! CSV writer (what `rig` and `analyses` need to declare their row types).
//! Errors: [`Error`].

#![warn(missing_docs)]

#[cfg(feature = "files")]
pub mod arrow;
pub mod csv;
pub mod error;
pub mod mcap;
#[cfg(feature = "files")]
pub mod read;
pub mod rows;

pub use error::Error;
use serde::Serialize;

pub use rows::{ColumnError, TableBuilder};

/// The values of one column: a table's cells of one field, typed.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// Floats (NaN for empty cells).
    F64(Vec<f64>),
    /// Signed integers.
    I64(Vec<i64>),
    /// Unsigned integers too large for `i64`.
    U64(Vec<u64>),
    /// Booleans.
    Bool(Vec<bool>),
    /// Strings (`""` for empty cells).
    Str(Vec<String>),
}

impl Column {
    /// The number of values.
    pub fn len(&self) -> usize {
        match self {
            Self::F64(v) => v.len(),
            Self::I64(v) => v.len(),
            Self::U64(v) => v.len(),
            Self::Bool(v) => v.len(),
            Self::Str(v) => v.len(),
        }
    }

    /// Whether it holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The type of a column declared by [`csv_row!`]: `f64`, `str` (a `&str` or
/// `String` field), `bool`, `int` (an integer that converts to `i64` without loss).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// [`Column::F64`].
    F64,
    /// [`Column::Str`].
    Str,
    /// [`Column::Bool`].
    Bool,
    /// [`Column::I64`].
    Int,
}

/// A row type whose columns are declared field by field ([`csv_row!`]
/// implements it with [`csv::CsvRow`], from the same field list, so the CSV and
/// the columns agree in names and order).
pub trait ColumnRows: Sized {
    /// The column names, in order (the struct's field names).
    const NAMES: &'static [&'static str];
    /// The columns' kinds, in the same order.
    const KINDS: &'static [Kind];
    /// The columns of `rows`, in [`ColumnRows::NAMES`]' order; each holds `rows.len()` values.
    fn columns(rows: &[Self]) -> Vec<Column>;
}

/// A table in memory: named columns of equal length, in the rows' field order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    /// `(name, values)` per column.
    pub columns: Vec<(String, Column)>,
}

impl Table {
    /// The table of `rows` of a type that derives `serde::Serialize` (a flat
    /// struct of scalars, `Option`s and unit enum variants): the cells the `csv`
    /// crate would write, with the empty-cell rules of [`rows`].
    ///
    /// # Errors
    /// [`ColumnError`] when a row is not a flat struct of scalars, or rows differ in their fields.
    pub fn of_rows<'a, T: Serialize + 'a>(rows: impl IntoIterator<Item = &'a T>) -> Result<Self, ColumnError> {
        let mut t = TableBuilder::default();
        for r in rows {
            t.push(r)?;
        }
        Ok(t.finish())
    }

    /// The table of `rows` of a type that declares its columns ([`ColumnRows`]),
    /// with the empty-cell rule of [`Table::of_rows`] (a text column whose cells
    /// are all empty is a float column of NaN, what a reader of the CSV sees), so
    /// the two paths give the same table (tested).
    pub fn of_columns<T: ColumnRows>(rows: &[T]) -> Self {
        let empty_text = |c: &Column| matches!(c, Column::Str(v) if !v.is_empty() && v.iter().all(String::is_empty));
        let columns = T::columns(rows).into_iter().map(|c| if empty_text(&c) { Column::F64(vec![f64::NAN; c.len()]) } else { c });
        Self { columns: T::NAMES.iter().map(|n| n.to_string()).zip(columns).collect() }
    }

    /// The number of rows (0 for a table without columns).
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |(_, c)| c.len())
    }
}

/// The file format of a command's long tables (`trace`, `events`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum TableFormat {
    /// CSV with a header row (`trace.csv`): floats in their shortest round-trip digits.
    #[default]
    Csv,
    /// Arrow IPC file, also called Feather v2 (`trace.arrow`): typed columns, floats
    /// with their bits, for `pandas.read_feather`, `polars.read_ipc`, pyarrow and
    /// `painleve.load` ([`arrow`]).
    Arrow,
    /// MCAP (`trace.mcap`, one file for all of a command's tables), the bag format
    /// of ROS 2 and Foxglove: a channel per signal group, JSON messages with JSON
    /// schemas, log times in ns of simulated time ([`mcap`]).
    Mcap,
}

impl TableFormat {
    /// The file extension, without the dot: `csv`, `arrow` or `mcap`.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Csv => "csv",
            Self::Arrow => "arrow",
            Self::Mcap => "mcap",
        }
    }

    /// The file name of table `stem` (`trace` -> `trace.csv`, `trace.arrow` or
    /// `trace.mcap`; with MCAP every table of a command goes into `trace.mcap`).
    pub fn file(self, stem: &str) -> String {
        format!("{stem}.{}", self.extension())
    }
}
