//! GPIO set-up from the pin map and embedded-hal 1.0 pins over it (RM0090 8.4).

use core::convert::Infallible;

use stm32f4::stm32f405 as pac;

use crate::pins::{Mode, Pin, Port, Pull};

/// Runs `$body` with `$g` bound to the register block of `$port`.
macro_rules! with_port {
    ($port:expr, |$g:ident| $body:expr) => {
        // SAFETY: pins are configured at start-up from one context, then each
        // pin's bits are written through BSRR (atomic per bit) or read only.
        match $port {
            Port::A => {
                let $g = unsafe { &*pac::GPIOA::ptr() };
                $body
            }
            Port::B => {
                let $g = unsafe { &*pac::GPIOB::ptr() };
                $body
            }
            Port::C => {
                let $g = unsafe { &*pac::GPIOC::ptr() };
                $body
            }
        }
    };
}

/// Configures `pin` as the map says (the port's clock must be on).
pub fn configure(pin: &Pin) {
    let i = u32::from(pin.index);
    let (moder, pull, af) = match pin.mode {
        Mode::Input(p) => (0b00, p, None),
        Mode::Output(high) => {
            write(pin, high); // the level first: no glitch when the pin turns output
            (0b01, Pull::Floating, None)
        }
        Mode::Alternate(n, p) => (0b10, p, Some(u32::from(n))),
        Mode::Analog => (0b11, Pull::Floating, None),
    };
    let pupd = match pull {
        Pull::Floating => 0b00,
        Pull::Up => 0b01,
    };
    with_port!(pin.port, |g| {
        // SAFETY (bits): each value is a 2-bit or 4-bit field of the pin's own position.
        g.pupdr().modify(|r, w| unsafe { w.bits((r.bits() & !(0b11 << (2 * i))) | (pupd << (2 * i))) });
        g.ospeedr().modify(|r, w| unsafe { w.bits(r.bits() | (0b11 << (2 * i))) });
        if let Some(af) = af {
            if i < 8 {
                g.afrl().modify(|r, w| unsafe { w.bits((r.bits() & !(0xF << (4 * i))) | (af << (4 * i))) });
            } else {
                let j = i - 8;
                g.afrh().modify(|r, w| unsafe { w.bits((r.bits() & !(0xF << (4 * j))) | (af << (4 * j))) });
            }
        }
        g.moder().modify(|r, w| unsafe { w.bits((r.bits() & !(0b11 << (2 * i))) | (moder << (2 * i))) });
    });
}

/// Drives an output pin.
pub fn write(pin: &Pin, high: bool) {
    let bit = if high { 1u32 << pin.index } else { 1u32 << (pin.index + 16) };
    // SAFETY (bits): BSRR sets or resets only the pin's own bit.
    with_port!(pin.port, |g| g.bsrr().write(|w| unsafe { w.bits(bit) }));
}

/// Reads a pin's input level.
pub fn read(pin: &Pin) -> bool {
    with_port!(pin.port, |g| g.idr().read().bits() & (1 << pin.index) != 0)
}

/// A pin of the map as an embedded-hal output or input.
#[derive(Debug, Clone, Copy)]
pub struct GpioPin(pub Pin);

impl embedded_hal::digital::ErrorType for GpioPin {
    type Error = Infallible;
}

impl embedded_hal::digital::OutputPin for GpioPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        write(&self.0, false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        write(&self.0, true);
        Ok(())
    }
}

impl embedded_hal::digital::InputPin for GpioPin {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(read(&self.0))
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!read(&self.0))
    }
}
