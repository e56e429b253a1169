//! TIM4 in encoder mode on the belt's quadrature encoder (RM0090 "Encoder
//! interface mode": CNT counts the edges up or down, wrapping at 16 bits), as
//! the drivers' `QuadratureCounter`. [`crate::BoardTwin`] sets the count from the
//! belt's travel by the belt sensor's one model, `drivers::belt::count_at`
//! (docs/hardware.md "The belt sensor's model").

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
