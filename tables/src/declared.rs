//! The declaration of a table: its columns' names and kinds, written once per row
//! type ([`declare!`], or [`crate::csv_row!`] for the long tables, which also
//! formats their CSV). Everything else follows from it: the CSV header (the row
//! type's serde field names, checked against it by [`crate::Table::of_rows`]), the
//! Arrow schema ([`crate::arrow::schema`]), the MCAP channels' JSON Schemas
//! ([`crate::mcap::McapRows`] adds the signal groups), and the types the CSV
//! reader gives a file whose header is the declaration's ([`crate::read`]).
//!
//! A column's kind is what its cells hold as the tables carry them, with no null:
//! an empty cell is NaN in a float column and `""` in a text column. So an
//! optional float (`Option<f64>`, empty when `None`) is `f64`; an optional integer
//! is `f64` too (NaN when `None`: an integer column has no empty cell); an
//! optional text, or an enum written by its variant's name, is `str`.

/// The kind of a column: `f64`, `int`, `bool` or `str` in a declaration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Floats ([`crate::Column::F64`], Arrow `Float64`, NumPy `float64`): NaN for an empty cell.
    F64,
    /// Text ([`crate::Column::Str`], Arrow `Utf8`, NumPy `str`): `""` for an empty cell.
    Str,
    /// Flags, `true` or `false` ([`crate::Column::Bool`], Arrow `Boolean`, NumPy `bool`); never empty.
    Bool,
    /// Integers that fit `i64` ([`crate::Column::I64`], Arrow `Int64`, NumPy `int64`); never empty.
    Int,
}

impl Kind {
    /// The kind's name in a declaration and in an MCAP file's metadata: `f64`, `str`, `bool`, `int`.
    pub fn name(self) -> &'static str {
        match self {
            Self::F64 => "f64",
            Self::Str => "str",
            Self::Bool => "bool",
            Self::Int => "int",
        }
    }

    /// The kind named `name` ([`Kind::name`]); `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::F64, Self::Str, Self::Bool, Self::Int].into_iter().find(|k| k.name() == name)
    }
}

/// A row type that declares its table's columns ([`declare!`], [`crate::csv_row!`]).
pub trait Declared {
    /// The column names, in order (the struct's field names: the CSV header).
    const NAMES: &'static [&'static str];
    /// The columns' kinds, in the same order.
    const KINDS: &'static [Kind];
}

/// A table's declaration as a value: what a reader matches a file's header against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Declaration {
    /// The column names, in order.
    pub names: &'static [&'static str],
    /// The columns' kinds, in the same order.
    pub kinds: &'static [Kind],
}

impl Declaration {
    /// The declaration of row type `T`.
    pub const fn of<T: Declared>() -> Self {
        Self { names: T::NAMES, kinds: T::KINDS }
    }

    /// The declaration among `declared` whose columns are named `header`, in order.
    pub fn find<'a>(declared: &'a [Self], header: &[&str]) -> Option<&'a Self> {
        declared.iter().find(|d| d.names == header)
    }
}

/// Declares a table whose row is a view of a library type: `$view` (a tuple struct
/// holding `&$of`) gets its columns ([`crate::Declared`]) and writes its cells in
/// the same order (`serde::Serialize`, the path the `csv` crate and
/// `Table::of_rows` take), each column once as `name: kind = |x| cell` with `x` the
/// viewed value. For a row whose cells sit in nested values (a case's fields, the
/// validity counters) that a flat table lists inline: the `csv` crate writes no
/// nested struct under a header, so the row would otherwise restate the type.
#[macro_export]
macro_rules! declare_view {
    ($view:ident of $of:ty { $($name:ident : $kind:ident = |$x:ident| $cell:expr),+ $(,)? }) => {
        $crate::declare!($view<'_> { $($name : $kind),+ });
        impl $crate::__serde::Serialize for $view<'_> {
            fn serialize<S: $crate::__serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                use $crate::__serde::ser::SerializeStruct;
                let mut row = s.serialize_struct(stringify!($view), <Self as $crate::Declared>::NAMES.len())?;
                $({
                    let $x: &$of = self.0;
                    row.serialize_field(stringify!($name), &$cell)?;
                })+
                row.end()
            }
        }
    };
}

/// Implements [`Declared`] for a struct from its fields, each with its kind:
/// `f64`, `str`, `bool`, `int` (see [`Kind`]; an `Option` field is `f64` for a
/// number, `str` for text). For the row types written through serde (`sweep.csv`,
/// `section.csv`, ...); the long tables use [`crate::csv_row!`], which also formats
/// their CSV. The fields are listed in the struct's order, the one serde writes.
#[macro_export]
macro_rules! declare {
    ($ty:ty { $($field:ident : $kind:ident),+ $(,)? }) => {
        impl $crate::Declared for $ty {
            const NAMES: &'static [&'static str] = &[$(stringify!($field)),+];
            const KINDS: &'static [$crate::Kind] = &[$($crate::declare!(@kind $kind)),+];
        }
    };
    (@kind f64) => { $crate::Kind::F64 };
    (@kind str) => { $crate::Kind::Str };
    (@kind bool) => { $crate::Kind::Bool };
    (@kind int) => { $crate::Kind::Int };
}
