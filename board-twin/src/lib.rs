//! The board twin (issue 23): a host simulation of the reference board
//! (docs/hardware.md "Reference board") at the bus level, each device from its
//! datasheet, running the `arm` image's very application (`arm-app`) with the
//! simulated arm in lockstep (`sil-host run --link twin`; docs/board.md "The
//! board twin").
//!
//! | module | models |
//! |---|---|
//! | [`description`] | the board's physical truth (mountings, gains, wiring, full scales), a scenario's `[board]` |
//! | [`bench`] | what the devices share in a period: the arm's inputs, the faults, the pins' outputs |
//! | [`acquisition`] | the encoders' frames of a period, as the image's DMA moves them, and its faults (TEIF, FEIF, DMEIF, timeout, stuck chip select) |
//! | [`as5047p`] | the AS5047P's SPI side: 16-bit frames, parity, the one-frame pipeline, ERRFL, DIAAGC |
//! | [`adc`] | the load cell's amplifiers into 12-bit ADC codes |
//! | [`counter`] | the belt's quadrature counter, 16-bit wrap |
//! | [`flash`] | the settings record's flash sector: erase to `0xFF`, program clears bits, word writes |
//! | [`motor_stage`] | PWM, direction, enable, nFAULT, the button; duty to joint torque |
//! | [`physics`] | the arm into what the devices sense, the pins' outputs into joint torques: shared by the twin and the emulated `arm` ELF |
//! | [`twin`] | [`BoardTwin`]: the application on the models, one tick at a time |
//!
//! What it does not model: SPI and ADC timing (transfers are instant), the
//! encoders' dynamic angle error and hysteresis, the amplifiers' bandwidth, the
//! drivers' current loop (torque follows the duty at once), the PWM's ripple, the
//! MCU's clock (a step takes no time: deadline figures come from PIL).

pub mod acquisition;
pub mod adc;
pub mod as5047p;
pub mod bench;
pub mod counter;
pub use board_description as description;
pub mod flash;
pub mod motor_stage;
pub mod physics;
pub mod twin;

pub use bench::EncoderFaults;
pub use description::{BoardDescription, EncoderMounting, LoadCellFrontEnd, MotorWiring};
pub use flash::FlashModel;
pub use physics::{ArmState, BoardPhysics, BusFaults};
pub use twin::{BoardTwin, TwinError, TwinIo};
