//! The command line as the Python functions' argument parser: each function's
//! arguments come as the tokens the CLI would get (`--mu=0.6`, ...), parsed by
//! `sil-host`'s own clap definitions, so the defaults, the value parsing and the
//! error messages are the CLI's; errors become `painleve.PainleveError` with the
//! CLI's message and exit code.

use clap::{CommandFactory, Parser};
use pyo3::{prelude::*, types::PyDict};
use sil_host::cli::{Cli, Command};
use sil_host::error::CliError;

pyo3::create_exception!(
    painleve,
    PainleveError,
    pyo3::exceptions::PyValueError,
    "Bad input or a failure of a painleve call, with the message `sil-host` prints for it (after `error: `) and its exit code (`exit_code`: 2 for bad input, 1 for a run that failed)."
);

/// A `PainleveError` with `message` and `exit_code`.
pub fn error(py: Python<'_>, message: String, exit_code: i32) -> PyErr {
    let err = PainleveError::new_err(message);
    // Best effort: instance attributes, read by `painleve`'s Python layer. `result`
    // is the partial result of a run that failed part way (set by `Result.check`),
    // None here: bad input computed nothing.
    let _ = err.value(py).setattr("exit_code", exit_code);
    let _ = err.value(py).setattr("result", py.None());
    err
}

/// A CLI error as a `PainleveError`: the message the CLI prints after `error: `,
/// and the CLI's exit code.
pub fn cli_error(py: Python<'_>, e: &CliError) -> PyErr {
    error(py, e.to_string(), e.exit_code())
}

/// Parses `sil-host <command> <tokens>`.
///
/// # Errors
/// `PainleveError` with clap's message (what the CLI prints, less its leading
/// `error: ` and the usage and help lines that follow the message's paragraph,
/// which name the command line's flags) and its exit code (2).
pub fn parse(py: Python<'_>, command: &str, tokens: &[String]) -> PyResult<Command> {
    let argv = ["sil-host", command].into_iter().map(String::from).chain(tokens.iter().cloned());
    match Cli::try_parse_from(argv) {
        Ok(cli) => Ok(cli.command),
        Err(e) => {
            let text = e.to_string();
            let text = text.trim_end().strip_prefix("error: ").unwrap_or(text.trim_end());
            let text = text.split("\n\n").next().unwrap_or(text).trim_end().to_string();
            Err(error(py, text, e.exit_code()))
        }
    }
}

/// Unwraps the command's arguments from a parsed command line.
macro_rules! args_of {
    ($py:expr, $command:literal, $tokens:expr, $variant:ident) => {
        match $crate::cli::parse($py, $command, $tokens)? {
            sil_host::cli::Command::$variant(args) => args,
            _ => unreachable!(concat!("`sil-host ", $command, "` parses as ", stringify!($variant))),
        }
    };
}
pub(crate) use args_of;

/// The CLI's options of `command` and their defaults: `{long flag name: [default
/// values as the CLI shows them]}` (an option without a default maps to `[]`, a
/// flag to `["false"]`). For the tests that check the Python signatures' defaults
/// against the CLI's.
///
/// # Errors
/// `PainleveError` for an unknown command.
#[pyfunction]
pub fn cli_defaults<'py>(py: Python<'py>, command: &str) -> PyResult<Bound<'py, PyDict>> {
    let cli = Cli::command();
    let sub = cli.find_subcommand(command).ok_or_else(|| error(py, format!("no command `{command}`"), 2))?;
    let out = PyDict::new(py);
    for arg in sub.get_arguments() {
        let Some(long) = arg.get_long() else { continue };
        let defaults: Vec<String> = arg.get_default_values().iter().map(|v| v.to_string_lossy().into_owned()).collect();
        out.set_item(long, defaults)?;
    }
    Ok(out)
}
