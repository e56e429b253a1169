//! What the arm application needs of a board: one associated type per part,
//! each behind the trait its driver is written against (embedded-hal 1.0 where
//! it has one; the drivers' own [`LoadCellAdc`] and [`QuadratureCounter`] where
//! it has none), plus the watchdog and the step's clock. The STM32F405 image
//! gives its registers; the board twin (`board-twin`) gives device models driven
//! by the simulated arm (copper-rs's sim mode: the same application, its sources
//! and sinks swapped).

use drivers::{LoadCellAdc, MotorStage, QuadratureCounter};
use embedded_hal::{
    digital::{InputPin, OutputPin},
    pwm::SetDutyCycle,
    spi::SpiDevice,
};
use embedded_storage::nor_flash::NorFlash;
use firmware::{TickClock, pil::StepClock};

/// An independent watchdog: not fed within its timeout, it resets the MCU (the
/// drivers come up disabled). RM0090 "Independent watchdog".
pub trait Watchdog {
    /// Reloads the watchdog's counter (IWDG_KR = 0xAAAA on the STM32F405).
    fn feed(&mut self);
}

/// The step's clock with the interval marks the tick handler needs
/// (docs/board.md "The control step's cost").
pub trait IntervalClock: TickClock {
    /// Starts an interval at an event (the control tick); returns the tick
    /// count it starts from. [`TickClock::ticks`] minus it (wrapping) is the
    /// interval so far.
    fn mark(&self) -> u32;
    /// What the ticks are (cycles on silicon, instructions under QEMU).
    fn kind(&self) -> StepClock;
}

/// A board's parts, by type (docs/hardware.md "Reference board"): the types a
/// board plugs into [`crate::ArmApp`].
pub trait ArmIo {
    /// One AS5047P's SPI device (bus plus its own chip select; mode 1, 16-bit words).
    type Spi: SpiDevice<u16>;
    /// The load cell's two ADC channels.
    type Adc: LoadCellAdc;
    /// The belt's quadrature counter (a timer in encoder mode).
    type Counter: QuadratureCounter;
    /// One motor driver's PWM channel (20 kHz; duty = torque magnitude).
    type Pwm: SetDutyCycle;
    /// A motor driver's direction pin, and the drivers' shared enable pin.
    type Out: OutputPin;
    /// The drivers' shared nFAULT line (low = fault) and the enable button
    /// (low = pressed).
    type In: InputPin;
    /// The independent watchdog.
    type Watchdog: Watchdog;
    /// The step's clock.
    type Clock: IntervalClock;
    /// The flash sector of the settings record (`crate::record`), addressed from 0.
    type Flash: NorFlash;
}

/// The motor stage of a board's parts.
pub type Motors<H> =
    MotorStage<<H as ArmIo>::Pwm, <H as ArmIo>::Out, <H as ArmIo>::Pwm, <H as ArmIo>::Out, <H as ArmIo>::Out, <H as ArmIo>::In>;
