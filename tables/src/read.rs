//! Reading the CLI's tables back (`painleve.read_csv`, `painleve.load`): a CSV
//! file into a [`Table`], each column typed from its cells, and the same typing
//! for a table read from Arrow ([`as_read_from_csv`]), so a table reads the same
//! from either format.
//!
//! The typing rule (the one `painleve`'s former pure-Python reader applied, and
//! `pandas.read_csv`'s for these files), per column:
//!
//! - no cell holds a value (every cell empty, or a table without rows):
//!   [`Column::F64`] of NaN, whatever the column held (a CSV cell carries no type);
//! - every cell `true` or `false`: [`Column::Bool`];
//! - every cell an integer (`[+-]?[0-9]+`, none empty): [`Column::I64`], or
//!   [`Column::U64`] when one is above `i64::MAX` and none is negative;
//! - every cell a number or empty: [`Column::F64`], an empty cell NaN (so an
//!   integer column with an empty cell is a float column). A number is what
//!   Python's `float` reads: Rust's correctly rounded parser (the same bits),
//!   `NaN`, `inf`, `infinity` in any case, with a sign, surrounding whitespace and
//!   `_` between digits allowed;
//! - otherwise text, [`Column::Str`], an empty cell `""`.
//!
//! A file the CLI writes ends with a line end and has as many cells in each row
//! as in its header; anything else is refused with the line where it goes wrong
//! (a file cut off while it was written ends inside a row), as is text that is
//! not UTF-8 and a header naming a column twice. Blank lines are skipped; an
//! empty file is a table without columns.
//!
//! How a file is read ([`read_csv_coded`]): a file the CLI writes (no quote, one
//! line end at its end) is read in chunks of lines, each chunk read from the file
//! (`pread`, into a buffer of its thread) and typed on rayon's threads, its
//! number cells parsed as the cells are split (`fast-float2`, correctly rounded:
//! the bits of `str::parse::<f64>`, tested), its text coded by distinct values
//! (no string per cell); the chunks' columns are then joined, a column per
//! thread. Any other file (quotes, a file cut off, a bad row, not UTF-8, a column
//! that turns out text after numbers) is read whole by [`parse_csv`], which gives
//! the same table, or the error with its line.

use std::{collections::HashMap, fmt, fs::File, num::IntErrorKind, os::unix::fs::FileExt, path::Path};

use super::{Column, Table};

/// Why a CSV table cannot be read: the file, the line (1-based; `None` for the
/// file as a whole) and what is wrong there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadError {
    /// The file.
    pub path: std::path::PathBuf,
    /// The line where it goes wrong.
    pub line: Option<u64>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "cannot read {}: line {line}: {}", self.path.display(), self.message),
            None => write!(f, "cannot read {}: {}", self.path.display(), self.message),
        }
    }
}

impl std::error::Error for ReadError {}

/// Reads the CSV table at `path` (a header row, then one row per line), each
/// column typed by the rule of this module.
///
/// # Errors
/// [`ReadError`] when the file cannot be read, is not UTF-8, ends inside a row,
/// has a row with another number of cells than its header, or names a column twice.
pub fn read_csv(path: &Path) -> Result<Table, ReadError> {
    let columns = read_csv_coded(path)?;
    Ok(Table { columns: columns.into_iter().map(|(name, c)| (name, c.into_column())).collect() })
}

/// A column as [`read_csv_coded`] gives it: typed values, or text coded by its
/// distinct values (a trace's `mode` has three values in 300 000 rows).
#[derive(Debug, Clone, PartialEq)]
pub enum ReadColumn {
    /// Floats, integers or flags: [`Column::F64`], [`Column::I64`], [`Column::U64`]
    /// or [`Column::Bool`], never [`Column::Str`].
    Values(Column),
    /// Text: `values`, the distinct cells in order of first appearance, and
    /// `codes`, one per row, the index of its cell in `values`.
    Text {
        /// The distinct cells, in order of first appearance.
        values: Vec<String>,
        /// Per row, the index of its cell in `values`.
        codes: Vec<u32>,
    },
}

impl ReadColumn {
    /// `col` as a [`ReadColumn`]: a [`Column::Str`] coded by its distinct cells, any
    /// other column as it is.
    pub fn of(col: Column) -> Self {
        match col {
            Column::Str(cells) => {
                let mut c = Coded::default();
                for cell in &cells {
                    c.push(cell);
                }
                c.into_read_column()
            }
            other => Self::Values(other),
        }
    }

    /// The column as a [`Column`] (text as [`Column::Str`], a string per row).
    pub fn into_column(self) -> Column {
        match self {
            Self::Values(col) => col,
            Self::Text { values, codes } => Column::Str(codes.iter().map(|&c| values[c as usize].clone()).collect()),
        }
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        match self {
            Self::Values(col) => col.len(),
            Self::Text { codes, .. } => codes.len(),
        }
    }

    /// Whether it has no row.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// [`read_csv`] with text columns coded by their distinct values
/// ([`ReadColumn::Text`]), `(name, column)` in the file's order: the same
/// table, without a string per text cell (what `painleve.read_csv` reads).
///
/// # Errors
/// As [`read_csv`].
pub fn read_csv_coded(path: &Path) -> Result<Vec<(String, ReadColumn)>, ReadError> {
    if let Some(columns) = read_plain_file(path, READ_CHUNK_BYTES) {
        return Ok(columns);
    }
    let bytes = std::fs::read(path).map_err(|e| ReadError { path: path.to_path_buf(), line: None, message: e.to_string() })?;
    let table = parse_csv(&bytes).map_err(|(line, message)| ReadError { path: path.to_path_buf(), line, message })?;
    Ok(table.columns.into_iter().map(|(name, c)| (name, ReadColumn::of(c))).collect())
}

/// [`read_csv`] of the file's bytes; the error is `(line, message)`.
///
/// # Errors
/// As [`read_csv`].
pub fn parse_csv(bytes: &[u8]) -> Result<Table, (Option<u64>, String)> {
    if bytes.is_empty() {
        return Ok(Table::default());
    }
    let line_at = |offset: usize| 1 + bytes[..offset].iter().filter(|&&b| b == b'\n').count() as u64;
    if !bytes.ends_with(b"\n") {
        return Err((Some(line_at(bytes.len())), "the file ends inside a row (a file cut off while it was written?)".into()));
    }
    if !bytes.contains(&b'"') {
        // No quoted cell (the CLI quotes only text holding `,`, `"` or a line end):
        // rows are lines and cells are split at commas, in parallel.
        let text = std::str::from_utf8(bytes).map_err(|e| (Some(line_at(e.valid_up_to())), "not UTF-8 text".to_string()))?;
        return parse_plain(text).map_err(|(offset, message)| (Some(line_at(offset)), message));
    }
    let reader = || csv::ReaderBuilder::new().has_headers(true).flexible(true).from_reader(bytes);
    let fail = |e: csv::Error| {
        let line = e.position().map(csv::Position::line);
        let message = match e.kind() {
            csv::ErrorKind::Utf8 { err, .. } => format!("not UTF-8 text (in cell {})", err.field() + 1),
            _ => e.to_string(),
        };
        (line, message)
    };
    let mut r = reader();
    let header: Vec<String> = r.headers().map_err(fail)?.iter().map(str::to_string).collect();
    twice(&header).map_err(|m| (Some(1), m))?;
    let mut columns: Vec<Infer> = header.iter().map(|_| Infer::Empty(0)).collect();
    let mut record = csv::StringRecord::new();
    let mut rows = 0usize;
    while r.read_record(&mut record).map_err(fail)? {
        if record.len() != header.len() {
            let line = record.position().map(csv::Position::line);
            return Err((line, format!("{} cells where the header has {}", record.len(), header.len())));
        }
        for (c, cell) in columns.iter_mut().zip(record.iter()) {
            c.push(cell);
        }
        rows += 1;
    }
    // The columns that turned out text after typed cells: their text, from a second pass.
    let redo: Vec<usize> = (0..columns.len()).filter(|&i| matches!(columns[i], Infer::Redo)).collect();
    let mut text: Vec<Vec<String>> = redo.iter().map(|_| Vec::with_capacity(rows)).collect();
    if !redo.is_empty() {
        let mut r = reader();
        while r.read_record(&mut record).map_err(fail)? {
            for (t, &i) in text.iter_mut().zip(&redo) {
                t.push(record[i].to_string());
            }
        }
    }
    let mut text = text.into_iter();
    let columns = header
        .into_iter()
        .zip(columns)
        .map(|(name, c)| {
            let col = c.finish().unwrap_or_else(|| Column::Str(text.next().unwrap_or_default()));
            (name, col)
        })
        .collect();
    Ok(Table { columns })
}

/// Refuses a header that names a column twice.
fn twice(header: &[String]) -> Result<(), String> {
    match header.iter().enumerate().find(|(i, name)| header[..*i].contains(name)) {
        Some((_, name)) => Err(format!("the header names the column `{name}` twice")),
        None => Ok(()),
    }
}

/// Bytes per chunk of rows typed on one thread, at least.
const CHUNK_BYTES: usize = 1 << 20;

/// [`parse_csv`] of a file without quotes (UTF-8, ending with a line end): a
/// row per line (a `\r` before the `\n` dropped, blank lines skipped), cells
/// split at commas; the rows typed in chunks on rayon's threads, the chunks'
/// columns then joined ([`Infer::join`]: the same types and values as one pass).
/// The error is `(byte offset, message)`.
fn parse_plain(text: &str) -> Result<Table, (usize, String)> {
    let end = text.find('\n').unwrap_or(text.len());
    let header: Vec<String> = text[..end].strip_suffix('\r').unwrap_or(&text[..end]).split(',').map(str::to_string).collect();
    twice(&header).map_err(|m| (0, m))?;
    if text[..end].trim_end_matches('\r').is_empty() {
        // A blank first line: no header, no table (as the csv crate reads it).
        return Ok(Table::default());
    }
    let body_at = (end + 1).min(text.len());
    let body = &text[body_at..];
    // Chunks of whole lines, one or a few per thread.
    let parts = (body.len() / CHUNK_BYTES).clamp(1, 4 * rayon::current_num_threads());
    let mut bounds = vec![0];
    for k in 1..parts {
        let at = (body.len() * k / parts).max(*bounds.last().unwrap_or(&0));
        match body.as_bytes()[at..].iter().position(|&b| b == b'\n') {
            Some(i) if at + i + 1 < body.len() => bounds.push(at + i + 1),
            _ => break,
        }
    }
    bounds.push(body.len());
    bounds.dedup();
    let ncols = header.len();
    use rayon::prelude::*;
    let chunks: Vec<Vec<Infer>> =
        bounds.par_windows(2).map(|w| typed_lines(&body[w[0]..w[1]], body_at + w[0], ncols)).collect::<Result<_, _>>()?;
    // Each column's chunks joined, its values copied once.
    let mut parts: Vec<std::vec::IntoIter<Infer>> = chunks.into_iter().map(Vec::into_iter).collect();
    let columns: Vec<Infer> = (0..ncols).map(|_| Infer::join_all(parts.iter_mut().filter_map(Iterator::next).collect())).collect();
    // The columns that turned out text after typed cells: their text, from a second pass.
    let redo: Vec<usize> = (0..ncols).filter(|&i| matches!(columns[i], Infer::Redo)).collect();
    let mut text_of: Vec<Vec<String>> = redo.iter().map(|_| Vec::new()).collect();
    if !redo.is_empty() {
        for line in body.split_terminator('\n') {
            let line = line.strip_suffix('\r').unwrap_or(line);
            if line.is_empty() {
                continue;
            }
            let mut cells = line.split(',');
            let mut at = 0;
            for (t, &i) in text_of.iter_mut().zip(&redo) {
                let cell = cells.nth(i - at).unwrap_or_default();
                at = i + 1;
                t.push(cell.to_string());
            }
        }
    }
    let mut text_of = text_of.into_iter();
    let columns = header
        .into_iter()
        .zip(columns)
        .map(|(name, c)| (name, c.finish().unwrap_or_else(|| Column::Str(text_of.next().unwrap_or_default()))))
        .collect();
    Ok(Table { columns })
}

/// The columns of the lines `lines` (whole lines, the last ending with `\n`,
/// starting at byte `at` of the file), typed; the error is `(byte offset of the
/// row, message)`.
fn typed_lines(lines: &str, at: usize, ncols: usize) -> Result<Vec<Infer>, (usize, String)> {
    let b = lines.as_bytes();
    let mut columns: Vec<Infer> = (0..ncols).map(|_| Infer::Empty(0)).collect();
    let mut reserved = false;
    let mut i = 0;
    while i < b.len() {
        let line = i;
        // A blank line (`\n` or `\r\n`).
        if b[i] == b'\n' {
            i += 1;
            continue;
        }
        if b[i] == b'\r' && b.get(i + 1) == Some(&b'\n') {
            i += 2;
            continue;
        }
        // A cell ends at `,` or at the line end (`\r\n` or `\n`); all are ASCII, so
        // every cell is a slice of whole characters.
        let mut n = 0;
        loop {
            let end = match columns.get_mut(n) {
                Some(c) => c.push_at(lines, i),
                None => cell_end(b, i),
            };
            n += 1;
            match b[end] {
                b',' => i = end + 1,
                b'\n' => {
                    i = end + 1;
                    break;
                }
                // `\r\n`
                _ => {
                    i = end + 2;
                    break;
                }
            }
        }
        if n != ncols {
            return Err((at + line, format!("{n} cells where the header has {ncols}")));
        }
        if !reserved {
            // Room for as many rows as lines of this one's length fit in the chunk.
            reserved = true;
            let rows = b.len() / (i - line) + 16;
            columns.iter_mut().for_each(|c| c.reserve(rows));
        }
    }
    Ok(columns)
}

/// The end of the cell starting at byte `i` of `b` (whole lines, the last ending
/// with `\n`): the index of the `,` or `\n` after it, or of the `\r` of a `\r\n`.
#[inline]
fn cell_end(b: &[u8], i: usize) -> usize {
    let e = memchr::memchr2(b',', b'\n', &b[i..]).map_or(b.len() - 1, |d| i + d);
    if b[e] == b'\n' && e > i && b[e - 1] == b'\r' { e - 1 } else { e }
}

/// `Some(e)` when byte `e` of `b` ends a cell (`,`, `\n`, or the `\r` of `\r\n`).
#[inline]
fn delimited(b: &[u8], e: usize) -> Option<usize> {
    match b.get(e) {
        Some(b',' | b'\n') => Some(e),
        Some(b'\r') if b.get(e + 1) == Some(&b'\n') => Some(e),
        _ => None,
    }
}

/// The number cell starting at byte `i` of `b` and its end ([`cell_end`]), when
/// it is a decimal number (an optional sign, then a digit or `.`) that
/// `fast-float2` reads to the cell's end: correctly rounded, the value
/// `str::parse::<f64>` gives (tested). `None` for any other cell (empty, `inf`,
/// `NaN`, with spaces or `_`, not a number), which [`float`] decides.
#[inline]
fn number_at(b: &[u8], i: usize) -> Option<(f64, usize)> {
    let s = &b[i..];
    let digit = |k: usize| s.get(k).is_some_and(|&c| c.is_ascii_digit() || c == b'.');
    if !(digit(0) || (matches!(s.first(), Some(b'-' | b'+')) && digit(1))) {
        return None;
    }
    let (x, n) = fast_float2::parse_partial::<f64, _>(s).ok()?;
    delimited(b, i + n).map(|end| (x, end))
}

/// The integer cell (`[+-]?[0-9]+` in `i64`'s range) starting at byte `i` of `b`
/// and its end; `None` for any other cell, which [`int`] decides.
#[inline]
fn integer_at(b: &[u8], i: usize) -> Option<(i64, usize)> {
    let (negative, mut k) = match b.get(i) {
        Some(b'-') => (true, i + 1),
        Some(b'+') => (false, i + 1),
        _ => (false, i),
    };
    let digits = k;
    let mut v: i64 = 0;
    while let Some(&c) = b.get(k)
        && c.is_ascii_digit()
    {
        let d = i64::from(c - b'0');
        v = v.checked_mul(10)?;
        v = if negative { v.checked_sub(d)? } else { v.checked_add(d)? };
        k += 1;
    }
    if k == digits {
        return None;
    }
    delimited(b, k).map(|end| (v, end))
}

/// Bytes of a file per chunk of lines read and typed on one thread.
const READ_CHUNK_BYTES: usize = 1 << 19;

std::thread_local! {
    /// Each thread's buffer for the chunks it reads (kept between calls).
    static CHUNK_BUFFER: std::cell::RefCell<Vec<u8>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// [`read_csv_coded`] of a file the CLI writes (UTF-8, no quote, ending with a
/// line end, a header naming each column once, every row with the header's
/// number of cells, no column text after numbers), in chunks of lines (of
/// `chunk` bytes, [`READ_CHUNK_BYTES`]) read and typed in parallel ([`typed_lines`]); the chunks' columns joined ([`Infer::join`]:
/// the types and values of one pass). `None` for any other file, or when the
/// file cannot be read: [`parse_csv`] of its bytes then decides (the same
/// table, or the error and its line).
fn read_plain_file(path: &Path, chunk: usize) -> Option<Vec<(String, ReadColumn)>> {
    use rayon::prelude::*;
    let file = File::open(path).ok()?;
    let len = usize::try_from(file.metadata().ok()?.len()).ok()?;
    if len == 0 {
        return None;
    }
    let mut last = [0u8];
    file.read_exact_at(&mut last, (len - 1) as u64).ok()?;
    if last[0] != b'\n' {
        return None;
    }
    // The header: the first line.
    let mut head = vec![0u8; len.min(1 << 16)];
    file.read_exact_at(&mut head, 0).ok()?;
    let end = loop {
        if let Some(e) = memchr::memchr(b'\n', &head) {
            break e;
        }
        let more = (len - head.len()).min(1 << 16);
        let at = head.len();
        head.resize(at + more, 0);
        file.read_exact_at(&mut head[at..], at as u64).ok()?;
    };
    let line = std::str::from_utf8(&head[..end]).ok()?;
    let line = line.strip_suffix('\r').unwrap_or(line);
    if line.is_empty() || line.contains('"') {
        return None;
    }
    let header: Vec<String> = line.split(',').map(str::to_string).collect();
    twice(&header).ok()?;
    let ncols = header.len();
    let body_at = end + 1;
    let parts = (len - body_at).div_ceil(chunk);
    let chunks: Vec<Vec<Infer>> = (0..parts)
        .into_par_iter()
        .map(|k| CHUNK_BUFFER.with_borrow_mut(|buf| read_chunk(&file, buf, (body_at, len), (k, chunk), ncols)))
        .collect::<Option<_>>()?;
    // Each column's chunks joined, a column per thread.
    let mut by_column: Vec<Vec<Infer>> = (0..ncols).map(|_| Vec::with_capacity(chunks.len())).collect();
    for chunk in chunks {
        for (c, piece) in by_column.iter_mut().zip(chunk) {
            c.push(piece);
        }
    }
    let columns: Vec<ReadColumn> = by_column.into_par_iter().map(|pieces| Infer::join_all(pieces).finish_coded()).collect::<Option<_>>()?;
    Some(header.into_iter().zip(columns).collect())
}

/// The columns of the lines of chunk `k` of the file's body (bytes `body_at..len`,
/// in chunks of `chunk` bytes): the lines that start in its bytes, read into `buf`. `None` when the file cannot be read, changed, or the lines are not
/// UTF-8, hold a quote, or a row has another number of cells than the header.
fn read_chunk(
    file: &File,
    buf: &mut Vec<u8>,
    (body_at, len): (usize, usize),
    (k, chunk): (usize, usize),
    ncols: usize,
) -> Option<Vec<Infer>> {
    let start = body_at + k * chunk;
    let end = (start + chunk).min(len);
    // From the byte before the chunk: a line starts after a `\n`.
    let from = if k == 0 { start } else { start - 1 };
    buf.resize(end - from, 0);
    file.read_exact_at(buf, from as u64).ok()?;
    let first = if k == 0 {
        0
    } else {
        match memchr::memchr(b'\n', &buf[..buf.len() - 1]) {
            Some(i) => i + 1,
            // No line starts in this chunk.
            None => return Some((0..ncols).map(|_| Infer::Empty(0)).collect()),
        }
    };
    // To the end of the line the chunk's last byte is in.
    while buf.last() != Some(&b'\n') {
        let at = buf.len();
        let more = (len - (from + at)).min(1 << 16);
        if more == 0 {
            return None;
        }
        buf.resize(at + more, 0);
        file.read_exact_at(&mut buf[at..], (from + at) as u64).ok()?;
        if let Some(i) = memchr::memchr(b'\n', &buf[at..]) {
            buf.truncate(at + i + 1);
        }
    }
    let lines = &buf[first..];
    if memchr::memchr(b'"', lines).is_some() {
        return None;
    }
    let lines = std::str::from_utf8(lines).ok()?;
    typed_lines(lines, from + first, ncols).ok()
}

/// `table` (read from Arrow) with the columns a CSV of it reads back as, so a
/// table reads the same from either format: a text column is typed from its
/// cells by this module's rule (a column of empty strings is NaN, one of numbers
/// is numbers), and every column of a table without rows is an empty
/// [`Column::F64`]. Float, integer and boolean columns with rows are kept (their
/// CSV cells read back as the same values).
pub fn as_read_from_csv(table: Table) -> Table {
    let empty = table.rows() == 0;
    let columns = table
        .columns
        .into_iter()
        .map(|(name, col)| {
            let col = match col {
                _ if empty => Column::F64(Vec::new()),
                Column::Str(cells) => {
                    let mut c = Infer::Empty(0);
                    for cell in &cells {
                        c.push(cell);
                    }
                    c.finish().unwrap_or(Column::Str(cells))
                }
                other => other,
            };
            (name, col)
        })
        .collect();
    Table { columns }
}

/// A column being typed from its cells, one at a time.
enum Infer {
    /// Only empty cells so far (their count).
    Empty(usize),
    Bool(Vec<bool>),
    Int(Ints<i64>),
    UInt(Ints<u64>),
    F64(Vec<f64>),
    /// Text whose earlier cells were all empty (collected as it goes, coded by
    /// distinct cells).
    Str(Coded),
    /// Text after typed cells, whose text was not kept: read again.
    Redo,
}

/// The integers of a column, and the rows whose cell is a negative zero (`-0`,
/// an integer, but `-0.0` once the column is floats, as Python's `float` reads it).
struct Ints<T> {
    v: Vec<T>,
    negative_zeros: Vec<usize>,
}

impl<T: Copy> Ints<T> {
    fn of(x: T, negative_zero: bool) -> Self {
        Self { v: vec![x], negative_zeros: if negative_zero { vec![0] } else { Vec::new() } }
    }

    #[inline]
    fn push(&mut self, x: T, negative_zero: bool) {
        if negative_zero {
            self.negative_zeros.push(self.v.len());
        }
        self.v.push(x);
    }

    fn extend(&mut self, next: Self) {
        let at = self.v.len();
        self.negative_zeros.extend(next.negative_zeros.into_iter().map(|i| at + i));
        self.v.extend(next.v);
    }

    /// The same cells as another type of integers.
    fn map<U>(self, f: impl Fn(T) -> U) -> Ints<U> {
        Ints { v: self.v.into_iter().map(f).collect(), negative_zeros: self.negative_zeros }
    }

    /// The cells as floats (each integer rounded correctly, as Python's `float`
    /// reads its digits; `-0` is `-0.0`).
    fn floats(self, f: impl Fn(T) -> f64) -> Vec<f64> {
        let mut x: Vec<f64> = self.v.into_iter().map(f).collect();
        for i in self.negative_zeros {
            x[i] = -0.0;
        }
        x
    }
}

/// Whether an integer cell of value `i` is a negative zero (`-0`, `-00`).
fn negative_zero(cell: &str, i: i64) -> bool {
    i == 0 && cell.starts_with('-')
}

/// An integer cell: `Some(Ok(i))`, `Some(Err(()))` for one of integer syntax out of
/// `i64`'s range, `None` for anything else.
fn int(cell: &str) -> Option<Result<i64, ()>> {
    match cell.parse::<i64>() {
        Ok(i) => Some(Ok(i)),
        // Integer syntax to the end (the parser reports an overflow before it has
        // seen every character: `10000000000000000000e` is no integer).
        Err(e) if matches!(e.kind(), IntErrorKind::PosOverflow | IntErrorKind::NegOverflow) => {
            let digits = cell.strip_prefix(['+', '-']).unwrap_or(cell);
            digits.bytes().all(|c| c.is_ascii_digit()).then_some(Err(()))
        }
        Err(_) => None,
    }
}

/// A number cell as Python's `float` reads it.
fn float(cell: &str) -> Option<f64> {
    if let Ok(x) = cell.parse::<f64>() {
        return Some(x);
    }
    // Python also takes surrounding whitespace and `_` between two digits.
    let s = cell.trim();
    let b = s.as_bytes();
    let underscores_ok = b
        .iter()
        .enumerate()
        .all(|(i, &c)| c != b'_' || (i > 0 && i + 1 < b.len() && b[i - 1].is_ascii_digit() && b[i + 1].is_ascii_digit()));
    if !underscores_ok || (s.len() == cell.len() && !s.contains('_')) {
        return None;
    }
    s.replace('_', "").parse::<f64>().ok()
}

fn bool_of(cell: &str) -> Option<bool> {
    match cell {
        "true" => Some(true),
        "false" => Some(false),
        _ => None,
    }
}

impl Infer {
    #[inline]
    fn push(&mut self, cell: &str) {
        match self {
            Self::F64(v) => match if cell.is_empty() { Some(f64::NAN) } else { float(cell) } {
                Some(x) => v.push(x),
                None => *self = Self::Redo,
            },
            Self::Str(v) => v.push(cell),
            Self::Redo => {}
            Self::Empty(n) => {
                let n = *n;
                if cell.is_empty() {
                    *self = Self::Empty(n + 1);
                } else if n > 0 {
                    // Neither flags nor integers have empty cells.
                    *self = match float(cell) {
                        Some(x) => Self::F64(std::iter::repeat_n(f64::NAN, n).chain([x]).collect()),
                        None => {
                            let mut text = Coded::empty(n);
                            text.push(cell);
                            Self::Str(text)
                        }
                    };
                } else if let Some(b) = bool_of(cell) {
                    *self = Self::Bool(vec![b]);
                } else {
                    *self = match int(cell) {
                        Some(Ok(i)) => Self::Int(Ints::of(i, negative_zero(cell, i))),
                        Some(Err(())) => match cell.parse::<u64>() {
                            Ok(u) => Self::UInt(Ints::of(u, false)),
                            Err(_) => Self::F64(vec![float(cell).unwrap_or(f64::NAN)]),
                        },
                        None => match float(cell) {
                            Some(x) => Self::F64(vec![x]),
                            None => Self::Str(Coded::empty(0).and(cell)),
                        },
                    };
                }
            }
            Self::Bool(v) => match bool_of(cell) {
                Some(b) => v.push(b),
                None => *self = Self::Redo,
            },
            Self::Int(v) => match int(cell) {
                Some(Ok(i)) => v.push(i, negative_zero(cell, i)),
                Some(Err(())) => match cell.parse::<u64>() {
                    Ok(u) if v.v.iter().all(|&i| i >= 0) => {
                        let Self::Int(v) = std::mem::replace(self, Self::Redo) else { unreachable!() };
                        let mut v = v.map(|i| i as u64);
                        v.push(u, false);
                        *self = Self::UInt(v);
                    }
                    _ => self.become_floats(cell),
                },
                None => self.become_floats(cell),
            },
            // `-0` is no `u64` (and the column's `-0`s, read before, are kept).
            Self::UInt(v) => match cell.parse::<u64>() {
                Ok(u) => v.push(u, false),
                Err(_) => self.become_floats(cell),
            },
        }
    }

    /// The number of rows (0 for a column to read again).
    fn len(&self) -> usize {
        match self {
            Self::Empty(n) => *n,
            Self::Bool(v) => v.len(),
            Self::Int(v) => v.v.len(),
            Self::UInt(v) => v.v.len(),
            Self::F64(v) => v.len(),
            Self::Str(v) => v.codes.len(),
            Self::Redo => 0,
        }
    }

    /// Room for `rows` rows in all (a typed column's values; nothing otherwise).
    fn reserve(&mut self, rows: usize) {
        let more = rows.saturating_sub(self.len());
        match self {
            Self::Bool(v) => v.reserve(more),
            Self::Int(v) => v.v.reserve(more),
            Self::UInt(v) => v.v.reserve(more),
            Self::F64(v) => v.reserve(more),
            Self::Str(v) => v.codes.reserve(more),
            Self::Empty(_) | Self::Redo => {}
        }
    }

    /// Appends `next`, the same column typed over the rows that follow: the
    /// column one pass over all the rows gives (its type depends only on which
    /// kinds of cells it holds, the rule of this module).
    fn join(&mut self, next: Self) {
        use Infer as I;
        let nan = |n: usize| std::iter::repeat_n(f64::NAN, n);
        let floats = |c: Self| -> Vec<f64> {
            match c {
                I::Int(v) => v.floats(|i| i as f64),
                I::UInt(v) => v.floats(|u| u as f64),
                I::F64(v) => v,
                I::Empty(n) => vec![f64::NAN; n],
                _ => unreachable!("only numbers and empty cells are floats"),
            }
        };
        let this = std::mem::replace(self, I::Redo);
        *self = match (this, next) {
            (I::Redo, _) | (_, I::Redo) => I::Redo,
            (I::Empty(a), I::Empty(b)) => I::Empty(a + b),
            (a, I::Empty(0)) => a,
            (I::Empty(0), b) => b,
            (I::Bool(mut a), I::Bool(b)) => {
                a.extend(b);
                I::Bool(a)
            }
            // Flags have no empty cell, and no other cell.
            (I::Bool(_), _) | (_, I::Bool(_)) => I::Redo,
            (I::Str(mut a), I::Str(b)) => {
                a.append(b);
                I::Str(a)
            }
            (I::Empty(n), I::Str(b)) => {
                let mut a = Coded::empty(n);
                a.append(b);
                I::Str(a)
            }
            (I::Str(mut a), I::Empty(n)) => {
                a.append(Coded::empty(n));
                I::Str(a)
            }
            // Text after numbers, or numbers after text: the numbers' text is gone.
            (I::Str(_), _) | (_, I::Str(_)) => I::Redo,
            (I::Int(mut a), I::Int(b)) => {
                a.extend(b);
                I::Int(a)
            }
            (I::UInt(mut a), I::UInt(b)) => {
                a.extend(b);
                I::UInt(a)
            }
            (I::Int(a), I::UInt(b)) if a.v.iter().all(|&i| i >= 0) => {
                let mut a = a.map(|i| i as u64);
                a.extend(b);
                I::UInt(a)
            }
            (I::UInt(mut a), I::Int(b)) if b.v.iter().all(|&i| i >= 0) => {
                a.extend(b.map(|i| i as u64));
                I::UInt(a)
            }
            (I::Empty(n), b) => I::F64(nan(n).chain(floats(b)).collect()),
            (a, b) => {
                let mut a = floats(a);
                a.extend(floats(b));
                I::F64(a)
            }
        };
    }

    /// An integer column meeting a cell that is not one of its integers: floats
    /// (each integer converted with correct rounding, as Python's `float` reads
    /// its digits), or text.
    fn become_floats(&mut self, cell: &str) {
        let x = if cell.is_empty() { Some(f64::NAN) } else { float(cell) };
        let Some(x) = x else {
            *self = Self::Redo;
            return;
        };
        let mut v: Vec<f64> = match std::mem::replace(self, Self::Redo) {
            Self::Int(v) => v.floats(|i| i as f64),
            Self::UInt(v) => v.floats(|u| u as f64),
            _ => unreachable!("only integer columns become floats"),
        };
        v.push(x);
        *self = Self::F64(v);
    }

    /// The column, or `None` for one to read again as text.
    fn finish(self) -> Option<Column> {
        Some(match self {
            Self::Empty(n) => Column::F64(vec![f64::NAN; n]),
            Self::Bool(v) => Column::Bool(v),
            Self::Int(v) => Column::I64(v.v),
            Self::UInt(v) => Column::U64(v.v),
            Self::F64(v) => Column::F64(v),
            Self::Str(v) => Column::Str(v.strings()),
            Self::Redo => return None,
        })
    }

    /// The column as [`ReadColumn`] (text coded), or `None` for one to read again as text.
    fn finish_coded(self) -> Option<ReadColumn> {
        match self {
            Self::Str(v) => Some(v.into_read_column()),
            other => other.finish().map(ReadColumn::Values),
        }
    }

    /// The column of `pieces`, the same column over consecutive rows, joined
    /// ([`Infer::join`]), each value copied once.
    fn join_all(pieces: Vec<Self>) -> Self {
        let total = pieces.iter().map(Self::len).sum();
        let mut c = Self::Empty(0);
        let mut reserved = false;
        for piece in pieces {
            c.join(piece);
            if !reserved && c.len() > 0 && !matches!(c, Self::Empty(_)) {
                reserved = true;
                c.reserve(total);
            }
        }
        c
    }

    /// Pushes the cell starting at byte `i` of `text` (whole lines, the last
    /// ending with `\n`) and returns its end ([`cell_end`]): a number cell of a
    /// float column or an integer cell of an integer column parsed as it is
    /// split ([`number_at`], [`integer_at`]), any other cell by [`Infer::push`].
    #[inline]
    fn push_at(&mut self, text: &str, i: usize) -> usize {
        let b = text.as_bytes();
        match self {
            Self::F64(v) => {
                if let Some((x, end)) = number_at(b, i) {
                    v.push(x);
                    return end;
                }
            }
            Self::Int(v) => {
                if let Some((x, end)) = integer_at(b, i) {
                    v.push(x, x == 0 && b[i] == b'-');
                    return end;
                }
            }
            _ => {}
        }
        let end = cell_end(b, i);
        self.push(&text[i..end]);
        end
    }
}

/// Text cells coded by their distinct values: `values` in order of first
/// appearance, `codes` one per cell (no string per cell).
#[derive(Default)]
struct Coded {
    values: Vec<String>,
    index: HashMap<String, u32>,
    codes: Vec<u32>,
}

impl Coded {
    /// `n` empty cells.
    fn empty(n: usize) -> Self {
        let mut c = Self::default();
        if n > 0 {
            let code = c.code("");
            c.codes = vec![code; n];
        }
        c
    }

    /// With `cell` pushed.
    fn and(mut self, cell: &str) -> Self {
        self.push(cell);
        self
    }

    /// Pushes a cell.
    #[inline]
    fn push(&mut self, cell: &str) {
        // Runs of the same cell (a trace's mode) without a hash.
        if let Some(&last) = self.codes.last()
            && self.values[last as usize] == cell
        {
            self.codes.push(last);
            return;
        }
        let code = self.code(cell);
        self.codes.push(code);
    }

    /// The code of `cell`, a new one for a cell not seen before.
    fn code(&mut self, cell: &str) -> u32 {
        if let Some(&c) = self.index.get(cell) {
            return c;
        }
        // As many distinct cells as rows at most, and a file has fewer than 2^32 rows
        // (each takes a line end).
        let c = self.values.len() as u32;
        self.values.push(cell.to_string());
        self.index.insert(cell.to_string(), c);
        c
    }

    /// Appends `next`'s cells (recoded into this one's values).
    fn append(&mut self, next: Self) {
        let map: Vec<u32> = next.values.iter().map(|v| self.code(v)).collect();
        self.codes.extend(next.codes.iter().map(|&c| map[c as usize]));
    }

    /// A string per cell.
    fn strings(self) -> Vec<String> {
        self.codes.iter().map(|&c| self.values[c as usize].clone()).collect()
    }

    fn into_read_column(self) -> ReadColumn {
        ReadColumn::Text { values: self.values, codes: self.codes }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn col<'a>(t: &'a Table, name: &str) -> &'a Column {
        &t.columns.iter().find(|(n, _)| n == name).unwrap().1
    }

    fn f64s(c: &Column) -> Vec<u64> {
        match c {
            Column::F64(v) => v.iter().map(|x| x.to_bits()).collect(),
            other => panic!("not floats: {other:?}"),
        }
    }

    #[test]
    fn columns_are_typed_from_their_cells() {
        let t = parse_csv(b"a,b,c,d,e,f,g,h\n1,1.5,true,x,,2,1,\"q,\"\"\"\n2,NaN,false,,,,y,\n").unwrap();
        assert_eq!(t.columns.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["a", "b", "c", "d", "e", "f", "g", "h"]);
        assert_eq!(*col(&t, "a"), Column::I64(vec![1, 2]));
        assert_eq!(f64s(col(&t, "b")), [1.5f64.to_bits(), f64::NAN.to_bits()]);
        assert_eq!(*col(&t, "c"), Column::Bool(vec![true, false]));
        assert_eq!(*col(&t, "d"), Column::Str(vec!["x".into(), String::new()]));
        assert_eq!(f64s(col(&t, "e")), [f64::NAN.to_bits(); 2], "no value: NaN");
        assert_eq!(f64s(col(&t, "f")), [2f64.to_bits(), f64::NAN.to_bits()], "an integer column with an empty cell is floats");
        assert_eq!(*col(&t, "g"), Column::Str(vec!["1".into(), "y".into()]), "text after a number: read again");
        assert_eq!(*col(&t, "h"), Column::Str(vec!["q,\"".into(), String::new()]));
    }

    #[test]
    fn integers_beyond_i64_are_u64_and_floats_keep_their_bits() {
        let t = parse_csv(b"u,v,x\n1,-1,0.1\n18446744073709551615,18446744073709551615,1e-320\n").unwrap();
        assert_eq!(*col(&t, "u"), Column::U64(vec![1, u64::MAX]));
        assert_eq!(f64s(col(&t, "v")), [(-1f64).to_bits(), (u64::MAX as f64).to_bits()]);
        assert_eq!(f64s(col(&t, "x")), [0.1f64.to_bits(), 1e-320f64.to_bits()]);
        let t = parse_csv(b"x\n 1.5\n1_000.25\ninf\n-Infinity\n").unwrap();
        assert_eq!(f64s(col(&t, "x")), [1.5f64, 1000.25, f64::INFINITY, f64::NEG_INFINITY].map(f64::to_bits));
        let t = parse_csv(b"x\n1__0\n").unwrap();
        assert_eq!(*col(&t, "x"), Column::Str(vec!["1__0".into()]));
    }

    #[test]
    fn a_header_alone_gives_empty_float_columns_and_an_empty_file_no_column() {
        let t = parse_csv(b"a,b\n").unwrap();
        assert_eq!(t.columns, [("a".to_string(), Column::F64(vec![])), ("b".to_string(), Column::F64(vec![]))]);
        assert_eq!(parse_csv(b"").unwrap(), Table::default());
        let t = parse_csv(b"a,b\n\n1,2\n\n").unwrap();
        assert_eq!(t.rows(), 1, "blank lines are skipped");
    }

    #[test]
    fn bad_files_are_refused_with_the_line() {
        let e = parse_csv(b"a,b\n1,2\n3,4").unwrap_err();
        assert_eq!(e.0, Some(3));
        assert!(e.1.contains("ends inside a row"), "{}", e.1);
        let e = parse_csv(b"a,b\n1,2\n3\n").unwrap_err();
        assert_eq!(e, (Some(3), "1 cells where the header has 2".into()));
        let e = parse_csv(b"a,b\n1,2,3\n").unwrap_err();
        assert_eq!(e.0, Some(2));
        let e = parse_csv(b"a,a\n1,2\n").unwrap_err();
        assert!(e.1.contains("`a` twice"), "{}", e.1);
        let e = parse_csv(b"a,b\n1,\xff\xfe\n").unwrap_err();
        assert_eq!(e.0, Some(2));
        assert!(e.1.contains("UTF-8"), "{}", e.1);
        let dir = tempfile::tempdir().unwrap();
        let e = read_csv(&dir.path().join("none.csv")).unwrap_err();
        assert!(e.to_string().starts_with("cannot read ") && e.to_string().contains("none.csv"), "{e}");
    }

    #[test]
    fn an_arrow_table_reads_as_its_csv() {
        let t = Table {
            columns: vec![
                ("s".into(), Column::Str(vec![String::new(), String::new()])),
                ("n".into(), Column::Str(vec!["1".into(), "2".into()])),
                ("m".into(), Column::Str(vec!["flight".into(), String::new()])),
                ("i".into(), Column::I64(vec![3, 4])),
            ],
        };
        let got = as_read_from_csv(t);
        assert_eq!(f64s(col(&got, "s")), [f64::NAN.to_bits(); 2]);
        assert_eq!(*col(&got, "n"), Column::I64(vec![1, 2]));
        assert_eq!(*col(&got, "m"), Column::Str(vec!["flight".into(), String::new()]));
        assert_eq!(*col(&got, "i"), Column::I64(vec![3, 4]));
        let none = Table { columns: vec![("i".into(), Column::I64(vec![])), ("b".into(), Column::Bool(vec![]))] };
        assert!(as_read_from_csv(none).columns.iter().all(|(_, c)| *c == Column::F64(vec![])));
    }

    /// Columns as comparable values: floats by their bits (NaN's too).
    fn exact(columns: Vec<(String, Column)>) -> Vec<(String, String)> {
        let text = |c: Column| match c {
            Column::F64(v) => format!("F64{:?}", v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()),
            other => format!("{other:?}"),
        };
        columns.into_iter().map(|(n, c)| (n, text(c))).collect()
    }

    /// The reference of the fused scan ([`typed_lines`]): a CSV without quotes
    /// split line by line and cell by cell, each column's cells typed by
    /// [`Infer::push`] (text from its cells when it turns out text after numbers).
    fn cell_by_cell(text: &str) -> Vec<(String, Column)> {
        let mut lines = text.split_terminator('\n').map(|l| l.strip_suffix('\r').unwrap_or(l));
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let mut cells: Vec<Vec<&str>> = header.iter().map(|_| Vec::new()).collect();
        for line in lines.filter(|l| !l.is_empty()) {
            for (c, cell) in cells.iter_mut().zip(line.split(',')) {
                c.push(cell);
            }
        }
        header
            .iter()
            .zip(cells)
            .map(|(name, cells)| {
                let mut c = Infer::Empty(0);
                cells.iter().for_each(|cell| c.push(cell));
                let col = c.finish().unwrap_or_else(|| Column::Str(cells.iter().map(|s| s.to_string()).collect()));
                (name.to_string(), col)
            })
            .collect()
    }

    /// A cell of a column of the kind `kind`: floats, integers, flags, text, or anything.
    fn cell(kind: u8) -> proptest::strategy::BoxedStrategy<String> {
        use proptest::prelude::*;
        let tricky = proptest::sample::select(vec![
            "",
            "0",
            "-0",
            "+1",
            "1e5",
            "1E+05",
            "-.5",
            "5.",
            ".",
            "1e",
            "1e-",
            "-",
            "+",
            "inf",
            "-Infinity",
            "NaN",
            "nan",
            "-nan",
            " 1.5",
            "1.5 ",
            "1_000",
            "1__0",
            "0x10",
            "1.5\r",
            "9223372036854775807",
            "9223372036854775808",
            "-9223372036854775808",
            "-9223372036854775809",
            "18446744073709551616",
            "1e400",
            "-1e-400",
            "5e-324",
            "2.2250738585072011e-308",
            "0.10000000000000000555111512312578270211815834045410156250001",
            "123456789012345678901234567890",
            "true",
            "false",
            "flight",
            "sliding",
            "É",
        ])
        .prop_map(str::to_string);
        match kind {
            0 => prop_oneof![4 => any::<f64>().prop_map(|x| x.to_string()), 1 => "[-+]?[0-9]{0,22}(\\.[0-9]{0,22})?([eE][-+]?[0-9]{0,4})?", 1 => Just(String::new())].boxed(),
            1 => prop_oneof![4 => any::<i64>().prop_map(|i| i.to_string()), 1 => Just(String::new()), 1 => Just("18446744073709551615".to_string())].boxed(),
            2 => proptest::sample::select(vec!["true", "false"]).prop_map(str::to_string).boxed(),
            3 => proptest::sample::select(vec!["flight", "sliding", "sticking", ""]).prop_map(str::to_string).boxed(),
            _ => prop_oneof![2 => tricky, 1 => "[-+.0-9eE_ infatyINF]{0,8}"].boxed(),
        }
    }

    /// A CSV without quotes: a header, rows of cells of each column's kind, `\n` or
    /// `\r\n` line ends, some blank lines.
    fn table() -> impl proptest::strategy::Strategy<Value = String> {
        use proptest::prelude::*;
        proptest::collection::vec(0u8..6, 1..6).prop_flat_map(|kinds| {
            let row = kinds.iter().map(|&k| cell(k)).collect::<Vec<_>>();
            (proptest::collection::vec((row, 0u8..12), 0..60), any::<bool>()).prop_map(move |(rows, crlf)| {
                let end = if crlf { "\r\n" } else { "\n" };
                let mut text = (0..kinds.len()).map(|i| format!("c{i}")).collect::<Vec<_>>().join(",") + end;
                for (cells, blank) in rows {
                    if blank == 0 {
                        text += end;
                    }
                    text += &cells.join(",");
                    text += end;
                }
                text
            })
        })
    }

    proptest::proptest! {
        #[test]
        fn the_fused_number_and_integer_parsers_agree_with_std(s in "[-+.0-9eE_ infatyINF]{0,30}|[-+]?[0-9]{0,25}(\\.[0-9]{0,25})?([eE][-+]?[0-9]{0,5})?") {
            let b = format!("{s},");
            if let Some((x, end)) = number_at(b.as_bytes(), 0) {
                proptest::prop_assert_eq!(end, s.len());
                proptest::prop_assert_eq!(s.parse::<f64>().map(f64::to_bits), Ok(x.to_bits()), "{:?}", s);
            }
            if let Some((i, end)) = integer_at(b.as_bytes(), 0) {
                proptest::prop_assert_eq!(end, s.len());
                proptest::prop_assert_eq!(s.parse::<i64>(), Ok(i), "{:?}", s);
            }
            // A plain decimal (what the CLI writes) takes the fast path.
            if s.parse::<f64>().is_ok() && !s.contains(['_', ' ', 'i', 'n', 'I', 'N', 'a', 't', 'f', 'y']) {
                proptest::prop_assert!(number_at(b.as_bytes(), 0).is_some(), "{:?}", s);
            }
        }

        #[test]
        fn the_fused_scan_types_as_cell_by_cell_and_chunks_as_one_pass(text in table()) {
            let whole = parse_csv(text.as_bytes()).unwrap();
            proptest::prop_assert_eq!(exact(whole.columns.clone()), exact(cell_by_cell(&text)));
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("t.csv");
            std::fs::write(&path, &text).unwrap();
            for chunk in [1, 2, 3, 7, 64, 1 << 20] {
                if let Some(columns) = read_plain_file(&path, chunk) {
                    let got = columns.into_iter().map(|(n, c)| (n, c.into_column())).collect();
                    proptest::prop_assert_eq!(exact(got), exact(whole.columns.clone()), "chunks of {} bytes", chunk);
                }
            }
            let coded = read_csv_coded(&path).unwrap().into_iter().map(|(n, c)| (n, c.into_column())).collect();
            proptest::prop_assert_eq!(exact(coded), exact(whole.columns));
        }
    }

    #[test]
    fn a_long_file_the_cli_writes_is_read_in_chunks_as_one_pass() {
        // Kinds that change between chunks, none text after numbers: the chunked reader.
        let mut text = String::from("t,i,late_float,gap,flag,mode,none,u\n");
        let n = 20_000;
        for k in 0..n {
            let late = if k == n - 3 { "2.5".to_string() } else { k.to_string() };
            let gap = if k < n / 2 { String::new() } else { (k as f64 * 0.1).to_string() };
            let mode = ["flight", "sliding", ""][k % 3];
            let u = if k == n / 3 { "18446744073709551615".to_string() } else { k.to_string() };
            text += &format!("{},{k},{late},{gap},{},{mode},,{u}\n", k as f64 * 1e-3, k % 2 == 0);
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.csv");
        std::fs::write(&path, &text).unwrap();
        let whole = parse_csv(text.as_bytes()).unwrap();
        for chunk in [100, 4096, READ_CHUNK_BYTES] {
            let got = read_plain_file(&path, chunk).expect("a file the CLI writes takes the chunked reader");
            let got: Vec<(String, Column)> = got.into_iter().map(|(n, c)| (n, c.into_column())).collect();
            assert_eq!(exact(got), exact(whole.columns.clone()), "chunks of {chunk} bytes");
        }
        let kinds: Vec<&str> = whole
            .columns
            .iter()
            .map(|(_, c)| match c {
                Column::F64(_) => "f",
                Column::I64(_) => "i",
                Column::U64(_) => "u",
                Column::Bool(_) => "b",
                Column::Str(_) => "s",
            })
            .collect();
        assert_eq!(kinds, ["f", "i", "f", "f", "b", "s", "f", "u"]);
        // Text coded by its distinct values, in order of first appearance.
        let coded = read_csv_coded(&path).unwrap();
        let ReadColumn::Text { values, codes } = &coded[5].1 else { panic!("mode is text") };
        assert_eq!(values, &["flight", "sliding", ""]);
        assert_eq!(codes.len(), n);
        // Files the chunked reader leaves to the whole-file reader.
        let others: [&[u8]; 7] = [b"a,b\n1,\"x\"\n", b"a,b\n1,2\n3", b"a,a\n1,2\n", b"a,b\n1\n", b"a\n1\nx\n", b"\n", b"a,b\n1,\xff\n"];
        for other in others {
            std::fs::write(&path, other).unwrap();
            assert!(read_plain_file(&path, 4).is_none(), "{:?}", String::from_utf8_lossy(other));
        }
    }
}
