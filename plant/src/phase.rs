//! The contact phase the integrator runs in ([`Phase`]): the plant's discrete
//! state, the contact mode with its slip direction.

use shared::SlipDirection;

/// Contact mode the integrator runs in (the plant's discrete state).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Off the belt: `f = 0`.
    Flight,
    /// Slipping on the belt in a fixed direction: `f_n = -b/p`, `f_t = -mu s f_n`.
    Sliding(SlipDirection),
    /// Carried by the belt: `z_ddot = 0`, `f = -Q^-1 a_free`.
    Sticking,
}
