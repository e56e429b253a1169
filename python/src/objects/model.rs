//! `painleve.Model`: the arm's model at one parameter set (paper Table I, `mu`,
//! `v_belt`), queried at any state: forward and inverse kinematics, `J`,
//! `J_dot q_dot`, `M`, `Q`, `p`, `b`, the Painlevé indicator and the contact
//! mode, as pydrake's `CalcJacobian...`/`CalcMassMatrix` or MuJoCo's
//! `mj_jac`/`mj_fullM` give them. Every value is `shared::model`'s and
//! `shared::kinematics`' (the ones the plant and the firmware use), in `f64`.

use nalgebra::{Matrix2, Vector2};
use numpy::{PyArray1, PyArray2};
use pyo3::{exceptions::PyValueError, prelude::*, types::PyDict};
use shared::{
    contact::{self, ContactMode},
    kinematics::{self, ElbowBranch},
    model::Arm,
    params::Params,
    slip::SlipDirection,
};

use super::scenario::PyScenario;
use crate::cli::error;

/// The `[plant]` keys of the model's parameters a `Model` takes as keywords.
const MODEL_KEYS: [&str; 9] = ["mu", "v_belt", "m", "l", "sigma", "k", "h", "alpha0", "g"];

/// The arm's model (paper eqs. 1 to 7) at one parameter set: the two-link arm of
/// paper Table I, its tip on the belt at height `-h` moving at `v_belt`, with
/// Coulomb friction `mu`.
///
/// Built from `scenario`'s `[plant]` (a `Scenario` or TOML text; `None`: the
/// default scenario's, paper Table I with `mu = 0.6`, `v_belt = -0.4` m/s) with
/// any of `mu`, `v_belt`, `m`, `l`, `sigma`, `k`, `h`, `alpha0`, `g` as a
/// keyword. States are `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s),
/// configurations `[theta1, theta2]` (rad), motor torques `[u1, u2]` (N m, the
/// base joint's and the elbow's). Every method returns NumPy arrays (`float64`)
/// or floats.
///
/// Raises `PainleveError` (exit_code 2) for parameters out of range
/// (`shared::Params::validate`; `alpha0` is in radians, within [-pi, pi]: Table
/// I's 13.72 degrees is `alpha0=0.2395`),
/// `TypeError` for an unknown keyword; each method raises `ValueError` naming
/// the argument and the element for a NaN or infinite angle, rate, torque or
/// position (`theta[0] = nan`), as the plant refuses such a state (issue 66:
/// they gave NaN, `False` or `"indeterminate"`). Source: python/src/objects/model.rs over
/// `shared::model::Arm` and `shared::kinematics`.
#[pyclass(name = "Model", module = "painleve._painleve", frozen)]
pub struct PyModel {
    arm: Arm<f64>,
}

/// `values`, the argument `name` in `unit`, when every element is finite.
///
/// # Errors
/// `ValueError` naming the argument and its first element that is NaN or
/// infinite, as Python writes it: `theta[1] = nan: expected finite numbers (rad)`.
fn finite<const N: usize>(name: &str, values: [f64; N], unit: &str) -> PyResult<[f64; N]> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(values),
        Some(i) => Err(PyValueError::new_err(format!("{name}[{i}] = {}: expected {N} finite numbers ({unit})", py_float(values[i])))),
    }
}

/// `v` as Python writes a float (`nan`, `inf`, `-inf`, `0.5`).
fn py_float(v: f64) -> String {
    match v {
        v if v.is_nan() => "nan".into(),
        v if v.is_infinite() => if v > 0.0 { "inf" } else { "-inf" }.into(),
        v => format!("{v:?}"),
    }
}

/// A configuration `theta` (rad) as a vector, checked ([`finite`]).
fn q_of(theta: [f64; 2]) -> PyResult<Vector2<f64>> {
    let theta = finite("theta", theta, "rad")?;
    Ok(Vector2::new(theta[0], theta[1]))
}

/// `[theta1, theta2]` and `[theta1_dot, theta2_dot]` of a state `[theta1,
/// theta1_dot, theta2, theta2_dot]` (rad, rad/s), checked ([`finite`]).
fn split(state: [f64; 4]) -> PyResult<(Vector2<f64>, Vector2<f64>)> {
    let state = finite("state", state, "rad, rad/s")?;
    Ok((Vector2::new(state[0], state[2]), Vector2::new(state[1], state[3])))
}

/// The generalised torque of motor torques `torques` (N m), checked ([`finite`]).
fn generalised(torques: [f64; 2]) -> PyResult<Vector2<f64>> {
    let torques = finite("torques", torques, "N m")?;
    Ok(Arm::generalised_torque(&Vector2::new(torques[0], torques[1])))
}

fn vec_py(py: Python<'_>, v: Vector2<f64>) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_vec(py, vec![v[0], v[1]])
}

fn mat_py(py: Python<'_>, m: Matrix2<f64>) -> PyResult<Bound<'_, PyArray2<f64>>> {
    PyArray2::from_vec2(py, &[vec![m[(0, 0)], m[(0, 1)]], vec![m[(1, 0)], m[(1, 1)]]]).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The slip direction named `direction` (`"positive"`: `z_r_dot > 0`, `"negative"`), or of `z_r_dot`'s sign.
fn direction(direction: &str) -> PyResult<SlipDirection> {
    match direction {
        "positive" | "+" => Ok(SlipDirection::Positive),
        "negative" | "-" => Ok(SlipDirection::Negative),
        other => Err(PyValueError::new_err(format!("direction `{other}`: \"positive\" (z_r_dot > 0) or \"negative\" (z_r_dot < 0)"))),
    }
}

#[pymethods]
impl PyModel {
    #[new]
    #[pyo3(signature = (scenario=None, **params))]
    fn new(py: Python<'_>, scenario: Option<&Bound<'_, PyAny>>, params: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let s = PyScenario::with_plant_keywords(py, PyScenario::of(py, scenario)?, params, &MODEL_KEYS, "Model()", "scenario")?;
        let params: Params<f64> = s.plant.params();
        params.validate().map_err(|e| error(py, e.to_string(), 2))?;
        Ok(Self { arm: Arm::new(params) })
    }

    /// The parameters as a dict (SI, radians): `m`, `l`, `sigma`, `k`, `h`,
    /// `alpha0`, `g`, `mu`, `v_belt` (paper Table I).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.arm.params;
        let d = PyDict::new(py);
        for (k, v) in [
            ("m", p.m),
            ("l", p.l),
            ("sigma", p.sigma),
            ("k", p.k),
            ("h", p.h),
            ("alpha0", p.alpha0),
            ("g", p.g),
            ("mu", p.mu),
            ("v_belt", p.v_belt),
        ] {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    /// Forward kinematics: the tip `[z_t, z_n]` (m, shape `(2,)`) at configuration
    /// `theta = [theta1, theta2]` (rad): `z_t = l (cos theta1 + cos theta2)`,
    /// `z_n = l (sin theta1 + sin theta2)` (docs/model.md; the belt is at `z_n = -h`).
    fn tip<'py>(&self, py: Python<'py>, theta: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let theta = super::numbers::<2>("theta", theta)?;
        Ok(vec_py(py, kinematics::tip_position(self.arm.params.l, &q_of(theta)?)))
    }

    /// Inverse kinematics: `[theta1, theta2]` (rad, shape `(2,)`) putting the tip at
    /// `z = [z_t, z_n]` (m) on elbow branch `branch` (`"down"`: `theta2 < theta1`,
    /// as the paper's `x0d`; `"up"`, as `x0u`).
    ///
    /// Raises `ValueError` for a point out of reach (farther than `2 l` or at the
    /// base), a non-finite one, or an unknown branch.
    #[pyo3(signature = (z, branch="down"))]
    fn inverse_kinematics<'py>(&self, py: Python<'py>, z: &Bound<'_, PyAny>, branch: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let z = super::numbers::<2>("z", z)?;
        let branch = match branch {
            "down" => ElbowBranch::Down,
            "up" => ElbowBranch::Up,
            other => return Err(PyValueError::new_err(format!("branch `{other}`: \"down\" (theta2 < theta1) or \"up\""))),
        };
        let z = finite("z", z, "m")?;
        let q = kinematics::inverse_kinematics(self.arm.params.l, &Vector2::new(z[0], z[1]), branch)
            .map_err(|e| PyValueError::new_err(format!("z = ({}, {}) m: {e}", z[0], z[1])))?;
        Ok(vec_py(py, q))
    }

    /// The Jacobian `J = d[z_t, z_n]/d[theta1, theta2]` (m/rad, shape `(2, 2)`)
    /// at configuration `theta` (paper eq. 2).
    fn jacobian<'py>(&self, py: Python<'py>, theta: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let theta = super::numbers::<2>("theta", theta)?;
        mat_py(py, kinematics::jacobian(self.arm.params.l, &q_of(theta)?))
    }

    /// `J_dot q_dot` (m/s^2, shape `(2,)`) at `state`: the tip's acceleration with
    /// no joint acceleration (paper eq. 2's `s`).
    fn jdot_qdot<'py>(&self, py: Python<'py>, state: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let state = super::numbers::<4>("state", state)?;
        let (q, qd) = split(state)?;
        Ok(vec_py(py, kinematics::jdot_qdot(self.arm.params.l, &q, &qd)))
    }

    /// The mass matrix `M(theta)` (kg m^2, shape `(2, 2)`), paper eq. 1.
    fn mass_matrix<'py>(&self, py: Python<'py>, theta: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let theta = super::numbers::<2>("theta", theta)?;
        mat_py(py, self.arm.mass_matrix(&q_of(theta)?))
    }

    /// `Q = J M^-1 J^T` (1/kg, shape `(2, 2)`, symmetric positive definite): the
    /// tip's acceleration per newton of tip force (paper eq. 3).
    fn q_matrix<'py>(&self, py: Python<'py>, theta: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let theta = super::numbers::<2>("theta", theta)?;
        mat_py(py, self.arm.q_matrix(&q_of(theta)?))
    }

    /// The generalised forces of the free arm `w + c` (N m, shape `(2,)`) at
    /// `state`: gravity, the spring and damping (`w`) and the velocity terms (`c`)
    /// of paper eq. 1, `M q_ddot = -(w + c) + J^T f + u`.
    fn bias<'py>(&self, py: Python<'py>, state: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let state = super::numbers::<4>("state", state)?;
        let (q, qd) = split(state)?;
        Ok(vec_py(py, self.arm.w(&q, &qd) + self.arm.c(&q, &qd)))
    }

    /// The generalised torque `u = [u1 - u2, u2]` (N m, shape `(2,)`) of the motor
    /// torques `torques = [u1, u2]` (paper eq. 1).
    fn generalised_torque<'py>(&self, py: Python<'py>, torques: &Bound<'_, PyAny>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let torques = super::numbers::<2>("torques", torques)?;
        Ok(vec_py(py, generalised(torques)?))
    }

    /// The paper's `p` (1/kg) at configuration `theta` when sliding in
    /// `direction` (`"positive"`: `z_r_dot > 0`; `"negative"`): `p = Q22 - mu
    /// sign(z_r_dot) Q21` (paper eq. 7). `p < 0` is the Painlevé paradox.
    #[pyo3(signature = (theta, direction="negative"))]
    fn p(&self, theta: &Bound<'_, PyAny>, direction: &str) -> PyResult<f64> {
        let theta = super::numbers::<2>("theta", theta)?;
        Ok(self.arm.p(&q_of(theta)?, self::direction(direction)?))
    }

    /// The paper's `b` (m/s^2) at `state` under motor torques `torques = [u1, u2]`
    /// (N m; `None`: none): the tip's free normal acceleration (paper eq. 6).
    #[pyo3(signature = (state, torques=None))]
    fn b(&self, state: &Bound<'_, PyAny>, torques: Option<&Bound<'_, PyAny>>) -> PyResult<f64> {
        let state = super::numbers::<4>("state", state)?;
        let torques = torques.map(|v| super::numbers::<2>("torques", v)).transpose()?.unwrap_or([0.0; 2]);
        let (q, qd) = split(state)?;
        Ok(self.arm.b(&q, &qd, &generalised(torques)?))
    }

    /// Whether configuration `theta` is in the Painlevé region when sliding in
    /// `direction`: `p < 0` (paper section III).
    #[pyo3(signature = (theta, direction="negative"))]
    fn painleve(&self, theta: &Bound<'_, PyAny>, direction: &str) -> PyResult<bool> {
        let theta = super::numbers::<2>("theta", theta)?;
        Ok(self.arm.p(&q_of(theta)?, self::direction(direction)?) < 0.0)
    }

    /// The contact mode (`"flight"`, `"sliding"`, `"sticking"`, `"jam"` or
    /// `"indeterminate"` ...; `shared::contact`'s names) of a tip on the belt at
    /// `state` under motor torques `torques`: the slipping classification by the
    /// signs of `b` and `p` (paper Table of modes; docs/model.md) with the slip
    /// direction of `z_r_dot = z_t_dot - v_belt`, or sticking when `|z_r_dot|` is
    /// at most `v_stick` (m/s, finite and >= 0) and the sticking force is in the
    /// friction cone.
    #[pyo3(signature = (state, torques=None, v_stick=1e-9))]
    fn contact_mode(&self, state: &Bound<'_, PyAny>, torques: Option<&Bound<'_, PyAny>>, v_stick: f64) -> PyResult<&'static str> {
        let state = super::numbers::<4>("state", state)?;
        let torques = torques.map(|v| super::numbers::<2>("torques", v)).transpose()?.unwrap_or([0.0; 2]);
        let (q, qd) = split(state)?;
        let u = generalised(torques)?;
        if !(v_stick.is_finite() && v_stick >= 0.0) {
            return Err(PyValueError::new_err(format!("v_stick = {}: expected a finite number >= 0 (m/s)", py_float(v_stick))));
        }
        let td = self.arm.tip_dynamics(&q, &qd, &u);
        let z_r_dot = td.z_dot[0] - self.arm.params.v_belt;
        let mode: ContactMode = contact::classify(&td, self.arm.params.mu, z_r_dot, v_stick);
        Ok(mode.name())
    }

    /// Mechanical energy (J) at `state`: kinetic `1/2 q_dot^T M q_dot` plus
    /// gravity and the spring (docs/plant.md "The energy ledger").
    fn energy(&self, state: &Bound<'_, PyAny>) -> PyResult<f64> {
        let state = super::numbers::<4>("state", state)?;
        let (q, qd) = split(state)?;
        Ok(self.arm.kinetic_energy(&q, &qd) + self.arm.potential_energy(&q))
    }

    fn __repr__(&self) -> String {
        let p = &self.arm.params;
        format!("Model(mu={}, v_belt={}, m={}, l={})", p.mu, p.v_belt, p.m, p.l)
    }
}
