//! The `arm` image's application, free of registers (issue 23): everything the
//! image does per control tick, generic over the parts' traits ([`ArmIo`]:
//! embedded-hal 1.0 `SpiDevice`, `OutputPin`, `InputPin`, `SetDutyCycle`; the
//! drivers' `LoadCellAdc` and `QuadratureCounter`; a [`Watchdog`]; the step's
//! [`IntervalClock`]). The STM32F405 image (`boards/stm32f405/src/bin/arm.rs`)
//! creates the peripherals and calls [`ArmApp::tick`] from TIM2's interrupt; the
//! board twin runs the very same code against device models on the host.
//!
//! | module | holds |
//! |---|---|
//! | [`io`] | the traits a board implements |
//! | [`app`] | [`ArmApp`]: start-up and the control tick |
//! | [`joint`] | the encoders by name, and their faults |
//! | [`monitor`] | the block the image publishes in RAM each tick for a debugger or the emulator |
//! | [`notice`] | what the application tells the operator, as values |
//! | [`bringup`] | the bring-up protocol on USART1: requests, replies, refusals |
//! | [`rate`] | the control rates the image runs, and [`ArmApp::retime`]: a board following a new one |
//! | [`record`] | the settings record in flash: format, load, save, and the lockout it drives |
//! | `service` | [`ArmApp::serve`]: the bring-up requests, and the jog the ticks run |
//! | [`step_stats`] | the step's execution time per window |
//! | [`telemetry`] | the window's report on USART1 |
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod app;
pub mod bringup;
pub mod calibration;
pub mod hardware;
pub mod io;
mod jog;
pub mod joint;
pub mod monitor;
pub mod notice;
pub mod rate;
pub mod record;
mod service;
pub mod step_stats;
pub mod telemetry;

pub use app::{ArmApp, ArmParts, StartError};
pub use calibration::ArmCalibration;
pub use hardware::{BUTTON_PRESS_S, CODES_FULL_SCALE, button_periods};
pub use io::{ArmIo, Blocking, EncoderAcquisition, IntervalClock, Motors, Watchdog};
pub use joint::{AcquisitionFault, EncoderFault, Joint};
pub use notice::Notice;
pub use record::Settings;
