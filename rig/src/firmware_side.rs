//! The firmware side of the loop, the same in both transports: the firmware's
//! step with the faults that act on it (a step that starts late), answering a
//! frame with a command and the step's telemetry. The in-process link calls it
//! directly; the firmware process (`sil-host firmware`) calls it for every frame
//! it receives over iceoryx2, so both produce the same commands bit for bit.

use firmware::{Firmware, TickClock};
use shared::{
    time::Instant,
    wire::{ActuatorCommand, FirmwareTelemetry, SensorFrame},
};

use super::{faults::FaultPlan, record::RunError, scenario::Scenario, setup::firmware_config};

/// The firmware and the faults injected on its side.
#[derive(Debug, Clone)]
pub struct FirmwareSide {
    fw: Firmware,
    faults: FaultPlan,
}

impl FirmwareSide {
    /// The firmware a scenario asks for.
    ///
    /// # Errors
    /// [`RunError::Firmware`] for an invalid configuration.
    pub fn new(s: &Scenario) -> Result<Self, RunError> {
        let fw = Firmware::new(firmware_config(s))?;
        Ok(Self { fw, faults: FaultPlan::new(&s.faults, s.timing.period()) })
    }

    /// The firmware.
    pub fn firmware(&self) -> &Firmware {
        &self.fw
    }

    /// The firmware, mutably (the process loop latches the safe state when its peer dies).
    pub fn firmware_mut(&mut self) -> &mut Firmware {
        &mut self.fw
    }

    /// Answers `frame`. The step starts at `max(frame.t_us + injected delay,
    /// now_floor)` on the frame's clock: `now_floor` is what the caller's clock
    /// says (the newest frame seen in lockstep, the wall clock in real time).
    pub fn answer<C: TickClock>(&mut self, frame: &SensorFrame, now_floor: Instant, clock: &C) -> (ActuatorCommand, FirmwareTelemetry) {
        let now = step_start(&self.faults, frame, now_floor);
        let command = self.fw.step(now, frame, clock);
        (command, self.fw.telemetry_message(&command))
    }
}

/// When the step of `frame` starts, on the frame's clock:
/// `max(frame.t_us + injected delay, now_floor)` (the `late_command` fault).
pub fn step_start(faults: &FaultPlan, frame: &SensorFrame, now_floor: Instant) -> Instant {
    let delay = faults.command_delay(u64::from(frame.seq));
    frame.sampled_at().saturating_add(delay).max(now_floor)
}
