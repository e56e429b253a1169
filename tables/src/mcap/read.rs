//! Reading the MCAP files [`super::McapFile`] and [`super::McapStream`] write
//! back into tables ([`read_mcap`]).

use std::{borrow::Cow, collections::BTreeMap, path::Path};

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
    // The messages of each topic, in order.
    let mut by_topic: BTreeMap<String, Vec<serde_json::Map<String, serde_json::Value>>> = BTreeMap::new();
    let messages = MessageStream::new_with_options(&bytes, lenient()).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
    for m in messages {
        let Ok(m) = m else { break };
        let list = by_topic.entry(m.channel.topic.clone()).or_default();
        if m.sequence as usize != list.len() {
            return Err(bad(format!("{}: message {} has sequence number {}", m.channel.topic, list.len(), m.sequence)));
        }
        let data: Cow<[u8]> = m.data;
        let object = serde_json::from_slice(&data)
            .map_err(|e| bad(format!("{}: message {}: not a JSON object: {e}", m.channel.topic, list.len())))?;
        list.push(object);
    }
    let mut tables = Vec::new();
    for spec in specs {
        if spec.columns.len() != spec.kinds.len() {
            return Err(bad(format!("table {}: {} columns but {} kinds", spec.name, spec.columns.len(), spec.kinds.len())));
        }
        let empty = Vec::new();
        let topics: Vec<&Vec<_>> = spec.topics.iter().map(|t| by_topic.get(t).unwrap_or(&empty)).collect();
        let n = topics.iter().map(|m| m.len()).min().unwrap_or(0);
        let mut columns = Vec::with_capacity(spec.columns.len());
        for (name, kind) in spec.columns.iter().zip(&spec.kinds) {
            // The first topic whose messages hold the column (`t` is in all).
            let source = topics.iter().find(|m| m.first().is_some_and(|o| o.contains_key(name)));
            let value = |k: usize| source.and_then(|m| m[k].get(name.as_str()));
            let wrong = |k: usize| bad(format!("table {}: row {k}: `{name}` is not a {kind}", spec.name));
            let column = match kind.as_str() {
                "f64" => Column::F64(
                    (0..n)
                        .map(|k| match value(k) {
                            Some(serde_json::Value::Null) => Ok(f64::NAN),
                            Some(v) => v.as_f64().ok_or_else(|| wrong(k)),
                            None => Err(wrong(k)),
                        })
                        .collect::<Result<_, _>>()?,
                ),
                "int" => Column::I64(
                    (0..n).map(|k| value(k).and_then(serde_json::Value::as_i64).ok_or_else(|| wrong(k))).collect::<Result<_, _>>()?,
                ),
                "bool" => Column::Bool(
                    (0..n).map(|k| value(k).and_then(serde_json::Value::as_bool).ok_or_else(|| wrong(k))).collect::<Result<_, _>>()?,
                ),
                "str" => Column::Str(
                    (0..n)
                        .map(|k| value(k).and_then(serde_json::Value::as_str).map(String::from).ok_or_else(|| wrong(k)))
                        .collect::<Result<_, _>>()?,
                ),
                other => return Err(bad(format!("table {}: column `{name}` of unknown kind `{other}`", spec.name))),
            };
            columns.push((name.clone(), column));
        }
        tables.push((spec.name, Table { columns }));
    }
    Ok(tables)
}
