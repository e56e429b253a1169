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
//! - **Pressing** (issue 80): a law that drives the tip into the belt with
//!   chattering contact reads full scale in most periods but not in ten in a
//!   row, and escapes the overload (45 periods at 22 to 71 N of true normal
//!   force, measured on a law of one's own). The press count is a leaky count
//!   of the periods whose measured normal force reaches [`PRESS_N`] (22 N, 88 %
//!   of the load cell's range) in magnitude: each adds [`PRESS_LEAK`], each
//!   other period takes 1 back, and [`PRESS_PERIODS`] pressed periods' worth
//!   trips [`Runaway::Overload`]. A press held every period trips at the
//!   tenth; one interrupted by chatter trips once it has pressed for ten
//!   periods plus a quarter of the periods between (a press in more than one
//!   period in five always trips). A healthy law never reads 22 N for long:
//!   `f_n*` is at most [`MAX_F_N_REF`] (20 N, 2 N below, 100 times the load
//!   cell's noise), and an impact's period or two of full scale leaks away
//!   between impacts.
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
/// The measured normal force that counts as pressing, N: 88 % of the load
/// cell's range (`shared::wire::LOAD_FULL_SCALE_N`), 2 N above the largest
/// `f_n*` ([`MAX_F_N_REF`]). Measured over the envelope (issue 80,
/// `board-link/tests/board/press.rs`): no healthy run of the paper's laws reads
/// 22 N in a single period (at 20 N, the PID's impacts do, for one), while a
/// law pressing at 24 N reads 22 to 25 N with its contact chattering.
pub const PRESS_N: f32 = 22.0;
/// Pressed periods' worth that trip the press count.
pub const PRESS_PERIODS: u16 = 10;
/// A pressed period adds this much to the press count; any other period takes
/// 1 back: a press in more than one period in `PRESS_LEAK + 1` accumulates.
pub const PRESS_LEAK: u16 = 4;
/// The largest normal-force reference `f_n*` a configuration may ask for, N:
/// 2 N below [`PRESS_N`], room for the force loop's transients and noise
/// (`crate::config::Config::validate`).
pub const MAX_F_N_REF: f32 = 20.0;

/// What ran away.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runaway {
    /// A joint's speed past [`SPEED_LIMIT`].
    Speed,
    /// The load cell at full scale for [`OVERLOAD_S`], or pressing at
    /// [`PRESS_N`] for [`PRESS_PERIODS`] periods' worth of the press count.
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
    /// The press count, in [`PRESS_LEAK`]ths of a pressed period.
    pressed: u16,
}

impl RunawayMonitor {
    /// Folds in one period: the joint rates `qd` (rad/s), whether the load
    /// cell is at full scale on either axis, and the measured normal force
    /// `f_n` (N). Returns what ran away once a limit held for its
    /// confirmation (the press count: [`PRESS_PERIODS`] pressed periods'
    /// worth); a non-finite rate counts as past the limit.
    pub fn update(&mut self, rule: &RunawayRule, qd: [f32; 2], load_clipped: bool, f_n: f32) -> Option<Runaway> {
        // `|w| <= limit` is false for NaN: one comparison a rate, NaN past the limit.
        let within = |w: f32| w.abs() <= rule.speed_limit;
        let fast = !(within(qd[0]) && within(qd[1]));
        self.fast = if fast { self.fast.saturating_add(1) } else { 0 };
        self.clipped = if load_clipped { self.clipped.saturating_add(1) } else { 0 };
        self.pressed = if f_n.abs() >= PRESS_N { self.pressed.saturating_add(PRESS_LEAK) } else { self.pressed.saturating_sub(1) };
        if self.fast >= rule.speed_confirm {
            Some(Runaway::Speed)
        } else if self.clipped >= rule.overload_confirm || self.pressed >= PRESS_PERIODS * PRESS_LEAK {
            Some(Runaway::Overload)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The press count at every duty of pressing (issue 80): held, it trips at
    /// the tenth pressed period; interrupted by chatter, once the pressed
    /// periods exceed ten plus a quarter of the others, whatever the pattern
    /// (every duty from 1 in 1 to 1 in 10, every phase); pressing in one period
    /// in five or fewer never trips it; nor does a healthy force of 21.9 N with a
    /// full-scale impact every 20 periods; a reading of -22.5 N (the axis
    /// reversed) counts as pressing.
    #[test]
    fn a_press_trips_within_ten_pressed_periods_plus_a_quarter_of_the_gaps_at_every_duty() {
        let rule = RunawayRule::at_period(1e-4);
        for on in 1..=10u32 {
            for off in 0..=10u32 {
                for phase in 0..(on + off) {
                    let mut m = RunawayMonitor::default();
                    let (mut pressed, mut other) = (0u32, 0u32);
                    let mut tripped = None;
                    for k in 0..2000u32 {
                        let press = (k + phase) % (on + off) < on;
                        let f_n = if press { 22.0 } else { 12.0 };
                        if press {
                            pressed += 1
                        } else {
                            other += 1
                        }
                        if m.update(&rule, [0.0; 2], false, f_n).is_some() {
                            tripped = Some(k);
                            break;
                        }
                    }
                    // Pressing more than one period in five accumulates.
                    match tripped {
                        Some(_) => {
                            assert!(4 * on > off, "{on} on {off} off tripped");
                            // The count is 4 pressed - other >= 40 at the trip
                            // (other periods never take it below 0).
                            assert!(pressed >= 10, "{on}/{off}/{phase}: {pressed} pressed");
                            assert!(4 * pressed <= 40 + other + 3, "{on}/{off}/{phase}: {pressed} pressed, {other} other");
                            if off == 0 {
                                assert_eq!(pressed, 10);
                            }
                        }
                        None => assert!(4 * on <= off, "{on} on {off} off never tripped"),
                    }
                }
            }
        }
        let mut m = RunawayMonitor::default();
        for k in 0..10_000 {
            let f_n = if k % 20 == 0 { 25.0 } else { 21.9 };
            assert_eq!(m.update(&rule, [0.0; 2], k % 20 == 0, f_n), None, "{k}");
        }
        let mut m = RunawayMonitor::default();
        for _ in 0..9 {
            assert_eq!(m.update(&rule, [0.0; 2], false, -22.5), None);
        }
        assert_eq!(m.update(&rule, [0.0; 2], false, -22.5), Some(Runaway::Overload));
        let mut m = RunawayMonitor::default();
        for _ in 0..100 {
            assert_eq!(m.update(&rule, [0.0; 2], false, f32::NAN), None, "NaN is no press (the frame's check rejects it)");
        }
    }

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
            assert_eq!(m.update(&rule, qd, false, 10.0), None);
        }
        assert_eq!(m.update(&rule, [-30.0, 0.0], false, 10.0), Some(Runaway::Speed));
        let mut m = RunawayMonitor::default();
        // The tangential axis clipped (the normal force healthy) for 10 ms.
        for _ in 0..9 {
            assert_eq!(m.update(&rule, [0.0; 2], true, 10.0), None);
        }
        assert_eq!(m.update(&rule, [0.0; 2], true, 10.0), Some(Runaway::Overload));
        // An impact's clip of a few periods never does.
        let mut m = RunawayMonitor::default();
        for k in 0..1000 {
            let f_n = if k % 20 < 2 { 25.0 } else { 10.0 };
            assert_eq!(m.update(&rule, [1.0, -1.0], k % 20 < 2, f_n), None);
        }
        let mut m = RunawayMonitor::default();
        for _ in 0..2 {
            assert_eq!(m.update(&rule, [f32::NAN, 0.0], false, 10.0), None);
        }
        assert_eq!(m.update(&rule, [f32::NAN, 0.0], false, 10.0), Some(Runaway::Speed));
    }
}
