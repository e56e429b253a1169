//! The arm's calibration: the encoders' zeros and directions, the load cell's
//! front end and the belt encoder's scale, which turn the board's raw readings
//! into the wire's units (docs/board.md "Calibration"). Kept in the flash record
//! ([`crate::record`]) and put in force by [`crate::app::ArmApp`].

use drivers::{frame::FrameCalibration, load_cell::Calibration};

/// The arm's calibration: what turns raw readings into the wire's units
/// (docs/board.md "Calibration").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmCalibration {
    /// The encoders' zeros and directions.
    pub encoders: FrameCalibration,
    /// The load cell's front end (zero counts, N per count, per axis).
    pub load_cell: Calibration,
    /// Belt travel per quadrature count, m (negative flips the direction).
    pub belt_metres_per_count: f32,
}
