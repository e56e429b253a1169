//! The objects a researcher holds and steps (issue 42, item 3): `Scenario`,
//! `Plant`, `Firmware`, the arm's `Model` (issue 55) and the closed loop with a Python controller
//! (`run_controller`). docs/python.md, "Objects".

mod controller_loop;
mod firmware;
mod model;
mod plant;
mod scenario;
mod sensed;

use pyo3::{exceptions::PyValueError, prelude::*};

/// The argument `name` as `N` numbers: a sequence of `N` numbers or an array of
/// shape `(N,)` (issue 69: a shape error named no argument).
///
/// # Errors
/// `ValueError` naming the argument, what it takes and what it got (`theta:
/// expected 2 numbers (a sequence, or an array of shape (2,)), got an array of
/// shape (2, 2)`); `TypeError` naming it when an element is not a number.
pub(crate) fn numbers<const N: usize>(name: &str, v: &Bound<'_, PyAny>) -> PyResult<[f64; N]> {
    let bad =
        |got: String| PyValueError::new_err(format!("{name}: expected {N} numbers (a sequence, or an array of shape ({N},)), got {got}"));
    if let Ok(shape) = v.getattr("shape").and_then(|s| s.extract::<Vec<usize>>())
        && shape.as_slice() != [N]
    {
        let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
        let shape = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
        return Err(bad(format!("an array of shape {shape}")));
    }
    if v.is_instance_of::<pyo3::types::PyString>() || !v.hasattr("__len__")? {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{name}: expected {N} numbers (a sequence, or an array of shape ({N},)), got {}",
            v.get_type().name()?
        )));
    }
    let n = v.len()?;
    if n != N {
        return Err(bad(format!("a sequence of {n}")));
    }
    let items: Vec<f64> = v.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!("{name}: expected {N} numbers, got an element that is not a number"))
    })?;
    Ok(items.try_into().unwrap_or([f64::NAN; N]))
}

/// Adds the classes and functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scenario::PyScenario>()?;
    m.add_class::<model::PyModel>()?;
    m.add_class::<plant::PyPlant>()?;
    m.add_class::<plant::PyStep>()?;
    m.add_class::<sensed::PySensed>()?;
    m.add_class::<firmware::PyFirmware>()?;
    m.add_class::<firmware::PyCommand>()?;
    m.add_function(wrap_pyfunction!(controller_loop::run_controller, m)?)?;
    Ok(())
}
