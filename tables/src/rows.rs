//! Tables by column from rows that derive `serde::Serialize`: the experiments' row
//! types (`trace.csv`, `sweep.csv`, ...) turned into one typed vector per column,
//! in the rows' field order, with the cells the CSV would hold.
//!
//! A cell is what the `csv` crate writes for the field: a float, an integer, a
//! bool, a string, or empty (`None`). Per column the type is that of its cells;
//! the rules for empty cells are those of `painleve.load` reading the CSV (and of
//! pandas' `read_csv`): an integer column with an empty cell becomes a float
//! column with NaN there, a column whose cells are all empty is a float column of
//! NaN, a string column keeps `""`. So a table computed in process and the same
//! table read back from the CLI's CSV have the same columns, types and values.

use std::fmt;

use serde::ser::{self, Impossible, Serialize, SerializeStruct, Serializer};

use super::Column;

/// A column being filled: its type is fixed by its first non-empty cell.
#[derive(Debug, Clone)]
enum Building {
    /// Only empty cells so far (their count).
    Empty(usize),
    /// The typed values, with the rows whose cell was empty.
    Typed(Column, Vec<usize>),
}

/// One cell, as the `csv` crate would write it.
#[derive(Debug, Clone, PartialEq)]
enum Cell {
    F64(f64),
    I64(i64),
    U64(u64),
    Bool(bool),
    Str(String),
    Empty,
}

/// A table being built from rows: named columns of equal length, in the rows'
/// field order ([`super::Table`] when finished).
#[derive(Debug, Clone, Default)]
pub struct TableBuilder {
    names: Vec<&'static str>,
    columns: Vec<Building>,
    rows: usize,
}

/// Why a row cannot be a table row (a nested field, a map): a bug of the row type.
#[derive(Debug, Clone)]
pub struct ColumnError(String);

impl fmt::Display for ColumnError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot tabulate a row: {}", self.0)
    }
}

impl std::error::Error for ColumnError {}

impl ser::Error for ColumnError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

impl TableBuilder {
    /// A table of the `rows`.
    ///
    /// # Errors
    /// [`ColumnError`] when a row is not a flat struct of scalars.
    pub fn of<'a, T: Serialize + 'a>(rows: impl IntoIterator<Item = &'a T>) -> Result<Self, ColumnError> {
        let mut t = Self::default();
        for r in rows {
            t.push(r)?;
        }
        Ok(t)
    }

    /// Appends one row.
    ///
    /// # Errors
    /// [`ColumnError`] when the row is not a flat struct of scalars, or its fields
    /// differ from the first row's.
    pub fn push<T: Serialize + ?Sized>(&mut self, row: &T) -> Result<(), ColumnError> {
        let mut cells = Vec::with_capacity(self.names.len());
        row.serialize(RowSerializer { cells: &mut cells })?;
        if self.rows == 0 && self.names.is_empty() {
            self.names = cells.iter().map(|(n, _)| *n).collect();
            self.columns = vec![Building::Empty(0); cells.len()];
        }
        if cells.len() != self.names.len() || cells.iter().zip(&self.names).any(|((a, _), b)| a != b) {
            return Err(ColumnError("rows of different fields in one table".into()));
        }
        for ((_, cell), col) in cells.into_iter().zip(&mut self.columns) {
            push_cell(col, cell, self.rows);
        }
        self.rows += 1;
        Ok(())
    }

    /// The finished table: the columns, named, in field order, with the empty-cell
    /// rules applied.
    pub fn finish(self) -> super::Table {
        super::Table { columns: self.names.into_iter().zip(self.columns).map(|(n, c)| (n.to_string(), finish(c))).collect() }
    }
}

fn push_cell(col: &mut Building, cell: Cell, row: usize) {
    match col {
        Building::Empty(n) => {
            if cell == Cell::Empty {
                *n += 1;
                return;
            }
            let empties: Vec<usize> = (0..*n).collect();
            let column = match &cell {
                Cell::F64(_) => Column::F64(vec![f64::NAN; *n]),
                Cell::I64(_) => Column::I64(vec![0; *n]),
                Cell::U64(_) => Column::U64(vec![0; *n]),
                Cell::Bool(_) => Column::Bool(vec![false; *n]),
                Cell::Str(_) | Cell::Empty => Column::Str(vec![String::new(); *n]),
            };
            *col = Building::Typed(column, empties);
            push_cell(col, cell, row);
        }
        Building::Typed(column, empties) => {
            match (&mut *column, cell) {
                (Column::F64(v), Cell::F64(x)) => v.push(x),
                (Column::F64(v), Cell::I64(x)) => v.push(x as f64),
                (Column::F64(v), Cell::U64(x)) => v.push(x as f64),
                (Column::F64(v), Cell::Empty) => {
                    v.push(f64::NAN);
                    empties.push(row);
                }
                (Column::I64(v), Cell::I64(x)) => v.push(x),
                (Column::I64(v), Cell::U64(x)) => match i64::try_from(x) {
                    Ok(x) => v.push(x),
                    Err(_) => {
                        let mut u: Vec<u64> = v.iter().map(|&y| y as u64).collect();
                        u.push(x);
                        *column = Column::U64(u);
                    }
                },
                (Column::U64(v), Cell::U64(x)) => v.push(x),
                (Column::U64(v), Cell::I64(x)) => v.push(x as u64),
                (Column::I64(v), Cell::Empty) => {
                    v.push(0);
                    empties.push(row);
                }
                (Column::U64(v), Cell::Empty) => {
                    v.push(0);
                    empties.push(row);
                }
                (Column::I64(v), Cell::F64(x)) => {
                    let mut f: Vec<f64> = v.iter().map(|&y| y as f64).collect();
                    for &i in empties.iter() {
                        f[i] = f64::NAN;
                    }
                    f.push(x);
                    *column = Column::F64(f);
                }
                (Column::Bool(v), Cell::Bool(x)) => v.push(x),
                (Column::Bool(v), Cell::Empty) => {
                    v.push(false);
                    empties.push(row);
                }
                (Column::Str(v), Cell::Str(x)) => v.push(x),
                (Column::Str(v), Cell::Empty) => {
                    v.push(String::new());
                    empties.push(row);
                }
                // Mixed types (not in any of the CLI's tables): the column becomes text.
                (_, cell) => {
                    let mut s = as_strings(column, empties);
                    s.push(cell_text(&cell));
                    *column = Column::Str(s);
                }
            }
        }
    }
}

fn cell_text(c: &Cell) -> String {
    match c {
        Cell::F64(x) => x.to_string(),
        Cell::I64(x) => x.to_string(),
        Cell::U64(x) => x.to_string(),
        Cell::Bool(x) => x.to_string(),
        Cell::Str(s) => s.clone(),
        Cell::Empty => String::new(),
    }
}

fn as_strings(c: &Column, empties: &[usize]) -> Vec<String> {
    let mut s: Vec<String> = match c {
        Column::F64(v) => v.iter().map(f64::to_string).collect(),
        Column::I64(v) => v.iter().map(i64::to_string).collect(),
        Column::U64(v) => v.iter().map(u64::to_string).collect(),
        Column::Bool(v) => v.iter().map(bool::to_string).collect(),
        Column::Str(v) => v.clone(),
    };
    for &i in empties {
        s[i].clear();
    }
    s
}

/// The empty-cell rules: all empty gives NaN floats, integers with an empty cell
/// become floats with NaN there, strings keep `""`; a string column whose cells are
/// all empty is all NaN floats too (what a reader of the CSV sees).
fn finish(b: Building) -> Column {
    match b {
        Building::Empty(n) => Column::F64(vec![f64::NAN; n]),
        Building::Typed(Column::I64(v), empties) if !empties.is_empty() => Column::F64(with_nan(v.iter().map(|&x| x as f64), &empties)),
        Building::Typed(Column::U64(v), empties) if !empties.is_empty() => Column::F64(with_nan(v.iter().map(|&x| x as f64), &empties)),
        Building::Typed(Column::Str(v), _) if !v.is_empty() && v.iter().all(String::is_empty) => Column::F64(vec![f64::NAN; v.len()]),
        Building::Typed(c, _) => c,
    }
}

fn with_nan(values: impl Iterator<Item = f64>, empties: &[usize]) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    for &i in empties {
        v[i] = f64::NAN;
    }
    v
}

/// Serialises one row (a struct) into its named cells.
struct RowSerializer<'a> {
    cells: &'a mut Vec<(&'static str, Cell)>,
}

/// Serialises one field into a cell.
struct CellSerializer;

macro_rules! unsupported_row {
    ($($f:ident($($t:ty),*)),* $(,)?) => {
        $(fn $f(self $(, _: $t)*) -> Result<Self::Ok, Self::Error> {
            Err(ColumnError(concat!("a row must be a struct (", stringify!($f), ")").into()))
        })*
    };
}

impl<'a> Serializer for RowSerializer<'a> {
    type Ok = ();
    type Error = ColumnError;
    type SerializeSeq = Impossible<(), ColumnError>;
    type SerializeTuple = Impossible<(), ColumnError>;
    type SerializeTupleStruct = Impossible<(), ColumnError>;
    type SerializeTupleVariant = Impossible<(), ColumnError>;
    type SerializeMap = Impossible<(), ColumnError>;
    type SerializeStruct = Self;
    type SerializeStructVariant = Impossible<(), ColumnError>;

    unsupported_row!(
        serialize_bool(bool),
        serialize_i8(i8),
        serialize_i16(i16),
        serialize_i32(i32),
        serialize_i64(i64),
        serialize_u8(u8),
        serialize_u16(u16),
        serialize_u32(u32),
        serialize_u64(u64),
        serialize_f32(f32),
        serialize_f64(f64),
        serialize_char(char),
        serialize_str(&str),
        serialize_bytes(&[u8]),
        serialize_none(),
        serialize_unit(),
        serialize_unit_struct(&'static str),
        serialize_unit_variant(&'static str, u32, &'static str),
    );

    fn serialize_some<T: ?Sized + Serialize>(self, value: &T) -> Result<(), ColumnError> {
        value.serialize(self)
    }

    fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _: &'static str, value: &T) -> Result<(), ColumnError> {
        value.serialize(self)
    }

    fn serialize_newtype_variant<T: ?Sized + Serialize>(self, _: &'static str, _: u32, _: &'static str, _: &T) -> Result<(), ColumnError> {
        Err(ColumnError("a row must be a struct (newtype variant)".into()))
    }

    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, ColumnError> {
        Err(ColumnError("a row must be a struct (sequence)".into()))
    }

    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, ColumnError> {
        Err(ColumnError("a row must be a struct (tuple)".into()))
    }

    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeTupleStruct, ColumnError> {
        Err(ColumnError("a row must be a struct (tuple struct)".into()))
    }

    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, ColumnError> {
        Err(ColumnError("a row must be a struct (tuple variant)".into()))
    }

    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, ColumnError> {
        Err(ColumnError("a row must be a struct (map)".into()))
    }

    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Self::SerializeStruct, ColumnError> {
        Ok(self)
    }

    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, ColumnError> {
        Err(ColumnError("a row must be a struct (struct variant)".into()))
    }
}

impl SerializeStruct for RowSerializer<'_> {
    type Ok = ();
    type Error = ColumnError;

    fn serialize_field<T: ?Sized + Serialize>(&mut self, key: &'static str, value: &T) -> Result<(), ColumnError> {
        let cell = value.serialize(CellSerializer).map_err(|e| ColumnError(format!("field `{key}`: {}", e.0)))?;
        self.cells.push((key, cell));
        Ok(())
    }

    fn skip_field(&mut self, _: &'static str) -> Result<(), ColumnError> {
        Ok(())
    }

    fn end(self) -> Result<(), ColumnError> {
        Ok(())
    }
}

macro_rules! nested {
    ($($f:ident($($t:ty),*) -> $r:ty),* $(,)?) => {
        $(fn $f(self $(, _: $t)*) -> Result<$r, Self::Error> {
            Err(ColumnError(concat!("a field must be a scalar (", stringify!($f), ")").into()))
        })*
    };
}

impl Serializer for CellSerializer {
    type Ok = Cell;
    type Error = ColumnError;
    type SerializeSeq = Impossible<Cell, ColumnError>;
    type SerializeTuple = Impossible<Cell, ColumnError>;
    type SerializeTupleStruct = Impossible<Cell, ColumnError>;
    type SerializeTupleVariant = Impossible<Cell, ColumnError>;
    type SerializeMap = Impossible<Cell, ColumnError>;
    type SerializeStruct = Impossible<Cell, ColumnError>;
    type SerializeStructVariant = Impossible<Cell, ColumnError>;

    fn serialize_bool(self, v: bool) -> Result<Cell, ColumnError> {
        Ok(Cell::Bool(v))
    }
    fn serialize_i8(self, v: i8) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v.into()))
    }
    fn serialize_i16(self, v: i16) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v.into()))
    }
    fn serialize_i32(self, v: i32) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v.into()))
    }
    fn serialize_i64(self, v: i64) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v))
    }
    fn serialize_u8(self, v: u8) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v.into()))
    }
    fn serialize_u16(self, v: u16) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v.into()))
    }
    fn serialize_u32(self, v: u32) -> Result<Cell, ColumnError> {
        Ok(Cell::I64(v.into()))
    }
    fn serialize_u64(self, v: u64) -> Result<Cell, ColumnError> {
        Ok(i64::try_from(v).map_or(Cell::U64(v), Cell::I64))
    }
    fn serialize_f32(self, v: f32) -> Result<Cell, ColumnError> {
        Ok(Cell::F64(v.into()))
    }
    fn serialize_f64(self, v: f64) -> Result<Cell, ColumnError> {
        Ok(Cell::F64(v))
    }
    fn serialize_char(self, v: char) -> Result<Cell, ColumnError> {
        Ok(Cell::Str(v.to_string()))
    }
    fn serialize_str(self, v: &str) -> Result<Cell, ColumnError> {
        // The csv crate writes an empty string as an empty field.
        Ok(if v.is_empty() { Cell::Str(String::new()) } else { Cell::Str(v.to_string()) })
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<Cell, ColumnError> {
        Ok(Cell::Str(String::from_utf8_lossy(v).into_owned()))
    }
    fn serialize_none(self) -> Result<Cell, ColumnError> {
        Ok(Cell::Empty)
    }
    fn serialize_some<T: ?Sized + Serialize>(self, value: &T) -> Result<Cell, ColumnError> {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result<Cell, ColumnError> {
        Ok(Cell::Empty)
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<Cell, ColumnError> {
        Ok(Cell::Empty)
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, variant: &'static str) -> Result<Cell, ColumnError> {
        Ok(Cell::Str(variant.to_string()))
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(self, _: &'static str, value: &T) -> Result<Cell, ColumnError> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<Cell, ColumnError> {
        Err(ColumnError("a field must be a scalar (newtype variant)".into()))
    }

    nested!(
        serialize_seq(Option<usize>) -> Self::SerializeSeq,
        serialize_tuple(usize) -> Self::SerializeTuple,
        serialize_tuple_struct(&'static str, usize) -> Self::SerializeTupleStruct,
        serialize_tuple_variant(&'static str, u32, &'static str, usize) -> Self::SerializeTupleVariant,
        serialize_map(Option<usize>) -> Self::SerializeMap,
        serialize_struct(&'static str, usize) -> Self::SerializeStruct,
        serialize_struct_variant(&'static str, u32, &'static str, usize) -> Self::SerializeStructVariant,
    );
}
