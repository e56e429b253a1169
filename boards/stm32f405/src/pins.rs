//! The pin map: every pin the images use, in one place (docs/hardware.md "The
//! reference board": pin assignments are the firmware's choice; a different
//! board changes this file only). Alternate-function numbers are those of the
//! STM32F405 datasheet (DS8626, table 9 "Alternate function mapping").
//!
//! | function | pin | mode |
//! |---|---|---|
//! | AS5047P SPI1 SCK / MISO / MOSI | PA5 / PA6 / PA7 | AF5 |
//! | AS5047P chip select, base joint (`theta1`) | PA4 | output, idle high |
//! | AS5047P chip select, elbow (`theta2 - theta1`) | PB0 | output, idle high |
//! | load cell, tangential `f_t` (ADC1 IN0) | PA0 | analog |
//! | load cell, normal `f_n` (ADC1 IN1) | PA1 | analog |
//! | belt encoder A / B (TIM4 CH1 / CH2, encoder mode) | PB6 / PB7 | AF2, pull-up |
//! | motor 1 (`u1`) PWM (TIM3 CH1, 20 kHz) | PB4 | AF2 |
//! | motor 2 (`u2`) PWM (TIM3 CH2, 20 kHz) | PB5 | AF2 |
//! | motor 1 / motor 2 direction | PB12 / PB13 | output |
//! | motor drivers' shared enable (high = on) | PB14 | output, low at start-up; fit a pull-down: during reset the pin floats |
//! | motor drivers' fault (`nFAULT`, open drain, low = fault) | PB15 | input, pull-up |
//! | enable button (to ground) | PC13 | input, pull-up |
//! | USART1 TX / RX (PIL and hardware in the loop, 2 Mbaud) | PA9 / PA10 | AF7 |
//! | SWD (probe-rs, RTT) | PA13 / PA14 | reserved |
//!
//! The control tick is TIM2's update interrupt (no pin); it also triggers the
//! load cell's conversions (TRGO to ADC1's injected group).

/// The board's crystal, Hz (the Netduino Plus 2 and QEMU's `netduinoplus2`: 25 MHz).
pub const HSE_HZ: u32 = 25_000_000;

/// A GPIO port used by the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Port {
    /// GPIOA.
    A,
    /// GPIOB.
    B,
    /// GPIOC.
    C,
}

/// An internal pull resistor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pull {
    /// None.
    Floating,
    /// Pull-up.
    Up,
}

/// How a pin is configured (RM0090 8.4: MODER, PUPDR, AFR).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Digital input.
    Input(Pull),
    /// Push-pull output starting at the given level (`true` = high).
    Output(bool),
    /// Alternate function `n` (0..=15), very high speed.
    Alternate(u8, Pull),
    /// Analog (ADC input).
    Analog,
}

/// One pin of the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pin {
    /// Port.
    pub port: Port,
    /// Index in the port, 0..=15.
    pub index: u8,
    /// Configuration.
    pub mode: Mode,
    /// What it is for (logs, docs).
    pub name: &'static str,
}

const fn pin(port: Port, index: u8, mode: Mode, name: &'static str) -> Pin {
    Pin { port, index, mode, name }
}

/// SPI1 clock to both encoders.
pub const SPI1_SCK: Pin = pin(Port::A, 5, Mode::Alternate(5, Pull::Floating), "SPI1 SCK");
/// SPI1 MISO (pulled up: an absent encoder then answers 0xFFFF, whose error flag is set).
pub const SPI1_MISO: Pin = pin(Port::A, 6, Mode::Alternate(5, Pull::Up), "SPI1 MISO");
/// SPI1 MOSI.
pub const SPI1_MOSI: Pin = pin(Port::A, 7, Mode::Alternate(5, Pull::Floating), "SPI1 MOSI");
/// Chip select of the base-joint encoder (active low).
pub const CS_THETA1: Pin = pin(Port::A, 4, Mode::Output(true), "CS theta1");
/// Chip select of the elbow encoder (active low).
pub const CS_ELBOW: Pin = pin(Port::B, 0, Mode::Output(true), "CS elbow");
/// Load cell, tangential channel: ADC1 IN0.
pub const LOAD_F_T: Pin = pin(Port::A, 0, Mode::Analog, "load cell f_t (ADC1 IN0)");
/// Load cell, normal channel: ADC1 IN1.
pub const LOAD_F_N: Pin = pin(Port::A, 1, Mode::Analog, "load cell f_n (ADC1 IN1)");
/// ADC1 channels of the load cell, `[f_t, f_n]`.
pub const LOAD_ADC_CHANNELS: [u8; 2] = [0, 1];
/// Belt encoder channel A: TIM4 CH1.
pub const BELT_A: Pin = pin(Port::B, 6, Mode::Alternate(2, Pull::Up), "belt A (TIM4 CH1)");
/// Belt encoder channel B: TIM4 CH2.
pub const BELT_B: Pin = pin(Port::B, 7, Mode::Alternate(2, Pull::Up), "belt B (TIM4 CH2)");
/// Motor 1 PWM: TIM3 CH1.
pub const PWM_U1: Pin = pin(Port::B, 4, Mode::Alternate(2, Pull::Floating), "PWM u1 (TIM3 CH1)");
/// Motor 2 PWM: TIM3 CH2.
pub const PWM_U2: Pin = pin(Port::B, 5, Mode::Alternate(2, Pull::Floating), "PWM u2 (TIM3 CH2)");
/// Motor 1 direction (high = positive torque).
pub const DIR_U1: Pin = pin(Port::B, 12, Mode::Output(false), "DIR u1");
/// Motor 2 direction (high = positive torque).
pub const DIR_U2: Pin = pin(Port::B, 13, Mode::Output(false), "DIR u2");
/// The drivers' shared enable (high = on); low from start-up.
pub const DRIVER_ENABLE: Pin = pin(Port::B, 14, Mode::Output(false), "driver enable");
/// The drivers' fault line (low = fault).
pub const DRIVER_FAULT: Pin = pin(Port::B, 15, Mode::Input(Pull::Up), "driver nFAULT");
/// The enable button (low = pressed).
pub const ENABLE_BUTTON: Pin = pin(Port::C, 13, Mode::Input(Pull::Up), "enable button");
/// USART1 TX.
pub const USART1_TX: Pin = pin(Port::A, 9, Mode::Alternate(7, Pull::Floating), "USART1 TX");
/// USART1 RX (pulled up: an idle, unconnected line reads as a stop bit).
pub const USART1_RX: Pin = pin(Port::A, 10, Mode::Alternate(7, Pull::Up), "USART1 RX");

/// The pins of the arm image (sensors, motors, button).
pub const ARM: [Pin; 17] = [
    SPI1_SCK,
    SPI1_MISO,
    SPI1_MOSI,
    CS_THETA1,
    CS_ELBOW,
    LOAD_F_T,
    LOAD_F_N,
    BELT_A,
    BELT_B,
    PWM_U1,
    PWM_U2,
    DIR_U1,
    DIR_U2,
    DRIVER_ENABLE,
    DRIVER_FAULT,
    ENABLE_BUTTON,
    USART1_TX,
];

/// The pins of the PIL image (the serial link only).
pub const PIL: [Pin; 2] = [USART1_TX, USART1_RX];

/// The debug port's pins, which no image may take (probe-rs and RTT need them).
pub const SWD: [(Port, u8); 2] = [(Port::A, 13), (Port::A, 14)];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_pin_is_used_twice_and_the_debug_port_stays_free() {
        let all: Vec<Pin> = ARM.iter().chain(PIL.iter()).copied().collect();
        for (i, a) in all.iter().enumerate() {
            assert!(a.index < 16, "{}", a.name);
            assert!(!SWD.contains(&(a.port, a.index)), "{} takes a debug pin", a.name);
            for b in &all[i + 1..] {
                if (a.port, a.index) == (b.port, b.index) {
                    assert_eq!(a, b, "{} and {} share a pin", a.name, b.name);
                }
            }
        }
    }

    #[test]
    fn alternate_functions_match_the_datasheet() {
        // DS8626 table 9: AF2 = TIM3..5, AF5 = SPI1/2, AF7 = USART1..3.
        for p in [SPI1_SCK, SPI1_MISO, SPI1_MOSI] {
            assert!(matches!(p.mode, Mode::Alternate(5, _)), "{}", p.name);
        }
        for p in [BELT_A, BELT_B, PWM_U1, PWM_U2] {
            assert!(matches!(p.mode, Mode::Alternate(2, _)), "{}", p.name);
        }
        for p in [USART1_TX, USART1_RX] {
            assert!(matches!(p.mode, Mode::Alternate(7, _)), "{}", p.name);
        }
        // ADC123_IN0 and IN1 are PA0 and PA1.
        assert_eq!((LOAD_F_T.port, LOAD_F_T.index, LOAD_F_N.index), (Port::A, 0, 1));
    }

    #[test]
    fn the_drivers_start_disabled() {
        assert_eq!(DRIVER_ENABLE.mode, Mode::Output(false));
        assert_eq!(CS_THETA1.mode, Mode::Output(true));
        assert_eq!(CS_ELBOW.mode, Mode::Output(true));
    }
}
