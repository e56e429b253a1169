//! Reading the MCAP files [`super::McapFile`] and [`super::McapStream`] write
//! back into tables ([`read_mcap`]).

use std::{collections::BTreeMap, path::Path, sync::Arc};

use prost::{
    Message as _,
    encoding::{DecodeContext, decode_key, skip_field},
};
use prost_types::FileDescriptorSet;
use rayon::prelude::*;

use mcap::{
    read::{LinearReader, MessageStream, Options},
    records::{ChunkIndex, Metadata, Record},
};

use super::schema::proto_type;
use crate::{Column, Table, declared::Kind, error::Error};

/// Reads the tables of the MCAP file at `path` that this module wrote: per
/// metadata record `painleve.table.<name>`, the [`Table`] of its columns (in
/// the CSV's order and types), row `k` made of the `k`-th message of each of
/// its topics, each message decoded by its channel's protobuf schema. A file
/// cut off (a run killed while writing) gives its whole chunks, and of a table
/// the rows whose every message is there. Tables in the order of their
/// metadata records. A whole file's chunks are found by its summary's chunk
/// index (those without a message of a table's channel are not read) and
/// decoded in parallel; a cut file is read linearly.
///
/// # Errors
/// [`Error::Unreadable`] naming the file when it cannot be read, is not MCAP, holds
/// no table metadata, a table's channel is not protobuf (a file written
/// before the tables' channels were: JSON) or its schema lacks a column or
/// gives it another type, or a message is not the one its schema describes
/// (a field of another wire type, twice, or missing; a sequence number out of
/// order).
pub fn read_mcap(path: &Path) -> Result<Vec<(String, Table)>, Error> {
    let bad = |what: String| Error::unreadable(path, what);
    let bytes = crate::input::read(path, crate::input::TABLE)?;
    let summary = mcap::Summary::read(&bytes).ok().flatten();
    let specs = specs(&bytes, summary.as_ref()).map_err(&bad)?;
    // Each table topic's declared kinds, by column name.
    let mut declared: BTreeMap<&str, BTreeMap<&str, Kind>> = BTreeMap::new();
    for spec in &specs {
        for topic in &spec.topics {
            declared.entry(topic.as_str()).or_default().extend(spec.columns.iter().map(|(c, k)| (c.as_str(), *k)));
        }
    }
    let by_topic = match summary.filter(|s| !s.chunk_indexes.is_empty()) {
        Some(summary) => {
            // The table channels' layouts, by channel id.
            let mut layouts: BTreeMap<u16, Arc<Layout>> = BTreeMap::new();
            for (id, channel) in &summary.channels {
                if let Some(declared) = declared.get(channel.topic.as_str()) {
                    layouts.insert(*id, Arc::new(Layout::new(channel, declared).map_err(&bad)?));
                }
            }
            let mut chunks: Vec<&ChunkIndex> = summary
                .chunk_indexes
                .iter()
                .filter(|c| c.message_index_offsets.is_empty() || c.message_index_offsets.keys().any(|id| layouts.contains_key(id)))
                .collect();
            chunks.sort_by_key(|c| c.chunk_start_offset);
            let parts: Vec<Result<BTreeMap<String, TopicColumns>, String>> = chunks
                .par_iter()
                .map(|chunk| {
                    let mut part = BTreeMap::new();
                    for m in summary.stream_chunk(&bytes, chunk).map_err(|e| format!("a chunk: {e}"))? {
                        let m = m.map_err(|e| format!("a chunk: {e}"))?;
                        if let Some(layout) = layouts.get(&m.channel.id) {
                            add_message(&mut part, layout, &m)?;
                        }
                    }
                    Ok(part)
                })
                .collect();
            let mut pieces: BTreeMap<String, Vec<TopicColumns>> = BTreeMap::new();
            for part in parts {
                for (topic, columns) in part.map_err(&bad)? {
                    pieces.entry(topic).or_default().push(columns);
                }
            }
            pieces
                .into_iter()
                .map(|(topic, p)| Ok((topic.clone(), join(p).map_err(|e| bad(format!("{topic}: {e}")))?)))
                .collect::<Result<_, Error>>()?
        }
        None => {
            let mut layouts: BTreeMap<u16, Arc<Layout>> = BTreeMap::new();
            let mut by_topic = BTreeMap::new();
            let lenient = Options::IgnoreEndMagic.into();
            let messages = MessageStream::new_with_options(&bytes, lenient).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
            for m in messages {
                // A cut file: its messages up to the cut.
                let Ok(m) = m else { break };
                let Some(declared) = declared.get(m.channel.topic.as_str()) else { continue };
                let layout = match layouts.get(&m.channel.id) {
                    Some(l) => l.clone(),
                    None => {
                        let l = Arc::new(Layout::new(&m.channel, declared).map_err(&bad)?);
                        layouts.insert(m.channel.id, l.clone());
                        l
                    }
                };
                add_message(&mut by_topic, &layout, &m).map_err(&bad)?;
            }
            if let Some((topic, c)) = by_topic.iter().find(|(_, c)| c.first_sequence.is_some_and(|s| s != 0)) {
                return Err(bad(format!("{topic}: message 0 has sequence number {:?}", c.first_sequence)));
            }
            by_topic
        }
    };
    let mut by_topic = by_topic;
    let mut tables = Vec::new();
    for spec in specs {
        let n = spec.topics.iter().map(|t| by_topic.get(t).map_or(0, |c| c.rows)).min().unwrap_or(0);
        let mut columns = Vec::with_capacity(spec.columns.len());
        for (name, kind) in &spec.columns {
            // The first topic whose messages hold the column (`t` is in all).
            let source = spec.topics.iter().find_map(|t| by_topic.get_mut(t).and_then(|c| c.take(name)));
            let column = match source {
                Some(mut c) => {
                    c.truncate(n);
                    c
                }
                None if n == 0 => Column::empty(*kind),
                None => return Err(bad(format!("table {}: no channel of it holds `{name}`", spec.name))),
            };
            columns.push((name.clone(), column));
        }
        tables.push((spec.name, Table { columns }));
    }
    Ok(tables)
}

/// A table as its metadata record `painleve.table.<name>` declares it.
struct Spec {
    name: String,
    /// Its columns in the CSV's order, with their kinds.
    columns: Vec<(String, Kind)>,
    /// Its channels' topics.
    topics: Vec<String>,
}

/// The tables `bytes` declares: from the summary's metadata index when the file
/// has one, else (a cut file) from the metadata records up to the cut.
fn specs(bytes: &[u8], summary: Option<&mcap::Summary>) -> Result<Vec<Spec>, String> {
    let mut records: Vec<Metadata> = Vec::new();
    let indexed = summary.map(|s| &s.metadata_indexes).filter(|m| !m.is_empty());
    match indexed {
        Some(indexes) => {
            let mut indexes: Vec<_> = indexes.iter().filter(|i| i.name.starts_with("painleve.table.")).collect();
            indexes.sort_by_key(|i| i.offset);
            for index in indexes {
                records.push(mcap::read::metadata(bytes, index).map_err(|e| format!("a metadata record: {e}"))?);
            }
        }
        None => {
            let lenient = Options::IgnoreEndMagic.into();
            for record in LinearReader::new_with_options(bytes, lenient).map_err(|e| format!("not an MCAP file: {e}"))? {
                // A cut file: its records up to the cut.
                let Ok(record) = record else { break };
                if let Record::Metadata(m) = record {
                    records.push(m);
                }
            }
        }
    }
    let mut specs = Vec::new();
    for m in records {
        let Some(name) = m.name.strip_prefix("painleve.table.") else { continue };
        let list = |k: &str| m.metadata.get(k).map(|s| s.split(',').map(String::from).collect::<Vec<_>>()).unwrap_or_default();
        let (columns, kinds) = (list("columns"), list("kinds"));
        if columns.len() != kinds.len() {
            return Err(format!("table {name}: {} columns but {} kinds", columns.len(), kinds.len()));
        }
        let columns = columns
            .into_iter()
            .zip(kinds)
            .map(|(c, k)| match Kind::from_name(&k) {
                Some(kind) => Ok((c, kind)),
                None => Err(format!("table {name}: column `{c}` of unknown kind `{k}`")),
            })
            .collect::<Result<_, _>>()?;
        specs.push(Spec { name: name.to_string(), columns, topics: list("topics") });
    }
    if specs.is_empty() {
        return Err("no table in it (no painleve.table.* metadata record): not written by sil-host --format mcap".into());
    }
    Ok(specs)
}

/// Where the fields of one table channel's messages go, from its protobuf
/// schema: the message's fields that its table declares, in the schema's
/// order, each a column of the declared kind.
#[derive(Debug)]
struct Layout {
    topic: String,
    /// The columns' names and kinds.
    columns: Vec<(String, Kind)>,
    /// By field number: the column it fills.
    slots: Vec<Option<usize>>,
}

/// A channel holds at most this many of a table's columns (one bit each in a
/// message's check that every field came once).
const MAX_CHANNEL_COLUMNS: usize = 64;

impl Layout {
    /// The layout of `channel`'s messages for the columns `declared` (name:
    /// kind): its schema's message (the schema's name, in its
    /// `FileDescriptorSet`), every field of which a declared column must have
    /// the type ([`proto_type`]).
    fn new(channel: &mcap::Channel<'_>, declared: &BTreeMap<&str, Kind>) -> Result<Self, String> {
        let topic = &channel.topic;
        let schema = channel.schema.as_ref().ok_or_else(|| format!("{topic}: the channel has no schema"))?;
        if channel.message_encoding != "protobuf" || schema.encoding != "protobuf" {
            return Err(format!(
                "{topic}: messages `{}` by a `{}` schema, not protobuf (a file written before sil-host's tables were protobuf: Foxglove or the mcap package read it)",
                channel.message_encoding, schema.encoding
            ));
        }
        let set = FileDescriptorSet::decode(&schema.data[..]).map_err(|e| format!("{topic}: schema {}: {e}", schema.name))?;
        let (package, name) = schema.name.rsplit_once('.').unwrap_or(("", schema.name.as_str()));
        let message = set
            .file
            .iter()
            .filter(|f| f.package() == package)
            .flat_map(|f| &f.message_type)
            .find(|m| m.name() == name)
            .ok_or_else(|| format!("{topic}: schema {} has no message {}", schema.name, schema.name))?;
        let mut columns = Vec::new();
        let mut slots = Vec::new();
        for field in &message.field {
            let Some(kind) = declared.get(field.name()) else { continue };
            let number =
                usize::try_from(field.number()).map_err(|_| format!("{topic}: field `{}` numbered {}", field.name(), field.number()))?;
            if field.r#type() != proto_type(*kind) {
                return Err(format!("{topic}: field `{}` is {:?}, its table declares {}", field.name(), field.r#type(), kind.name()));
            }
            if slots.len() <= number {
                slots.resize(number + 1, None);
            }
            slots[number] = Some(columns.len());
            columns.push((field.name().to_string(), *kind));
        }
        if columns.len() > MAX_CHANNEL_COLUMNS {
            return Err(format!("{topic}: {} columns, at most {MAX_CHANNEL_COLUMNS} in a channel", columns.len()));
        }
        Ok(Self { topic: topic.clone(), columns, slots })
    }
}

/// Adds message `m` (of `layout`'s channel) to its topic's columns in
/// `by_topic`: its sequence number must follow the topic's last.
fn add_message(by_topic: &mut BTreeMap<String, TopicColumns>, layout: &Arc<Layout>, m: &mcap::Message<'_>) -> Result<(), String> {
    let topic = match by_topic.get_mut(&layout.topic) {
        Some(t) => t,
        None => by_topic.entry(layout.topic.clone()).or_insert_with(|| TopicColumns::new(layout.clone())),
    };
    let first = *topic.first_sequence.get_or_insert(m.sequence);
    let k = first as usize + topic.rows;
    if m.sequence as usize != k {
        return Err(format!("{}: message {k} has sequence number {}", layout.topic, m.sequence));
    }
    topic.push(&m.data).map_err(|e| format!("{}: message {k}: {e}", layout.topic))
}

/// The columns of one topic's messages so far (of the whole file, or of one
/// chunk), as its [`Layout`] gives them; the sequence number of the first.
#[derive(Debug)]
struct TopicColumns {
    layout: Arc<Layout>,
    /// One per column of the layout; `None` once taken ([`TopicColumns::take`]).
    columns: Vec<Option<Column>>,
    rows: usize,
    first_sequence: Option<u32>,
}

impl TopicColumns {
    fn new(layout: Arc<Layout>) -> Self {
        let columns = layout.columns.iter().map(|(_, k)| Some(Column::empty(*k))).collect();
        Self { layout, columns, rows: 0, first_sequence: None }
    }

    /// Column `name`, taken out (a second take gives `None`).
    fn take(&mut self, name: &str) -> Option<Column> {
        let i = self.layout.columns.iter().position(|(n, _)| n == name)?;
        self.columns[i].take()
    }

    /// Appends the message `data` (protobuf): each field of the layout exactly
    /// once, of its wire type; fields it does not know are skipped.
    fn push(&mut self, mut data: &[u8]) -> Result<(), String> {
        let mut seen = 0u64;
        let buf = &mut data;
        while !buf.is_empty() {
            let (number, wire) = decode_key(buf).map_err(|e| format!("not the protobuf message its schema describes: {e}"))?;
            let Some(slot) = self.layout.slots.get(number as usize).copied().flatten() else {
                skip_field(wire, number, buf, DecodeContext::default()).map_err(|e| format!("field {number}: {e}"))?;
                continue;
            };
            let (name, _) = &self.layout.columns[slot];
            if seen & (1 << slot) != 0 {
                return Err(format!("`{name}` twice"));
            }
            seen |= 1 << slot;
            let wrong = |e: prost::DecodeError| format!("`{name}`: {e}");
            let ctx = DecodeContext::default();
            match &mut self.columns[slot] {
                Some(Column::F64(v)) => {
                    let mut x = 0.0;
                    prost::encoding::double::merge(wire, &mut x, buf, ctx).map_err(wrong)?;
                    v.push(x);
                }
                Some(Column::I64(v)) => {
                    let mut x = 0;
                    prost::encoding::int64::merge(wire, &mut x, buf, ctx).map_err(wrong)?;
                    v.push(x);
                }
                Some(Column::Bool(v)) => {
                    let mut x = false;
                    prost::encoding::bool::merge(wire, &mut x, buf, ctx).map_err(wrong)?;
                    v.push(x);
                }
                Some(Column::Str(v)) => {
                    let mut x = String::new();
                    prost::encoding::string::merge(wire, &mut x, buf, ctx).map_err(wrong)?;
                    v.push(x);
                }
                None => return Err(format!("`{name}` after its column was taken")),
            }
        }
        let all = if self.layout.columns.len() == 64 { u64::MAX } else { (1u64 << self.layout.columns.len()) - 1 };
        if seen != all {
            let missing = (0..self.layout.columns.len()).find(|i| seen & (1 << i) == 0).map(|i| self.layout.columns[i].0.as_str());
            return Err(format!("`{}` is missing", missing.unwrap_or_default()));
        }
        self.rows += 1;
        Ok(())
    }
}

/// One topic's columns from the chunks `parts` (in file order), joined: the
/// sequence numbers continuing from 0, each column allocated once.
fn join(parts: Vec<TopicColumns>) -> Result<TopicColumns, String> {
    let mut expected = 0usize;
    for p in &parts {
        if p.first_sequence.map(|s| s as usize) != Some(expected) {
            return Err(format!("message {expected} has sequence number {:?}", p.first_sequence));
        }
        expected += p.rows;
    }
    let mut parts = parts.into_iter();
    let Some(mut whole) = parts.next() else { return Err("no message".into()) };
    let rest: Vec<TopicColumns> = parts.collect();
    for (i, column) in whole.columns.iter_mut().enumerate() {
        let Some(column) = column else { continue };
        let more = rest.iter().filter_map(|p| p.columns[i].as_ref());
        column.reserve_and_extend(expected, more)?;
    }
    whole.rows = expected;
    Ok(whole)
}

/// Helpers on [`Column`] for the reader.
trait ColumnExt {
    fn empty(kind: Kind) -> Self;
    fn truncate(&mut self, n: usize);
    fn reserve_and_extend<'a>(&mut self, total: usize, more: impl Iterator<Item = &'a Column>) -> Result<(), String>;
}

impl ColumnExt for Column {
    /// An empty column of kind `kind`.
    fn empty(kind: Kind) -> Self {
        match kind {
            Kind::F64 => Column::F64(Vec::new()),
            Kind::Int => Column::I64(Vec::new()),
            Kind::Bool => Column::Bool(Vec::new()),
            Kind::Str => Column::Str(Vec::new()),
        }
    }

    /// Keeps the first `n` values.
    fn truncate(&mut self, n: usize) {
        match self {
            Column::F64(v) => v.truncate(n),
            Column::I64(v) => v.truncate(n),
            Column::Bool(v) => v.truncate(n),
            Column::Str(v) => v.truncate(n),
        }
    }

    /// Appends the columns `more` (of the same kind), room made for `total` values at once.
    fn reserve_and_extend<'a>(&mut self, total: usize, more: impl Iterator<Item = &'a Column>) -> Result<(), String> {
        fn extend<T: Clone>(v: &mut Vec<T>, total: usize, more: &mut dyn Iterator<Item = Option<&[T]>>) -> Result<(), String> {
            v.reserve_exact(total.saturating_sub(v.len()));
            for m in more {
                v.extend_from_slice(m.ok_or("a column of another kind in a later chunk")?);
            }
            Ok(())
        }
        match self {
            Column::F64(v) => extend(v, total, &mut more.map(|c| if let Column::F64(m) = c { Some(&m[..]) } else { None })),
            Column::I64(v) => extend(v, total, &mut more.map(|c| if let Column::I64(m) = c { Some(&m[..]) } else { None })),
            Column::Bool(v) => extend(v, total, &mut more.map(|c| if let Column::Bool(m) = c { Some(&m[..]) } else { None })),
            Column::Str(v) => extend(v, total, &mut more.map(|c| if let Column::Str(m) = c { Some(&m[..]) } else { None })),
        }
    }
}
