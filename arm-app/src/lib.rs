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
//! | [`notice`] | what the application tells the operator, as values |
//! | [`step_stats`] | the step's execution time per window |
//! | [`telemetry`] | the window's report on USART1 |
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod app;
pub mod io;
pub mod notice;
pub mod step_stats;
pub mod telemetry;

pub use app::{ArmApp, ArmCalibration, ArmParts, BUTTON_PERIODS, Motors, StartError};
pub use io::{ArmIo, IntervalClock, Watchdog};
pub use notice::{EncoderFault, Joint, Notice};
