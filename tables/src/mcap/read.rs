//! Reading the MCAP files [`super::McapFile`] and [`super::McapStream`] write
//! back into tables ([`read_mcap`]).

use std::{borrow::Cow, collections::BTreeMap, path::Path};

use rayon::prelude::*;

use mcap::{
    read::{LinearReader, MessageStream, Options},
    records::Record,
};

use crate::{Column, Table, error::Error};

/// Reads the tables of the MCAP file at `path` that this module wrote: per
/// metadata record `painleve.table.<name>`, the [`Table`] of its columns (in
/// the CSV's order and types; `null` floats as NaN), row `k` made of the `k`-th
/// message of each of its topics. A file cut off (a run killed while writing)
/// gives its whole chunks, and of a table the rows whose every message is there.
/// Tables in the order of their metadata records.
///
/// # Errors
/// [`Error::Io`] naming the file when it cannot be read, is not MCAP, holds
/// no table metadata, or a message is not the JSON object its table's columns
/// describe.
pub fn read_mcap(path: &Path) -> Result<Vec<(String, Table)>, Error> {
    let bad = |what: String| Error::Io { path: path.to_path_buf(), source: std::io::Error::other(what) };
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let lenient = || Options::IgnoreEndMagic.into();
    struct Spec {
        name: String,
        columns: Vec<String>,
        kinds: Vec<String>,
        topics: Vec<String>,
    }
    let mut specs = Vec::new();
    let records = LinearReader::new_with_options(&bytes, lenient()).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
    for record in records {
        // A cut file: its records up to the cut.
        let Ok(record) = record else { break };
        if let Record::Metadata(m) = record
            && let Some(name) = m.name.strip_prefix("painleve.table.")
        {
            let list = |k: &str| m.metadata.get(k).map(|s| s.split(',').map(String::from).collect::<Vec<_>>()).unwrap_or_default();
            specs.push(Spec { name: name.to_string(), columns: list("columns"), kinds: list("kinds"), topics: list("topics") });
        }
    }
    if specs.is_empty() {
        return Err(bad("no table in it (no painleve.table.* metadata record): not written by sil-host --format mcap".into()));
    }
    // Each topic's columns, parsed message by message into typed columns (no JSON
    // tree per message): the kinds are the tables' declarations.
    let mut kinds: BTreeMap<&str, BTreeMap<&str, &str>> = BTreeMap::new();
    for spec in &specs {
        if spec.columns.len() != spec.kinds.len() {
            return Err(bad(format!("table {}: {} columns but {} kinds", spec.name, spec.columns.len(), spec.kinds.len())));
        }
        for topic in &spec.topics {
            let of_topic = kinds.entry(topic.as_str()).or_default();
            for (c, k) in spec.columns.iter().zip(&spec.kinds) {
                of_topic.insert(c.as_str(), k.as_str());
            }
        }
    }
    // A whole file's chunks, from its summary's chunk index, parsed in parallel
    // and joined in file order; a cut file (no summary) read linearly.
    let summary = mcap::Summary::read(&bytes).ok().flatten().filter(|s| !s.chunk_indexes.is_empty());
    let by_topic = match summary {
        Some(summary) => {
            let mut chunks = summary.chunk_indexes.clone();
            chunks.sort_by_key(|c| c.chunk_start_offset);
            let parts: Vec<Result<BTreeMap<String, TopicColumns>, String>> = chunks
                .par_iter()
                .map(|chunk| {
                    let mut part = BTreeMap::new();
                    let messages = summary.stream_chunk(&bytes, chunk).map_err(|e| format!("a chunk: {e}"))?;
                    for m in messages {
                        add_message(&mut part, &kinds, m.map_err(|e| format!("a chunk: {e}"))?)?;
                    }
                    Ok(part)
                })
                .collect();
            let mut joined: BTreeMap<String, TopicColumns> = BTreeMap::new();
            for part in parts {
                for (topic, columns) in part.map_err(&bad)? {
                    match joined.get_mut(&topic) {
                        Some(have) => have.append(columns).map_err(|e| bad(format!("{topic}: {e}")))?,
                        None if columns.first_sequence == Some(0) => {
                            joined.insert(topic, columns);
                        }
                        None => return Err(bad(format!("{topic}: message 0 has sequence number {:?}", columns.first_sequence))),
                    }
                }
            }
            joined
        }
        None => {
            let mut by_topic = BTreeMap::new();
            let messages = MessageStream::new_with_options(&bytes, lenient()).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
            for m in messages {
                // A cut file: its messages up to the cut.
                let Ok(m) = m else { break };
                add_message(&mut by_topic, &kinds, m).map_err(&bad)?;
            }
            if let Some((topic, c)) = by_topic.iter().find(|(_, c)| c.first_sequence.is_some_and(|s| s != 0)) {
                return Err(bad(format!("{topic}: message 0 has sequence number {:?}", c.first_sequence)));
            }
            by_topic
        }
    };
    let mut tables = Vec::new();
    for spec in specs {
        let empty = TopicColumns::default();
        let topics: Vec<&TopicColumns> = spec.topics.iter().map(|t| by_topic.get(t).unwrap_or(&empty)).collect();
        let n = topics.iter().map(|t| t.rows).min().unwrap_or(0);
        let mut columns = Vec::with_capacity(spec.columns.len());
        for (name, kind) in spec.columns.iter().zip(&spec.kinds) {
            if !["f64", "int", "bool", "str"].contains(&kind.as_str()) {
                return Err(bad(format!("table {}: column `{name}` of unknown kind `{kind}`", spec.name)));
            }
            // The first topic whose messages hold the column (`t` is in all).
            let source = topics.iter().find_map(|t| t.names.iter().position(|c| c == name).map(|i| &t.columns[i]));
            let column = match source {
                Some(c) => c.head(n),
                None if n == 0 => TopicColumns::new_column(kind),
                None => return Err(bad(format!("table {}: row 0: `{name}` is not a {kind}", spec.name))),
            };
            columns.push((name.clone(), column));
        }
        tables.push((spec.name, Table { columns }));
    }
    Ok(tables)
}

/// Adds message `m` to its topic's columns in `by_topic` (a topic no table
/// declares is skipped): its sequence number must follow the topic's last.
fn add_message(
    by_topic: &mut BTreeMap<String, TopicColumns>,
    kinds: &BTreeMap<&str, BTreeMap<&str, &str>>,
    m: mcap::Message<'_>,
) -> Result<(), String> {
    let Some(of_topic) = kinds.get(m.channel.topic.as_str()) else { return Ok(()) };
    let columns = by_topic.entry(m.channel.topic.clone()).or_default();
    let first = *columns.first_sequence.get_or_insert(m.sequence);
    if m.sequence as usize != first as usize + columns.rows {
        return Err(format!("{}: message {} has sequence number {}", m.channel.topic, first as usize + columns.rows, m.sequence));
    }
    columns.push(&m.data, of_topic).map_err(|e| format!("{}: message {}: {e}", m.channel.topic, first as usize + columns.rows))
}

/// The columns of one topic's messages so far (of the whole file, or of one
/// chunk): the keys of its first message that a table declares, in that
/// message's order, each a typed column; the sequence number of the first.
#[derive(Debug, Default)]
struct TopicColumns {
    names: Vec<String>,
    columns: Vec<Column>,
    rows: usize,
    first_sequence: Option<u32>,
}

impl TopicColumns {
    /// Appends `next`, the same topic's messages that follow these (the next
    /// chunk's): the same keys, the sequence numbers continuing.
    fn append(&mut self, next: TopicColumns) -> Result<(), String> {
        let expected = self.first_sequence.unwrap_or(0) as usize + self.rows;
        if next.first_sequence.map(|s| s as usize) != Some(expected) {
            return Err(format!("message {expected} has sequence number {:?}", next.first_sequence));
        }
        if next.names != self.names {
            return Err(format!("message {expected} has the keys {:?}, the first {:?}", next.names, self.names));
        }
        for (have, more) in self.columns.iter_mut().zip(next.columns) {
            match (have, more) {
                (Column::F64(a), Column::F64(b)) => a.extend(b),
                (Column::I64(a), Column::I64(b)) => a.extend(b),
                (Column::Bool(a), Column::Bool(b)) => a.extend(b),
                (Column::Str(a), Column::Str(b)) => a.extend(b),
                _ => return Err(format!("message {expected}: a column of another kind")),
            }
        }
        self.rows += next.rows;
        Ok(())
    }

    /// An empty column of kind `kind` (`f64`, `int`, `bool`, else text).
    fn new_column(kind: &str) -> Column {
        match kind {
            "f64" => Column::F64(Vec::new()),
            "int" => Column::I64(Vec::new()),
            "bool" => Column::Bool(Vec::new()),
            _ => Column::Str(Vec::new()),
        }
    }

    /// Appends the message `data` (a JSON object): each declared key's value to
    /// its column (`null` as NaN in a float column); the first message sets the
    /// keys, every later one must hold the same.
    fn push(&mut self, data: &[u8], kinds: &BTreeMap<&str, &str>) -> Result<(), String> {
        let first = self.rows == 0 && self.names.is_empty();
        let mut de = serde_json::Deserializer::from_slice(data);
        let seen = serde::de::Deserializer::deserialize_map(&mut de, MessageVisitor { topic: self, kinds, first })
            .map_err(|e| format!("not the JSON object its table describes: {e}"))?;
        de.end().map_err(|e| format!("not a JSON object: {e}"))?;
        if seen != self.names.len() {
            let missing = self.columns.iter().zip(&self.names).find(|(c, _)| c.len() <= self.rows).map(|(_, n)| n.clone());
            return Err(format!("`{}` is missing", missing.unwrap_or_default()));
        }
        self.rows += 1;
        Ok(())
    }
}

/// Column `c`'s first `n` values.
trait Head {
    fn head(&self, n: usize) -> Column;
}

impl Head for Column {
    fn head(&self, n: usize) -> Column {
        match self {
            Column::F64(v) => Column::F64(v[..n].to_vec()),
            Column::I64(v) => Column::I64(v[..n].to_vec()),
            Column::Bool(v) => Column::Bool(v[..n].to_vec()),
            Column::Str(v) => Column::Str(v[..n].to_vec()),
        }
    }
}

/// Visits one message's JSON object into [`TopicColumns`]; gives how many of
/// the topic's columns it filled.
struct MessageVisitor<'a, 'k> {
    topic: &'a mut TopicColumns,
    kinds: &'a BTreeMap<&'k str, &'k str>,
    first: bool,
}

/// A key of a message, borrowed from it when it has no escapes.
struct Key<'de>(Cow<'de, str>);

impl<'de> serde::Deserialize<'de> for Key<'de> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Key<'de>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a key")
            }
            fn visit_borrowed_str<E>(self, v: &'de str) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Borrowed(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Owned(v.to_string())))
            }
        }
        d.deserialize_str(V)
    }
}

impl<'de> serde::de::Visitor<'de> for MessageVisitor<'_, '_> {
    type Value = usize;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON object")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<usize, A::Error> {
        use serde::de::{Error as _, IgnoredAny};
        let topic = self.topic;
        let mut seen = 0;
        let mut at = 0;
        while let Some(Key(key)) = map.next_key::<Key<'de>>()? {
            // The keys come in the first message's order: try the next one first.
            let index = if topic.names.get(at).is_some_and(|n| *n == key) { Some(at) } else { topic.names.iter().position(|n| *n == key) };
            let index = match (index, self.first) {
                (Some(i), _) => i,
                (None, true) => match self.kinds.get(key.as_ref()) {
                    Some(kind) => {
                        topic.names.push(key.to_string());
                        topic.columns.push(TopicColumns::new_column(kind));
                        topic.names.len() - 1
                    }
                    None => {
                        map.next_value::<IgnoredAny>()?;
                        continue;
                    }
                },
                (None, false) => {
                    map.next_value::<IgnoredAny>()?;
                    continue;
                }
            };
            at = index + 1;
            let wrong = |kind: &str| A::Error::custom(format!("`{key}` is not a {kind}"));
            match &mut topic.columns[index] {
                Column::F64(v) => v.push(map.next_value::<Option<f64>>().map_err(|_| wrong("f64"))?.unwrap_or(f64::NAN)),
                Column::I64(v) => v.push(map.next_value::<i64>().map_err(|_| wrong("int"))?),
                Column::Bool(v) => v.push(map.next_value::<bool>().map_err(|_| wrong("bool"))?),
                Column::Str(v) => v.push(map.next_value::<String>().map_err(|_| wrong("str"))?),
            }
            seen += 1;
        }
        Ok(seen)
    }
}
