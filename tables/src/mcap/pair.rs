//! Two tables in one MCAP file, their rows interleaved in order of time:
//! `simulate`'s `trace.mcap` (the samples and the events), written the same way
//! by every front (`sil-host simulate --format mcap`, `painleve`'s
//! `Result.write_mcap`), so a run gives the same bytes from either.

use std::{fs::File, path::PathBuf};

use super::{FILE_CHUNK_BYTES, McapFile, McapRows, McapTable, McapView};
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
