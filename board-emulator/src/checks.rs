//! The reference board's checks of the peripherals rsemu models (RCC, flash
//! wait states, GPIO, TIM2, TIM3, TIM4, IWDG), read as a debugger reads them:
//! the image must configure each as the board and the parts need, or the run
//! stops with a [`BoardError`] naming the register and its value. Sources: the
//! board's pin table (docs/board.md), the STM32F405 datasheet DS8626 (table 9,
//! alternate functions; the LSI's range), RM0090 (registers), the AS5047P and
//! motor drivers' needs (docs/hardware.md).

use rsemu::{
    core::{space::MemAttrs, value::Width},
    machine::Machine,
};

use crate::device::BoardError;

/// The board's crystal (docs/hardware.md: 25 MHz), Hz.
pub const HSE_HZ: u32 = 25_000_000;
/// The core clock the board runs at, Hz.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// TIM2 to TIM5's clock: APB1 (42 MHz) times 2, Hz (RM0090 7.2).
pub const APB1_TIMER_HZ: u32 = 84_000_000;
/// The motor drivers' PWM rate (docs/hardware.md), Hz.
pub const PWM_HZ: u32 = 20_000;
/// The LSI's fastest (DS8626 table 40: 47 kHz), Hz.
pub const LSI_MAX_HZ: u32 = 47_000;

/// A pin's required configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PinMode {
    /// General-purpose output.
    Output,
    /// Input with the given pull (`Some(true)` up, `Some(false)` down, `None` any).
    Input(Option<bool>),
    /// Alternate function `af` (DS8626 table 9), with a pull-up when `true`.
    Alternate(u8, bool),
    /// Analog (an ADC input).
    Analog,
}

/// One pin of the board's table: port (`b'A'`...), number, mode, signal.
pub type PinSpec = (u8, u8, PinMode, &'static str);

/// The reference board's pins (docs/board.md "Pin map"), each with the
/// alternate function DS8626 table 9 gives its signal on that pin.
pub const BOARD_PINS: [PinSpec; 18] = [
    (b'A', 5, PinMode::Alternate(5, false), "SPI1_SCK (AF5) to both AS5047P"),
    (b'A', 6, PinMode::Alternate(5, true), "SPI1_MISO (AF5, pulled up) from both AS5047P"),
    (b'A', 7, PinMode::Alternate(5, false), "SPI1_MOSI (AF5) to both AS5047P"),
    (b'A', 4, PinMode::Output, "the theta1 encoder's chip select"),
    (b'B', 0, PinMode::Output, "the elbow encoder's chip select"),
    (b'A', 0, PinMode::Analog, "ADC123_IN0: the load cell's f_t amplifier"),
    (b'A', 1, PinMode::Analog, "ADC123_IN1: the load cell's f_n amplifier"),
    (b'B', 6, PinMode::Alternate(2, true), "TIM4_CH1 (AF2): the belt encoder's A"),
    (b'B', 7, PinMode::Alternate(2, true), "TIM4_CH2 (AF2): the belt encoder's B"),
    (b'B', 4, PinMode::Alternate(2, false), "TIM3_CH1 (AF2): motor 1's PWM"),
    (b'B', 5, PinMode::Alternate(2, false), "TIM3_CH2 (AF2): motor 2's PWM"),
    (b'B', 12, PinMode::Output, "motor 1's direction"),
    (b'B', 13, PinMode::Output, "motor 2's direction"),
    (b'B', 14, PinMode::Output, "the drivers' shared enable"),
    (b'B', 15, PinMode::Input(Some(true)), "the drivers' nFAULT (open drain, pulled up)"),
    (b'C', 13, PinMode::Input(Some(true)), "the enable button (to ground, pulled up)"),
    (b'A', 9, PinMode::Alternate(7, false), "USART1_TX (AF7): the bring-up line"),
    (b'A', 10, PinMode::Alternate(7, false), "USART1_RX (AF7): the bring-up line"),
];

/// A debugger's read of the word at `addr` (0 when nothing answers).
pub fn peek(m: &Machine, addr: u32) -> u32 {
    m.space("mem").and_then(|s| s.read(u64::from(addr), Width::U32, MemAttrs::DEBUG).ok()).unwrap_or(0) as u32
}

fn err(name: &str, addr: u32, value: u32, why: String) -> BoardError {
    BoardError::new(format!("{name} ({addr:#010x})"), value, why)
}

/// The clock tree from the board's 25 MHz crystal: PLL from HSE to 168 MHz
/// with a VCO input of 1 to 2 MHz, SYSCLK from the PLL, AHB /1, APB1 /4 (42
/// MHz, timers 84 MHz), APB2 /2 (84 MHz), and 5 flash wait states (RM0090 3.5.1:
/// 168 MHz at 2.7 to 3.6 V).
///
/// # Errors
/// The first register that differs.
pub fn clock_tree(m: &Machine) -> Result<(), BoardError> {
    const RCC: u32 = 0x4002_3800;
    let pll = peek(m, RCC + 0x04);
    let (pllm, plln, pllp) = (pll & 0x3F, (pll >> 6) & 0x1FF, 2 * (((pll >> 16) & 0b11) + 1));
    if pll & (1 << 22) == 0 {
        return Err(err(
            "RCC_PLLCFGR",
            RCC + 4,
            pll,
            "the PLL's source is HSI: the board's clock is its 25 MHz crystal (PLLSRC = 1)".into(),
        ));
    }
    let vco_in = f64::from(HSE_HZ) / f64::from(pllm.max(1));
    let sys = vco_in * f64::from(plln) / f64::from(pllp);
    if !(1e6..=2e6).contains(&vco_in) || (sys - f64::from(SYSCLK_HZ)).abs() > 1.0 {
        return Err(err(
            "RCC_PLLCFGR",
            RCC + 4,
            pll,
            format!(
                "PLLM {pllm}, PLLN {plln}, PLLP {pllp} give {:.3} MHz from the 25 MHz crystal (VCO input {:.3} MHz): the board runs at 168 MHz with a VCO input of 1 to 2 MHz",
                sys / 1e6,
                vco_in / 1e6
            ),
        ));
    }
    let cfgr = peek(m, RCC + 0x08);
    let (sws, hpre, ppre1, ppre2) = ((cfgr >> 2) & 0b11, (cfgr >> 4) & 0xF, (cfgr >> 10) & 0b111, (cfgr >> 13) & 0b111);
    if sws != 0b10 || hpre != 0 || ppre1 != 0b101 || ppre2 != 0b100 {
        return Err(err(
            "RCC_CFGR",
            RCC + 8,
            cfgr,
            "the clocks must be SYSCLK from the PLL (SWS 0b10), AHB /1, APB1 /4 (42 MHz: timers at 84 MHz), APB2 /2 (84 MHz: SPI1, ADC1, USART1)".into(),
        ));
    }
    let acr = peek(m, 0x4002_3C00);
    if acr & 0xF < 5 {
        return Err(err("FLASH_ACR", 0x4002_3C00, acr, format!("{} wait states: 168 MHz needs 5 (RM0090 table 10)", acr & 0xF)));
    }
    Ok(())
}

/// Each pin of [`BOARD_PINS`] in its mode, with its alternate function and pull.
///
/// # Errors
/// The first pin whose MODER, AFR or PUPDR differs, naming the pin and its signal.
pub fn pins(m: &Machine) -> Result<(), BoardError> {
    for (port, n, mode, signal) in BOARD_PINS {
        let base = 0x4002_0000 + 0x400 * u32::from(port - b'A');
        let pin = u32::from(n);
        let moder = (peek(m, base) >> (2 * pin)) & 0b11;
        let pupd = (peek(m, base + 0x0C) >> (2 * pin)) & 0b11;
        let afr_addr = base + if pin < 8 { 0x20 } else { 0x24 };
        let af = (peek(m, afr_addr) >> (4 * (pin % 8))) & 0xF;
        let name = format!("P{}{n}", port as char);
        let want = |what: &str| format!("{name} carries {signal}: it must be {what}");
        match mode {
            PinMode::Output if moder != 0b01 => {
                return Err(err(&format!("GPIO{}_MODER", port as char), base, peek(m, base), want("an output (MODER 0b01)")));
            }
            PinMode::Analog if moder != 0b11 => {
                return Err(err(&format!("GPIO{}_MODER", port as char), base, peek(m, base), want("analog (MODER 0b11)")));
            }
            PinMode::Input(_) if moder != 0b00 => {
                return Err(err(&format!("GPIO{}_MODER", port as char), base, peek(m, base), want("an input (MODER 0b00)")));
            }
            PinMode::Alternate(..) if moder != 0b10 => {
                return Err(err(&format!("GPIO{}_MODER", port as char), base, peek(m, base), want("an alternate function (MODER 0b10)")));
            }
            PinMode::Alternate(want_af, _) if af != u32::from(want_af) => {
                return Err(err(
                    &format!("GPIO{}_AFR{}", port as char, if pin < 8 { 'L' } else { 'H' }),
                    afr_addr,
                    peek(m, afr_addr),
                    want(&format!("AF{want_af} (AF{af} routes another peripheral there)")),
                ));
            }
            PinMode::Input(Some(true)) | PinMode::Alternate(_, true) if pupd != 0b01 => {
                return Err(err(&format!("GPIO{}_PUPDR", port as char), base + 0x0C, peek(m, base + 0x0C), want("pulled up (PUPDR 0b01)")));
            }
            _ => {}
        }
    }
    Ok(())
}

/// TIM2 as the control tick (update interrupt at `rate_hz`, TRGO on update for
/// the ADC), TIM3 as the motors' 20 kHz PWM (channels 1 and 2, PWM mode 1,
/// active high, edge-aligned, counting up), TIM4 in encoder mode 3 on both
/// inputs, counting the belt's way, 16-bit.
///
/// # Errors
/// The first register that differs.
pub fn timers(m: &Machine, rate_hz: f64) -> Result<(), BoardError> {
    let (t2, t3, t4) = (0x4000_0000, 0x4000_0400, 0x4000_0800);
    let rate = |t: u32| f64::from(APB1_TIMER_HZ) / f64::from(peek(m, t + 0x28) + 1) / (f64::from(peek(m, t + 0x2C)) + 1.0);
    let cr1 = peek(m, t2);
    if cr1 & 1 == 0 || peek(m, t2 + 0x0C) & 1 == 0 {
        return Err(err(
            "TIM2_CR1",
            t2,
            cr1,
            "the control tick's timer is not counting with its update interrupt enabled (CEN, DIER.UIE)".into(),
        ));
    }
    let f2 = rate(t2);
    if (f2 / rate_hz - 1.0).abs() > 1e-6 {
        return Err(err(
            "TIM2_ARR",
            t2 + 0x2C,
            peek(m, t2 + 0x2C),
            format!("TIM2 updates at {f2:.3} Hz: the control rate is {rate_hz} Hz"),
        ));
    }
    let cr2 = peek(m, t2 + 0x04);
    if (cr2 >> 4) & 0b111 != 0b010 {
        return Err(err(
            "TIM2_CR2",
            t2 + 4,
            cr2,
            "MMS is not `update` (0b010): TRGO would not start the load cell's conversions at the tick".into(),
        ));
    }
    let f3 = rate(t3);
    if (f3 / f64::from(PWM_HZ) - 1.0).abs() > 0.01 || peek(m, t3) & 1 == 0 {
        return Err(err(
            "TIM3_ARR",
            t3 + 0x2C,
            peek(m, t3 + 0x2C),
            format!("the motors' PWM runs at {f3:.1} Hz (or TIM3 is stopped): the drivers take 20 kHz"),
        ));
    }
    let c3 = peek(m, t3);
    if (c3 >> 4) & 0b111 != 0 {
        return Err(err(
            "TIM3_CR1",
            t3,
            c3,
            "centre-aligned or down-counting PWM: the duty is edge-aligned up-counting (CMS 0, DIR 0)".into(),
        ));
    }
    let ccmr = peek(m, t3 + 0x18);
    for (ch, shift) in [(1, 4), (2, 12)] {
        if (ccmr >> shift) & 0b111 != 0b110 || (ccmr >> (shift - 4)) & 0b11 != 0 {
            return Err(err(
                "TIM3_CCMR1",
                t3 + 0x18,
                ccmr,
                format!("channel {ch} is not an output in PWM mode 1 (CCxS 0, OCxM 0b110): the duty must be the torque"),
            ));
        }
    }
    let ccer = peek(m, t3 + 0x20);
    for (ch, shift) in [(1, 0), (2, 4)] {
        if (ccer >> shift) & 1 == 0 || (ccer >> (shift + 1)) & 1 != 0 {
            return Err(err(
                "TIM3_CCER",
                t3 + 0x20,
                ccer,
                format!("channel {ch}'s output is off or active low (CCxE 1, CCxP 0): the drivers read a high duty as torque"),
            ));
        }
    }
    let smcr = peek(m, t4 + 0x08);
    if smcr & 0b111 != 0b011 {
        return Err(err(
            "TIM4_SMCR",
            t4 + 8,
            smcr,
            format!("slave mode {:#05b}: the belt's quadrature needs encoder mode 3 (SMS 0b011: both edges of both inputs)", smcr & 0b111),
        ));
    }
    let ccmr4 = peek(m, t4 + 0x18);
    if ccmr4 & 0b11 != 0b01 || (ccmr4 >> 8) & 0b11 != 0b01 {
        return Err(err(
            "TIM4_CCMR1",
            t4 + 0x18,
            ccmr4,
            "CC1S or CC2S is not its own input (0b01): TI1 and TI2 must be the belt's A and B".into(),
        ));
    }
    let ccer4 = peek(m, t4 + 0x20);
    if ccer4 & ((1 << 1) | (1 << 5)) != 0 {
        return Err(err("TIM4_CCER", t4 + 0x20, ccer4, "an inverted input (CC1P or CC2P): the belt would count the other way".into()));
    }
    if peek(m, t4) & 1 == 0 || peek(m, t4 + 0x2C) != 0xFFFF {
        return Err(err(
            "TIM4_ARR",
            t4 + 0x2C,
            peek(m, t4 + 0x2C),
            "the belt's counter is stopped or wraps before 16 bits (CEN 1, ARR 0xFFFF)".into(),
        ));
    }
    Ok(())
}

/// The IWDG's timeout at the LSI's fastest (47 kHz) is longer than two control
/// periods, so that a healthy loop is never reset (docs/hardware.md: "a few
/// periods long").
///
/// # Errors
/// `IWDG_RLR` with the timeout found.
pub fn watchdog(m: &Machine, period_s: f64) -> Result<(), BoardError> {
    let (pr, rlr) = (peek(m, 0x4000_3004) & 0b111, peek(m, 0x4000_3008) & 0xFFF);
    let timeout = f64::from(4u32 << pr.min(6)) * f64::from(rlr + 1) / f64::from(LSI_MAX_HZ);
    if timeout < 2.0 * period_s {
        return Err(err(
            "IWDG_RLR",
            0x4000_3008,
            rlr,
            format!(
                "with PR {pr} the watchdog fires after {:.3} ms at the LSI's 47 kHz: a healthy loop of {:.3} ms periods would be reset",
                timeout * 1e3,
                period_s * 1e3
            ),
        ));
    }
    Ok(())
}
