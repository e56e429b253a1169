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
    /// Reading the Arrow or MCAP file `path` failed ([`crate::arrow::read_arrow`],
    /// [`crate::mcap::read_mcap`]): an OS error, or a file that is not the table
    /// it should be.
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

#[cfg(all(test, feature = "files"))]
mod tests {
    /// Issue 66: a file being read that cannot be read says "cannot read", never
    /// "cannot write": missing, or not the table it should be, for both readers.
    #[test]
    fn a_file_that_cannot_be_read_says_so() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("none.mcap");
        let text = dir.path().join("trace.arrow");
        std::fs::write(&text, "t,theta1\n0,1\n").unwrap();
        let errors = [
            crate::mcap::read_mcap(&missing).unwrap_err(),
            crate::mcap::read_mcap(&text).unwrap_err(),
            crate::arrow::read_arrow(&missing).unwrap_err(),
            crate::arrow::read_arrow(&text).unwrap_err(),
            crate::arrow::read_arrow_batch(&text).unwrap_err(),
        ];
        for e in errors {
            let message = e.to_string();
            assert!(message.starts_with("cannot read ") && !message.contains("cannot write"), "{message}");
            assert!(message.contains("none.mcap") || message.contains("trace.arrow"), "names the file: {message}");
        }
    }
}
