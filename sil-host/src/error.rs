//! The command line's error: the experiments' ([`experiments::Error`], which
//! wraps [`analyses::AnalysisError`]), with its exit codes.

pub use experiments::error::{Error as CliError, io_err};
