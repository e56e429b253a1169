//! The image's defmt log: QEMU's standard output (semihosting) decoded with
//! `defmt-decoder` from the image's own ELF, line by line as it arrives.

use std::{io::Read, path::Path, sync::Mutex};

use serde::Serialize;

use crate::record::RunError;

/// One decoded line of the image's defmt log.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LogLine {
    /// The line's defmt timestamp as the image formats it (`boards/stm32f405`'s
    /// `mcu::log_time`: seconds with six decimals, the control period's number
    /// times the period, `0.001000`); `None` for an image without
    /// `defmt::timestamp!`.
    pub timestamp: Option<String>,
    /// `trace`, `debug`, `info`, `warn`, `error` (or `println`).
    pub level: String,
    /// The formatted message.
    pub message: String,
}

impl LogLine {
    /// The line as `defmt.log` and the console show it: `TIMESTAMP [level]
    /// message`, or `[level] message` without a timestamp.
    pub fn display(&self) -> String {
        match &self.timestamp {
            Some(t) => format!("{t} [{}] {}", self.level, self.message),
            None => format!("[{}] {}", self.level, self.message),
        }
    }
}

/// Called for every defmt line as it arrives (on the log reader's thread).
pub type LogSink = Box<dyn Fn(&LogLine) + Send>;

/// The defmt table of the image at `image` (its ELF), to decode its log with.
///
/// # Errors
/// [`RunError::Transport`] when the image cannot be read, is not a defmt image,
/// or has no defmt table.
pub(super) fn table_of(image: &Path) -> Result<defmt_decoder::Table, RunError> {
    let elf = tables::input::read(image, tables::input::ELF_IMAGE).map_err(|e| RunError::Transport(e.to_string()))?;
    defmt_decoder::Table::parse(&elf)
        .map_err(|e| RunError::Transport(format!("{}: not a defmt image: {e}", image.display())))?
        .ok_or_else(|| RunError::Transport(format!("{}: no defmt table (is it the `pil` image?)", image.display())))
}

/// Decodes the defmt stream from QEMU's standard output until it closes.
pub(super) fn decode_defmt(
    table: &defmt_decoder::Table,
    mut out: impl Read,
    log: &Mutex<Vec<LogLine>>,
    on_log: Option<&(dyn Fn(&LogLine) + Send)>,
) -> Result<(), String> {
    let mut decoder = table.new_stream_decoder();
    let mut chunk = [0u8; 1024];
    loop {
        let n = out.read(&mut chunk).map_err(|e| e.to_string())?;
        if n == 0 {
            return Ok(());
        }
        decoder.received(&chunk[..n]);
        loop {
            match decoder.decode() {
                Ok(frame) => {
                    let line = LogLine {
                        timestamp: frame.display_timestamp().map(|t| t.to_string()),
                        level: frame.level().map_or("println", |l| l.as_str()).to_string(),
                        message: frame.display_message().to_string(),
                    };
                    if let Some(f) = on_log {
                        f(&line);
                    }
                    if let Ok(mut l) = log.lock() {
                        l.push(line);
                    }
                }
                Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                Err(defmt_decoder::DecodeError::Malformed) => {
                    return Err("the defmt stream is corrupt (an image built from other sources?)".into());
                }
            }
        }
    }
}

/// The defmt log in `bytes` (an RTT buffer's content, or QEMU's output) of the
/// image at `image`, decoded whole: what probe-rs prints for a board.
///
/// # Errors
/// [`RunError::Transport`] for an image without a defmt table, or a stream
/// that does not decode with it.
pub fn decode_log(image: &Path, bytes: &[u8]) -> Result<Vec<LogLine>, RunError> {
    let table = table_of(image)?;
    let log = Mutex::new(Vec::new());
    decode_defmt(&table, bytes, &log, None).map_err(RunError::Transport)?;
    Ok(log.into_inner().unwrap_or_default())
}

/// `; image log: <its last three lines>`, or nothing for an empty log.
pub(super) fn tail(log: &[LogLine]) -> String {
    if log.is_empty() {
        return String::new();
    }
    let last: Vec<String> = log.iter().rev().take(3).rev().map(LogLine::display).collect();
    format!("; image log: {}", last.join(" | "))
}
