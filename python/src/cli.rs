//! The experiments' settings from the Python functions' keyword arguments:
//! the Python layer checks each argument's type and passes those given (not
//! `None`, not equal to the default) as a dict; [`settings`] lays them over the
//! settings' defaults, which are clap's ([`experiments::settings`], the ones
//! `sil-host` parses its flags with: one definition of the defaults, choices and
//! conflicts), and builds the typed settings with serde. No command-line text is
//! made. Errors become `painleve.PainleveError` with the experiment's message and
//! exit code.
//!
//! What this path checks that serde alone would not: an unknown keyword, two
//! keywords the settings declare in conflict (`x0` and `x0_deg`), a non-finite
//! number where the settings take a number; what clap checks through `requires`
//! (`--live-rate` needs `--live`, ...) belongs to options the Python functions do
//! not take.

use clap::{Args, FromArgMatches};
use experiments::{Error as CliError, settings::*};
use pyo3::{
    prelude::*,
    types::{PyBool, PyDict, PyFloat, PyInt, PyString},
};
use serde::{Serialize, de::DeserializeOwned};
use serde_json::Value;

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

/// The defaults of settings `T`: clap's, as the command line has them with no flag.
fn defaults<T: Args + FromArgMatches>(py: Python<'_>, command: &'static str) -> PyResult<T> {
    let no_flags: [&str; 0] = [];
    let matches = command_of::<T>(command).try_get_matches_from(no_flags).map_err(|e| error(py, e.to_string(), 2))?;
    T::from_arg_matches(&matches).map_err(|e| error(py, e.to_string(), 2))
}

/// A keyword argument's value as a JSON value: `None`, `bool`, `int`, a finite
/// `float` (exactly: no text in between), `str`, an `os.PathLike` (its path), or
/// a sequence of them (`tuple`, `list`, a NumPy array).
///
/// # Errors
/// `PainleveError` (exit 2) naming `name`: a non-finite number, or a value of no
/// such type.
fn json_of(py: Python<'_>, name: &str, v: &Bound<'_, PyAny>) -> PyResult<Value> {
    let bad = |why: String| error(py, format!("{name}: {why}"), 2);
    if v.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(Value::String(s.to_cow()?.into_owned()));
    }
    if v.is_instance_of::<PyInt>() || (!v.is_instance_of::<PyFloat>() && v.hasattr("__index__")?) {
        if let Ok(i) = v.extract::<i64>() {
            return Ok(i.into());
        }
        return v.extract::<u64>().map(Value::from).map_err(|_| bad(format!("{v} is out of the 64-bit range")));
    }
    if let Ok(x) = v.extract::<f64>() {
        return serde_json::Number::from_f64(x).map(Value::Number).ok_or_else(|| bad(format!("expected a finite number, got {x}")));
    }
    if let Ok(path) = py.import("os")?.call_method1("fspath", (v,)) {
        return json_of(py, name, &path);
    }
    if let Ok(items) = v.try_iter() {
        return items.map(|x| json_of(py, name, &x?)).collect::<PyResult<Vec<_>>>().map(Value::Array);
    }
    Err(bad(format!("cannot take a {}", v.get_type().name()?)))
}

/// Builds the settings `T` of experiment `command` from the keyword arguments
/// `given` (`{name: value}`, names as the settings' fields: `v_belt`,
/// `impact_law`), laid over `T`'s defaults. A list setting (`e_n`, `ics`,
/// `impact_law` of a sweep) takes one value as a list of one, and a string
/// split at the setting's delimiter (`"a,d"`), as the command line does.
///
/// # Errors
/// `PainleveError` (exit 2): an unknown name, two names in conflict (`the
/// argument x0 cannot be used with x0_deg`, clap's words), a value serde cannot
/// read as the setting's type (naming it), or a value [`json_of`] refuses.
pub fn settings<T>(py: Python<'_>, command: &'static str, given: &Bound<'_, PyDict>) -> PyResult<T>
where
    T: Args + FromArgMatches + Serialize + DeserializeOwned,
{
    let cmd = command_of::<T>(command);
    let Value::Object(mut document) = serde_json::to_value(defaults::<T>(py, command)?).map_err(|e| error(py, e.to_string(), 2))? else {
        return Err(error(py, format!("{command}: its settings are not a table"), 2));
    };
    let base = document.clone();
    let mut named: Vec<String> = Vec::new();
    for (key, v) in given.iter() {
        let key: String = key.extract()?;
        let Some(arg) = cmd.get_arguments().find(|a| a.get_id().as_str() == key) else {
            return Err(error(py, format!("{command}: no parameter `{key}`"), 2));
        };
        // clap declares a conflict on one of the two arguments: both directions.
        let conflict = |n: &String| {
            let other = cmd.get_arguments().find(|a| a.get_id().as_str() == n.as_str());
            cmd.get_arg_conflicts_with(arg).iter().any(|c| c.get_id().as_str() == n.as_str())
                || other.is_some_and(|o| cmd.get_arg_conflicts_with(o).iter().any(|c| c.get_id() == arg.get_id()))
        };
        if let Some(earlier) = named.iter().find(|n| conflict(n)) {
            return Err(error(py, format!("the argument {earlier} cannot be used with {key}"), 2));
        }
        let mut value = json_of(py, &key, &v)?;
        if matches!(arg.get_action(), clap::ArgAction::Append) {
            value = match (value, arg.get_value_delimiter()) {
                (Value::String(s), Some(d)) => Value::Array(s.split(d).map(|x| Value::String(x.to_string())).collect()),
                (Value::Array(a), _) => Value::Array(a),
                (one, _) => Value::Array(vec![one]),
            };
        }
        document.insert(key.clone(), value);
        named.push(key);
    }
    serde_json::from_value::<T>(Value::Object(document.clone())).map_err(|e| {
        // Serde's message names no field under the flattened groups: the first
        // given name that alone fails is the one named.
        let culprit = named.iter().find(|k| {
            let mut one = base.clone();
            if let Some(v) = document.get(k.as_str()) {
                one.insert((*k).clone(), v.clone());
            }
            serde_json::from_value::<T>(Value::Object(one)).is_err()
        });
        // In clap's words, as the command line says it (`invalid value 'x' for
        // '--theta1-dot <MIN,MAX>': ...`, the flag in the call's terms).
        match (culprit, culprit.and_then(|k| document.get(k.as_str()))) {
            (Some(k), Some(Value::String(s))) => error(py, format!("invalid value '{s}' for {k}: {e}"), 2),
            (Some(k), Some(v)) => error(py, format!("invalid value {v} for {k}: {e}"), 2),
            _ => error(py, e.to_string(), 2),
        }
    })
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
