//! Two tables in one MCAP file, their rows interleaved in order of time:
//! `simulate`'s `trace.mcap` (the samples and the events), written the same way
//! by every front (`sil-host simulate --format mcap`, `painleve`'s
//! `Result.write_mcap`), so a run gives the same bytes from either.

use std::{fs::File, path::PathBuf};

use super::{FILE_CHUNK_BYTES, McapFile, McapRows, McapTable, McapView, STREAM_CHUNK_ROWS};
use crate::error::Error;

/// The views of the two tables of a [`McapPair`], each optional ([`McapView`]).
pub type PairViews<A, B> = (Option<Box<dyn McapView<A>>>, Option<Box<dyn McapView<B>>>);

/// Two tables of rows `A` and `B` (with their views) in one [`McapFile`],
/// chunks closed at [`FILE_CHUNK_BYTES`] of the tables' messages. Rows are
/// handed over in batches ([`McapPair::send`]); within a batch the two tables'
/// rows are interleaved by time ([`McapFile::write_merged`]). The bytes depend
/// on the rows and on where the batches end: a front that wants the command
/// line's bytes sends the same batches (`simulate`: the first sample with the
/// start-up events, then one batch per chunk of the open loop).
pub struct McapPair<A: McapRows + 'static, B: McapRows + 'static> {
    file: McapFile,
    tables: (McapTable, McapTable),
    rows: std::marker::PhantomData<fn(&A, &B)>,
}

impl<A: McapRows + 'static, B: McapRows + 'static> McapPair<A, B> {
    /// Starts the file `file` (at `path`, for error messages): its header, then
    /// table `A` with `views.0`, then table `B` with `views.1`.
    ///
    /// # Errors
    /// [`Error::Io`] when the header, schemas or channels cannot be written.
    pub fn new(path: PathBuf, file: File, views: PairViews<A, B>) -> Result<Self, Error> {
        let mut file = McapFile::new(path, file, Some(FILE_CHUNK_BYTES))?;
        let a = file.add_table_with_view::<A>(views.0)?;
        let b = file.add_table_with_view::<B>(views.1)?;
        Ok(Self { file, tables: (a, b), rows: std::marker::PhantomData })
    }

    /// Writes one batch: `a` and `b` (each in order of `t`) interleaved by time,
    /// `a`'s row first on a tie.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn send(&mut self, a: &[A], b: &[B]) -> Result<(), Error> {
        self.file.write_merged((self.tables.0, a), (self.tables.1, b))
    }

    /// Writes the last chunks, the summary and the footer, and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(self) -> Result<(), Error> {
        self.file.finish()
    }
}

/// Two tables streamed into one MCAP file as a run makes them (`sil-host run`'s
/// `trace` and `frames`): rows wait until table `A` has [`STREAM_CHUNK_ROWS`]
/// rows, then both tables' waiting rows go out interleaved by time (`A`'s row
/// first on a tie) as one chunk, and the file is flushed. Counted in rows, not
/// wall time, so the bytes are the same over every link, as [`super::McapStream`]'s.
pub struct McapPairStream<A: McapRows + 'static, B: McapRows + 'static> {
    file: McapFile,
    tables: (McapTable, McapTable),
    pending: (Vec<A>, Vec<B>),
}

impl<A: McapRows + 'static, B: McapRows + 'static> McapPairStream<A, B> {
    /// Starts the file `file` (at `path`, for error messages): its header, table
    /// `A` with `views.0`, table `B` with `views.1`, flushed.
    ///
    /// # Errors
    /// [`Error::Io`] when the header, schemas or channels cannot be written.
    pub fn new(path: PathBuf, file: File, views: PairViews<A, B>) -> Result<Self, Error> {
        let mut file = McapFile::new(path, file, None)?;
        let a = file.add_table_with_view::<A>(views.0)?;
        let b = file.add_table_with_view::<B>(views.1)?;
        file.flush()?;
        Ok(Self { file, tables: (a, b), pending: (Vec::with_capacity(STREAM_CHUNK_ROWS), Vec::with_capacity(STREAM_CHUNK_ROWS)) })
    }

    /// Appends a row of table `A`; writes a chunk when `A` has [`STREAM_CHUNK_ROWS`] waiting.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn push_a(&mut self, row: A) -> Result<(), Error> {
        self.pending.0.push(row);
        if self.pending.0.len() >= STREAM_CHUNK_ROWS { self.flush() } else { Ok(()) }
    }

    /// Appends a row of table `B` (written with the next chunk of `A`'s rows).
    pub fn push_b(&mut self, row: B) {
        self.pending.1.push(row);
    }

    /// Writes the waiting rows of both tables as one chunk and flushes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), Error> {
        if self.pending.0.is_empty() && self.pending.1.is_empty() {
            return Ok(());
        }
        self.file.write_merged((self.tables.0, &self.pending.0), (self.tables.1, &self.pending.1))?;
        self.pending.0.clear();
        self.pending.1.clear();
        self.file.flush()
    }

    /// Writes the rest, the summary and the footer, and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.flush()?;
        self.file.finish()
    }
}
