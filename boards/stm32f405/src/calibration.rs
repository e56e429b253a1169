//! The arm's calibration constants: where each encoder's zero is, the load
//! cell's front end, the belt encoder's scale. Measure them on your arm and
//! change them here (docs/board.md "Calibration").

use drivers::{
    frame::{EncoderCalibration, FrameCalibration},
    load_cell::Calibration,
};

/// The encoders' zeros and directions: the raw count with the link hanging
/// straight down (`theta1 = 0`) and with the two links aligned (`theta2 -
/// theta1 = 0`). Zero until measured.
pub const ENCODERS: FrameCalibration = FrameCalibration {
    theta1: EncoderCalibration { zero_count: 0, reversed: false },
    elbow: EncoderCalibration { zero_count: 0, reversed: false },
};

/// The load cell's front end: zero force at mid-scale, 25 N over 2048 counts
/// (the wire's scale, docs/hardware.md: +-25 N on 12 bits).
pub const LOAD_CELL: Calibration = Calibration { zero_counts: [2048.0; 2], newtons_per_count: [25.0 / 2048.0; 2] };

/// Belt travel per quadrature count, m: at the default 1 kHz one count per
/// period is 1 mm/s, the resolution docs/hardware.md asks for.
pub const BELT_METRES_PER_COUNT: f32 = 1e-6;
