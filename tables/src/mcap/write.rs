//! Writing MCAP files: [`McapFile`] (tables registered, rows written, chunks
//! closed at a size) and [`McapStream`] (one table, a chunk every
//! [`STREAM_CHUNK_ROWS`] rows, flushed at once).

use std::{
    any::Any,
    collections::BTreeMap,
    fs::File,
    io::BufWriter,
    path::{Path, PathBuf},
};

use mcap::{
    McapError, WriteOptions, Writer,
    records::{MessageHeader, Metadata},
};

use super::{
    McapRows, STREAM_CHUNK_ROWS,
    channel::{ChannelSpec, McapView, RowEncoder, log_time_ns},
};
use crate::{Column, error::Error};

/// The zstd level of the chunks: 1, the fastest (a 300 s `simulate`: 45 MB in 1.0 s,
/// against 49 MB in 2.1 s at the `mcap` crate's default 3).
const ZSTD_LEVEL: u32 = 1;

/// The error of an MCAP file, as the CLI reports it: the file and what failed.
fn mcap_err(path: &Path) -> impl Fn(McapError) -> Error + '_ {
    move |e| Error::Io {
        path: path.to_path_buf(),
        source: match e {
            McapError::Io(io) => io,
            other => std::io::Error::other(other.to_string()),
        },
    }
}

/// The channels of one table in an [`McapFile`]: its own and its view's.
struct TableChannels {
    /// The table's [`RowEncoder`] (of its row type, checked at each write).
    encoder: Box<dyn Any + Send>,
    /// The MCAP channel id of each group.
    channels: Vec<u16>,
    /// Rows written so far (the next message's sequence number).
    rows: u32,
    /// The table's view, if it has one.
    view: Option<ViewChannels>,
}

/// A table's view in an [`McapFile`]: the `Box<dyn McapView<T>>`, its
/// channels' ids and their next sequence numbers.
struct ViewChannels {
    view: Box<dyn Any + Send>,
    ids: Vec<u16>,
    sequences: Vec<u32>,
}

/// A table registered in an [`McapFile`] ([`McapFile::add_table`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct McapTable(usize);

/// An MCAP file being written: tables registered with [`McapFile::add_table`]
/// (or [`McapFile::add_table_with_view`]), rows written with [`McapFile::write`]
/// (or two tables' rows interleaved by time, [`McapFile::write_merged`]);
/// [`McapFile::finish`] writes the last chunk, the summary (indexes,
/// statistics) and the footer.
///
/// The tables' messages and their views' go to separate chunks: the rows'
/// chunk is closed, then the view messages of the same rows follow in a chunk
/// of their own (same log times, so the two overlap in time, which MCAP
/// readers merge). A reader of the tables alone ([`super::read_mcap`]) skips
/// the views' chunks by the chunk index without decompressing them.
pub struct McapFile {
    path: PathBuf,
    writer: Writer<BufWriter<File>>,
    tables: Vec<TableChannels>,
    /// Close the chunks when the tables' messages since the last close hold this many bytes.
    chunk_size: Option<u64>,
    /// The tables' message bytes since the chunks were last closed.
    table_bytes: u64,
    /// The views' messages since the chunks were last closed, for their own chunk.
    views: ViewBuffer,
}

/// View messages waiting for their chunk: each header and where its bytes end in `data`.
#[derive(Default)]
struct ViewBuffer {
    headers: Vec<(MessageHeader, usize)>,
    data: Vec<u8>,
}

impl McapFile {
    /// Starts the MCAP file `file` (at `path`, for error messages): its magic
    /// and header (profile empty: the channels are protobuf, no ROS).
    /// `chunk_size`: close the tables' chunk (and the views' after it) when
    /// the tables' messages in it hold that many bytes; `None`: only at
    /// [`McapFile::flush`]. Chunks are built in memory and written whole, so the
    /// file only ever ends inside a chunk while one is being written.
    ///
    /// # Errors
    /// [`Error::Io`] when the header cannot be written.
    pub fn new(path: PathBuf, file: File, chunk_size: Option<u64>) -> Result<Self, Error> {
        let options = WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(ZSTD_LEVEL)
            .compression_threads(0)
            .chunk_size(None)
            .disable_seeking(true)
            .library(concat!("painleve sil-host ", env!("CARGO_PKG_VERSION"), " (mcap crate)"));
        let writer = Writer::with_options(BufWriter::new(file), options).map_err(mcap_err(&path))?;
        Ok(Self { path, writer, tables: Vec::new(), chunk_size, table_bytes: 0, views: ViewBuffer::default() })
    }

    /// Registers the table of rows `T`: a schema and a channel per group, and
    /// the metadata record `painleve.table.<T::TABLE>` (`columns`, `kinds`:
    /// comma-separated, in the CSV's order; `topics`: the table's channels).
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails, or when `T`'s groups name a column it
    /// lacks or leave one out (a bug of the row type, reported as an error).
    pub fn add_table<T: McapRows + 'static>(&mut self) -> Result<McapTable, Error> {
        self.add_table_with_view::<T>(None)
    }

    /// [`McapFile::add_table`], and `view`'s channels after the table's: each
    /// row written is followed by its view's messages ([`McapView`]).
    ///
    /// # Errors
    /// As [`McapFile::add_table`].
    pub fn add_table_with_view<T: McapRows + 'static>(&mut self, view: Option<Box<dyn McapView<T>>>) -> Result<McapTable, Error> {
        let bad = |what: String| Error::Io { path: self.path.clone(), source: std::io::Error::other(what) };
        let encoder = RowEncoder::<T>::new().map_err(bad)?;
        let channels = encoder.channels().iter().map(|c| self.add_channel(c)).collect::<Result<Vec<_>, _>>()?;
        let view_metadata = view.as_ref().map(|v| v.metadata()).unwrap_or_default();
        // The view's channels before the metadata record, which closes the chunk
        // being built: the schemas and channels of a table share one chunk.
        let view = match view {
            Some(v) => {
                let ids = v.channels().iter().map(|c| self.add_channel(c)).collect::<Result<Vec<_>, _>>()?;
                let sequences = vec![0; ids.len()];
                Some(ViewChannels { view: Box::new(v), ids, sequences })
            }
            None => None,
        };
        let join = |v: &mut dyn Iterator<Item = &str>| v.collect::<Vec<_>>().join(",");
        let metadata = BTreeMap::from([
            ("columns".to_string(), join(&mut T::NAMES.iter().copied())),
            ("kinds".to_string(), join(&mut T::KINDS.iter().map(|k| k.name()))),
            ("topics".to_string(), join(&mut T::GROUPS.iter().map(|g| g.topic))),
        ]);
        let name = format!("painleve.table.{}", T::TABLE);
        self.writer.write_metadata(&Metadata { name, metadata }).map_err(mcap_err(&self.path))?;
        for (name, metadata) in view_metadata {
            self.writer.write_metadata(&Metadata { name, metadata }).map_err(mcap_err(&self.path))?;
        }
        self.tables.push(TableChannels { encoder: Box::new(encoder), channels, rows: 0, view });
        Ok(McapTable(self.tables.len() - 1))
    }

    /// Adds `c`'s schema and channel; returns the channel's id.
    fn add_channel(&mut self, c: &ChannelSpec) -> Result<u16, Error> {
        let schema = self.writer.add_schema(&c.schema_name, &c.schema_encoding, &c.schema).map_err(mcap_err(&self.path))?;
        self.writer.add_channel(schema, &c.topic, &c.message_encoding, &BTreeMap::new()).map_err(mcap_err(&self.path))
    }

    /// Writes `rows` of `table` (registered for `T`): one message per group and
    /// row, then the row's view messages.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails or `table` was registered for another row type.
    pub fn write<T: McapRows + 'static>(&mut self, table: McapTable, rows: &[T]) -> Result<(), Error> {
        let columns = T::columns(rows);
        for (i, row) in rows.iter().enumerate() {
            self.write_row(table, &columns, i, row)?;
        }
        Ok(())
    }

    /// Writes `a`'s rows and `b`'s interleaved in order of time (each is in
    /// order of `t`; on a tie `a`'s row first): `simulate`'s samples and events.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails or a table was registered for another row type.
    pub fn write_merged<A: McapRows + 'static, B: McapRows + 'static>(
        &mut self,
        a: (McapTable, &[A]),
        b: (McapTable, &[B]),
    ) -> Result<(), Error> {
        let (ca, cb) = (A::columns(a.1), B::columns(b.1));
        let time = |t: usize, cols: &[Column], i: usize| match &cols[t] {
            Column::F64(v) => v[i],
            _ => f64::NAN,
        };
        let (ta, tb) = (A::NAMES.iter().position(|n| *n == "t").unwrap_or(0), B::NAMES.iter().position(|n| *n == "t").unwrap_or(0));
        let (mut i, mut j) = (0, 0);
        while i < a.1.len() || j < b.1.len() {
            let take_b = i == a.1.len() || (j < b.1.len() && time(tb, &cb, j) < time(ta, &ca, i));
            if take_b {
                self.write_row(b.0, &cb, j, &b.1[j])?;
                j += 1;
            } else {
                self.write_row(a.0, &ca, i, &a.1[i])?;
                i += 1;
            }
        }
        Ok(())
    }

    /// Writes row `i` of `columns` (`T`'s columns of a batch whose row `i` is
    /// `row`): its message on each channel, then its view's.
    fn write_row<T: McapRows + 'static>(&mut self, table: McapTable, columns: &[Column], i: usize, row: &T) -> Result<(), Error> {
        let wrong = || Error::Io {
            path: self.path.clone(),
            source: std::io::Error::other(format!("table {} written with rows of another type", T::TABLE)),
        };
        let tc = &mut self.tables[table.0];
        let Some(encoder) = tc.encoder.downcast_mut::<RowEncoder<T>>() else { return Err(wrong()) };
        let ns = log_time_ns(encoder.time(columns, i));
        let sequence = tc.rows;
        tc.rows = tc.rows.wrapping_add(1);
        let writer = &mut self.writer;
        let mut result = Ok(());
        let table_bytes = &mut self.table_bytes;
        encoder.encode(columns, i, &mut |g, bytes| {
            if result.is_ok() {
                let header = MessageHeader { channel_id: tc.channels[g], sequence, log_time: ns, publish_time: ns };
                *table_bytes += bytes.len() as u64;
                result = writer.write_to_known_channel(&header, bytes);
            }
        });
        if let Some(ViewChannels { view, ids, sequences }) = &mut tc.view {
            let Some(view) = view.downcast_mut::<Box<dyn McapView<T>>>() else { return Err(wrong()) };
            let views = &mut self.views;
            view.messages(row, &mut |c, bytes| {
                let header = MessageHeader { channel_id: ids[c], sequence: sequences[c], log_time: ns, publish_time: ns };
                sequences[c] = sequences[c].wrapping_add(1);
                views.data.extend_from_slice(bytes);
                views.headers.push((header, views.data.len()));
            });
        }
        result.map_err(mcap_err(&self.path))?;
        if self.chunk_size.is_some_and(|size| self.table_bytes >= size) {
            self.close_chunks()?;
        }
        Ok(())
    }

    /// Closes the tables' chunk being built, then writes the views' messages
    /// of the same rows as a chunk of their own.
    fn close_chunks(&mut self) -> Result<(), Error> {
        let err = mcap_err(&self.path);
        self.writer.flush().map_err(&err)?;
        if !self.views.headers.is_empty() {
            let mut start = 0;
            for (header, end) in &self.views.headers {
                self.writer.write_to_known_channel(header, &self.views.data[start..*end]).map_err(&err)?;
                start = *end;
            }
            self.views.headers.clear();
            self.views.data.clear();
            self.writer.flush().map_err(&err)?;
        }
        self.table_bytes = 0;
        Ok(())
    }

    /// Closes the chunks being built (the tables', then the views') and
    /// flushes the file to the operating system: a process killed after this
    /// keeps every row written.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), Error> {
        self.close_chunks()
    }

    /// Writes the last chunk, the summary section and the footer, and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.close_chunks()?;
        self.writer.finish().map_err(mcap_err(&self.path))?;
        let path = self.path.clone();
        let buffered = self.writer.into_inner();
        buffered.into_inner().map_err(|e| Error::Io { path, source: e.into_error() })?;
        Ok(())
    }
}

/// One table written as an MCAP file as a run produces it (`run` and `pil` with
/// `--format mcap`): rows wait in memory until [`STREAM_CHUNK_ROWS`] have come
/// (or [`McapStream::flush`]), then go out as one chunk, flushed to the
/// operating system at once, so a process killed outright keeps every chunk
/// before (a linear reader gets them: [`read_mcap`], `painleve.load`, the Python
/// `mcap` package's `NonSeekingReader`).
pub struct McapStream<T: McapRows + 'static> {
    file: McapFile,
    table: McapTable,
    pending: Vec<T>,
}

impl<T: McapRows + 'static> McapStream<T> {
    /// Starts the file `file` (at `path`, for error messages) with `T`'s table.
    ///
    /// # Errors
    /// [`Error::Io`] when the header, schemas or channels cannot be written.
    pub fn new(path: PathBuf, file: File) -> Result<Self, Error> {
        Self::with_view(path, file, None)
    }

    /// [`McapStream::new`], with `view`'s channels and messages after each row's ([`McapView`]).
    ///
    /// # Errors
    /// As [`McapStream::new`].
    pub fn with_view(path: PathBuf, file: File, view: Option<Box<dyn McapView<T>>>) -> Result<Self, Error> {
        let mut file = McapFile::new(path, file, None)?;
        let table = file.add_table_with_view::<T>(view)?;
        file.flush()?;
        Ok(Self { file, table, pending: Vec::with_capacity(STREAM_CHUNK_ROWS) })
    }

    /// Adds `row`; at [`STREAM_CHUNK_ROWS`] waiting rows, writes them as one chunk and flushes.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn push(&mut self, row: T) -> Result<(), Error> {
        self.pending.push(row);
        if self.pending.len() >= STREAM_CHUNK_ROWS { self.flush() } else { Ok(()) }
    }

    /// Writes the waiting rows as one chunk and flushes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), Error> {
        if self.pending.is_empty() {
            return Ok(());
        }
        self.file.write(self.table, &self.pending)?;
        self.pending.clear();
        self.file.flush()
    }

    /// Writes the rows still waiting, the summary and the footer.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.flush()?;
        self.file.finish()
    }
}
