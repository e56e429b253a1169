//! The wiring faults of issue 52, as changes of the board's truth
//! ([`BoardDescription`]): what the firmware's wiring checks must stop within
//! 0.1 s and 30 mm of the healthy path, under any law (the board's tests for
//! the paper's laws, `examples/law-template/tests/protection.rs` for a law of
//! one's own).

use board_twin::BoardDescription;

/// A wiring fault: its name, and how it changes the board's truth.
pub type WiringFault = (&'static str, fn(&mut BoardDescription));

/// The wiring faults of issue 52.
pub const WIRING_FAULTS: [WiringFault; 8] = [
    ("motor 1 reversed", |b| b.motor1.reversed = true),
    ("motor 2 reversed", |b| b.motor2.reversed = true),
    ("theta1 encoder reversed", |b| b.theta1_encoder.reversed = true),
    ("elbow encoder reversed", |b| b.elbow_encoder.reversed = true),
    ("encoders swapped", |b| b.encoders_swapped = true),
    ("load cell's normal axis reversed", |b| b.load_cell.counts_per_newton[1] *= -1.0),
    ("load cell's tangential axis reversed", |b| b.load_cell.counts_per_newton[0] *= -1.0),
    ("load cell reversed", |b| {
        b.load_cell.counts_per_newton[0] *= -1.0;
        b.load_cell.counts_per_newton[1] *= -1.0;
    }),
];
