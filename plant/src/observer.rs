//! Observers of a plant's advance: what an analysis needs to see of the
//! continuous trajectory (every accepted integration step with its dense
//! output, the start of each smooth segment, the events) without the plant
//! knowing the analysis. The Poincaré section (`analyses::poincare`) and the
//! sweep's maxima (`analyses::sweep`) are observers.
//!
//! A segment may be integrated more than once: an attempt that misses an event
//! is discarded and retried with smaller steps. Observers see each attempt
//! ([`Observer::on_attempt`], then its steps) and keep what they saw only when
//! the plant keeps the attempt ([`Observer::on_kept`]).

use shared::ContactMode;

use crate::{
    dop853::DenseStep,
    events::PlantEvent,
    segment::{OdeState, STATE_LEN},
};

/// Sees a plant's advance; every method defaults to doing nothing.
///
/// `OdeState` is the integrated state: `[theta1, theta1_dot, theta2, theta2_dot]`
/// (rad, rad/s) and two controller states.
pub trait Observer {
    /// A smooth segment starts at `t` (s) in `mode`, in state `y` (after any
    /// velocity jump: an impact ends one segment and starts the next).
    fn on_segment_start(&mut self, _t: f64, _y: &OdeState, _mode: ContactMode) {}

    /// An attempt at integrating the current segment begins.
    fn on_attempt(&mut self) {}

    /// An accepted step of the current attempt, with its dense output, in
    /// `mode`. `stop`: the time (s) and state of the event that ends the segment
    /// inside this step, if one was located there (the trajectory ends there).
    fn on_step(&mut self, _step: &mut dyn DenseStep<STATE_LEN>, _stop: Option<(f64, OdeState)>, _mode: ContactMode) {}

    /// The index of the next instant of [`crate::Plant::advance_sampling`]'s grid to
    /// sample, if any (the plant's own sampler answers; other observers leave it).
    fn next_sample(&self) -> Option<u64> {
        None
    }

    /// The sample asked for by [`Observer::next_sample`], read from a step of the
    /// current attempt (kept only if the attempt is).
    fn on_sample(&mut self, _sample: &crate::plant::Sample) {}

    /// The plant keeps the current attempt; the segment ended in state `y_end`.
    fn on_kept(&mut self, _y_end: &OdeState, _mode: ContactMode) {}

    /// The advance ended at `t` (s) in state `y` (which may follow an impact at
    /// its very end and so belong to no step).
    fn on_advanced(&mut self, _t: f64, _y: &OdeState) {}

    /// An event of the advance, in time order, at its end.
    fn on_event(&mut self, _event: &PlantEvent) {}
}

/// Sees nothing: an advance with no analysis watching.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoObserver;

impl Observer for NoObserver {}
