//! The error of the tables: a file that cannot be written or read. The front ends
//! convert it into their own error (`experiments::Error`, with the same message).

use std::path::{Path, PathBuf};

/// Why a table file cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Writing or reading the file `path` failed: an OS error, or a file that is
    /// not the table it should be (Arrow, MCAP), or a row type whose declaration
    /// is inconsistent (an MCAP group naming a column the table lacks).
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error, or what is wrong with the file.
        source: std::io::Error,
    },
}

impl Error {
    /// An [`Error::Io`] on `path` that is not an OS error: `message` says what is wrong.
    pub fn other(path: &Path, message: impl Into<String>) -> Self {
        Self::Io { path: path.to_path_buf(), source: std::io::Error::other(message.into()) }
    }
}

/// Maps an I/O error on `path` into an [`Error::Io`].
pub fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io { path: path.to_path_buf(), source }
}
