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

/// Every float back with its bits (protobuf `double`: NaN and infinities
/// too), text with quotes, backslashes and newlines back as it was.
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
        assert_eq!((g.t.to_bits(), g.a.to_bits(), &g.b, g.c, g.d), (w.t.to_bits(), w.a.to_bits(), &w.b, w.c, w.d));
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
    assert_eq!(encodings[0], ("/events".to_string(), "protobuf".to_string(), "protobuf".to_string()));
}

/// Each channel's schema is a `FileDescriptorSet` of one proto3 message named
/// as the group's schema: `t` as field 1, then the group's columns in order,
/// each of its kind's type, with its unit in the field's comment.
#[test]
fn the_schemas_are_protobuf_descriptors_with_every_column_in_order() {
    use prost::Message as _;
    use prost_types::field_descriptor_proto::Type;
    let encoder = RowEncoder::<Row>::new().unwrap();
    let two = &encoder.channels()[1];
    assert_eq!((two.topic.as_str(), two.schema_name.as_str(), two.schema_encoding.as_str()), ("/two", "test.Two", "protobuf"));
    let set = prost_types::FileDescriptorSet::decode(&two.schema[..]).unwrap();
    let [file] = &set.file[..] else { panic!("{set:?}") };
    assert_eq!((file.package(), file.syntax(), file.message_type[0].name()), ("test", "proto3", "Two"));
    let fields: Vec<_> = file.message_type[0].field.iter().map(|f| (f.name(), f.number(), f.r#type())).collect();
    assert_eq!(fields, [("t", 1, Type::Double), ("b", 2, Type::String), ("d", 3, Type::Int64)]);
    let comments = &file.source_code_info.as_ref().unwrap().location;
    assert_eq!(comments[0].path, [4, 0, 2, 0]);
    assert!(comments[0].leading_comments().contains("time, s"), "{:?}", comments[0]);
}

/// A file whose table channel is not the protobuf the reader knows, or
/// whose messages break their schema, is refused with the channel, the
/// message and the field: JSON messages (a file written before), a field
/// missing, twice, or of another wire type, bytes cut inside a field.
#[test]
fn a_message_that_breaks_its_schema_is_refused_by_field() {
    use prost::encoding::{double, string};
    let dir = tempfile::tempdir().unwrap();
    let encoder = RowEncoder::<Event>::new().unwrap();
    let spec = &encoder.channels()[0];
    let write = |name: &str, encoding: &str, data: &[u8]| {
        let path = dir.path().join(name);
        let mut w = mcap::Writer::new(std::io::BufWriter::new(File::create(&path).unwrap())).unwrap();
        let schema = w.add_schema(&spec.schema_name, encoding, &spec.schema).unwrap();
        let channel = w.add_channel(schema, "/events", encoding, &Default::default()).unwrap();
        let metadata = [("columns", "t,kind"), ("kinds", "f64,str"), ("topics", "/events")];
        let metadata = metadata.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        w.write_metadata(&mcap::records::Metadata { name: "painleve.table.events".into(), metadata }).unwrap();
        let header = mcap::records::MessageHeader { channel_id: channel, sequence: 0, log_time: 0, publish_time: 0 };
        w.write_to_known_channel(&header, data).unwrap();
        w.finish().unwrap();
        drop(w);
        read_mcap(&path).map(|t| t[0].1.rows()).map_err(|e| e.to_string())
    };
    let mut good = Vec::new();
    double::encode(1, &0.5, &mut good);
    string::encode(2, &"touchdown".to_string(), &mut good);
    assert_eq!(write("good.mcap", "protobuf", &good), Ok(1));
    // An unknown field is skipped.
    let mut more = good.clone();
    double::encode(9, &1.0, &mut more);
    assert_eq!(write("more.mcap", "protobuf", &more), Ok(1));
    let e = write("json.mcap", "json", br#"{"t":0.5,"kind":"touchdown"}"#).unwrap_err();
    assert!(e.contains("json.mcap") && e.contains("/events") && e.contains("not protobuf"), "{e}");
    let mut missing = Vec::new();
    double::encode(1, &0.5, &mut missing);
    let e = write("missing.mcap", "protobuf", &missing).unwrap_err();
    assert!(e.contains("/events: message 0: `kind` is missing"), "{e}");
    let mut twice = good.clone();
    double::encode(1, &0.5, &mut twice);
    assert!(write("twice.mcap", "protobuf", &twice).unwrap_err().contains("`t` twice"));
    let mut wrong = Vec::new();
    string::encode(1, &"0.5".to_string(), &mut wrong);
    string::encode(2, &"touchdown".to_string(), &mut wrong);
    let e = write("wrong.mcap", "protobuf", &wrong).unwrap_err();
    assert!(e.contains("message 0: `t`"), "{e}");
    let e = write("cut.mcap", "protobuf", &good[..good.len() - 3]).unwrap_err();
    assert!(e.contains("message 0: `kind`"), "{e}");
}

#[test]
fn not_mcap_is_refused_with_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trace.mcap");
    std::fs::write(&path, "t,theta1\n0,1\n").unwrap();
    let e = read_mcap(&path).unwrap_err().to_string();
    assert!(e.contains("trace.mcap"), "{e}");
}

/// A view's channels come after its table's. The view messages of a chunk's
/// rows come in a chunk of their own right after it, with each row's log time
/// and their own sequence numbers (from 0); the chunk index tells the two
/// apart, and the reader leaves the views out and gives the table back whole,
/// from a whole file and from one cut inside a view's chunk.
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
    // Per chunk of STREAM_CHUNK_ROWS rows: row k's /one and /two, for every
    // row; then, per row, /odd (odd d) and /every twice.
    let (mut k, mut odd, mut every) = (0, 0, 0);
    let mut it = messages.iter();
    for block in want.chunks(STREAM_CHUNK_ROWS) {
        for row in block {
            let t = (row.t * 1e9).round() as u64;
            let (topic, seq, ns, _) = it.next().unwrap();
            assert_eq!((topic.as_str(), *seq as usize, *ns), ("/one", k, t));
            let (topic, seq, ns, _) = it.next().unwrap();
            assert_eq!((topic.as_str(), *seq as usize, *ns), ("/two", k, t));
            k += 1;
        }
        for row in block {
            let t = (row.t * 1e9).round() as u64;
            if row.d % 2 == 1 {
                let (topic, seq, ns, data) = it.next().unwrap();
                assert_eq!((topic.as_str(), *seq, *ns, data.as_slice()), ("/odd", odd, t, &row.d.to_le_bytes()[..]));
                odd += 1;
            }
            for byte in [b'a', b'b'] {
                let (topic, seq, ns, data) = it.next().unwrap();
                assert_eq!((topic.as_str(), *seq, *ns, data.as_slice()), ("/every", every, t, &[byte][..]));
                every += 1;
            }
        }
    }
    assert_eq!((k, odd, every, it.next()), (250, 125, 500, None));
    // Each chunk of messages holds the table's channels or the view's, never
    // both, in turn (the first chunk holds only the schemas and channels).
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let id = |topic: &str| summary.channels.values().find(|c| c.topic == topic).unwrap().id;
    let table = [id("/one"), id("/two")];
    assert!(summary.chunk_indexes[0].message_index_offsets.is_empty());
    let kinds: Vec<bool> = summary.chunk_indexes[1..]
        .iter()
        .map(|c| {
            let ids: Vec<u16> = c.message_index_offsets.keys().copied().collect();
            assert!(ids.iter().all(|i| table.contains(i)) || ids.iter().all(|i| !table.contains(i)), "{ids:?}");
            table.contains(&ids[0])
        })
        .collect();
    assert_eq!(kinds, [true, false, true, false, true, false]);
    // Cut inside the second view chunk: the first two table chunks' rows.
    let second_view = &summary.chunk_indexes[4];
    std::fs::write(&path, &bytes[..(second_view.chunk_start_offset + second_view.chunk_length / 2) as usize]).unwrap();
    let got = back(&read_mcap(&path).unwrap()[0].1);
    let bits = |r: &[Row]| r.iter().map(|r| (r.t.to_bits(), r.a.to_bits(), r.b.clone(), r.c, r.d)).collect::<Vec<_>>();
    assert!(bits(&got) == bits(&want[..2 * STREAM_CHUNK_ROWS]), "{} rows", got.len());
    std::fs::write(&path, &bytes).unwrap();
    let tables = read_mcap(&path).unwrap();
    assert_eq!(back(&tables[0].1).len(), want.len());
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// Any rows come back from a file with every float's bits (any bit
    /// pattern: NaNs with their payloads, infinities, subnormals, -0), every
    /// string (any Unicode), flag and integer as written, across chunks.
    #[test]
    fn random_rows_round_trip_with_their_bits(
        raw in proptest::collection::vec((proptest::prelude::any::<u64>(), proptest::prelude::any::<u64>(), ".{0,12}", proptest::prelude::any::<bool>(), proptest::prelude::any::<u32>()), 0..260),
    ) {
        let want: Vec<Row> = raw
            .iter()
            .map(|(t, a, b, c, d)| Row { t: f64::from_bits(*t), a: f64::from_bits(*a), b: b.clone(), c: *c, d: *d })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.mcap");
        let mut w = McapStream::<Row>::new(path.clone(), File::create(&path).unwrap()).unwrap();
        for r in &want {
            w.push(r.clone()).unwrap();
        }
        w.finish().unwrap();
        let got = back(&read_mcap(&path).unwrap()[0].1);
        let bits = |r: &[Row]| r.iter().map(|r| (r.t.to_bits(), r.a.to_bits(), r.b.clone(), r.c, r.d)).collect::<Vec<_>>();
        proptest::prop_assert_eq!(bits(&got), bits(&want));
    }
}
