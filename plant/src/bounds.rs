//! The bounds on an initial state that [`Plant::new`](crate::Plant::new) accepts
//! (issue 15, "Bounds on input"): what is not a state of the arm is refused
//! ([`SimError::NonPhysicalInitialState`](crate::SimError::NonPhysicalInitialState)),
//! and a tip slightly inside the belt is projected onto it.

/// Largest initial joint angle magnitude, rad (10 turns): beyond it the state is refused.
pub const MAX_ANGLE: f64 = 20.0 * std::f64::consts::PI;

/// Largest initial joint rate magnitude, rad/s.
pub const MAX_RATE: f64 = 1e3;

/// Largest initial penetration of the tip into the belt that is projected onto it, m.
pub const PROJECTION_TOLERANCE: f64 = 1e-3;
