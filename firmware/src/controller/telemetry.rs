//! What the firmware reports of its last step: [`Telemetry`] (its estimates,
//! reference, forces and the law's torques, for SIL traces and tests) and the
//! wire's telemetry message built from it ([`Firmware::telemetry_message`]).

use shared::wire::{self, ActuatorCommand};

use super::Firmware;

/// What the firmware computed in its last step (for telemetry, SIL traces and tests):
/// what the wire's telemetry message carries. Stored every step, so nothing more
/// (issue 56: the tip's estimate, the reference's rate and acceleration, the hybrid
/// law's signals, the lift-off flag and the innovations were 15 stores a step that
/// no message carried, and under the PID the reference's acceleration was computed
/// for them alone; the law's signals are [`crate::law::hybrid_at`]'s return, the
/// tip's from [`crate::law::TipKinematics`], the reference from
/// [`crate::reference::Quintic::at`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Telemetry {
    /// Estimated `[theta1, theta2]`, rad.
    pub q: [f32; 2],
    /// Estimated `[theta1_dot, theta2_dot]`, rad/s.
    pub qd: [f32; 2],
    /// Reference `z_t*`, m.
    pub z_t_ref: f32,
    /// Normal-force reference `f_n*` after the start-up ramp, N.
    pub f_n_ref: f32,
    /// Measured `[f_t, f_n]`, N.
    pub f: [f32; 2],
    /// Motor torques before saturation and quantisation, N m.
    pub u_raw: [f32; 2],
}

impl<L: crate::control_law::ControlLaw> Firmware<L> {
    /// The telemetry message of the last step, answering `command` (SIL rig).
    pub fn telemetry_message(&self, command: &ActuatorCommand) -> wire::FirmwareTelemetry {
        let t = &self.telemetry;
        wire::FirmwareTelemetry {
            seq: command.seq,
            status: command.status,
            z_t_ref: t.z_t_ref,
            f_n_ref: t.f_n_ref,
            q: t.q,
            qd: t.qd,
            f: t.f,
            u_raw: t.u_raw,
        }
    }
}
