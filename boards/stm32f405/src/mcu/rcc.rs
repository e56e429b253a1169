//! [`ClockControl`] on the chip's RCC, PWR and flash interface through the PAC,
//! and the peripheral clock enables the images need (RM0090 6.3.10 to 6.3.14).

use stm32f4::stm32f405 as pac;

use crate::clock_tree::{self, ClockControl, ClockOutcome, PllConfig};

/// The RCC, PWR and flash registers.
pub struct Rcc;

fn rcc() -> &'static pac::rcc::RegisterBlock {
    // SAFETY: the RCC is configured from one context (start-up, before any interrupt).
    unsafe { &*pac::RCC::ptr() }
}

impl ClockControl for Rcc {
    fn hsi_ready(&mut self) -> bool {
        rcc().cr().read().hsirdy().bit_is_set()
    }
    fn start_hse(&mut self) {
        rcc().cr().modify(|_, w| w.hseon().set_bit());
    }
    fn hse_ready(&mut self) -> bool {
        rcc().cr().read().hserdy().bit_is_set()
    }
    fn regulator_scale_1(&mut self) {
        rcc().apb1enr().modify(|_, w| w.pwren().set_bit());
        // SAFETY: PWR is only touched here.
        unsafe { &*pac::PWR::ptr() }.cr().modify(|_, w| w.vos().set_bit());
    }
    fn configure_pll(&mut self, pll: &PllConfig) {
        rcc().pllcfgr().modify(|_, w| unsafe {
            // SAFETY: `PllConfig::for_168mhz` keeps every divider in its field's range.
            w.pllm().bits(pll.m as u8).plln().bits(pll.n as u16).pllp().bits((pll.p / 2 - 1) as u8).pllq().bits(pll.q as u8)
        });
        rcc().pllcfgr().modify(|_, w| w.pllsrc().hse());
    }
    fn start_pll(&mut self) {
        rcc().cr().modify(|_, w| w.pllon().set_bit());
    }
    fn pll_ready(&mut self) -> bool {
        rcc().cr().read().pllrdy().bit_is_set()
    }
    fn set_flash_latency(&mut self, wait_states: u8) {
        // SAFETY: FLASH's access control register is only touched here.
        let flash = unsafe { &*pac::FLASH::ptr() };
        flash.acr().write(|w| unsafe { w.latency().bits(wait_states).prften().set_bit().icen().set_bit().dcen().set_bit() });
    }
    fn flash_latency(&mut self) -> u8 {
        // SAFETY: a read.
        unsafe { &*pac::FLASH::ptr() }.acr().read().latency().bits()
    }
    fn switch_to_pll(&mut self) {
        rcc().cfgr().modify(|_, w| w.ppre1().div4().ppre2().div2().hpre().div1().sw().pll());
    }
    fn runs_on_pll(&mut self) -> bool {
        rcc().cfgr().read().sws().is_pll()
    }
}

/// Brings the clocks up from the board's crystal; on failure logs why and
/// sleeps forever with nothing enabled: the control loop never runs at the
/// wrong rate (its timing assumes 168 MHz).
pub fn bring_up_or_halt() -> ClockOutcome {
    match clock_tree::bring_up(&mut Rcc, crate::pins::HSE_HZ, 200_000) {
        Ok(o @ ClockOutcome::Pll { m, n }) => {
            defmt::info!("core clock 168 MHz from the {=u32} Hz crystal (PLL m={=u32} n={=u32})", crate::pins::HSE_HZ, m, n);
            o
        }
        Ok(o @ ClockOutcome::NoClockModel) => {
            defmt::info!("no RCC model (emulator): core clock as emulated");
            o
        }
        Err(e) => {
            defmt::error!("clock bring-up failed: {}; not running the control loop", e);
            loop {
                cortex_m::asm::wfi();
            }
        }
    }
}

/// Clocks of the GPIO ports A to C, SPI1, ADC1, USART1 (APB2), TIM2 to TIM4 (APB1).
pub fn enable_peripheral_clocks() {
    let r = rcc();
    r.ahb1enr().modify(|_, w| w.gpioaen().set_bit().gpioben().set_bit().gpiocen().set_bit());
    r.apb1enr().modify(|_, w| w.tim2en().set_bit().tim3en().set_bit().tim4en().set_bit());
    r.apb2enr().modify(|_, w| w.spi1en().set_bit().adc1en().set_bit().usart1en().set_bit());
    // The enables take two bus cycles (RM0090 6.3.10 note): read one back.
    let _ = r.apb2enr().read();
}

/// Whether the last reset came from the independent watchdog; clears the flags.
pub fn take_watchdog_reset_flag() -> bool {
    let r = rcc();
    let iwdg = r.csr().read().wdgrstf().bit_is_set();
    r.csr().modify(|_, w| w.rmvf().set_bit());
    iwdg
}
