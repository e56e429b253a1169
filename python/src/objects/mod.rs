//! The objects a researcher holds and steps (issue 42, item 3): `Scenario`,
//! `Plant`, `Firmware`, the arm's `Model` (issue 55) and the closed loop with a Python controller
//! (`run_controller`). docs/python.md, "Objects".

mod controller_loop;
mod firmware;
mod model;
mod plant;
mod scenario;
mod sensed;

use pyo3::prelude::*;

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
