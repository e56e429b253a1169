//! A long table written as it is produced, in the format the user chose
//! (`--format csv|arrow`): CSV by a writer thread ([`crate::fastcsv::CsvThread`]),
//! or an Arrow IPC file ([`crate::arrow_table::ArrowFile`]).

use serde::Serialize;

use crate::{
    arrow_table::{ArrowFile, ArrowRow},
    error::CliError,
    fastcsv::{CsvRow, CsvThread},
    output::OutputSet,
};

/// The file format of a command's long tables (`trace`, `events`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TableFormat {
    /// CSV with a header row (`trace.csv`): floats in their shortest round-trip digits.
    #[default]
    Csv,
    /// Arrow IPC file, also called Feather v2 (`trace.arrow`): typed columns, floats
    /// with their bits, for `pandas.read_feather`, `polars.read_ipc`, pyarrow and
    /// `painleve.load` ([`crate::arrow_table`]).
    Arrow,
}

impl TableFormat {
    /// The file extension, without the dot: `csv` or `arrow`.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Csv => "csv",
            Self::Arrow => "arrow",
        }
    }

    /// The file name of table `stem` (`trace` -> `trace.csv` or `trace.arrow`).
    pub fn file(self, stem: &str) -> String {
        format!("{stem}.{}", self.extension())
    }
}

/// A table of rows `T` being written into an [`OutputSet`] (under its temporary
/// name until the set is committed).
pub enum TableOut<T: CsvRow + ArrowRow + Send + 'static> {
    /// CSV, formatted and written by a thread of its own while the caller goes on.
    Csv(CsvThread<T>),
    /// An Arrow IPC file, a record batch at a time.
    Arrow(Box<ArrowFile<T>>),
}

impl<T: CsvRow + ArrowRow + Send + 'static> TableOut<T> {
    /// Starts table `stem` of `out` in `format` (`stem.csv` or `stem.arrow`).
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created or its header written.
    pub fn create(out: &mut OutputSet, stem: &str, format: TableFormat) -> Result<Self, CliError> {
        let name = format.file(stem);
        Ok(match format {
            TableFormat::Csv => Self::Csv(CsvThread::spawn(out.create_csv(&name, T::HEADER)?)?),
            TableFormat::Arrow => {
                let (path, file) = out.create_unbuffered(&name)?;
                Self::Arrow(Box::new(ArrowFile::new(path, file)?))
            }
        })
    }

    /// Hands over `rows` and returns an empty vector to fill next (the capacity kept).
    ///
    /// # Errors
    /// [`CliError::Io`] when writing has failed.
    pub fn send(&mut self, mut rows: Vec<T>) -> Result<Vec<T>, CliError> {
        match self {
            Self::Csv(t) => t.send(rows),
            Self::Arrow(a) => {
                a.push(&mut rows)?;
                Ok(rows)
            }
        }
    }

    /// Writes everything still waiting and closes the file.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn finish(self) -> Result<(), CliError> {
        match self {
            Self::Csv(t) => t.finish(),
            Self::Arrow(a) => a.finish(),
        }
    }
}
