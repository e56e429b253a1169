//! Drivers for the reference board's parts (docs/hardware.md "Reference board"),
//! written against embedded-hal 1.0 traits so that they run on any MCU (the board
//! crate passes STM32F405 peripherals) and are tested on the host against
//! `embedded-hal-mock`. `no_std`, no heap, no `unsafe`; no driver panics on what a
//! device sends.
//!
//! | module | part | for |
//! |---|---|---|
//! | [`as5047p`] | AS5047P 14-bit magnetic encoders on SPI | `theta1` and the elbow's `theta2 - theta1` |
//! | [`load_cell`] | two-axis load cell, instrumentation amplifiers, ADC1 | tip forces `f_t`, `f_n` |
//! | [`belt`] | the belt drive's quadrature encoder on a timer | belt speed, mm/s |
//! | [`motor`] | two current-mode motor drivers: PWM, direction, enable, nFAULT | joint torques `u1`, `u2`, the safe state |
//! | [`frame`] | (none) | the period's `shared::wire::SensorFrame` from the readings above |
//!
//! embedded-hal 1.0 has no ADC trait and no encoder-counter trait, so the load
//! cell and the belt encoder take two small traits of their own,
//! [`LoadCellAdc`] and [`QuadratureCounter`], which the board implements on its
//! ADC and timer.
//!
//! Every driver error is meant to end as an invalid reading in the frame's
//! flags ([`frame::assemble`]), where the firmware's rules decide (hold, then the
//! safe state); a motor-stage error is answered with [`MotorStage::disable`].
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod as5047p;
pub mod belt;
pub mod frame;
pub mod load_cell;
pub mod motor;

pub use as5047p::{As5047p, Diagnostics};
pub use belt::{BeltEncoder, BeltError, QuadratureCounter};
pub use frame::{EncoderCalibration, FrameCalibration, Readings, assemble};
pub use load_cell::{Axis, Calibration, CalibrationError, LoadCell, LoadCellAdc};
pub use motor::{Motor, MotorStage};
