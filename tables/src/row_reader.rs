//! Rows read back from a [`Table`] through serde: the way back of [`crate::rows`].
//! A row type that derives `serde::Deserialize` and declares its columns
//! ([`Declared`]) is read from any table of those columns, whichever file it came
//! from (a CSV file read by [`crate::read`], an Arrow file, an MCAP file's
//! channels): the readers are derived from the declaration, never written out
//! column by column.
//!
//! The table must hold every declared column and no other, in any order. Each
//! field is read from its column's cell: a float column's cell as an `f64`, an
//! integer column's as an `i64` (narrowed by serde to the field's type, so a value
//! outside a `u16` field's range is refused, naming it), a flag column's as a
//! `bool`, a text column's as a string (a unit enum variant by its name). An
//! `Option` field reads an empty text cell or a NaN as `None`.

use std::fmt;

use serde::de::{self, DeserializeOwned, DeserializeSeed, IntoDeserializer, MapAccess, Visitor};

use crate::{Column, Table, declared::Declared};

/// Why a table's rows cannot be read as the row type: a column missing or
/// added, or a cell the field cannot take. The message names the row (from 1)
/// and the column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowError(pub String);

impl fmt::Display for RowError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RowError {}

impl de::Error for RowError {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

/// The rows of `table` as `T`, in order.
///
/// # Errors
/// [`RowError`]: `no column `name`` for a declared column the table lacks,
/// `column `name` is not declared` for one it has beyond them, or
/// `row i, column `name`: ...` for a cell the field cannot take (a value outside
/// its type's range, a name that is none of an enum's variants, a column of
/// another kind).
pub fn rows_of<T: DeserializeOwned + Declared>(table: &Table) -> Result<Vec<T>, RowError> {
    // The declared columns, each found by name in the table.
    let mut columns = Vec::with_capacity(T::NAMES.len());
    for name in T::NAMES {
        let column = table.columns.iter().find(|(n, _)| n == name).map(|(_, c)| c);
        columns.push((*name, column.ok_or_else(|| RowError(format!("no column `{name}`")))?));
    }
    if let Some((extra, _)) = table.columns.iter().find(|(n, _)| !T::NAMES.contains(&n.as_str())) {
        return Err(RowError(format!("column `{extra}` is not declared (the table is not of this kind)")));
    }
    (0..table.rows())
        .map(|row| {
            T::deserialize(RowDeserializer { columns: &columns, row, next: 0 }).map_err(|e| RowError(format!("row {}, {}", row + 1, e.0)))
        })
        .collect()
}

/// One row of the table, read as a struct (a map of the declared columns).
struct RowDeserializer<'a> {
    columns: &'a [(&'static str, &'a Column)],
    row: usize,
    next: usize,
}

impl<'de> de::Deserializer<'de> for RowDeserializer<'_> {
    type Error = RowError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, RowError> {
        visitor.visit_map(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map struct enum identifier ignored_any
    }
}

impl<'de> MapAccess<'de> for RowDeserializer<'_> {
    type Error = RowError;

    fn next_key_seed<K: DeserializeSeed<'de>>(&mut self, seed: K) -> Result<Option<K::Value>, RowError> {
        match self.columns.get(self.next) {
            Some((name, _)) => seed.deserialize((*name).into_deserializer()).map(Some),
            None => Ok(None),
        }
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, RowError> {
        let (name, column) = self.columns[self.next];
        self.next += 1;
        seed.deserialize(CellDeserializer { column, row: self.row }).map_err(|e| RowError(format!("column `{name}`: {}", e.0)))
    }
}

/// One cell.
struct CellDeserializer<'a> {
    column: &'a Column,
    row: usize,
}

impl<'de> de::Deserializer<'de> for CellDeserializer<'_> {
    type Error = RowError;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, RowError> {
        match self.column {
            Column::F64(v) => visitor.visit_f64(v[self.row]),
            Column::I64(v) => visitor.visit_i64(v[self.row]),
            Column::Bool(v) => visitor.visit_bool(v[self.row]),
            Column::Str(v) => visitor.visit_str(&v[self.row]),
        }
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, RowError> {
        let none = match self.column {
            Column::F64(v) => v[self.row].is_nan(),
            Column::Str(v) => v[self.row].is_empty(),
            Column::I64(_) | Column::Bool(_) => false,
        };
        if none { visitor.visit_none() } else { visitor.visit_some(self) }
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, RowError> {
        match self.column {
            Column::Str(v) => visitor.visit_enum(v[self.row].as_str().into_deserializer()),
            _ => Err(de::Error::custom("a name is expected, the column is not of text")),
        }
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf unit unit_struct newtype_struct seq tuple
        tuple_struct map struct identifier ignored_any
    }
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};

    use super::*;

    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(rename_all = "lowercase")]
    enum Mode {
        Sliding,
        Flight,
    }

    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    struct Row {
        t: f64,
        code: u16,
        mode: Mode,
        flag: bool,
        note: Option<String>,
        x: Option<f64>,
    }
    crate::declare!(Row { t: f64, code: int, mode: str, flag: bool, note: str, x: f64 });

    fn rows() -> Vec<Row> {
        vec![
            Row { t: 0.0, code: 0, mode: Mode::Sliding, flag: true, note: None, x: Some(-0.0) },
            Row { t: 1e-300, code: 65535, mode: Mode::Flight, flag: false, note: Some("a, b".into()), x: None },
            Row { t: f64::MAX, code: 7, mode: Mode::Sliding, flag: true, note: Some("c".into()), x: Some(f64::MIN_POSITIVE) },
        ]
    }

    #[test]
    fn rows_written_to_a_table_read_back_bit_for_bit_in_any_column_order() {
        let rows = rows();
        let mut table = Table::of_rows(&rows).expect("tabulates");
        assert_eq!(rows_of::<Row>(&table).expect("reads"), rows);
        table.columns.reverse();
        let back: Vec<Row> = rows_of(&table).expect("reads in another order");
        assert_eq!(
            back.iter().map(|r| r.x.map(f64::to_bits)).collect::<Vec<_>>(),
            rows.iter().map(|r| r.x.map(f64::to_bits)).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_cell_out_of_range_an_unknown_name_and_a_missing_or_extra_column_are_refused_by_row_and_column() {
        let mut table = Table::of_rows(&rows()).expect("tabulates");
        let at = |t: &Table, name: &str| t.columns.iter().position(|(n, _)| n == name).expect("declared");
        let (code, mode) = (at(&table, "code"), at(&table, "mode"));
        table.columns[code].1 = Column::I64(vec![0, 65536, 1]);
        let e = rows_of::<Row>(&table).unwrap_err().0;
        assert!(e.starts_with("row 2, column `code`: invalid value: integer `65536`"), "{e}");
        table.columns[code].1 = Column::I64(vec![0, 1, 2]);
        table.columns[mode].1 = Column::Str(vec!["sliding".into(), "sticking".into(), "flight".into()]);
        let e = rows_of::<Row>(&table).unwrap_err().0;
        assert!(e.starts_with("row 2, column `mode`: unknown variant `sticking`"), "{e}");
        table.columns[mode].1 = Column::F64(vec![0.0; 3]);
        let e = rows_of::<Row>(&table).unwrap_err().0;
        assert!(e.starts_with("row 1, column `mode`: a name is expected"), "{e}");
        table.columns.push(("extra".into(), Column::F64(vec![0.0; 3])));
        assert_eq!(rows_of::<Row>(&table).unwrap_err().0, "column `extra` is not declared (the table is not of this kind)");
        table.columns.remove(code);
        assert_eq!(rows_of::<Row>(&table).unwrap_err().0, "no column `code`");
    }
}
