//! Writing MCAP files: [`McapFile`] (tables registered, rows written, chunks
//! closed at a size) and [`McapStream`] (one table, a chunk every
//! [`STREAM_CHUNK_ROWS`] rows, flushed at once).

use std::{
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
    schema::{kind_name, schema_json},
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

/// The channels of one table in an [`McapFile`].
struct TableChannels {
    /// `(channel id, the group's column indices)` per group.
    channels: Vec<(u16, Vec<usize>)>,
    /// The index of column `t`.
    t: usize,
    /// The table's column names.
    names: &'static [&'static str],
    /// Rows written so far (the next message's sequence number).
    rows: u32,
}

/// A table registered in an [`McapFile`] ([`McapFile::add_table`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct McapTable(usize);

/// An MCAP file being written: tables registered with [`McapFile::add_table`],
/// rows written with [`McapFile::write`] (or two tables' rows interleaved by
/// time, [`McapFile::write_merged`]); [`McapFile::finish`] writes the last chunk,
/// the summary (indexes, statistics) and the footer.
pub struct McapFile {
    path: PathBuf,
    writer: Writer<BufWriter<File>>,
    tables: Vec<TableChannels>,
    buf: Vec<u8>,
}

impl McapFile {
    /// Starts the MCAP file `file` (at `path`, for error messages): its magic
    /// and header. `chunk_size`: close a chunk when it holds that many bytes
    /// (uncompressed); `None`: only at [`McapFile::flush`]. Chunks are built in
    /// memory and written whole, so the file only ever ends inside a chunk while
    /// one is being written.
    ///
    /// # Errors
    /// [`Error::Io`] when the header cannot be written.
    pub fn new(path: PathBuf, file: File, chunk_size: Option<u64>) -> Result<Self, Error> {
        let options = WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(ZSTD_LEVEL)
            .compression_threads(0)
            .chunk_size(chunk_size)
            .disable_seeking(true)
            .library(concat!("painleve sil-host ", env!("CARGO_PKG_VERSION"), " (mcap crate)"));
        let writer = Writer::with_options(BufWriter::new(file), options).map_err(mcap_err(&path))?;
        Ok(Self { path, writer, tables: Vec::new(), buf: Vec::with_capacity(1024) })
    }

    /// Registers the table of rows `T`: a schema and a channel per group, and
    /// the metadata record `painleve.table.<T::TABLE>` (`columns`, `kinds`:
    /// comma-separated, in the CSV's order; `topics`: the table's channels).
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails, or when `T`'s groups name a column it
    /// lacks or leave one out (a bug of the row type, reported as an error).
    pub fn add_table<T: McapRows>(&mut self) -> Result<McapTable, Error> {
        let bad = |what: String| Error::Io { path: self.path.clone(), source: std::io::Error::other(what) };
        let t = T::NAMES.iter().position(|n| *n == "t").ok_or_else(|| bad(format!("table {}: no column `t`", T::TABLE)))?;
        let grouped: usize = T::GROUPS.iter().map(|g| g.columns.len()).sum();
        if grouped + 1 != T::NAMES.len() {
            return Err(bad(format!("table {}: its groups hold {grouped} columns besides t, not {}", T::TABLE, T::NAMES.len() - 1)));
        }
        let mut channels = Vec::with_capacity(T::GROUPS.len());
        for g in T::GROUPS {
            let schema = schema_json(T::NAMES, T::KINDS, g).map_err(bad)?;
            let indices = g
                .columns
                .iter()
                .map(|c| T::NAMES.iter().position(|n| n == c).ok_or_else(|| bad(format!("group {}: no column `{c}`", g.topic))))
                .collect::<Result<Vec<_>, _>>()?;
            let schema_id = self.writer.add_schema(g.schema, "jsonschema", &schema).map_err(mcap_err(&self.path))?;
            let channel = self.writer.add_channel(schema_id, g.topic, "json", &BTreeMap::new()).map_err(mcap_err(&self.path))?;
            channels.push((channel, indices));
        }
        let join = |v: &mut dyn Iterator<Item = &str>| v.collect::<Vec<_>>().join(",");
        let metadata = BTreeMap::from([
            ("columns".to_string(), join(&mut T::NAMES.iter().copied())),
            ("kinds".to_string(), join(&mut T::KINDS.iter().map(|k| kind_name(*k)))),
            ("topics".to_string(), join(&mut T::GROUPS.iter().map(|g| g.topic))),
        ]);
        let name = format!("painleve.table.{}", T::TABLE);
        self.writer.write_metadata(&Metadata { name, metadata }).map_err(mcap_err(&self.path))?;
        self.tables.push(TableChannels { channels, t, names: T::NAMES, rows: 0 });
        Ok(McapTable(self.tables.len() - 1))
    }

    /// Writes `rows` of `table` (registered for `T`): one message per group and row.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn write<T: McapRows>(&mut self, table: McapTable, rows: &[T]) -> Result<(), Error> {
        let columns = T::columns(rows);
        for i in 0..rows.len() {
            self.write_row(table, &columns, i)?;
        }
        Ok(())
    }

    /// Writes `a`'s rows and `b`'s interleaved in order of time (each is in
    /// order of `t`; on a tie `a`'s row first): `simulate`'s samples and events.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn write_merged<A: McapRows, B: McapRows>(&mut self, a: (McapTable, &[A]), b: (McapTable, &[B])) -> Result<(), Error> {
        let (ca, cb) = (A::columns(a.1), B::columns(b.1));
        let (ta, tb) = (self.tables[a.0.0].t, self.tables[b.0.0].t);
        let time = |t: usize, cols: &[Column], i: usize| match &cols[t] {
            Column::F64(v) => v[i],
            _ => f64::NAN,
        };
        let (mut i, mut j) = (0, 0);
        while i < a.1.len() || j < b.1.len() {
            let take_b = i == a.1.len() || (j < b.1.len() && time(tb, &cb, j) < time(ta, &ca, i));
            if take_b {
                self.write_row(b.0, &cb, j)?;
                j += 1;
            } else {
                self.write_row(a.0, &ca, i)?;
                i += 1;
            }
        }
        Ok(())
    }

    /// Writes row `i` of `columns` (a table's columns): its message on each channel.
    fn write_row(&mut self, table: McapTable, columns: &[Column], i: usize) -> Result<(), Error> {
        let tc = &mut self.tables[table.0];
        let t = match &columns[tc.t] {
            Column::F64(v) => v[i],
            _ => f64::NAN,
        };
        // Nanoseconds of simulated time; a negative or NaN time (never written) is 0.
        let ns = (t * 1e9).round() as u64;
        let sequence = tc.rows;
        tc.rows = tc.rows.wrapping_add(1);
        for (channel, indices) in &tc.channels {
            let buf = &mut self.buf;
            buf.clear();
            buf.extend_from_slice(b"{\"t\":");
            push_value(buf, &columns[tc.t], i);
            for &c in indices {
                buf.extend_from_slice(b",\"");
                buf.extend_from_slice(tc.names[c].as_bytes());
                buf.extend_from_slice(b"\":");
                push_value(buf, &columns[c], i);
            }
            buf.push(b'}');
            let header = MessageHeader { channel_id: *channel, sequence, log_time: ns, publish_time: ns };
            self.writer.write_to_known_channel(&header, buf).map_err(mcap_err(&self.path))?;
        }
        Ok(())
    }

    /// Closes the chunk being built (written whole) and flushes the file to the
    /// operating system: a process killed after this keeps every row written.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), Error> {
        self.writer.flush().map_err(mcap_err(&self.path))
    }

    /// Writes the last chunk, the summary section and the footer, and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.writer.finish().map_err(mcap_err(&self.path))?;
        let path = self.path.clone();
        let buffered = self.writer.into_inner();
        buffered.into_inner().map_err(|e| Error::Io { path, source: e.into_error() })?;
        Ok(())
    }
}

/// Appends value `i` of `c` as JSON: a float with the CSV's digits (`null` for
/// NaN and infinities), an integer, `true`/`false`, a string escaped.
fn push_value(buf: &mut Vec<u8>, c: &Column, i: usize) {
    match c {
        Column::F64(v) if v[i].is_finite() => crate::csv::push_f64(buf, v[i]),
        Column::F64(_) => buf.extend_from_slice(b"null"),
        Column::I64(v) => buf.extend_from_slice(itoa::Buffer::new().format(v[i]).as_bytes()),
        Column::U64(v) => buf.extend_from_slice(itoa::Buffer::new().format(v[i]).as_bytes()),
        Column::Bool(v) => buf.extend_from_slice(if v[i] { b"true" } else { b"false" }),
        // Writing a string into a Vec cannot fail.
        Column::Str(v) => serde_json::to_writer(&mut *buf, &v[i]).unwrap_or_default(),
    }
}

/// One table written as an MCAP file as a run produces it (`run` and `pil` with
/// `--format mcap`): rows wait in memory until [`STREAM_CHUNK_ROWS`] have come
/// (or [`McapStream::flush`]), then go out as one chunk, flushed to the
/// operating system at once, so a process killed outright keeps every chunk
/// before (a linear reader gets them: [`read_mcap`], `painleve.load`, the Python
/// `mcap` package's `NonSeekingReader`).
pub struct McapStream<T: McapRows> {
    file: McapFile,
    table: McapTable,
    pending: Vec<T>,
}

impl<T: McapRows> McapStream<T> {
    /// Starts the file `file` (at `path`, for error messages) with `T`'s table.
    ///
    /// # Errors
    /// [`Error::Io`] when the header, schemas or channels cannot be written.
    pub fn new(path: PathBuf, file: File) -> Result<Self, Error> {
        let mut file = McapFile::new(path, file, None)?;
        let table = file.add_table::<T>()?;
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
