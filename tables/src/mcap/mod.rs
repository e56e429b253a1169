//! The long tables as an MCAP file (`--format mcap`: `trace.mcap`), the bag
//! format of ROS 2 and Foxglove's own, for robotics tools: Foxglove (File > Open
//! local file) plots its channels without a plugin.
//!
//! One file holds every table of a command (`simulate`: `trace` and `events`;
//! `run` and `pil`: `trace`). Each table's columns are split into signal groups
//! ([`McapRows::GROUPS`]), one channel per group (`/state`, `/contact`,
//! `/torques`, `/firmware`, `/events`); a row is one message on each of its
//! table's channels. A message is protobuf (message encoding `protobuf`): the
//! row's time `t` (s) as field 1, then the group's columns as fields 2, 3, ...
//! by the CSV's names; each channel's schema is a `FileDescriptorSet` (schema
//! encoding `protobuf`, module `schema`: the fields' types and, in their comments,
//! units). Log and publish times are the row's `t` in nanoseconds of simulated
//! time (`round(t * 1e9)`), the sequence number the row's index in its table
//! (from 0). Floats are `double` fields with their bits (NaN and infinities
//! too), integers `int64`, flags `bool`, text `string`; every field is written,
//! zeros included.
//!
//! A table may carry a view ([`McapView`]): channels drawn from its rows
//! besides its own, in any schema, with each row's log time, in chunks of
//! their own after the chunk of the rows they are drawn from (a reader of the
//! tables skips them by the chunk index) (`arm-view`: the arm's frames, 3D scene and log in
//! Foxglove's own schemas). [`RowEncoder`] and [`ChannelSpec`] give the
//! channels and bytes apart from the file, for a live stream of the same.
//!
//! A metadata record per table (`painleve.table.<name>`: `columns`, `kinds`,
//! `topics`) gives its columns in the CSV's order, so a reader
//! ([`read_mcap`], `painleve.load`) puts the table back together.
//!
//! Writing is the `mcap` crate's: chunks compressed with zstd (level 1, single-threaded,
//! so the same rows give the same bytes), closed when the tables' messages reach a size
//! ([`McapFile::new`] with a chunk size: `simulate`) or every [`STREAM_CHUNK_ROWS`] rows
//! ([`McapStream`]: `run` and `pil`, flushed to the operating system at once);
//! a run killed outright leaves its whole chunks, which a linear reader reads
//! (the summary and footer written by [`McapFile::finish`] are missing).
//!
//! The declarations ([`McapGroup`], [`McapRows`]) are always here; the writer
//! ([`McapFile`], [`McapStream`]) comes with the feature `mcap`, the reader
//! ([`read_mcap`]) with `read`.

use crate::ColumnRows;

#[cfg(feature = "mcap")]
mod channel;
#[cfg(feature = "mcap")]
mod pair;
#[cfg(feature = "read")]
mod read;
#[cfg(feature = "mcap")]
mod schema;
#[cfg(all(test, feature = "read"))]
mod tests;
#[cfg(feature = "mcap")]
mod write;

#[cfg(feature = "mcap")]
pub use channel::{ChannelSpec, McapView, RowEncoder, log_time_ns};
#[cfg(feature = "mcap")]
pub use pair::{McapPair, McapPairStream, PairViews};
#[cfg(feature = "read")]
pub use read::read_mcap;
#[cfg(feature = "mcap")]
pub use write::{McapFile, McapStream, McapTable};

/// Rows per chunk of an [`McapStream`] (`run`, `pil`): 100 control periods
/// (0.1 s of simulated time at 1 kHz), at most what a run killed outright loses.
/// A count of rows, not of wall time, so the same run gives the same bytes over
/// any link.
pub const STREAM_CHUNK_ROWS: usize = 100;

/// The target size of an uncompressed chunk of `simulate`'s file, bytes (1 MiB).
pub const FILE_CHUNK_BYTES: u64 = 1 << 20;

/// One signal group of a table: a channel of the MCAP file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct McapGroup {
    /// The channel's topic (`/state`).
    pub topic: &'static str,
    /// The schema's name (`painleve.State`).
    pub schema: &'static str,
    /// The table's columns in the group's messages, after `t` (CSV names).
    pub columns: &'static [&'static str],
}

/// A row type written as MCAP messages: its table's name and its columns'
/// signal groups. Every column but `t` is in exactly one group, `t` in none
/// (each message starts with it); tested for the tables of the CLI.
pub trait McapRows: ColumnRows {
    /// The table's name (`trace`, `events`): metadata record `painleve.table.<TABLE>`.
    const TABLE: &'static str;
    /// The signal groups, one channel each, in the order of their messages.
    const GROUPS: &'static [McapGroup];
}
