//! The chip: peripherals through the `stm32f4` PAC, behind the embedded-hal
//! and `drivers` traits the images use (Cortex-M4F builds only).

pub mod acquisition;
pub mod adc;
pub mod cycles;
pub mod exit;
pub mod flash;
pub mod gpio;
pub mod iwdg;
pub mod log_time;
pub mod notices;
pub mod rcc;
pub mod spi;
pub mod stack;
pub mod timers;
pub mod usart;

use crate::clock_tree::ClockOutcome;

/// What every image does first: paint the stack, bring up the clocks (or halt),
/// enable the peripheral clocks and start the step's tick counter.
pub fn start(core: &mut cortex_m::Peripherals) -> (ClockOutcome, cycles::CycleClock) {
    stack::paint();
    let clocks = rcc::bring_up_or_halt();
    rcc::enable_peripheral_clocks();
    let clock = cycles::CycleClock::start(&mut core.DCB, &mut core.DWT, &mut core.SYST);
    (clocks, clock)
}
