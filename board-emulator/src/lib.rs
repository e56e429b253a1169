//! The reference board emulated at the register level (issue 38): the
//! unmodified `arm` ELF, the bytes an engineer flashes, on an emulated
//! STM32F405 whose peripherals the board twin's device models sit behind. The
//! layer the board twin skips (the clock tree, SPI1's mode and frames, ADC1's
//! injected group and its trigger, TIM3's PWM, TIM4's encoder mode, USART1, the
//! flash record, the IWDG) runs here as it would on the part, and every
//! configuration the part or the board would not work with stops the run with
//! the register and its value.
//!
//! The engine is rsemu 0.0.7 (MIT; docs/architecture.md "The emulated image"
//! gives the measurements that chose it): its Cortex-M4F core with NVIC, DWT
//! and SysTick, and its STM32F4 RCC, flash, timers, GPIO and IWDG; ours are
//! SPI1, ADC1, USART1 and the board's side of the pins, added through its
//! public registry, with the devices behind them from `board_twin` (one model
//! of each device for the twin and the emulator).
//!
//! | module | holds |
//! |---|---|
//! | [`image`] | the ELF: flash content, the RAM symbols read (monitor block, RTT, stack) |
//! | [`machine`] | the rsemu machine: the STM32F407 description plus the board's parts and wires |
//! | [`device`] | our device classes in rsemu, and [`device::BoardError`] |
//! | [`spi1`], [`adc1`], [`usart1`], [`dma2`] | the peripherals we model, each strict |
//! | [`checks`] | the board's checks of the peripherals rsemu models (clock tree, pins, timers, IWDG) |
//! | [`core_clock`] | the core wrapped: a sleeping core skips to the next event; the tick handler's instructions, latency and cycles |
//! | [`accelerator`], [`flash_reads`] | the flash's wait states behind the ART accelerator, costed on the executed instructions |
//! | [`belt`] | the belt encoder's quadrature edges into TIM4 |
//! | [`board`] | [`EmulatedBoard`]: one control period at a time, against the board's physics |
//! | [`flash_sequence`] | the flash interface's programming sequence, checked |
//! | `widen` | narrow writes for rsemu's word-only windows (the IWDG) |

pub mod accelerator;
pub mod adc1;
pub mod belt;
pub mod board;
pub mod checks;
pub mod core_clock;
pub mod device;
pub mod dma2;
pub mod flash_reads;
pub mod flash_sequence;
pub mod image;
pub mod machine;
pub mod spi1;
pub mod usart1;
mod widen;

pub use board::{EmuError, EmulatedBoard, RegisterFault};
pub use device::BoardError;
pub use dma2::DmaFaults;
pub use image::{ArmImage, ImageError};
pub use spi1::SpiFaults;
