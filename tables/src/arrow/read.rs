//! Reading an Arrow IPC file (or stream) back ([`read_arrow_batch`], [`read_arrow`]).

use std::{
    fs::File,
    io::{Read, Seek, SeekFrom},
    path::Path,
    sync::Arc,
};

use arrow_array::RecordBatch;
use arrow_ipc::reader::{FileReader, StreamReader};
use arrow_schema::{ArrowError, Schema};

use super::{arrow_read_err, settle, table_of};
use crate::{Table, error::Error};

/// Reads the Arrow IPC file (or stream) at `path` into one record batch: its
/// columns in the file's order and with the file's types, every record batch
/// appended (`arrow-select`'s `concat_batches`); a null float is NaN and a null
/// text `""` (what the CLI's files never hold, and a table without nulls
/// carries). A file cut off before its footer (a run killed while writing,
/// [`super::StreamedArrowFile`]) gives its whole batches: the file format is the
/// stream format after the magic and its padding ([`stream_start`]). An IPC
/// stream (what `run` wrote before issue 55) is read too.
///
/// # Errors
/// [`Error::Unreadable`] naming the file when it cannot be read, is neither an Arrow
/// IPC file (nor one cut off before its footer) nor a stream, has a column of
/// another type than Float64, Int64, Boolean or Utf8, or a null integer or flag.
pub fn read_arrow_batch(path: &Path) -> Result<RecordBatch, Error> {
    let bad = |msg: String| Error::unreadable(path, msg);
    let io = |e: std::io::Error| Error::Unreadable { path: path.to_path_buf(), source: e };
    let mut file = crate::input::open(path, crate::input::TABLE)?;
    // The file format starts with the magic `ARROW1` and two bytes of padding; the
    // stream format with a message.
    let mut magic = [0u8; 6];
    let is_file = file.read_exact(&mut magic).is_ok() && &magic == b"ARROW1";
    file.rewind().map_err(io)?;
    let whole = if is_file { FileReader::try_new_buffered(file, None).ok() } else { None };
    let (schema, batches): (Arc<Schema>, Box<dyn Iterator<Item = Result<RecordBatch, ArrowError>>>) = match whole {
        Some(reader) => (reader.schema(), Box::new(reader)),
        None => {
            // A stream, or a file cut off before its footer: the stream after its head.
            let mut file = crate::input::open(path, crate::input::TABLE)?;
            let start = if is_file { stream_start(&mut file).map_err(io)? } else { 0 };
            file.seek(SeekFrom::Start(start)).map_err(io)?;
            let reader = StreamReader::try_new_buffered(file, None).map_err(arrow_read_err(path))?;
            // Cut off (a killed run): its whole batches, the cut one dropped.
            let mut done = false;
            (reader.schema(), Box::new(reader.take_while(move |b| !std::mem::replace(&mut done, b.is_err())).filter(Result::is_ok)))
        }
    };
    let batches = batches.collect::<Result<Vec<_>, _>>().map_err(arrow_read_err(path))?;
    let batch = arrow_select::concat::concat_batches(&schema, &batches).map_err(arrow_read_err(path))?;
    settle(&batch, true).map_err(|(_, _, message)| bad(message))
}

/// Where the stream inside an IPC file `file` starts: after the magic `ARROW1`
/// and its zero padding to the writer's alignment (8 bytes in the format's
/// specification, 64 by arrow-rs's default), at the first 8 bytes that are not
/// all zero (a message starts with its continuation marker `0xFFFFFFFF`, or its
/// non-zero length). Reads the file's head; leaves the position anywhere.
fn stream_start(file: &mut File) -> std::io::Result<u64> {
    file.rewind()?;
    let mut head = Vec::with_capacity(1024);
    file.take(1024).read_to_end(&mut head)?;
    let mut at = 8;
    while at + 8 <= head.len() && head[at..at + 8].iter().all(|&b| b == 0) {
        at += 8;
    }
    Ok(at as u64)
}

/// Reads the Arrow IPC file (or stream) at `path` into a [`Table`] ([`read_arrow_batch`]).
///
/// # Errors
/// As [`read_arrow_batch`].
pub fn read_arrow(path: &Path) -> Result<Table, Error> {
    table_of(&read_arrow_batch(path)?).map_err(|m| Error::unreadable(path, m))
}
