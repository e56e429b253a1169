//! `painleve._painleve`: the compiled part of the Python package `painleve`
//! (python/painleve, the pure-Python layer users import). It reproduces ECC 2019's
//! "Control of Painlevé Paradox in a Robotic System" through this workspace's
//! libraries: the experiments (`experiments`: their settings, checks, loops,
//! summaries and tables, the ones the command line `sil-host` uses too) over the
//! plant (`plant`), the SIL rig (`rig`) and the analyses (`analyses`).
//!
//! Each function takes the keyword arguments given (a dict `{"mu": 0.6, ...}`,
//! those the Python layer found not `None` nor equal to their defaults; laid
//! over the settings' defaults by `cli::settings`) and an optional progress object, and
//! returns a dict (`convert::Outcome`) the Python layer wraps in
//! `painleve.Result`. See docs/python.md.

mod cli;
mod commands;
mod convert;
mod objects;
mod read;
mod recording;
mod replay;
mod work;

use pyo3::prelude::*;

/// The embedded default scenario (`scenarios/default.toml`'s text, as `sil-host`
/// embeds it).
#[pyfunction]
fn default_scenario_toml() -> &'static str {
    rig::scenario::DEFAULT_TOML
}

/// A TOML document as JSON text (for `painleve.default_scenario` and scenario
/// dicts on Python 3.9 and 3.10, which have no `tomllib`).
///
/// # Errors
/// `PainleveError` (exit code 2) for text that is not TOML.
#[pyfunction]
fn toml_to_json(py: Python<'_>, text: &str) -> PyResult<String> {
    let table: toml::Table = toml::from_str(text).map_err(|e| cli::error(py, format!("invalid scenario: {e}"), 2))?;
    serde_json::to_string(&table).map_err(|e| cli::error(py, format!("invalid scenario: {e}"), 2))
}

/// A JSON object (a scenario given as a dict) as TOML text, for `--scenario`.
///
/// # Errors
/// `PainleveError` (exit code 2) when it has no TOML form (`None` values, a
/// top level that is not a table, mixed arrays TOML cannot hold).
#[pyfunction]
fn json_to_toml(py: Python<'_>, text: &str) -> PyResult<String> {
    let bad = |m: String| cli::error(py, format!("invalid scenario: {m}"), 2);
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    match toml_of(&value, "").map_err(bad)? {
        toml::Value::Table(table) => toml::to_string(&table).map_err(|e| bad(e.to_string())),
        _ => Err(bad("a scenario must be a table (a dict)".into())),
    }
}

/// A JSON value as a TOML value (a JSON integer is a TOML integer, any other
/// number a float); `at` is its dotted key, for the error.
fn toml_of(v: &serde_json::Value, at: &str) -> Result<toml::Value, String> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => return Err(format!("`{at}` is None, which TOML cannot hold")),
        J::Bool(b) => toml::Value::Boolean(*b),
        J::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => toml::Value::Integer(i),
            (None, Some(x)) => toml::Value::Float(x),
            (None, None) => return Err(format!("`{at}`: {n} is not a number TOML can hold")),
        },
        J::String(s) => toml::Value::String(s.clone()),
        J::Array(a) => toml::Value::Array(a.iter().enumerate().map(|(i, x)| toml_of(x, &format!("{at}[{i}]"))).collect::<Result<_, _>>()?),
        J::Object(o) => {
            let mut t = toml::Table::new();
            for (k, x) in o {
                let key = if at.is_empty() { k.clone() } else { format!("{at}.{k}") };
                t.insert(k.clone(), toml_of(x, &key)?);
            }
            toml::Value::Table(t)
        }
    })
}

#[pymodule]
fn _painleve(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("PainleveError", m.py().get_type::<cli::PainleveError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<recording::Recording>()?;
    m.add_function(wrap_pyfunction!(recording::write_file, m)?)?;
    m.add_function(wrap_pyfunction!(recording::recording_of_run, m)?)?;
    m.add_function(wrap_pyfunction!(commands::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(commands::admissible, m)?)?;
    m.add_function(wrap_pyfunction!(commands::modes, m)?)?;
    m.add_function(wrap_pyfunction!(commands::poincare, m)?)?;
    m.add_function(wrap_pyfunction!(commands::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(commands::zmax, m)?)?;
    m.add_function(wrap_pyfunction!(commands::run, m)?)?;
    m.add_function(wrap_pyfunction!(commands::sensitivity, m)?)?;
    m.add_function(wrap_pyfunction!(replay::replay, m)?)?;
    m.add_function(wrap_pyfunction!(read::read_arrow, m)?)?;
    m.add_function(wrap_pyfunction!(read::read_csv, m)?)?;
    m.add_function(wrap_pyfunction!(read::read_mcap, m)?)?;
    m.add_function(wrap_pyfunction!(read::declared_tables, m)?)?;
    m.add_function(wrap_pyfunction!(read::read_text, m)?)?;
    m.add_function(wrap_pyfunction!(cli::cli_defaults, m)?)?;
    m.add_function(wrap_pyfunction!(cli::cli_choices, m)?)?;
    m.add_function(wrap_pyfunction!(default_scenario_toml, m)?)?;
    m.add_function(wrap_pyfunction!(toml_to_json, m)?)?;
    m.add_function(wrap_pyfunction!(json_to_toml, m)?)?;
    objects::register(m)?;
    Ok(())
}
