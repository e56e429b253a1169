//! The channels of a trace and their messages, apart from where they go: an
//! MCAP file ([`super::McapFile`]) or a live stream (the `arm-view` crate's
//! Foxglove WebSocket server). Both take their channels and bytes from here,
//! so a live viewer gets exactly the file's messages.
//!
//! - [`ChannelSpec`]: a channel's topic, schema and encodings.
//! - [`RowEncoder`]: a table's own channels, one per signal group
//!   ([`McapRows::GROUPS`]), a protobuf message per row and group.
//! - [`McapView`]: channels drawn from a table's rows besides its own (the
//!   arm's frames, 3D scene and log in Foxglove's schemas).

use std::marker::PhantomData;

use super::{McapRows, schema::schema_proto};
use crate::Column;

/// One channel: its topic, its schema (name, encoding and bytes) and its
/// messages' encoding, as an MCAP Schema and Channel record hold them
/// (<https://mcap.dev/spec#channel-op0x04>).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelSpec {
    /// The topic (`/state`, `/tf`).
    pub topic: String,
    /// The schema's name (`painleve.State`, `foxglove.FrameTransforms`).
    pub schema_name: String,
    /// The schema's encoding (`jsonschema`, `protobuf`).
    pub schema_encoding: String,
    /// The schema itself (a JSON Schema's text, a protobuf `FileDescriptorSet`).
    pub schema: Vec<u8>,
    /// The messages' encoding (`json`, `protobuf`).
    pub message_encoding: String,
}

/// Messages drawn from a table's rows besides the table's own: the arm's
/// frames, 3D scene and log for Foxglove (`arm-view`). The writer calls
/// [`McapView::messages`] after each row's own messages, with the row's log
/// time, so the file stays in order of time.
pub trait McapView<T>: Send {
    /// The view's channels, registered once, after the table's own.
    fn channels(&self) -> Vec<ChannelSpec>;
    /// The messages of `row` (none, one or several), each given to `emit` as
    /// (its channel's index in [`McapView::channels`], its bytes). A message's
    /// log time is the row's time.
    fn messages(&mut self, row: &T, emit: &mut dyn FnMut(usize, &[u8]));
    /// The view's metadata records (MCAP `Metadata`: a name and string pairs), written
    /// once after the table's own `painleve.table.<name>` record; none by default. The
    /// arm's view gives `painleve.run` with the control law that ran
    /// (`arm_view::ArmView::of_law`), which Foxglove shows in its metadata panel.
    fn metadata(&self) -> Vec<(String, std::collections::BTreeMap<String, String>)> {
        Vec::new()
    }
}

/// The protobuf messages of a table's rows, one per signal group: the channels
/// [`RowEncoder::channels`] and, per row, [`RowEncoder::encode`]. A message
/// holds the row's time `t` (s, field 1) and then the group's columns (fields
/// 2, 3, ... in the group's order, named as in the CSV; the channel's schema,
/// [`super::schema`]), every field written, zeros included: floats as `double`
/// with their bits (NaN and infinities too), integers as `int64`, flags as
/// `bool`, text as `string`.
pub struct RowEncoder<T: McapRows> {
    channels: Vec<ChannelSpec>,
    /// The column indices of each group, in its messages' order.
    groups: Vec<Vec<usize>>,
    /// The index of column `t`.
    t: usize,
    buf: Vec<u8>,
    rows: PhantomData<fn(&T)>,
}

impl<T: McapRows> RowEncoder<T> {
    /// The encoder of `T`'s table.
    ///
    /// # Errors
    /// A message when `T` has no column `t`, or its groups name a column it
    /// lacks or leave one out (a bug of the row type, reported as an error).
    pub fn new() -> Result<Self, String> {
        let t = T::NAMES.iter().position(|n| *n == "t").ok_or_else(|| format!("table {}: no column `t`", T::TABLE))?;
        let grouped: usize = T::GROUPS.iter().map(|g| g.columns.len()).sum();
        if grouped + 1 != T::NAMES.len() {
            return Err(format!("table {}: its groups hold {grouped} columns besides t, not {}", T::TABLE, T::NAMES.len() - 1));
        }
        let mut channels = Vec::with_capacity(T::GROUPS.len());
        let mut groups = Vec::with_capacity(T::GROUPS.len());
        for g in T::GROUPS {
            let indices = g
                .columns
                .iter()
                .map(|c| T::NAMES.iter().position(|n| n == c).ok_or_else(|| format!("group {}: no column `{c}`", g.topic)))
                .collect::<Result<Vec<_>, _>>()?;
            channels.push(ChannelSpec {
                topic: g.topic.to_string(),
                schema_name: g.schema.to_string(),
                schema_encoding: "protobuf".into(),
                schema: schema_proto(T::NAMES, T::KINDS, g)?,
                message_encoding: "protobuf".into(),
            });
            groups.push(indices);
        }
        Ok(Self { channels, groups, t, buf: Vec::with_capacity(1024), rows: PhantomData })
    }

    /// The table's channels, one per group, in [`McapRows::GROUPS`]' order.
    pub fn channels(&self) -> &[ChannelSpec] {
        &self.channels
    }

    /// The time of row `i` of `columns` (`T`'s columns), s; NaN when `t` is not a float column.
    pub fn time(&self, columns: &[Column], i: usize) -> f64 {
        match &columns[self.t] {
            Column::F64(v) => v[i],
            _ => f64::NAN,
        }
    }

    /// The messages of row `i` of `columns` (`T`'s columns), one per group in
    /// order, each given to `emit` as (channel index, bytes).
    pub fn encode(&mut self, columns: &[Column], i: usize, emit: &mut dyn FnMut(usize, &[u8])) {
        for (g, indices) in self.groups.iter().enumerate() {
            let buf = &mut self.buf;
            buf.clear();
            push_field(buf, 1, &columns[self.t], i);
            for (number, &c) in (2..).zip(indices) {
                push_field(buf, number, &columns[c], i);
            }
            emit(g, buf);
        }
    }
}

/// The log time of a row at `t` (s): nanoseconds of simulated time,
/// `round(t * 1e9)`; a negative or NaN time (never written) is 0.
pub fn log_time_ns(t: f64) -> u64 {
    (t * 1e9).round() as u64
}

/// Appends value `i` of `c` as protobuf field `number` (its key and its
/// value, written even when zero or empty): `double` (fixed 64 bits), `int64`
/// and `bool` (varints), `string` (length-delimited).
fn push_field(buf: &mut Vec<u8>, number: u32, c: &Column, i: usize) {
    use prost::encoding::{bool, double, int64, string};
    match c {
        Column::F64(v) => double::encode(number, &v[i], buf),
        Column::I64(v) => int64::encode(number, &v[i], buf),
        Column::Bool(v) => bool::encode(number, &v[i], buf),
        Column::Str(v) => string::encode(number, &v[i], buf),
    }
}
