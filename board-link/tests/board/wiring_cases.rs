//! The wiring faults of issue 52 and the random admissible scenarios they are
//! tried on (`board_link::random_scenarios`), shared by the twin's tests (`twin.rs`: 200 scenarios per fault and
//! law) and the flashed image's (`emulator.rs`: a sample).

pub use board_link::random_scenarios::random_admissible;
use board_twin::BoardDescription;

/// A wiring fault: its name, and how it changes the board's truth.
pub type WiringFault = (&'static str, fn(&mut BoardDescription));

/// The wiring faults of issue 52, as changes of the board's truth.
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

/// Whether the paper's `kind` law leaves `fault` without any input to act on:
/// the PID (paper eq. 8) uses no force, and its joint-2 gains are 0 (`u2 = 0`).
pub fn unused_by(kind: &str, fault: &str) -> bool {
    kind == "pid" && (fault.starts_with("load cell") || fault == "motor 2 reversed")
}
