//! `painleve.Plant`: the hybrid plant (`plant::Plant`, paper eqs. 1 to 7) held in
//! Python and advanced interval by interval under held motor torques (zero-order
//! hold), as pydrake's `Simulator.AdvanceTo` or MuJoCo's `mj_step` do.

use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::{prelude::*, types::PyDict};
use rig::Scenario;

use plant::{Hold, NoObserver, Plant, SimConfig, SimError, StepReport, initial};

use super::scenario::PyScenario;
use crate::cli::error;
use crate::convert::to_py;

/// The `[plant]` keys a `Plant` takes as keyword arguments.
const PLANT_KEYS: [&str; 17] =
    ["mu", "v_belt", "x0", "impact_law", "e_n", "iwc", "singular", "rtol", "atol", "max_step", "m", "l", "sigma", "k", "h", "alpha0", "g"];

/// The simulator settings of a scenario's `[plant]` (as `rig::setup::plant_for`).
fn sim_config(s: &Scenario) -> SimConfig {
    let p = &s.plant;
    SimConfig {
        rtol: p.rtol,
        atol: p.atol,
        impact_law: p.impact_law,
        e_n: p.e_n,
        iwc: p.iwc,
        max_step: p.max_step,
        singular: p.singular,
        ..SimConfig::default()
    }
}

/// The hybrid plant: the two-link arm (paper Table I) with its tip on the belt
/// moving at `v_belt`, Coulomb friction `mu`, impacts (paper eqs. 1 to 7);
/// advanced under held motor torques `(u1, u2)` (N m, zero-order hold).
///
/// Built from `scenario`'s `[plant]` (a `Scenario` or TOML text; `None`: the
/// default scenario's, paper Table I with `mu = 0.6`, `v_belt = -0.4` m/s,
/// Newton `e_n = 0.2`, from `x0 = "a"` as `painleve.simulate`), with any key of
/// `[plant]` as a keyword (`mu`, `v_belt`, `x0`, `impact_law`, `e_n`, `iwc`,
/// `singular`, `rtol`, `atol`, `max_step`, `m`, `l`, `sigma`, `k`, `h`,
/// `alpha0`, `g`), and `state`, `(4,)` `[theta1, theta1_dot, theta2,
/// theta2_dot]` (rad, rad/s), instead of the paper's initial condition.
///
/// Raises `PainleveError` (exit_code 2) for bad parameters or an initial state
/// below the belt, `TypeError` for an unknown keyword. Source:
/// python/src/objects/plant.rs over `plant::Plant` and `rig::plant_for`.
#[pyclass(name = "Plant", module = "painleve._painleve")]
pub struct PyPlant {
    plant: Mutex<Plant>,
    initial: Mutex<Plant>,
    scenario: Scenario,
}

impl PyPlant {
    fn with<T>(&self, f: impl FnOnce(&Plant) -> T) -> T {
        f(&self.plant.lock().unwrap_or_else(|p| p.into_inner()))
    }

    /// A plant of this one's parameters and settings at state `x`, time `t` (s),
    /// no torque yet: `plant::Plant::new`, which refuses a state below the belt.
    fn at(&self, py: Python<'_>, x: [f64; 4], t: f64) -> PyResult<Plant> {
        if !x.iter().all(|v| v.is_finite()) {
            return Err(error(py, format!("state {x:?}: expected four finite numbers (rad, rad/s)"), 2));
        }
        let params = self.with(|p| p.arm().params);
        Plant::new(params, sim_config(&self.scenario), x, t, [0.0, 0.0]).map_err(|e| error(py, e.to_string(), 2))
    }
}

/// A `SimError` while advancing: exit code 1 (a failure while running), or 2 for
/// bad input (a step or torque the plant refused).
fn sim_error(py: Python<'_>, e: &SimError) -> PyErr {
    let code = if matches!(e, SimError::BadStep(_) | SimError::BadTorque(_)) { 2 } else { 1 };
    error(py, e.to_string(), code)
}

/// What one `Plant.advance` reports (`plant::StepReport`): `t` (s), `mode`,
/// `state` `(4,)`, `tip` `(2,)` m, `force` `(2,)` `[f_t, f_n]` N, `events`.
#[pyclass(name = "Step", module = "painleve._painleve", frozen)]
pub struct PyStep {
    report: StepReport,
    tip: [f64; 2],
}

#[pymethods]
impl PyStep {
    /// Time at the end of the interval, s.
    #[getter]
    fn t(&self) -> f64 {
        self.report.t
    }

    /// Contact mode at the end: `"flight"`, `"sliding"` or `"sticking"`.
    #[getter]
    fn mode(&self) -> &'static str {
        self.report.mode.name()
    }

    /// State at the end, `(4,)`: theta1 rad, theta1_dot rad/s, theta2 rad, theta2_dot rad/s.
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.report.x)
    }

    /// Tip position at the end, `(2,)`: `[z_t, z_n]`, m.
    #[getter]
    fn tip<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.tip)
    }

    /// Contact force at the end, `(2,)`: `[f_t, f_n]`, N (zero in flight).
    #[getter]
    fn force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.report.f)
    }

    /// The interval's events in time order: dicts with `t` (s), `kind`
    /// (`"lift_off"`, `"touchdown"`, ...), `mode_after`, the velocities before
    /// and after, `impulse`, `energy_change`, `contact_work`, `resolution`.
    #[getter]
    fn events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.report.events)
    }

    fn __repr__(&self) -> String {
        let kinds: Vec<&str> = self.report.events.iter().map(|e| e.kind.name()).collect();
        format!("<Step t = {} s, {}, events [{}]>", self.report.t, self.report.mode.name(), kinds.join(", "))
    }
}

#[pymethods]
impl PyPlant {
    /// `Plant(scenario=None, *, state=None, **params)`.
    #[new]
    #[pyo3(signature = (scenario=None, *, state=None, **params))]
    fn new(
        py: Python<'_>,
        scenario: Option<&Bound<'_, PyAny>>,
        state: Option<&Bound<'_, PyAny>>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let state = state.map(|v| super::numbers::<4>("state", v)).transpose()?;
        let given = scenario.is_some_and(|s| !s.is_none());
        let mut s = PyScenario::of(py, scenario)?;
        if !given {
            // `painleve.simulate`'s initial condition.
            s.plant.x0 = initial::PaperX0::A;
        }
        let s = PyScenario::with_plant_keywords(py, s, params, &PLANT_KEYS, "Plant()", "scenario, state")?;
        let plant = match state {
            None => rig::plant_for(&s),
            Some(x) => {
                let params = s.plant.params();
                params.validate().map_err(SimError::from).and_then(|()| Plant::new(params, sim_config(&s), x, 0.0, [0.0, 0.0]))
            }
        }
        .map_err(|e| error(py, e.to_string(), 2))?;
        Ok(Self { initial: Mutex::new(plant.clone()), plant: Mutex::new(plant), scenario: s })
    }

    /// Advances by `dt` (s, >= 0) with the motor torques `torques = (u1, u2)`
    /// (N m) held over the interval; returns the interval's `Step` (its events
    /// at their exact times, the state, the contact force at its end).
    ///
    /// Raises `PainleveError`: exit_code 2 for a negative or NaN `dt` or a
    /// non-finite torque (the plant unchanged), exit_code 1 for a failure of
    /// the plant during the interval (`plant::SimError`; the plant is left at
    /// the failure time). `TypeError` when `torques` is not two numbers.
    #[pyo3(signature = (dt, torques=(0.0, 0.0)))]
    fn advance(&mut self, py: Python<'_>, dt: f64, torques: (f64, f64)) -> PyResult<PyStep> {
        let u = [torques.0, torques.1];
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(error(py, format!("dt = {dt} s: expected a finite step >= 0"), 2));
        }
        if !u.iter().all(|x| x.is_finite()) {
            return Err(error(py, format!("torques = [{}, {}] N m: expected two finite numbers", u[0], u[1]), 2));
        }
        let plant = self.plant.get_mut().unwrap_or_else(|p| p.into_inner());
        // The plant runs without the GIL (other Python threads go on).
        let report = py.detach(|| plant.advance(&Hold(u), dt, &mut NoObserver)).map_err(|e| sim_error(py, &e))?;
        let z = plant.tip();
        Ok(PyStep { report, tip: [z[0], z[1]] })
    }

    /// Advances to time `t` (s, >= `time`): `advance(t - time, torques)`.
    #[pyo3(signature = (t, torques=(0.0, 0.0)))]
    fn advance_to(&mut self, py: Python<'_>, t: f64, torques: (f64, f64)) -> PyResult<PyStep> {
        let now = self.with(Plant::time);
        if !(t.is_finite() && t >= now) {
            return Err(error(py, format!("t = {t} s: expected a finite time >= the plant's, {now} s"), 2));
        }
        self.advance(py, t - now, torques)
    }

    /// Back to the initial state (time 0, the counters cleared); with `state`,
    /// `(4,)` `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s), to that
    /// state instead, at time `t` (s, default 0): a new plant of the same
    /// parameters there, its contact mode found from the state (counters, ledger
    /// and events start afresh), as MuJoCo's writable `qpos`/`qvel` or pydrake's
    /// `SetPositionsAndVelocities`.
    ///
    /// Raises `PainleveError` (exit_code 2, the plant unchanged) for a state
    /// below the belt (the tip under `z_n = -H`), a non-finite state or a
    /// negative or non-finite `t`.
    #[pyo3(signature = (state=None, t=None))]
    fn reset(&mut self, py: Python<'_>, state: Option<&Bound<'_, PyAny>>, t: Option<f64>) -> PyResult<()> {
        let state = state.map(|v| super::numbers::<4>("state", v)).transpose()?;
        let t0 = t.unwrap_or(0.0);
        if !(t0.is_finite() && t0 >= 0.0) {
            return Err(error(py, format!("t = {t0} s: expected a finite time >= 0"), 2));
        }
        let plant = match (state, t) {
            (None, None) => self.initial.get_mut().unwrap_or_else(|p| p.into_inner()).clone(),
            (x, _) => {
                let x = x.unwrap_or_else(|| self.initial.get_mut().unwrap_or_else(|p| p.into_inner()).state());
                self.at(py, x, t0)?
            }
        };
        *self.plant.get_mut().unwrap_or_else(|p| p.into_inner()) = plant;
        Ok(())
    }

    /// A copy (its own state from now on).
    fn copy(&self) -> Self {
        let initial = self.initial.lock().unwrap_or_else(|p| p.into_inner()).clone();
        Self { plant: Mutex::new(self.with(Plant::clone)), initial: Mutex::new(initial), scenario: self.scenario.clone() }
    }

    fn __copy__(&self) -> Self {
        self.copy()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.copy()
    }

    /// Time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.with(Plant::time)
    }

    /// State, `(4,)`: theta1 rad, theta1_dot rad/s, theta2 rad, theta2_dot rad/s.
    /// Settable: `plant.state = x` is `plant.reset(state=x, t=plant.time)` (a new
    /// plant there, checked against the contact; `PainleveError` with exit_code 2
    /// for a state below the belt, the plant unchanged).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.with(Plant::state))
    }

    #[setter]
    fn set_state(&mut self, py: Python<'_>, state: &Bound<'_, PyAny>) -> PyResult<()> {
        let state = super::numbers::<4>("state", state)?;
        let now = self.with(Plant::time);
        let plant = self.at(py, state, now)?;
        *self.plant.get_mut().unwrap_or_else(|p| p.into_inner()) = plant;
        Ok(())
    }

    /// Tip position, `(2,)`: `[z_t, z_n]`, m (the belt is at `z_n = -H`).
    #[getter]
    fn tip<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let z = self.with(Plant::tip);
        PyArray1::from_slice(py, &[z[0], z[1]])
    }

    /// Tip velocity, `(2,)`: `[z_t_dot, z_n_dot]`, m/s.
    #[getter]
    fn tip_velocity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v = self.with(Plant::tip_velocity);
        PyArray1::from_slice(py, &[v[0], v[1]])
    }

    /// Contact mode: `"flight"`, `"sliding"` or `"sticking"`.
    #[getter]
    fn mode(&self) -> &'static str {
        self.with(Plant::mode).name()
    }

    /// Mechanical energy (kinetic + gravity + spring), J.
    #[getter]
    fn energy(&self) -> f64 {
        self.with(Plant::energy)
    }

    /// Contact force, `(2,)`: `[f_t, f_n]` (N) in the current mode under motor
    /// torques `torques = [u1, u2]` (N m).
    #[pyo3(signature = (torques=(0.0, 0.0)))]
    fn contact_force<'py>(&self, py: Python<'py>, torques: (f64, f64)) -> PyResult<Bound<'py, PyArray1<f64>>> {
        if !(torques.0.is_finite() && torques.1.is_finite()) {
            return Err(error(py, format!("torques = [{}, {}] N m: expected two finite numbers", torques.0, torques.1), 2));
        }
        Ok(PyArray1::from_slice(py, &self.with(|p| p.contact_force([torques.0, torques.1]))))
    }

    /// Event counts since creation (or `reset`): dict of int (`lift_offs`, every
    /// departure from the belt as in every result, and `lift_offs_from_contact`,
    /// those without the bounces; `touchdowns`, `bounces`,
    /// `impacts_without_collision`, ...; `bridged_s` in s), as `simulate`'s
    /// `summary.json` writes them (`experiments::counters::Published`).
    #[getter]
    fn counters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = self.with(|p| *p.counters());
        to_py(py, &experiments::counters::Published(&c))
    }

    /// The validity counters since creation (`energy_gains`, `cone_violations`,
    /// `integrator_failures`, `zeno_stops`, fallbacks, ...): dict of int.
    #[getter]
    fn validity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.with(|p| p.validity(None)))
    }

    /// The energy ledger since creation (docs/plant.md "The energy ledger"): dict
    /// of float, J (`energy_change_j`, `motors_j`, `damping_j`, `belt_j`, `slip_j`,
    /// `projections_j`, `events_j`: the events' energy changes summed, `residual_j`,
    /// `worst_entry_j`, `worst_ratio`, `largest_event_belt_j`) and int
    /// (`refinements`, `violations`, `impulses_outside_cone`, `impulses_off_law`,
    /// `projections_beyond_drift`, `impulses_undue`, `projections_unphysical`, whose
    /// energy `projections_unphysical_j` is in J; `largest_projection_drift_m_s` is a
    /// float, m/s).
    #[getter]
    fn ledger<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.with(|p| p.ledger()))
    }

    /// The events at time 0 while the initial mode was chosen (list of dicts, as `Step.events`).
    #[getter]
    fn startup_events<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let events = self.with(|p| p.startup_events().to_vec());
        to_py(py, &events)
    }

    /// The plant's parameters: dict of `m`, `l`, `sigma`, `k`, `h`, `alpha0`, `g`,
    /// `mu`, `v_belt` (SI units, radians).
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.with(|p| p.arm().params))
    }

    /// The scenario whose `[plant]` built this plant (the keyword arguments applied).
    #[getter]
    fn scenario(&self) -> PyScenario {
        PyScenario { inner: self.scenario.clone() }
    }

    fn __repr__(&self) -> String {
        self.with(|p| {
            let x = p.state();
            format!(
                "<Plant t = {} s, {}, state [{:.6}, {:.6}, {:.6}, {:.6}], mu = {}, v_belt = {} m/s>",
                p.time(),
                p.mode().name(),
                x[0],
                x[1],
                x[2],
                x[3],
                p.arm().params.mu,
                p.arm().params.v_belt
            )
        })
    }
}
