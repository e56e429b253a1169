//! The bring-up requests ([`crate::bringup`]) served by the application: on the
//! MCU from the idle loop (inside a critical section, between two ticks), on the
//! board twin between two ticks. A jog is started here and run by the ticks
//! (`crate::jog`), one period at a time, the firmware's command set aside.

use drivers::{EncoderCalibration, frame::FrameCalibration, load_cell::Calibration};
use firmware::ControlLaw;

use crate::{
    app::ArmApp,
    app::{board_firmware, check_stored},
    bringup::{
        Activity, BRINGUP_PROTOCOL, CalibrationRecord, EnableOutcome, JogFault, JogOutcome, MAX_JOG_CODES, MAX_JOG_PERIODS, MAX_JOG_US,
        MIN_SPAN_COUNTS, Missing, REDUCED_TORQUE_CODES, Refusal, Reply, Request, SpanStep, Status,
    },
    hardware::{CODES_FULL_SCALE, Hardware, Jog},
    io::ArmIo,
    joint::Joint,
    record::{self, Settings, Stored},
};

/// Counts per turn of the joints' encoders.
const COUNTS: u16 = 1 << 14;

impl<H: ArmIo, L: ControlLaw> ArmApp<H, L> {
    /// Answers one bring-up request (see [`Request`] for each).
    pub fn serve(&mut self, request: Request) -> Reply {
        let hw = &mut self.hw;
        let busy = hw.motors.is_enabled() || hw.jog.is_some() || hw.enable_requested || hw.reset_pending;
        match request {
            Request::Hello => Reply::Hello { protocol: BRINGUP_PROTOCOL },
            Request::Status => Reply::Status(status(hw, const { L::SPEC.digest() })),
            Request::Raw => {
                // The field strength needs DIAAGC: two more frames per encoder.
                let agc = [hw.theta1.diagnostics().ok().map(|d| d.agc), hw.elbow.diagnostics().ok().map(|d| d.agc)];
                hw.raw.encoder_agc = agc;
                Reply::Raw(hw.raw)
            }
            Request::GetCalibration => Reply::Calibration(hw.cal),
            Request::GetConfig => Reply::Config(hw.config),
            Request::Telemetry => Reply::Telemetry(hw.last_report),
            _ if busy && !matches!(request, Request::JogResult | Request::Disable | Request::LiftTorqueLimit) => {
                Reply::Refused(if hw.jog.is_some() { Refusal::Busy } else { Refusal::DriversEnabled })
            }
            Request::SetZeros { pose_counts } => set_zeros(hw, pose_counts),
            Request::Jog { joint, code, periods } => start_jog(hw, joint, code, periods),
            Request::JogResult => match (hw.jog, hw.last_jog) {
                (Some(_), _) => Reply::Refused(Refusal::Busy),
                (None, Some(j)) => Reply::Jogged(j),
                (None, None) => Reply::Refused(Refusal::NoJog),
            },
            Request::Tare => match hw.raw.adc_counts {
                Some(counts) => {
                    let mut cal = hw.cal;
                    cal.load_zero_counts = counts.map(f32::from);
                    cal.tared = true;
                    apply_calibration(hw, cal)
                }
                None => Reply::Refused(Refusal::NoConversion),
            },
            Request::Span { axis, newtons } => span(hw, axis, newtons),
            Request::SkipSpan { axis } => {
                let Some(i) = [0, 1].into_iter().find(|&i| i == usize::from(axis)) else {
                    return Reply::Refused(Refusal::OutOfRange);
                };
                let mut cal = hw.cal;
                if cal.span[i] == SpanStep::NotDone {
                    cal.span[i] = SpanStep::Skipped;
                }
                apply_calibration(hw, cal)
            }
            Request::SetCalibration(cal) => apply_calibration(hw, cal),
            Request::Restore(stored) => {
                if !crate::rate::supported(stored.config.period) {
                    return Reply::Refused(Refusal::Rate);
                }
                // The configuration as every configuration a board takes, then the
                // flash record's own check at reset: the calibration against it.
                let fw = match board_firmware::<L>(stored.config) {
                    Ok(_) => match check_stored::<L>(&stored) {
                        Ok(fw) => fw,
                        Err(_) => return Reply::Refused(Refusal::OutOfRange),
                    },
                    Err(why) => return Reply::Refused(why),
                };
                // Both are valid: neither can be refused now (the belt's scale
                // checked at the record's period, which it is put in force at).
                let Reply::Calibration(_) = put_calibration(hw, stored.calibration, false, stored.config.period) else {
                    return Reply::Refused(Refusal::OutOfRange);
                };
                if stored.config != self.hw.config {
                    self.set_firmware(fw);
                    self.hw.config = stored.config;
                    self.hw.settings = Settings::Unsaved;
                }
                Reply::Done
            }
            Request::Configure(config) => {
                if !crate::rate::supported(config.period) {
                    return Reply::Refused(Refusal::Rate);
                }
                match board_firmware(config) {
                    Ok(fw) => {
                        // The belt's speed per count is per period: the calibration
                        // in force again at the new one (the last check: refused,
                        // nothing changed; the same calibration changes nothing else).
                        let cal = self.hw.cal;
                        let Reply::Calibration(_) = put_calibration(&mut self.hw, cal, false, config.period) else {
                            return Reply::Refused(Refusal::OutOfRange);
                        };
                        self.set_firmware(fw);
                        if config != self.hw.config {
                            self.hw.settings = Settings::Unsaved;
                        }
                        self.hw.config = config;
                        Reply::Done
                    }
                    Err(why) => Reply::Refused(why),
                }
            }
            Request::LiftTorqueLimit => {
                if hw.directions_checked == [true; 2] {
                    hw.torque_limit = CODES_FULL_SCALE;
                    Reply::Done
                } else {
                    Reply::Refused(Refusal::DirectionsNotChecked)
                }
            }
            Request::Enable => match hw.enable_lockout() {
                Some(why) => Reply::Refused(why),
                None => {
                    hw.reset_pending = true;
                    hw.last_enable = EnableOutcome::Pending;
                    Reply::Done
                }
            },
            Request::Save if !hw.cal.missing().is_empty() => Reply::Refused(Refusal::Incomplete(hw.cal.missing())),
            // The settings in force are the record: a save would say "done" having
            // saved nothing the operator sent (a reset since reloaded the record).
            Request::Save if hw.settings == Settings::Saved => Reply::Refused(Refusal::NothingToSave),
            Request::Save => match record::save(&mut hw.flash, &Stored { calibration: hw.cal, config: hw.config }) {
                Ok(()) => {
                    hw.settings = Settings::Saved;
                    Reply::Done
                }
                Err(e) => Reply::Refused(Refusal::Flash(e)),
            },
            Request::Disable => {
                let _ = hw.motors.disable();
                if hw.last_enable == EnableOutcome::Pending {
                    hw.last_enable = EnableOutcome::Cancelled;
                }
                hw.enable_requested = false;
                hw.reset_pending = false;
                if let Some(j) = hw.jog.take() {
                    hw.last_jog = Some(JogOutcome { joint: j.joint, code: j.code, moved_counts: [0; 2], verdict: Err(JogFault::NoMotion) });
                }
                Reply::Done
            }
        }
    }
}

fn status<H: ArmIo>(hw: &Hardware<H>, law_digest: u32) -> Status {
    let activity = if hw.jog.is_some() {
        Activity::Jogging
    } else if hw.motors.is_enabled() {
        Activity::Running
    } else {
        Activity::Idle
    };
    Status {
        activity,
        periods: hw.seq,
        drivers_enabled: hw.motors.is_enabled(),
        status: hw.last_command.map_or(0, |c| c.status),
        overruns: hw.last_command.map_or(0, |c| c.overruns),
        torque_limit_codes: hw.torque_limit,
        zeros_set: hw.cal.zeros_set,
        directions_checked: hw.directions_checked == [true; 2],
        settings: hw.settings,
        missing: hw.cal.missing(),
        last_enable: hw.last_enable,
        period_us: hw.period_us as u32,
        law_digest,
    }
}

fn set_zeros<H: ArmIo>(hw: &mut Hardware<H>, pose: [u16; 2]) -> Reply {
    if pose.iter().any(|&p| p >= COUNTS) {
        return Reply::Refused(Refusal::OutOfRange);
    }
    let raw = match hw.raw.encoder_counts {
        [Ok(a), Ok(b)] => [a, b],
        [Err(e), _] | [_, Err(e)] => return Reply::Refused(Refusal::EncoderFault(e)),
    };
    let mut cal = hw.cal;
    for j in 0..2 {
        // apply(): (raw - zero) or, reversed, (zero - raw), mod 2^14, is the pose.
        cal.zero_counts[j] =
            if cal.reversed[j] { raw[j].wrapping_add(pose[j]) & (COUNTS - 1) } else { raw[j].wrapping_sub(pose[j]) & (COUNTS - 1) };
    }
    cal.zeros_set = true;
    cal.directions_checked = false;
    apply_calibration(hw, cal)
}

fn span<H: ArmIo>(hw: &mut Hardware<H>, axis: u8, newtons: f32) -> Reply {
    let i = usize::from(axis);
    if i > 1 || !(newtons.is_finite() && newtons != 0.0 && newtons.abs() <= 25.0) {
        return Reply::Refused(Refusal::OutOfRange);
    }
    if !hw.cal.tared {
        return Reply::Refused(Refusal::Incomplete(Missing(Missing::TARE)));
    }
    let Some(counts) = hw.raw.adc_counts else { return Reply::Refused(Refusal::NoConversion) };
    let diff = f32::from(counts[i]) - hw.cal.load_zero_counts[i];
    if diff.abs() < f32::from(MIN_SPAN_COUNTS) {
        return Reply::Refused(Refusal::NoSpan);
    }
    let mut cal = hw.cal;
    cal.load_newtons_per_count[i] = newtons / diff;
    cal.span[i] = SpanStep::Measured;
    apply_calibration(hw, cal)
}

/// Puts `cal` in force in every driver, or refuses it whole. New encoder zeros
/// or directions clear the direction checks unless they come from `SetZeros`
/// (which clears them itself).
fn apply_calibration<H: ArmIo>(hw: &mut Hardware<H>, cal: CalibrationRecord) -> Reply {
    let period = hw.config.period;
    put_calibration(hw, cal, true, period)
}

/// [`apply_calibration`]; with `clear_checks` false (a restored backup) the
/// direction checks are taken as the record says. The belt's scale is set for
/// control period `period` (the configuration's that comes with it).
fn put_calibration<H: ArmIo>(hw: &mut Hardware<H>, mut cal: CalibrationRecord, clear_checks: bool, period: shared::time::Period) -> Reply {
    let encoders_changed = (cal.zero_counts, cal.reversed) != (hw.cal.zero_counts, hw.cal.reversed);
    if encoders_changed && clear_checks {
        cal.directions_checked = false;
    }
    if cal.zero_counts.iter().any(|&z| z >= COUNTS) {
        return Reply::Refused(Refusal::OutOfRange);
    }
    let load = Calibration { zero_counts: cal.load_zero_counts, newtons_per_count: cal.load_newtons_per_count };
    if load.validate().is_err() || hw.belt.set_scale(cal.belt_metres_per_count, period.as_secs_f32()).is_err() {
        return Reply::Refused(Refusal::OutOfRange);
    }
    let _ = hw.load.set_calibration(load);
    hw.encoders = FrameCalibration {
        theta1: EncoderCalibration { zero_count: cal.zero_counts[0], reversed: cal.reversed[0] },
        elbow: EncoderCalibration { zero_count: cal.zero_counts[1], reversed: cal.reversed[1] },
    };
    // A new calibration runs at the reduced torque limit until both directions are
    // checked and the operator lifts it.
    if cal != hw.cal {
        hw.torque_limit = hw.torque_limit.min(REDUCED_TORQUE_CODES);
        hw.settings = Settings::Unsaved;
    }
    if encoders_changed || cal.directions_checked != hw.cal.directions_checked {
        hw.directions_checked = [cal.directions_checked; 2];
    }
    hw.cal = cal;
    Reply::Calibration(cal)
}

fn start_jog<H: ArmIo>(hw: &mut Hardware<H>, joint: Joint, code: i16, periods: u16) -> Reply {
    if !hw.cal.zeros_set {
        return Reply::Refused(Refusal::ZerosNotSet);
    }
    let too_long = periods > MAX_JOG_PERIODS || u64::from(periods) * hw.period_us > MAX_JOG_US;
    if code == 0 || code.unsigned_abs() > MAX_JOG_CODES.unsigned_abs() || periods == 0 || too_long {
        return Reply::Refused(Refusal::OutOfRange);
    }
    match hw.joint_counts() {
        Ok(start) => {
            hw.jog = Some(Jog { joint, code, left: periods, start, started: false });
            Reply::Done
        }
        Err(e) => Reply::Refused(Refusal::EncoderFault(e)),
    }
}
