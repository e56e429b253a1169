//! Runaway detection: the loop has lost the arm (issue 39). Motor-control
//! firmware stops on a joint speed or a force that no healthy motion reaches
//! (ODrive's `vel_limit`, VESC's current and speed faults); so does this one,
//! with a reason of its own, within a bound that follows from the arm's
//! dynamics and the sensors' ranges (docs/board.md "Runaway limits").
//!
//! Two limits, each confirmed over consecutive periods so that one glitched
//! sample never trips it:
//! - **Joint speed**: `|theta_dot|` of either joint (the observer's rate) past
//!   [`SPEED_LIMIT`] for [`SPEED_CONFIRM`] periods. The paper's moves need less
//!   than 1 rad/s; the fastest healthy motion is the PID's lift-off from `x0u`
//!   (the Painlevé bounce), 14.6 rad/s; the limit is 20 rad/s.
//! - **Overload**: the load cell at its full scale on either axis for
//!   [`OVERLOAD_S`] (10 ms) in a row. There the measured force under-reads:
//!   the hybrid law's force loop, the innovation check and the lift-off
//!   detector are blind, so the firmware is no longer in control of the force
//!   it makes. Healthy runs never clip the load cell for one period (the paper's
//!   `f_n*` is 10 N against a 25 N range); an impact does for a period or two.
//!
//! A reversed motor (the audit's reproducer: `board.motor2.reversed=true`)
//! presses the tip into the belt until the load cell clips, then whips the arm
//! off it: the overload trips 10 periods after the clip, 34 ms after the start,
//! the tip 10 mm from where it was. Where the motors saturate and the arm can no
//! longer hold the tip (`mu = 1` with `f_n* = 10 N`, docs/results.md), the arm
//! is dragged and whipped past 20 rad/s: that is a runaway too, and the firmware
//! stops it.

/// The joint speed limit, rad/s (1.37 times the fastest healthy motion, 14.6 rad/s).
pub const SPEED_LIMIT: f32 = 20.0;
/// Consecutive periods past the speed limit that trip it.
pub const SPEED_CONFIRM: u16 = 3;
/// How long the load cell may stay at full scale, s.
pub const OVERLOAD_S: f32 = 0.010;

/// What ran away.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runaway {
    /// A joint's speed past [`SPEED_LIMIT`].
    Speed,
    /// The load cell at full scale for [`OVERLOAD_S`].
    Overload,
}

/// `seconds` in whole periods of `ts` seconds, rounded up (a thousandth of a
/// period below a whole number counts as it: 0.010 s at 1 kHz is 10), at least
/// 1 and below `u16::MAX`: the confirmation times of every monitor.
pub fn periods_of(seconds: f32, ts: f32) -> u16 {
    let n = libm::ceilf(seconds / ts - 1e-3);
    if n >= 1.0 && n < f32::from(u16::MAX) { n as u16 } else { 1 }
}

/// The limits in periods of the control rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunawayRule {
    /// Speed limit, rad/s.
    pub speed_limit: f32,
    /// Periods past it that trip.
    pub speed_confirm: u16,
    /// Periods at full scale that trip.
    pub overload_confirm: u16,
}

impl RunawayRule {
    /// The limits above at a control period of `ts` seconds.
    pub fn at_period(ts: f32) -> Self {
        Self { speed_limit: SPEED_LIMIT, speed_confirm: SPEED_CONFIRM, overload_confirm: periods_of(OVERLOAD_S, ts) }
    }
}

/// The monitor's state across periods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RunawayMonitor {
    fast: u16,
    clipped: u16,
}

impl RunawayMonitor {
    /// Folds in one period: the joint rates `qd` (rad/s) and whether the load
    /// cell is at full scale on either axis. Returns what ran away once a limit
    /// held for its confirmation; a non-finite rate counts as past the limit.
    pub fn update(&mut self, rule: &RunawayRule, qd: [f32; 2], load_clipped: bool) -> Option<Runaway> {
        // `|w| <= limit` is false for NaN: one comparison a rate, NaN past the limit.
        let within = |w: f32| w.abs() <= rule.speed_limit;
        let fast = !(within(qd[0]) && within(qd[1]));
        self.fast = if fast { self.fast.saturating_add(1) } else { 0 };
        self.clipped = if load_clipped { self.clipped.saturating_add(1) } else { 0 };
        if self.fast >= rule.speed_confirm {
            Some(Runaway::Speed)
        } else if self.clipped >= rule.overload_confirm {
            Some(Runaway::Overload)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_overload_time_is_10_ms_at_every_rate() {
        assert_eq!(RunawayRule::at_period(1e-3).overload_confirm, 10);
        assert_eq!(RunawayRule::at_period(1e-4).overload_confirm, 100);
        assert_eq!(RunawayRule::at_period(4e-3).overload_confirm, 3);
    }

    #[test]
    fn a_limit_trips_only_when_held_for_its_confirmation() {
        let rule = RunawayRule::at_period(1e-3);
        let mut m = RunawayMonitor::default();
        // Two fast periods, one slow, then three fast: the third trips.
        for qd in [[21.0, 0.0], [0.0, -21.0], [19.9, 19.9], [21.0, 0.0], [0.0, 25.0]] {
            assert_eq!(m.update(&rule, qd, false), None);
        }
        assert_eq!(m.update(&rule, [-30.0, 0.0], false), Some(Runaway::Speed));
        let mut m = RunawayMonitor::default();
        for _ in 0..9 {
            assert_eq!(m.update(&rule, [0.0; 2], true), None);
        }
        assert_eq!(m.update(&rule, [0.0; 2], true), Some(Runaway::Overload));
        // An impact's clip of a few periods never does.
        let mut m = RunawayMonitor::default();
        for k in 0..100 {
            assert_eq!(m.update(&rule, [1.0, -1.0], k % 10 < 3), None);
        }
        let mut m = RunawayMonitor::default();
        for _ in 0..2 {
            assert_eq!(m.update(&rule, [f32::NAN, 0.0], false), None);
        }
        assert_eq!(m.update(&rule, [f32::NAN, 0.0], false), Some(Runaway::Speed));
    }
}
