//! The board links and tools end to end, one test binary: the board twin in
//! closed loop (`twin`), the flashed image on the emulated board (`emulator`,
//! `emulator_faults`), bring-up over the protocol (`bringup`), and the wiring
//! faults and random scenarios the twin and the image share (`wiring_cases`).

mod bringup;
mod emulator;
mod emulator_faults;
mod twin;
mod wiring_cases;
