//! `painleve.Firmware`: the firmware's control step (`firmware::Firmware`, through
//! `rig::firmware_side::FirmwareSide::answer`, the path `rig::InProcessLink` takes)
//! on the wire types: a frame in SI units is encoded as the rig's sensor model
//! encodes it (`rig::sensors::Sensors`, no noise), its belt speed as stated
//! (`rig::sensors::with_stated_belt_speed`: mm/s, not through the belt encoder's
//! model, which needs the periods before), the command that answers it is
//! decoded to SI (`shared::wire::decode_torque`).

use std::sync::Mutex;

use firmware::board::FrozenClock;
use numpy::PyArray1;
use pyo3::{
    exceptions::{PyKeyError, PyTypeError},
    prelude::*,
    types::PyDict,
};
use rig::{
    Scenario,
    firmware_side::FirmwareSide,
    sensors::{SensorModel, Sensors, with_stated_belt_speed},
};
use shared::wire::{self, ActuatorCommand, FirmwareTelemetry, SensorFrame};

use super::{scenario::PyScenario, sensed::PySensed};
use crate::cli::error;
use crate::convert::to_py;

/// The firmware of a scenario (`rig::firmware_config`; `None`: the default
/// scenario), stepped frame by frame on the wire types: `step(frame)` encodes
/// the frame as the rig's sensors do (14-bit encoders, 12-bit load cell, no
/// noise) and answers through `rig::firmware_side::FirmwareSide::answer`, as
/// `rig::InProcessLink` does, bit for bit (bring-up, checks and safe state
/// included); the command comes back decoded to SI (`Command`).
///
/// Raises `PainleveError` (exit_code 2) for a configuration the firmware
/// refuses. Source: python/src/objects/firmware.rs.
#[pyclass(name = "Firmware", module = "painleve._painleve")]
pub struct PyFirmware {
    side: Mutex<FirmwareSide>,
    initial: FirmwareSide,
    scenario: Scenario,
    /// The next period index.
    k: u32,
}

/// The firmware's answer to one frame (`shared::wire::ActuatorCommand`) decoded
/// to SI: `u1`, `u2` (N m), `torques` `(2,)`, `status` and its words,
/// `lift_off`, `safe_state`, `telemetry`; `u1, u2 = command`.
#[pyclass(name = "Command", module = "painleve._painleve", frozen)]
pub struct PyCommand {
    command: ActuatorCommand,
    telemetry: FirmwareTelemetry,
}

impl PyCommand {
    /// The joint torques `[u1, u2]`, N m, as the plant applies them.
    pub fn si(&self) -> [f64; 2] {
        [f64::from(wire::decode_torque(self.command.u1_code)), f64::from(wire::decode_torque(self.command.u2_code))]
    }
}

#[pymethods]
impl PyCommand {
    /// Motor torque u1 (base joint), N m (the wire's 12-bit code decoded).
    #[getter]
    fn u1(&self) -> f64 {
        self.si()[0]
    }

    /// Motor torque u2 (elbow), N m.
    #[getter]
    fn u2(&self) -> f64 {
        self.si()[1]
    }

    /// `(2,)` array `[u1, u2]`, N m.
    #[getter]
    fn torques<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.si())
    }

    /// The frame this answers (`seq`).
    #[getter]
    fn seq(&self) -> u32 {
        self.command.seq
    }

    /// The status word (`shared::wire::status` bits).
    #[getter]
    fn status(&self) -> u32 {
        self.command.status
    }

    /// The status word in words (`rig::status_words::describe_status`).
    #[getter]
    fn status_text(&self) -> String {
        rig::status_words::describe_status(self.command.status)
    }

    /// Whether the firmware detected lift-off (`status::LIFT_OFF`).
    #[getter]
    fn lift_off(&self) -> bool {
        self.command.status & wire::status::LIFT_OFF != 0
    }

    /// The safe state's reason in words, `None` while running.
    #[getter]
    fn safe_state(&self) -> Option<&'static str> {
        firmware::SafeReason::from_status(self.command.status).map(firmware::SafeReason::describe)
    }

    /// When the command left, s on the frame's clock.
    #[getter]
    fn t_sent(&self) -> f64 {
        self.command.t_sent_us as f64 * 1e-6
    }

    /// The raw command: dict of `t_sent_us`, `seq`, `u1_code`, `u2_code`
    /// (codes of 5/2048 N m), `status`, `step_ticks`, `overruns`.
    #[getter]
    fn raw<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.command)
    }

    /// The step's telemetry: dict of `z_t_ref` (m), `f_n_ref` (N), `q` (rad),
    /// `qd` (rad/s), `f` (N), `u_raw` (N m, before saturation and quantisation).
    #[getter]
    fn telemetry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.telemetry)
    }

    fn __len__(&self) -> usize {
        2
    }

    /// `u1`, `u2` (so that `u1, u2 = command` and a controller may return it).
    fn __getitem__(&self, i: isize) -> PyResult<f64> {
        match i {
            0 | -2 => Ok(self.si()[0]),
            1 | -1 => Ok(self.si()[1]),
            _ => Err(pyo3::exceptions::PyIndexError::new_err("a command has two torques: 0 (u1) and 1 (u2)")),
        }
    }

    fn __repr__(&self) -> String {
        let u = self.si();
        format!(
            "<Command seq {}: u1 = {} N m, u2 = {} N m, status {:#x} ({})>",
            self.command.seq,
            u[0],
            u[1],
            self.command.status,
            self.status_text()
        )
    }
}

/// A float from a frame dict (`key`), or `default` when absent.
fn field(d: &Bound<'_, PyDict>, key: &str, default: Option<f64>) -> PyResult<f64> {
    match d.get_item(key)? {
        Some(v) => v.extract::<f64>().map_err(|_| {
            PyTypeError::new_err(format!(
                "frame[{key:?}]: expected a number, got {}",
                v.get_type().name().map(|n| n.to_string()).unwrap_or_default()
            ))
        }),
        None => default
            .ok_or_else(|| PyKeyError::new_err(format!("frame: `{key}` is missing (it needs theta1, theta2 in rad and f_t, f_n in N)"))),
    }
}

#[pymethods]
impl PyFirmware {
    /// `Firmware(scenario=None)`: the firmware configured as the scenario asks
    /// (`rig::firmware_config`; the default scenario when `None`).
    #[new]
    #[pyo3(signature = (scenario=None))]
    fn new(py: Python<'_>, scenario: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let s = PyScenario::of(py, scenario)?;
        let setup = rig::RunSetup::new(s.clone()).map_err(|e| error(py, e.to_string(), 2))?;
        let side = FirmwareSide::new(&setup).map_err(|e| error(py, e.to_string(), 2))?;
        Ok(Self { side: Mutex::new(side.clone()), initial: side, scenario: s, k: 0 })
    }

    /// Answers one frame: a `Sensed` (its raw frame as it crossed the wire) or a
    /// dict with `theta1`, `theta2` (rad), `f_t`, `f_n` (N), and optionally
    /// `v_belt` (m/s; the scenario's; sent as stated, to 1 mm/s) and `k` (the period index; the next one).
    /// Returns the `Command`.
    ///
    /// Raises `KeyError` for a missing key, `TypeError` for a value that is
    /// not a number, `PainleveError` (exit_code 2) for a bad `k`. A frame the
    /// firmware does not trust (a NaN, a repeated `k`) is answered as on the
    /// board: the previous command held, its status says why.
    fn step(&mut self, py: Python<'_>, frame: &Bound<'_, PyAny>) -> PyResult<PyCommand> {
        let period = self.scenario.timing.period();
        let frame: SensorFrame = if let Ok(s) = frame.cast::<PySensed>() {
            s.get().frame
        } else if let Ok(d) = frame.cast::<PyDict>() {
            let theta1 = field(d, "theta1", None)?;
            let theta2 = field(d, "theta2", None)?;
            let f = [field(d, "f_t", None)?, field(d, "f_n", None)?];
            let v_belt = field(d, "v_belt", Some(self.scenario.plant.v_belt))?;
            let k = match d.get_item("k")? {
                Some(k) => k.extract::<u32>().map_err(|_| error(py, format!("frame[\"k\"] = {k}: expected a period index >= 0"), 2))?,
                None => self.k,
            };
            let mut sensors = Sensors::new(0, 0.0, period).with_encoder_bits(self.scenario.sensors.encoder_bits);
            let frame = sensors.frame(k, period.sample(u64::from(k)).as_us(), &[theta1, 0.0, theta2, 0.0], f, 0.0);
            with_stated_belt_speed(frame, v_belt)
        } else {
            return Err(PyTypeError::new_err(format!("frame: expected a painleve.Sensed or a dict, got {}", frame.get_type().name()?)));
        };
        self.k = frame.seq.saturating_add(1);
        let side = self.side.get_mut().unwrap_or_else(|p| p.into_inner());
        let (command, telemetry) = side.answer(&frame, frame.sampled_at(), &FrozenClock);
        Ok(PyCommand { command, telemetry })
    }

    /// Back to the firmware as configured (before its first frame).
    fn reset(&mut self) {
        *self.side.get_mut().unwrap_or_else(|p| p.into_inner()) = self.initial.clone();
        self.k = 0;
    }

    /// The next period index `k` a frame dict without `k` gets.
    #[getter]
    fn k(&self) -> u32 {
        self.k
    }

    /// The control period Ts, s.
    #[getter]
    fn period(&self) -> f64 {
        self.scenario.timing.period().as_secs_f64()
    }

    /// The safe state's reason in words, `None` while running.
    #[getter]
    fn safe_state(&self) -> Option<&'static str> {
        self.side.lock().unwrap_or_else(|p| p.into_inner()).firmware().safe_state().map(firmware::SafeReason::describe)
    }

    /// The scenario that configured it.
    #[getter]
    fn scenario(&self) -> PyScenario {
        PyScenario { inner: self.scenario.clone() }
    }

    fn __repr__(&self) -> String {
        format!("<Firmware {} at {} Hz, next k = {}>", self.scenario.controller.kind.name(), self.scenario.timing.rate_hz, self.k)
    }
}
