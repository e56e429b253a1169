//! The firmware's calibration of the board (a scenario's `[calibration]`):
//! what the `arm` application believes about its encoders' zeros and
//! directions, the load cell's front end and the belt's scale, kept apart from
//! the board's truth (`[board]`, `board_twin::BoardDescription`) so that the
//! board twin can run a calibration that does not match its board.

use arm_app::ArmCalibration;
use drivers::{EncoderCalibration, FrameCalibration, load_cell::Calibration};
use serde::{Deserialize, Serialize};

/// The firmware's calibration of the board (a scenario's `[calibration]`): what
/// the firmware believes, against the board's truth (`[board]`,
/// `board_twin::BoardDescription`). The defaults equal the reference board's
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
    /// The load cell's gain `[f_t, f_n]`, N per count; non-zero.
    pub load_newtons_per_count: [f32; 2],
    /// Belt travel per quadrature count, m; non-zero.
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

    /// Checks every field; returns what is wrong, naming the key.
    ///
    /// # Errors
    /// A message for the first bad key.
    pub fn check(&self) -> Result<(), String> {
        for (key, v) in [("calibration.theta1_zero_count", self.theta1_zero_count), ("calibration.elbow_zero_count", self.elbow_zero_count)]
        {
            if v >= 16384 {
                return Err(format!("{key} = {v}: a count in [0, 16384)"));
            }
        }
        self.arm_calibration().load_cell.validate().map_err(|e| format!("calibration.load_*: {e:?}"))?;
        let b = self.belt_metres_per_count;
        if !(b.is_finite() && b != 0.0 && b.abs() <= 1.0) {
            return Err(format!("calibration.belt_metres_per_count = {b}: non-zero, |value| <= 1 m"));
        }
        Ok(())
    }
}
