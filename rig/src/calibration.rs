//! The firmware's calibration of the board (a scenario's `[calibration]`):
//! what the `arm` application believes about its encoders' zeros and
//! directions, the load cell's front end and the belt's scale, kept apart from
//! the board's truth (`[board]`, `board_description::BoardDescription`) so that the
//! board twin can run a calibration that does not match its board.

use arm_app::ArmCalibration;
use drivers::{EncoderCalibration, FrameCalibration, load_cell::Calibration};
use serde::{Deserialize, Serialize};

/// The firmware's calibration of the board (a scenario's `[calibration]`): what
/// the firmware believes, against the board's truth (`[board]`,
/// `board_description::BoardDescription`). The defaults equal the reference board's
/// description, and the `arm` image's compiled-in calibration
/// (`boards/stm32f405/src/calibration.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CalibrationSection {
    /// The base encoder's raw count at `theta1 = 0`, in `[0, 16384)`.
    pub theta1_zero_count: u16,
    /// The base encoder counts against `theta1`.
    pub theta1_reversed: bool,
    /// The elbow encoder's raw count at `theta2 - theta1 = 0`, in `[0, 16384)`.
    pub elbow_zero_count: u16,
    /// The elbow encoder counts against `theta2 - theta1`.
    pub elbow_reversed: bool,
    /// The load cell's ADC count at zero force `[f_t, f_n]`, in `[0, 4095]`.
    pub load_zero_counts: [f32; 2],
    /// The load cell's gain `[f_t, f_n]`, N per count; positive, within a factor
    /// 4 of the nominal 25/2048 ([`check_load_cell`]).
    pub load_newtons_per_count: [f32; 2],
    /// Belt travel per quadrature count, m; non-zero, 0.153 to 100 mm/s per count
    /// over a control period ([`check_belt`]).
    pub belt_metres_per_count: f32,
}

impl Default for CalibrationSection {
    fn default() -> Self {
        Self {
            theta1_zero_count: 0,
            theta1_reversed: false,
            elbow_zero_count: 0,
            elbow_reversed: false,
            load_zero_counts: [2048.0; 2],
            load_newtons_per_count: [25.0 / 2048.0; 2],
            belt_metres_per_count: 1e-6,
        }
    }
}

impl CalibrationSection {
    /// The application's calibration.
    pub fn arm_calibration(&self) -> ArmCalibration {
        ArmCalibration {
            encoders: FrameCalibration {
                theta1: EncoderCalibration { zero_count: self.theta1_zero_count, reversed: self.theta1_reversed },
                elbow: EncoderCalibration { zero_count: self.elbow_zero_count, reversed: self.elbow_reversed },
            },
            load_cell: Calibration { zero_counts: self.load_zero_counts, newtons_per_count: self.load_newtons_per_count },
            belt_metres_per_count: self.belt_metres_per_count,
        }
    }

    /// Checks every field at control period `period_s` (s; the belt's scale
    /// is judged per period), with the firmware's own rules ([`check_load_cell`],
    /// [`check_belt`]); returns what is wrong, naming the key.
    ///
    /// # Errors
    /// A message for the first bad key (`` `calibration.load_newtons_per_count[1]` = ... ``).
    pub fn check(&self, period_s: f32) -> Result<(), String> {
        for (key, v) in [("calibration.theta1_zero_count", self.theta1_zero_count), ("calibration.elbow_zero_count", self.elbow_zero_count)]
        {
            if v >= 16384 {
                return Err(format!("{key} = {v}: a count in [0, 16384)"));
            }
        }
        check_load_cell(&self.arm_calibration().load_cell, "calibration.load_zero_counts", "calibration.load_newtons_per_count")?;
        check_belt("calibration.belt_metres_per_count", self.belt_metres_per_count, period_s)
    }
}

/// The load cell's calibration by the firmware's rule
/// (`drivers::load_cell::Calibration::validate`: each zero within the ADC's
/// 0..=4095 counts, each gain positive and within a factor 4 of the nominal
/// 25/2048 N per count), the refused value named by its key: `zero_key[i]` or
/// `gain_key[i]` (`i` 0 for `f_t`, 1 for `f_n`).
///
/// # Errors
/// `` "`key[i]` = value: why" `` for the first refused value.
pub fn check_load_cell(cal: &Calibration, zero_key: &str, gain_key: &str) -> Result<(), String> {
    cal.validate().map_err(|e| {
        let i = e.axis().index();
        match e {
            drivers::load_cell::CalibrationError::BadZero(_) => format!("`{zero_key}[{i}]` = {}: {e}", cal.zero_counts[i]),
            drivers::load_cell::CalibrationError::BadGain(_) => format!("`{gain_key}[{i}]` = {:e}: {e}", cal.newtons_per_count[i]),
        }
    })
}

/// The belt's scale `metres_per_count` at control period `period_s` by the
/// firmware's rule (`drivers::belt::scale`: finite, non-zero, 0.153 to 100 mm/s
/// per count of change over a period), named `key`.
///
/// # Errors
/// `` "`key` = value: why" `` when refused.
pub fn check_belt(key: &str, metres_per_count: f32, period_s: f32) -> Result<(), String> {
    drivers::belt::scale(metres_per_count, period_s).map(|_| ()).map_err(|_| {
        let (lo, hi) = (drivers::belt::MIN_MM_S_PER_COUNT, drivers::belt::MAX_MM_S_PER_COUNT);
        format!(
            "`{key}` = {metres_per_count:e}: the belt's travel per count must give {lo:.3} to {hi} mm/s per count of change over \
             a control period of {period_s} s ({:e} to {:e} m per count; the reference board's is 1e-6)",
            lo * period_s / 1000.0,
            hi * period_s / 1000.0
        )
    })
}
