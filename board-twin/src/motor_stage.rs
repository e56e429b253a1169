//! The motor stage's side of the MCU's pins (docs/hardware.md "Reference
//! board", "Full scales and signs"): TIM3's two PWM channels, the two direction
//! pins, the shared enable pin, the shared nFAULT input and the enable button,
//! as embedded-hal 1.0 `SetDutyCycle`, `OutputPin` and `InputPin`; and the
//! drivers' physics: joint torque `u_i = s_i * (duty_i / max_duty) *
//! full_scale_i` with `s_i = +1` for the direction pin high (`-1` low, and the
//! other way for a motor wired reversed), zero while the enable pin is low or
//! nFAULT is asserted.

use core::convert::Infallible;

use embedded_hal::{
    digital::{ErrorType as PinErrorType, InputPin, OutputPin},
    pwm::{ErrorKind, ErrorType as PwmErrorType, SetDutyCycle},
};

use crate::bench::Shared;
use board_description::BoardDescription;

/// A duty above the channel's full scale (the PWM refuses it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DutyOutOfRange;

impl embedded_hal::pwm::Error for DutyOutOfRange {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// One PWM channel (`0`: u1, `1`: u2).
#[derive(Debug)]
pub struct PwmModel {
    bench: Shared,
    index: usize,
    max_duty: u16,
}

impl PwmModel {
    /// Channel `index` of `bench` with full-scale duty `max_duty` counts.
    pub fn new(bench: Shared, index: usize, max_duty: u16) -> Self {
        Self { bench, index: index.min(1), max_duty }
    }
}

impl PwmErrorType for PwmModel {
    type Error = DutyOutOfRange;
}

impl SetDutyCycle for PwmModel {
    fn max_duty_cycle(&self) -> u16 {
        self.max_duty
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), DutyOutOfRange> {
        if duty > self.max_duty {
            return Err(DutyOutOfRange);
        }
        crate::bench::lock(&self.bench).outputs.duty[self.index] = duty;
        Ok(())
    }
}

/// Which wire a pin model is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wire {
    /// Joint 1's direction pin (output).
    Dir1,
    /// Joint 2's direction pin (output).
    Dir2,
    /// The drivers' shared enable pin (output, high = on).
    Enable,
    /// The drivers' shared nFAULT line (input, low = fault).
    Fault,
    /// The enable button (input, low = pressed).
    Button,
}

/// A GPIO pin of the motor stage or the button.
#[derive(Debug)]
pub struct PinModel {
    bench: Shared,
    wire: Wire,
}

impl PinModel {
    /// The pin on `wire` of `bench`.
    pub fn new(bench: Shared, wire: Wire) -> Self {
        Self { bench, wire }
    }

    fn level(&self) -> bool {
        let b = crate::bench::lock(&self.bench);
        match self.wire {
            Wire::Dir1 => b.outputs.dir_high[0],
            Wire::Dir2 => b.outputs.dir_high[1],
            Wire::Enable => b.outputs.enable,
            Wire::Fault => !b.driver_fault,
            Wire::Button => !b.button_held,
        }
    }

    fn drive(&mut self, high: bool) {
        let mut b = crate::bench::lock(&self.bench);
        match self.wire {
            Wire::Dir1 => b.outputs.dir_high[0] = high,
            Wire::Dir2 => b.outputs.dir_high[1] = high,
            Wire::Enable => b.outputs.enable = high,
            // Inputs: driving them does nothing (the pin is not an output).
            Wire::Fault | Wire::Button => {}
        }
    }
}

impl PinErrorType for PinModel {
    type Error = Infallible;
}

impl OutputPin for PinModel {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.drive(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.drive(true);
        Ok(())
    }
}

impl InputPin for PinModel {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(self.level())
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(!self.level())
    }
}

/// The joint torques `[u1, u2]` (N m) the drivers make from the outputs on
/// `bench`, with the wiring and full scales of `board`: zero when disabled or
/// in fault; otherwise the duty's fraction of full scale, signed by the
/// direction pin and the motor's wiring. Saturates at full scale (a duty
/// above it is refused by the PWM).
pub fn joint_torques(bench: &Shared, board: &BoardDescription) -> [f64; 2] {
    let b = crate::bench::lock(bench);
    if !b.outputs.enable || b.driver_fault {
        return [0.0; 2];
    }
    let max = f64::from(board.pwm_max_duty);
    let one = |i: usize, m: &board_description::MotorWiring| {
        let fraction = (f64::from(b.outputs.duty[i]) / max).min(1.0);
        if fraction == 0.0 {
            // Zero duty is zero torque whichever way the direction pin points.
            return 0.0;
        }
        let sign = if b.outputs.dir_high[i] != m.reversed { 1.0 } else { -1.0 };
        sign * fraction * m.full_scale_nm
    };
    [one(0, &board.motor1), one(1, &board.motor2)]
}
