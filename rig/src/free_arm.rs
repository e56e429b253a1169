//! The arm hanging free over a lowered belt, sensed and driven by the board
//! twin: what bring-up runs against in CI (docs/board.md "Bring-up"). The
//! procedure asks for the belt lowered below the hanging tip; here the base
//! stands 0.4199 m above it (within the arm's 0.42 m reach, so the simulator
//! takes it), and the arm at rest, its elbow bent by the spring between the
//! links, clears it by a few millimetres; a jog lifts the tip.

use board_twin::{ArmState, BoardDescription, BoardTwin, BusFaults, FlashModel, TwinError};
use plant::{Hold, NoObserver, Plant, SimConfig, SimError};
use shared::wire::encode_angle;

use crate::{
    calibration::CalibrationSection,
    scenario::Scenario,
    setup::{firmware_config, plant_params},
};

/// The base's height above the lowered belt, m.
pub const LOWERED_BELT_H: f64 = 0.4199;
/// Simulated time the arm is left to come to rest before bring-up, s (the
/// light joint damping needs tens of seconds).
pub const SETTLE_S: f64 = 40.0;

/// Why the bench did not start.
#[derive(Debug, thiserror::Error)]
pub enum FreeArmError {
    /// The plant refused its set-up or failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The twin did not start.
    #[error(transparent)]
    Twin(#[from] TwinError),
}

/// The arm, its board, and the twin on it.
pub struct FreeArm {
    plant: Plant,
    twin: BoardTwin,
    u: [f64; 2],
    ts: f64,
    sensed: [f64; 4],
    faults: BusFaults,
}

impl FreeArm {
    /// The arm of scenario `s` (its parameters, its firmware configuration and
    /// sensors' seed) on board `board` with the firmware's calibration `cal`,
    /// hanging over the lowered belt, after [`SETTLE_S`] of rest.
    ///
    /// # Errors
    /// [`FreeArmError`] when the plant or the twin refuses its set-up.
    pub fn new(s: &Scenario, board: BoardDescription, cal: &CalibrationSection) -> Result<Self, FreeArmError> {
        let twin = BoardTwin::new(board, firmware_config(s), &cal.arm_calibration(), s.sensors.seed, s.sensors.load_noise_n)?;
        Self::start(s, twin)
    }

    /// As [`FreeArm::new`], the board's settings sector being `flash` (erased:
    /// a board fresh from the factory; a damaged record; a record saved by an
    /// earlier bench, for a power cycle). `cal` and the scenario's configuration
    /// are the image's compiled-in fallback.
    ///
    /// # Errors
    /// As [`FreeArm::new`].
    pub fn with_flash(s: &Scenario, board: BoardDescription, cal: &CalibrationSection, flash: FlashModel) -> Result<Self, FreeArmError> {
        let twin = BoardTwin::with_flash(board, flash, firmware_config(s), &cal.arm_calibration(), s.sensors.seed, s.sensors.load_noise_n)?;
        Self::start(s, twin)
    }

    fn start(s: &Scenario, twin: BoardTwin) -> Result<Self, FreeArmError> {
        let params = shared::Params { h: LOWERED_BELT_H, ..plant_params(s) };
        // From an elbow bent clear of the belt.
        let plant = Plant::new(params, SimConfig::default(), [0.0, 0.0, 0.3, 0.0], 0.0, [0.0; 2])?;
        let ts = s.timing.period().as_secs_f64();
        let mut arm = Self { plant, twin, u: [0.0; 2], ts, sensed: [0.0; 4], faults: BusFaults::default() };
        arm.ticks((SETTLE_S / ts).round() as usize)?;
        Ok(arm)
    }

    /// One period: the devices sense the arm, the tick runs, the arm moves.
    ///
    /// # Errors
    /// [`SimError`] when the plant fails.
    pub fn tick(&mut self) -> Result<(), SimError> {
        self.sensed = self.plant.state();
        let arm = ArmState { x: self.sensed, f: self.plant.contact_force(self.u), belt_travel_m: 0.0 };
        self.u = self.twin.tick(&arm, &self.faults, true);
        self.plant.advance(&Hold(self.u), self.ts, &mut NoObserver)?;
        Ok(())
    }

    /// `n` periods.
    ///
    /// # Errors
    /// As [`FreeArm::tick`].
    pub fn ticks(&mut self, n: usize) -> Result<(), SimError> {
        (0..n).try_for_each(|_| self.tick())
    }

    /// The pose's joint counts `[theta1, theta2 - theta1]` at the last tick (2^14
    /// per turn): what the calibration jig's drawing gives.
    pub fn pose_counts(&self) -> [u16; 2] {
        let x = self.sensed;
        [x[0], x[2] - x[0]].map(encode_angle)
    }

    /// Holds `faults` on the bus from the next tick on (an asserted fault line,
    /// a magnet lost, ...).
    pub fn set_faults(&mut self, faults: BusFaults) {
        self.faults = faults;
    }

    /// The twin.
    pub fn twin(&self) -> &BoardTwin {
        &self.twin
    }

    /// The twin, to serve requests between ticks.
    pub fn twin_mut(&mut self) -> &mut BoardTwin {
        &mut self.twin
    }
}
