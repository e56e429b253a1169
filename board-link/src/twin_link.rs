//! The board twin as a link (`sil-host run --link twin`; docs/board.md "The
//! board twin"): instead of handing the firmware a ready-made frame, the plant's
//! true state drives device models of the reference board (`board_twin`), and
//! the `arm` image's application (`arm_app`) samples them over its buses, steps
//! the firmware and drives the motor stage, whose duties, directions and enable
//! become the joint torques the plant holds (zero-order hold).
//!
//! Before period 0 the operator presses the enable button
//! ([`board_twin::BoardTwin::press_enable`]: 20 ticks with the arm standing at its
//! initial state, noise-free readings), timed so that the firmware's reset lands
//! on period 0: from then on the firmware sees what the wire-level rig's
//! firmware sees, through the bus instead of the wire. The wire-level frame the
//! rig makes is not used here (its sensor model still runs, so that a run's
//! other outputs are unchanged).

use arm_app::{AcquisitionFault, Notice};
use board_twin::{ArmState, BoardTwin, BusFaults};
use firmware::{ControlLaw, PaperLaws};
use shared::wire::{ActuatorCommand, GroundTruth, SensorFrame};

use rig::{
    faults::{FaultKind, FaultPlan, LinkKind, Signal},
    link::{Exchange, FirmwareLink},
    record::RunError,
    setup::RunSetup,
};

/// The board twin, running control law `L` (the paper's laws by default),
/// behind the rig's link.
pub struct TwinLink<L: ControlLaw = PaperLaws> {
    twin: BoardTwin<L>,
    plan: FaultPlan,
    v_belt: f64,
    period_us: u64,
    started: bool,
    torque: [f64; 2],
    announced: rig::handshake::Announced,
    /// What the application said, with the run's period (its window reports left out).
    pub notices: Vec<(usize, Notice)>,
}

impl TwinLink {
    /// [`TwinLink::for_law`] with the paper's laws (what `sil-host run --link
    /// twin` runs).
    ///
    /// # Errors
    /// As [`TwinLink::for_law`].
    pub fn new(setup: &RunSetup) -> Result<Self, RunError> {
        Self::for_law(setup)
    }
}

impl<L: ControlLaw> TwinLink<L> {
    /// The twin of `setup`: its scenario's `[board]` and `[calibration]`, its
    /// firmware configuration, its sensors' seed and load-cell noise.
    ///
    /// # Errors
    /// [`RunError::NotOnABoard`] for the runaway limits off (a board never runs
    /// without them); [`RunError::Unsupported`] for a fault the twin cannot inject;
    /// [`RunError::Board`] when the board, the calibration or the configuration
    /// is refused.
    pub fn for_law(setup: &RunSetup) -> Result<Self, RunError> {
        let s = setup.scenario();
        LinkKind::Twin.check(&s.faults)?;
        rig::board_protection::check_protection(setup.firmware(), "controller.runaway_limits").map_err(RunError::NotOnABoard)?;
        s.calibration.check(s.timing.period().as_secs_f32()).map_err(RunError::Board)?;
        // The scenario's `[law]` table bound to what `L` declares (the paper's
        // laws: none).
        let config = setup.firmware_for(&rig::law::LawDescription::of(&L::SPEC))?;
        let announced = rig::handshake::of_config(&config, &L::SPEC)?;
        let twin = BoardTwin::<L>::for_law(s.board, config, &s.calibration.arm_calibration(), s.sensors.seed, s.sensors.load_noise_n)
            .map_err(|e| RunError::Board(e.to_string()))?;
        Ok(Self {
            twin,
            plan: setup.faults().clone(),
            v_belt: s.plant.v_belt,
            period_us: s.timing.period().as_us(),
            started: false,
            torque: [0.0; 2],
            announced,
            notices: Vec::new(),
        })
    }

    /// The twin itself.
    pub fn twin(&self) -> &BoardTwin<L> {
        &self.twin
    }
}

impl<L: ControlLaw> FirmwareLink for TwinLink<L> {
    fn transport(&self) -> &'static str {
        "twin"
    }

    fn announcement(&self) -> Option<&rig::handshake::Announced> {
        Some(&self.announced)
    }

    fn exchange(&mut self, frame: &SensorFrame, truth: &GroundTruth) -> Result<Exchange, RunError> {
        let faults = bus_faults(&self.plan, u64::from(frame.seq));
        let arm = ArmState { x: truth.x, f: truth.f, belt_travel_m: self.v_belt * truth.t };
        if !self.started {
            self.twin.press_enable(&arm, &faults);
            // Start-up and the press: logged as period 0's.
            self.notices.extend(self.twin.take_notices().into_iter().filter(|n| !matches!(n, Notice::Window(_))).map(|n| (0, n)));
        }
        self.torque = self.twin.tick(&arm, &faults, true);
        if !self.started {
            self.twin.release_button();
            self.started = true;
        }
        let k = frame.seq as usize;
        self.notices.extend(self.twin.take_notices().into_iter().filter(|n| !matches!(n, Notice::Window(_))).map(|n| (k, n)));
        let Some(app_command) = self.twin.app().last_command().copied() else {
            return Ok(Exchange::NoAnswer);
        };
        let telemetry = self.twin.app().firmware().map(|fw| fw.telemetry_message(&app_command)).unwrap_or_default();
        Ok(answer(frame, &app_command, telemetry, self.period_us))
    }

    /// The torques the motor stage makes from the duties, directions and enable
    /// the application left on its pins (not the command's codes: PWM duty
    /// quantisation, the drivers' full scales and wiring, the enable and the
    /// fault line are the board's).
    fn actuator_torque(&self, _command: &ActuatorCommand) -> [f64; 2] {
        self.torque
    }
}

/// The exchange of `frame` answered by the application's last command
/// `app_command` and `telemetry` (the twin's, or the emulated image's monitor
/// block): the application numbers its frames from its power-up, the plant from
/// period 0, so the command is renumbered to the frame and its send time taken
/// relative to the frame's (`period_us` between two).
pub fn answer(frame: &SensorFrame, app_command: &ActuatorCommand, telemetry: shared::wire::FirmwareTelemetry, period_us: u64) -> Exchange {
    let app_frame_us = u64::from(app_command.seq) * period_us;
    let command =
        ActuatorCommand { seq: frame.seq, t_sent_us: frame.t_us + app_command.t_sent_us.saturating_sub(app_frame_us), ..*app_command };
    Exchange::Answered { command, telemetry: shared::wire::FirmwareTelemetry { seq: frame.seq, ..telemetry }, at_stamp: false }
}

/// The bus faults of period `k` of `plan` (the board twin's and the emulated
/// board's: the same devices). The DMA faults become the period's
/// acquisition fault (`dma_transfer_error` TEIF, `dma_fifo_error` FEIF,
/// `dma_direct_mode_error` DMEIF, `dma_late_transfer` the deadline's
/// `Timeout`; two at once: the last listed in the scenario), a stuck chip
/// select the encoder's `chip_select_stuck`. The sensors' faults the devices
/// make (`encoder_spike`, `load_cell_drift`, `belt_gain`) and the board's truth
/// (`board`) are the plan's, as the wire-level sensor model takes them.
pub fn bus_faults(plan: &FaultPlan, k: u64) -> BusFaults {
    let mut b = BusFaults {
        encoder_spike: [plan.spike_counts(Signal::Theta1, k), plan.spike_counts(Signal::Elbow, k)],
        load_offsets_n: plan.load_offsets_n(k),
        belt_gain: plan.belt_gain(k),
        board: plan.board(k),
        ..BusFaults::default()
    };
    for (kind, signal) in plan.board_faults(k) {
        let encoder = match signal {
            Some(Signal::Theta1) => Some(0),
            Some(Signal::Elbow) => Some(1),
            _ => None,
        };
        match (kind, encoder, signal) {
            (FaultKind::SpiError, Some(i), _) => b.encoders[i].spi_error = true,
            (FaultKind::ParityError, Some(i), _) => b.encoders[i].parity_error = true,
            (FaultKind::MagnetLost, Some(i), _) => b.encoders[i].magnet_lost = true,
            (FaultKind::StuckSensor, Some(i), _) => b.encoders[i].stuck = true,
            (FaultKind::StuckSensor, None, Some(Signal::FT)) => b.adc_stuck[0] = true,
            (FaultKind::StuckSensor, None, Some(Signal::FN)) => b.adc_stuck[1] = true,
            (FaultKind::StuckSensor, None, Some(Signal::Belt)) => b.belt_stuck = true,
            (FaultKind::MissingConversion, ..) => b.missing_conversion = true,
            (FaultKind::DriverFault, ..) => b.driver_fault = true,
            (FaultKind::StuckChipSelect, Some(i), _) => b.encoders[i].chip_select_stuck = true,
            (FaultKind::DmaTransferError, ..) => b.acquisition = Some(AcquisitionFault::TransferError),
            (FaultKind::DmaFifoError, ..) => b.acquisition = Some(AcquisitionFault::FifoError),
            (FaultKind::DmaDirectModeError, ..) => b.acquisition = Some(AcquisitionFault::DirectModeError),
            (FaultKind::DmaLateTransfer, ..) => b.acquisition = Some(AcquisitionFault::Timeout),
            _ => {}
        }
    }
    b
}

/// A notice of the application as its log line (the image's defmt lines, in words).
pub fn describe(n: &Notice) -> String {
    match n {
        Notice::EncoderReady { joint, agc } => format!("encoder {}: ready, AGC {agc}", joint.name()),
        Notice::EncoderNotReady { joint, fault } => format!("encoder {}: not ready ({})", joint.name(), fault.describe()),
        Notice::InvalidReadings { flags, .. } => {
            format!("invalid readings: {} (frame flags {flags:#x})", rig::status_words::describe_frame_flags(*flags))
        }
        Notice::ReadingsBack { .. } => "every sensor reads again".into(),
        Notice::AcquisitionFault { fault, .. } => format!("the encoders' acquisition failed: {}", fault.describe()),
        Notice::SafeState { reason, .. } => format!(
            "{}: drivers disabled",
            rig::status_words::describe_status(
                shared::wire::status::SAFE_STATE | (u32::from(*reason) << shared::wire::status::REASON_SHIFT)
            )
        ),
        Notice::DriversDidNotDisable => "the drivers did not disable".into(),
        Notice::DriversEnabled { .. } => "drivers enabled".into(),
        Notice::DriversRefused { .. } => "the drivers refuse to enable (fault line asserted)".into(),
        Notice::FirmwareReset => "enable button: firmware reset".into(),
        Notice::Jogged(j) => format!("jog of {} at code {}: moved {:?} counts: {:?}", j.joint.name(), j.code, j.moved_counts, j.verdict),
        Notice::Window(w) => format!("window: step worst {} ticks, drivers enabled {}", w.step.worst, w.drivers_enabled),
        Notice::Settings(s) => format!("settings: {}", s.describe()),
        Notice::LockedOut(s) => format!("enable button ignored: {}", s.describe()),
    }
}
