//! The arm hanging free over a lowered belt, sensed and driven by its board
//! (the board twin, [`TwinBench`], or the emulated `arm` image,
//! `board_emulator::EmulatedBoard`: [`ArmBoard`]): what bring-up runs against
//! in CI (docs/board.md "Bring-up"). The
//! procedure asks for the belt lowered below the hanging tip; here the base
//! stands 0.4199 m above it (within the arm's 0.42 m reach, so the simulator
//! takes it), and the arm at rest, its elbow bent by the spring between the
//! links, clears it by a few millimetres; a jog lifts the tip. For the first
//! enable and closed-loop run (steps 7 and 8) the belt is raised to the tip
//! ([`FreeArm::move_belt`], `belt up` on `board-twin`'s standard input): the arm
//! stands at the scenario's initial state with its tip on the belt, which runs at
//! the scenario's `v_belt`, held there while the drivers are off.

use arm_app::bringup::Request;
use board_emulator::{ArmImage, EmulatedBoard, SpiFaults, core_clock::Mode};
use board_twin::{ArmState, BoardDescription, BoardTwin, BusFaults, FlashModel, TwinError};
use firmware::pil::{FrameBuffer, MAX_FRAME, Push, decode, encode};
use plant::{Hold, NoObserver, Plant, SimConfig, SimError};
use shared::wire::encode_angle;

use rig::{
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
    /// The emulated board stopped (an image misconfiguring the board, a bus fault, ...).
    #[error("the emulated board: {0}")]
    Emulated(String),
}

/// What the hanging arm is wired to: a board that senses it and drives its
/// joints every period, and serves the bring-up line between two ticks.
pub trait ArmBoard {
    /// One control tick: the devices sense `arm` (with `faults` on the bus);
    /// returns the joint torques `[u1, u2]`, N m, until the next tick.
    ///
    /// # Errors
    /// The board's failure, in words.
    fn tick(&mut self, arm: &ArmState, faults: &BusFaults) -> Result<[f64; 2], String>;
    /// Bytes from the host on USART1; returns the bytes the board sent since.
    fn line(&mut self, from_host: &[u8]) -> Vec<u8>;
    /// The reset button (NRST) pressed and released: the MCU starts again
    /// from its flash, the saved record reloaded (the drivers locked out until
    /// an enable), the devices sensing `arm`.
    ///
    /// # Errors
    /// The board's failure to come back, in words.
    fn reset(&mut self, arm: &ArmState) -> Result<(), String>;
    /// Whether the motor drivers are enabled after the last tick.
    fn drivers_enabled(&self) -> bool;
    /// The control period the board's tick runs now, us (it follows the
    /// configuration in force: a `Configure` of another rate changes it,
    /// `arm_app::rate`).
    fn period_us(&self) -> u64;
}

/// The board twin with the image's idle loop: requests out of the line's frames.
pub struct TwinBench {
    twin: BoardTwin,
    /// The twin again from the same flash (its reset).
    restart: Box<dyn Fn() -> Result<BoardTwin, TwinError>>,
    frames: FrameBuffer,
    replies: Vec<u8>,
}

impl ArmBoard for TwinBench {
    fn tick(&mut self, arm: &ArmState, faults: &BusFaults) -> Result<[f64; 2], String> {
        Ok(self.twin.tick(arm, faults, true))
    }

    fn line(&mut self, from_host: &[u8]) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        for &b in from_host {
            if let Push::Frame(f) = self.frames.push(b)
                && let Ok(request) = decode::<Request>(f)
            {
                let reply = self.twin.serve(request);
                if let Ok(bytes) = encode(&reply, &mut out) {
                    self.replies.extend_from_slice(bytes);
                }
            }
        }
        std::mem::take(&mut self.replies)
    }

    fn reset(&mut self, _arm: &ArmState) -> Result<(), String> {
        self.twin = (self.restart)().map_err(|e| e.to_string())?;
        self.frames = FrameBuffer::default();
        self.replies.clear();
        Ok(())
    }

    fn drivers_enabled(&self) -> bool {
        self.twin.drivers_enabled()
    }

    fn period_us(&self) -> u64 {
        self.twin.period_us()
    }
}

impl ArmBoard for EmulatedBoard {
    fn tick(&mut self, arm: &ArmState, faults: &BusFaults) -> Result<[f64; 2], String> {
        EmulatedBoard::tick(self, arm, faults, SpiFaults::default(), true).map_err(|e| e.to_string())
    }

    fn line(&mut self, from_host: &[u8]) -> Vec<u8> {
        self.send(from_host);
        self.take_sent()
    }

    fn reset(&mut self, arm: &ArmState) -> Result<(), String> {
        EmulatedBoard::reset(self, arm).map(|_| ()).map_err(|e| e.to_string())
    }

    fn drivers_enabled(&self) -> bool {
        // The image's monitor block, as a debug probe reads it.
        self.monitor().is_some_and(|m| m.drivers_enabled != 0)
    }

    fn period_us(&self) -> u64 {
        self.period_ns() / 1000
    }
}

/// The arm, its board, and the board's application or image.
pub struct FreeArm<B: ArmBoard = TwinBench> {
    plant: Plant,
    board: B,
    u: [f64; 2],
    sensed: [f64; 4],
    faults: BusFaults,
    /// A known load hung on the load cell `[f_t, f_n]`, N (a weight for the span).
    load: Load,
    /// The reset button, pressed by whoever holds it: the next tick resets first.
    reset_button: ResetButton,
    /// The belt's position asked by whoever moves it (`true`: raised to the tip).
    belt: BeltLift,
    /// The belt's position now.
    raised: bool,
    /// The belt's travel, m (its encoder's count): it runs while raised.
    belt_travel_m: f64,
    /// The scenario: its plant at its initial state is the arm on the raised belt.
    scenario: Box<Scenario>,
}

/// The belt's lift, shared with whoever works it (the twin's operator on its
/// standard input, `belt up` and `belt down`): `true` raises the belt to the
/// tip from the next tick on, `false` lowers it below the hanging tip.
pub type BeltLift = std::sync::Arc<std::sync::atomic::AtomicBool>;

/// The reset button (NRST), shared with whoever presses it (the twin's
/// operator on its standard input): `true` until the next tick takes it.
pub type ResetButton = std::sync::Arc<std::sync::atomic::AtomicBool>;

/// A known load on the load cell `[f_t, f_n]`, N, shared with whoever hangs it
/// (the twin's operator on its standard input).
pub type Load = std::sync::Arc<std::sync::Mutex<[f64; 2]>>;

/// The plant of the hanging arm of scenario `s`, from an elbow bent clear of the belt.
fn hanging_plant(s: &Scenario) -> Result<Plant, SimError> {
    let params = shared::Params { h: LOWERED_BELT_H, ..plant_params(s) };
    Plant::new(params, SimConfig::default(), [0.0, 0.0, 0.3, 0.0], 0.0, [0.0; 2])
}

impl FreeArm<EmulatedBoard> {
    /// The arm of scenario `s` on the emulated board `board` running the `arm`
    /// ELF at `image`, its settings sector `flash`. The arm first comes to rest
    /// for [`SETTLE_S`] with the board unpowered (no torque: as the twin's
    /// drivers, disabled until an enable), then the image boots.
    ///
    /// # Errors
    /// [`FreeArmError`]: the plant, an image that cannot be read, a board that
    /// does not boot.
    pub fn emulated(s: &Scenario, board: BoardDescription, flash: &FlashModel, image: &std::path::Path) -> Result<Self, FreeArmError> {
        let arm_image = ArmImage::load(image).map_err(|e| FreeArmError::Emulated(e.to_string()))?;
        let sector = flash.bytes().borrow().clone();
        let period_ns = s.timing.period().as_us() * 1000;
        let mut emulated =
            EmulatedBoard::new(arm_image, board, &sector, period_ns, s.sensors.seed, s.sensors.load_noise_n, Mode::Functional)
                .map_err(|e| FreeArmError::Emulated(e.to_string()))?;
        let mut plant = hanging_plant(s)?;
        plant.advance(&Hold([0.0; 2]), SETTLE_S, &mut NoObserver)?;
        let sensed = plant.state();
        let arm = ArmState { x: sensed, f: plant.contact_force([0.0; 2]), belt_travel_m: 0.0 };
        emulated.boot(&arm).map_err(|e| FreeArmError::Emulated(e.to_string()))?;
        Ok(Self {
            plant,
            board: emulated,
            u: [0.0; 2],
            sensed,
            faults: BusFaults::default(),
            load: Load::default(),
            reset_button: ResetButton::default(),
            belt: BeltLift::default(),
            raised: false,
            belt_travel_m: 0.0,
            scenario: Box::new(s.clone()),
        })
    }
}

impl FreeArm<TwinBench> {
    /// The arm of scenario `s` (its parameters, its firmware configuration and
    /// sensors' seed) on board `board` with the firmware's calibration `cal`,
    /// hanging over the lowered belt, after [`SETTLE_S`] of rest.
    ///
    /// # Errors
    /// [`FreeArmError`] when the plant or the twin refuses its set-up.
    pub fn new(s: &Scenario, board: BoardDescription, cal: &CalibrationSection) -> Result<Self, FreeArmError> {
        let flash = FlashModel::brought_up(&cal.arm_calibration(), firmware_config(s)).map_err(TwinError::Flash)?;
        Self::with_flash(s, board, cal, flash)
    }

    /// As [`FreeArm::new`], the board's settings sector being `flash` (erased:
    /// a board fresh from the factory; a damaged record; a record saved by an
    /// earlier bench, for a power cycle). `cal` and the scenario's configuration
    /// are the image's compiled-in fallback.
    ///
    /// # Errors
    /// As [`FreeArm::new`].
    pub fn with_flash(s: &Scenario, board: BoardDescription, cal: &CalibrationSection, flash: FlashModel) -> Result<Self, FreeArmError> {
        let (config, arm_cal, seed, noise) = (firmware_config(s), cal.arm_calibration(), s.sensors.seed, s.sensors.load_noise_n);
        // The flash's bytes are shared: a reset reads what the last save wrote.
        let restart = move || BoardTwin::with_flash(board, flash.clone(), config, &arm_cal, seed, noise);
        let twin = restart()?;
        let plant = hanging_plant(s)?;
        let board = TwinBench { twin, restart: Box::new(restart), frames: FrameBuffer::default(), replies: Vec::new() };
        let mut arm = Self {
            plant,
            board,
            u: [0.0; 2],
            sensed: [0.0; 4],
            faults: BusFaults::default(),
            load: Load::default(),
            reset_button: ResetButton::default(),
            belt: BeltLift::default(),
            raised: false,
            belt_travel_m: 0.0,
            scenario: Box::new(s.clone()),
        };
        let ts = arm.period_s();
        arm.ticks((SETTLE_S / ts).round() as usize)?;
        Ok(arm)
    }

    /// The twin.
    pub fn twin(&self) -> &BoardTwin {
        &self.board.twin
    }

    /// The twin, to serve requests between ticks.
    pub fn twin_mut(&mut self) -> &mut BoardTwin {
        &mut self.board.twin
    }
}

impl<B: ArmBoard> FreeArm<B> {
    /// The control period the board runs now, s ([`ArmBoard::period_us`]):
    /// each tick advances the arm by it.
    pub fn period_s(&self) -> f64 {
        self.board.period_us() as f64 * 1e-6
    }

    /// One period of the board's (its period now: [`FreeArm::period_s`]): the
    /// devices sense the arm, the tick runs, the arm moves.
    ///
    /// # Errors
    /// [`FreeArmError`] when the plant or the board fails.
    pub fn tick(&mut self) -> Result<(), FreeArmError> {
        if self.reset_button.swap(false, std::sync::atomic::Ordering::Relaxed) {
            self.reset()?;
        }
        let raise = self.belt.load(std::sync::atomic::Ordering::Relaxed);
        if raise != self.raised {
            self.move_belt(raise)?;
        }
        self.sensed = self.plant.state();
        let load = *self.load.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let f = self.plant.contact_force(self.u);
        let arm = ArmState { x: self.sensed, f: [f[0] + load[0], f[1] + load[1]], belt_travel_m: self.belt_travel_m };
        // The period this tick runs: a request served during the last one may
        // have changed it (`Configure` of another rate).
        let ts = self.period_s();
        self.u = self.board.tick(&arm, &self.faults).map_err(FreeArmError::Emulated)?;
        if self.raised {
            self.belt_travel_m += self.scenario.plant.v_belt * ts;
            // On the raised belt the operator holds the arm at its pose while the
            // drivers are off (as before a run's enable, docs/board.md "The board
            // twin"); it moves under the drivers' torques once they are on.
            if !self.board.drivers_enabled() {
                return Ok(());
            }
        }
        self.plant.advance(&Hold(self.u), ts, &mut NoObserver)?;
        Ok(())
    }

    /// Raises the belt to the tip (`true`: the arm stood at the scenario's
    /// initial state with its tip on the belt, which runs at the scenario's
    /// `v_belt`: docs/board.md "Bring-up", step 7) or lowers it below the
    /// hanging tip (`false`: the arm left where it is, at rest).
    ///
    /// # Errors
    /// [`FreeArmError::Sim`] when the plant refuses the new set-up.
    pub fn move_belt(&mut self, raise: bool) -> Result<(), FreeArmError> {
        self.plant = if raise {
            rig::setup::plant_for(&self.scenario)?
        } else {
            let x = self.plant.state();
            let params = shared::Params { h: LOWERED_BELT_H, ..plant_params(&self.scenario) };
            Plant::new(params, SimConfig::default(), [x[0], 0.0, x[2], 0.0], 0.0, [0.0; 2])?
        };
        // The belt's counter goes on from where it was (an encoder counts edges,
        // it never jumps).
        self.raised = raise;
        self.belt.store(raise, std::sync::atomic::Ordering::Relaxed);
        Ok(())
    }

    /// The belt's lift, to work from another thread: the next tick raises or
    /// lowers the belt ([`FreeArm::move_belt`]).
    pub fn belt_lift(&self) -> BeltLift {
        self.belt.clone()
    }

    /// Whether the belt is raised to the tip.
    pub fn belt_raised(&self) -> bool {
        self.raised
    }

    /// `n` periods.
    ///
    /// # Errors
    /// As [`FreeArm::tick`].
    pub fn ticks(&mut self, n: usize) -> Result<(), FreeArmError> {
        (0..n).try_for_each(|_| self.tick())
    }

    /// Bytes from the host on the bring-up line; the board's bytes since.
    pub fn line(&mut self, from_host: &[u8]) -> Vec<u8> {
        self.board.line(from_host)
    }

    /// The board.
    pub fn board(&self) -> &B {
        &self.board
    }

    /// The board, mutable.
    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }

    /// The pose's joint counts `[theta1, theta2 - theta1]` at the last tick (2^14
    /// per turn): what the calibration jig's drawing gives.
    pub fn pose_counts(&self) -> [u16; 2] {
        let x = self.sensed;
        [x[0], x[2] - x[0]].map(encode_angle)
    }

    /// The load on the load cell, to hang a known weight for the span
    /// (`[f_t, f_n]`, N; the arm itself is not moved by it: the weight hangs on
    /// the cell's hook, as docs/board.md "Bring-up" step 4 asks).
    pub fn load(&self) -> Load {
        self.load.clone()
    }

    /// The reset button, to press from another thread: the next tick resets
    /// the board first ([`FreeArm::reset`]).
    pub fn reset_button(&self) -> ResetButton {
        self.reset_button.clone()
    }

    /// The reset button (NRST): the board restarts from its flash
    /// ([`ArmBoard::reset`]), the arm where it hangs.
    ///
    /// # Errors
    /// [`FreeArmError::Emulated`] with the board's failure to come back.
    pub fn reset(&mut self) -> Result<(), FreeArmError> {
        self.sensed = self.plant.state();
        let arm = ArmState { x: self.sensed, f: self.plant.contact_force([0.0; 2]), belt_travel_m: 0.0 };
        self.u = [0.0; 2];
        self.board.reset(&arm).map_err(FreeArmError::Emulated)
    }

    /// Holds `faults` on the bus from the next tick on (an asserted fault line,
    /// a magnet lost, ...).
    pub fn set_faults(&mut self, faults: BusFaults) {
        self.faults = faults;
    }
}
