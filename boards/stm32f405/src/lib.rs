//! The reference board (docs/hardware.md "Reference board"): an STM32F405RG with
//! a 25 MHz crystal, two AS5047P encoders, a load cell, a belt encoder and two
//! motor drivers. Everything specific to the chip and the board lives here:
//! start-up, the clock tree, the pin map ([`pins`]: a different board changes
//! that file), the peripherals (through the `stm32f4` PAC) and the images:
//!
//! - `arm` (`src/bin/arm.rs`): the controller on the arm. TIM2's update interrupt
//!   runs one step per period: sensors sampled at the tick, torques written at
//!   the end, the watchdog fed; the safe state disables the drivers.
//! - `pil` (`src/bin/pil.rs`): the controller against the PC's plant over
//!   USART1 (processor in the loop under QEMU, hardware in the loop on a board).
//!
//! Both run the portable firmware through [`firmware::board::handle`]; the
//! `arm` image's per-tick application is the hardware-independent crate
//! `arm-app` (its step statistics and telemetry too), which this crate feeds
//! with the chip's peripherals. The modules here that do not touch the chip
//! ([`clock_tree`], [`pins`], [`timing`]) are tested on the host.
#![cfg_attr(not(test), no_std)]
#![warn(missing_docs)]

pub mod calibration;
pub mod clock_tree;
pub mod pins;
pub mod timing;

#[cfg(target_os = "none")]
pub mod images;
#[cfg(target_os = "none")]
pub mod mcu;
