//! The arm's sensors, drivers and per-tick bookkeeping: the board side of
//! `firmware::board::handle` (the tick, `crate::app`) and of the bring-up
//! requests (`crate::service`).

use drivers::{
    As5047p, BeltEncoder, LoadCell,
    frame::{self, FrameCalibration, Readings},
};
use embedded_hal::digital::InputPin;
use firmware::Config;
use shared::{
    time::Instant,
    wire::{ActuatorCommand, SensorFrame, frame_flags},
};

use crate::{
    bringup::{CalibrationRecord, JogOutcome, RawReadings},
    io::{ArmIo, EncoderAcquisition, Motors},
    joint::{EncoderFault, Joint},
    notice::Notice,
    record::Settings,
    step_stats::StepStats,
    telemetry::ArmTelemetry,
};

/// How long the enable button must read pressed, s: a press, not a bounce of its
/// contacts (20 periods at 1 kHz).
pub const BUTTON_PRESS_S: f32 = 0.020;

/// [`BUTTON_PRESS_S`] in periods of `period_us` microseconds, rounded up, at
/// least one (`firmware::runaway::periods_of`, as the monitors' times): 20 at
/// 1 kHz, 200 at 10 kHz, 5 at 250 Hz. Before issue 56's rates it was 20 periods
/// at any rate, 2 ms at 10 kHz: shorter than a contact's bounce.
pub fn button_periods(period_us: u64) -> u16 {
    firmware::runaway::periods_of(BUTTON_PRESS_S, period_us as f32 * 1e-6)
}

/// Torque codes of full scale (the wire's: 2048 = 5 N m); the torque limit when
/// none is set.
pub const CODES_FULL_SCALE: i16 = 2048;

/// A jog under way (`Request::Jog`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Jog {
    pub(crate) joint: Joint,
    pub(crate) code: i16,
    pub(crate) left: u16,
    /// The calibrated joint counts when it started `[theta1, elbow]`.
    pub(crate) start: [u16; 2],
    pub(crate) started: bool,
}

/// The sensors, the drivers and the per-tick bookkeeping: the board side of
/// `firmware::board::handle` (and of the bring-up requests, `crate::service`).
pub(crate) struct Hardware<H: ArmIo> {
    pub(crate) theta1: As5047p<H::Spi>,
    pub(crate) elbow: As5047p<H::Spi>,
    pub(crate) acquisition: H::Encoders,
    /// The acquisition fault last logged (`None`: none, or the acquisition is back).
    pub(crate) acquisition_logged: Option<crate::joint::AcquisitionFault>,
    /// Consecutive periods whose acquisition failed (0 after a clean one).
    pub(crate) acquisition_faults: u16,
    pub(crate) load: LoadCell<H::Adc>,
    pub(crate) belt: BeltEncoder<H::Counter>,
    pub(crate) motors: Motors<H>,
    pub(crate) button: H::In,
    pub(crate) watchdog: H::Watchdog,
    pub(crate) encoders: FrameCalibration,
    /// The calibration in force, as the bring-up protocol shows it.
    pub(crate) cal: CalibrationRecord,
    /// The firmware's configuration in force.
    pub(crate) config: Config,
    /// The settings record's flash.
    pub(crate) flash: H::Flash,
    /// The settings in force against the record.
    pub(crate) settings: Settings,
    /// The last window's telemetry.
    pub(crate) last_report: Option<ArmTelemetry>,
    /// The window closed at the last tick, its step's summary to come
    /// (`ArmApp::idle`).
    pub(crate) closing: Option<ArmTelemetry>,
    /// This period's raw readings.
    pub(crate) raw: RawReadings,
    /// The torque limit on the codes written to the drivers (2048: none).
    pub(crate) torque_limit: i16,
    /// Each joint's direction was checked by a jog with these zeros.
    pub(crate) directions_checked: [bool; 2],
    /// The jog under way.
    pub(crate) jog: Option<Jog>,
    /// The last jog's outcome.
    pub(crate) last_jog: Option<JogOutcome>,
    pub(crate) button_low: u16,
    pub(crate) button_released: bool,
    pub(crate) reset_pending: bool,
    pub(crate) enable_requested: bool,
    /// What became of the last enable.
    pub(crate) last_enable: crate::bringup::EnableOutcome,
    /// The period the board's tick runs, us (`crate::rate`: the
    /// configuration's, once the board has followed it).
    pub(crate) period_us: u64,
    /// [`button_periods`] of `period_us`, set with it.
    pub(crate) button_press_periods: u16,
    /// Added to `seq x period_us` for a frame's time, us (wrapping): nonzero
    /// after the rate changed (`ArmApp::retime`), so the time goes on.
    pub(crate) time_offset_us: u64,
    pub(crate) seq: u32,
    pub(crate) tick_mark: u32,
    pub(crate) now: Instant,
    pub(crate) interval: [u32; 2],
    pub(crate) handler_worst: u32,
    pub(crate) stats: StepStats,
    pub(crate) invalid_logged: u16,
    pub(crate) safe_logged: bool,
    pub(crate) last_command: Option<ActuatorCommand>,
}

impl<H: ArmIo> Hardware<H> {
    /// Samples every sensor now (the tick): the frame of period `seq`, with a
    /// notice when the set of invalid readings changes.
    pub(crate) fn sample(&mut self, log: &mut impl FnMut(Notice)) -> SensorFrame {
        let encoder_counts = self.acquisition.acquire(&mut self.theta1, &mut self.elbow);
        let acquisition = encoder_counts.iter().find_map(|r| match r {
            Err(EncoderFault::Acquisition(f)) => Some(*f),
            _ => None,
        });
        if acquisition != self.acquisition_logged {
            if let Some(fault) = acquisition {
                log(Notice::AcquisitionFault { seq: self.seq, fault });
            }
            self.acquisition_logged = acquisition;
        }
        self.acquisition_faults = if acquisition.is_some() { self.acquisition_faults.saturating_add(1) } else { 0 };
        let load = self.load.read_counts_and_codes().ok();
        let readings = Readings {
            theta1_raw: encoder_counts[0].ok(),
            elbow_raw: encoder_counts[1].ok(),
            load_codes: load.map_or([None, None], |(_, [t, n])| [Some(t), Some(n)]),
            belt_mm_s: self.belt.speed_mm_s().ok(),
            driver_fault: self.motors.fault_asserted().ok(),
        };
        self.raw = RawReadings {
            seq: self.seq,
            encoder_counts,
            encoder_agc: self.raw.encoder_agc,
            adc_counts: load.map(|(counts, _)| counts),
            belt_count: self.belt.last_count(),
            driver_fault: readings.driver_fault != Some(false),
        };
        let f = frame::assemble(
            u64::from(self.seq).wrapping_mul(self.period_us).wrapping_add(self.time_offset_us),
            self.seq,
            readings,
            &self.encoders,
        );
        let invalid = f.flags & frame_flags::ANY_INVALID;
        if invalid != self.invalid_logged {
            log(if invalid == 0 {
                Notice::ReadingsBack { seq: self.seq }
            } else {
                Notice::InvalidReadings { seq: self.seq, flags: invalid }
            });
            self.invalid_logged = invalid;
        }
        f
    }

    /// Why the drivers may not be enabled now, if they may not: settings in
    /// force that are not the saved record, a calibration that lacks a
    /// bring-up step (a saved record never does: `Save` refuses it), or a tick
    /// that does not run the configuration's period.
    pub(crate) fn enable_lockout(&self) -> Option<crate::bringup::Refusal> {
        use crate::bringup::Refusal;
        if !self.settings.allows_enable() {
            Some(Refusal::LockedOut(self.settings))
        } else if !self.cal.missing().is_empty() {
            Some(Refusal::Incomplete(self.cal.missing()))
        } else if self.period_us != self.config.period.as_us() {
            // The tick does not run the configuration's period (a board that
            // could not follow a new rate): the firmware's Ts would be wrong.
            Some(Refusal::Rate)
        } else {
            None
        }
    }

    /// A press: low for [`button_periods`] of the tick's period
    /// (`button_press_periods`) after having been seen released (a
    /// button stuck low, a pin that cannot be read, or one QEMU does not model,
    /// never presses).
    pub(crate) fn button_pressed(&mut self) -> bool {
        match self.button.is_high() {
            Ok(true) => {
                self.button_low = 0;
                self.button_released = true;
                return false;
            }
            Ok(false) => {}
            Err(_) => return false,
        }
        if !self.button_released {
            return false;
        }
        self.button_low = self.button_low.saturating_add(1);
        if self.button_low == self.button_press_periods {
            self.button_released = false;
            return true;
        }
        false
    }

    /// The encoders' calibrated joint counts `[theta1, elbow]` of this period,
    /// or the first encoder's fault.
    pub(crate) fn joint_counts(&self) -> Result<[u16; 2], EncoderFault> {
        let [a, b] = self.raw.encoder_counts;
        Ok([self.encoders.theta1.apply(a?), self.encoders.elbow.apply(b?)])
    }
}
