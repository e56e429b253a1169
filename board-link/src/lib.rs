//! The rig's links to a board, and the board tools (docs/board.md), above the
//! rig (`rig`: scenarios, the period loop, the wire-level links):
//!
//! | module | what it holds |
//! |---|---|
//! | [`twin_link`] | the board twin as a firmware link (`run --link twin`) |
//! | [`emulator_link`] | the unmodified `arm` ELF on the emulated board as a firmware link (`run --link emulator`) |
//! | [`free_arm`] | the arm hanging free over a lowered belt, on the twin or the emulated image: what bring-up runs against |
//! | [`bringup_line`] | the bring-up protocol over a serial line: the host's client and the twin's server |
//! | [`bringup_procedure`] | the bring-up steps `sil-host board` runs, each refusal and failed check in words |
//! | [`board_backup`] | a board's configuration and calibration as a TOML file (`board backup`, `board restore`) |
//! | [`fmea`] | the FMEA's fault classes and its promise, measured on the twin under any law |
//! | [`random_scenarios`] | random admissible scenarios, reproducible: the wiring faults' and the control handler's samples |
//!
//! Kept out of `rig` so that what only simulates (the analyses, the
//! experiments, the Python package, the fuzzers) builds neither the board twin
//! nor the emulator.
#![warn(missing_docs)]

pub mod board_backup;
pub mod bringup_line;
pub mod bringup_procedure;
pub mod emulator_link;
pub mod fmea;
pub mod free_arm;
pub mod random_scenarios;
pub mod setting_units;
pub mod twin_link;
pub mod wiring_faults;

pub use emulator_link::EmulatorLink;
pub use twin_link::TwinLink;
