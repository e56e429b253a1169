//! The emulated image as a link (`sil-host run --link emulator`; docs/board.md
//! "The emulated image"): the unmodified `arm` ELF (profile `mcu`, the bytes an
//! engineer flashes) on the emulated reference board (`board_emulator`), the
//! plant in lockstep. As on the board twin ([`crate::twin_link`]) the plant's
//! true state drives the board's devices (the same models), but here the
//! image's own register code samples them (SPI1 frames, ADC1's injected
//! conversions on TIM2's TRGO, TIM4's quadrature count) and its PWM, direction
//! and enable pins make the joint torques.
//!
//! Before period 0 the image boots (its clock tree, pins, the settings record
//! from flash, the encoders' check) and the operator presses the enable button
//! as on the twin: 20 ticks with the arm standing at its initial state, so
//! that the firmware's reset lands on period 0. The command and telemetry of
//! each tick are read from the image's monitor block (`arm_app::monitor`), as a
//! debug probe reads them.

use std::path::{Path, PathBuf};

use arm_app::button_periods;
use board_emulator::{
    ArmImage, EmuError, EmulatedBoard, SpiFaults,
    core_clock::{HandlerRun, Mode},
};
use board_twin::{ArmState, BusFaults, FlashModel};
use shared::wire::{ActuatorCommand, GroundTruth, SensorFrame};

use rig::{
    faults::{FaultPlan, LinkKind},
    link::{Exchange, FirmwareLink},
    record::RunError,
    setup::RunSetup,
};

use crate::twin_link::bus_faults;

/// The control periods the `arm` image runs, us: TIM2's reload comes from the
/// configuration in its settings record (issue 56), any whole number of
/// microseconds from 100 (10 kHz) to 4 000 (250 Hz), docs/hardware.md "Timing"
/// (`arm_app::rate`, the one statement the image and the host share; the
/// image refuses to start outside them).
pub const IMAGE_PERIODS_US: std::ops::RangeInclusive<u64> = arm_app::rate::MIN_PERIOD_US..=arm_app::rate::MAX_PERIOD_US;

/// Where `run --link emulator` looks for the image by default: the `mcu`
/// profile's output next to this executable's target folder, else in the
/// workspace this crate was built from.
pub fn default_image() -> PathBuf {
    rig::image_path::beside_this_executable(Path::new("thumbv7em-none-eabihf/mcu/arm"))
}

/// How to build the image (for error messages).
pub const BUILD_HINT: &str = "cargo build -p board-stm32f405 --profile mcu --target thumbv7em-none-eabihf --bin arm";

/// The emulated board behind the rig's link.
pub struct EmulatorLink {
    board: EmulatedBoard,
    plan: FaultPlan,
    v_belt: f64,
    period_us: u64,
    started: bool,
    torque: [f64; 2],
    announced: rig::handshake::Announced,
    /// The image's ticks counted by its monitor block at the last exchange.
    last_ticks: Option<u32>,
    /// The image's defmt frames (RTT), for its log.
    pub rtt: Vec<u8>,
    /// The image's path.
    pub image: PathBuf,
    /// Which image was loaded: its absolute path, bytes of flash and CRC-32
    /// (`board_emulator::image::ArmImage::describe`), for the run's log.
    pub loaded: String,
    /// Every run of TIM2's handler from period 0 on ([`Mode::Counted`]).
    pub handlers: Vec<HandlerRun>,
    /// The handler's runs before period 0 ([`Mode::Counted`]): the boot's tick
    /// and the enable button's held ticks, the drivers still off (the worst-case
    /// bound covers them too: `board-link/tests/board/emulator_bound.rs`).
    pub start_handlers: Vec<HandlerRun>,
}

fn board_error(e: EmuError) -> RunError {
    RunError::Board(e.to_string())
}

impl EmulatorLink {
    /// The emulated board of scenario `s` running the image at `image`: the
    /// scenario's `[board]`, its calibration and firmware configuration saved
    /// in the flash record (a board brought up), its sensors' seed and
    /// load-cell noise.
    ///
    /// # Errors
    /// [`RunError::NotOnABoard`] for the runaway limits off (a board never runs
    /// without them); [`RunError::Unsupported`] for a fault the emulator cannot inject;
    /// [`RunError::Board`] for an image that cannot be read, a rate other than
    /// the image's, a board or calibration refused.
    pub fn new(setup: &RunSetup, image: &Path) -> Result<Self, RunError> {
        Self::with_mode(setup, image, Mode::Functional)
    }

    /// As [`EmulatorLink::new`], the core run in `mode`: [`Mode::Counted`]
    /// counts every instruction of TIM2's handler ([`EmulatorLink::handlers`];
    /// about 3 times slower), with the same trace.
    ///
    /// # Errors
    /// As [`EmulatorLink::new`].
    pub fn with_mode(setup: &RunSetup, image: &Path, mode: Mode) -> Result<Self, RunError> {
        let s = setup.scenario();
        LinkKind::Emulator.check(&s.faults)?;
        rig::board_protection::check_protection(setup.firmware(), "controller.runaway_limits").map_err(RunError::NotOnABoard)?;
        s.calibration.check(s.timing.period().as_secs_f32()).map_err(RunError::Board)?;
        let period_us = s.timing.period().as_us();
        if !IMAGE_PERIODS_US.contains(&period_us) {
            return Err(RunError::Board(format!(
                "the `arm` image runs control periods of {} (TIM2's reload from the saved configuration); the scenario's period is {period_us} us",
                arm_app::rate::RANGE_WORDS
            )));
        }
        let arm_image = ArmImage::load(image).map_err(|e| RunError::Board(format!("{e} (build it: {BUILD_HINT})")))?;
        let loaded = arm_image.describe();
        // The law the image runs, from its ELF (`PAINLEVE_LAW_SPEC`; an image
        // without it is refused), binds the scenario's `[law]` table.
        let law = rig::law::LawDescription::declared_by(image)?;
        let config = setup.firmware_for(&law)?;
        let announced = rig::handshake::of_described(&config, law)?;
        let flash = FlashModel::brought_up(&s.calibration.arm_calibration(), config)
            .map_err(|e| RunError::Board(format!("the settings record: {}", e.describe())))?;
        let sector = flash.bytes().borrow().clone();
        let board = EmulatedBoard::new(arm_image, s.board, &sector, period_us * 1000, s.sensors.seed, s.sensors.load_noise_n, mode)
            .map_err(board_error)?;
        Ok(Self {
            board,
            plan: setup.faults().clone(),
            v_belt: s.plant.v_belt,
            period_us,
            started: false,
            torque: [0.0; 2],
            announced,
            last_ticks: None,
            rtt: Vec::new(),
            image: image.into(),
            loaded,
            handlers: Vec::new(),
            start_handlers: Vec::new(),
        })
    }

    /// The emulated board.
    pub fn board(&self) -> &EmulatedBoard {
        &self.board
    }

    fn tick(&mut self, arm: &ArmState, faults: &BusFaults, noisy: bool) -> Result<[f64; 2], RunError> {
        let u = self.board.tick(arm, faults, SpiFaults::default(), noisy).map_err(board_error)?;
        self.rtt.extend(self.board.take_rtt());
        self.handlers.extend(self.board.core().take_handlers());
        Ok(u)
    }

    /// Boots the image and presses the enable button so that the firmware's
    /// reset lands on the next tick (as `board_twin::BoardTwin::press_enable`).
    fn start(&mut self, arm: &ArmState, faults: &BusFaults) -> Result<(), RunError> {
        self.board.boot(arm).map_err(board_error)?;
        // The image's tick from its saved configuration: the scenario's rate.
        if self.board.period_ns() != self.period_us * 1000 {
            return Err(RunError::Board(format!(
                "the image's tick runs {} ns, the scenario's period is {} us: TIM2's reload is not the saved configuration's",
                self.board.period_ns(),
                self.period_us
            )));
        }
        self.board.hold_button(false);
        self.tick(arm, faults, false)?;
        self.board.hold_button(true);
        for _ in 1..button_periods(self.period_us) {
            self.tick(arm, faults, false)?;
        }
        Ok(())
    }
}

impl FirmwareLink for EmulatorLink {
    fn transport(&self) -> &'static str {
        "emulator"
    }

    fn announcement(&self) -> Option<&rig::handshake::Announced> {
        Some(&self.announced)
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let faults = bus_faults(&self.plan, u64::from(frame.seq));
        let arm = ArmState { x: truth.x, f: truth.f, belt_travel_m: self.v_belt * truth.t };
        if !self.started {
            self.start(&arm, &faults)?;
            // The timing (and the profile, if on) counts from period 0's handler
            // on; the start's runs kept apart.
            self.start_handlers = std::mem::take(&mut self.handlers);
            self.board.core().clear_profile();
        }
        self.torque = self.tick(&arm, &faults, true)?;
        if !self.started {
            self.board.hold_button(false);
            self.started = true;
        }
        let Some(m) = self.board.monitor() else {
            return Ok(Exchange::NoAnswer);
        };
        if let Some(last) = self.last_ticks
            && m.ticks != last.wrapping_add(1)
        {
            return Err(RunError::Board(format!(
                "the image ran {} ticks in one period (its monitor block went from tick {last} to {})",
                m.ticks.wrapping_sub(last),
                m.ticks
            )));
        }
        self.last_ticks = Some(m.ticks);
        Ok(crate::twin_link::answer(frame, &m.command, m.telemetry, self.period_us))
    }

    /// The torques the motor stage makes from TIM3's duty, the direction pins
    /// and the enable pin the image left.
    fn actuator_torque(&self, _command: &ActuatorCommand) -> [f64; 2] {
        self.torque
    }
}

/// The ceiling of the control handler's worst instructions on the paper
/// scenarios at 1 kHz (issue 56: 2 432 to 2 477 measured at `74a020e`;
/// 4 082 to 4 118 before the reset's fresh firmware left the handler, 7 960
/// before the notices did): CI's gate (`board-link/tests/board/emulator.rs`),
/// `sil-host bench --only emulator`.
pub const HANDLER_INSTRUCTIONS_CEILING: u64 = 3_000;
/// The ceiling of the handler's worst core cycles with the flash's wait states
/// at 1 kHz ([`ImageTiming::flash_cycles`]), every period, period 0 (the
/// enable button's press) in: the target, 3 % of the 1 ms period at
/// 168 MHz (issue 56: 4 609 to 4 755 measured at `74a020e` on the four paper
/// scenarios, medians 4 220 to 4 353; 8 189 to 8 418 before, period 0 with the
/// firmware's reset in it and the windows' close at 7 600 to 7 900;
/// docs/measurements.md "Speed IV (issue 56)").
pub const HANDLER_CYCLES_CEILING: u64 = 5_000;
/// The ceiling of the control handler's worst core cycles with the flash's
/// wait states at 10 kHz (issue 56: 4 609 measured at `74a020e` on the
/// default scenario; 8 189 before): half the 100 us period at 168 MHz, the
/// other half left to the acquisition's interrupts, USART1 and the idle loop
/// (which logs the notices, `boards/stm32f405/src/bin/arm.rs`). CI's gate
/// (`board-link/tests/board/emulator.rs`), `sil-host bench --only emulator`.
pub const HANDLER_CYCLES_CEILING_10KHZ: u64 = 8_400;
/// The ceiling of the flashed image's stack high-water mark, bytes (4 992 measured).
pub const STACK_CEILING_BYTES: u32 = 6 * 1024;

/// The flashed image's timing over a run ([`Mode::Counted`]), as the issue's
/// timing table gives it: TIM2's handler per period, and the stack.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ImageTiming {
    /// Handler runs measured.
    pub runs: usize,
    /// Instructions of one handler: median and worst.
    pub instructions: [u64; 2],
    /// Core cycles of one handler (rsemu's Cortex-M4 cost model: 1 an
    /// instruction, +1 a data access, +2 a taken branch, 12 to enter, 10 to
    /// return; flash at zero wait states, the ART accelerator hitting): median and worst.
    pub cycles: [u64; 2],
    /// Core cycles of one handler with the flash's 5 wait states at 168 MHz
    /// behind the ART accelerator (prefetch, 64-line instruction cache, 8-line
    /// data cache; `board_emulator::accelerator`, RM0090 §3.5.2): `cycles` plus
    /// the stalls, costed on the instructions executed. Median and worst.
    pub flash_cycles: [u64; 2],
    /// The worst of `flash_cycles` over every run but the first: period 0,
    /// where the enable button's firmware reset lands (`Firmware::reset`, the
    /// drivers' enable and their notices), left out; the window periods, the
    /// step's longest paths and the run's end in.
    pub steady_flash_cycles: u64,
    /// Cycles from TIM2's interrupt line rising to the handler's first instruction: least and most.
    pub latency_cycles: [u64; 2],
    /// The spread of the interval between two handlers' starts around the
    /// period, cycles: least and most of (interval - period).
    pub jitter_cycles: [i64; 2],
    /// The stack's high-water mark at the end, bytes (the painted-stack probe).
    pub stack_high_water_bytes: u32,
    /// The core clock the cycles count, Hz.
    pub core_hz: u32,
}

impl ImageTiming {
    /// The timing of `runs` (consecutive handler runs), the stack's mark
    /// `stack`, at `period_us`.
    pub fn of(runs: &[HandlerRun], stack: u32, period_us: u64) -> Option<Self> {
        if runs.is_empty() {
            return None;
        }
        let median_max = |mut v: Vec<u64>| {
            v.sort_unstable();
            [v[v.len() / 2], v[v.len() - 1]]
        };
        let min_max = |v: &[u64]| [v.iter().copied().min().unwrap_or(0), v.iter().copied().max().unwrap_or(0)];
        let core_hz = board_emulator::checks::SYSCLK_HZ;
        let period = (u64::from(core_hz) / 1_000_000 * period_us) as i64;
        let spread: Vec<i64> = runs.windows(2).map(|w| (w[1].started_at - w[0].started_at) as i64 - period).collect();
        Some(Self {
            runs: runs.len(),
            instructions: median_max(runs.iter().map(|r| r.instructions).collect()),
            cycles: median_max(runs.iter().map(|r| r.cycles).collect()),
            flash_cycles: median_max(runs.iter().map(|r| r.cycles + r.wait_cycles).collect()),
            steady_flash_cycles: runs.iter().skip(1).map(|r| r.cycles + r.wait_cycles).max().unwrap_or(0),
            latency_cycles: min_max(&runs.iter().map(|r| r.latency_cycles).collect::<Vec<_>>()),
            jitter_cycles: [spread.iter().copied().min().unwrap_or(0), spread.iter().copied().max().unwrap_or(0)],
            stack_high_water_bytes: stack,
            core_hz,
        })
    }
}

impl EmulatorLink {
    /// The timing of the run so far ([`Mode::Counted`]; `None` otherwise or before period 0).
    pub fn timing(&self) -> Option<ImageTiming> {
        ImageTiming::of(&self.handlers, self.board.stack_high_water_bytes(), self.period_us)
    }
}
