//! The project's tables, one layer for every format. Each row type declares its
//! table's columns once ([`declared`]: names and kinds); from that declaration
//! rows become typed columns ([`Table`], [`Column`]), CSV is written row by row
//! ([`csv`], the `csv` crate's bytes), Arrow IPC files are written and read
//! ([`arrow`], the declaration's schema), MCAP files split a table's columns into
//! signal groups, a channel each ([`mcap`]), and a CSV file is read back with
//! the declared types ([`read`], by arrow-csv). A long table's CSV or Arrow file
//! is written by a thread of its own ([`writer`], one for every format).
//!
//! Two ways from rows to a [`Table`]: the long tables' row types (`trace`,
//! `events`, the closed-loop trace) fill their columns field by field
//! ([`csv_row!`], [`ColumnRows`], no per-cell dispatch); the other row types
//! derive `serde::Serialize` and declare their columns ([`declare!`]), and go
//! through [`Table::of_rows`] ([`rows`], the cells the `csv` crate writes, each
//! in its declared column). The two give the same table (tested). The way back,
//! from any table to rows that derive `serde::Deserialize`, is [`Table::rows_as`]
//! ([`row_reader`]).
//!
//! Features (none by default; Cargo.toml says each): `arrow` the Arrow IPC writer,
//! `mcap` the MCAP writer, `read` every reader (CSV, Arrow, MCAP; only the Python
//! package and the tests read tables). Without them the crate holds the
//! declarations, the rows-to-columns layer and the CSV writer: what the command
//! line's main job and the crates that declare row types (`rig`, `analyses`) need.
//! Every input file the host tools read is opened and read within a stated
//! size bound, a regular file only ([`input`], issue 80). Errors: [`Error`].

#![warn(missing_docs)]

#[cfg(feature = "arrow")]
pub mod arrow;
pub mod csv;
pub mod declared;
pub mod error;
pub mod input;
pub mod mcap;
#[cfg(feature = "read")]
pub mod read;
pub mod row_reader;
pub mod rows;
pub mod writer;

pub use error::Error;
/// serde, for [`declare_view!`]'s expansion in the crates that use it.
#[doc(hidden)]
pub use serde as __serde;
use serde::Serialize;

pub use declared::{Declaration, Declared, Kind};
pub use row_reader::RowError;
pub use rows::{ColumnError, TableBuilder};

/// The values of one column: a table's cells of one field, typed.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// Floats (NaN for empty cells).
    F64(Vec<f64>),
    /// Signed integers.
    I64(Vec<i64>),
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
            Self::Bool(v) => v.len(),
            Self::Str(v) => v.len(),
        }
    }

    /// Whether it holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A row type whose columns are filled field by field, typed, without serde
/// ([`csv_row!`] implements it with [`csv::CsvRow`] and [`Declared`], from the
/// same field list, so the CSV and the columns agree in names and order).
pub trait ColumnRows: Declared + Sized {
    /// The columns of `rows`, in [`Declared::NAMES`]' order, of [`Declared::KINDS`];
    /// each holds `rows.len()` values.
    fn columns(rows: &[Self]) -> Vec<Column>;
}

/// A table in memory: named columns of equal length, in the rows' field order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    /// `(name, values)` per column.
    pub columns: Vec<(String, Column)>,
}

impl Table {
    /// The table of `rows` of a type that declares its columns ([`Declared`]) and
    /// derives `serde::Serialize` (a flat struct of scalars, `Option`s and unit
    /// enum variants): the cells the `csv` crate would write, each in its declared
    /// column ([`rows`]: NaN for an empty float cell, `""` for an empty text cell).
    ///
    /// # Errors
    /// [`ColumnError`] when a row is not a flat struct of scalars, its fields are
    /// not the declared columns, or a cell does not fit its column's kind.
    pub fn of_rows<'a, T: Declared + Serialize + 'a>(rows: impl IntoIterator<Item = &'a T>) -> Result<Self, ColumnError> {
        let mut t = TableBuilder::new(Declaration::of::<T>());
        for r in rows {
            t.push(r)?;
        }
        Ok(t.finish())
    }

    /// The table of `rows` of a type whose columns are filled without serde
    /// ([`ColumnRows`]): the same table as [`Table::of_rows`] (tested).
    pub fn of_columns<T: ColumnRows>(rows: &[T]) -> Self {
        Self { columns: T::NAMES.iter().map(|n| n.to_string()).zip(T::columns(rows)).collect() }
    }

    /// The rows of this table as `T`, a row type that declares its columns and
    /// derives `serde::Deserialize` ([`row_reader`]: the way back of
    /// [`Table::of_rows`] and [`Table::of_columns`]).
    ///
    /// # Errors
    /// [`RowError`] naming the missing or undeclared column, or the row and
    /// column of a cell the field cannot take.
    pub fn rows_as<T: serde::de::DeserializeOwned + Declared>(&self) -> Result<Vec<T>, RowError> {
        row_reader::rows_of(self)
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
    /// of ROS 2 and Foxglove: a channel per signal group, protobuf messages with their
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
