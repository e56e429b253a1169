//! The per-period step (being written).

use crate::{TickClock, config::Config};
use shared::wire::{ActuatorCommand, SensorFrame};

/// The firmware's state across periods.
#[derive(Debug, Clone)]
pub struct Firmware {
    cfg: Config,
}

impl Firmware {
    /// A firmware instance with configuration `cfg`.
    pub fn new(cfg: Config) -> Self {
        Self { cfg }
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// One control period: decode `frame` (received at `now_us`), estimate, detect
    /// lift-off, run the control law, encode the command.
    pub fn step<C: TickClock>(&mut self, now_us: u64, frame: &SensorFrame, clock: &C) -> ActuatorCommand {
        let _ = (now_us, clock);
        ActuatorCommand { seq: frame.seq, ..ActuatorCommand::default() }
    }
}
