//! The errors of the plant simulator ([`SimError`]): bad input (parameters,
//! settings, initial state, step, torque) and failures during a run.

use shared::{IkError, ParamError};

use crate::{
    bounds::{MAX_ANGLE, MAX_RATE},
    impact::ImpactError,
};

/// Errors of the plant simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A physical parameter is out of range.
    #[error(transparent)]
    Params(#[from] ParamError),
    /// A simulator setting is out of range.
    #[error("setting `{name}` = {value} is out of range: expected {expected}")]
    BadConfig {
        /// Field of [`SimConfig`](crate::SimConfig).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// The initial state is not finite.
    #[error("initial state {0:?} is not finite")]
    NonFiniteInitialState([f64; 4]),
    /// The initial state is finite but not a state of the arm: an angle beyond
    /// [`MAX_ANGLE`] or a rate beyond [`MAX_RATE`].
    #[error(
        "initial state {0:?} (rad, rad/s) is not a state of the arm: angles within +-{MAX_ANGLE} rad (10 turns), rates within +-{MAX_RATE} rad/s"
    )]
    NonPhysicalInitialState([f64; 4]),
    /// The initial tip position is below the belt by more than the projection tolerance.
    #[error(
        "initial tip is {depth_mm:.3} mm below the belt (z_n = {z_n:.6} m, belt at -H = {belt:.6} m); at most {tolerance_mm} mm is projected onto it"
    )]
    BelowBelt {
        /// Penetration, mm.
        depth_mm: f64,
        /// Tip normal position, m.
        z_n: f64,
        /// Belt height `-H`, m.
        belt: f64,
        /// Largest penetration projected onto the belt, mm.
        tolerance_mm: f64,
    },
    /// A tip position has no inverse kinematics.
    #[error(transparent)]
    Unreachable(#[from] IkError),
    /// A time step is negative or not finite.
    #[error("time step {0} s must be finite and >= 0")]
    BadStep(f64),
    /// A torque is not finite.
    #[error("torque {0:?} N m is not finite")]
    BadTorque([f64; 2]),
    /// The integrator failed.
    #[error("integrator failed at t = {t} s: {message}")]
    Integrator {
        /// Time, s.
        t: f64,
        /// The integrator's message.
        message: String,
    },
    /// The state became NaN or infinite.
    #[error("state is not finite at t = {t} s (mode {mode})")]
    NonFinite {
        /// Time, s.
        t: f64,
        /// Mode at the time.
        mode: &'static str,
    },
    /// An impact could not be resolved.
    #[error("impact at t = {t} s: {source}")]
    Impact {
        /// Time, s.
        t: f64,
        /// Why.
        source: ImpactError,
    },
    /// A Moreau-Jean bridge across a collapsed step did not converge: at the
    /// smallest step its joint angles still differed from the half-step bridge's
    /// by more than the tolerance (docs/plant.md "The bridge").
    #[error(
        "bridge at t = {t} s did not converge: at a step of {step:e} s its angles differ by {difference:e} rad and its rates by {rate_difference:e} rad/s from the half-step bridge's"
    )]
    Bridge {
        /// Start of the bridge, s.
        t: f64,
        /// The last step tried, s.
        step: f64,
        /// The difference of the joint angles there, rad.
        difference: f64,
        /// The difference of the joint rates there, rad/s.
        rate_difference: f64,
    },
    /// A segment ended outside its mode without the event being located, even with small steps.
    #[error("event missed at t = {t} s in mode {mode}: the segment left its domain between steps")]
    MissedEvent {
        /// Start of the segment, s.
        t: f64,
        /// The mode.
        mode: &'static str,
    },
    /// Too many events in one `advance` (a hang guard).
    #[error("more than {count} events in one interval at t = {t} s: accumulating events the Zeno rule did not end (last: {recent})")]
    EventStorm {
        /// Time, s.
        t: f64,
        /// The limit.
        count: usize,
        /// The last few events, for diagnosis.
        recent: String,
    },
}

impl SimError {
    /// Whether the run failed in the integrator or the event handling (as opposed
    /// to bad input): counted as [`Validity::integrator_failures`](crate::Validity::integrator_failures).
    pub fn is_integrator_failure(&self) -> bool {
        matches!(
            self,
            Self::Integrator { .. }
                | Self::NonFinite { .. }
                | Self::Impact { .. }
                | Self::Bridge { .. }
                | Self::MissedEvent { .. }
                | Self::EventStorm { .. }
        )
    }

    /// Whether the error comes from the caller's input (parameters, settings,
    /// initial state), as opposed to a failure during the run.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            Self::Params(_)
                | Self::BadConfig { .. }
                | Self::NonFiniteInitialState(_)
                | Self::NonPhysicalInitialState(_)
                | Self::BelowBelt { .. }
                | Self::Unreachable(_)
                | Self::BadStep(_)
                | Self::BadTorque(_)
        )
    }
}
