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

use std::{fmt, num::IntErrorKind, path::Path};

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
    let bytes = std::fs::read(path).map_err(|e| ReadError { path: path.to_path_buf(), line: None, message: e.to_string() })?;
    parse_csv(&bytes).map_err(|(line, message)| ReadError { path: path.to_path_buf(), line, message })
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
    let columns: Vec<Infer> = (0..ncols)
        .map(|_| {
            let pieces: Vec<Infer> = parts.iter_mut().filter_map(Iterator::next).collect();
            let total = pieces.iter().map(Infer::len).sum();
            let mut c = Infer::Empty(0);
            for (k, piece) in pieces.into_iter().enumerate() {
                c.join(piece);
                if k == 0 {
                    c.reserve(total);
                }
            }
            c
        })
        .collect();
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

/// The columns of the lines `lines` (whole lines, starting at byte `at` of the
/// file), typed; the error is `(byte offset, message)`.
fn typed_lines(lines: &str, at: usize, ncols: usize) -> Result<Vec<Infer>, (usize, String)> {
    let mut columns: Vec<Infer> = (0..ncols).map(|_| Infer::Empty(0)).collect();
    // One scan of the bytes: a cell ends at `,` or at the line end (`\r\n` or
    // `\n`); both are ASCII, so every cell is a slice of whole characters.
    let (mut line, mut cell, mut n) = (0, 0, 0);
    let mut reserved = false;
    for (i, &b) in lines.as_bytes().iter().enumerate() {
        if b == b',' {
            if let Some(c) = columns.get_mut(n) {
                c.push(&lines[cell..i]);
            }
            n += 1;
            cell = i + 1;
        } else if b == b'\n' {
            let end = if i > cell && lines.as_bytes()[i - 1] == b'\r' { i - 1 } else { i };
            if n == 0 && end == line {
                // A blank line.
            } else {
                if let Some(c) = columns.get_mut(n) {
                    c.push(&lines[cell..end]);
                }
                if n + 1 != ncols {
                    return Err((at + line, format!("{} cells where the header has {ncols}", n + 1)));
                }
            }
            if !reserved && end > line {
                // Room for as many rows as lines of this one's length fit in the chunk.
                reserved = true;
                let rows = lines.len() / (i + 1 - line) + 16;
                columns.iter_mut().for_each(|c| c.reserve(rows));
            }
            (line, cell, n) = (i + 1, i + 1, 0);
        }
    }
    Ok(columns)
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
    Int(Vec<i64>),
    UInt(Vec<u64>),
    F64(Vec<f64>),
    /// Text whose earlier cells were all empty (collected as it goes).
    Str(Vec<String>),
    /// Text after typed cells, whose text was not kept: read again.
    Redo,
}

/// An integer cell: `Some(Ok(i))`, `Some(Err(()))` for one of integer syntax out of
/// `i64`'s range, `None` for anything else.
fn int(cell: &str) -> Option<Result<i64, ()>> {
    match cell.parse::<i64>() {
        Ok(i) => Some(Ok(i)),
        Err(e) if matches!(e.kind(), IntErrorKind::PosOverflow | IntErrorKind::NegOverflow) => Some(Err(())),
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
            Self::Str(v) => v.push(cell.to_string()),
            Self::Redo => {}
            Self::Empty(n) => {
                let n = *n;
                if cell.is_empty() {
                    *self = Self::Empty(n + 1);
                } else if n > 0 {
                    // Neither flags nor integers have empty cells.
                    *self = match float(cell) {
                        Some(x) => Self::F64(std::iter::repeat_n(f64::NAN, n).chain([x]).collect()),
                        None => Self::Str(std::iter::repeat_n(String::new(), n).chain([cell.to_string()]).collect()),
                    };
                } else if let Some(b) = bool_of(cell) {
                    *self = Self::Bool(vec![b]);
                } else {
                    *self = match int(cell) {
                        Some(Ok(i)) => Self::Int(vec![i]),
                        Some(Err(())) => match cell.parse::<u64>() {
                            Ok(u) => Self::UInt(vec![u]),
                            Err(_) => Self::F64(vec![float(cell).unwrap_or(f64::NAN)]),
                        },
                        None => match float(cell) {
                            Some(x) => Self::F64(vec![x]),
                            None => Self::Str(vec![cell.to_string()]),
                        },
                    };
                }
            }
            Self::Bool(v) => match bool_of(cell) {
                Some(b) => v.push(b),
                None => *self = Self::Redo,
            },
            Self::Int(v) => match int(cell) {
                Some(Ok(i)) => v.push(i),
                Some(Err(())) => match cell.parse::<u64>() {
                    Ok(u) if v.iter().all(|&i| i >= 0) => *self = Self::UInt(v.iter().map(|&i| i as u64).chain([u]).collect()),
                    _ => self.become_floats(cell),
                },
                None => self.become_floats(cell),
            },
            Self::UInt(v) => match cell.parse::<u64>() {
                Ok(u) => v.push(u),
                Err(_) => self.become_floats(cell),
            },
        }
    }

    /// The number of rows (0 for a column to read again).
    fn len(&self) -> usize {
        match self {
            Self::Empty(n) => *n,
            Self::Bool(v) => v.len(),
            Self::Int(v) => v.len(),
            Self::UInt(v) => v.len(),
            Self::F64(v) => v.len(),
            Self::Str(v) => v.len(),
            Self::Redo => 0,
        }
    }

    /// Room for `rows` rows in all (a typed column's values; nothing otherwise).
    fn reserve(&mut self, rows: usize) {
        let more = rows.saturating_sub(self.len());
        match self {
            Self::Bool(v) => v.reserve(more),
            Self::Int(v) => v.reserve(more),
            Self::UInt(v) => v.reserve(more),
            Self::F64(v) => v.reserve(more),
            Self::Str(v) => v.reserve(more),
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
                I::Int(v) => v.into_iter().map(|i| i as f64).collect(),
                I::UInt(v) => v.into_iter().map(|u| u as f64).collect(),
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
                a.extend(b);
                I::Str(a)
            }
            (I::Empty(n), I::Str(b)) => I::Str(std::iter::repeat_n(String::new(), n).chain(b).collect()),
            (I::Str(mut a), I::Empty(n)) => {
                a.extend(std::iter::repeat_n(String::new(), n));
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
            (I::Int(a), I::UInt(b)) if a.iter().all(|&i| i >= 0) => I::UInt(a.into_iter().map(|i| i as u64).chain(b).collect()),
            (I::UInt(mut a), I::Int(b)) if b.iter().all(|&i| i >= 0) => {
                a.extend(b.into_iter().map(|i| i as u64));
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
        let mut v: Vec<f64> = match self {
            Self::Int(v) => v.iter().map(|&i| i as f64).collect(),
            Self::UInt(v) => v.iter().map(|&u| u as f64).collect(),
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
            Self::Int(v) => Column::I64(v),
            Self::UInt(v) => Column::U64(v),
            Self::F64(v) => Column::F64(v),
            Self::Str(v) => Column::Str(v),
            Self::Redo => return None,
        })
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
}
