//! `painleve.Sensed`: one sensor frame (`shared::wire::SensorFrame`) decoded to SI
//! units as the firmware decodes it (`firmware::decode::decode_bits`): what a
//! controller sees after the sensor models (encoder quantisation, load-cell
//! noise and quantisation, the belt encoder), with the raw frame kept so that
//! `Firmware.step` can take it unchanged.

use numpy::PyArray1;
use pyo3::prelude::*;
use shared::wire::SensorFrame;

/// A sensor frame as a controller sees it, in SI units: `k`, `t` (s), `theta1`,
/// `theta2` (rad), `theta1_dot`, `theta2_dot` (rad/s, estimated), `f_t`, `f_n`
/// (N), `v_belt` (m/s), `z_t`, `z_n` (m), `state` `(4,)`, `valid`, `fault`,
/// `frame` (the raw counts). Source: python/src/objects/sensed.rs.
#[pyclass(name = "Sensed", module = "painleve._painleve", frozen)]
#[derive(Clone)]
pub struct PySensed {
    /// The frame as it crossed the wire.
    pub frame: SensorFrame,
    /// Sample time `t_k = k Ts`, s.
    pub t: f64,
    /// `[theta1, theta2]`, rad (NaN when the frame is not valid).
    pub q: [f64; 2],
    /// `[theta1_dot, theta2_dot]`, rad/s: the alpha-beta tracker's estimate.
    pub qd: [f64; 2],
    /// `[f_t, f_n]`, N.
    pub f: [f64; 2],
    /// Belt speed, m/s.
    pub v_belt: f64,
    /// Tip `[z_t, z_n]` from the sensed angles, m.
    pub z: [f64; 2],
    /// Why the frame is not trusted (`None`: valid).
    pub fault: Option<&'static str>,
}

impl PySensed {
    /// `frame` decoded for `encoder_bits`-bit encoders at `t` s, with the velocity
    /// estimate `qd` and links of length `l` (m) for the tip position.
    pub fn decode(frame: SensorFrame, t: f64, encoder_bits: u8, qd: [f64; 2], l: f64) -> Self {
        match firmware::decode::decode_bits(&frame, encoder_bits) {
            Ok(m) => {
                let q = [f64::from(m.theta1), f64::from(m.theta1) + f64::from(m.elbow)];
                // shared::kinematics::tip_position: [l (sin theta1 + sin theta2), -l (cos theta1 + cos theta2)].
                let z = [l * (q[0].sin() + q[1].sin()), -l * (q[0].cos() + q[1].cos())];
                Self { frame, t, q, qd, f: [f64::from(m.f_t), f64::from(m.f_n)], v_belt: f64::from(m.v_belt), z: [z[0], z[1]], fault: None }
            }
            Err(e) => {
                let nan = [f64::NAN; 2];
                let fault = match e {
                    firmware::decode::FrameFault::EncoderOutOfRange => "encoder count out of range",
                    firmware::decode::FrameFault::LoadOutOfRange => "load-cell code out of range",
                    firmware::decode::FrameFault::BeltOutOfRange => "belt speed out of range",
                    firmware::decode::FrameFault::Stale => "stale frame",
                    firmware::decode::FrameFault::SensorInvalid => "a sensor flagged its reading invalid",
                };
                Self { frame, t, q: nan, qd: nan, f: nan, v_belt: f64::NAN, z: nan, fault: Some(fault) }
            }
        }
    }
}

#[pymethods]
impl PySensed {
    /// Period index `k` (the frame's `seq`).
    #[getter]
    fn k(&self) -> u32 {
        self.frame.seq
    }

    /// Sample time `t_k = k Ts`, s.
    #[getter]
    fn t(&self) -> f64 {
        self.t
    }

    /// Base-joint angle theta1 from its encoder, rad, in (-pi, pi].
    #[getter]
    fn theta1(&self) -> f64 {
        self.q[0]
    }

    /// Link-2 angle theta2 = theta1 + the elbow encoder's angle, rad.
    #[getter]
    fn theta2(&self) -> f64 {
        self.q[1]
    }

    /// theta1_dot, rad/s: the alpha-beta tracker's estimate from the encoder
    /// (`firmware::estimator::AngleTracker` at the firmware's observer bandwidth,
    /// without the firmware's model-driven prediction); 0 at period 0.
    #[getter]
    fn theta1_dot(&self) -> f64 {
        self.qd[0]
    }

    /// theta2_dot, rad/s (as `theta1_dot`).
    #[getter]
    fn theta2_dot(&self) -> f64 {
        self.qd[1]
    }

    /// Tangential tip force f_t from the load cell, N.
    #[getter]
    fn f_t(&self) -> f64 {
        self.f[0]
    }

    /// Normal tip force f_n from the load cell, N.
    #[getter]
    fn f_n(&self) -> f64 {
        self.f[1]
    }

    /// Belt speed v_belt from the belt encoder, m/s.
    #[getter]
    fn v_belt(&self) -> f64 {
        self.v_belt
    }

    /// Tangential tip position z_t from the sensed angles, m.
    #[getter]
    fn z_t(&self) -> f64 {
        self.z[0]
    }

    /// Normal tip position z_n from the sensed angles, m (the belt is at -H).
    #[getter]
    fn z_n(&self) -> f64 {
        self.z[1]
    }

    /// `(4,)` array `[theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s), the
    /// plant's state order.
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &[self.q[0], self.qd[0], self.q[1], self.qd[1]])
    }

    /// Whether the frame decodes (no sensor flagged invalid, every count in range).
    #[getter]
    fn valid(&self) -> bool {
        self.fault.is_none()
    }

    /// Why it does not (`None` when valid).
    #[getter]
    fn fault(&self) -> Option<&'static str> {
        self.fault
    }

    /// The raw frame: dict of `t_us`, `seq`, `theta1_count`, `elbow_count`,
    /// `f_t_code`, `f_n_code`, `belt_count`, `flags` (ints, the wire's units).
    #[getter]
    fn frame<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::to_py(py, &self.frame)
    }

    fn __repr__(&self) -> String {
        format!(
            "<Sensed k = {}, t = {} s, theta1 = {:.6} rad, theta2 = {:.6} rad, f_t = {:.4} N, f_n = {:.4} N{}>",
            self.frame.seq,
            self.t,
            self.q[0],
            self.q[1],
            self.f[0],
            self.f[1],
            self.fault.map_or(String::new(), |f| format!(", invalid: {f}"))
        )
    }
}
