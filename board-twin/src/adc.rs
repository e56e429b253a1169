//! ADC1's two injected conversions of the load cell's amplifiers (RM0090
//! "Analog-to-digital converter": 12 bit, right-aligned, started by the control
//! timer's trigger), as the drivers' `LoadCellAdc`. The counts themselves are
//! made by [`crate::BoardTwin`] from the force, the front end's gain and offset
//! and the noise; a missing conversion is `None` on the bench.

use drivers::LoadCellAdc;

use crate::bench::Shared;

/// Why a conversion could not be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdcError {
    /// No end of conversion this period (the trigger was lost, an overrun).
    Missing,
}

/// The load cell's ADC.
#[derive(Debug)]
pub struct AdcModel {
    bench: Shared,
}

impl AdcModel {
    /// The ADC of `bench`.
    pub fn new(bench: Shared) -> Self {
        Self { bench }
    }
}

impl LoadCellAdc for AdcModel {
    type Error = AdcError;

    fn read(&mut self) -> Result<[u16; 2], AdcError> {
        crate::bench::lock(&self.bench).adc_counts.ok_or(AdcError::Missing)
    }
}

/// The 12-bit count of an amplifier output: `zero + gain * force`, rounded to the
/// nearest count and saturated at the converter's rails `[0, 4095]` (an input
/// beyond them reads as the rail). NaN reads as the lower rail.
pub fn adc_count(zero_counts: f64, counts_per_newton: f64, force_n: f64) -> u16 {
    let v = (zero_counts + counts_per_newton * force_n).round();
    if v.is_nan() { 0 } else { v.clamp(0.0, 4095.0) as u16 }
}
