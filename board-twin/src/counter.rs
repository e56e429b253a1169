//! TIM4 in encoder mode on the belt's quadrature encoder (RM0090 "Encoder
//! interface mode": CNT counts the edges up or down, wrapping at 16 bits), as
//! the drivers' `QuadratureCounter`. [`crate::BoardTwin`] sets the count from the
//! belt's travel.

use drivers::QuadratureCounter;

use crate::bench::Shared;

/// The belt's counter.
#[derive(Debug)]
pub struct CounterModel {
    bench: Shared,
}

impl CounterModel {
    /// The counter of `bench`.
    pub fn new(bench: Shared) -> Self {
        Self { bench }
    }
}

impl QuadratureCounter for CounterModel {
    fn count(&mut self) -> u16 {
        crate::bench::lock(&self.bench).belt_count
    }
}

/// CNT after `travel_m` metres of belt from the count 0, at `counts_per_metre`:
/// the whole counts passed (an encoder counts edges: truncated toward minus
/// infinity), wrapped to 16 bits.
pub fn belt_count(travel_m: f64, counts_per_metre: f64) -> u16 {
    let counts = (travel_m * counts_per_metre).floor();
    if counts.is_finite() { (counts.rem_euclid(65536.0) as u32 & 0xFFFF) as u16 } else { 0 }
}
