//! Reading an Arrow IPC file or stream back ([`read_arrow_batch`], [`read_arrow`]).

use std::{fs::File, path::Path, sync::Arc};

use arrow_array::RecordBatch;
use arrow_ipc::reader::{FileReader, StreamReader};
use arrow_schema::{ArrowError, Schema};

use super::{arrow_err, settle, table_of};
use crate::{Table, error::Error};

/// Reads the Arrow IPC file or stream at `path` into one record batch: its
/// columns in the file's order and with the file's types, every record batch
/// appended (`arrow-select`'s `concat_batches`); a null float is NaN and a null
/// text `""` (what the CLI's files never hold, and a table without nulls
/// carries). A stream cut off (a run killed while writing, [`super::ArrowStream`])
/// gives its whole batches.
///
/// # Errors
/// [`Error::Io`] naming the file when it cannot be read, is neither an Arrow
/// IPC file (nor one cut off before its footer) nor a stream, has a column of
/// another type than Float64, Int64, Boolean or Utf8, or a null integer or flag.
pub fn read_arrow_batch(path: &Path) -> Result<RecordBatch, Error> {
    let bad = |msg: String| Error::other(path, msg);
    let mut file = File::open(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    // The file format starts with the magic `ARROW1`; the stream format (`run`,
    // `pil`) with a message.
    let mut magic = [0u8; 6];
    let is_file = std::io::Read::read_exact(&mut file, &mut magic).is_ok() && &magic == b"ARROW1";
    std::io::Seek::rewind(&mut file).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let (schema, batches): (Arc<Schema>, Box<dyn Iterator<Item = Result<RecordBatch, ArrowError>>>) = if is_file {
        let reader = FileReader::try_new_buffered(file, None).map_err(arrow_err(path))?;
        (reader.schema(), Box::new(reader))
    } else {
        let reader = StreamReader::try_new_buffered(file, None).map_err(arrow_err(path))?;
        // A stream cut off (a killed run): its whole batches, the cut one dropped.
        let mut done = false;
        (reader.schema(), Box::new(reader.take_while(move |b| !std::mem::replace(&mut done, b.is_err())).filter(Result::is_ok)))
    };
    let batches = batches.collect::<Result<Vec<_>, _>>().map_err(arrow_err(path))?;
    let batch = arrow_select::concat::concat_batches(&schema, &batches).map_err(arrow_err(path))?;
    settle(&batch, true).map_err(|(_, _, message)| bad(message))
}

/// Reads the Arrow IPC file or stream at `path` into a [`Table`] ([`read_arrow_batch`]).
///
/// # Errors
/// As [`read_arrow_batch`].
pub fn read_arrow(path: &Path) -> Result<Table, Error> {
    table_of(&read_arrow_batch(path)?).map_err(|m| Error::other(path, m))
}
