//! The experiments' settings as the Python functions' arguments: the Python layer
//! checks each keyword argument's type and turns it into a token (`--mu=0.6`,
//! ...), parsed here by the settings' own clap definitions
//! ([`experiments::settings`], the ones `sil-host` parses its flags with), so the
//! defaults, the value parsing and the ranges are one; errors become
//! `painleve.PainleveError` with the experiment's message and exit code.

use clap::{Args, FromArgMatches};
use experiments::{Error as CliError, settings::*};
use pyo3::{prelude::*, types::PyDict};

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

/// The settings' arguments as a clap command named `name`, as the command
/// line's subcommand has them (negative numbers are values).
fn command_of<T: Args>(name: &'static str) -> clap::Command {
    T::augment_args(clap::Command::new(name).no_binary_name(true).allow_negative_numbers(true))
}

/// Parses the settings `T` of experiment `command` from `tokens`.
///
/// # Errors
/// `PainleveError` with clap's message (its first paragraph, less the leading
/// `error: `; the usage and help lines that follow name command-line flags) and
/// its exit code (2).
pub fn parse<T: Args + FromArgMatches>(py: Python<'_>, command: &'static str, tokens: &[String]) -> PyResult<T> {
    let fail = |e: clap::Error| {
        let text = e.to_string();
        let text = text.trim_end().strip_prefix("error: ").unwrap_or(text.trim_end());
        let text = text.split("\n\n").next().unwrap_or(text).trim_end().to_string();
        error(py, text, e.exit_code())
    };
    let matches = command_of::<T>(command).try_get_matches_from(tokens).map_err(fail)?;
    T::from_arg_matches(&matches).map_err(fail)
}

/// The options of experiment `command` and their defaults: `{long flag name: [default
/// values as the CLI shows them]}` (an option without a default maps to `[]`, a
/// flag to `["false"]`). For the tests that check the Python signatures' defaults
/// against the CLI's.
///
/// # Errors
/// `PainleveError` for an unknown command.
#[pyfunction]
pub fn cli_defaults<'py>(py: Python<'py>, command: &str) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for arg in experiment_command(py, command)?.get_arguments() {
        let Some(long) = arg.get_long() else { continue };
        let defaults: Vec<String> = arg.get_default_values().iter().map(|v| v.to_string_lossy().into_owned()).collect();
        out.set_item(long, defaults)?;
    }
    Ok(out)
}

/// The choices of experiment `command`'s options that take one of a fixed set
/// of values: `{long flag name: [values]}` (`impact-law`: `["newton",
/// "poisson", "energetic"]`). For the tests that check the Python signatures'
/// `Literal` annotations against the settings.
///
/// # Errors
/// `PainleveError` for an unknown experiment.
#[pyfunction]
pub fn cli_choices<'py>(py: Python<'py>, command: &str) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    for arg in experiment_command(py, command)?.get_arguments() {
        let Some(long) = arg.get_long() else { continue };
        let values: Vec<String> = arg.get_possible_values().iter().filter(|v| !v.is_hide_set()).map(|v| v.get_name().to_string()).collect();
        // A flag's possible values are `true` and `false`: not a choice.
        if !values.is_empty() && arg.get_action().takes_values() {
            out.set_item(long, values)?;
        }
    }
    Ok(out)
}

/// The clap command of experiment `command`'s settings.
fn experiment_command(py: Python<'_>, command: &str) -> PyResult<clap::Command> {
    Ok(match command {
        "simulate" => command_of::<SimulateArgs>("simulate"),
        "admissible" => command_of::<AdmissibleArgs>("admissible"),
        "modes" => command_of::<ModesArgs>("modes"),
        "poincare" => command_of::<PoincareArgs>("poincare"),
        "sweep" => command_of::<SweepArgs>("sweep"),
        "zmax" => command_of::<ZmaxArgs>("zmax"),
        "run" => command_of::<RunArgs>("run"),
        "sensitivity" => command_of::<SensitivityArgs>("sensitivity"),
        _ => return Err(error(py, format!("no experiment `{command}`"), 2)),
    })
}
