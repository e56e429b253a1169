//! The hybrid law's expectations (issue 52): under the force/motion law the
//! tip stays on the belt and follows `z_t*` along it within a bound no healthy
//! run comes near, and a miswired arm breaks one of them within a few periods.
//!
//! **On the belt.** The law commands the normal force `f_n*` (paper eq. 11):
//! below `Z_t,sliding` the tip never leaves the belt (docs/model.md experiment
//! 6; 0 periods of lift-off over 1 000 random admissible scenarios). Lift-off
//! declared for [`LIFT_OFF_S`] (10 ms) in a row is therefore a fault: the tip
//! whipped off the belt by a reversed motor, or a load cell that reads no
//! force while the tip presses (its sign reversed: the law then commands no
//! force). Beyond `Z_t,sliding` the law's own bounce (the paradox) trips it too:
//! on a board that is a stop, as the runaway limits already made it.
//!
//! **The bound.** The motion loop (paper eq. 10, `K'_P = K'_D = 900`) starts at
//! the tip's own position (`crate::reference::Quintic`), so the error is what
//! the loop's disturbances leave: the sampled, delayed command and the friction
//! term's error (`mu_hat` against `mu`). Over the default, the four paper
//! scenarios and 1 000 random admissible scenarios (`mu` 0.3 to 0.8, `v_belt`
//! -1 to -0.1 m/s, `f_n*` 3 to 10 N, targets below `Z_t,sliding`, from `x0d`
//! and `x0u`) the largest `|z_t - z_t*|` is 0.52 mm (`board-link/tests/board/twin.rs`).
//! The bound, [`TRACKING_M`] = 5 mm, is ten times it, and a sixth of the 30 mm a
//! miswired arm may stray before it is stopped (docs/board.md "Wiring checks").
//! The error must also stand above
//! its own 50 ms average by [`DIVERGING_M`] (2 mm: growing at 4 cm/s or more),
//! or be past [`TRACKING_ANY_M`] (25 mm): a wrong
//! `mu_hat` leaves a steady error of 10 to 20 mm that builds over the move's
//! seconds at millimetres per second (docs/analyses.md), a miswired arm drives
//! it away at 0.1 to 4 m/s.
//! A reversed motor drives the tip away at 0.1 to 4 m/s: past 5 mm within 2 to
//! 10 ms, [`CONFIRM_S`] later the safe state.
//!
//! The PID (paper eq. 8) lifts off by design from `x0u` (its healthy tip moves
//! 212 mm in the first 0.1 s): there is no such bound for it, and its wiring
//! faults are the wiring check's ([`crate::wiring`]).

/// How long lift-off may stay declared under the hybrid law, s.
pub const LIFT_OFF_S: f32 = 0.010;

/// The largest `|z_t - z_t*|` under the hybrid law, m.
pub const TRACKING_M: f32 = 0.005;
/// How long past it trips, s.
pub const CONFIRM_S: f32 = 0.003;
/// How far `|z_t - z_t*|` must stand above its own 50 ms average to count, m:
/// an error that grows at 4 cm/s or faster.
pub const DIVERGING_M: f32 = 0.002;
/// The average's time constant, s.
pub const AVERAGE_S: f32 = 0.05;
/// The error past which it counts however it moves, m: beyond the steady error
/// of a `mu_hat` 20 % off (20.5 mm, docs/analyses.md).
pub const TRACKING_ANY_M: f32 = 0.025;

/// The check's state across periods.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrackingMonitor {
    run: u16,
    lifted: u16,
    /// `|z_t - z_t*|` averaged over [`AVERAGE_S`], m.
    average: f32,
}

/// What the hybrid law's expectations found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expectation {
    /// `|z_t - z_t*|` past [`TRACKING_M`] for [`CONFIRM_S`].
    Tracking,
    /// Lift-off declared for [`LIFT_OFF_S`].
    LiftOff,
}

/// The check in periods of the control rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingRule {
    /// [`TRACKING_M`], m.
    pub bound: f32,
    /// Periods past it that trip.
    pub confirm: u16,
    /// Periods of declared lift-off that trip.
    pub lift_off: u16,
    /// The average's gain per period, `Ts / (AVERAGE_S + Ts)`.
    pub smoothing: f32,
}

impl TrackingRule {
    /// The check above at a control period of `ts` seconds.
    pub fn at_period(ts: f32) -> Self {
        Self {
            bound: TRACKING_M,
            confirm: crate::runaway::periods_of(CONFIRM_S, ts),
            lift_off: crate::runaway::periods_of(LIFT_OFF_S, ts),
            smoothing: ts / (AVERAGE_S + ts),
        }
    }
}

impl TrackingMonitor {
    /// Folds in one period's tracking error `z_t - z_t*` (m) and whether
    /// lift-off is declared; returns what was found once the error was past the
    /// bound and [`DIVERGING_M`] above its own average (or past
    /// [`TRACKING_ANY_M`], or not finite) for the confirmation, or lift-off held
    /// for its time.
    pub fn update(&mut self, rule: &TrackingRule, error: f32, lifted: bool) -> Option<Expectation> {
        let size = error.abs();
        let diverging = size - self.average > DIVERGING_M;
        // A select, not a branch: the average moves only for a finite error.
        let average = self.average + rule.smoothing * (size - self.average);
        self.average = if size < f32::INFINITY { average } else { self.average };
        // Not within `TRACKING_ANY_M`: past it, or NaN (one comparison for both).
        let within_any = size <= TRACKING_ANY_M;
        let past = !within_any || (size > rule.bound && diverging);
        self.run = if past { self.run.saturating_add(1) } else { 0 };
        self.lifted = if lifted { self.lifted.saturating_add(1) } else { 0 };
        if self.run >= rule.confirm {
            Some(Expectation::Tracking)
        } else if self.lifted >= rule.lift_off {
            Some(Expectation::LiftOff)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_trips_after_its_confirmation_at_every_rate() {
        for (ts, n) in [(1e-3, 3), (1e-4, 30), (4e-3, 1)] {
            let rule = TrackingRule::at_period(ts);
            assert_eq!(rule.confirm, n, "{ts}");
            let mut m = TrackingMonitor::default();
            for _ in 1..n {
                assert_eq!(m.update(&rule, -0.006, false), None);
            }
            assert_eq!(m.update(&rule, 0.0051, false), Some(Expectation::Tracking));
        }
        let rule = TrackingRule::at_period(1e-3);
        let mut m = TrackingMonitor::default();
        for k in 0..100 {
            assert_eq!(m.update(&rule, if k % 3 == 2 { 0.0 } else { 0.01 }, false), None, "a period within the bound clears it");
        }
        // A steady error, or one that shrinks, is the friction term's (a wrong
        // `mu_hat` leaves 10 to 20 mm, docs/analyses.md), not a fault.
        let mut m = TrackingMonitor::default();
        for k in 0..20_000 {
            // 1 cm/s up to 20 mm, then steady.
            let e = (k as f32 * 1e-5).min(0.02);
            assert_eq!(m.update(&rule, e, false), None, "{k}");
        }
        // Beyond 25 mm it counts however the error moves.
        let mut m = TrackingMonitor::default();
        for _ in 1..rule.confirm {
            assert_eq!(m.update(&rule, 0.026, false), None);
        }
        assert_eq!(m.update(&rule, -0.026, false), Some(Expectation::Tracking));
        let mut m = TrackingMonitor::default();
        m.update(&rule, f32::NAN, false);
        m.update(&rule, f32::NAN, false);
        assert_eq!(m.update(&rule, f32::NAN, false), Some(Expectation::Tracking), "a non-finite error is past the bound");
    }

    #[test]
    fn a_lift_off_of_10_ms_trips_and_a_bounce_shorter_does_not() {
        for (ts, n) in [(1e-3, 10u16), (1e-4, 100), (4e-3, 3)] {
            let rule = TrackingRule::at_period(ts);
            assert_eq!(rule.lift_off, n, "{ts}");
            let mut m = TrackingMonitor::default();
            for _ in 0..20 {
                for _ in 1..n {
                    assert_eq!(m.update(&rule, 0.0, true), None);
                }
                assert_eq!(m.update(&rule, 0.0, false), None, "touchdown clears it");
            }
            for _ in 1..n {
                assert_eq!(m.update(&rule, 0.0, true), None);
            }
            assert_eq!(m.update(&rule, 0.0, true), Some(Expectation::LiftOff));
        }
    }
}
