//! The long tables as an MCAP file (`--format mcap`: `trace.mcap`), the bag
//! format of ROS 2 and Foxglove's own, for robotics tools: Foxglove (File > Open
//! local file) plots its channels without a plugin.
//!
//! One file holds every table of a command (`simulate`: `trace` and `events`;
//! `run` and `pil`: `trace`). Each table's columns are split into signal groups
//! ([`McapRows::GROUPS`]), one channel per group (`/state`, `/contact`,
//! `/torques`, `/firmware`, `/events`); a row is one message on each of its
//! table's channels. A message is a JSON object (message encoding `json`) with
//! the row's time `t` (s) first and then the group's columns, by the CSV's names;
//! each channel has a JSON Schema (schema encoding `jsonschema`: the fields'
//! types and, in their descriptions, units). Log and publish times are the
//! row's `t` in nanoseconds of simulated time (`round(t * 1e9)`), the sequence
//! number the row's index in its table (from 0). Floats are written with the
//! CSV's digits (the shortest that read back to the same bits, so any correct
//! JSON parser gets the bits back); NaN and infinities, which JSON cannot
//! hold, are `null` (read back as NaN). Integers are JSON integers, flags
//! `true`/`false`, text JSON strings.
//!
//! A metadata record per table (`painleve.table.<name>`: `columns`, `kinds`,
//! `topics`) gives its columns in the CSV's order, so a reader
//! ([`read_mcap`], `painleve.load`) puts the table back together.
//!
//! Writing is the `mcap` crate's: chunks compressed with zstd (level 1, single-threaded,
//! so the same rows give the same bytes), closed at a size ([`McapFile::new`]
//! with a chunk size: `simulate`) or every [`STREAM_CHUNK_ROWS`] rows
//! ([`McapStream`]: `run` and `pil`, flushed to the operating system at once);
//! a run killed outright leaves its whole chunks, which a linear reader reads
//! (the summary and footer written by [`McapFile::finish`] are missing).

use std::{
    borrow::Cow,
    collections::BTreeMap,
    fs::File,
    io::BufWriter,
    path::{Path, PathBuf},
};

use mcap::{
    McapError, WriteOptions, Writer,
    read::{LinearReader, MessageStream, Options},
    records::{MessageHeader, Metadata, Record},
};

use super::{Column, ColumnRows, Kind, Table};
use crate::error::Error as CliError;

/// Rows per chunk of an [`McapStream`] (`run`, `pil`): 100 control periods
/// (0.1 s of simulated time at 1 kHz), at most what a run killed outright loses.
/// A count of rows, not of wall time, so the same run gives the same bytes over
/// any link.
pub const STREAM_CHUNK_ROWS: usize = 100;

/// The target size of an uncompressed chunk of `simulate`'s file, bytes (1 MiB).
pub const FILE_CHUNK_BYTES: u64 = 1 << 20;

/// The zstd level of the chunks: 1, the fastest (a 300 s `simulate`: 45 MB in 1.0 s,
/// against 49 MB in 2.1 s at the `mcap` crate's default 3).
const ZSTD_LEVEL: u32 = 1;

/// One signal group of a table: a channel of the MCAP file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct McapGroup {
    /// The channel's topic (`/state`).
    pub topic: &'static str,
    /// The schema's name (`painleve.State`).
    pub schema: &'static str,
    /// The table's columns in the group's messages, after `t` (CSV names).
    pub columns: &'static [&'static str],
}

/// A row type written as MCAP messages: its table's name and its columns'
/// signal groups. Every column but `t` is in exactly one group, `t` in none
/// (each message starts with it); tested for the tables of the CLI.
pub trait McapRows: ColumnRows {
    /// The table's name (`trace`, `events`): metadata record `painleve.table.<TABLE>`.
    const TABLE: &'static str;
    /// The signal groups, one channel each, in the order of their messages.
    const GROUPS: &'static [McapGroup];
}

/// The error of an MCAP file, as the CLI reports it: the file and what failed.
fn mcap_err(path: &Path) -> impl Fn(McapError) -> CliError + '_ {
    move |e| CliError::Io {
        path: path.to_path_buf(),
        source: match e {
            McapError::Io(io) => io,
            other => std::io::Error::other(other.to_string()),
        },
    }
}

/// What a column holds and in which unit, for the JSON Schema's descriptions
/// (the CLI's tables' columns; another gets its name).
fn describe(name: &str) -> &str {
    match name {
        "t" => "time, s (log time: t in ns)",
        "theta1" => "shoulder angle theta1, rad",
        "theta1_dot" => "shoulder rate theta1_dot, rad/s",
        "theta2" => "elbow angle theta2, rad",
        "theta2_dot" => "elbow rate theta2_dot, rad/s",
        "energy" => "mechanical energy (kinetic + gravity + spring), J",
        "mode" => "contact mode: flight, sliding or sticking",
        "f_t" => "tangential contact force f_t, N",
        "f_n" => "normal contact force f_n, N",
        "z_t" => "tip tangential position z_t, m",
        "z_n" => "tip normal position z_n (height above the belt), m",
        "z_t_dot" => "tip tangential velocity z_t_dot, m/s",
        "z_n_dot" => "tip normal velocity z_n_dot, m/s",
        "z_r_dot" => "relative tangential velocity z_t_dot - v_belt, m/s",
        "z_t_ref" => "the firmware's reference z_t*, m",
        "lift_off_true" => "the tip in flight at t (true lift-off)",
        "u1_cmd" => "shoulder torque u1 taking effect in this period, N m",
        "u2_cmd" => "elbow torque u2 taking effect in this period, N m",
        "u1_applied" => "shoulder torque u1 applied at t (the previous command), N m",
        "u2_applied" => "elbow torque u2 applied at t (the previous command), N m",
        "lift_off_detected" => "lift-off as the firmware reports it",
        "deadline_miss" => "deadline miss seen by the plant (the previous command held)",
        "firmware_deadline_miss" => "deadline miss counted by the firmware (DEADLINE_MISS)",
        "overruns" => "the firmware's overrun counter (0 without a command)",
        "status" => "the firmware's status word (0 without a command)",
        "kind" => "the event: touchdown, lift_off, p_zero, jam, slip_to_stick, ...",
        "mode_after" => "contact mode after the event",
        "v_n_before" => "normal tip velocity before the event, m/s",
        "v_n_after" => "normal tip velocity after the event, m/s",
        "v_r_before" => "relative tangential velocity before the event, m/s",
        "v_r_after" => "relative tangential velocity after the event, m/s",
        "impulse_t" => "tangential impulse of an impact, N s",
        "impulse_n" => "normal impulse of an impact, N s",
        "energy_change" => "change of mechanical energy at the event, J",
        "contact_work" => "work of the contact impulse, J",
        "resolution" => "how an impact was resolved (empty when not an impact)",
        other => other,
    }
}

/// The name of a column kind in the metadata record (`f64`, `str`, `bool`, `int`).
fn kind_name(k: Kind) -> &'static str {
    match k {
        Kind::F64 => "f64",
        Kind::Str => "str",
        Kind::Bool => "bool",
        Kind::Int => "int",
    }
}

/// The JSON Schema (draft 2020-12) of a group's messages: an object with `t`
/// and the group's columns, in the messages' order, all required; floats are
/// `number` or `null` (NaN).
fn schema_json(names: &[&str], kinds: &[Kind], group: &McapGroup) -> Result<Vec<u8>, String> {
    // Built as text: serde_json's maps sort their keys, and the order of the
    // properties is what Foxglove lists.
    let quote = |s: &str| serde_json::to_string(s).unwrap_or_default();
    let mut properties = Vec::new();
    let mut required = Vec::new();
    for name in std::iter::once(&"t").chain(group.columns) {
        let i = names.iter().position(|n| n == name).ok_or_else(|| format!("group {}: no column `{name}`", group.topic))?;
        let t = match kinds[i] {
            Kind::F64 => r#"["number","null"]"#,
            Kind::Str => r#""string""#,
            Kind::Bool => r#""boolean""#,
            Kind::Int => r#""integer""#,
        };
        properties.push(format!(r#"{}:{{"type":{t},"description":{}}}"#, quote(name), quote(describe(name))));
        required.push(quote(name));
    }
    let schema = format!(
        r#"{{"$schema":"https://json-schema.org/draft/2020-12/schema","title":{},"type":"object","properties":{{{}}},"required":[{}]}}"#,
        quote(group.schema),
        properties.join(","),
        required.join(",")
    );
    // Checked to parse, so a bad name or description fails here and not in a reader.
    serde_json::from_str::<serde_json::Value>(&schema).map_err(|e| format!("group {}: schema: {e}", group.topic))?;
    Ok(schema.into_bytes())
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
    /// [`CliError::Io`] when the header cannot be written.
    pub fn new(path: PathBuf, file: File, chunk_size: Option<u64>) -> Result<Self, CliError> {
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
    /// [`CliError::Io`] when writing fails, or when `T`'s groups name a column it
    /// lacks or leave one out (a bug of the row type, reported as an error).
    pub fn add_table<T: McapRows>(&mut self) -> Result<McapTable, CliError> {
        let bad = |what: String| CliError::Io { path: self.path.clone(), source: std::io::Error::other(what) };
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
    /// [`CliError::Io`] when writing fails.
    pub fn write<T: McapRows>(&mut self, table: McapTable, rows: &[T]) -> Result<(), CliError> {
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
    /// [`CliError::Io`] when writing fails.
    pub fn write_merged<A: McapRows, B: McapRows>(&mut self, a: (McapTable, &[A]), b: (McapTable, &[B])) -> Result<(), CliError> {
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
    fn write_row(&mut self, table: McapTable, columns: &[Column], i: usize) -> Result<(), CliError> {
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
    /// [`CliError::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), CliError> {
        self.writer.flush().map_err(mcap_err(&self.path))
    }

    /// Writes the last chunk, the summary section and the footer, and closes the file.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), CliError> {
        self.writer.finish().map_err(mcap_err(&self.path))?;
        let path = self.path.clone();
        let buffered = self.writer.into_inner();
        buffered.into_inner().map_err(|e| CliError::Io { path, source: e.into_error() })?;
        Ok(())
    }
}

/// Appends value `i` of `c` as JSON: a float with the CSV's digits (`null` for
/// NaN and infinities), an integer, `true`/`false`, a string escaped.
fn push_value(buf: &mut Vec<u8>, c: &Column, i: usize) {
    match c {
        Column::F64(v) if v[i].is_finite() => super::csv::push_f64(buf, v[i]),
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
    /// [`CliError::Io`] when the header, schemas or channels cannot be written.
    pub fn new(path: PathBuf, file: File) -> Result<Self, CliError> {
        let mut file = McapFile::new(path, file, None)?;
        let table = file.add_table::<T>()?;
        file.flush()?;
        Ok(Self { file, table, pending: Vec::with_capacity(STREAM_CHUNK_ROWS) })
    }

    /// Adds `row`; at [`STREAM_CHUNK_ROWS`] waiting rows, writes them as one chunk and flushes.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn push(&mut self, row: T) -> Result<(), CliError> {
        self.pending.push(row);
        if self.pending.len() >= STREAM_CHUNK_ROWS { self.flush() } else { Ok(()) }
    }

    /// Writes the waiting rows as one chunk and flushes the file.
    ///
    /// # Errors
    /// [`CliError::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), CliError> {
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
    /// [`CliError::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), CliError> {
        self.flush()?;
        self.file.finish()
    }
}

/// Reads the tables of the MCAP file at `path` that this module wrote: per
/// metadata record `painleve.table.<name>`, the [`Table`] of its columns (in
/// the CSV's order and types; `null` floats as NaN), row `k` made of the `k`-th
/// message of each of its topics. A file cut off (a run killed while writing)
/// gives its whole chunks, and of a table the rows whose every message is there.
/// Tables in the order of their metadata records.
///
/// # Errors
/// [`CliError::Io`] naming the file when it cannot be read, is not MCAP, holds
/// no table metadata, or a message is not the JSON object its table's columns
/// describe.
pub fn read_mcap(path: &Path) -> Result<Vec<(String, Table)>, CliError> {
    let bad = |what: String| CliError::Io { path: path.to_path_buf(), source: std::io::Error::other(what) };
    let bytes = std::fs::read(path).map_err(|source| CliError::Io { path: path.to_path_buf(), source })?;
    let lenient = || Options::IgnoreEndMagic.into();
    struct Spec {
        name: String,
        columns: Vec<String>,
        kinds: Vec<String>,
        topics: Vec<String>,
    }
    let mut specs = Vec::new();
    let records = LinearReader::new_with_options(&bytes, lenient()).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
    for record in records {
        // A cut file: its records up to the cut.
        let Ok(record) = record else { break };
        if let Record::Metadata(m) = record
            && let Some(name) = m.name.strip_prefix("painleve.table.")
        {
            let list = |k: &str| m.metadata.get(k).map(|s| s.split(',').map(String::from).collect::<Vec<_>>()).unwrap_or_default();
            specs.push(Spec { name: name.to_string(), columns: list("columns"), kinds: list("kinds"), topics: list("topics") });
        }
    }
    if specs.is_empty() {
        return Err(bad("no table in it (no painleve.table.* metadata record): not written by sil-host --format mcap".into()));
    }
    // The messages of each topic, in order.
    let mut by_topic: BTreeMap<String, Vec<serde_json::Map<String, serde_json::Value>>> = BTreeMap::new();
    let messages = MessageStream::new_with_options(&bytes, lenient()).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
    for m in messages {
        let Ok(m) = m else { break };
        let list = by_topic.entry(m.channel.topic.clone()).or_default();
        if m.sequence as usize != list.len() {
            return Err(bad(format!("{}: message {} has sequence number {}", m.channel.topic, list.len(), m.sequence)));
        }
        let data: Cow<[u8]> = m.data;
        let object = serde_json::from_slice(&data)
            .map_err(|e| bad(format!("{}: message {}: not a JSON object: {e}", m.channel.topic, list.len())))?;
        list.push(object);
    }
    let mut tables = Vec::new();
    for spec in specs {
        if spec.columns.len() != spec.kinds.len() {
            return Err(bad(format!("table {}: {} columns but {} kinds", spec.name, spec.columns.len(), spec.kinds.len())));
        }
        let empty = Vec::new();
        let topics: Vec<&Vec<_>> = spec.topics.iter().map(|t| by_topic.get(t).unwrap_or(&empty)).collect();
        let n = topics.iter().map(|m| m.len()).min().unwrap_or(0);
        let mut columns = Vec::with_capacity(spec.columns.len());
        for (name, kind) in spec.columns.iter().zip(&spec.kinds) {
            // The first topic whose messages hold the column (`t` is in all).
            let source = topics.iter().find(|m| m.first().is_some_and(|o| o.contains_key(name)));
            let value = |k: usize| source.and_then(|m| m[k].get(name.as_str()));
            let wrong = |k: usize| bad(format!("table {}: row {k}: `{name}` is not a {kind}", spec.name));
            let column = match kind.as_str() {
                "f64" => Column::F64(
                    (0..n)
                        .map(|k| match value(k) {
                            Some(serde_json::Value::Null) => Ok(f64::NAN),
                            Some(v) => v.as_f64().ok_or_else(|| wrong(k)),
                            None => Err(wrong(k)),
                        })
                        .collect::<Result<_, _>>()?,
                ),
                "int" => Column::I64(
                    (0..n).map(|k| value(k).and_then(serde_json::Value::as_i64).ok_or_else(|| wrong(k))).collect::<Result<_, _>>()?,
                ),
                "bool" => Column::Bool(
                    (0..n).map(|k| value(k).and_then(serde_json::Value::as_bool).ok_or_else(|| wrong(k))).collect::<Result<_, _>>()?,
                ),
                "str" => Column::Str(
                    (0..n)
                        .map(|k| value(k).and_then(serde_json::Value::as_str).map(String::from).ok_or_else(|| wrong(k)))
                        .collect::<Result<_, _>>()?,
                ),
                other => return Err(bad(format!("table {}: column `{name}` of unknown kind `{other}`", spec.name))),
            };
            columns.push((name.clone(), column));
        }
        tables.push((spec.name, Table { columns }));
    }
    Ok(tables)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, PartialEq)]
    struct Row {
        t: f64,
        a: f64,
        b: String,
        c: bool,
        d: u32,
    }
    crate::csv_row!(Row { t: f64, a: f64, b: str, c: bool, d: int });
    impl McapRows for Row {
        const TABLE: &'static str = "trace";
        const GROUPS: &'static [McapGroup] = &[
            McapGroup { topic: "/one", schema: "test.One", columns: &["a", "c"] },
            McapGroup { topic: "/two", schema: "test.Two", columns: &["b", "d"] },
        ];
    }

    #[derive(Debug, Clone, PartialEq)]
    struct Event {
        t: f64,
        kind: &'static str,
    }
    crate::csv_row!(Event { t: f64, kind: str });
    impl McapRows for Event {
        const TABLE: &'static str = "events";
        const GROUPS: &'static [McapGroup] = &[McapGroup { topic: "/events", schema: "test.Event", columns: &["kind"] }];
    }

    fn back(table: &Table) -> Vec<Row> {
        let [(_, Column::F64(t)), (_, Column::F64(a)), (_, Column::Str(b)), (_, Column::Bool(c)), (_, Column::I64(d))] = &table.columns[..]
        else {
            panic!("unexpected columns {:?}", table.columns)
        };
        (0..t.len()).map(|i| Row { t: t[i], a: a[i], b: b[i].clone(), c: c[i], d: u32::try_from(d[i]).unwrap() }).collect()
    }

    fn rows(n: usize) -> Vec<Row> {
        let awkward = [0.1, -0.0, 1e-300, f64::MAX, 5e-324, 1.0 / 3.0, 1e16, 123456789.0, f64::NAN, f64::INFINITY];
        (0..n)
            .map(|i| Row { t: i as f64 * 1e-3, a: awkward[i % awkward.len()], b: format!("s\"{i}\\,\n"), c: i % 3 == 0, d: i as u32 * 7 })
            .collect()
    }

    /// Every finite float back with its bits (the CSV's digits are JSON numbers
    /// that parse to them), NaN and infinities as NaN, text escaped and back.
    #[test]
    fn a_stream_round_trips_and_a_cut_one_gives_its_whole_chunks() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.mcap");
        let want = rows(250);
        let mut w = McapStream::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap();
        let mut ends = Vec::new();
        for (i, r) in want.iter().enumerate() {
            w.push(r.clone()).unwrap();
            if (i + 1) % STREAM_CHUNK_ROWS == 0 {
                ends.push(std::fs::metadata(&path).unwrap().len());
            }
        }
        w.finish().unwrap();
        let tables = read_mcap(&path).unwrap();
        assert_eq!(tables.len(), 1);
        assert_eq!(tables[0].0, "trace");
        let got = back(&tables[0].1);
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(&want) {
            let a = if w.a.is_finite() { w.a } else { f64::NAN };
            assert_eq!((g.t.to_bits(), g.a.to_bits(), &g.b, g.c, g.d), (w.t.to_bits(), a.to_bits(), &w.b, w.c, w.d));
        }
        // Killed inside the third chunk: the first two come back.
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[bytes.len() - 8..], b"\x89MCAP0\r\n");
        std::fs::write(&path, &bytes[..ends[1] as usize + 40]).unwrap();
        assert_eq!(back(&read_mcap(&path).unwrap()[0].1).len(), 2 * STREAM_CHUNK_ROWS);
        std::fs::write(&path, &bytes[..ends[1] as usize]).unwrap();
        assert_eq!(back(&read_mcap(&path).unwrap()[0].1).len(), 2 * STREAM_CHUNK_ROWS);
        // Cut anywhere (in a record's head, its body, the summary, the closing
        // magic): a prefix of the rows, as many or more for a later cut, all of
        // them once the cut is past the last chunk.
        let mut last = 0;
        for cut in (ends[0] as usize..=bytes.len()).step_by(7).chain([bytes.len() - 1, bytes.len()]) {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            let got = back(&read_mcap(&path).unwrap()[0].1);
            assert!(got.len() >= last.max(STREAM_CHUNK_ROWS), "cut at {cut}: {} rows after {last}", got.len());
            assert!(got.iter().zip(&want).all(|(g, w)| (g.t.to_bits(), &g.b, g.d) == (w.t.to_bits(), &w.b, w.d)), "cut at {cut}");
            last = got.len();
        }
        assert_eq!(last, want.len());
    }

    /// Two tables in one file, their messages in order of log time, which is
    /// `t` in ns; the same rows give the same bytes.
    #[test]
    fn merged_tables_are_in_time_order_and_deterministic() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str| {
            let path = dir.path().join(name);
            let mut f = McapFile::new(path.clone(), File::create(&path).unwrap(), Some(4096)).unwrap();
            let (tr, ev) = (f.add_table::<Row>().unwrap(), f.add_table::<Event>().unwrap());
            let events = [Event { t: 0.0, kind: "start" }, Event { t: 0.0105, kind: "touchdown" }, Event { t: 0.5, kind: "end" }];
            f.write_merged((tr, &rows(100)), (ev, &events)).unwrap();
            f.finish().unwrap();
            path
        };
        let (p, q) = (write("a.mcap"), write("b.mcap"));
        assert_eq!(std::fs::read(&p).unwrap(), std::fs::read(&q).unwrap());
        let bytes = std::fs::read(&p).unwrap();
        let times: Vec<(String, u64)> =
            MessageStream::new(&bytes).unwrap().map(|m| m.unwrap()).map(|m| (m.channel.topic.clone(), m.log_time)).collect();
        assert!(times.windows(2).all(|w| w[0].1 <= w[1].1), "log times in order");
        assert_eq!(times.iter().filter(|(t, _)| t == "/events").map(|(_, ns)| *ns).collect::<Vec<_>>(), [0, 10_500_000, 500_000_000]);
        let tables = read_mcap(&p).unwrap();
        assert_eq!(tables.iter().map(|(n, t)| (n.as_str(), t.rows())).collect::<Vec<_>>(), [("trace", 100), ("events", 3)]);
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let mut encodings: Vec<_> = summary
            .channels
            .values()
            .map(|c| (c.topic.clone(), c.message_encoding.clone(), c.schema.as_ref().unwrap().encoding.clone()))
            .collect();
        encodings.sort();
        assert_eq!(encodings[0], ("/events".to_string(), "json".to_string(), "jsonschema".to_string()));
    }

    /// The CLI's tables: every column but `t` in exactly one group, each group's
    /// columns the table's; `add_table` accepts them.
    #[test]
    fn the_cli_tables_groups_hold_each_column_once() {
        fn check<T: McapRows>() {
            let mut grouped: Vec<&str> = T::GROUPS.iter().flat_map(|g| g.columns.iter().copied()).collect();
            grouped.sort_unstable();
            let mut names: Vec<&str> = T::NAMES.iter().copied().filter(|n| *n != "t").collect();
            names.sort_unstable();
            assert_eq!(grouped, names, "{}", T::TABLE);
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("t.mcap");
            let mut f = McapFile::new(path.clone(), File::create(&path).unwrap(), None).unwrap();
            f.add_table::<T>().unwrap();
            f.finish().unwrap();
        }
        check::<crate::simulate::summary::TraceRow>();
        check::<crate::simulate::summary::EventRow>();
        check::<rig::record::PeriodRecord>();
    }

    #[test]
    fn not_mcap_is_refused_with_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.mcap");
        std::fs::write(&path, "t,theta1\n0,1\n").unwrap();
        let e = read_mcap(&path).unwrap_err().to_string();
        assert!(e.contains("trace.mcap"), "{e}");
    }
}
