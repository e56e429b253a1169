//! Hardware behind traits (the way smoltcp and embassy keep logic testable):
//! where frames come from and commands go is the board's business.

use shared::wire::{ActuatorCommand, SensorFrame};

/// A free-running tick counter the step uses to measure its own execution time
/// (SysTick or DWT on the MCU, `Instant` on the host, a fake in tests).
pub trait TickClock {
    /// Current tick count (wraps; differences are taken with `wrapping_sub`).
    fn ticks(&self) -> u32;
    /// Ticks per second.
    fn ticks_per_second(&self) -> u32;
}

/// A board: the source of sensor frames and the sink of commands.
pub trait Board {
    /// Why the board failed (a dead peer, a broken link).
    type Error;
    /// Blocks until the next sensor frame; `None` when the sequence has ended.
    ///
    /// # Errors
    /// The board's error (peer gone, link broken).
    fn next_frame(&mut self) -> Result<Option<SensorFrame>, Self::Error>;
    /// Sends a command.
    ///
    /// # Errors
    /// The board's error.
    fn send(&mut self, command: &ActuatorCommand) -> Result<(), Self::Error>;
    /// Time now, microseconds on the same clock as [`SensorFrame::t_us`].
    fn now_us(&self) -> u64;
}

/// A clock that never advances (tests, replay on the host): every step takes 0 ticks.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrozenClock;

impl TickClock for FrozenClock {
    fn ticks(&self) -> u32 {
        0
    }
    fn ticks_per_second(&self) -> u32 {
        1_000_000
    }
}
