//! `painleve.Scenario`: a closed-loop scenario (`rig::Scenario`) held in Python:
//! loaded from TOML text or a file, the embedded default, changed key by key with
//! the dotted keys of the CLI's `--set` (`rig::overrides`), validated by the rig's
//! own validation on every change, written back as TOML, read as a dict.

use pyo3::{
    exceptions::{PyKeyError, PyTypeError},
    prelude::*,
    types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple},
};
use rig::{Override, Scenario, ScenarioError};

use crate::cli::error;
use crate::convert::to_py;

/// A scenario error as `PainleveError` (exit code 2: bad input). The rig names an
/// override as `--set KEY=VALUE`; here it was `Scenario.set`.
pub fn scenario_error(py: Python<'_>, e: &ScenarioError) -> PyErr {
    error(py, e.to_string().replace("(from --set ", "(from set ").replace("--set ", ""), 2)
}

/// A closed-loop scenario: the plant (paper Table I, `mu`, `v_belt`, the initial
/// condition, the impact law), the firmware's controller and gains, the timing
/// (rate, `delta`, duration), the sensor models and the injected faults. Always
/// valid: every change is validated by the rig (`rig::Scenario::validate`).
///
/// `Scenario()` or `Scenario.default()`: the embedded default
/// (`scenarios/default.toml`); `Scenario(text)`: TOML text;
/// `Scenario(path)` or `Scenario.load(path)`: a file. `s.set("plant.mu", 0.5)` changes a key (the
/// CLI's `--set` keys), `s["plant.mu"]` reads one, `s.to_toml()`, `s.to_dict()`.
///
/// Raises `PainleveError` (exit_code 2) for invalid TOML, an unknown key or a
/// value out of range, naming the key. Source: python/src/objects/scenario.rs
/// over `rig::scenario` and `rig::overrides`.
#[pyclass(name = "Scenario", module = "painleve._painleve", eq)]
#[derive(Clone, PartialEq)]
pub struct PyScenario {
    pub inner: Scenario,
}

impl PyScenario {
    /// `s` with the keyword arguments `keywords` set as keys of its `[plant]`
    /// (`mu=0.5` is `plant.mu = 0.5`), set and validated together; `owner`
    /// (`"Plant()"`, `"Model()"`) takes the keys of `allowed` and `besides` (its
    /// other arguments, for the message).
    ///
    /// # Errors
    /// `TypeError` for a keyword not in `allowed`; `PainleveError` (exit_code 2)
    /// for a value the scenario refuses.
    pub fn with_plant_keywords(
        py: Python<'_>,
        s: Scenario,
        keywords: Option<&Bound<'_, PyDict>>,
        allowed: &[&str],
        owner: &str,
        besides: &str,
    ) -> PyResult<Scenario> {
        let Some(keywords) = keywords else { return Ok(s) };
        let keys = PyDict::new(py);
        for (k, v) in keywords.iter() {
            let key: String = k.extract()?;
            if !allowed.contains(&key.as_str()) {
                return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                    "{owner} got an unexpected keyword argument `{key}` (it takes {besides} and the keys of [plant]: {})",
                    allowed.join(", ")
                )));
            }
            keys.set_item(format!("plant.{key}"), v)?;
        }
        let sc = Self::update(Bound::new(py, Self { inner: s })?, &keys)?;
        let inner = sc.borrow().inner.clone();
        Ok(inner)
    }

    /// The scenario of a Python value: a `Scenario`, TOML text, or `None` (`default`).
    pub fn of(py: Python<'_>, value: Option<&Bound<'_, PyAny>>) -> PyResult<Scenario> {
        match value {
            None => Ok(Scenario::default_scenario()),
            Some(v) if v.is_none() => Ok(Scenario::default_scenario()),
            Some(v) => {
                if let Ok(s) = v.cast::<PyScenario>() {
                    return Ok(s.borrow().inner.clone());
                }
                // A str with a key in it is TOML text; any other str or os.PathLike a file.
                if v.is_instance_of::<PyString>() {
                    let text: String = v.extract()?;
                    if text.contains('=') || text.contains('\n') {
                        return Scenario::from_toml(&text).map_err(|e| scenario_error(py, &e));
                    }
                }
                if let Ok(path) = v.extract::<std::path::PathBuf>() {
                    return Ok(Self::load(py, path)?.inner);
                }
                Err(PyTypeError::new_err(format!(
                    "scenario: expected a painleve.Scenario, TOML text, the path of a TOML file or None, got {}",
                    v.get_type().name()?
                )))
            }
        }
    }
}

/// A Python value as a TOML value (`key` names it in errors): bool, int, float,
/// str, a list or tuple of them, a dict of them.
fn toml_of(key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    let bad = || -> PyResult<toml::Value> {
        Err(PyTypeError::new_err(format!("`{key}`: expected a bool, int, float, str, list or dict, got {}", v.get_type().name()?)))
    };
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(PyTypeError::new_err(format!("`{key}`: the integer {v} is out of TOML's range"))),
        };
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v.try_iter()?.enumerate().map(|(i, x)| toml_of(&format!("{key}[{i}]"), &x?)).collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k.extract().map_err(|_| PyTypeError::new_err(format!("`{key}`: dict keys must be str")))?;
            let inner = toml_of(&format!("{key}.{k}"), &x)?;
            t.insert(k, inner);
        }
        return Ok(toml::Value::Table(t));
    }
    // NumPy scalars and other numbers: integers through `__index__`, the rest through float.
    if let Ok(i) = v.extract::<i64>() {
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    bad()
}

/// The value at dotted key `key` of a TOML table.
fn lookup<'a>(table: &'a toml::Table, key: &str) -> Option<&'a toml::Value> {
    let mut parts = key.split('.');
    let mut v = table.get(parts.next()?)?;
    for p in parts {
        v = v.as_table()?.get(p)?;
    }
    Some(v)
}

#[pymethods]
impl PyScenario {
    /// `Scenario(source=None)`: `None` the embedded default
    /// (`scenarios/default.toml`), TOML text, or the path of a TOML file.
    #[new]
    #[pyo3(signature = (source=None))]
    fn new(py: Python<'_>, source: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        Ok(Self { inner: Self::of(py, source)? })
    }

    /// The embedded default scenario (`scenarios/default.toml`).
    #[staticmethod]
    fn default() -> Self {
        Self { inner: Scenario::default_scenario() }
    }

    /// A scenario from TOML text.
    #[staticmethod]
    fn from_toml(py: Python<'_>, text: &str) -> PyResult<Self> {
        Scenario::from_toml(text).map(|inner| Self { inner }).map_err(|e| scenario_error(py, &e))
    }

    /// A scenario from a TOML file: a regular file of at most 4 MiB
    /// (`tables::input::SCENARIO`), else `PainleveError` (exit code 2) naming
    /// the file and the bound.
    #[staticmethod]
    fn load(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        let text = tables::input::read_to_string(&path, tables::input::SCENARIO).map_err(|e| error(py, e.to_string(), 2))?;
        Self::from_toml(py, &text)
    }

    /// Sets the value at dotted key `key` (`"plant.mu"`, `"controller.pid.kp"`),
    /// validated; returns the scenario (for chaining).
    fn set<'py>(slf: Bound<'py, Self>, key: &str, value: &Bound<'py, PyAny>) -> PyResult<Bound<'py, Self>> {
        let py = slf.py();
        let toml_value = toml_of(key, value)?;
        let text = toml_value.to_string();
        let o = Override { key: key.trim().to_string(), value: toml_value, text };
        if o.key.is_empty() || o.key.split('.').any(str::is_empty) {
            return Err(error(py, format!("`{key}` is not a dotted scenario key, e.g. plant.mu"), 2));
        }
        let next = slf.borrow().inner.with_overrides(std::slice::from_ref(&o)).map_err(|e| scenario_error(py, &e))?;
        slf.borrow_mut().inner = next;
        Ok(slf)
    }

    /// Sets several dotted keys at once (`{"plant.mu": 0.5, "timing.duration_s":
    /// 2.0}`), validated together; returns the scenario (for chaining). Raises as
    /// `set` (the scenario unchanged on error).
    pub fn update<'py>(slf: Bound<'py, Self>, values: &Bound<'py, PyDict>) -> PyResult<Bound<'py, Self>> {
        let py = slf.py();
        let mut overrides = Vec::with_capacity(values.len());
        for (k, v) in values.iter() {
            let key: String = k.extract().map_err(|_| PyTypeError::new_err("Scenario.update: keys must be dotted scenario keys (str)"))?;
            let value = toml_of(&key, &v)?;
            let key = key.trim().to_string();
            if key.is_empty() || key.split('.').any(str::is_empty) {
                return Err(error(py, format!("`{key}` is not a dotted scenario key, e.g. plant.mu"), 2));
            }
            overrides.push(Override { key, text: value.to_string(), value });
        }
        rig::overrides::check_unique(&overrides).map_err(|e| scenario_error(py, &e.into()))?;
        let next = slf.borrow().inner.with_overrides(&overrides).map_err(|e| scenario_error(py, &e))?;
        slf.borrow_mut().inner = next;
        Ok(slf)
    }

    /// Checks the scenario again (it always is valid: every change is checked).
    fn validate(&self, py: Python<'_>) -> PyResult<()> {
        self.inner.validate().map_err(|e| scenario_error(py, &e))
    }

    /// The scenario as TOML text (every key written out).
    fn to_toml(&self, py: Python<'_>) -> PyResult<String> {
        toml::to_string(&self.inner).map_err(|e| error(py, format!("cannot write the scenario as TOML: {e}"), 1))
    }

    /// The scenario as a dict of its tables.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.inner)
    }

    /// The value at dotted key `key`.
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let table = self.inner.to_table().map_err(|e| scenario_error(py, &e))?;
        let v = lookup(&table, key).ok_or_else(|| PyKeyError::new_err(format!("no scenario key `{key}`")))?;
        to_py(py, v)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.get(py, key)
    }

    /// A copy.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __copy__(&self) -> Self {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.clone()
    }

    /// The scenario's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// Control periods in the run (`timing.duration_s` times `timing.rate_hz`).
    #[getter]
    fn periods(&self) -> u64 {
        self.inner.timing.periods()
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "<Scenario {:?}: {} from x0{}, mu = {}, v_belt = {} m/s, {} s at {} Hz>",
            s.name,
            s.controller.kind.name(),
            s.plant.x0.letter(),
            s.plant.mu,
            s.plant.v_belt,
            s.timing.duration_s,
            s.timing.rate_hz
        )
    }

    fn __str__(&self, py: Python<'_>) -> PyResult<String> {
        self.to_toml(py)
    }
}
