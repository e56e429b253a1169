//! Arrow files written and read back: every value with its bits, over batch
//! boundaries, streams cut off, files refused, nulls settled, text coded.

use std::{fs::File, path::PathBuf};

use arrow_array::{Array, BooleanArray, Float64Array, Int64Array, RecordBatch, StringArray};
use arrow_schema::{DataType, Field, Schema};

use super::*;
use crate::{Column, Declared};

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

/// A streamed file (`run --format arrow`): an IPC file (its head and tail magic,
/// arrow-ipc's file reader takes it), every batch back, in order; cut off after
/// two whole batches (a killed run, no footer), those two.
#[test]
fn a_streamed_file_is_an_ipc_file_read_whole_and_a_cut_one_to_its_last_whole_batch() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.arrow");
    let rows: Vec<Row> = (0..30).map(|i| Row { a: i as f64 * 0.25, b: format!("r{i}"), c: i % 3 == 0, d: i }).collect();
    let mut w = StreamedArrowFile::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap();
    let mut ends = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let write = (i + 1) % 10 == 0;
        w.push(r.clone(), write).unwrap();
        if write {
            ends.push(std::fs::metadata(&path).unwrap().len());
        }
    }
    w.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(b"ARROW1") && bytes.ends_with(b"ARROW1"), "the IPC file format");
    let reader = arrow_ipc::reader::FileReader::try_new(File::open(&path).unwrap(), None).unwrap();
    assert_eq!(reader.num_batches(), 3);
    assert_eq!(back(&read_arrow(&path).unwrap().columns), rows);
    // Killed inside the third batch: the first two come back.
    std::fs::write(&path, &bytes[..ends[1] as usize + 17]).unwrap();
    assert_eq!(back(&read_arrow(&path).unwrap().columns), rows[..20]);
}

/// A file cut in its footer keeps its batches; cut inside its only batch, none;
/// text is refused with the file's path.
#[test]
fn a_file_cut_before_its_end_gives_its_whole_batches_and_text_is_refused_with_its_path() {
    let rows: Vec<Row> = (0..100).map(|i| Row { a: i as f64, b: String::new(), c: true, d: 1 }).collect();
    let (_dir, path) = write(rows.clone());
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 20]).unwrap();
    assert_eq!(back(&read_arrow(&path).unwrap().columns), rows);
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    assert!(read_arrow(&path).unwrap().columns.iter().all(|(_, c)| c.is_empty()));
    std::fs::write(&path, b"trace.csv is not arrow").unwrap();
    let e = read_arrow(&path).unwrap_err().to_string();
    assert!(e.contains("t.arrow"), "{e}");
}

#[test]
fn the_schema_is_the_declaration_and_a_batch_reads_with_it() {
    let rows: Vec<Row> = (0..3).map(|i| Row { a: f64::from(i), b: format!("x{i}"), c: i % 2 == 0, d: i }).collect();
    let (_dir, path) = write(rows);
    let batch = read_arrow_batch(&path).unwrap();
    assert_eq!(*batch.schema(), schema(Declaration::of::<Row>()));
    assert_eq!(<Row as Declared>::NAMES, ["a", "b", "c", "d"]);
    assert_eq!(batch.num_rows(), 3);
}

#[test]
fn nulls_settle_to_nan_and_empty_text_or_are_refused() {
    let schema = Arc::new(Schema::new(vec![
        Field::new("x", DataType::Float64, true),
        Field::new("s", DataType::Utf8, true),
        Field::new("i", DataType::Int64, true),
        Field::new("b", DataType::Boolean, true),
    ]));
    let batch = RecordBatch::try_new(
        schema,
        vec![
            Arc::new(Float64Array::from(vec![Some(1.5), None])),
            Arc::new(StringArray::from(vec![None, Some("a")])),
            Arc::new(Int64Array::from(vec![Some(3), None])),
            Arc::new(BooleanArray::from(vec![None, Some(true)])),
        ],
    )
    .unwrap();
    let e = settle(&batch, true).unwrap_err();
    assert_eq!((e.0.as_str(), e.1), ("i", Some(1)));
    let t = table_of(&settle(&batch, false).unwrap()).unwrap();
    let [(_, Column::F64(x)), (_, Column::Str(s)), (_, Column::F64(i)), (_, Column::Str(b))] = &t.columns[..] else {
        panic!("{:?}", t.columns)
    };
    assert_eq!((x[0], x[1].is_nan()), (1.5, true));
    assert_eq!(s, &["", "a"]);
    assert_eq!((i[0], i[1].is_nan()), (3.0, true));
    assert_eq!(b, &["", "true"]);
    assert!(settle(&batch, false).unwrap().schema().fields().iter().all(|f| !f.is_nullable()));
}

#[test]
fn text_is_coded_by_its_distinct_values_in_order_of_first_appearance() {
    let text = StringArray::from(vec!["sliding", "flight", "sliding", "", "flight"]);
    let d = coded(&text).unwrap();
    assert_eq!(d.keys().values().to_vec(), [0, 1, 0, 2, 1]);
    let values = d.values().as_any().downcast_ref::<StringArray>().unwrap();
    assert_eq!(values.iter().map(Option::unwrap).collect::<Vec<_>>(), ["sliding", "flight", ""]);
}

/// The writer thread (`simulate --format arrow`) writes the same file, byte for
/// byte, as [`ArrowFile`] given the same rows, whatever the chunks they are handed
/// over in (batches of [`BATCH_ROWS`] cut at the same rows), and the rows come back.
#[test]
fn the_writer_thread_writes_the_same_file_as_the_file_itself() {
    let n = BATCH_ROWS * 2 + 123;
    let rows: Vec<Row> =
        (0..n).map(|i| Row { a: (i as f64).sqrt() - 7.25, b: format!("r{}", i % 5), c: i % 3 == 0, d: (i * 7) as u32 }).collect();
    let (_dir, whole) = write(rows.clone());
    for chunk in [1, 999, BATCH_ROWS, n] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.arrow");
        let mut w = ArrowThread::spawn(ArrowFile::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap()).unwrap();
        for part in rows.chunks(chunk) {
            let back = w.send(part.to_vec()).unwrap();
            assert!(back.is_empty());
        }
        w.finish().unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), std::fs::read(&whole).unwrap(), "chunks of {chunk}");
        assert_eq!(back(&read_arrow(&path).unwrap().columns), rows);
    }
}
