//! Reading the CLI's CSV tables back (`painleve.read_csv`, `painleve.load`) with
//! arrow-csv, into one Arrow record batch of the declared types.
//!
//! The project wrote every file it reads, so it knows each column's type: the
//! file's header is matched against the declarations of the tables the project
//! writes ([`crate::declared::Declaration`], given by the caller: `experiments::DECLARED`),
//! and the file is read with that declaration's schema
//! (`arrow_csv::ReaderBuilder::new(schema).with_header(true)`). An empty cell is
//! NaN in a float column and `""` in a text column; in an integer or flag column
//! it is an error (the file is not the table it names). The batch's schema is
//! then the declaration's ([`crate::arrow::schema`]): the same record batch as
//! the table's Arrow file gives ([`crate::arrow::read_arrow_batch`]).
//!
//! A file whose header matches no declaration (not written by the project, or
//! by another version of it) is read with the types arrow-csv's own inference
//! gives (`arrow_csv::reader::Format::infer_schema` over the whole file):
//! `Int64`, `Float64`, `Boolean`, `Utf8`; a column without a value is `Float64`
//! (NaN), dates and times are text, and an inferred integer column with empty
//! cells is floats (NaN there), an inferred flag column with empty cells text.
//! Its rules are arrow-csv's (a cell of digits is an integer, one with a point
//! or an exponent, or `NaN`, a number; `true` and `false` in any case a flag).
//!
//! Errors name the file, and the line where arrow-csv or this module says it: a
//! file that does not end with a line end (cut off while it was written), a row
//! with another number of cells than the header, text that is not UTF-8, a cell
//! that is not of its column's type, a header naming a column twice. An empty
//! file is a table without columns.

use std::{
    io::{Read, Seek, SeekFrom},
    path::Path,
    sync::Arc,
};

use arrow_array::RecordBatch;
use arrow_csv::{ReaderBuilder, reader::Format};
use arrow_schema::{ArrowError, DataType, Field, Schema};

use crate::{
    Table,
    arrow::{BATCH_ROWS, data_type, settle, table_of},
    declared::Declaration,
    error::Error,
};

/// Reads the CSV table at `path` into one record batch: with the schema of the
/// declaration among `declared` whose columns its header names, in order, or
/// else with the types arrow-csv infers (this module's rules).
///
/// # Errors
/// [`Error::Read`] naming the file (and the line, where known) when it cannot be
/// read, is not UTF-8, ends inside a row, has a row with another number of cells
/// than its header, a cell that is not of its column's type (an empty cell in a
/// declared integer or flag column), or names a column twice.
pub fn read_csv(path: &Path, declared: &[Declaration]) -> Result<RecordBatch, Error> {
    let fail = |line: Option<u64>, message: String| Error::Read { path: path.to_path_buf(), line, message };
    let os = |e: std::io::Error| fail(None, e.to_string());
    let mut file = crate::input::open(path, crate::input::TABLE)?;
    if file.metadata().map_err(os)?.len() == 0 {
        return Ok(RecordBatch::new_empty(Arc::new(Schema::empty())));
    }
    let mut last = [0u8];
    file.seek(SeekFrom::End(-1)).and_then(|_| file.read_exact(&mut last)).map_err(os)?;
    if last[0] != b'\n' {
        // The line of the cut row, for the message.
        let lines = crate::input::read(path, crate::input::TABLE)?.iter().filter(|&&b| b == b'\n').count();
        return Err(fail(Some(lines as u64 + 1), "the file ends inside a row (a file cut off while it was written?)".into()));
    }
    let format = Format::default().with_header(true);
    let arrow = |e: ArrowError| match &e {
        // arrow-csv counts a cell's line from 1 at the first row after the header.
        ArrowError::ParseError(m) => match row_of(m) {
            Some((row, message)) => fail(Some(row + 1), message),
            None => fail(None, e.to_string()),
        },
        _ => fail(None, e.to_string()),
    };
    file.rewind().map_err(os)?;
    let (header, _) = format.infer_schema(&mut file, Some(0)).map_err(arrow)?;
    let names: Vec<&str> = header.fields().iter().map(|f| f.name().as_str()).collect();
    if let Some((_, name)) = names.iter().enumerate().find(|(i, name)| names[..*i].contains(name)) {
        return Err(fail(Some(1), format!("the header names the column `{name}` twice")));
    }
    let declaration = Declaration::find(declared, &names);
    let schema = match declaration {
        Some(d) => Schema::new(d.names.iter().zip(d.kinds).map(|(n, k)| Field::new(*n, data_type(*k), true)).collect::<Vec<_>>()),
        None => {
            file.rewind().map_err(os)?;
            let (inferred, _) = format.infer_schema(&mut file, None).map_err(arrow)?;
            Schema::new(inferred.fields().iter().map(|f| Field::new(f.name(), readable(f.data_type()), true)).collect::<Vec<_>>())
        }
    };
    let schema = Arc::new(schema);
    file.rewind().map_err(os)?;
    let reader = ReaderBuilder::new(schema.clone()).with_format(format).with_batch_size(BATCH_ROWS).build(file).map_err(arrow)?;
    let batches = reader.collect::<Result<Vec<_>, _>>().map_err(arrow)?;
    let batch = arrow_select::concat::concat_batches(&schema, &batches).map_err(arrow)?;
    // Row k of the body is line k + 2 of a file the project writes (no blank line,
    // no line end inside a cell).
    settle(&batch, declaration.is_some()).map_err(|(_, row, message)| fail(row.map(|r| r as u64 + 2), message))
}

/// [`read_csv`] as a [`Table`].
///
/// # Errors
/// As [`read_csv`].
pub fn read_csv_table(path: &Path, declared: &[Declaration]) -> Result<Table, Error> {
    let batch = read_csv(path, declared)?;
    table_of(&batch).map_err(|message| Error::Read { path: path.to_path_buf(), line: None, message })
}

/// The 1-based row of the body in arrow-csv's message about a cell it cannot
/// parse (`... for column 3 at line 5. Row data: ...`), and the message without it.
fn row_of(message: &str) -> Option<(u64, String)> {
    let at = message.find(" at line ")?;
    let digits = &message[at + " at line ".len()..];
    let n = digits.find(|c: char| !c.is_ascii_digit()).unwrap_or(digits.len());
    let row = digits[..n].parse().ok()?;
    Some((row, format!("{}{}", &message[..at], &digits[n..])))
}

/// The type an undeclared column is read as, from the one arrow-csv inferred: a
/// column without a value (`Null`) is floats (NaN), dates and times are text.
fn readable(inferred: &DataType) -> DataType {
    match inferred {
        DataType::Null => DataType::Float64,
        DataType::Int64 | DataType::Float64 | DataType::Boolean => inferred.clone(),
        _ => DataType::Utf8,
    }
}

#[cfg(test)]
mod tests;
