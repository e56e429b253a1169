//! `painleve.run_controller`: the closed loop with a Python callable as the
//! controller. The plant side is the rig's own (`rig::run_loop` and
//! `rig::PeriodLoop`: the sensor models and their faults, the zero-order hold,
//! the command taking effect at `t_k + delta`, deadline misses); the controller is
//! reached through a [`FirmwareLink`], [`PythonLink`], in place of the firmware's.
//!
//! What differs from the firmware's path (`painleve.run`, `rig::InProcessLink`):
//! the frame is decoded here (`firmware::decode::decode_bits`, as the firmware
//! decodes it) and handed over in SI units; the torques come back as numbers and
//! go out as the wire's 12-bit torque codes (saturated at 5 N m), as the
//! firmware's do (the trace's `u1_cmd`/`u2_cmd` are the callable's values, before
//! that quantisation); none of the firmware's
//! checks (bad or stale frames, deadline misses, the safe state, runaway and
//! sensor-consistency monitors, the reference ramp) run; the loop runs on the
//! calling thread holding the GIL, and checks for Ctrl-C every period.

use std::time::Instant;

use experiments::run_observer::{Gather, KeepFrames};
use firmware::estimator::AngleTracker;
use pyo3::{
    exceptions::{PyTypeError, PyValueError},
    prelude::*,
    types::{PyDict, PyString, PyTuple},
};
use rig::{
    Exchange, FaultPlan, FirmwareLink, LinkKind, RunError, RunSetup, firmware_side::step_start, stats::RunStats, summary::RunSummary,
};
use shared::wire::{ActuatorCommand, FirmwareTelemetry, GroundTruth, SensorFrame};

use super::{scenario::PyScenario, sensed::PySensed};
use crate::cli::error;
use crate::convert::{Outcome, rows_to_py, to_py};

/// A Python callable `controller(t, sensed) -> (u1, u2)` as the firmware of a run.
pub struct PythonLink<'py> {
    controller: Bound<'py, PyAny>,
    faults: FaultPlan,
    encoder_bits: u8,
    /// Link length for the sensed tip position (the firmware's model's), m.
    l: f64,
    ts: f32,
    bandwidth: f32,
    trackers: Option<[AngleTracker; 2]>,
    /// The torques of the last answer, N m.
    torques: [f64; 2],
    /// The Python exception that stopped the run.
    pub raised: Option<PyErr>,
}

impl<'py> PythonLink<'py> {
    /// The link of `controller` for run `setup`.
    ///
    /// # Errors
    /// [`RunError::Unsupported`] for faults that need the firmware in a process
    /// of its own (as the in-process link).
    pub fn new(setup: &RunSetup, controller: Bound<'py, PyAny>) -> Result<Self, RunError> {
        let s = setup.scenario();
        LinkKind::InProcess.check(&s.faults)?;
        let cfg = setup.firmware();
        Ok(Self {
            controller,
            faults: setup.faults().clone(),
            encoder_bits: s.sensors.encoder_bits,
            l: rig::setup::firmware_params(s).l,
            ts: cfg.period.as_secs_f32(),
            bandwidth: cfg.observer_bandwidth,
            trackers: None,
            torques: [0.0; 2],
            raised: None,
        })
    }

    /// The frame decoded, the velocity trackers updated.
    fn sense(&mut self, frame: &SensorFrame) -> PySensed {
        let t = frame.t_us as f64 * 1e-6;
        let mut sensed = PySensed::decode(*frame, t, self.encoder_bits, [0.0; 2], self.l);
        if sensed.fault.is_none() {
            let q = sensed.q.map(|x| x as f32);
            let trackers = match &mut self.trackers {
                Some(tr) => {
                    tr[0].update(q[0], self.ts);
                    tr[1].update(q[1], self.ts);
                    tr
                }
                None => self.trackers.insert(q.map(|x| AngleTracker::new(x, self.bandwidth, self.ts))),
            };
            sensed.qd = [f64::from(trackers[0].rate), f64::from(trackers[1].rate)];
        }
        sensed
    }

    /// Calls the controller on `sensed`; its torques, or the Python error. An
    /// exception the controller raised is kept as it is (its type, message and
    /// traceback) with a note naming the period and time (issue 52, 8: it did not
    /// say when it was raised): `raised by the controller at period 7 (t = 0.007 s)`.
    fn call(&self, py: Python<'py>, sensed: PySensed) -> PyResult<[f64; 2]> {
        let (k, t) = (sensed.frame.seq, sensed.t);
        let out = self.controller.call1((t, Bound::new(py, sensed)?)).inspect_err(|e| {
            // To the nanosecond: the sample time k Ts, without its last bits (0.006999999999 s).
            let shown = (t * 1e9).round() / 1e9;
            add_note(py, e, &format!("raised by the controller at period {k} (t = {shown} s)"));
        })?;
        torques_of(&out, k, t)
    }
}

/// Adds `note` to the exception `e` (PEP 678's `add_note`, shown under its
/// message in a traceback, in `e.__notes__`); before Python 3.11, which has no
/// `add_note`, sets `__notes__` itself.
fn add_note(py: Python<'_>, e: &PyErr, note: &str) {
    let value = e.value(py);
    if value.call_method1("add_note", (note,)).is_err() {
        let _ = value.setattr("__notes__", vec![note]);
    }
}

/// The two torques a controller returned at period `k` (`t` s).
///
/// # Errors
/// `TypeError` for anything but two numbers, `ValueError` for a NaN or infinite one.
fn torques_of(out: &Bound<'_, PyAny>, k: u32, t: f64) -> PyResult<[f64; 2]> {
    let what = || format!("the controller's return at period {k} (t = {t} s)");
    let type_name = || out.get_type().name().map(|n| n.to_string()).unwrap_or_default();
    // A tuple, a list, a (2,) array: anything of length 2 but text and mappings.
    let len = if out.is_instance_of::<PyString>() || out.is_instance_of::<PyDict>() { None } else { out.len().ok() };
    if len != Some(2) {
        let got = match out.cast::<PyTuple>() {
            Ok(tuple) => format!("a tuple of {}", tuple.len()),
            Err(_) => type_name(),
        };
        return Err(PyTypeError::new_err(format!("{}: expected two torques (u1, u2) in N m, got {got}", what())));
    }
    let item = |i: usize| -> PyResult<f64> {
        let x = out.get_item(i)?;
        x.extract::<f64>().map_err(|_| {
            PyTypeError::new_err(format!(
                "{}: torque {i} is {}, not a number",
                what(),
                x.get_type().name().map(|n| n.to_string()).unwrap_or_default()
            ))
        })
    };
    let u = [item(0)?, item(1)?];
    if !u.iter().all(|x| x.is_finite()) {
        return Err(PyValueError::new_err(format!("{}: torques ({}, {}) N m; expected two finite numbers", what(), u[0], u[1])));
    }
    Ok(u)
}

impl FirmwareLink for PythonLink<'_> {
    fn transport(&self) -> &'static str {
        "python"
    }

    fn exchange(&mut self, frame: &SensorFrame, _truth: &GroundTruth) -> Result<Exchange, RunError> {
        let py = self.controller.py();
        let k = frame.seq as usize;
        let t = frame.t_us as f64 * 1e-6;
        if let Err(e) = py.check_signals() {
            self.raised = Some(e);
            return Err(RunError::Interrupted { k });
        }
        let sensed = self.sense(frame);
        let (q, qd, f) = (sensed.q, sensed.qd, sensed.f);
        match self.call(py, sensed) {
            Ok(u) => self.torques = u,
            Err(e) => {
                self.raised = Some(e);
                return Err(RunError::Transport(format!("the Python controller raised at period {k} (t = {t} s)")));
            }
        }
        // The `late_command` fault delays the answer as it delays the firmware's step.
        let sent = step_start(&self.faults, frame, frame.sampled_at());
        let u = self.torques;
        let command = ActuatorCommand {
            t_sent_us: sent.as_us(),
            seq: frame.seq,
            // The wire's torque codes, as the firmware sends them: the plant applies
            // them decoded (12-bit, 5/2048 N m a code, saturated at +-5 N m).
            u1_code: shared::wire::encode_torque(u[0] as f32).0,
            u2_code: shared::wire::encode_torque(u[1] as f32).0,
            ..ActuatorCommand::default()
        };
        let f32s = |v: [f64; 2]| v.map(|x| x as f32);
        let telemetry = FirmwareTelemetry {
            seq: frame.seq,
            status: 0,
            z_t_ref: f32::NAN,
            f_n_ref: f32::NAN,
            q: f32s(q),
            qd: f32s(qd),
            f: f32s(f),
            u_raw: f32s(u),
        };
        Ok(Exchange::Answered { command, telemetry, at_stamp: false })
    }
}

/// `painleve.run_controller`: the closed loop of `scenario` with `controller`
/// in place of the firmware; the raw result dict of `painleve.run`'s shape.
#[pyfunction]
#[pyo3(signature = (controller, scenario=None, duration=None))]
pub fn run_controller<'py>(
    py: Python<'py>,
    controller: Bound<'py, PyAny>,
    scenario: Option<Bound<'py, PyAny>>,
    duration: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    if !controller.is_callable() {
        return Err(PyTypeError::new_err(format!(
            "controller: expected a callable controller(t, sensed) -> (u1, u2), got {}",
            controller.get_type().name()?
        )));
    }
    // The callable's name for the MCAP's `/log` (`Result.law` says the same).
    let law = controller
        .getattr("__qualname__")
        .and_then(|n| n.extract::<String>())
        .or_else(|_| controller.get_type().name().map(|n| n.to_string()))
        .map_or_else(|_| "a Python controller".to_string(), |n| format!("Python {n}"));
    let mut s = PyScenario::of(py, scenario.as_ref())?;
    crate::commands::warn(py, experiments::scenario::board_tables_note(&s, "a Python controller (no board)"))?;
    if let Some(d) = duration {
        let o = rig::Override { key: "timing.duration_s".into(), value: toml::Value::Float(d), text: d.to_string() };
        s = s.with_overrides(&[o]).map_err(|e| super::scenario::scenario_error(py, &e))?;
    }
    let setup = RunSetup::new(s.clone()).map_err(|e| error(py, e.to_string(), 2))?;
    let mut link = PythonLink::new(&setup, controller).map_err(|e| error(py, e.to_string(), 2))?;
    // The page of a closed-loop run, its controller the caller's: the title and
    // the controller fact say so (the scenario's controller is not the one run).
    let mut info = figures::trace_page::PageInfo::closed_loop(setup.scenario(), "python");
    info.title = format!("Python controller (painleve.run_controller), scenario {}: from x0{}", s.name, s.plant.x0);
    if let Some(fact) = info.facts.iter_mut().find(|(k, _)| k == "controller") {
        fact.1 = "the caller's Python function (painleve.run_controller); the scenario's references".into();
    }
    let page = figures::trace_page::TracePage::new(info);
    // The validity, ledger and page as `painleve.run` gathers them, every frame kept.
    let mut finished = Gather::new(KeepFrames::default(), Some(page));
    let started = Instant::now();
    let (records, failure) = rig::run_loop(&setup, &mut link, &mut finished);
    let wall_s = started.elapsed().as_secs_f64();
    if let Some(e) = link.raised.take() {
        return Err(e);
    }
    let validity = finished.validity;
    let stats = RunStats::of(&records);
    let summary = RunSummary {
        ledger: finished.ledger,
        law: law.clone(),
        ..RunSummary::from_stats(&s, &stats, failure.as_ref(), link.transport(), "lockstep", wall_s, validity)
    };
    let failed = failure.map(|e| {
        let code = if matches!(e, RunError::Unsupported(_) | RunError::Firmware(_)) { 2 } else { 1 };
        (e.to_string(), code)
    });
    let (message, code) = failed.map_or((None, 0), |(m, c)| (Some(m), c));
    let trace_py = rows_to_py(py, &records)?;
    let frames_py = rows_to_py(py, &finished.sink.0)?;
    let recording =
        crate::recording::Recording::closed_loop(arm_view::ArmGeometry::of(&rig::setup::plant_params(&s)), law, records, finished.sink.0);
    Outcome::new(py, "run_controller", to_py(py, &summary)?)?
        .table("trace", trace_py)?
        .table("frames", frames_py)?
        .extra("scenario", to_py(py, &s)?)?
        .extra("page", finished.page.map(figures::trace_page::TracePage::html).unwrap_or_default().into_pyobject(py)?.into_any())?
        .extra("recording", Py::new(py, recording)?.into_any().into_bound(py))?
        .validity(&validity)?
        .failure(message, code)
        .map(Outcome::done)
}
