//! The interface the plant calls inside the integration: a torque law
//! ([`Controller`]), and the zero-order hold of a sampled controller ([`Hold`]).

use crate::phase::Phase;

/// A torque law the plant evaluates inside the integration.
///
/// The zero-order hold of a sampled controller is [`Hold`]; the paper's ideal
/// setting (a continuous-time controller with exact measurements) implements this
/// trait directly, with up to two internal states `xi` (e.g. integrators)
/// integrated alongside the plant.
pub trait Controller {
    /// Motor torques `[u1, u2]` (N m, base joint and elbow) at time `t` (s), plant state
    /// `x = [theta1, theta1_dot, theta2, theta2_dot]` (rad, rad/s) and internal states
    /// `xi`; writes `d xi / dt` into `xi_dot` (left zero for a stateless law).
    ///
    /// The contact force depends on the torque (through `b`), so a law that needs
    /// it computes it from the shared model itself (`shared::contact`).
    fn torque(&self, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2];

    /// As [`Controller::torque`], told the contact phase the plant integrates in
    /// (flight, sliding in a direction, or sticking): what a law with exact contact
    /// measurements knows (e.g. the paper's hybrid law, whose friction term is the
    /// true `f_t`, zero in flight). The plant always calls this one; the default
    /// ignores the phase.
    fn torque_in(&self, phase: Phase, t: f64, x: &[f64; 4], xi: &[f64; 2], xi_dot: &mut [f64; 2]) -> [f64; 2] {
        let _ = phase;
        self.torque(t, x, xi, xi_dot)
    }

    /// The torques `[u1, u2]` (N m) if this law holds them constant over the
    /// interval (a zero-order hold, [`Hold`]), for [`Plant::advance`](crate::Plant::advance)'s check.
    fn held(&self) -> Option<[f64; 2]> {
        None
    }
}

/// Zero-order hold: motor torques `[u1, u2]` (N m) held constant over the interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hold(pub [f64; 2]);

impl Controller for Hold {
    #[inline]
    fn torque(&self, _t: f64, _x: &[f64; 4], _xi: &[f64; 2], _xi_dot: &mut [f64; 2]) -> [f64; 2] {
        self.0
    }

    fn held(&self) -> Option<[f64; 2]> {
        Some(self.0)
    }
}
