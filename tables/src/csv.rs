//! A fast CSV writer for the long tables (`trace.csv`, `events.csv`) whose
//! output is byte for byte the one of the `csv` crate's serde path
//! (`csv::Writer::serialize`, default settings) it replaces.
//!
//! Why: at a 1 ms trace, formatting rows through serde and `csv-core` (and
//! floats through `ryu`) cost as much as the simulation itself (docs/measurements.md,
//! "Speed and scale (issue 16)"). Here a row is appended straight to a byte
//! buffer: floats by [`zmij`] (shortest round-trip digits, like `ryu`, about
//! twice as fast) with `ryu`'s notation restored, integers by [`itoa`], and
//! strings with the `csv` crate's quoting rule. The tests in this module and
//! `tests/fastcsv.rs` check the equality against the `csv` crate over
//! arbitrary values.

use std::{fs::File, io::Write, path::PathBuf};

use crate::{
    error::{Error, io_err},
    writer::{RowSink, WriterThread},
};

/// Bytes buffered before they go to the file (one `write` system call each).
pub const FLUSH_BYTES: usize = 1 << 20;

/// Appends `v` as the `csv` crate writes an `f64` field: `ryu`'s format, i.e.
/// the shortest digits that read back to `v`, in plain notation for decimal
/// exponents -5..=15 (`0.001`, `1.0`, `-0.0`, `12340000000.0`) and in exponent
/// notation otherwise (`1e-7`, `1.234e33`, no `+`), and `NaN`, `inf`, `-inf`.
#[inline]
pub fn push_f64(buf: &mut Vec<u8>, v: f64) {
    if !v.is_finite() {
        // ryu ignores the sign of a NaN.
        buf.extend_from_slice(if v.is_nan() {
            b"NaN"
        } else if v > 0.0 {
            b"inf"
        } else {
            b"-inf"
        });
        return;
    }
    let mut b = zmij::Buffer::new();
    let s = b.format_finite(v).as_bytes();
    // zmij and ryu agree on the digits and on where plain notation stops
    // (checked in the tests); they differ only in zmij's `e+` for positive
    // exponents (`1e+30`, ryu `1e30`), which only a number >= 1e16 has.
    if v.abs() >= 1e16
        && let Some(p) = s.iter().position(|&c| c == b'+')
    {
        buf.extend_from_slice(&s[..p]);
        buf.extend_from_slice(&s[p + 1..]);
        return;
    }
    buf.extend_from_slice(s);
}

/// Appends `s` as the `csv` crate writes a string field with its default
/// settings (`QuoteStyle::Necessary`, `"` as quote, `\n` as terminator): in
/// double quotes, with `"` doubled, when it holds `,`, `"`, `\r` or `\n`; as it
/// is otherwise.
#[inline]
pub fn push_str(buf: &mut Vec<u8>, s: &str) {
    let bytes = s.as_bytes();
    if !bytes.iter().any(|&c| matches!(c, b',' | b'"' | b'\r' | b'\n')) {
        buf.extend_from_slice(bytes);
        return;
    }
    buf.push(b'"');
    for &c in bytes {
        if c == b'"' {
            buf.push(b'"');
        }
        buf.push(c);
    }
    buf.push(b'"');
}

/// Appends `b` as `true` or `false`.
#[inline]
pub fn push_bool(buf: &mut Vec<u8>, b: bool) {
    buf.extend_from_slice(if b { b"true" } else { b"false" });
}

/// Appends the decimal digits of `n`.
#[inline]
pub fn push_int<I: itoa::Integer>(buf: &mut Vec<u8>, n: I) {
    buf.extend_from_slice(itoa::Buffer::new().format(n).as_bytes());
}

/// A row of a CSV table written by [`push_row`]: the same bytes as
/// `csv::Writer::serialize` of the row (its header from the field names).
pub trait CsvRow {
    /// The column names, in order (the struct's field names).
    const HEADER: &'static [&'static str];

    /// Appends the fields, each followed by `,` (the last one's is replaced by
    /// the terminator in [`push_row`]).
    fn push_fields(&self, buf: &mut Vec<u8>);
}

/// Appends one record of `fields` (comma separated, `\n` terminated).
pub fn push_header(buf: &mut Vec<u8>, fields: &[&str]) {
    for f in fields {
        push_str(buf, f);
        buf.push(b',');
    }
    end_record(buf, fields.len());
}

/// Appends `row` and its terminator.
#[inline]
pub fn push_row<T: CsvRow>(buf: &mut Vec<u8>, row: &T) {
    row.push_fields(buf);
    end_record(buf, T::HEADER.len());
}

/// Replaces the trailing `,` by `\n` (a record of one empty field is `""`, as
/// the `csv` crate writes it).
#[inline]
fn end_record(buf: &mut Vec<u8>, n_fields: usize) {
    match buf.last_mut() {
        Some(last @ b',') => {
            *last = b'\n';
            if n_fields == 1 && (buf.len() == 1 || buf[buf.len() - 2] == b'\n') {
                buf.pop();
                buf.extend_from_slice(b"\"\"\n");
            }
        }
        _ => buf.push(b'\n'),
    }
}

/// Declares a long table's row type ([`crate::Declared`], as [`crate::declare!`])
/// and implements [`CsvRow`] and [`crate::ColumnRows`] for it from the same
/// fields, each with its kind: `f64`, `str` (a `&str` or `String` field), `bool`,
/// `int` (an integer that converts to `i64` without loss). The CSV header, the
/// columns (Arrow, NumPy) and the MCAP groups list the same columns in the same order.
/// A `str` field is anything that is `AsRef<str>` (a `&'static str`, a `String`,
/// an enum that names its variants). [`crate::table_row!`] declares the struct
/// itself with it, each field's kind beside its type.
#[macro_export]
macro_rules! csv_row {
    ($ty:ty { $($field:ident : $kind:ident),+ $(,)? }) => {
        $crate::declare!($ty { $($field : $kind),+ });
        impl $crate::csv::CsvRow for $ty {
            const HEADER: &'static [&'static str] = <$ty as $crate::Declared>::NAMES;
            #[inline]
            fn push_fields(&self, buf: &mut Vec<u8>) {
                $(
                    $crate::csv_row!(@push buf, $kind, self.$field);
                    buf.push(b',');
                )+
            }
        }
        impl $crate::ColumnRows for $ty {
            fn columns(rows: &[Self]) -> Vec<$crate::Column> {
                vec![$($crate::csv_row!(@column rows, $kind, $field)),+]
            }
        }
    };
    (@column $rows:ident, f64, $f:ident) => { $crate::Column::F64($rows.iter().map(|r| r.$f).collect()) };
    (@column $rows:ident, str, $f:ident) => { $crate::Column::Str($rows.iter().map(|r| -> String { AsRef::<str>::as_ref(&r.$f).to_string() }).collect()) };
    (@column $rows:ident, bool, $f:ident) => { $crate::Column::Bool($rows.iter().map(|r| r.$f).collect()) };
    (@column $rows:ident, int, $f:ident) => { $crate::Column::I64($rows.iter().map(|r| i64::from(r.$f)).collect()) };
    (@push $buf:ident, f64, $v:expr) => { $crate::csv::push_f64($buf, $v) };
    (@push $buf:ident, str, $v:expr) => { $crate::csv::push_str($buf, AsRef::<str>::as_ref(&$v)) };
    (@push $buf:ident, bool, $v:expr) => { $crate::csv::push_bool($buf, $v) };
    (@push $buf:ident, int, $v:expr) => { $crate::csv::push_int($buf, $v) };
}

/// Declares a long table's row type once: the struct, each field with its
/// column kind beside its type (`pub t: f64 => f64`), and from that the
/// declaration, the CSV row and the columns ([`crate::csv_row!`]). The field
/// order is the column order. Attributes (docs, derives, serde's) go where they
/// go on a struct:
///
/// ```
/// tables::table_row! {
///     /// One sample.
///     #[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
///     pub struct Sample {
///         /// Time, s.
///         pub t: f64 => f64,
///         /// A counter.
///         pub n: u32 => int,
///     }
/// }
/// assert_eq!(<Sample as tables::Declared>::NAMES, ["t", "n"]);
/// ```
#[macro_export]
macro_rules! table_row {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $( $(#[$fmeta:meta])* $fvis:vis $field:ident : $ty:ty => $kind:ident ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        $vis struct $name {
            $( $(#[$fmeta])* $fvis $field : $ty, )+
        }
        $crate::csv_row!($name { $($field : $kind),+ });
    };
}

/// A CSV file written through a byte buffer of about [`FLUSH_BYTES`]: one
/// system call per mebibyte, nothing else allocated per row.
pub struct CsvFile {
    path: PathBuf,
    file: File,
    buf: Vec<u8>,
}

impl CsvFile {
    /// Wraps `file` (at `path`, for error messages), writing the header `header` first.
    pub fn new(path: PathBuf, file: File, header: &[&str]) -> Self {
        let mut buf = Vec::with_capacity(FLUSH_BYTES + 4096);
        push_header(&mut buf, header);
        Self { path, file, buf }
    }

    /// Appends `row`; writes the buffer out when it is full.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    #[inline]
    pub fn row<T: CsvRow>(&mut self, row: &T) -> Result<(), Error> {
        push_row(&mut self.buf, row);
        if self.buf.len() >= FLUSH_BYTES { self.flush() } else { Ok(()) }
    }

    /// Writes what is buffered to the file (to the operating system, not to disk).
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn flush(&mut self) -> Result<(), Error> {
        self.file.write_all(&self.buf).map_err(io_err(&self.path))?;
        self.buf.clear();
        Ok(())
    }

    /// The path written to.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// Writes the rest and closes the file.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn finish(mut self) -> Result<(), Error> {
        self.flush()
    }
}

impl<T: CsvRow> RowSink<T> for CsvFile {
    const THREAD_NAME: &'static str = "csv-writer";
    const FORMAT: &'static str = "CSV";

    fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// Appends the rows ([`CsvFile::row`]) and clears `rows`.
    fn write_rows(&mut self, rows: &mut Vec<T>) -> Result<(), Error> {
        for r in rows.iter() {
            self.row(r)?;
        }
        rows.clear();
        Ok(())
    }

    fn finish(self) -> Result<(), Error> {
        CsvFile::finish(self)
    }
}

/// A [`CsvFile`] written by a thread of its own ([`WriterThread`]): the caller
/// hands over chunks of rows and goes on (the simulation) while they are
/// formatted and written, so on two cores the trace costs little more than the
/// simulation alone. At most [`WriterThread::DEPTH`] chunks wait in the channel
/// (bounded memory); emptied chunks come back for reuse. The file is the one
/// [`CsvFile`] writes given the same rows.
pub type CsvThread<T> = WriterThread<T, CsvFile>;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The old path: one record through `csv::Writer::serialize`.
    fn via_csv<T: serde::Serialize>(v: T) -> Vec<u8> {
        let mut w = csv::WriterBuilder::new().has_headers(false).from_writer(Vec::new());
        w.serialize(v).unwrap();
        w.into_inner().unwrap()
    }

    fn via_fast(f: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
        let mut buf = Vec::new();
        f(&mut buf);
        buf.push(b',');
        end_record(&mut buf, 1);
        buf
    }

    #[test]
    fn special_floats_match_the_csv_crate() {
        let cases = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            1e-5,
            1e-6,
            1e-7,
            1e15,
            9.999999999999998e15,
            1e16,
            1e21,
            1.234e33,
            -1.5543122344752192e-15,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for v in cases {
            assert_eq!(via_fast(|b| push_f64(b, v)), via_csv((v,)), "{v:e}");
        }
        // A sweep over every binary exponent, with a few mantissas each.
        for e in 0..2048u64 {
            for m in [0u64, 1, 0x8_0000_0000_0000, 0xF_FFFF_FFFF_FFFF, 0x3_3333_3333_3333] {
                for s in [0u64, 1] {
                    let v = f64::from_bits(s << 63 | e << 52 | m);
                    assert_eq!(via_fast(|b| push_f64(b, v)), via_csv((v,)), "{:#x}", v.to_bits());
                }
            }
        }
    }

    #[derive(Debug, Clone, serde::Serialize)]
    struct Row {
        a: f64,
        b: &'static str,
        c: bool,
        d: u32,
    }
    crate::csv_row!(Row { a: f64, b: str, c: bool, d: int });

    #[test]
    fn the_writer_thread_writes_every_row_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let rows: Vec<Row> = (0..5000).map(|i| Row { a: f64::from(i) * 0.1, b: "x,y", c: i % 3 == 0, d: i }).collect();
        let csv = CsvFile::new(path.clone(), File::create(&path).unwrap(), Row::HEADER);
        let mut t = CsvThread::spawn(csv).unwrap();
        let mut chunk = Vec::with_capacity(7);
        for r in &rows {
            chunk.push(r.clone());
            if chunk.len() == 7 {
                chunk = t.send(chunk).unwrap();
                assert!(chunk.is_empty());
            }
        }
        t.send(chunk).unwrap();
        t.finish().unwrap();
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in &rows {
            w.serialize(r).unwrap();
        }
        assert_eq!(std::fs::read(&path).unwrap(), w.into_inner().unwrap());
    }

    #[test]
    fn a_write_error_of_the_thread_is_reported() {
        // /dev/full: every write fails with ENOSPC.
        let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else { return };
        let csv = CsvFile::new("/dev/full".into(), full, Row::HEADER);
        let mut t = CsvThread::spawn(csv).unwrap();
        let mut failed = false;
        // Enough rows to fill the 1 MiB buffer and more.
        for _ in 0..200 {
            let chunk: Vec<Row> = (0..1000).map(|d| Row { a: 1.0, b: "flight", c: true, d }).collect();
            if t.send(chunk).is_err() {
                failed = true;
                break;
            }
        }
        assert!(failed || t.finish().is_err());
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 20_000, ..ProptestConfig::default() })]

        /// Any bit pattern: subnormals, NaNs of any payload and sign, infinities, -0.0.
        #[test]
        fn floats_match_the_csv_crate(bits in any::<u64>()) {
            let v = f64::from_bits(bits);
            prop_assert_eq!(via_fast(|b| push_f64(b, v)), via_csv((v,)));
        }

        /// Decimal-looking values (short digit strings at every exponent).
        #[test]
        fn short_decimals_match_the_csv_crate(m in -99_999i64..99_999, e in -330i32..310) {
            let v: f64 = format!("{m}e{e}").parse().unwrap();
            prop_assert_eq!(via_fast(|b| push_f64(b, v)), via_csv((v,)));
        }

        #[test]
        fn strings_match_the_csv_crate(s in "[a-z,\"\r\n _.-]{0,12}", t in ".{0,8}") {
            prop_assert_eq!(via_fast(|b| push_str(b, &s)), via_csv((&s,)));
            prop_assert_eq!(via_fast(|b| push_str(b, &t)), via_csv((&t,)));
            // Two fields: no special case for a lone empty field.
            let mut buf = Vec::new();
            push_str(&mut buf, &s);
            buf.push(b',');
            push_str(&mut buf, &t);
            buf.push(b',');
            end_record(&mut buf, 2);
            prop_assert_eq!(buf, via_csv((&s, &t)));
        }

        #[test]
        fn integers_and_bools_match_the_csv_crate(a in any::<u32>(), c in any::<u64>(), b in any::<bool>()) {
            prop_assert_eq!(via_fast(|x| push_int(x, a)), via_csv((a,)));
            prop_assert_eq!(via_fast(|x| push_int(x, c)), via_csv((c,)));
            prop_assert_eq!(via_fast(|x| push_bool(x, b)), via_csv((b,)));
        }
    }
}
