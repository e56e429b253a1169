//! Sensor-consistency monitor: the encoders and the load cell must agree on where
//! the tip is.
//!
//! The load cell and the two joint encoders measure the same contact from two
//! sides. While the load cell reads a normal force `f_n` the tip presses on the
//! belt, so the tip height `z_n + H` from the encoders' forward kinematics must be
//! zero to within the encoders' quantisation (two 14-bit counts put the tip within
//! about `2 l q = 0.2 mm` of its true place at `l = 0.5 m`); and the tip can never
//! be inside the belt, whatever the force. A sensor that sticks (repeats its last
//! count) while the arm moves breaks one of these within a few periods: a stuck
//! base or elbow encoder moves the computed tip off the belt line while the tip
//! still presses, a stuck load cell reads contact while the encoders see the tip
//! in flight. Neither happens in a healthy run, bounces and impacts included:
//! forces and angles are sampled at the same instant, and in flight `f_n = 0`.
//!
//! A second check watches each angle observer's innovation (measured minus
//! model-predicted angle, [`crate::estimator::AngleTracker`]). The prediction is
//! driven by the model's joint acceleration under the commanded torque and the
//! measured forces, so in a healthy run the innovation is quantisation noise
//! (within 2 counts on the paper's scenarios). An encoder that sticks while the
//! arm accelerates leaves a persistent innovation of one sign, of about
//! `a Ts^2 / beta` (`beta` the observer's gain, 0.05 at 40 Hz and 1 kHz: 2 mrad,
//! 5 counts, at `a = 100 rad/s^2`). An impact is the one healthy event with a
//! large innovation (an unmeasured impulse changes the velocity): the check is
//! off while lift-off is declared and for a settling time after touchdown. It is
//! off too while the load cell is at full scale (then the measured force, and the
//! prediction made with it, is wrong: the true force is larger).
//!
//! A belt can only push: a normal force below `-contact_force` is inconsistent
//! wherever the tip is. Noise and quantisation stay within tens of mN of zero in
//! flight, so only a load cell of the wrong sign (its normal axis mounted or
//! calibrated the other way) or a zero offset of several newtons reads it
//! (issue 23: a wrong calibration must never drive the arm away).
//!
//! What it cannot see: both encoders stuck while the tip stays on the belt line
//! (the computed tip is frozen on the belt and consistent with the force), or a
//! stuck sensor while the arm is at rest (then the reading is right).

/// Thresholds of the monitor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConsistencyRule {
    /// Normal force above which the load cell says the tip presses on the belt, N.
    pub contact_force: f32,
    /// Largest `|z_n + H|` from the encoders that is still on the belt, m.
    pub height_tolerance: f32,
    /// Consecutive inconsistent periods that declare a sensor fault.
    pub confirm: u8,
}

/// The monitor's state across periods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ConsistencyMonitor {
    inconsistent: u8,
    pulling: u8,
}

/// Consecutive periods of a pulling belt (`f_n < -contact_force`) that declare
/// a sensor fault, whatever `confirm`: no healthy sample reads it (the noise is
/// 20 mN), and a load cell of the wrong sign must be caught on the two frames a
/// PID from `x0d` reads before its lift-off (issue 52).
pub const PULLING_CONFIRM: u8 = 2;

impl ConsistencyMonitor {
    /// Folds in one period: the measured normal force `f_n` (N) and the tip height
    /// above the belt from the encoders `height` (`z_n + H`, m). Returns `true`
    /// once `rule.confirm` consecutive periods were inconsistent (pressing while off
    /// the belt line, or below the belt by more than the tolerance); a consistent
    /// period clears the count. Non-finite inputs count as inconsistent, and so
    /// does a pulling belt (`f_n < -contact_force`), which declares the fault
    /// after [`PULLING_CONFIRM`] periods.
    pub fn update(&mut self, rule: &ConsistencyRule, f_n: f32, height: f32) -> bool {
        let pressing_off_the_belt = f_n > rule.contact_force && height.abs() > rule.height_tolerance;
        let inside_the_belt = height < -rule.height_tolerance;
        let pulling = f_n < -rule.contact_force;
        let inconsistent = pressing_off_the_belt || inside_the_belt || pulling || !crate::finite::finite_both(f_n, height);
        self.inconsistent = if inconsistent { self.inconsistent.saturating_add(1) } else { 0 };
        self.pulling = if pulling { self.pulling.saturating_add(1) } else { 0 };
        self.inconsistent >= rule.confirm || self.pulling >= PULLING_CONFIRM.min(rule.confirm)
    }
}

/// Slip speed `|z_t_dot - v_belt|` above which the tip surely slides, m/s
/// (the observer's velocity noise is a few mm/s).
pub const SLIP_MIN: f32 = 0.05;
/// How long friction along the slip must last to declare a sensor fault, s:
/// longer than the observer's lag after an unmeasured velocity jump (the belt
/// grabbing a tip at rest makes it stick at once, and the estimated slip lags
/// the true one by about `2 / w`, 8 ms at 40 Hz).
pub const FRICTION_CONFIRM_S: f32 = 0.020;

/// Coulomb's law against the load cell's tangential axis (issue 52): while the
/// tip slides on the belt (the normal force above `contact_force`, the slip
/// speed above [`SLIP_MIN`]), friction opposes the slip, `f_t (z_t_dot -
/// v_belt) < 0`, whatever `mu`. A tangential axis of the wrong sign reads
/// friction along the slip at `mu f_n`; a healthy one never does (noise is
/// 20 mN, the threshold a quarter of `contact_force`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrictionSignMonitor {
    run: u16,
    /// Periods left before the check counts again after a lift-off.
    quiet: u16,
}

impl FrictionSignMonitor {
    /// Folds in one period: the measured forces `f_t`, `f_n` (N) and the slip
    /// velocity `slip = z_t_dot - v_belt` (m/s), and whether the slip may be
    /// wrong (lift-off declared, or the load cell at full scale). Returns `true` once friction was along the slip for `confirm`
    /// periods in a row ([`FrictionSignMonitor::confirm_periods`]). A touchdown
    /// is an unmeasured impulse too (the estimated slip lags the true one): the
    /// check counts only from `confirm` periods after the last unsure one.
    pub fn update(&mut self, contact_force: f32, f_t: f32, f_n: f32, slip: f32, unsure: bool, confirm: u16) -> bool {
        if unsure {
            self.quiet = confirm;
        } else {
            self.quiet = self.quiet.saturating_sub(1);
        }
        // Friction along the slip first: in a healthy slide it opposes it, so the
        // usual period ends at the first comparison (the same verdict in any order:
        // each term is a comparison of its own, issue 56).
        let along = f_t * slip > 0.0
            && self.quiet == 0
            && !unsure
            && f_n > contact_force
            && slip.abs() > SLIP_MIN
            && f_t.abs() > 0.25 * contact_force;
        self.run = if along { self.run.saturating_add(1) } else { 0 };
        self.run >= confirm
    }

    /// [`FRICTION_CONFIRM_S`] in periods of `ts` seconds (at least 1).
    pub fn confirm_periods(ts: f32) -> u16 {
        crate::runaway::periods_of(FRICTION_CONFIRM_S, ts)
    }
}

/// Thresholds of the innovation check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InnovationRule {
    /// Innovation magnitude that counts as inconsistent, rad.
    pub threshold: f32,
    /// Consecutive periods of one sign above the threshold that declare a sensor fault.
    pub confirm: u16,
    /// Periods after a declared touchdown during which the check is off (the
    /// observer settles after the impact's velocity jump).
    pub settle: u16,
}

/// The innovation check's state across periods: per joint, the length of the
/// current run of same-sign innovations above the threshold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct InnovationMonitor {
    run: [u16; 2],
    sign: [i8; 2],
    settling: u16,
    was_lifted: bool,
}

impl InnovationMonitor {
    /// Folds in one period's innovations `[theta1, theta2]` (rad), whether
    /// lift-off is declared, and whether the load cell is at full scale. Returns
    /// `true` once either joint has had `rule.confirm` consecutive innovations of
    /// one sign beyond `rule.threshold` outside the impact windows (lift-off, and
    /// `rule.settle` periods after touchdown) and with the load cell in range.
    pub fn update(&mut self, rule: &InnovationRule, innovation: [f32; 2], lifted: bool, load_saturated: bool) -> bool {
        if self.was_lifted && !lifted {
            self.settling = rule.settle;
        }
        self.was_lifted = lifted;
        if lifted || load_saturated || self.settling > 0 {
            self.settling = self.settling.saturating_sub(1);
            *self = Self { run: [0; 2], sign: [0; 2], ..*self };
            return false;
        }
        // Two joints written out (the loop is not unrolled at `opt-level = "s"`).
        let mut joint = |j: usize, r: f32| {
            let sign = side(r, rule.threshold);
            self.run[j] = if sign != 0 && sign == self.sign[j] { self.run[j].saturating_add(1) } else { u16::from(sign != 0) };
            self.sign[j] = sign;
            self.run[j] >= rule.confirm
        };
        let first = joint(0, innovation[0]);
        joint(1, innovation[1]) | first
    }
}

/// The side of `threshold` an innovation `r` (rad) lies on: `1` above it, `-1`
/// below `-threshold`, else 0 (a NaN too). Within the threshold first (the usual
/// period: one comparison, no taken branch), then the two sides: the same sign
/// for every `r` and threshold as the two comparisons alone (`|r| <= t` makes both
/// `r > t` and `r < -t` false; a NaN, or a threshold that is not a number, takes
/// the two comparisons; test `the_side_is_the_two_comparisons`). Issue 56.
#[inline(always)]
fn side(r: f32, threshold: f32) -> i8 {
    if r.abs() <= threshold {
        0
    } else if r > threshold {
        1
    } else if r < -threshold {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The friction sign check with its conjunction reordered keeps the state and
    /// verdicts of the order before issue 56's fifth round: pseudo-random runs of
    /// forces, slips (NaNs and infinities among them) and unsure periods.
    #[test]
    fn the_reordered_friction_check_is_the_former() {
        fn former(m: &mut FrictionSignMonitor, contact_force: f32, f_t: f32, f_n: f32, slip: f32, unsure: bool, confirm: u16) -> bool {
            if unsure {
                m.quiet = confirm;
            } else {
                m.quiet = m.quiet.saturating_sub(1);
            }
            let along = m.quiet == 0
                && !unsure
                && f_n > contact_force
                && slip.abs() > SLIP_MIN
                && f_t * slip > 0.0
                && f_t.abs() > 0.25 * contact_force;
            m.run = if along { m.run.saturating_add(1) } else { 0 };
            m.run >= confirm
        }
        let mut seed = 0x9e37_79b9_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed as f32 / u32::MAX as f32 - 0.5
        };
        let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0];
        let (mut a, mut b) = (FrictionSignMonitor::default(), FrictionSignMonitor::default());
        let mut trips = 0;
        for i in 0..300_000usize {
            let (mut f_t, f_n, mut slip) = (next() * 10.0, next() * 20.0 + 5.0, next() * 0.4);
            if i % 53 == 0 {
                f_t = odd[(i / 53) % odd.len()];
            }
            if i % 71 == 0 {
                slip = odd[(i / 71) % odd.len()];
            }
            let unsure = i % 97 < 2;
            let va = a.update(2.0, f_t, f_n, slip, unsure, 4);
            assert_eq!(va, former(&mut b, 2.0, f_t, f_n, slip, unsure, 4), "step {i}");
            assert_eq!(a, b, "step {i}");
            trips += usize::from(va);
        }
        assert!(trips > 10, "{trips}");
    }

    /// [`side`] against the two comparisons it starts with a third for: every
    /// innovation and threshold of a grid over both signs and the `f32` range by
    /// exponent, each value's neighbours, the zeros, the infinities and NaNs.
    #[test]
    fn the_side_is_the_two_comparisons() {
        let two = |r: f32, t: f32| {
            if r > t {
                1
            } else if r < -t {
                -1
            } else {
                0
            }
        };
        let mut values = std::vec![0.0f32, -0.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -f32::NAN, f32::MAX, 1e-45];
        for e in -40..=40 {
            let x = libm::exp2f(e as f32 * 0.5);
            for v in [x, f32::from_bits(x.to_bits() + 1), f32::from_bits(x.to_bits() - 1)] {
                values.extend([v, -v]);
            }
        }
        for &r in &values {
            for &t in &values {
                assert_eq!(side(r, t), two(r, t), "r {r:e}, threshold {t:e}");
            }
        }
    }

    const RULE: ConsistencyRule = ConsistencyRule { contact_force: 2.0, height_tolerance: 2e-3, confirm: 3 };

    #[test]
    fn sliding_flight_and_touchdown_are_consistent() {
        let mut m = ConsistencyMonitor::default();
        // Sliding with quantisation error, flight with load-cell noise, touchdown.
        let samples = [(10.0, 2e-4), (10.0, -2e-4), (0.03, 5e-3), (-0.03, 2e-2), (0.0, 1e-3), (25.0, 0.0)];
        for _ in 0..100 {
            for (f_n, h) in samples {
                assert!(!m.update(&RULE, f_n, h));
            }
        }
    }

    #[test]
    fn a_belt_that_pulls_is_a_load_cell_of_the_wrong_sign() {
        let mut m = ConsistencyMonitor::default();
        // Flight noise and a light touch pass; a pulling belt on the belt line is
        // declared after `confirm` periods.
        for f_n in [-0.05, -1.9, 0.0] {
            assert!(!m.update(&RULE, f_n, 0.0), "{f_n}");
        }
        assert!(!m.update(&RULE, -10.0, 0.0));
        assert!(m.update(&RULE, -10.0, 0.0), "two periods of a pulling belt");
        let mut m = ConsistencyMonitor::default();
        for _ in 0..50 {
            assert!(!m.update(&RULE, -10.0, 0.0));
            assert!(!m.update(&RULE, 5.0, 0.0), "a pushing period between clears the count");
        }
    }

    #[test]
    fn pressing_off_the_belt_is_declared_after_confirm_periods_and_a_good_period_clears_it() {
        let mut m = ConsistencyMonitor::default();
        assert!(!m.update(&RULE, 10.0, 3e-3));
        assert!(!m.update(&RULE, 10.0, 3e-3));
        assert!(!m.update(&RULE, 10.0, 0.0), "a consistent period clears the count");
        assert!(!m.update(&RULE, 10.0, 3e-3));
        assert!(!m.update(&RULE, 10.0, -3e-3));
        assert!(m.update(&RULE, 10.0, 3e-3), "3rd consecutive");
    }

    #[test]
    fn inside_the_belt_or_non_finite_is_inconsistent_whatever_the_force() {
        let mut m = ConsistencyMonitor::default();
        for _ in 0..2 {
            assert!(!m.update(&RULE, 0.0, -5e-3));
        }
        assert!(m.update(&RULE, 0.0, -5e-3));
        let mut m = ConsistencyMonitor::default();
        for _ in 0..2 {
            assert!(!m.update(&RULE, f32::NAN, 0.0));
        }
        assert!(m.update(&RULE, 0.0, f32::INFINITY));
    }
}

#[cfg(test)]
mod friction_tests {
    use super::*;

    #[test]
    fn friction_along_the_slip_is_declared_after_20_ms_and_only_while_sliding() {
        let mut m = FrictionSignMonitor::default();
        // Healthy sliding: the belt moves at -0.4 m/s under a still tip, slip +0.4,
        // friction -mu f_n.
        for _ in 0..100 {
            assert!(!m.update(2.0, -6.0, 10.0, 0.4, false, 20));
        }
        // Reversed axis: 19 periods pass, the 20th (20 ms at 1 kHz) declares.
        assert_eq!(FrictionSignMonitor::confirm_periods(1e-3), 20);
        assert_eq!(FrictionSignMonitor::confirm_periods(1e-4), 200);
        for _ in 1..20 {
            assert!(!m.update(2.0, 6.0, 10.0, 0.4, false, 20));
        }
        assert!(m.update(2.0, 6.0, 10.0, 0.4, false, 20));
        // Not in contact, sticking, or noise: never.
        let mut m = FrictionSignMonitor::default();
        for _ in 0..100 {
            assert!(!m.update(2.0, 6.0, 1.0, 0.4, false, 1), "light contact");
            assert!(!m.update(2.0, 6.0, 10.0, 0.01, false, 1), "sticking");
            assert!(!m.update(2.0, 0.03, 10.0, 0.4, false, 1), "noise");
        }
        // After a lift-off it is quiet for `confirm` periods (the 20th counts), then
        // trips after `confirm` more.
        let mut m = FrictionSignMonitor::default();
        assert!(!m.update(2.0, 6.0, 0.0, 0.4, true, 20));
        for k in 0..38 {
            assert!(!m.update(2.0, 6.0, 10.0, 0.4, false, 20), "{k}");
        }
        assert!(m.update(2.0, 6.0, 10.0, 0.4, false, 20));
    }
}

#[cfg(test)]
mod innovation_tests {
    use super::*;

    const RULE: InnovationRule = InnovationRule { threshold: 1e-3, confirm: 4, settle: 5 };

    #[test]
    fn a_persistent_one_sign_innovation_is_declared_after_confirm_periods() {
        let mut m = InnovationMonitor::default();
        for _ in 0..3 {
            assert!(!m.update(&RULE, [0.0, 2e-3], false, false));
        }
        assert!(m.update(&RULE, [0.0, 2e-3], false, false));
    }

    #[test]
    fn sign_changes_and_noise_reset_the_run() {
        let mut m = InnovationMonitor::default();
        for k in 0..100 {
            let r = if k % 3 == 0 { -2e-3 } else { 2e-3 };
            assert!(!m.update(&RULE, [r, 5e-4], false, false));
        }
    }

    #[test]
    fn the_check_is_off_in_flight_and_while_settling_after_touchdown() {
        let mut m = InnovationMonitor::default();
        for _ in 0..10 {
            assert!(!m.update(&RULE, [5e-3, 5e-3], true, false));
        }
        // Touchdown: 5 settling periods, then 4 more to confirm.
        for k in 0..8 {
            assert!(!m.update(&RULE, [5e-3, 0.0], false, false), "period {k}");
        }
        assert!(m.update(&RULE, [5e-3, 0.0], false, false));
    }

    #[test]
    fn the_check_is_off_while_the_load_cell_is_at_full_scale() {
        let mut m = InnovationMonitor::default();
        for _ in 0..100 {
            assert!(!m.update(&RULE, [5e-3, 5e-3], false, true));
        }
        for _ in 0..3 {
            assert!(!m.update(&RULE, [5e-3, 5e-3], false, false));
        }
        assert!(m.update(&RULE, [5e-3, 5e-3], false, false));
    }
}
