//! The error of drawing a figure or reading what it is drawn from.

use std::path::PathBuf;

/// An error that ends a figure: the file, and what failed.
///
/// The fronts' error takes it as its own (`experiments::Error`: `Io`, `Plot`,
/// and bad input, exit 2), with the same message.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Writing or reading a file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// Drawing a figure failed (plotters, the PDF conversion, the GIF encoder).
    #[error("cannot draw {path}: {message}")]
    Plot {
        /// The figure file.
        path: PathBuf,
        /// What the drawing library reported.
        message: String,
    },
    /// What the figure is drawn from is not what it needs (a table without a
    /// column, an unreadable row, an animation's frame rate out of range): the
    /// message names it.
    #[error("invalid input: {0}")]
    BadInput(String),
}

impl Error {
    /// [`Error::BadInput`] with `message`.
    pub fn bad_input(message: impl Into<String>) -> Self {
        Self::BadInput(message.into())
    }
}
