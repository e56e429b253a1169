//! The error of the tables: a file that cannot be written or read. The front ends
//! convert it into their own error (`experiments::Error`, with the same message).

use std::path::{Path, PathBuf};

/// Why a table file cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Writing the file `path` failed: an OS error, or a row type whose
    /// declaration is inconsistent (an MCAP group naming a column the table lacks).
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error, or what is wrong.
        source: std::io::Error,
    },
    /// Reading the Arrow or MCAP file `path` failed (`read_arrow`, `read_mcap`):
    /// an OS error, or a file that is not the table it should be.
    #[error("cannot read {path}: {source}")]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The OS error, or what is wrong with the file.
        source: std::io::Error,
    },
    /// A CSV table cannot be read ([`crate::read`]): the file, the line where it
    /// goes wrong when known (1-based; else it is in `message` as arrow-csv words
    /// it, or the file as a whole is wrong), and what is wrong.
    #[error("cannot read {}: {}{message}", path.display(), line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Read {
        /// The file.
        path: PathBuf,
        /// The line where it goes wrong (1-based), when this crate found it.
        line: Option<u64>,
        /// What is wrong.
        message: String,
    },
    /// An input file that is not a regular file within its bound
    /// ([`crate::input`]: a FIFO, a device, a directory, a file too large).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
}

impl Error {
    /// An [`Error::Io`] on `path` that is not an OS error: `message` says what is wrong.
    pub fn other(path: &Path, message: impl Into<String>) -> Self {
        Self::Io { path: path.to_path_buf(), source: std::io::Error::other(message.into()) }
    }

    /// An [`Error::Unreadable`] on `path` that is not an OS error: `message`
    /// says what is wrong with the file.
    pub fn unreadable(path: &Path, message: impl Into<String>) -> Self {
        Self::Unreadable { path: path.to_path_buf(), source: std::io::Error::other(message.into()) }
    }
}

/// Maps an I/O error on `path` into an [`Error::Io`].
pub fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io { path: path.to_path_buf(), source }
}
