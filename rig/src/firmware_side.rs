//! The firmware side of the loop, the same in both transports: the firmware's
//! step with the faults that act on it (a step that starts late), answering a
//! frame with a command and the step's telemetry. The in-process link calls
//! [`FirmwareSide::answer`]; the firmware process (`sil-host firmware`) starts
//! each step at [`step_start`] on its own board, so both produce the same
//! commands bit for bit.
//!
//! The step goes through [`firmware::board::handle`], the one path every image
//! and the firmware process take: the in-process side is a [`Board`] whose event
//! is the frame, whose clock says when the step starts ([`step_start`]) and
//! which keeps the command it is told to write.

use std::convert::Infallible;

use firmware::{
    ControlLaw, Event, Firmware, Outcome, PaperLaws, TickClock,
    board::{self, Board},
};
use shared::{
    time::Instant,
    wire::{ActuatorCommand, FirmwareTelemetry, SensorFrame},
};

use super::{faults::FaultPlan, record::RunError, setup::RunSetup};

/// The firmware running law `L` (the paper's laws by default) and the faults
/// injected on its side.
#[derive(Debug, Clone)]
pub struct FirmwareSide<L: ControlLaw = PaperLaws> {
    /// Always `Some` ([`CONFIGURED`]): [`board::handle`] takes the firmware as a
    /// board holds it, none until a configuration arrives.
    fw: Option<Firmware<L>>,
    faults: FaultPlan,
}

impl FirmwareSide {
    /// The firmware a scenario asks for, running the paper's laws
    /// ([`FirmwareSide::for_law`]).
    ///
    /// # Errors
    /// As [`FirmwareSide::for_law`].
    pub fn new(setup: &RunSetup) -> Result<Self, RunError> {
        Self::for_law(setup)
    }
}

impl<L: ControlLaw> FirmwareSide<L> {
    /// The firmware a scenario asks for running law `L`, its `[law]` table
    /// bound to what `L` declares ([`RunSetup::firmware_for`]).
    ///
    /// # Errors
    /// [`RunError::Firmware`] for an invalid configuration, [`RunError::Law`]
    /// for a `[law]` table that does not fit `L`.
    pub fn for_law(setup: &RunSetup) -> Result<Self, RunError> {
        let fw = Firmware::<L>::with_law(setup.firmware_for(&crate::law::LawDescription::of(&L::SPEC))?)?;
        Ok(Self { fw: Some(fw), faults: setup.faults().clone() })
    }

    /// The firmware.
    pub fn firmware(&self) -> &Firmware<L> {
        self.fw.as_ref().unwrap_or_else(|| unreachable!("{CONFIGURED}"))
    }

    /// The firmware, mutably (the process loop latches the safe state when its peer dies).
    pub fn firmware_mut(&mut self) -> &mut Firmware<L> {
        self.fw.as_mut().unwrap_or_else(|| unreachable!("{CONFIGURED}"))
    }

    /// Answers `frame` through [`board::handle`]. The step starts at
    /// `max(frame.t_us + injected delay, now_floor)` on the frame's clock:
    /// `now_floor` is what the caller's clock says (the newest frame seen in
    /// lockstep, the wall clock in real time).
    pub fn answer<C: TickClock>(&mut self, frame: &SensorFrame, now_floor: Instant, clock: &C) -> (ActuatorCommand, FirmwareTelemetry) {
        let mut board = StepBoard { frame: *frame, now: step_start(&self.faults, frame, now_floor), answer: None };
        let Ok(event) = board.next_event();
        let Ok(_) = board::handle(&mut self.fw, event, &mut board, clock);
        // A configured firmware answers every frame with a command.
        board.answer.unwrap_or_else(|| unreachable!("{CONFIGURED}"))
    }
}

/// Why [`FirmwareSide`]'s firmware is always there: [`FirmwareSide::new`]
/// configures it, and [`board::handle`] only ever replaces it on a new
/// configuration, which this side never receives.
const CONFIGURED: &str = "a firmware side is configured from the start";

/// The board of one in-process step: its one event is the frame, its clock
/// says when the step starts, and it keeps the command it is told to write
/// with the step's telemetry.
struct StepBoard {
    frame: SensorFrame,
    now: Instant,
    answer: Option<(ActuatorCommand, FirmwareTelemetry)>,
}

impl Board for StepBoard {
    type Error = Infallible;

    fn next_event(&mut self) -> Result<Event, Infallible> {
        Ok(Event::Frame(self.frame))
    }

    fn now(&self) -> Instant {
        self.now
    }

    fn apply<L: ControlLaw>(&mut self, outcome: &Outcome, firmware: Option<&Firmware<L>>) -> Result<(), Infallible> {
        if let (Outcome::Command(command), Some(fw)) = (outcome, firmware) {
            self.answer = Some((*command, fw.telemetry_message(command)));
        }
        Ok(())
    }
}

/// When the step of `frame` starts, on the frame's clock:
/// `max(frame.t_us + injected delay, now_floor)` (the `late_command` fault).
pub fn step_start(faults: &FaultPlan, frame: &SensorFrame, now_floor: Instant) -> Instant {
    let delay = faults.command_delay(u64::from(frame.seq));
    frame.sampled_at().saturating_add(delay).max(now_floor)
}
