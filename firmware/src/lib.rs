//! The arm's control firmware: `no_std`, heap-free, control maths in `f32`.
//!
//! One function per control period, time passed in and hardware behind traits:
//! [`Firmware::step`] takes a [`SensorFrame`] of raw counts and returns an
//! [`ActuatorCommand`] of torque codes and a status word. The same code runs on
//! the host (SIL rig, tests) and on the Cortex-M4F (`boards/stm32f405`: the
//! `arm` and `pil` images), every board through [`board::handle`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

// clap's derives name `::std` (host-only feature).
#[cfg(all(feature = "clap", not(test)))]
extern crate std;

pub mod announce;
pub mod belt_check;
pub mod board;
pub mod chatter;
pub mod config;
pub mod consistency;
pub mod control_law;
pub mod controller;
pub mod decode;
pub mod estimator;
mod finite;
pub mod law;
pub mod law_params;
pub mod law_spec;
pub mod liftoff;
pub mod mu_estimate;
pub mod paper_laws;
pub mod pil;
pub mod reference;
pub mod runaway;
pub mod tick_clock;
pub mod tracking;
pub mod wiring;

#[cfg(test)]
mod tests;

pub use board::{Board, Event, Outcome};
pub use config::{Config, ControllerKind};
pub use control_law::{ControlLaw, Declares, LawContext, LawInput, LawOutput, TrackingDynamics};
pub use controller::{Firmware, SafeReason, Telemetry};
pub use law_spec::{LawName, LawParams, LawSpec, ParamSpec};
pub use paper_laws::{HybridLaw, PaperLaws, PidLaw};
pub use shared;
pub use shared::wire::{ActuatorCommand, SensorFrame};
pub use tick_clock::TickClock;

/// The model in the firmware's scalar type: the paper's parameters in `f32`.
pub fn paper_arm() -> shared::Arm<f32> {
    shared::Arm::new(shared::Params::paper())
}
