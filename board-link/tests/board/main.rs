//! The board links and tools end to end, one test binary: the board twin in
//! closed loop (`twin`), the flashed image on the emulated board (`emulator`,
//! `emulator_faults`; `dma_faults`: the encoders' acquisition faults over random
//! sequences on both), bring-up over the protocol (`bringup`), and the wiring
//! faults and random scenarios the twin and the image share (`wiring_cases`),
//! the control rate set by configuration on both (`rate`).

mod bringup;
mod dma_faults;
mod emulator;
mod emulator_faults;
mod rate;
mod twin;
mod wiring_cases;
