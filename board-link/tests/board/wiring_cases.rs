//! The wiring faults of issue 52 and the random admissible scenarios they are
//! tried on (`board_link::random_scenarios`), shared by the twin's tests (`twin.rs`: 200 scenarios per fault and
//! law) and the flashed image's (`emulator.rs`: a sample).

pub use board_link::random_scenarios::random_admissible;
pub use board_link::wiring_faults::WIRING_FAULTS;

/// Whether the paper's `kind` law leaves `fault` without any input to act on:
/// the PID (paper eq. 8) uses no force, and its joint-2 gains are 0 (`u2 = 0`).
pub fn unused_by(kind: &str, fault: &str) -> bool {
    kind == "pid" && (fault.starts_with("load cell") || fault == "motor 2 reversed")
}
