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
    /// The last period's change of the command `[u1, u2]`, N m.
    last_change: [f32; 2],
    /// Consecutive reversals per motor.
    run: [u16; 2],
}

impl ChatterMonitor {
    /// Folds in one period's saturated command `u` (N m) under the torque
    /// limit `limit` (N m); true once a motor's command swung by more than
    /// [`CHATTER_FRACTION`] of the limit, reversing the direction of its last
    /// change, for [`CHATTER_PERIODS`] periods in a row: a command reversing
    /// its sign so, and (issue 80) one that chatters without crossing
    /// zero: a law holding the tip on the belt against the paradox swings its
    /// base motor between +5 and +1.7 N m every period as the contact
    /// chatters, which the wiring check saw as a joint moving against its
    /// torque (`Miswired`, 25 of 203 stopped draws of the template's law over
    /// the envelope). Non-finite commands never count (the step stops them).
    #[inline(always)]
    pub fn update(&mut self, u: [f32; 2], limit: f32) -> bool {
        let step = CHATTER_FRACTION * limit;
        let change = [u[0] - self.last[0], u[1] - self.last[1]];
        // A reversal of the change by more than `step`: a command that crosses
        // zero by that much reverses its change too (from rest, the first swing
        // counts as a sign reversal did), so one comparison a motor serves both.
        let reversed = |change: f32, last_change: f32| change * last_change < 0.0 && change.abs() > step;
        let count = |n: u16, r: bool| if r { n.saturating_add(1) } else { 0 };
        self.run =
            [count(self.run[0], reversed(change[0], self.last_change[0])), count(self.run[1], reversed(change[1], self.last_change[1]))];
        self.last = u;
        self.last_change = change;
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
        // A command that swings by more than half the limit without crossing
        // zero, its change reversing each period, trips at the fourth swing
        // that reverses the one before (the template's law against the
        // chattering contact: from 0, up to 5, then 1.7, 5, 1.8, 5).
        let mut m = ChatterMonitor::default();
        let seq = [5.0, 1.7, 5.0, 1.8];
        for (k, u) in seq.into_iter().enumerate() {
            assert!(!m.update([u, 2.0], 5.0), "{k}: {u}");
        }
        assert!(m.update([5.0, 2.0], 5.0), "the fourth reversal of the change trips");
        // Swings of 2.4 N m, or a monotone ramp of large steps, never do.
        let mut m = ChatterMonitor::default();
        for k in 0..100 {
            assert!(!m.update([if k % 2 == 0 { 4.9 } else { 2.5 }, 0.0], 5.0), "{k}");
        }
        let mut m = ChatterMonitor::default();
        for k in 0..4 {
            assert!(!m.update([-5.0 + 3.0 * k as f32, 0.0], 5.0), "{k}");
        }
        // NaN never counts.
        let mut m = ChatterMonitor::default();
        for k in 0..10 {
            assert!(!m.update([if k % 2 == 0 { f32::NAN } else { 5.0 }, 0.0], 5.0));
        }
    }
}
