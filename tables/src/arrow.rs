//! The long tables as Arrow IPC files (`--format arrow`): `trace.arrow`,
//! `events.arrow`, the columns and values of the CSV tables they replace, typed.
//!
//! The Arrow IPC *file* format (also called Feather v2; Apache Arrow columnar
//! format 1.0, metadata version 5, no compression) is what pandas
//! (`pandas.read_feather`, with pyarrow), polars (`polars.read_ipc`), pyarrow
//! (`pyarrow.ipc.open_file`), R's `arrow` and DuckDB load directly, without
//! parsing text: a 300 s trace at 1 ms is 34 MB against 66 MB of CSV, and
//! written without formatting a single float. Writing and reading are the
//! `arrow-ipc` crate's; this module maps the rows onto its columns.
//!
//! Columns: `f64` fields are `Float64` (the value's bits, NaN and infinities
//! included), strings `Utf8`, booleans `Boolean`, integers `Int64`; none is
//! nullable. Rows go out in record batches of at most [`BATCH_ROWS`] rows, so
//! a writer holds at most one batch in memory however long the run.

use std::{
    fs::File,
    io::BufWriter,
    path::{Path, PathBuf},
    sync::Arc,
};

use arrow_array::{Array, ArrayRef, BooleanArray, Float64Array, Int64Array, RecordBatch, StringArray, UInt64Array};
use arrow_ipc::{
    reader::{FileReader, StreamReader},
    writer::{FileWriter, StreamWriter},
};
use arrow_schema::{ArrowError, DataType, Field, Schema};

use super::{Column, ColumnRows, Kind, Table};
use crate::error::Error;

/// Rows per record batch: 64 Ki rows (about 7 MB of a 14-column trace).
pub const BATCH_ROWS: usize = 1 << 16;

/// The error of an Arrow file, as the CLI reports it: the file and what failed.
fn arrow_err(path: &Path) -> impl Fn(ArrowError) -> Error + '_ {
    move |e| Error::Io {
        path: path.to_path_buf(),
        source: match e {
            ArrowError::IoError(_, io) => io,
            other => std::io::Error::other(other.to_string()),
        },
    }
}

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
        let schema = Arc::new(schema_of(T::NAMES, T::KINDS));
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

/// A table written as an Arrow IPC *stream* as a run produces it (`run` and `pil`
/// with `--format arrow`): rows wait in memory until [`ArrowStream::push`] is told
/// to write them, as one record batch, flushed to the operating system at once, so
/// a process killed outright keeps every batch written before (a reader of the
/// stream gets them; [`read_arrow`] reads a stream whose end marker is missing up to
/// its last whole batch). The stream format is the file format without its footer:
/// pandas (`pyarrow.ipc.open_stream`), polars (`polars.read_ipc_stream`) and
/// `painleve.load` read it.
pub struct ArrowStream<T: ColumnRows> {
    path: PathBuf,
    writer: StreamWriter<File>,
    schema: Arc<Schema>,
    pending: Vec<T>,
}

impl<T: ColumnRows> ArrowStream<T> {
    /// Starts the stream `file` (at `path`, for error messages) with `T`'s schema.
    ///
    /// # Errors
    /// [`Error::Io`] when the schema message cannot be written.
    pub fn new(path: PathBuf, file: File) -> Result<Self, Error> {
        let schema = Arc::new(schema_of(T::NAMES, T::KINDS));
        let writer = StreamWriter::try_new(file, &schema).map_err(arrow_err(&path))?;
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

    /// Writes the rows still waiting and the end-of-stream marker.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.write_pending()?;
        self.writer.finish().map_err(arrow_err(&self.path))
    }
}

/// The Arrow schema of columns `names` of kinds `kinds`: one non-nullable field
/// per column (`Float64`, `Utf8`, `Boolean`, `Int64`).
fn schema_of(names: &[&str], kinds: &[Kind]) -> Schema {
    let field = |(name, kind): (&&str, &Kind)| {
        let t = match kind {
            Kind::F64 => DataType::Float64,
            Kind::Str => DataType::Utf8,
            Kind::Bool => DataType::Boolean,
            Kind::Int => DataType::Int64,
        };
        Field::new(*name, t, false)
    };
    Schema::new(names.iter().zip(kinds).map(field).collect::<Vec<_>>())
}

/// A column as an Arrow array (the values move; strings are copied once).
fn array_of(c: Column) -> ArrayRef {
    match c {
        Column::F64(v) => Arc::new(Float64Array::from(v)),
        Column::I64(v) => Arc::new(Int64Array::from(v)),
        Column::U64(v) => Arc::new(UInt64Array::from(v)),
        Column::Bool(v) => Arc::new(BooleanArray::from(v)),
        Column::Str(v) => Arc::new(StringArray::from_iter_values(v)),
    }
}

/// An empty column of Arrow type `t`, or `None` for a type the tables never hold.
fn empty_column(t: &DataType) -> Option<Column> {
    Some(match t {
        DataType::Float64 => Column::F64(Vec::new()),
        DataType::Int64 => Column::I64(Vec::new()),
        DataType::Boolean => Column::Bool(Vec::new()),
        DataType::Utf8 => Column::Str(Vec::new()),
        _ => return None,
    })
}

/// Appends the values of the Arrow array `a` to `c`; `None` when `a` is of
/// another type, or has nulls where the column cannot hold them (a null float
/// reads as NaN, a null string as `""`).
fn extend(c: &mut Column, a: &dyn Array) -> Option<()> {
    let any = a.as_any();
    match c {
        Column::F64(v) => {
            let a = any.downcast_ref::<Float64Array>()?;
            v.extend((0..a.len()).map(|i| if a.is_null(i) { f64::NAN } else { a.value(i) }));
        }
        Column::I64(v) => {
            let a = any.downcast_ref::<Int64Array>()?;
            if a.null_count() > 0 {
                return None;
            }
            v.extend_from_slice(a.values());
        }
        Column::U64(_) => return None,
        Column::Bool(v) => {
            let a = any.downcast_ref::<BooleanArray>()?;
            if a.null_count() > 0 {
                return None;
            }
            v.extend((0..a.len()).map(|i| a.value(i)));
        }
        Column::Str(v) => {
            let a = any.downcast_ref::<StringArray>()?;
            v.extend((0..a.len()).map(|i| if a.is_null(i) { String::new() } else { a.value(i).to_string() }));
        }
    }
    Some(())
}

/// Reads the Arrow IPC file or stream at `path` into a [`Table`]: its columns in
/// the file's order, every record batch appended. A stream cut off (a run killed
/// while writing, [`ArrowStream`]) gives its whole batches.
///
/// # Errors
/// [`Error::Io`] naming the file when it cannot be read, is neither an Arrow
/// IPC file (nor one cut off before its footer) nor a stream, or has a column of
/// another type than Float64, Int64, Boolean or Utf8.
pub fn read_arrow(path: &Path) -> Result<Table, Error> {
    let bad = |msg: String| Error::Io { path: path.to_path_buf(), source: std::io::Error::other(msg) };
    let mut file = File::open(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    // The file format starts with the magic `ARROW1`; the stream format (`run`,
    // `pil`) with a message.
    let mut magic = [0u8; 6];
    let is_file = std::io::Read::read_exact(&mut file, &mut magic).is_ok() && &magic == b"ARROW1";
    std::io::Seek::rewind(&mut file).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let (schema, batches): (Arc<Schema>, Box<dyn Iterator<Item = Result<RecordBatch, ArrowError>>>) = if is_file {
        let reader = FileReader::try_new_buffered(file, None).map_err(arrow_err(path))?;
        (reader.schema(), Box::new(reader))
    } else {
        let reader = StreamReader::try_new_buffered(file, None).map_err(arrow_err(path))?;
        // A stream cut off (a killed run): its whole batches, the cut one dropped.
        let mut done = false;
        (reader.schema(), Box::new(reader.take_while(move |b| !std::mem::replace(&mut done, b.is_err())).filter(Result::is_ok)))
    };
    let mut columns = Vec::with_capacity(schema.fields().len());
    for f in schema.fields() {
        let c = empty_column(f.data_type())
            .ok_or_else(|| bad(format!("column `{}` is {}, not Float64, Int64, Boolean or Utf8", f.name(), f.data_type())))?;
        columns.push((f.name().clone(), c));
    }
    for batch in batches {
        let batch = batch.map_err(arrow_err(path))?;
        for ((name, c), a) in columns.iter_mut().zip(batch.columns()) {
            extend(c, a.as_ref()).ok_or_else(|| bad(format!("column `{name}`: a batch of another type, or nulls where none can be")))?;
        }
    }
    Ok(Table { columns })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[derive(Debug, Clone, PartialEq)]
    struct Row {
        a: f64,
        b: String,
        c: bool,
        d: u32,
    }
    crate::csv_row!(Row { a: f64, b: str, c: bool, d: int });

    fn write(rows: Vec<Row>) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.arrow");
        let mut w = ArrowFile::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap();
        let mut rows = rows;
        w.push(&mut rows).unwrap();
        assert!(rows.is_empty());
        w.finish().unwrap();
        (dir, path)
    }

    fn back(cols: &[(String, Column)]) -> Vec<Row> {
        let [(na, Column::F64(a)), (nb, Column::Str(b)), (nc, Column::Bool(c)), (nd, Column::I64(d))] = cols else {
            panic!("unexpected columns {cols:?}")
        };
        assert_eq!([na, nb, nc, nd], ["a", "b", "c", "d"]);
        (0..a.len()).map(|i| Row { a: a[i], b: b[i].clone(), c: c[i], d: u32::try_from(d[i]).unwrap() }).collect()
    }

    proptest! {
        /// Every value comes back with its bits (NaN, -0.0, infinities), over
        /// batch boundaries.
        #[test]
        fn rows_round_trip(rows in proptest::collection::vec((any::<f64>(), ".{0,8}", any::<bool>(), any::<u32>()), 0..50)) {
            let rows: Vec<Row> = rows.into_iter().map(|(a, b, c, d)| Row { a, b, c, d }).collect();
            let (_dir, path) = write(rows.clone());
            let got = back(&read_arrow(&path).unwrap().columns);
            prop_assert_eq!(got.len(), rows.len());
            for (g, r) in got.iter().zip(&rows) {
                prop_assert_eq!(g.a.to_bits(), r.a.to_bits());
                prop_assert_eq!(&g.b, &r.b);
                prop_assert_eq!(g.c, r.c);
                prop_assert_eq!(g.d, r.d);
            }
        }
    }

    #[test]
    fn more_rows_than_a_batch_come_back_in_order() {
        let n = BATCH_ROWS * 2 + 7;
        let rows: Vec<Row> = (0..n).map(|i| Row { a: i as f64 * 0.5, b: format!("{}", i % 3), c: i % 2 == 0, d: i as u32 }).collect();
        let (_dir, path) = write(rows.clone());
        assert_eq!(back(&read_arrow(&path).unwrap().columns), rows);
    }

    #[test]
    fn an_empty_table_keeps_its_columns() {
        let (_dir, path) = write(Vec::new());
        let cols = read_arrow(&path).unwrap().columns;
        assert_eq!(cols.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["a", "b", "c", "d"]);
        assert!(cols.iter().all(|(_, c)| c.is_empty()));
    }

    /// A stream (`run --format arrow`): every batch back, in order; cut off after
    /// two whole batches (a killed run), those two.
    #[test]
    fn a_stream_is_read_whole_and_a_cut_one_to_its_last_whole_batch() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.arrow");
        let rows: Vec<Row> = (0..30).map(|i| Row { a: i as f64 * 0.25, b: format!("r{i}"), c: i % 3 == 0, d: i }).collect();
        let mut w = ArrowStream::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap();
        let mut ends = Vec::new();
        for (i, r) in rows.iter().enumerate() {
            let write = (i + 1) % 10 == 0;
            w.push(r.clone(), write).unwrap();
            if write {
                ends.push(std::fs::metadata(&path).unwrap().len());
            }
        }
        w.finish().unwrap();
        assert_eq!(back(&read_arrow(&path).unwrap().columns), rows);
        let bytes = std::fs::read(&path).unwrap();
        // Killed inside the third batch: the first two come back.
        std::fs::write(&path, &bytes[..ends[1] as usize + 17]).unwrap();
        assert_eq!(back(&read_arrow(&path).unwrap().columns), rows[..20]);
    }

    #[test]
    fn a_file_cut_before_its_footer_is_refused_with_its_path() {
        let rows: Vec<Row> = (0..100).map(|i| Row { a: i as f64, b: String::new(), c: true, d: 1 }).collect();
        let (_dir, path) = write(rows);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 20]).unwrap();
        let e = read_arrow(&path).unwrap_err().to_string();
        assert!(e.contains("t.arrow"), "{e}");
        std::fs::write(&path, b"trace.csv is not arrow").unwrap();
        assert!(read_arrow(&path).is_err());
    }
}
