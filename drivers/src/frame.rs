//! Assembling the period's [`SensorFrame`] from what the drivers read
//! (docs/hardware.md "Sensors": raw counts cross the wire, as on hardware).
//!
//! A reading that failed (any driver error) or is out of its field's range is
//! sent as count 0 with its `frame_flags::*_INVALID` bit set, exactly as the host
//! simulator sends a NaN reading; an asserted (or unreadable) driver fault line
//! sets `frame_flags::DRIVER_FAULT`. So every driver error reaches the firmware's
//! step as an invalid reading, and the firmware's own rules (hold, then the safe
//! state) decide what to do.

use shared::wire::{ENCODER_COUNTS, LOAD_CODE_MAX, LOAD_CODE_MIN, SensorFrame, frame_flags};

use crate::belt::MAX_SPEED_MM_S;

/// Mask of a 14-bit encoder count (`ENCODER_COUNTS` is `2^14`).
const COUNT_MASK: u16 = (ENCODER_COUNTS - 1) as u16;

/// Where an absolute encoder's zero is and which way it counts: the magnet's
/// zero is not the arm's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EncoderCalibration {
    /// The raw count (0..2^14; taken mod 2^14) at the arm's zero angle.
    pub zero_count: u16,
    /// The encoder counts against the joint's positive direction.
    pub reversed: bool,
}

impl EncoderCalibration {
    /// The joint's count in `[0, 2^14)` from a `raw` encoder count: `(raw -
    /// zero) mod 2^14`, or `(zero - raw) mod 2^14` when reversed (counts of
    /// `2 pi / 2^14` rad). `raw` is taken mod 2^14 (so is any 16-bit difference:
    /// 2^14 divides 2^16).
    pub fn apply(&self, raw: u16) -> u16 {
        let diff = if self.reversed { self.zero_count.wrapping_sub(raw) } else { raw.wrapping_sub(self.zero_count) };
        diff & COUNT_MASK
    }
}

/// The calibrations of both encoders.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameCalibration {
    /// The base-joint encoder (`theta1`).
    pub theta1: EncoderCalibration,
    /// The elbow encoder, which sees `theta2 - theta1` directly (it turns with
    /// link 1), so it needs no more than its own zero and direction.
    pub elbow: EncoderCalibration,
}

/// What the drivers read in one period; `None` is a failed reading. The
/// default is "everything failed".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Readings {
    /// The base-joint encoder's raw count (`As5047p::sample`), `[0, 2^14)`.
    pub theta1_raw: Option<u16>,
    /// The elbow encoder's raw count, `[0, 2^14)`.
    pub elbow_raw: Option<u16>,
    /// Load-cell codes `[f_t, f_n]` (`LoadCell::read_codes`), codes of
    /// 25/2048 N in `[-2048, 2047]`; from that read's result `r`:
    /// `r.ok().map_or([None; 2], |c| c.map(Some))`.
    pub load_codes: [Option<i16>; 2],
    /// Belt speed (`BeltEncoder::speed_mm_s`), mm/s in `[-5000, 5000]`.
    pub belt_mm_s: Option<i16>,
    /// Whether the motor drivers assert their fault line
    /// (`MotorStage::fault_asserted`); `None` (unreadable) counts as a fault.
    pub driver_fault: Option<bool>,
}

/// The frame of period `seq` sampled at `t_us` (microseconds since the start)
/// from `readings`, with the encoders' calibrations `cal` applied. A `None`
/// reading, or one outside its field's range (above), sends 0 and sets its
/// `frame_flags::*_INVALID` bit; a driver fault (or an unreadable fault line)
/// sets `frame_flags::DRIVER_FAULT`. No other flag is set.
pub fn assemble(t_us: u64, seq: u32, readings: Readings, cal: &FrameCalibration) -> SensorFrame {
    let load = |code: Option<i16>| code.filter(|c| (LOAD_CODE_MIN..=LOAD_CODE_MAX).contains(c));
    let [f_t, f_n] = readings.load_codes;
    let mut flags = 0;
    let theta1_count = or_invalid(encoder(readings.theta1_raw, &cal.theta1), frame_flags::THETA1_INVALID, &mut flags);
    let elbow_count = or_invalid(encoder(readings.elbow_raw, &cal.elbow), frame_flags::ELBOW_INVALID, &mut flags);
    let f_t_code = or_invalid(load(f_t), frame_flags::F_T_INVALID, &mut flags);
    let f_n_code = or_invalid(load(f_n), frame_flags::F_N_INVALID, &mut flags);
    let belt = readings.belt_mm_s.filter(|v| v.unsigned_abs() <= MAX_SPEED_MM_S.unsigned_abs());
    let belt_count = or_invalid(belt, frame_flags::BELT_INVALID, &mut flags);
    if readings.driver_fault != Some(false) {
        flags |= frame_flags::DRIVER_FAULT;
    }
    SensorFrame { t_us, seq, theta1_count, elbow_count, f_t_code, f_n_code, belt_count, flags }
}

/// The calibrated count of a raw reading, `None` if absent or not 14-bit.
fn encoder(raw: Option<u16>, cal: &EncoderCalibration) -> Option<u16> {
    raw.filter(|&r| r <= COUNT_MASK).map(|r| cal.apply(r))
}

/// The reading, or 0 with `bit` set in `flags` (as the simulator sends a NaN).
fn or_invalid<T: Default>(reading: Option<T>, bit: u16, flags: &mut u16) -> T {
    reading.unwrap_or_else(|| {
        *flags |= bit;
        T::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn good() -> Readings {
        Readings {
            theta1_raw: Some(1000),
            elbow_raw: Some(16000),
            load_codes: [Some(-12), Some(819)],
            belt_mm_s: Some(-400),
            driver_fault: Some(false),
        }
    }

    fn cal() -> FrameCalibration {
        FrameCalibration {
            theta1: EncoderCalibration { zero_count: 1200, reversed: false },
            elbow: EncoderCalibration { zero_count: 100, reversed: true },
        }
    }

    fn good_frame() -> SensorFrame {
        SensorFrame {
            t_us: 7000,
            seq: 7,
            theta1_count: 16384 - 200,
            elbow_count: 100 + 16384 - 16000,
            f_t_code: -12,
            f_n_code: 819,
            belt_count: -400,
            flags: 0,
        }
    }

    #[test]
    fn valid_readings_make_a_clean_frame() {
        assert_eq!(assemble(7000, 7, good(), &cal()), good_frame());
    }

    #[test]
    fn each_failed_reading_sets_exactly_its_bit_and_zeroes_exactly_its_field() {
        type Case = (fn(&mut Readings), u16, fn(&mut SensorFrame));
        let cases: [Case; 6] = [
            (|r| r.theta1_raw = None, frame_flags::THETA1_INVALID, |f| f.theta1_count = 0),
            (|r| r.elbow_raw = None, frame_flags::ELBOW_INVALID, |f| f.elbow_count = 0),
            (|r| r.load_codes[0] = None, frame_flags::F_T_INVALID, |f| f.f_t_code = 0),
            (|r| r.load_codes[1] = None, frame_flags::F_N_INVALID, |f| f.f_n_code = 0),
            (|r| r.belt_mm_s = None, frame_flags::BELT_INVALID, |f| f.belt_count = 0),
            (|r| r.driver_fault = None, frame_flags::DRIVER_FAULT, |_| {}),
        ];
        for (break_reading, bit, zero_field) in cases {
            let mut r = good();
            break_reading(&mut r);
            let mut expected = good_frame();
            zero_field(&mut expected);
            expected.flags = bit;
            assert_eq!(assemble(7000, 7, r, &cal()), expected, "bit {bit:#x}");
        }
        let fault = Readings { driver_fault: Some(true), ..good() };
        assert_eq!(assemble(7000, 7, fault, &cal()), SensorFrame { flags: frame_flags::DRIVER_FAULT, ..good_frame() });
        let none = assemble(1, 2, Readings::default(), &cal());
        assert_eq!(none, SensorFrame { t_us: 1, seq: 2, flags: frame_flags::ANY_INVALID, ..SensorFrame::default() });
    }

    #[test]
    fn out_of_range_readings_are_invalid() {
        let r = Readings {
            theta1_raw: Some(16384),
            elbow_raw: Some(u16::MAX),
            load_codes: [Some(2048), Some(-2049)],
            belt_mm_s: Some(5001),
            driver_fault: Some(false),
        };
        let f = assemble(0, 0, r, &cal());
        assert_eq!(f, SensorFrame { flags: frame_flags::ANY_INVALID & !frame_flags::DRIVER_FAULT, ..SensorFrame::default() });
        let edges = Readings {
            theta1_raw: Some(16383),
            elbow_raw: Some(0),
            load_codes: [Some(2047), Some(-2048)],
            belt_mm_s: Some(-5000),
            driver_fault: Some(false),
        };
        let f = assemble(0, 0, edges, &FrameCalibration::default());
        assert_eq!(f, SensorFrame { theta1_count: 16383, f_t_code: 2047, f_n_code: -2048, belt_count: -5000, ..SensorFrame::default() });
    }

    #[test]
    fn calibration_wraps_both_ways() {
        let fwd = EncoderCalibration { zero_count: 16000, reversed: false };
        assert_eq!(fwd.apply(16000), 0);
        assert_eq!(fwd.apply(10), 394);
        assert_eq!(fwd.apply(15999), 16383);
        let rev = EncoderCalibration { zero_count: 10, reversed: true };
        assert_eq!(rev.apply(10), 0);
        assert_eq!(rev.apply(11), 16383);
        assert_eq!(rev.apply(16383), 11);
    }

    proptest! {
        #[test]
        fn calibration_is_a_rotation_mod_2_14(raw in 0u16..16384, zero in 0u16..16384) {
            let fwd = EncoderCalibration { zero_count: zero, reversed: false }.apply(raw);
            let rev = EncoderCalibration { zero_count: zero, reversed: true }.apply(raw);
            prop_assert!(fwd < 16384 && rev < 16384);
            prop_assert_eq!((fwd + zero) % 16384, raw);
            prop_assert_eq!((fwd + rev) % 16384, 0);
            prop_assert_eq!(EncoderCalibration { zero_count: zero, reversed: false }.apply(zero), 0);
        }

        #[test]
        fn valid_readings_pass_through(raw in 0u16..16384, ft in -2048i16..=2047, fnn in -2048i16..=2047, v in -5000i16..=5000) {
            let r = Readings { theta1_raw: Some(raw), elbow_raw: Some(raw), load_codes: [Some(ft), Some(fnn)], belt_mm_s: Some(v), driver_fault: Some(false) };
            let f = assemble(0, 0, r, &FrameCalibration::default());
            prop_assert_eq!(f, SensorFrame { t_us: 0, seq: 0, theta1_count: raw, elbow_count: raw, f_t_code: ft, f_n_code: fnn, belt_count: v, flags: 0 });
        }
    }
}
