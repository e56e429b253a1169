//! ADC1 for the load cell (RM0090 13): the two channels of the map in the
//! injected group, converted on TIM2's TRGO (the control tick), so the sample
//! instant is the period's start (docs/hardware.md). ADC clock APB2 / 4 = 21 MHz,
//! 15-cycle sampling: both conversions take about 1.4 us.

use stm32f4::stm32f405 as pac;

use super::gpio;
use crate::pins;

/// Why no reading is available.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum AdcError {
    /// The injected conversions of this tick did not complete (JEOC never set:
    /// no trigger, a stopped ADC, or an emulator without the injected group).
    /// The injected group has no overrun flag (RM0090 13.8.2): a handler late
    /// by a whole period reads the newer conversion, and the step's deadline
    /// check reports that lateness instead.
    Missing,
}

fn adc() -> &'static pac::adc1::RegisterBlock {
    // SAFETY: ADC1 is read by the control interrupt only after start-up.
    unsafe { &*pac::ADC1::ptr() }
}

/// Sets ADC1 up and turns it on (clocks must be on; TIM2 starts the conversions).
pub fn init() {
    gpio::configure(&pins::LOAD_F_T);
    gpio::configure(&pins::LOAD_F_N);
    // SAFETY: the common registers are only written here.
    unsafe { &*pac::ADC_COMMON::ptr() }.ccr().modify(|_, w| w.adcpre().div4());
    let a = adc();
    let [ch_t, ch_n] = pins::LOAD_ADC_CHANNELS;
    // Injected sequence of two: with JL = 1 the conversions are JSQ3 then JSQ4 (RM0090 13.13.12).
    a.jsqr().write(|w| unsafe { w.jl().bits(1).jsq3().bits(ch_t).jsq4().bits(ch_n) });
    // 15 cycles of sampling on both channels (SMP = 0b001).
    a.smpr2().write(|w| unsafe { w.bits(0b001 | (0b001 << 3)) });
    a.cr1().write(|w| w.scan().set_bit());
    // JEXTSEL 0b0011 = TIM2 TRGO, on its rising edge.
    a.cr2().write(|w| unsafe { w.jextsel().bits(0b0011) }.jexten().rising_edge().adon().set_bit());
}

/// The period's injected conversions, as the acquisition copied them, as the load cell's ADC.
#[derive(Debug, Default)]
pub struct LoadCellAdc;

impl drivers::load_cell::LoadCellAdc for LoadCellAdc {
    type Error = AdcError;

    fn read(&mut self) -> Result<[u16; 2], AdcError> {
        // Copied by the acquisition (`super::acquisition`) after the tick's
        // frames: memory, no wait on JEOC here.
        super::acquisition::conversions_of_period().ok_or(AdcError::Missing)
    }
}
