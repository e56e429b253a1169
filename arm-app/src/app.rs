//! The arm application: what the `arm` image does at every control tick, on any
//! board that gives its parts ([`ArmIo`]).
//!
//! At the tick (TIM2's update interrupt on the reference board):
//! 1. the interval since the previous tick is recorded (its spread is the tick's
//!    jitter plus the handler's latency);
//! 2. the enable button is read (a press: low for [`BUTTON_PRESS_S`] after
//!    having been seen released);
//! 3. the sensors are sampled now: both encoders (`As5047p::sample`), the load
//!    cell's conversions, the belt's counter, the drivers' fault line, into the
//!    period's `SensorFrame` ([`drivers::frame::assemble`] with the encoders'
//!    calibration);
//! 4. the firmware steps on it through `firmware::board::handle`, the one path
//!    every image and the host take;
//! 5. the command is written: a safe state disables the drivers (enable low, zero
//!    duty); after the button's reset the drivers enable at the first command that
//!    is not the safe state; the duties follow the torque codes
//!    (`drivers::motor::duty_for`; disabled drivers get zero duty);
//! 6. the watchdog is fed, and the step's ticks are recorded; every
//!    `step_stats::WINDOW` periods the window closes, and between two ticks
//!    ([`ArmApp::idle`]) its report is made and returned for a [`Notice::Window`].
//!
//! A reset (or a watchdog reset) comes up with the drivers disabled until the
//! enable button resets the firmware.

use drivers::{
    As5047p, BeltEncoder, LoadCell,
    belt::BeltError,
    load_cell::{Calibration, CalibrationError},
};
use firmware::{
    Config, ControlLaw, Event, Firmware, Outcome, PaperLaws, SafeReason, TickClock,
    board::{self, Board},
    config::ConfigError,
};
use shared::{
    time::{Duration, Instant},
    wire::{ActuatorCommand, status},
};

use crate::{
    bringup::{CalibrationRecord, EnableOutcome, REDUCED_TORQUE_CODES, RawReadings, Refusal},
    calibration::ArmCalibration,
    hardware::{CODES_FULL_SCALE, Hardware},
    io::Motors,
    io::{ArmIo, IntervalClock, Watchdog},
    joint::{EncoderFault, Joint},
    notice::Notice,
    record::{self, RecordFault, Settings, Stored},
    step_stats::{StepStats, WindowSummary},
    telemetry::ArmTelemetry,
};

/// The firmware of configuration `config` as a board runs it: the
/// configuration valid (`firmware::Config::validate`) and the runaway limits on
/// (`Config::runaway_limits`: a board never runs without them; the studies
/// that need them off run without a board). The check of every configuration
/// put in force: `Configure`, `Restore`, the flash record at reset, the
/// compiled-in fallback.
///
/// # Errors
/// [`Refusal::ProtectionOff`] when the runaway limits are off (checked first),
/// [`Refusal::InvalidConfig`] when the configuration is invalid.
pub fn board_firmware<L: ControlLaw>(config: Config) -> Result<Firmware<L>, Refusal> {
    if !config.runaway_limits {
        return Err(Refusal::ProtectionOff);
    }
    Firmware::with_law(config).map_err(|_| Refusal::InvalidConfig)
}

/// Whether a stored record's values would be taken: its configuration
/// ([`board_firmware`]), its encoders' zeros, its load-cell calibration, its
/// belt scale at its control period. The check of the record loaded at reset,
/// and of `Request::Restore`.
///
/// # Errors
/// [`RecordFault::ProtectionOff`] for a configuration with the runaway limits
/// off, [`RecordFault::Content`] for any other invalid value.
pub(crate) fn check_stored<L: ControlLaw>(s: &Stored) -> Result<Firmware<L>, RecordFault> {
    let c = s.calibration;
    let fw = board_firmware(s.config)
        .map_err(|r| if r == Refusal::ProtectionOff { RecordFault::ProtectionOff } else { RecordFault::Content })?;
    let valid = c.zero_counts.iter().all(|&z| z < 1 << 14)
        && Calibration { zero_counts: c.load_zero_counts, newtons_per_count: c.load_newtons_per_count }.validate().is_ok()
        && drivers::belt::scale(c.belt_metres_per_count, s.config.period.as_secs_f32()).is_ok();
    if valid { Ok(fw) } else { Err(RecordFault::Content) }
}

/// A board's parts, handed to [`ArmApp::new`]. The motor stage comes built: a
/// board makes it first, so that the drivers are disabled before anything else
/// can fail.
pub struct ArmParts<H: ArmIo> {
    /// The base joint's encoder (`theta1`).
    pub theta1: H::Spi,
    /// The elbow's encoder (`theta2 - theta1`).
    pub elbow: H::Spi,
    /// How the period's encoder samples are taken.
    pub encoders: H::Encoders,
    /// The load cell's ADC.
    pub adc: H::Adc,
    /// The belt's counter.
    pub belt: H::Counter,
    /// Both motor drivers, disabled.
    pub motors: Motors<H>,
    /// The enable button (low = pressed).
    pub button: H::In,
    /// The independent watchdog (already started by the board).
    pub watchdog: H::Watchdog,
    /// The step's clock.
    pub clock: H::Clock,
    /// The settings record's flash sector.
    pub flash: H::Flash,
}

/// Why the application did not start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StartError {
    /// The firmware's configuration is invalid.
    Config(ConfigError),
    /// The load cell's calibration is invalid.
    LoadCell(CalibrationError),
    /// The belt's scale (or the control period) is invalid.
    Belt(BeltError),
    /// The fallback configuration turns the runaway limits off, which a board
    /// never runs ([`board_firmware`]).
    ProtectionOff,
}

/// The arm application: the firmware and the board it runs on.
pub struct ArmApp<H: ArmIo, L: ControlLaw = PaperLaws> {
    pub(crate) hw: Hardware<H>,
    /// The firmware in force is `slots[active]`. The other slot holds, once
    /// [`ArmApp::prepare_reset`] made it between two ticks, a fresh firmware
    /// of the same configuration: the enable button's reset then takes it
    /// (`active` flips) instead of `Firmware::reset` rebuilding and copying
    /// the whole state in the control interrupt (issue 56: 2 300 of the
    /// press's period's 7 850 cycles on the `arm` image).
    slots: [Option<Firmware<L>>; 2],
    active: usize,
    clock: H::Clock,
}

impl<H: ArmIo, L: ControlLaw> ArmApp<H, L> {
    /// Starts the application on `parts`: loads the settings record from the
    /// flash (`crate::record`; a [`Notice::Settings`] says what was found), and
    /// when there is none or it is refused, falls back to the compiled-in
    /// `config` and `cal` with the drivers locked out; checks both encoders
    /// (start-up notices: ready with the AGC, or not ready and why: their
    /// readings will then be invalid), then the load cell's calibration and the
    /// belt's scale. The drivers stay disabled until the enable button.
    ///
    /// # Errors
    /// [`StartError`]: an invalid fallback configuration (or one with the
    /// runaway limits off), load-cell calibration or belt scale (a stored record
    /// with invalid values is refused instead, the drivers locked out:
    /// `Settings::Corrupt(RecordFault::Content)`, or
    /// `Settings::Corrupt(RecordFault::ProtectionOff)` for one with the runaway
    /// limits off).
    pub fn new(mut parts: ArmParts<H>, config: Config, cal: &ArmCalibration, log: &mut impl FnMut(Notice)) -> Result<Self, StartError> {
        let fallback = CalibrationRecord::uncalibrated(cal);
        let loaded = record::load(&mut parts.flash).and_then(|s| match s.map(|s| check_stored::<L>(&s).map(|_| s)) {
            Some(Err(fault)) => Err(fault),
            Some(Ok(s)) => Ok(Some(s)),
            None => Ok(None),
        });
        let (settings, config, record) = match loaded {
            Ok(Some(s)) if !s.calibration.missing().is_empty() => {
                (Settings::Corrupt(RecordFault::Incomplete(s.calibration.missing())), config, fallback)
            }
            Ok(Some(s)) => (Settings::Saved, s.config, s.calibration),
            Ok(None) => (Settings::Missing, config, fallback),
            Err(e) => (Settings::Corrupt(e), config, fallback),
        };
        let cal = record.arm_calibration();
        let directions_checked = record.directions_checked;
        log(Notice::Settings(settings));
        if !config.runaway_limits {
            return Err(StartError::ProtectionOff);
        }
        let firmware = Firmware::<L>::with_law(config).map_err(StartError::Config)?;
        let mut theta1 = As5047p::new(parts.theta1);
        let mut elbow = As5047p::new(parts.elbow);
        for (joint, enc) in [(Joint::Theta1, &mut theta1), (Joint::Elbow, &mut elbow)] {
            log(match enc.check_ready() {
                Ok(d) => Notice::EncoderReady { joint, agc: d.agc },
                Err(e) => Notice::EncoderNotReady { joint, fault: EncoderFault::of(&e) },
            });
        }
        let load = LoadCell::new(parts.adc, cal.load_cell).map_err(StartError::LoadCell)?;
        let belt = BeltEncoder::new(parts.belt, cal.belt_metres_per_count, config.period.as_secs_f32()).map_err(StartError::Belt)?;
        let clock = parts.clock;
        let tick_mark = clock.mark();
        let hw = Hardware {
            theta1,
            elbow,
            acquisition: parts.encoders,
            acquisition_logged: None,
            acquisition_faults: 0,
            load,
            belt,
            motors: parts.motors,
            button: parts.button,
            watchdog: parts.watchdog,
            encoders: cal.encoders,
            cal: record,
            flash: parts.flash,
            settings,
            config,
            raw: RawReadings {
                seq: 0,
                encoder_counts: [Err(EncoderFault::NotReady); 2],
                encoder_agc: [None; 2],
                adc_counts: None,
                belt_count: 0,
                driver_fault: false,
            },
            torque_limit: if directions_checked { CODES_FULL_SCALE } else { REDUCED_TORQUE_CODES },
            directions_checked: [directions_checked; 2],
            last_report: None,
            closing: None,
            jog: None,
            last_jog: None,
            button_low: 0,
            button_released: false,
            reset_pending: false,
            enable_requested: false,
            last_enable: EnableOutcome::NotAsked,
            period_us: config.period.as_us(),
            button_press_periods: crate::hardware::button_periods(config.period.as_us()),
            time_offset_us: 0,
            seq: 0,
            tick_mark,
            now: Instant::from_us(0),
            interval: [u32::MAX, 0],
            handler_worst: 0,
            stats: StepStats::default(),
            invalid_logged: 0,
            safe_logged: false,
            last_command: None,
        };
        Ok(Self { hw, slots: [Some(firmware), None], active: 0, clock })
    }

    /// Puts `fw` in force (a configuration taken): the fresh spare of the
    /// last one, if any, is dropped.
    pub(crate) fn set_firmware(&mut self, fw: Firmware<L>) {
        self.active &= 1;
        self.slots[self.active] = Some(fw);
        self.slots[self.active ^ 1] = None;
    }

    /// Makes the fresh firmware the next reset takes, if there is none yet:
    /// `Firmware::new` of the configuration in force, the state
    /// `Firmware::reset` would make (which it is: `Firmware::reset` is
    /// `Firmware::new` of its own configuration, tested). Between two ticks (the
    /// `arm` image's idle loop; the board twin after each tick): its cost
    /// (about 3 000 cycles on the image) leaves the control interrupt, whose
    /// reset is then a flip of two slots. Without it the reset rebuilds in
    /// place, to the same state.
    pub fn prepare_reset(&mut self) {
        self.active &= 1;
        let spare = self.active ^ 1;
        if self.slots[spare].is_none()
            && let Some(fw) = &self.slots[self.active]
        {
            self.slots[spare] = Firmware::with_law(*fw.config()).ok();
        }
    }

    /// What a board does between two ticks (the `arm` image's idle loop, the
    /// board twin after each tick), the control interrupt's work that can
    /// wait: the window closed at the last tick finished (the step's median
    /// and worst from its histogram, `step_stats`), its report returned for
    /// the log ([`Notice::Window`]) and kept for `Request::Telemetry`; and the
    /// next reset's fresh firmware made ([`ArmApp::prepare_reset`]).
    pub fn idle(&mut self) -> Option<ArmTelemetry> {
        self.prepare_reset();
        let hw = &mut self.hw;
        let mut report = hw.closing.take()?;
        report.step = hw.stats.finish()?;
        hw.last_report = Some(report);
        Some(report)
    }

    /// Whether the next reset's fresh firmware is made ([`ArmApp::prepare_reset`]).
    pub fn reset_prepared(&self) -> bool {
        self.slots[(self.active & 1) ^ 1].is_some()
    }

    /// One control period (the tick's interrupt): see the module's documentation.
    /// `log` receives what the operator should know.
    pub fn tick(&mut self, log: &mut impl FnMut(Notice)) {
        let Self { hw, slots, active, clock } = self;
        let interval = clock.ticks().wrapping_sub(hw.tick_mark);
        hw.tick_mark = clock.mark();
        if hw.seq > 0 {
            hw.interval = [hw.interval[0].min(interval), hw.interval[1].max(interval)];
        }
        if hw.button_pressed() {
            if hw.enable_lockout().is_none() {
                hw.reset_pending = true;
                hw.last_enable = EnableOutcome::Pending;
            } else {
                log(Notice::LockedOut(hw.settings));
            }
        }
        let mut board = TickBoard { hw, clock, log };
        loop {
            let Ok(event) = board.next_event();
            // The acquisition's own safe-state reason (issue 56): its faults make
            // the frame bad, and the firmware's bad-frame rule would name them
            // `BadFrames` at the same period (or the consistency check, on held
            // encoders, `SensorFault`): latched first, before the step.
            if board.hw.acquisition_faults >= board.hw.config.bad_frame_limit
                && let Some(fw) = slots[*active & 1].as_mut()
            {
                fw.enter_safe_state(SafeReason::Acquisition);
            }
            // The reset with its fresh firmware made: the slots flip, and the
            // event goes through `board::handle` with no firmware (which
            // resets none and answers `Outcome::Reset`, as it would with one).
            let old = *active & 1;
            let prepared = matches!(event, Event::Reset) && slots[old ^ 1].is_some();
            if prepared {
                slots[old] = None;
                *active = old ^ 1;
            }
            let _ = board::handle(&mut slots[old], event, &mut board, clock);
            if matches!(event, Event::Frame(_)) {
                break;
            }
        }
        hw.seq = hw.seq.wrapping_add(1);
        hw.handler_worst = hw.handler_worst.max(clock.ticks().wrapping_sub(hw.tick_mark));
    }

    /// The firmware's configuration in force (the settings record's, else the
    /// fallback's): its period is the control tick's.
    pub fn config(&self) -> &Config {
        &self.hw.config
    }

    /// Periods run so far.
    pub fn periods(&self) -> u32 {
        self.hw.seq
    }

    /// Whether the motor drivers are enabled.
    pub fn drivers_enabled(&self) -> bool {
        self.hw.motors.is_enabled()
    }

    /// The command of the last tick (`None` before the first).
    pub fn last_command(&self) -> Option<&ActuatorCommand> {
        self.hw.last_command.as_ref()
    }

    /// The firmware (its counters, its estimate).
    pub fn firmware(&self) -> Option<&Firmware<L>> {
        self.slots[self.active & 1].as_ref()
    }
}

/// The board of one tick: the hardware, the clock and the notice sink.
struct TickBoard<'a, H: ArmIo, L: FnMut(Notice)> {
    hw: &'a mut Hardware<H>,
    clock: &'a H::Clock,
    log: &'a mut L,
}

impl<H: ArmIo, N: FnMut(Notice)> Board for TickBoard<'_, H, N> {
    type Error = core::convert::Infallible;

    fn next_event(&mut self) -> Result<Event, Self::Error> {
        if core::mem::take(&mut self.hw.reset_pending) {
            return Ok(Event::Reset);
        }
        let frame = self.hw.sample(self.log);
        // The step starts now: the tick plus the sampling.
        let per_us = (self.clock.ticks_per_second() / 1_000_000).max(1);
        let us = self.clock.ticks().wrapping_sub(self.hw.tick_mark) / per_us;
        self.hw.now = frame.sampled_at().saturating_add(Duration::from_us(u64::from(us)));
        Ok(Event::Frame(frame))
    }

    fn now(&self) -> Instant {
        self.hw.now
    }

    fn apply<L: ControlLaw>(&mut self, outcome: &Outcome, fw: Option<&Firmware<L>>) -> Result<(), Self::Error> {
        let hw = &mut *self.hw;
        match outcome {
            Outcome::Command(c) => {
                hw.last_command = Some(*c);
                if hw.jog.is_some() {
                    if let Some(n) = crate::jog::jog_tick(hw) {
                        (self.log)(n);
                    }
                    hw.watchdog.feed();
                    return Ok(());
                }
                if c.status & status::SAFE_STATE != 0 {
                    let were_enabled = hw.motors.is_enabled();
                    if hw.motors.disable().is_err() {
                        (self.log)(Notice::DriversDidNotDisable);
                    }
                    if core::mem::take(&mut hw.enable_requested) {
                        hw.last_enable = EnableOutcome::SafeState { seq: c.seq, status: c.status };
                    }
                    if !hw.safe_logged {
                        let reason = SafeReason::from_status(c.status);
                        // A check of what the motors do, tripped while the drivers
                        // were never on (before the enable button): the motors did
                        // nothing because they were off, not because of a fault.
                        // Not logged (issue 80: a spurious `Miswired` line at every
                        // start); the enable button resets the firmware.
                        if were_enabled || !reason.is_some_and(SafeReason::needs_the_motors) {
                            (self.log)(Notice::SafeState { seq: c.seq, reason: reason.map_or(0, |r| r as u8) });
                        }
                        hw.safe_logged = true;
                    }
                } else if core::mem::take(&mut hw.enable_requested) {
                    let (notice, outcome) = match hw.motors.enable() {
                        Ok(()) => (Notice::DriversEnabled { seq: c.seq }, EnableOutcome::Enabled { seq: c.seq }),
                        Err(_) => (Notice::DriversRefused { seq: c.seq }, EnableOutcome::DriversRefused { seq: c.seq }),
                    };
                    hw.last_enable = outcome;
                    (self.log)(notice);
                }
                // Disabled drivers get zero duty whatever the codes; the torque
                // limit of a fresh calibration caps the rest.
                let limit = hw.torque_limit;
                let _ = hw.motors.apply([c.u1_code, c.u2_code].map(|u| u.clamp(-limit, limit)));
                hw.watchdog.feed();
                if hw.stats.record(c.step_ticks) {
                    // The step's summary is made between two ticks
                    // (`ArmApp::idle`), which reports the window.
                    hw.closing = Some(ArmTelemetry {
                        seq: c.seq,
                        status: c.status,
                        overruns: fw.map_or(0, Firmware::overruns),
                        drivers_enabled: hw.motors.is_enabled(),
                        clock: self.clock.kind(),
                        step: WindowSummary::default(),
                        tick_interval: hw.interval,
                        handler_worst: hw.handler_worst,
                        // Filled in by the board's idle loop: scanning the stack
                        // takes too long in the tick.
                        stack_high_water_bytes: 0,
                    });
                    hw.interval = [u32::MAX, 0];
                    hw.handler_worst = 0;
                }
            }
            Outcome::Reset => {
                (self.log)(Notice::FirmwareReset);
                hw.enable_requested = true;
                hw.safe_logged = false;
            }
            _ => {}
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::wire::SensorFrame;

    #[test]
    fn a_prepared_fresh_firmware_is_the_state_the_reset_makes() {
        // `ArmApp::prepare_reset`'s claim: `Firmware::new` of the configuration
        // in force is what `Firmware::reset` makes of a firmware that has run
        // (stepped, latched a safe state), field for field (their Debug).
        for config in [Config::default(), Config { period: shared::time::Period::from_us(100).unwrap(), ..Config::default() }] {
            let mut fw = Firmware::new(config).unwrap();
            for seq in 0..50u32 {
                let frame = SensorFrame {
                    t_us: u64::from(seq) * config.period.as_us(),
                    seq,
                    theta1_count: 15_860 + (seq as u16 % 7),
                    elbow_count: 15_290,
                    ..SensorFrame::default()
                };
                let _ = fw.step(Instant::from_us(frame.t_us), &frame, &firmware::board::FrozenClock);
            }
            fw.enter_safe_state(SafeReason::PeerLost);
            let fresh = format!("{:?}", Firmware::new(*fw.config()).unwrap());
            assert_ne!(format!("{fw:?}"), fresh, "the run changed the state");
            fw.reset();
            assert_eq!(format!("{fw:?}"), fresh);
        }
    }
}
