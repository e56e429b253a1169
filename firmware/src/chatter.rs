//! A law that chatters (issue 66): the command of a motor reversing by more
//! than half the torque limit period after period. A sampled loop past its
//! stability chatters so: the paper's PID from `x0u` at 250 Hz (`K_D Ts` over
//! the base joint's effective inertia, `2 x 0.004 / 0.0031 = 2.6`, past the
//! derivative loop's limit of 2) swings its base motor between +5 and -5 N m
//! every period (364 reversals in 500 periods) before any fault, and the
//! hybrid law's motion loop past `K'_D Ts = 1.5` does the same. No healthy law
//! of the envelope reverses a motor by half its range four periods in a row
//! (docs/hardware.md "The envelope", `board-link/tests/board/envelope.rs`): the
//! firmware stops it as the law's own failure, [`crate::SafeReason::Unstable`],
//! before the arm is shaken.

/// Consecutive reversals of one motor's command that trip.
pub const CHATTER_PERIODS: u16 = 4;
/// The reversal that counts, as a fraction of the torque limit: from one
/// period to the next the command changes sign and moves by more than this
/// times the limit.
pub const CHATTER_FRACTION: f32 = 0.5;

/// The check's state across periods.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ChatterMonitor {
    /// The last period's saturated command `[u1, u2]`, N m.
    last: [f32; 2],
    /// Consecutive reversals per motor.
    run: [u16; 2],
}

impl ChatterMonitor {
    /// Folds in one period's saturated command `u` (N m) under the torque
    /// limit `limit` (N m); true once a motor reversed by more than
    /// [`CHATTER_FRACTION`] of the limit for [`CHATTER_PERIODS`] periods in a
    /// row. Non-finite commands never count (the law's own check latches them).
    #[inline(always)]
    pub fn update(&mut self, u: [f32; 2], limit: f32) -> bool {
        let step = CHATTER_FRACTION * limit;
        let reversed = |now: f32, before: f32| now * before < 0.0 && (now - before).abs() > step;
        let count = |n: u16, r: bool| if r { n.saturating_add(1) } else { 0 };
        self.run = [count(self.run[0], reversed(u[0], self.last[0])), count(self.run[1], reversed(u[1], self.last[1]))];
        self.last = u;
        self.run[0] >= CHATTER_PERIODS || self.run[1] >= CHATTER_PERIODS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_reversals_by_half_the_limit_trip_and_smaller_or_fewer_do_not() {
        let mut m = ChatterMonitor::default();
        let seq = [1.0, -2.0, 2.0, -2.0];
        for u in seq {
            assert!(!m.update([u, 0.0], 5.0), "{u}");
        }
        assert!(m.update([2.0, 0.0], 5.0), "the fourth reversal trips");
        // Reversals of 2.4 N m at a 5 N m limit never count.
        let mut m = ChatterMonitor::default();
        for k in 0..100 {
            assert!(!m.update([0.0, if k % 2 == 0 { 1.2 } else { -1.2 }], 5.0));
        }
        // Three in a row, then a period without: never.
        let mut m = ChatterMonitor::default();
        for k in 0..100 {
            let u = match k % 4 {
                0 => 3.0,
                1 => -3.0,
                2 => 3.0,
                _ => 3.0,
            };
            assert!(!m.update([u, 0.0], 5.0), "{k}");
        }
        // NaN never counts.
        let mut m = ChatterMonitor::default();
        for k in 0..10 {
            assert!(!m.update([if k % 2 == 0 { f32::NAN } else { 5.0 }, 0.0], 5.0));
        }
    }
}
