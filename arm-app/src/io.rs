//! What the arm application needs of a board: one associated type per part,
//! each behind the trait its driver is written against (embedded-hal 1.0 where
//! it has one; the drivers' own [`LoadCellAdc`] and [`QuadratureCounter`] where
//! it has none), plus the watchdog and the step's clock. The STM32F405 image
//! gives its registers; the board twin (`board-twin`) gives device models driven
//! by the simulated arm (copper-rs's sim mode: the same application, its sources
//! and sinks swapped).

use drivers::{As5047p, LoadCellAdc, MotorStage, QuadratureCounter};
use embedded_hal::{
    digital::{InputPin, OutputPin},
    pwm::SetDutyCycle,
    spi::SpiDevice,
};
use embedded_storage::nor_flash::NorFlash;
use firmware::{TickClock, pil::StepClock};

use crate::joint::EncoderFault;

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

/// How a board takes the period's sample of both encoders (the frames of
/// `drivers::as5047p::SampleSequence`, theta1's then the elbow's).
///
/// The `arm` image acquires them without the core: TIM2's update starts SPI1's
/// frames through DMA2 and the results are in memory when the control interrupt
/// runs (docs/board.md "The encoders by DMA"); the board twin runs the same
/// frames on its device models ([`Blocking`] plus the acquisition's faults).
pub trait EncoderAcquisition<S: SpiDevice<u16>> {
    /// This period's samples `[theta1, elbow]`: each the 14-bit count in
    /// `[0, 2^14)` or why there is none. `theta1` and `elbow` are the
    /// encoders' drivers, for a board that samples them on the spot.
    fn acquire(&mut self, theta1: &mut As5047p<S>, elbow: &mut As5047p<S>) -> [Result<u16, EncoderFault>; 2];
}

/// The encoders sampled on the spot by their drivers ([`As5047p::sample`],
/// blocking on each frame).
#[derive(Debug, Clone, Copy, Default)]
pub struct Blocking;

impl<S: SpiDevice<u16>> EncoderAcquisition<S> for Blocking {
    fn acquire(&mut self, theta1: &mut As5047p<S>, elbow: &mut As5047p<S>) -> [Result<u16, EncoderFault>; 2] {
        [theta1.sample(), elbow.sample()].map(|r| r.map_err(|e| EncoderFault::of(&e)))
    }
}

/// A board's parts, by type (docs/hardware.md "Reference board"): the types a
/// board plugs into [`crate::ArmApp`].
pub trait ArmIo {
    /// One AS5047P's SPI device (bus plus its own chip select; mode 1, 16-bit words).
    type Spi: SpiDevice<u16>;
    /// How the period's encoder samples are taken ([`EncoderAcquisition`]).
    type Encoders: EncoderAcquisition<Self::Spi>;
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
