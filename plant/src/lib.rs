//! The plant simulator: the arm on the moving belt as an event-driven hybrid
//! system (docs/model.md; paper eqs. 1 to 7), in `f64`.
//!
//! Modes: flight, sliding (`f_n = -b/p`, Coulomb friction opposing the slip),
//! sticking (`z_r_dot = 0`, `f = -Q^-1 a_free` while `|f_t| <= mu f_n`). Each
//! mode is a smooth ODE integrated by DOP853, the Dormand-Prince 8(5,3) method of
//! Hairer, Nørsett and Wanner ("Solving Ordinary Differential Equations I",
//! sec. II.10; [`dop853`], allocation-free on the fixed-size state): its 7th-order
//! dense output locates events two orders more accurately than Dormand-Prince
//! 5(4)'s. The events that end a mode are located on the dense output by a
//! bracketing root search ([`segment::EventLocator`], to 1e-14 s + 1e-15 |t|):
//! touchdown (`z_n = -H`), lift-off (`f_n` reaching 0, i.e. `b = 0` while sliding),
//! `p` reaching 0 while sliding, slip-to-stick (`z_r_dot = 0`), stick-to-slip
//! (`|f_t| = mu f_n`).
//!
//! Discrete transitions:
//! - touchdown: an impact ([`impact::touchdown`]); the tip flies off again if its
//!   normal velocity after the impact exceeds `zeno_velocity`, otherwise the bounce
//!   sequence is ended (*Zeno rule*: the remaining normal velocity is removed, a
//!   completely inelastic last impact, and the tip stays in contact);
//! - in contact with `z_n_dot = 0` the mode follows docs/model.md's table; the
//!   indeterminate case resolves to flight; the inconsistent case (the Painlevé
//!   paradox) is an impact without collision ([`impact::without_collision`]);
//! - every impact is checked for energy: the contact may never create energy
//!   (the work of the impulse on the tip's motion relative to the belt must be
//!   `<= 0`; the arm's kinetic energy itself may grow, fed by the moving belt);
//!   a violation is reported as an [`EventKind::EnergyGain`] event and counted.
//!
//! In contact the state is projected back onto the constraint (`z_n = -H` at the
//! same `z_t` and elbow branch, `z_n_dot = 0`, and `z_r_dot = 0` in sticking) at
//! the end of every segment, so integration error cannot drift the tip into or
//! off the belt.
//!
//! Slip from rest (after slip-to-stick fails or at stick-to-slip) goes in a
//! *consistent* direction: one whose sliding solution accelerates the slip that
//! way, preferring the direction the sticking force points to.
//!
//! Corner case: at rest relative to the belt with no consistent contact force
//! (sticking force outside the cone and no consistent slip, the tip pressed on the
//! belt), or when the contact mode keeps switching at one instant (slip starting
//! and stopping at once because the slip acceleration is zero to rounding), the tip
//! is held stuck with the cone ignored until lift-off or the end of the current
//! `advance` interval, then the contact problem is solved again; one
//! [`EventKind::ConeViolation`] is reported per episode.
#![warn(missing_docs)]

pub mod dop853;
pub mod hermite;
pub mod impact;
pub mod initial;
pub mod ledger;
pub mod moreau_jean;
pub mod observer;
pub mod segment;
pub mod time_scale;
pub mod trig;
pub mod validity;

mod bounds;
mod config;
mod controller;
mod error;
mod events;
mod phase;
mod plant;

#[cfg(test)]
mod corner_reference_tests;
#[cfg(test)]
mod corner_tests;
#[cfg(test)]
mod ledger_tests;

pub use bounds::{MAX_ANGLE, MAX_RATE, PROJECTION_TOLERANCE};
pub use config::{MAX_STEP_RANGE, SimConfig};
pub use controller::{Controller, Hold};
pub use error::SimError;
pub use events::{Counters, EventKind, PlantEvent, StepReport};
pub use ledger::Ledger;
pub use observer::{NoObserver, Observer};
pub use phase::Phase;
pub use plant::bridge::BRIDGE_IMPULSE_LOAD;
pub use plant::{Checkpoint, Plant, Sample, SampleGrid};
pub use validity::Validity;

#[cfg(test)]
mod tests;
