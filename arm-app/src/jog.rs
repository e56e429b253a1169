//! A jog (bring-up, `Request::Jog`): a low torque on one joint for a bounded
//! time, the other at zero, run by the ticks in place of the firmware's
//! command; the joint must move the way its torque pushes, by a bounded angle.
//! It checks, before any closed loop, that each motor turns its joint the way
//! its encoder counts (ODrive's encoder-offset calibration does the same).

use crate::{
    bringup::{JogFault, JogOutcome, MAX_JOG_COUNTS, MIN_JOG_COUNTS},
    hardware::Hardware,
    io::ArmIo,
    joint::Joint,
    notice::Notice,
};

/// Counts per turn of the joints' encoders.
const COUNTS: u16 = 1 << 14;

/// The signed change from `from` to `to` of a 14-bit count, in `[-2^13, 2^13)`.
fn wrapped_diff(from: u16, to: u16) -> i32 {
    let d = i32::from(to.wrapping_sub(from) & (COUNTS - 1));
    if d >= 1 << 13 { d - (1 << 14) } else { d }
}

/// One period of the jog under way: drives the jogged joint with the jog's
/// torque (the other at zero), watches both joints, and ends it (drivers
/// disabled, outcome recorded, a notice) when its time is up, the joint went too
/// far, an encoder failed or the drivers refused.
pub(crate) fn jog_tick<H: ArmIo>(hw: &mut Hardware<H>) -> Option<Notice> {
    let mut jog = hw.jog?;
    let j = usize::from(jog.joint == Joint::Elbow);
    let moved = hw.joint_counts().map(|now| [0, 1].map(|i| wrapped_diff(jog.start[i], now[i])));
    let verdict = match moved {
        Err(_) => Some(Err(JogFault::EncoderFault)),
        Ok(m) if m[j].abs() > MAX_JOG_COUNTS => Some(Err(JogFault::TooFar)),
        Ok(_) if !jog.started && hw.motors.enable().is_err() => Some(Err(JogFault::DriversRefused)),
        Ok(m) if jog.left == 0 => Some(if m[j].abs() < MIN_JOG_COUNTS {
            Err(JogFault::NoMotion)
        } else if (m[j] > 0) != (jog.code > 0) {
            Err(JogFault::WrongDirection)
        } else {
            Ok(())
        }),
        Ok(_) => None,
    };
    jog.started = true;
    match verdict {
        None => {
            let mut codes = [0i16; 2];
            codes[j] = jog.code;
            let _ = hw.motors.apply(codes);
            jog.left -= 1;
            hw.jog = Some(jog);
            None
        }
        Some(verdict) => {
            let _ = hw.motors.disable();
            hw.jog = None;
            hw.directions_checked[j] = verdict.is_ok();
            let checked = hw.directions_checked == [true; 2];
            if checked != hw.cal.directions_checked {
                // The calibration in force is no longer the saved one.
                hw.cal.directions_checked = checked;
                hw.settings = crate::record::Settings::Unsaved;
            }
            let outcome = JogOutcome { joint: jog.joint, code: jog.code, moved_counts: moved.unwrap_or([0; 2]), verdict };
            hw.last_jog = Some(outcome);
            Some(Notice::Jogged(outcome))
        }
    }
}
