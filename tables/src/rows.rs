//! Tables by column from rows that derive `serde::Serialize`: the project's row
//! types written through serde (`sweep.csv`, `section.csv`, ...) turned into one
//! typed vector per column, in the rows' field order, each column of the kind its
//! declaration gives ([`crate::Declared`]).
//!
//! A cell is what the `csv` crate writes for the field: a float, an integer, a
//! bool, a string, or empty (`None`). It goes into its column by the column's
//! kind: a float column takes numbers (an integer as its float) and an empty
//! cell as NaN; an integer column integers that fit `i64`; a flag column flags;
//! a text column text and an empty cell as `""`. Any other cell, or a row whose
//! fields are not the declared columns, is a [`ColumnError`] (a bug of the
//! declaration, found by the tests that tabulate each row type).

use std::fmt;

use serde::ser::{self, Impossible, Serialize, SerializeStruct, Serializer};

use crate::{Column, Table, declared::Declaration, declared::Kind};

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

/// A table being built from rows of a declared type: named columns of equal
/// length, of the declared kinds ([`Table`] when finished).
#[derive(Debug, Clone)]
pub struct TableBuilder {
    declaration: Declaration,
    columns: Vec<Column>,
    cells: Vec<(&'static str, Cell)>,
}

/// Why a row cannot be a table row (a nested field, a map, a cell its declared
/// column cannot hold): a bug of the row type or of its declaration.
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
    /// An empty table of the columns `declaration` declares.
    pub fn new(declaration: Declaration) -> Self {
        let columns = declaration
            .kinds
            .iter()
            .map(|k| match k {
                Kind::F64 => Column::F64(Vec::new()),
                Kind::Int => Column::I64(Vec::new()),
                Kind::Bool => Column::Bool(Vec::new()),
                Kind::Str => Column::Str(Vec::new()),
            })
            .collect();
        Self { declaration, columns, cells: Vec::with_capacity(declaration.names.len()) }
    }

    /// Appends one row.
    ///
    /// # Errors
    /// [`ColumnError`] when the row is not a flat struct of scalars, its fields are
    /// not the declared columns (in order), or a cell does not fit its column's kind.
    pub fn push<T: Serialize + ?Sized>(&mut self, row: &T) -> Result<(), ColumnError> {
        self.cells.clear();
        row.serialize(RowSerializer { cells: &mut self.cells })?;
        let names = self.declaration.names;
        if self.cells.len() != names.len() || self.cells.iter().zip(names).any(|((a, _), b)| a != b) {
            let fields: Vec<&str> = self.cells.iter().map(|(n, _)| *n).collect();
            return Err(ColumnError(format!("the row's fields {fields:?} are not the declared columns {names:?}")));
        }
        // Checked before any column grows, so a refused row leaves the table as it was.
        for ((name, cell), column) in self.cells.iter().zip(&self.columns) {
            if !fits(column, cell) {
                return Err(ColumnError(format!("field `{name}`: {cell:?} in a column declared {}", kind_of(column).name())));
            }
        }
        for ((_, cell), column) in self.cells.drain(..).zip(&mut self.columns) {
            push_cell(column, cell);
        }
        Ok(())
    }

    /// The finished table: the declared columns, in order.
    pub fn finish(self) -> Table {
        Table { columns: self.declaration.names.iter().map(|n| n.to_string()).zip(self.columns).collect() }
    }
}

/// The kind of a column being built.
fn kind_of(c: &Column) -> Kind {
    match c {
        Column::F64(_) => Kind::F64,
        Column::I64(_) => Kind::Int,
        Column::Bool(_) => Kind::Bool,
        Column::Str(_) => Kind::Str,
    }
}

/// Whether `cell` goes into `column` (the rules of this module).
fn fits(column: &Column, cell: &Cell) -> bool {
    matches!(
        (column, cell),
        (Column::F64(_), Cell::F64(_) | Cell::I64(_) | Cell::U64(_) | Cell::Empty)
            | (Column::I64(_), Cell::I64(_))
            | (Column::Bool(_), Cell::Bool(_))
            | (Column::Str(_), Cell::Str(_) | Cell::Empty)
    )
}

/// Appends `cell` ([`fits`] checked) to `column`.
fn push_cell(column: &mut Column, cell: Cell) {
    match (column, cell) {
        (Column::F64(v), Cell::F64(x)) => v.push(x),
        (Column::F64(v), Cell::I64(x)) => v.push(x as f64),
        (Column::F64(v), Cell::U64(x)) => v.push(x as f64),
        (Column::F64(v), _) => v.push(f64::NAN),
        (Column::I64(v), Cell::I64(x)) => v.push(x),
        (Column::Bool(v), Cell::Bool(x)) => v.push(x),
        (Column::Str(v), Cell::Str(x)) => v.push(x),
        (Column::Str(v), _) => v.push(String::new()),
        _ => {}
    }
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

#[cfg(test)]
mod tests {
    use crate::{Column, Table};

    #[derive(serde::Serialize)]
    #[serde(rename_all = "snake_case")]
    enum Mode {
        Sliding,
    }

    #[derive(serde::Serialize)]
    struct Row {
        a: Option<f64>,
        n: Option<usize>,
        s: Option<&'static str>,
        m: Mode,
        k: u64,
        f: bool,
    }
    crate::declare!(Row { a: f64, n: f64, s: str, m: str, k: int, f: bool });

    #[test]
    fn serde_rows_fill_their_declared_columns() {
        let rows = [
            Row { a: Some(1.5), n: Some(3), s: Some("x"), m: Mode::Sliding, k: 7, f: true },
            Row { a: None, n: None, s: None, m: Mode::Sliding, k: 8, f: false },
        ];
        let t = Table::of_rows(&rows).unwrap();
        let [(_, Column::F64(a)), (_, Column::F64(n)), (_, Column::Str(s)), (_, Column::Str(m)), (_, Column::I64(k)), (_, Column::Bool(f))] =
            &t.columns[..]
        else {
            panic!("{:?}", t.columns)
        };
        assert_eq!((a[0], n[0], a[1].is_nan(), n[1].is_nan()), (1.5, 3.0, true, true));
        assert_eq!((s, m, k, f), (&vec!["x".to_string(), String::new()], &vec!["sliding".to_string(); 2], &vec![7, 8], &vec![true, false]));
        // No row: the declared columns, empty.
        let t = Table::of_rows::<Row>(&[]).unwrap();
        assert_eq!(t.columns.iter().map(|(n, c)| (n.as_str(), c.len())).collect::<Vec<_>>().len(), 6);
        assert!(matches!(t.columns[4].1, Column::I64(_)));
    }

    #[derive(serde::Serialize)]
    struct Wrong {
        a: &'static str,
        b: Option<u32>,
    }
    crate::declare!(Wrong { a: f64, b: int });

    #[derive(serde::Serialize)]
    struct Renamed {
        a: f64,
    }
    crate::declare!(Renamed { b: f64 });

    #[test]
    fn a_cell_its_column_cannot_hold_or_other_fields_are_refused() {
        let e = Table::of_rows(&[Wrong { a: "x", b: Some(1) }]).unwrap_err().to_string();
        assert!(e.contains("field `a`") && e.contains("declared f64"), "{e}");
        let e = Table::of_rows(&[Wrong { a: "x", b: None }]).unwrap_err().to_string();
        assert!(e.contains("field `a`"), "{e}");
        let e = Table::of_rows(&[Renamed { a: 1.0 }]).unwrap_err().to_string();
        assert!(e.contains("not the declared columns"), "{e}");
    }
}
