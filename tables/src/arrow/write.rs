//! Writing Arrow IPC files of a declared row type, a record batch at a time:
//! whole ([`ArrowFile`], `simulate`) or as a run produces the rows
//! ([`StreamedArrowFile`], `run` and `pil`).

use std::{fs::File, io::BufWriter, path::PathBuf, sync::Arc};

use arrow_array::RecordBatch;
use arrow_ipc::writer::FileWriter;
use arrow_schema::Schema;

use super::{BATCH_ROWS, array_of, arrow_err, schema};
use crate::{
    ColumnRows,
    declared::Declaration,
    error::Error,
    writer::{RowSink, WriterThread},
};

/// An Arrow IPC file being written: rows are buffered and written a record
/// batch of [`BATCH_ROWS`] at a time; [`ArrowFile::finish`] writes the last
/// batch and the footer (a file without its footer is not an Arrow file:
/// readers refuse it, so a run that fails before `finish` leaves no half table).
pub struct ArrowFile<T: ColumnRows> {
    path: PathBuf,
    writer: FileWriter<BufWriter<File>>,
    schema: Arc<Schema>,
    pending: Vec<T>,
}

impl<T: ColumnRows> ArrowFile<T> {
    /// Starts the Arrow IPC file `file` (at `path`, for error messages) with `T`'s schema.
    ///
    /// # Errors
    /// [`Error::Io`] when the header cannot be written.
    pub fn new(path: PathBuf, file: File) -> Result<Self, Error> {
        let schema = Arc::new(schema(Declaration::of::<T>()));
        let writer = FileWriter::try_new_buffered(file, &schema).map_err(arrow_err(&path))?;
        Ok(Self { path, writer, schema, pending: Vec::with_capacity(BATCH_ROWS) })
    }

    /// Takes the rows of `rows` (leaving it empty, its capacity kept); writes a
    /// record batch whenever [`BATCH_ROWS`] rows are waiting.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn push(&mut self, rows: &mut Vec<T>) -> Result<(), Error> {
        for row in rows.drain(..) {
            self.pending.push(row);
            if self.pending.len() >= BATCH_ROWS {
                self.write_pending()?;
            }
        }
        Ok(())
    }

    fn write_pending(&mut self) -> Result<(), Error> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let batch = RecordBatch::try_new(self.schema.clone(), T::columns(&self.pending).into_iter().map(array_of).collect())
            .map_err(arrow_err(&self.path))?;
        self.writer.write(&batch).map_err(arrow_err(&self.path))?;
        self.pending.clear();
        Ok(())
    }

    /// Writes the rows still waiting, the footer, and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.write_pending()?;
        self.writer.finish().map_err(arrow_err(&self.path))?;
        let path = self.path.clone();
        let buffered = self.writer.into_inner().map_err(arrow_err(&path))?;
        buffered.into_inner().map_err(|e| Error::Io { path, source: e.into_error() })?;
        Ok(())
    }
}

impl<T: ColumnRows + Send + 'static> RowSink<T> for ArrowFile<T> {
    const THREAD_NAME: &'static str = "arrow-writer";
    const FORMAT: &'static str = "Arrow";

    fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// [`ArrowFile::push`].
    fn write_rows(&mut self, rows: &mut Vec<T>) -> Result<(), Error> {
        self.push(rows)
    }

    /// [`ArrowFile::finish`]: the last batch, the footer.
    fn finish(self) -> Result<(), Error> {
        ArrowFile::finish(self)
    }
}

/// An [`ArrowFile`] written by a thread of its own (`simulate --format arrow`,
/// [`WriterThread`]): the caller hands over chunks of rows and goes on while the
/// thread batches them, builds the record batches' columns and writes them, as
/// [`crate::csv::CsvThread`] does for CSV. The file is the same, byte for byte,
/// as [`ArrowFile`] given the same rows (the batches are cut at the same rows).
pub type ArrowThread<T> = WriterThread<T, ArrowFile<T>>;

/// A table written as an Arrow IPC *file* as a run produces it (`run` and `pil`
/// with `--format arrow`): rows wait in memory until [`StreamedArrowFile::push`]
/// is told to write them, as one record batch, flushed to the operating system at
/// once; [`StreamedArrowFile::finish`] writes the footer. The same format as
/// [`ArrowFile`] (one `.arrow` convention: `pandas.read_feather`,
/// `polars.read_ipc`, `pyarrow.ipc.open_file` read both). A process killed
/// outright leaves the file without its footer: the IPC file format is the
/// stream format between the magic (padded to 64 bytes) and the footer, so
/// [`super::read_arrow`] (and `painleve.load`) still gives every whole batch
/// written before.
pub struct StreamedArrowFile<T: ColumnRows> {
    path: PathBuf,
    writer: FileWriter<File>,
    schema: Arc<Schema>,
    pending: Vec<T>,
}

impl<T: ColumnRows> StreamedArrowFile<T> {
    /// Starts the Arrow IPC file `file` (at `path`, for error messages) with `T`'s schema.
    ///
    /// # Errors
    /// [`Error::Io`] when the head and the schema cannot be written.
    pub fn new(path: PathBuf, file: File) -> Result<Self, Error> {
        let schema = Arc::new(schema(Declaration::of::<T>()));
        let writer = FileWriter::try_new(file, &schema).map_err(arrow_err(&path))?;
        Ok(Self { path, writer, schema, pending: Vec::new() })
    }

    /// Adds `row`; with `write`, writes every waiting row as one record batch and
    /// flushes it (the caller decides: `run` every 1 ms of wall time, like its CSV).
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn push(&mut self, row: T, write: bool) -> Result<(), Error> {
        self.pending.push(row);
        if write { self.write_pending() } else { Ok(()) }
    }

    fn write_pending(&mut self) -> Result<(), Error> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let batch = RecordBatch::try_new(self.schema.clone(), T::columns(&self.pending).into_iter().map(array_of).collect())
            .map_err(arrow_err(&self.path))?;
        self.writer.write(&batch).map_err(arrow_err(&self.path))?;
        self.writer.flush().map_err(arrow_err(&self.path))?;
        self.pending.clear();
        Ok(())
    }

    /// Writes the rows still waiting and the footer.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.write_pending()?;
        self.writer.finish().map_err(arrow_err(&self.path))
    }
}
