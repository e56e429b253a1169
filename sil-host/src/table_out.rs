//! A long table written as it is produced, in the format the user chose
//! (`--format csv|arrow|mcap`): CSV by a writer thread ([`tables::csv::CsvThread`]),
//! an Arrow IPC file by a writer thread ([`tables::arrow::ArrowThread`]), or, for two
//! tables at once ([`TablesOut`]), one MCAP file ([`tables::mcap::McapFile`]).
//! Arrow and MCAP are the feature `formats`'s; without it they are refused
//! ([`crate::features::require_format`], exit 2).

use crate::{
    error::CliError,
    output::{OutputSet, View},
};
pub use tables::TableFormat;
use tables::{
    ColumnRows,
    csv::{CsvRow, CsvThread},
    mcap::McapRows,
};
#[cfg(feature = "formats")]
use tables::{
    arrow::{ArrowFile, ArrowThread},
    mcap::McapPair,
};

/// A table of rows `T` being written into an [`OutputSet`] (under its temporary
/// name until the set is committed).
pub enum TableOut<T: CsvRow + ColumnRows + Send + 'static> {
    /// CSV, formatted and written by a thread of its own while the caller goes on.
    Csv(CsvThread<T>),
    /// An Arrow IPC file, a record batch at a time, batched and written by a
    /// thread of its own while the caller goes on.
    #[cfg(feature = "formats")]
    Arrow(ArrowThread<T>),
}

impl<T: CsvRow + ColumnRows + Send + 'static> TableOut<T> {
    /// Starts table `stem` of `out` in `format` (`stem.csv` or `stem.arrow`).
    ///
    /// # Errors
    /// [`CliError::Io`] when the file cannot be created or its header written;
    /// [`CliError::Io`] for [`TableFormat::Mcap`], which holds several tables in
    /// one file ([`TablesOut`]); [`CliError::BadInput`] for Arrow or MCAP in a
    /// build without the feature `formats`.
    pub fn create(out: &mut OutputSet, stem: &str, format: TableFormat) -> Result<Self, CliError> {
        crate::features::require_format(format)?;
        let name = format.file(stem);
        Ok(match format {
            TableFormat::Csv => Self::Csv(CsvThread::spawn(out.create_csv(&name, T::HEADER)?)?),
            #[cfg(not(feature = "formats"))]
            TableFormat::Arrow => return Err(crate::features::format_missing(format)),
            #[cfg(feature = "formats")]
            TableFormat::Arrow => {
                let (path, file) = out.create_unbuffered(&name)?;
                Self::Arrow(ArrowThread::spawn(ArrowFile::new(path, file)?)?)
            }
            TableFormat::Mcap => {
                return Err(CliError::Io {
                    path: out.path(&name),
                    source: std::io::Error::other("an MCAP file holds all of a command's tables: written by TablesOut"),
                });
            }
        })
    }

    /// Hands over `rows` and returns an empty vector to fill next (the capacity kept).
    ///
    /// # Errors
    /// [`CliError::Io`] when writing has failed.
    pub fn send(&mut self, rows: Vec<T>) -> Result<Vec<T>, CliError> {
        match self {
            Self::Csv(t) => Ok(t.send(rows)?),
            #[cfg(feature = "formats")]
            Self::Arrow(a) => Ok(a.send(rows)?),
        }
    }

    /// Writes everything still waiting and closes the file.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn finish(self) -> Result<(), CliError> {
        match self {
            Self::Csv(t) => Ok(t.finish()?),
            #[cfg(feature = "formats")]
            Self::Arrow(a) => Ok(a.finish()?),
        }
    }
}

/// The views of two tables in an MCAP file (the arm's frames and scene, the
/// events' log: `arm_view`), one per table, each optional ([`View`]).
pub type Views<A, B> = (View<A>, View<B>);

/// Two tables of a command (`simulate`'s `trace` of rows `A` and `events` of
/// rows `B`): two files (`trace.csv` and `events.csv`, or `.arrow`), or one MCAP
/// file `trace.mcap` holding both, their messages interleaved in order of time
/// ([`McapPair`], as `painleve`'s `Result.write_mcap` writes it).
pub enum TablesOut<A: CsvRow + McapRows + Send + 'static, B: CsvRow + McapRows + Send + 'static> {
    /// A file per table.
    Two(TableOut<A>, TableOut<B>),
    /// One MCAP file.
    #[cfg(feature = "formats")]
    Mcap(Box<McapPair<A, B>>),
}

impl<A: CsvRow + McapRows + Send + 'static, B: CsvRow + McapRows + Send + 'static> TablesOut<A, B> {
    /// Starts tables `stems` (`["trace", "events"]`) of `out` in `format`: the
    /// files [`TablesOut::files`] names; an MCAP file carries each table's view
    /// of `views` too ([`tables::mcap::McapView`]: the arm in Foxglove's schemas).
    ///
    /// # Errors
    /// [`CliError::Io`] when a file cannot be created or its header written;
    /// [`CliError::BadInput`] for Arrow or MCAP in a build without the feature
    /// `formats`.
    pub fn create(out: &mut OutputSet, stems: [&str; 2], format: TableFormat, views: Views<A, B>) -> Result<Self, CliError> {
        crate::features::require_format(format)?;
        #[cfg(not(feature = "formats"))]
        let _ = views;
        Ok(match format {
            #[cfg(feature = "formats")]
            TableFormat::Mcap => {
                let (path, file) = out.create_unbuffered(&format.file(stems[0]))?;
                Self::Mcap(Box::new(McapPair::new(path, file, views)?))
            }
            _ => Self::Two(TableOut::create(out, stems[0], format)?, TableOut::create(out, stems[1], format)?),
        })
    }

    /// The files of tables `stems` in `format`: `trace.csv`, `events.csv`; or
    /// `trace.arrow`, `events.arrow`; or `trace.mcap`.
    pub fn files(stems: [&str; 2], format: TableFormat) -> Vec<String> {
        match format {
            TableFormat::Mcap => vec![format.file(stems[0])],
            _ => stems.iter().map(|s| format.file(s)).collect(),
        }
    }

    /// Hands over rows of both tables (each in order of time) and returns empty
    /// vectors to fill next (the capacity kept).
    ///
    /// # Errors
    /// [`CliError::Io`] when writing has failed.
    pub fn send(&mut self, a: Vec<A>, b: Vec<B>) -> Result<(Vec<A>, Vec<B>), CliError> {
        match self {
            Self::Two(ta, tb) => Ok((ta.send(a)?, tb.send(b)?)),
            #[cfg(feature = "formats")]
            Self::Mcap(pair) => {
                pair.send(&a, &b)?;
                let (mut a, mut b) = (a, b);
                a.clear();
                b.clear();
                Ok((a, b))
            }
        }
    }

    /// Writes everything still waiting and closes the files.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn finish(self) -> Result<(), CliError> {
        match self {
            Self::Two(a, b) => {
                a.finish()?;
                b.finish()
            }
            #[cfg(feature = "formats")]
            Self::Mcap(pair) => Ok(pair.finish()?),
        }
    }
}
