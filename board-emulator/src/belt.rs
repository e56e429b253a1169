//! The belt encoder's quadrature into TIM4's inputs (PB6 = A = TI1, PB7 = B =
//! TI2): each period, the edges that move TIM4's count from where the last
//! period left it to the count the belt's travel gives
//! (`drivers::belt::count_at`, the belt sensor's one model: docs/hardware.md
//! "The belt sensor's model"), in quadrature order for the direction
//! (RM0090 18.3.12, encoder mode 3: an edge of A counts up when A differs from B
//! after it, an edge of B when they are equal), spaced so that TIM4's input
//! filter (ICxF = 0b0011: 8 samples at 84 MHz, 95 ns) takes each.
//!
//! The edges fall between the end of a period's run and the next tick, so the
//! tick reads the whole count. [`crate::core_clock::Mode::Functional`] queues
//! them in the core at exact core ticks (about 0.5 us of wall time an edge);
//! [`crate::core_clock::Mode::Counted`] drives each between two scheduler
//! rounds (`step_until`, about 8 us an edge).

use crate::{
    core_clock::{Edge, Mode},
    machine::{BoardMachine, out},
};

/// Why the edges could not be driven.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BeltError {
    /// More edges than fit before the next tick.
    #[error("the belt moves {edges} quadrature counts in one period: more than the emulated encoder's {room} edges before the next tick")]
    TooFast {
        /// The edges this period needs.
        edges: u64,
        /// The edges that fit.
        room: u64,
    },
    /// The emulator refused to step.
    #[error("the emulator stopped: {0}")]
    Emulator(String),
}

/// Core ticks between two edges (one on A, the next on B): the same input's
/// edges are 20 core ticks (119 ns at 168 MHz) apart, above the filter's 95 ns.
pub const EDGE_SPACING_TICKS: u64 = 10;
/// The same between scheduler rounds ([`Mode::Counted`]): TIM4 then sees an
/// edge only where a round is cut, and at 60 ns some were lost; 200 ns apart
/// none are (the counted run equals the functional one bit for bit:
/// `board-link/tests/board/emulator.rs`).
pub const ROUND_EDGE_SPACING_TICKS: u64 = 34;
/// Core ticks from the end of a period's run to the first edge.
const LEAD_TICKS: u64 = 168;

/// The quadrature's state: the two lines' levels and the count they stand for.
#[derive(Debug, Clone, Copy, Default)]
pub struct Quadrature {
    a: bool,
    b: bool,
    count: u16,
}

impl Quadrature {
    /// The input to toggle for one count `up` (or down): 0 for A, 1 for B.
    fn next(&mut self, up: bool) -> usize {
        if (self.a == self.b) == up {
            self.a = !self.a;
            0
        } else {
            self.b = !self.b;
            1
        }
    }

    /// Drives the edges from the count the lines stand for to `target`, before
    /// the next tick at core tick `next_tick`.
    ///
    /// # Errors
    /// [`BeltError::TooFast`] when the edges do not fit before the next tick (a
    /// belt faster than the emulated encoder can count: over 1.4 m/s at 1 kHz
    /// and 1e6 counts per metre); [`BeltError::Emulator`].
    pub fn drive_to(&mut self, m: &mut BoardMachine, target: u16, next_tick: u64) -> Result<(), BeltError> {
        let delta = target.wrapping_sub(self.count) as i16;
        if delta == 0 {
            return Ok(());
        }
        let up = delta > 0;
        let n = u64::from(delta.unsigned_abs());
        let Some(pins) = m.hub.pins() else { return Ok(()) };
        let spacing = match m.core.mode() {
            Mode::Functional => EDGE_SPACING_TICKS,
            Mode::Counted => ROUND_EDGE_SPACING_TICKS,
        };
        let start = m.core.end_tick() + LEAD_TICKS;
        if start + n * spacing >= next_tick {
            return Err(BeltError::TooFast { edges: n, room: next_tick.saturating_sub(start) / spacing });
        }
        let mut edges = Vec::with_capacity(n as usize);
        for i in 0..n {
            let line = self.next(up);
            let (line, high) = if line == 0 { (out::BELT_A, self.a) } else { (out::BELT_B, self.b) };
            edges.push(Edge { at: start + i * spacing, line, high });
        }
        self.count = target;
        match m.core.mode() {
            Mode::Functional => m.core.queue_edges(&pins, edges),
            Mode::Counted => {
                let ns_per_tick = 1e9 / f64::from(crate::checks::SYSCLK_HZ);
                for e in edges {
                    let at = (e.at as f64 * ns_per_tick).ceil() as u64;
                    m.step_until(at).map_err(BeltError::Emulator)?;
                    pins.drive(e.line, e.high);
                }
            }
        }
        Ok(())
    }
}
