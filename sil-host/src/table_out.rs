//! A long table written as it is produced, in the format the user chose
//! (`--format csv|arrow`): CSV by a writer thread ([`experiments::table::csv::CsvThread`]),
//! or an Arrow IPC file ([`experiments::table::arrow::ArrowFile`]).

use crate::{error::CliError, output::OutputSet};
pub use experiments::table::TableFormat;
use experiments::table::{
    ColumnRows,
    arrow::ArrowFile,
    csv::{CsvRow, CsvThread},
};

/// A table of rows `T` being written into an [`OutputSet`] (under its temporary
/// name until the set is committed).
pub enum TableOut<T: CsvRow + ColumnRows + Send + 'static> {
    /// CSV, formatted and written by a thread of its own while the caller goes on.
    Csv(CsvThread<T>),
    /// An Arrow IPC file, a record batch at a time.
    Arrow(Box<ArrowFile<T>>),
}

impl<T: CsvRow + ColumnRows + Send + 'static> TableOut<T> {
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
