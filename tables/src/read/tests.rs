//! The CSV reader: a declared table reads back with its declared types and its
//! values' bits; an undeclared one with arrow-csv's inferred types; bad files are
//! refused with the file and the line.

use std::path::PathBuf;

use arrow_array::{Array, BooleanArray, Float64Array, Int64Array, StringArray};
use proptest::prelude::*;

use super::*;
use crate::{
    Column, Declared,
    csv::{CsvRow, push_header, push_row},
};

#[derive(Debug, Clone, PartialEq)]
struct Row {
    t: f64,
    mode: String,
    flag: bool,
    n: u32,
    x: f64,
}
crate::csv_row!(Row { t: f64, mode: str, flag: bool, n: int, x: f64 });

const DECLARED: &[Declaration] = &[Declaration::of::<Row>()];

/// `rows` written as the CLI writes a long table, at `t.csv` in a new folder.
fn written(rows: &[Row]) -> (tempfile::TempDir, PathBuf) {
    let mut buf = Vec::new();
    push_header(&mut buf, Row::HEADER);
    for r in rows {
        push_row(&mut buf, r);
    }
    text(&buf)
}

/// A file of `bytes` at `t.csv` in a new folder.
fn text(bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.csv");
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

fn float() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<u64>().prop_map(f64::from_bits),
        -10.0..10.0f64,
        Just(0.0),
        Just(-0.0),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(5e-324),
        Just(1e-7),
        Just(1e16),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, ..ProptestConfig::default() })]

    /// Every value back: floats with their bits (a NaN as NaN), text with commas,
    /// quotes, line ends and empty cells, flags, integers; the declared schema.
    #[test]
    fn a_declared_table_reads_back_with_its_types_and_bits(
        rows in proptest::collection::vec((float(), "[a-z,\"\r\n ]{0,6}|NaN|1.5|", any::<bool>(), any::<u32>(), float()), 0..40)
    ) {
        let rows: Vec<Row> = rows.into_iter().map(|(t, mode, flag, n, x)| Row { t, mode, flag, n, x }).collect();
        let (_dir, path) = written(&rows);
        let batch = read_csv(&path, DECLARED).unwrap();
        prop_assert_eq!(&*batch.schema(), &crate::arrow::schema(Declaration::of::<Row>()));
        let t = read_csv_table(&path, DECLARED).unwrap();
        let [(_, Column::F64(t_)), (_, Column::Str(mode)), (_, Column::Bool(flag)), (_, Column::I64(n)), (_, Column::F64(x))] = &t.columns[..] else {
            panic!("{:?}", t.columns)
        };
        prop_assert_eq!(t_.len(), rows.len());
        let bits = |v: f64| if v.is_nan() { f64::NAN.to_bits() } else { v.to_bits() };
        for (i, r) in rows.iter().enumerate() {
            prop_assert_eq!(bits(t_[i]), bits(r.t), "t at row {}", i);
            prop_assert_eq!(bits(x[i]), bits(r.x), "x at row {}", i);
            prop_assert_eq!(&mode[i], &r.mode);
            prop_assert_eq!(flag[i], r.flag);
            prop_assert_eq!(n[i], i64::from(r.n));
        }
    }
}

#[test]
fn a_header_alone_is_an_empty_table_of_the_declared_types_and_an_empty_file_no_table() {
    let (_dir, path) = written(&[]);
    let batch = read_csv(&path, DECLARED).unwrap();
    assert_eq!(batch.num_rows(), 0);
    assert_eq!(*batch.schema(), crate::arrow::schema(Declaration::of::<Row>()));
    let (_dir, path) = text(b"");
    assert_eq!(read_csv(&path, DECLARED).unwrap().num_columns(), 0);
    // The same header without the declaration: no value, so floats.
    let (_dir, path) = written(&[]);
    let batch = read_csv(&path, &[]).unwrap();
    assert!(batch.schema().fields().iter().all(|f| *f.data_type() == DataType::Float64));
    assert_eq!(batch.schema().fields().iter().map(|f| f.name().as_str()).collect::<Vec<_>>(), Row::NAMES);
}

#[test]
fn an_undeclared_table_has_the_types_arrow_csv_infers() {
    let (_dir, path) = text(b"i,f,b,s,gap,none,flags\n1,1.5,true,x,,,true\n2,2,false,,3,,\n-3,NaN,true,y,4,,false\n");
    let batch = read_csv(&path, DECLARED).unwrap();
    let types: Vec<String> = batch.schema().fields().iter().map(|f| f.data_type().to_string()).collect();
    assert_eq!(types, ["Int64", "Float64", "Boolean", "Utf8", "Float64", "Float64", "Utf8"]);
    let col = |i: usize| batch.column(i).clone();
    assert_eq!(col(0).as_any().downcast_ref::<Int64Array>().unwrap().values().to_vec(), [1, 2, -3]);
    let f = col(1);
    let f = f.as_any().downcast_ref::<Float64Array>().unwrap();
    assert!(f.value(0) == 1.5 && f.value(1) == 2.0 && f.value(2).is_nan(), "NaN is a number to arrow-csv");
    let gap = col(4);
    let gap = gap.as_any().downcast_ref::<Float64Array>().unwrap();
    assert!(gap.value(0).is_nan() && gap.value(1) == 3.0, "an integer column with an empty cell is floats");
    let none = col(5);
    assert!(none.as_any().downcast_ref::<Float64Array>().unwrap().values().iter().all(|x| x.is_nan()));
    let s = col(3);
    assert_eq!(s.as_any().downcast_ref::<StringArray>().unwrap().iter().map(Option::unwrap).collect::<Vec<_>>(), ["x", "", "y"]);
    let flags = col(6);
    let flags = flags.as_any().downcast_ref::<StringArray>().unwrap();
    assert_eq!(flags.iter().map(Option::unwrap).collect::<Vec<_>>(), ["true", "", "false"], "flags with an empty cell are text");
    let b = col(2);
    assert_eq!(b.as_any().downcast_ref::<BooleanArray>().unwrap().values().iter().collect::<Vec<_>>(), [true, false, true]);
    assert!(batch.schema().fields().iter().all(|f| !f.is_nullable()) && batch.columns().iter().all(|c| c.null_count() == 0));
}

/// The error's text, and that it names the file.
fn error(bytes: &[u8]) -> String {
    let (_dir, path) = text(bytes);
    let e = read_csv(&path, DECLARED).unwrap_err().to_string();
    assert!(e.starts_with(&format!("cannot read {}: ", path.display())), "{e}");
    e
}

#[test]
fn bad_files_are_refused_with_the_file_and_the_line() {
    let e = error(b"t,mode,flag,n,x\n0,a,true,1,2\n0.5,b");
    assert!(e.contains("line 3: the file ends inside a row"), "{e}");
    // A row of another number of cells, in an undeclared file (found by the
    // inference's pass) and in a declared one (by the reader's).
    let e = error(b"a,b\n1,2\n3\n");
    assert!(e.contains("line 3") && e.contains("Expected 2"), "{e}");
    let e = error(b"a,b\n1,2,3\n");
    assert!(e.contains("line 2") && e.contains("Expected 2"), "{e}");
    let e = error(b"t,mode,flag,n,x\n0,a,true,1,2\n0,a,true,1\n");
    assert!(e.contains("incorrect number of fields for line 3, expected 5 got 4"), "{e}");
    let e = error(b"t,mode,flag,n,x\n0,a,true,1,2\n0,\xff,true,1,2\n");
    assert!(e.contains("invalid UTF-8") && e.contains("line 3"), "{e}");
    let e = error(b"a,b\n1,\xff\xfe\n");
    assert!(e.contains("invalid UTF-8") && e.contains("line 2"), "{e}");
    let e = error(b"a,a\n1,2\n");
    assert!(e.contains("line 1: the header names the column `a` twice"), "{e}");
    // Declared: a cell not of its column's type, an empty integer.
    let e = error(b"t,mode,flag,n,x\n0,a,true,1,2\n0.5,b,false,,3\n");
    assert!(e.contains("line 3: an empty cell (null) in the integer column `n`"), "{e}");
    let e = error(b"t,mode,flag,n,x\n0,a,true,1,2\n0.5,b,maybe,2,3\n");
    assert!(e.contains("line 3: ") && e.contains("'maybe' as type 'Boolean'"), "{e}");
    let e = error(b"t,mode,flag,n,x\n0.x,a,true,1,2\n");
    assert!(e.contains("line 2: ") && e.contains("'0.x' as type 'Float64'") && !e.contains("at line"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let e = read_csv(&dir.path().join("none.csv"), DECLARED).unwrap_err().to_string();
    assert!(e.starts_with("cannot read ") && e.contains("none.csv"), "{e}");
}
