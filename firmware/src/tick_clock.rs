//! The step's own clock: a free-running tick counter behind a trait, so the
//! firmware measures its execution time the same way on every target (the DWT
//! cycle counter or SysTick on the MCU, `Instant` on the host, a fake in tests).

/// A free-running tick counter the step uses to measure its own execution time
/// (the DWT cycle counter or SysTick on the MCU, `Instant` on the host, a fake in tests).
pub trait TickClock {
    /// Current tick count (wraps; differences are taken with `wrapping_sub`).
    fn ticks(&self) -> u32;
    /// Ticks per second.
    fn ticks_per_second(&self) -> u32;
}
