//! Wiring checks: a joint that accelerates against the torque its motor was
//! commanded (issue 52). A motor wired the other way, an encoder mounted
//! reversed or the two encoders' chip selects swapped all make the arm move, as
//! the firmware sees it, against what it commands, from the first period and
//! at any speed: the runaway limits ([`crate::runaway`]) see it only once the
//! arm is whipped past 20 rad/s or the load cell clips, 30 to 450 ms later.
//!
//! **The signal.** Each angle's observer ([`crate::estimator::AngleTracker`])
//! predicts the angle with the model's joint acceleration under the applied
//! torque and the measured contact force, and corrects its rate by
//! `beta / Ts * r` for an innovation `r`: that correction, per second, is the
//! joint acceleration the model did not explain, `a_u = beta r / (Ts dt)`
//! (rad/s^2). Through the mass matrix it is the generalised torque the model
//! missed, `M(q) a_u`, and, with `u_gen = [u1 - u2, u2]` (paper eq. 9), the
//! motor torques it missed: `du = [d0 + d1, d1]` (N m). A first-order filter of
//! time constant [`FILTER_S`] takes the quantisation's noise out of it (one
//! 14-bit count of innovation is `beta q / Ts^2` = 19 rad/s^2 at 1 kHz; the
//! filtered torque noise is a few mN m).
//!
//! **The rule.** Motor `j` is miswired when its missed torque opposes the
//! torque it applied by more than [`AGAINST_FRACTION`] of it plus the model's
//! uncertainty [`MARGIN_NM`], `du_j u_j < 0` and `|du_j| > 0.5 |u_j| + 0.15 N m`,
//! or opposes the net torque the model expected to move the joint by more than
//! [`NET_FRACTION`] of it plus [`NET_MARGIN_NM`] (`0.3 |net_j| + 0.1 N m`), for
//! [`CONFIRM_S`] in a row. A reversed motor makes `du_j = -2 u_j`: four times
//! the fraction. A reversed encoder makes the joint's measured acceleration the
//! negative of the true one, so the firmware sees `du_j` of about `-2 u_j` too.
//! In a healthy run `du` is the model's error: the contact force's change
//! within a period (the load cell is sampled at the period's start), the
//! command's delay (`delta`), the PWM's duty quantisation and the load cell's
//! noise, all within tens of mN m.
//!
//! **Where it is off.** An impact changes the joints' velocities by an impulse
//! the load cell never samples: the observers take about [`SETTLE_S`] to absorb
//! it, and their `a_u` is then large and of any sign. The check is therefore
//! off while the load cell is at full scale (its force under-reads), from a
//! touchdown for [`SETTLE_S`], and while the tip, declared lifted, descends
//! within [`IMPACT_HEIGHT_M`] of the belt (an impact may come), and for
//! [`SETTLE_S`] after; a tip declared lifted that sits at the belt longer than
//! [`IMPACT_SERIES_S`] is no longer coming down to an impact (a load cell that
//! reads no force under a pressing tip), and the check runs. A tip that rises from the belt cannot hit it: a motor
//! that whips the arm off the belt is seen from the first periods.

/// The fraction of its applied torque a motor's missed torque must oppose it by.
pub const AGAINST_FRACTION: f32 = 0.5;
/// The model's uncertainty in motor torque, N m.
pub const MARGIN_NM: f32 = 0.15;
/// The fraction of the net torque (`WiringInput::net`) a joint's missed torque
/// must oppose it by: a joint that does not move as the torque beyond the arm's
/// load should (a stuck encoder misses all of it, about 40 to 100 % through the
/// coupling of the joints). Measured, not derived: over the 2 000 healthy runs of
/// the envelope and issue 52's 1 000 the model's own error stays below 0.25 of the
/// net torque plus [`NET_MARGIN_NM`], and 0.3 with 0.075 N m hold too; 0.2 with
/// 0.05 N m stop healthy runs (a PID's touchdown from `x0u`, a 400 Hz hybrid run).
pub const NET_FRACTION: f32 = 0.3;
/// The model's uncertainty against the net torque, N m (see [`NET_FRACTION`]).
pub const NET_MARGIN_NM: f32 = 0.1;
/// The missed torque's filter time constant, s.
pub const FILTER_S: f32 = 0.004;
/// How long the rule must hold, s.
pub const CONFIRM_S: f32 = 0.005;
/// How long the check stays off after an impact may have happened, s.
pub const SETTLE_S: f32 = 0.015;
/// Height above the belt within which a descending lifted tip may hit it, m.
pub const IMPACT_HEIGHT_M: f32 = 0.005;
/// Longest a tip declared lifted may sit at the belt (its estimated height at or
/// below 0) and still count as coming down to an impact, s: a series of small
/// bounces (restitution `e_n` 0.2 of the paper's arm) ends in sustained contact,
/// which the load cell samples, within a few tens of milliseconds (the PID from
/// `x0u`: 16 ms); a load cell that reads no force with the tip on the belt for
/// longer is a fault the check must see (a dead normal axis).
pub const IMPACT_SERIES_S: f32 = 0.1;

/// The rule in periods of the control rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WiringRule {
    /// `AGAINST_FRACTION`.
    pub against_fraction: f32,
    /// `MARGIN_NM`, N m.
    pub margin_nm: f32,
    /// `NET_FRACTION`.
    pub net_fraction: f32,
    /// `NET_MARGIN_NM`, N m.
    pub net_margin_nm: f32,
    /// The filter's gain per period, `Ts / (FILTER_S + Ts)`.
    pub smoothing: f32,
    /// Periods the rule must hold.
    pub confirm: u16,
    /// Periods the check stays off after a possible impact.
    pub settle: u16,
    /// `IMPACT_HEIGHT_M`, m.
    pub impact_height: f32,
    /// `IMPACT_SERIES_S` in periods.
    pub impact_series: u16,
}

impl WiringRule {
    /// The rule above at a control period of `ts` seconds.
    pub fn at_period(ts: f32) -> Self {
        Self {
            against_fraction: AGAINST_FRACTION,
            margin_nm: MARGIN_NM,
            net_fraction: NET_FRACTION,
            net_margin_nm: NET_MARGIN_NM,
            smoothing: ts / (FILTER_S + ts),
            confirm: crate::runaway::periods_of(CONFIRM_S, ts),
            settle: crate::runaway::periods_of(SETTLE_S, ts),
            impact_height: IMPACT_HEIGHT_M,
            impact_series: crate::runaway::periods_of(IMPACT_SERIES_S, ts),
        }
    }
}

/// What one period tells the check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WiringInput {
    /// The joint accelerations the model did not explain `[theta1, theta2]`, rad/s^2.
    pub unexplained: [f32; 2],
    /// `cos(theta2 - theta1)`, for the mass matrix.
    pub c21: f32,
    /// The motor torques `[u1, u2]` applied over the interval, N m.
    pub applied: [f32; 2],
    /// The motor torques the model expected to accelerate the joints over the
    /// interval, `[v0 + v1, v1]` of `M q_ddot = u - w - c + J^T f` (N m):
    /// `applied` less what holds the arm against gravity, the spring and the
    /// contact.
    pub net: [f32; 2],
    /// Lift-off declared.
    pub lifted: bool,
    /// The tip's height above the belt from the estimate, `z_n + H`, m.
    pub height: f32,
    /// The tip's normal velocity `z_n_dot`, m/s.
    pub height_rate: f32,
    /// The load cell is at full scale on either axis.
    pub load_saturated: bool,
}

/// The check's state across periods.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WiringMonitor {
    /// The filtered missed motor torques `[u1, u2]`, N m.
    missed: [f32; 2],
    /// The filtered net motor torques (`WiringInput::net`), N m.
    net: [f32; 2],
    run: [u16; 2],
    settling: u16,
    was_lifted: bool,
    /// Periods in a row declared lifted with the tip at or below the belt.
    at_belt: u16,
}

impl WiringMonitor {
    /// The filtered missed motor torques `[u1, u2]`, N m.
    pub fn missed(&self) -> [f32; 2] {
        self.missed
    }

    /// Whether the rule holds at the last period for either motor, its
    /// confirmation not reached yet: the evidence of a miswired motor when
    /// another check trips first (issue 80: the chatter check named reversed
    /// motors and encoders `Unstable`, the law's own failure).
    pub fn suspects(&self) -> bool {
        self.run[0] > 0 || self.run[1] > 0
    }

    /// Folds in one period with `m`, the arm's `m l^2` (kg m^2). Returns the
    /// motor (0: `u1`, 1: `u2`) found miswired once the rule held for its
    /// confirmation. Non-finite inputs are no evidence (the other checks see them).
    pub fn update(&mut self, rule: &WiringRule, ml2: f32, input: &WiringInput) -> Option<usize> {
        self.update_folded(rule, [(4.0 / 3.0) * ml2, 0.5 * ml2, (1.0 / 3.0) * ml2], input)
    }

    /// [`WiringMonitor::update`] with the mass matrix's factors folded once per
    /// configuration, `[4/3, 1/2, 1/3]` times `m l^2` (kg m^2; `shared::model::ArmTerms`'
    /// `m11`, `half_ml2`, `m22`, the same products): the same bits, without the
    /// step's five products for them.
    #[inline(always)]
    pub fn update_folded(&mut self, rule: &WiringRule, mass: [f32; 3], input: &WiringInput) -> Option<usize> {
        // M(q) a_u (paper eq. 1), then the motor torques of u_gen = [u1 - u2, u2].
        let [m11, half_ml2, m22] = mass;
        let off = half_ml2 * input.c21;
        let a = input.unexplained;
        let d0 = m11 * a[0] + off * a[1];
        let d1 = off * a[0] + m22 * a[1];
        let du = [d0 + d1, d1];
        // Two joints written out (the loops' iterators are not unrolled at `opt-level = "s"`).
        // Selects, not conditional stores: the filtered values stay in registers for
        // the rule below (the same bits: a non-finite `d` leaves the value as it was).
        let smoothing = rule.smoothing;
        let filter = |m: f32, d: f32| if crate::finite::finite(d) { m + smoothing * (d - m) } else { m };
        let missed = [filter(self.missed[0], du[0]), filter(self.missed[1], du[1])];
        self.missed = missed;
        let net = [filter(self.net[0], input.net[0]), filter(self.net[1], input.net[1])];
        self.net = net;
        let touchdown = self.was_lifted && !input.lifted;
        self.was_lifted = input.lifted;
        self.at_belt = if input.lifted && input.height <= 0.0 { self.at_belt.saturating_add(1) } else { 0 };
        let impact_may_come =
            input.lifted && input.height < rule.impact_height && input.height_rate < -0.01 && self.at_belt <= rule.impact_series;
        if touchdown || impact_may_come {
            self.settling = rule.settle;
        }
        if input.load_saturated || self.settling > 0 {
            self.settling = self.settling.saturating_sub(1);
            self.run = [0; 2];
            return None;
        }
        let (fraction, margin) = (rule.against_fraction, rule.margin_nm);
        let against = |d: f32, u: f32| d * u < 0.0 && d.abs() > fraction * u.abs() + margin;
        let run = |n: u16, against: bool| if against { n.saturating_add(1) } else { 0 };
        // Against the applied torque (a reversed motor, encoder or pair), or
        // against the net torque the model expected to move the joint (a stuck
        // encoder: the joint does not move as the torque beyond the arm's load
        // should; a dead or weak motor under a load).
        let (net_fraction, net_margin) = (rule.net_fraction, rule.net_margin_nm);
        let against_net = |d: f32, u: f32| d * u < 0.0 && d.abs() > net_fraction * u.abs() + net_margin;
        let joint = |j: usize| against(missed[j], input.applied[j]) || against_net(missed[j], net[j]);
        self.run = [run(self.run[0], joint(0)), run(self.run[1], joint(1))];
        if self.run[0] >= rule.confirm {
            Some(0)
        } else if self.run[1] >= rule.confirm {
            Some(1)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's arm: `m l^2` of m = 0.12 kg, l = 0.21 m.
    const ML2: f32 = 0.12 * 0.21 * 0.21;

    /// The joint accelerations a missed motor torque `du` (N m) leaves at
    /// `c21`: `M^-1` of the generalised torque `[du1 - du2, du2]`.
    fn accel_of(du: [f32; 2], c21: f32) -> [f32; 2] {
        let (a, b, d) = ((4.0 / 3.0) * ML2, 0.5 * ML2 * c21, ML2 / 3.0);
        let t = [du[0] - du[1], du[1]];
        let det = a * d - b * b;
        [(d * t[0] - b * t[1]) / det, (a * t[1] - b * t[0]) / det]
    }

    fn input(unexplained: [f32; 2], applied: [f32; 2]) -> WiringInput {
        WiringInput { unexplained, c21: 0.9, applied, net: applied, lifted: false, height: 0.0, height_rate: 0.0, load_saturated: false }
    }

    /// The factors folded in `ArmTerms` are the products `update` takes of `m l^2`,
    /// so `update_folded` with them keeps every bit of `update`'s state and verdicts.
    #[test]
    fn the_folded_factors_are_the_products_bit_for_bit() {
        let p = shared::Params::<f32>::paper();
        let terms = shared::model::ArmTerms::of(&p);
        let ml2 = p.m * p.l * p.l;
        assert_eq!(
            [terms.m11, terms.half_ml2, terms.m22].map(f32::to_bits),
            [(4.0 / 3.0) * ml2, 0.5 * ml2, (1.0 / 3.0) * ml2].map(f32::to_bits)
        );
        let rule = WiringRule::at_period(1e-3);
        let (mut a, mut b) = (WiringMonitor::default(), WiringMonitor::default());
        for i in 0..200 {
            let x = i as f32 * 0.37;
            let inp = WiringInput { c21: libm::cosf(x), ..input([30.0 * libm::sinf(x), -50.0 * libm::cosf(1.3 * x)], [0.4, -0.2]) };
            let (va, vb) = (a.update(&rule, ml2, &inp), b.update_folded(&rule, [terms.m11, terms.half_ml2, terms.m22], &inp));
            assert_eq!(va, vb);
            assert_eq!(a.missed().map(f32::to_bits), b.missed().map(f32::to_bits), "step {i}");
        }
    }

    /// [`WiringMonitor::update_folded`] as issue 56's fourth round left it: the
    /// filter by conditional stores, the rule on the stored values.
    fn update_stored(m: &mut WiringMonitor, rule: &WiringRule, mass: [f32; 3], input: &WiringInput) -> Option<usize> {
        let [m11, half_ml2, m22] = mass;
        let off = half_ml2 * input.c21;
        let a = input.unexplained;
        let d0 = m11 * a[0] + off * a[1];
        let d1 = off * a[0] + m22 * a[1];
        let du = [d0 + d1, d1];
        let filter = |m: &mut f32, d: f32| {
            if crate::finite::finite(d) {
                *m += rule.smoothing * (d - *m);
            }
        };
        filter(&mut m.missed[0], du[0]);
        filter(&mut m.missed[1], du[1]);
        filter(&mut m.net[0], input.net[0]);
        filter(&mut m.net[1], input.net[1]);
        let touchdown = m.was_lifted && !input.lifted;
        m.was_lifted = input.lifted;
        m.at_belt = if input.lifted && input.height <= 0.0 { m.at_belt.saturating_add(1) } else { 0 };
        let impact_may_come =
            input.lifted && input.height < rule.impact_height && input.height_rate < -0.01 && m.at_belt <= rule.impact_series;
        if touchdown || impact_may_come {
            m.settling = rule.settle;
        }
        if input.load_saturated || m.settling > 0 {
            m.settling = m.settling.saturating_sub(1);
            m.run = [0; 2];
            return None;
        }
        let against = |d: f32, u: f32| d * u < 0.0 && d.abs() > rule.against_fraction * u.abs() + rule.margin_nm;
        let against_net = |d: f32, u: f32| d * u < 0.0 && d.abs() > rule.net_fraction * u.abs() + rule.net_margin_nm;
        let run = |n: u16, against: bool| if against { n.saturating_add(1) } else { 0 };
        let joint = |j: usize| against(m.missed[j], input.applied[j]) || against_net(m.missed[j], m.net[j]);
        m.run = [run(m.run[0], joint(0)), run(m.run[1], joint(1))];
        if m.run[0] >= rule.confirm {
            Some(0)
        } else if m.run[1] >= rule.confirm {
            Some(1)
        } else {
            None
        }
    }

    /// The filter by selects keeps the stored form's state and verdicts bit for
    /// bit: long pseudo-random runs of accelerations (non-finite ones among them),
    /// torques, lift-offs, heights and full-scale periods, at three rates.
    #[test]
    fn the_selected_filter_is_the_stored_one_bit_for_bit() {
        let terms = shared::model::ArmTerms::of(&shared::Params::<f32>::paper());
        let mass = [terms.m11, terms.half_ml2, terms.m22];
        let mut seed = 0x2545_f491_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30];
        let mut trips = 0;
        for ts in [1e-3f32, 1e-4, 4e-3] {
            let rule = WiringRule::at_period(ts);
            let (mut a, mut b) = (WiringMonitor::default(), WiringMonitor::default());
            for i in 0..200_000 {
                let mut r = |scale: f32| (next() as f32 / u32::MAX as f32 - 0.5) * scale;
                let mut unexplained = [r(400.0), r(400.0)];
                if i % 97 == 0 {
                    unexplained[i % 2] = odd[(i / 97) % odd.len()];
                }
                let input = WiringInput {
                    unexplained,
                    c21: r(2.0),
                    applied: [r(1.0), r(1.0)],
                    net: [r(1.0), r(1.0)],
                    lifted: i % 50 < 3,
                    height: r(0.02),
                    height_rate: r(0.2),
                    load_saturated: i % 211 == 0,
                };
                let (va, vb) = (a.update_folded(&rule, mass, &input), update_stored(&mut b, &rule, mass, &input));
                assert_eq!(va, vb, "step {i}");
                assert_eq!(
                    (a.missed.map(f32::to_bits), a.net.map(f32::to_bits), a.run, a.settling, a.was_lifted, a.at_belt),
                    (b.missed.map(f32::to_bits), b.net.map(f32::to_bits), b.run, b.settling, b.was_lifted, b.at_belt),
                    "step {i}"
                );
                trips += usize::from(va.is_some());
            }
        }
        assert!(trips > 100, "{trips} trips");
    }

    #[test]
    fn the_missed_torque_is_the_motor_torque_that_made_the_acceleration() {
        // One period with the filter's gain 1 gives back the motor torques exactly.
        let rule = WiringRule { smoothing: 1.0, ..WiringRule::at_period(1e-3) };
        for du in [[0.3f32, 0.0], [0.0, -0.2], [1.0, 1.0], [-0.7, 0.4]] {
            let mut m = WiringMonitor::default();
            m.update(&rule, ML2, &input(accel_of(du, 0.9), [0.0; 2]));
            for j in 0..2 {
                assert!((m.missed()[j] - du[j]).abs() < 1e-5, "{du:?}: {:?}", m.missed());
            }
        }
    }

    #[test]
    fn a_reversed_motor_trips_after_the_filter_and_the_confirmation_at_every_rate() {
        for (j, u) in [(0usize, 0.4f32), (1, -0.3)] {
            for ts in [1e-3f32, 1e-4, 4e-3] {
                let rule = WiringRule::at_period(ts);
                let mut applied = [0.0; 2];
                applied[j] = u;
                let mut du = [0.0; 2];
                du[j] = -2.0 * u;
                let mut m = WiringMonitor::default();
                let a = accel_of(du, 0.9);
                let trip = (1..10_000).find(|_| m.update(&rule, ML2, &input(a, applied)).is_some()).unwrap();
                // The filter reaches the rule's threshold, then the confirmation runs.
                let t = trip as f32 * ts;
                assert!(t <= FILTER_S * 2.0 + CONFIRM_S + ts, "motor {j} at {ts} s: tripped after {t} s");
                assert!(t >= CONFIRM_S - 1e-6, "motor {j} at {ts} s: tripped after {t} s");
            }
        }
    }

    #[test]
    fn a_joint_that_misses_its_net_torque_trips_and_one_within_the_net_margin_never_does() {
        // The motor holds the arm's load (3 N m applied) and the model expects 1 N m
        // of it to move joint 1: missing 0.45 N m of that opposes it beyond
        // 0.3 x 1 + 0.1; 0.35 N m does not, nor does any torque along it.
        let rule = WiringRule::at_period(1e-3);
        for (missed, trips) in [(-0.45f32, true), (-0.35, false), (0.9, false)] {
            let mut m = WiringMonitor::default();
            let i = WiringInput { net: [1.0, 0.0], ..input(accel_of([missed, 0.0], 0.9), [3.0, 0.0]) };
            let k = (1..1000).find(|_| m.update(&rule, ML2, &i).is_some());
            assert_eq!(k.is_some(), trips, "missed {missed} N m against a net 1 N m: {k:?}");
        }
    }

    #[test]
    fn a_missed_torque_along_the_applied_one_or_within_the_margin_never_trips() {
        let rule = WiringRule::at_period(1e-3);
        let mut m = WiringMonitor::default();
        for k in 0..10_000 {
            // The model's error helping the motor, and small errors against it.
            let along = accel_of([0.8, -0.8], 0.9);
            assert_eq!(m.update(&rule, ML2, &input(along, [0.4, -0.4])), None);
            let small = accel_of([-0.2, 0.12], 0.9);
            assert_eq!(m.update(&rule, ML2, &input(small, [0.1, -0.01])), None, "{k}");
        }
    }

    #[test]
    fn the_check_is_off_at_full_scale_after_touchdown_and_while_a_lifted_tip_descends_to_the_belt() {
        let rule = WiringRule::at_period(1e-3);
        let a = accel_of([-1.0, 0.0], 0.9);
        let trips_after = |m: &mut WiringMonitor, i: &WiringInput| (1..1000).find(|_| m.update(&rule, ML2, i).is_some());
        // At full scale: never.
        let mut m = WiringMonitor::default();
        assert_eq!(trips_after(&mut m, &WiringInput { load_saturated: true, ..input(a, [0.5, 0.0]) }), None);
        // Descending within 5 mm of the belt, lifted: never; rising from it: at once.
        let mut m = WiringMonitor::default();
        let descending = WiringInput { lifted: true, height: 0.002, height_rate: -0.1, ..input(a, [0.5, 0.0]) };
        assert_eq!(trips_after(&mut m, &descending), None);
        let mut m = WiringMonitor::default();
        let rising = WiringInput { lifted: true, height: 0.002, height_rate: 0.1, ..input(a, [0.5, 0.0]) };
        assert!(trips_after(&mut m, &rising).is_some_and(|k| k <= 10));
        // Lifted but at the belt (height at or below 0) for longer than a series of
        // bounces lasts: a load cell that reads no force under a pressing tip. The
        // exemption ends after `impact_series`, the settling time after it.
        let mut m = WiringMonitor::default();
        let at_belt = WiringInput { lifted: true, height: -0.0003, height_rate: -0.17, ..input(a, [0.5, 0.0]) };
        let k = trips_after(&mut m, &at_belt).unwrap();
        let off = usize::from(rule.impact_series) + usize::from(rule.settle);
        assert!(k > off && k <= off + usize::from(rule.confirm) + 2, "tripped {k} periods in, the exemption {off}");
        // A touchdown holds it off for the settling time.
        let mut m = WiringMonitor::default();
        m.update(&rule, ML2, &WiringInput { lifted: true, height: 0.01, height_rate: 0.1, ..input([0.0; 2], [0.0; 2]) });
        let k = trips_after(&mut m, &input(a, [0.5, 0.0])).unwrap();
        assert!(k > usize::from(rule.settle) + usize::from(rule.confirm) - 1, "tripped {k} periods after the touchdown");
    }
}
