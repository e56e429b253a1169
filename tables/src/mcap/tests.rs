//! The MCAP writer and reader together: round trips, cut files, merged tables.

use std::fs::File;

use mcap::read::MessageStream;

use super::*;
use crate::{Column, Table};

#[derive(Debug, Clone, PartialEq)]
struct Row {
    t: f64,
    a: f64,
    b: String,
    c: bool,
    d: u32,
}
crate::csv_row!(Row { t: f64, a: f64, b: str, c: bool, d: int });
impl McapRows for Row {
    const TABLE: &'static str = "trace";
    const GROUPS: &'static [McapGroup] = &[
        McapGroup { topic: "/one", schema: "test.One", columns: &["a", "c"] },
        McapGroup { topic: "/two", schema: "test.Two", columns: &["b", "d"] },
    ];
}

#[derive(Debug, Clone, PartialEq)]
struct Event {
    t: f64,
    kind: &'static str,
}
crate::csv_row!(Event { t: f64, kind: str });
impl McapRows for Event {
    const TABLE: &'static str = "events";
    const GROUPS: &'static [McapGroup] = &[McapGroup { topic: "/events", schema: "test.Event", columns: &["kind"] }];
}

fn back(table: &Table) -> Vec<Row> {
    let [(_, Column::F64(t)), (_, Column::F64(a)), (_, Column::Str(b)), (_, Column::Bool(c)), (_, Column::I64(d))] = &table.columns[..]
    else {
        panic!("unexpected columns {:?}", table.columns)
    };
    (0..t.len()).map(|i| Row { t: t[i], a: a[i], b: b[i].clone(), c: c[i], d: u32::try_from(d[i]).unwrap() }).collect()
}

fn rows(n: usize) -> Vec<Row> {
    let awkward = [0.1, -0.0, 1e-300, f64::MAX, 5e-324, 1.0 / 3.0, 1e16, 123456789.0, f64::NAN, f64::INFINITY];
    (0..n)
        .map(|i| Row { t: i as f64 * 1e-3, a: awkward[i % awkward.len()], b: format!("s\"{i}\\,\n"), c: i % 3 == 0, d: i as u32 * 7 })
        .collect()
}

/// Every finite float back with its bits (the CSV's digits are JSON numbers
/// that parse to them), NaN and infinities as NaN, text escaped and back.
#[test]
fn a_stream_round_trips_and_a_cut_one_gives_its_whole_chunks() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.mcap");
    let want = rows(250);
    let mut w = McapStream::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap();
    let mut ends = Vec::new();
    for (i, r) in want.iter().enumerate() {
        w.push(r.clone()).unwrap();
        if (i + 1) % STREAM_CHUNK_ROWS == 0 {
            ends.push(std::fs::metadata(&path).unwrap().len());
        }
    }
    w.finish().unwrap();
    let tables = read_mcap(&path).unwrap();
    assert_eq!(tables.len(), 1);
    assert_eq!(tables[0].0, "trace");
    let got = back(&tables[0].1);
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        let a = if w.a.is_finite() { w.a } else { f64::NAN };
        assert_eq!((g.t.to_bits(), g.a.to_bits(), &g.b, g.c, g.d), (w.t.to_bits(), a.to_bits(), &w.b, w.c, w.d));
    }
    // Killed inside the third chunk: the first two come back.
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[bytes.len() - 8..], b"\x89MCAP0\r\n");
    std::fs::write(&path, &bytes[..ends[1] as usize + 40]).unwrap();
    assert_eq!(back(&read_mcap(&path).unwrap()[0].1).len(), 2 * STREAM_CHUNK_ROWS);
    std::fs::write(&path, &bytes[..ends[1] as usize]).unwrap();
    assert_eq!(back(&read_mcap(&path).unwrap()[0].1).len(), 2 * STREAM_CHUNK_ROWS);
    // Cut anywhere (in a record's head, its body, the summary, the closing
    // magic): a prefix of the rows, as many or more for a later cut, all of
    // them once the cut is past the last chunk.
    let mut last = 0;
    for cut in (ends[0] as usize..=bytes.len()).step_by(7).chain([bytes.len() - 1, bytes.len()]) {
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let got = back(&read_mcap(&path).unwrap()[0].1);
        assert!(got.len() >= last.max(STREAM_CHUNK_ROWS), "cut at {cut}: {} rows after {last}", got.len());
        assert!(got.iter().zip(&want).all(|(g, w)| (g.t.to_bits(), &g.b, g.d) == (w.t.to_bits(), &w.b, w.d)), "cut at {cut}");
        last = got.len();
    }
    assert_eq!(last, want.len());
}

/// Two tables in one file, their messages in order of log time, which is
/// `t` in ns; the same rows give the same bytes.
#[test]
fn merged_tables_are_in_time_order_and_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str| {
        let path = dir.path().join(name);
        let mut f = McapFile::new(path.clone(), File::create(&path).unwrap(), Some(4096)).unwrap();
        let (tr, ev) = (f.add_table::<Row>().unwrap(), f.add_table::<Event>().unwrap());
        let events = [Event { t: 0.0, kind: "start" }, Event { t: 0.0105, kind: "touchdown" }, Event { t: 0.5, kind: "end" }];
        f.write_merged((tr, &rows(100)), (ev, &events)).unwrap();
        f.finish().unwrap();
        path
    };
    let (p, q) = (write("a.mcap"), write("b.mcap"));
    assert_eq!(std::fs::read(&p).unwrap(), std::fs::read(&q).unwrap());
    let bytes = std::fs::read(&p).unwrap();
    let times: Vec<(String, u64)> =
        MessageStream::new(&bytes).unwrap().map(|m| m.unwrap()).map(|m| (m.channel.topic.clone(), m.log_time)).collect();
    assert!(times.windows(2).all(|w| w[0].1 <= w[1].1), "log times in order");
    assert_eq!(times.iter().filter(|(t, _)| t == "/events").map(|(_, ns)| *ns).collect::<Vec<_>>(), [0, 10_500_000, 500_000_000]);
    let tables = read_mcap(&p).unwrap();
    assert_eq!(tables.iter().map(|(n, t)| (n.as_str(), t.rows())).collect::<Vec<_>>(), [("trace", 100), ("events", 3)]);
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let mut encodings: Vec<_> = summary
        .channels
        .values()
        .map(|c| (c.topic.clone(), c.message_encoding.clone(), c.schema.as_ref().unwrap().encoding.clone()))
        .collect();
    encodings.sort();
    assert_eq!(encodings[0], ("/events".to_string(), "json".to_string(), "jsonschema".to_string()));
}

#[test]
fn not_mcap_is_refused_with_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.mcap");
    std::fs::write(&path, "t,theta1\n0,1\n").unwrap();
    let e = read_mcap(&path).unwrap_err().to_string();
    assert!(e.contains("trace.mcap"), "{e}");
}

/// A view's channels come after its table's; each row's view messages follow
/// its own, with its log time and their own sequence numbers (from 0); the
/// reader leaves them out and gives the table back whole.
#[test]
fn a_views_messages_follow_their_rows_and_the_reader_skips_them() {
    /// A message on `/odd` for each row with an odd `d`, two on `/every` for every row.
    struct Odd;
    impl McapView<Row> for Odd {
        fn channels(&self) -> Vec<ChannelSpec> {
            let spec = |topic: &str| ChannelSpec {
                topic: topic.into(),
                schema_name: "test.Blob".into(),
                schema_encoding: String::new(),
                schema: Vec::new(),
                message_encoding: "application/octet-stream".into(),
            };
            vec![spec("/odd"), spec("/every")]
        }
        fn messages(&mut self, row: &Row, emit: &mut dyn FnMut(usize, &[u8])) {
            if row.d % 2 == 1 {
                emit(0, &row.d.to_le_bytes());
            }
            emit(1, b"a");
            emit(1, b"b");
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.mcap");
    let want = rows(250);
    let mut w = McapStream::<Row>::with_view(path.clone(), File::create(&path).unwrap(), Some(Box::new(Odd))).unwrap();
    for r in &want {
        w.push(r.clone()).unwrap();
    }
    w.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let messages: Vec<(String, u32, u64, Vec<u8>)> = MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .map(|m| (m.channel.topic.clone(), m.sequence, m.log_time, m.data.to_vec()))
        .collect();
    // Row k: /one, /two, then /odd (odd d), /every twice.
    let mut k = 0;
    let mut odd = 0;
    let mut it = messages.iter();
    while let Some((topic, seq, ns, _)) = it.next() {
        assert_eq!((topic.as_str(), *seq as usize), ("/one", k));
        let t = (want[k].t * 1e9).round() as u64;
        assert_eq!(*ns, t);
        assert_eq!(it.next().unwrap().0, "/two");
        if want[k].d % 2 == 1 {
            let (topic, seq, ns, data) = it.next().unwrap();
            assert_eq!((topic.as_str(), *seq, *ns, data.as_slice()), ("/odd", odd, t, &want[k].d.to_le_bytes()[..]));
            odd += 1;
        }
        for (i, byte) in [b'a', b'b'].into_iter().enumerate() {
            let (topic, seq, ns, data) = it.next().unwrap();
            assert_eq!((topic.as_str(), *seq as usize, *ns, data.as_slice()), ("/every", 2 * k + i, t, &[byte][..]));
        }
        k += 1;
    }
    assert_eq!((k, odd), (250, 125));
    let tables = read_mcap(&path).unwrap();
    assert_eq!(back(&tables[0].1).len(), want.len());
}
