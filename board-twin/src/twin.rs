//! The board twin: the arm application (`arm_app::ArmApp`, the `arm` image's
//! very code) on device models of the reference board, driven by the simulated
//! arm. Per control tick, [`BoardTwin::tick`] sets what the devices sense from the
//! arm's state (the magnets' angles through each encoder's mounting, the forces
//! through the load cell's front end and its noise, the belt's travel), runs the
//! application's tick (bus transactions, `frame::assemble`, the firmware's
//! step, the motor stage), and returns the joint torques the drivers make from
//! the duties, directions and enable it left on the pins.

pub use crate::physics::{ArmState, BusFaults};
use crate::{
    acquisition::TwinAcquisition,
    adc::AdcModel,
    as5047p::As5047pModel,
    counter::CounterModel,
    flash::FlashModel,
    motor_stage::{PinModel, PwmModel, Wire},
    physics::BoardPhysics,
};
use arm_app::{ArmApp, ArmCalibration, ArmIo, ArmParts, IntervalClock, Notice, StartError, Watchdog, button_periods, record::RecordFault};
use board_description::BoardDescription;
use drivers::{Motor, MotorStage};
use firmware::{Config, TickClock, pil::StepClock};
use firmware::{ControlLaw, PaperLaws};

/// The watchdog: counts its feeds on the bench's side (a tick that did not
/// feed it is a hung step).
#[derive(Debug)]
pub struct WatchdogModel {
    feeds: std::rc::Rc<std::cell::Cell<u64>>,
}

impl Watchdog for WatchdogModel {
    fn feed(&mut self) {
        self.feeds.set(self.feeds.get() + 1);
    }
}

/// The twin's step clock: no time passes in a simulated step (every count is 0),
/// so a twin run is a function of its inputs alone.
#[derive(Debug, Clone, Copy, Default)]
pub struct TwinClock;

impl TickClock for TwinClock {
    fn ticks(&self) -> u32 {
        0
    }
    fn ticks_per_second(&self) -> u32 {
        1_000_000
    }
}

impl IntervalClock for TwinClock {
    fn mark(&self) -> u32 {
        0
    }
    fn kind(&self) -> StepClock {
        StepClock::Simulated
    }
}

/// The twin's parts, by type.
#[derive(Debug)]
pub enum TwinIo {}

impl ArmIo for TwinIo {
    type Spi = As5047pModel;
    type Encoders = TwinAcquisition;
    type Adc = AdcModel;
    type Counter = CounterModel;
    type Pwm = PwmModel;
    type Out = PinModel;
    type In = PinModel;
    type Watchdog = WatchdogModel;
    type Clock = TwinClock;
    type Flash = FlashModel;
}

/// Why the twin did not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TwinError {
    /// The board description is invalid.
    #[error("{0}")]
    Board(String),
    /// The motor stage did not come up disabled.
    #[error("the motor stage did not come up disabled")]
    MotorStage,
    /// The settings record could not be written to the flash model.
    #[error("the settings record could not be written: {0:?}")]
    Flash(RecordFault),
    /// The application refused its configuration or calibration.
    #[error("the arm application did not start: {0:?}")]
    Start(StartError),
}

/// The reference board, simulated at the bus level, running the arm
/// application with control law `L` (the paper's laws by default; a law of
/// one's own: [`BoardTwin::for_law`]).
pub struct BoardTwin<L: ControlLaw = PaperLaws> {
    app: ArmApp<TwinIo, L>,
    physics: BoardPhysics,
    feeds: std::rc::Rc<std::cell::Cell<u64>>,
    notices: Vec<Notice>,
    ticks: u64,
}

impl BoardTwin {
    /// [`BoardTwin::for_law`] with the paper's laws.
    ///
    /// # Errors
    /// As [`BoardTwin::for_law`].
    pub fn new(board: BoardDescription, config: Config, cal: &ArmCalibration, seed: u64, load_noise_n: f64) -> Result<Self, TwinError> {
        Self::for_law(board, config, cal, seed, load_noise_n)
    }

    /// [`BoardTwin::with_flash_for_law`] with the paper's laws.
    ///
    /// # Errors
    /// As [`BoardTwin::for_law`].
    pub fn with_flash(
        board: BoardDescription,
        flash: FlashModel,
        config: Config,
        cal: &ArmCalibration,
        seed: u64,
        load_noise_n: f64,
    ) -> Result<Self, TwinError> {
        Self::with_flash_for_law(board, flash, config, cal, seed, load_noise_n)
    }
}

impl<L: ControlLaw> BoardTwin<L> {
    /// A powered board that was brought up: its flash holds the settings record
    /// of the firmware's `config` and calibration `cal` (directions checked),
    /// which the application loads at power-up; load-cell noise of
    /// `load_noise_n` N rms (white, seeded by `seed`, drawn `[f_t, f_n]` per tick
    /// as the wire-level sensor model draws it). The drivers are disabled until
    /// the enable button ([`BoardTwin::press_enable`]).
    ///
    /// # Errors
    /// [`TwinError`]: a bad description, a record that cannot be written, a
    /// motor stage that does not disable, an application that refuses the
    /// configuration or calibration.
    pub fn for_law(board: BoardDescription, config: Config, cal: &ArmCalibration, seed: u64, load_noise_n: f64) -> Result<Self, TwinError> {
        let flash = FlashModel::brought_up(cal, config).map_err(TwinError::Flash)?;
        Self::with_flash_for_law(board, flash, config, cal, seed, load_noise_n)
    }

    /// A powered board whose settings sector is `flash` (erased: a board fresh
    /// from the factory; or a record a test damaged). `config` and `cal` are
    /// the image's compiled-in fallback, in force (drivers locked out) when the
    /// flash holds no valid record. Otherwise as [`BoardTwin::new`].
    ///
    /// # Errors
    /// As [`BoardTwin::new`].
    pub fn with_flash_for_law(
        board: BoardDescription,
        flash: FlashModel,
        config: Config,
        cal: &ArmCalibration,
        seed: u64,
        load_noise_n: f64,
    ) -> Result<Self, TwinError> {
        let physics = BoardPhysics::new(board, seed, load_noise_n).map_err(TwinError::Board)?;
        let bench = physics.bench().clone();
        let feeds = std::rc::Rc::new(std::cell::Cell::new(0));
        let pin = |w| PinModel::new(bench.clone(), w);
        let m1 = Motor::new(PwmModel::new(bench.clone(), 0, board.pwm_max_duty), pin(Wire::Dir1));
        let m2 = Motor::new(PwmModel::new(bench.clone(), 1, board.pwm_max_duty), pin(Wire::Dir2));
        let motors = MotorStage::new(m1, m2, pin(Wire::Enable), pin(Wire::Fault)).map_err(|_| TwinError::MotorStage)?;
        let parts = ArmParts::<TwinIo> {
            theta1: As5047pModel::new(bench.clone(), 0),
            elbow: As5047pModel::new(bench.clone(), 1),
            encoders: TwinAcquisition::new(bench.clone()),
            adc: AdcModel::new(bench.clone()),
            belt: CounterModel::new(bench.clone()),
            motors,
            button: pin(Wire::Button),
            watchdog: WatchdogModel { feeds: feeds.clone() },
            clock: TwinClock,
            flash,
        };
        let mut notices = Vec::new();
        let app = ArmApp::<TwinIo, L>::new(parts, config, cal, &mut |n| notices.push(n)).map_err(TwinError::Start)?;
        Ok(Self { app, physics, feeds, notices, ticks: 0 })
    }

    /// Sets the devices from `arm` and `faults` (with load-cell noise when
    /// `noisy`), then runs one control tick. Returns the joint torques `[u1, u2]`
    /// (N m) the drivers apply until the next tick (zero-order hold).
    pub fn tick(&mut self, arm: &ArmState, faults: &BusFaults, noisy: bool) -> [f64; 2] {
        self.physics.sense(arm, faults, noisy);
        let notices = &mut self.notices;
        self.app.tick(&mut |n| notices.push(n));
        // Between two ticks, as the image's idle loop: the window's report,
        // the next reset's fresh firmware (`ArmApp::idle`).
        if let Some(report) = self.app.idle() {
            self.notices.push(Notice::Window(report));
        }
        self.ticks += 1;
        self.physics.torques(self.physics.board().pwm_max_duty)
    }

    /// The operator's enable, timed so that the firmware's reset lands on the
    /// next tick: one tick with the button released, then `button_periods - 1`
    /// ticks with it held (noise-free readings of `arm`, which stands still);
    /// the button stays held for the next [`BoardTwin::tick`], whose frame is the
    /// first after the reset (the drivers enable at its command), and is released
    /// after it by [`BoardTwin::release_button`].
    pub fn press_enable(&mut self, arm: &ArmState, faults: &BusFaults) {
        self.physics.hold_button(false);
        self.tick(arm, faults, false);
        self.physics.hold_button(true);
        for _ in 1..button_periods(self.period_us()) {
            self.tick(arm, faults, false);
        }
    }

    /// Holds the enable button down (`true`) or lets it go, from the next tick on.
    pub fn press_button(&mut self, held: bool) {
        self.physics.hold_button(held);
    }

    /// Lets the enable button go.
    pub fn release_button(&mut self) {
        self.physics.hold_button(false);
    }

    /// Serves a bring-up request between two ticks, as the image's idle loop
    /// does, then follows a new control rate as the image does
    /// ([`ArmApp::retime`]: the twin's tick is whoever calls [`BoardTwin::tick`],
    /// which paces it by [`BoardTwin::period_us`]).
    pub fn serve(&mut self, request: arm_app::bringup::Request) -> arm_app::bringup::Reply {
        let reply = self.app.serve(request);
        self.app.retime(Some);
        reply
    }

    /// The control period the twin's tick runs, us: the configuration's in
    /// force (the saved record's at power-up, a `Configure` or `Restore`'s since).
    pub fn period_us(&self) -> u64 {
        self.app.tick_period_us()
    }

    /// What the application said since the last call.
    pub fn take_notices(&mut self) -> Vec<Notice> {
        std::mem::take(&mut self.notices)
    }

    /// Whether the drivers are enabled.
    pub fn drivers_enabled(&self) -> bool {
        self.app.drivers_enabled()
    }

    /// Ticks run, and watchdog feeds seen (equal while no step hangs).
    pub fn ticks_and_feeds(&self) -> (u64, u64) {
        (self.ticks, self.feeds.get())
    }

    /// The application (its firmware's counters and estimate).
    pub fn app(&self) -> &ArmApp<TwinIo, L> {
        &self.app
    }

    /// The board description.
    pub fn board(&self) -> &BoardDescription {
        self.physics.board()
    }
}
