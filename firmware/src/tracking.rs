//! The hybrid law's expectations (issues 52 and 66): under the force/motion law
//! the tip stays on the belt and follows `z_t*` along it within a bound derived
//! from the law's own error under the model error the envelope accepts
//! (docs/hardware.md "The envelope"), and a miswired arm breaks one of them
//! within a few periods.
//!
//! **On the belt.** The law commands the normal force `f_n*` (paper eq. 11):
//! below `Z_t,sliding` the tip never leaves the belt (docs/model.md experiment
//! 6). Lift-off declared for [`LIFT_OFF_S`] (2 ms) in a row is therefore a
//! fault: the tip whipped off the belt by a reversed motor, or a load cell that
//! reads no force while the tip presses. Beyond `Z_t,sliding` the law's own
//! bounce (the paradox) trips it too: on a board that is a stop. (10 ms until
//! issue 80: a motor reversed from mid-run throws the moving tip 30 mm in 10 to
//! 15 ms, and 11 of 200 such runs strayed 30 mm before the stop; over the
//! envelope, 2 ms stopped one more healthy draw of 300, one whose unprotected
//! arm lifts off, and stopped 15 others a few periods sooner, as `LiftOff`.)
//!
//! **The healthy error, derived.** In a slide the law (paper eq. 9) leaves the
//! tangential acceleration a disturbance `d` it cannot see: with the friction
//! term `f_t_hat = -mu_u s N` (`mu_u` the coefficient the term uses, `N` its
//! normal force), the belt's constraint and Coulomb's law give (docs/analyses.md
//! "The hybrid law when friction is not known")
//!
//! `d = -s (mu - mu_u) f_n det Q / p_u`, `p_u = Q_22 - mu_u s Q_21`,
//!
//! with `p_u = Q_22` when the term uses the measured `f_n` or no friction (then
//! `mu_u = 0`, the whole `mu` unknown). The envelope accepts `mu_hat` within
//! [`MU_HAT_ERROR`] (25 %) of `mu`, so `|mu - mu_hat| <= mu_hat / 3`, and the
//! firmware bounds `|d|` each period by `D = Delta |f_n| det Q / |p_u|`
//! ([`crate::law::HybridSignals::disturbance`]; `det Q / p_u = l^2 sin^2(theta1 -
//! theta2) / p_det` in the law's scaled terms). The motion loop (paper eq. 10)
//! makes the error `e = z_t* - z_t` obey `e'' + K'_D e' + K'_P e = -d`, so
//! `|e| <= (h * D)` and `|e'| <= (|h'| * D)` for the loop's impulse response `h`.
//! With the loop's poles `a <= b` (real: `s^2 + K'_D s + K'_P`; complex: both
//! taken at their real part `K'_D / 2`, whose `t e^(-a t)` bounds `|h|`),
//! `h = e^(-a t) * e^(-b t)` and `|h'| <= e^(-b t) + a h`: two first-order
//! filters of `D`, `z1' = -b z1 + D`, `z2' = -a z2 + z1`, give the bounds
//! `|e| <= z2` and `|e'| <= z1 + a z2` ([`HealthyBound`]), exactly in
//! continuous time, whatever the move does to `Q`.
//!
//! **The rule.** The error counts when it is past its bound plus the margin
//! [`TRACKING_M`] (5 mm: the sampling, the command's delay and the encoders'
//! quantisation, which leave at most 0.6 mm with `mu_hat` exact), or when it is
//! past the margin and grows faster than the bound on `|e'|` allows: `|e|`
//! stands more than `g + DIVERGING_M` above its own [`AVERAGE_S`] average,
//! `g` the most a signal whose rate stays within `z1 + a z2` can stand above
//! that average (the average's own recursion driven by the rate bound: about
//! `AVERAGE_S (z1 + a z2)` for a steady bound). A miswired arm drives the error away at 0.1 to
//! 4 m/s; a healthy one, with `mu_hat` 25 % off, at most a few cm/s. Past it
//! for [`CONFIRM_S`], the check trips; if the law saturated a motor within the
//! last [`AVERAGE_S`] and the error is past its bound without running away
//! faster than a healthy error can, the law could not act and the reason is
//! saturation ([`Expectation::Saturated`]), not a fault of the wiring (a
//! reversed motor drives the law into its limit within a few periods, its error
//! running away at 0.1 m/s or more: that stays [`Expectation::Tracking`]).
//!
//! A law of one's own that promises no tracking dynamics but holds the tip on
//! the belt ([`crate::Declares::on_belt`]) is stopped at the firmware's first
//! declared lift-off instead (`crate::controller`): without the error's bound
//! the lift-off is its only expectation, and a reversed motor's 2 ms more
//! would carry its tip past 30 mm.
//!
//! The PID (paper eq. 8) lifts off by design from `x0u` (its healthy tip moves
//! 212 mm in the first 0.1 s): there is no such bound for it, and its wiring
//! faults are the wiring check's ([`crate::wiring`]).

/// How long lift-off may stay declared under the hybrid law, s (module docs: why 2 ms).
pub const LIFT_OFF_S: f32 = 0.002;

/// The relative error of `mu_hat` against `mu` the envelope accepts:
/// `|mu_hat - mu| <= MU_HAT_ERROR mu` (docs/hardware.md "The envelope").
pub const MU_HAT_ERROR: f32 = 0.25;

/// `|mu - mu_hat|` per unit `mu_hat` at the envelope's edge:
/// `1 / (1 - MU_HAT_ERROR) - 1` (`mu = mu_hat / 0.75`).
pub const MU_ERROR_PER_MU_HAT: f32 = 1.0 / (1.0 - MU_HAT_ERROR) - 1.0;

/// The largest disturbance bound `D` the filters take, m/s^2: near the
/// Painlevé boundary (`p_u -> 0`) the bound grows without limit; capped, the
/// check keeps no promise there (a 2 m error) and recovers at the loop's slow
/// pole once the arm leaves it.
pub const DISTURBANCE_CAP: f32 = 2.0e4;

/// The margin above the derived bound, m.
pub const TRACKING_M: f32 = 0.005;
/// How long past it trips, s.
pub const CONFIRM_S: f32 = 0.003;
/// How far `|z_t - z_t*|` must stand above its own 50 ms average beyond what
/// the derived rate allows, m: 4 cm/s beyond it.
pub const DIVERGING_M: f32 = 0.002;
/// The average's time constant, s.
pub const AVERAGE_S: f32 = 0.05;

/// The check's state across periods.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrackingMonitor {
    run: u16,
    lifted: u16,
    /// `|z_t - z_t*|` averaged over [`AVERAGE_S`], m.
    average: f32,
    /// The healthy error's bounds.
    bound: HealthyBound,
    /// How far a healthy `|e|` may stand above its average, m: `g_k = (1 -
    /// smoothing) (g_(k-1) + Ts R_k)` for the rate bound `R` over the period
    /// (the average's own recursion, driven by the largest change a period can
    /// bring).
    growth: f32,
    /// Periods left of the window after the law last saturated a motor.
    saturated_recently: u16,
}

/// The two filters of the disturbance bound `D` that bound a healthy arm's
/// tracking error and its rate (module docs): `z1' = -b z1 + D`, m/s, and
/// `z2' = -a z2 + z1`, m; `|e| <= z2`, `|e'| <= z1 + a z2`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct HealthyBound {
    /// `z1`, m/s.
    pub z1: f32,
    /// `z2`, m.
    pub z2: f32,
}

/// What the hybrid law's expectations found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expectation {
    /// `|z_t - z_t*|` past its derived bound for [`CONFIRM_S`].
    Tracking,
    /// Past the derived bound (not running away faster than a healthy error
    /// can) with a motor saturated by the law within the last [`AVERAGE_S`]:
    /// the law could not act (its torque limit), not a fault.
    Saturated,
    /// Lift-off declared for [`LIFT_OFF_S`].
    LiftOff,
    /// Either check tripped with the gains outside the envelope at this rate
    /// ([`TrackingRule::unstable`]): the law's own failure (at 250 Hz the
    /// paper's gains, `K'_D Ts = 3.6`, make the sampled loop bounce).
    Unstable,
}

/// The check in periods of the control rate, for the motion loop's gains.
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
    /// The period `Ts`, s.
    pub period: f32,
    /// The loop's slow pole `a`, 1/s.
    pub slow: f32,
    /// `e^(-a Ts)`, `e^(-b Ts)`: the filters' decay per period.
    pub decay: [f32; 2],
    /// `(1 - e^(-b Ts)) / b`, s: the fast filter's input gain (`z2`'s input
    /// comes through [`TrackingRule::cross`]).
    pub gain: f32,
    /// The cascade's cross terms over a period: `z1`'s share in `z2`,
    /// `int_0^Ts e^(-a (Ts - t)) e^(-b t) dt` (s), and `D`'s,
    /// `(gain_a - that) / b` (s^2): with them the filters are exact for a `D`
    /// held over the period.
    pub cross: [f32; 2],
    /// Periods after a saturated one within which a trip is [`Expectation::Saturated`].
    pub saturation_window: u16,
    /// The gains are outside the envelope at this rate (`K'_D Ts` past
    /// [`crate::config::KD_TS_MAX`], `K'_P Ts^2` past
    /// [`crate::config::KP_TS2_MAX`], `K'_I Ts` past
    /// [`crate::config::KI_TS_MAX`], or `K'_P`, `K'_D` not positive): the sampled loop
    /// need not hold, and every trip is [`Expectation::Unstable`].
    pub unstable: bool,
}

impl TrackingRule {
    /// The check above at a control period of `ts` seconds for the motion
    /// loop's gains `kp` (`K'_P`, 1/s^2) and `kd` (`K'_D`, 1/s), both > 0 in
    /// the envelope (docs/hardware.md), and the force integrator's `ki` (`K'_I`,
    /// 1/s), whose envelope is `K'_I Ts <= 1` ([`TrackingRule::unstable`]). The poles of `s^2 + kd s + kp`:
    /// real, `a <= b`; complex, both at `kd / 2`.
    pub fn at_period(ts: f32, kp: f32, kd: f32, ki: f32) -> Self {
        let disc = kd * kd - 4.0 * kp;
        let (a, b) = if disc > 0.0 {
            let root = libm::sqrtf(disc);
            // The slow pole as kp / b: no cancellation for kd^2 >> 4 kp.
            let b = 0.5 * (kd + root);
            (kp / b, b)
        } else {
            (0.5 * kd, 0.5 * kd)
        };
        let (da, db) = (libm::expf(-a * ts), libm::expf(-b * ts));
        let (ga, gb) = (decay_integral(a, ts), decay_integral(b, ts));
        // int_0^Ts e^(-a (Ts - t)) e^(-b t) dt = e^(-a Ts) int_0^Ts e^(-(b - a) t) dt.
        let c12 = da * decay_integral(b - a, ts);
        // int_0^Ts e^(-a (Ts - t)) (1 - e^(-b t)) / b dt: its closed form
        // `(ga - c12) / b` cancels to a few per cent in `f32` when the poles are
        // slow against the rate, so there its series, `sum_(n >= 2) (-1)^n Ts^n /
        // n! h_(n-2)(a, b)` (`h_j = sum_i a^i b^(j-i)`, `h_j = b h_(j-1) + a^j`):
        // terms fall as `(b Ts)^n`, eight of them within f32's rounding at `b Ts <
        // 0.1`. A few hundred cycles either way: the image derives this rule in its
        // control handler when a configuration comes into force.
        let c2 = if b * ts < 0.1 {
            let (mut h, mut a_pow, mut term, mut sum) = (1.0f32, 1.0f32, ts * ts / 2.0, 0.0f32);
            for n in 2..10 {
                sum += term * h;
                a_pow *= a;
                h = b * h + a_pow;
                term *= -ts / (n + 1) as f32;
            }
            sum
        } else {
            (ga - c12) / b
        };
        let window = crate::runaway::periods_of(AVERAGE_S, ts);
        Self {
            bound: TRACKING_M,
            confirm: crate::runaway::periods_of(CONFIRM_S, ts),
            lift_off: crate::runaway::periods_of(LIFT_OFF_S, ts),
            smoothing: ts / (AVERAGE_S + ts),
            period: ts,
            slow: a,
            decay: [da, db],
            gain: gb,
            cross: [c12, c2],
            saturation_window: window,
            unstable: !(kd * ts <= crate::config::KD_TS_MAX
                && kp * ts * ts <= crate::config::KP_TS2_MAX
                && ki * ts <= crate::config::KI_TS_MAX
                && kp > 0.0
                && kd > 0.0),
        }
    }
}

/// `(1 - e^(-c t)) / c = int_0^t e^(-c s) ds`, s, for `c >= 0` (1/s): by its
/// series where `c t` is small (no cancellation), else by its closed form.
fn decay_integral(c: f32, t: f32) -> f32 {
    let x = c * t;
    if x < 0.05 { t * (1.0 - x / 2.0 * (1.0 - x / 3.0 * (1.0 - x / 4.0 * (1.0 - x / 5.0)))) } else { (1.0 - libm::expf(-x)) / c }
}

impl HealthyBound {
    /// One period of the filters under the disturbance bound `d`, m/s^2 (NaN
    /// and anything past [`DISTURBANCE_CAP`] taken as the cap).
    #[inline(always)]
    pub fn update(&mut self, rule: &TrackingRule, d: f32) {
        let d = if d < DISTURBANCE_CAP { d } else { DISTURBANCE_CAP };
        let z1 = self.z1;
        self.z1 = rule.decay[1] * z1 + rule.gain * d;
        self.z2 = rule.decay[0] * self.z2 + rule.cross[0] * z1 + rule.cross[1] * d;
    }

    /// The bound on a healthy arm's `|e'|`, `z1 + a z2`, m/s.
    #[inline(always)]
    pub fn rate(&self, rule: &TrackingRule) -> f32 {
        self.z1 + rule.slow * self.z2
    }
}

impl TrackingMonitor {
    /// The healthy error's bounds as they stand.
    pub fn healthy_bound(&self) -> HealthyBound {
        self.bound
    }

    /// Folds in one period's tracking error `z_t - z_t*` (m), whether lift-off
    /// is declared, the disturbance bound `D` of the law's last evaluation
    /// (m/s^2, [`crate::law::HybridSignals::disturbance`]) and whether the law
    /// saturated a motor last period. Returns what was found once the error was
    /// past its derived bound plus [`TRACKING_M`], or past [`TRACKING_M`] and
    /// growing faster than the derived rate allows (or not finite), for the
    /// confirmation ([`Expectation::Saturated`] if the law saturated within
    /// [`AVERAGE_S`]), or lift-off held for its time.
    pub fn update(&mut self, rule: &TrackingRule, error: f32, lifted: bool, disturbance: f32, saturated: bool) -> Option<Expectation> {
        let rate_before = self.bound.rate(rule);
        self.bound.update(rule, disturbance);
        let rate_after = self.bound.rate(rule);
        let rate = if rate_after > rate_before { rate_after } else { rate_before };
        self.growth = (1.0 - rule.smoothing) * (self.growth + rule.period * rate);
        let size = error.abs();
        let diverging = size - self.average > self.growth + DIVERGING_M;
        // A select, not a branch: the average moves only for a finite error.
        let average = self.average + rule.smoothing * (size - self.average);
        self.average = if size < f32::INFINITY { average } else { self.average };
        // Not within the derived bound: past it, or NaN (one comparison for both).
        let within = size <= self.bound.z2 + rule.bound;
        let fast = size > rule.bound && diverging;
        let past = !within || fast;
        self.run = if past { self.run.saturating_add(1) } else { 0 };
        self.lifted = if lifted { self.lifted.saturating_add(1) } else { 0 };
        self.saturated_recently = if saturated { rule.saturation_window } else { self.saturated_recently.saturating_sub(1) };
        let found = if self.run >= rule.confirm {
            // Saturated, the law could not hold the tip; but an error that runs away
            // faster than a healthy one can is a fault's, saturated or not (a
            // reversed motor drives the law into its limit within a few periods).
            Some(if self.saturated_recently > 0 && !fast { Expectation::Saturated } else { Expectation::Tracking })
        } else if self.lifted >= rule.lift_off {
            Some(Expectation::LiftOff)
        } else {
            None
        };
        if rule.unstable { found.map(|_| Expectation::Unstable) } else { found }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const PAPER: (f32, f32) = (900.0, 900.0);

    /// The paper's gains where the envelope takes them, else `K'_D Ts = 0.9`.
    fn rule_at(ts: f32) -> TrackingRule {
        let k = PAPER.0.min(0.9 / ts);
        TrackingRule::at_period(ts, k, k, 0.0)
    }

    #[test]
    fn the_poles_are_the_loops_own() {
        // s^2 + 900 s + 900: a = 1.0011, b = 898.999 (a b = kp, a + b = kd).
        let r = TrackingRule::at_period(1e-3, PAPER.0, PAPER.1, 0.0);
        assert!((r.slow - 1.001_114).abs() < 1e-5, "{}", r.slow);
        assert!((r.decay[1] - libm::expf(-0.898_999)).abs() < 1e-5);
        // Complex poles: both at kd / 2.
        let r = TrackingRule::at_period(1e-3, 2500.0, 60.0, 0.0);
        assert_eq!((r.slow, r.decay[0]), (30.0, r.decay[1]));
        // The filters' DC gain: z2 -> D / (a b) = D / kp for a constant D.
        let r = TrackingRule::at_period(1e-3, PAPER.0, PAPER.1, 0.0);
        let mut b = HealthyBound::default();
        for _ in 0..40_000 {
            b.update(&r, 9.0);
        }
        assert!((b.z2 - 0.01).abs() < 1e-5, "{}", b.z2);
        assert!((b.z1 - 9.0 / 898.999).abs() < 1e-6, "{}", b.z1);
    }

    #[test]
    fn the_bound_trips_after_its_confirmation_at_every_rate() {
        for (ts, n) in [(1e-3, 3), (1e-4, 30), (4e-3, 1)] {
            let rule = rule_at(ts);
            assert_eq!(rule.confirm, n, "{ts}");
            let mut m = TrackingMonitor::default();
            for _ in 1..n {
                assert_eq!(m.update(&rule, -0.006, false, 0.0, false), None);
            }
            assert_eq!(m.update(&rule, 0.0051, false, 0.0, false), Some(Expectation::Tracking));
        }
        let rule = TrackingRule::at_period(1e-3, PAPER.0, PAPER.1, 0.0);
        let mut m = TrackingMonitor::default();
        for k in 0..100 {
            assert_eq!(
                m.update(&rule, if k % 3 == 2 { 0.0 } else { 0.01 }, false, 0.0, false),
                None,
                "a period within the bound clears it"
            );
        }
        let mut m = TrackingMonitor::default();
        m.update(&rule, f32::NAN, false, 0.0, false);
        m.update(&rule, f32::NAN, false, 0.0, false);
        assert_eq!(m.update(&rule, f32::NAN, false, 0.0, false), Some(Expectation::Tracking), "a non-finite error is past the bound");
        // A non-finite disturbance bound is the cap, never a NaN bound.
        let mut m = TrackingMonitor::default();
        m.update(&rule, 0.0, false, f32::NAN, false);
        assert!(m.healthy_bound().z2 > 0.0 && m.healthy_bound().z2.is_finite());
    }

    #[test]
    fn a_trip_within_50_ms_of_a_saturated_motor_is_the_laws_saturation() {
        let rule = TrackingRule::at_period(1e-3, PAPER.0, PAPER.1, 0.0);
        let mut m = TrackingMonitor::default();
        // An error that crept past its 5 mm bound (1 mm over 50 ms: not running away).
        let creep = |k: usize| 0.004 + 2e-5 * k as f32;
        for _ in 0..300 {
            assert_eq!(m.update(&rule, 0.004, false, 0.0, false), None);
        }
        for k in 0..50 {
            assert_eq!(m.update(&rule, creep(k), false, 0.0, k == 45), None, "{k}");
        }
        let found = (50..60).find_map(|k| m.update(&rule, creep(k), false, 0.0, false).map(|x| (k, x)));
        assert_eq!(found, Some((53, Expectation::Saturated)), "past 5 mm from k = 51, confirmed over 3 periods");
        // The same error running away at once is a fault's, saturated or not.
        let mut m = TrackingMonitor::default();
        m.update(&rule, 0.0, false, 0.0, true);
        m.update(&rule, 0.1, false, 0.0, true);
        m.update(&rule, 0.1, false, 0.0, true);
        assert_eq!(m.update(&rule, 0.1, false, 0.0, true), Some(Expectation::Tracking));
        let mut m = TrackingMonitor::default();
        m.update(&rule, 0.0, false, 0.0, true);
        for _ in 0..50 {
            m.update(&rule, 0.0, false, 0.0, false);
        }
        m.update(&rule, 0.1, false, 0.0, false);
        m.update(&rule, 0.1, false, 0.0, false);
        assert_eq!(m.update(&rule, 0.1, false, 0.0, false), Some(Expectation::Tracking), "50 ms on");
    }

    /// The loop `e'' + kd e' + kp e = -d(t)` from rest, `d` within `D(t)`
    /// (a random piecewise-constant bound and sign), integrated by RK4 with 20
    /// substeps a period, against the monitor fed `D` each period: returns the
    /// worst `|e| / (z2 + eps)`, `|e'| / (z1 + a z2 + eps)` and whether it tripped.
    fn healthy_loop(kp: f32, kd: f32, ts: f32, pieces: &[(f32, f32, u32)]) -> (f64, f64, bool) {
        let rule = TrackingRule::at_period(ts, kp, kd, 0.0);
        let mut m = TrackingMonitor::default();
        let (kp64, kd64) = (f64::from(kp), f64::from(kd));
        let (mut e, mut v) = (0.0f64, 0.0f64);
        let (mut worst_e, mut worst_v, mut tripped) = (0.0f64, 0.0f64, false);
        for &(bound, sign, periods) in pieces {
            let d = f64::from(bound * sign);
            for _ in 0..periods {
                let h = f64::from(ts) / 20.0;
                let f = |e: f64, v: f64| (v, -d - kd64 * v - kp64 * e);
                for _ in 0..20 {
                    let (k1e, k1v) = f(e, v);
                    let (k2e, k2v) = f(e + 0.5 * h * k1e, v + 0.5 * h * k1v);
                    let (k3e, k3v) = f(e + 0.5 * h * k2e, v + 0.5 * h * k2v);
                    let (k4e, k4v) = f(e + h * k3e, v + h * k3v);
                    e += h / 6.0 * (k1e + 2.0 * k2e + 2.0 * k3e + k4e);
                    v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
                }
                // The bound fed the period's `D` after it acted, as the step does.
                if m.update(&rule, e as f32, false, bound, false).is_some() {
                    tripped = true;
                }
                let b = m.healthy_bound();
                worst_e = worst_e.max(e.abs() / (f64::from(b.z2) + 1e-9));
                worst_v = worst_v.max(v.abs() / (f64::from(b.rate(&rule)) + 1e-9));
            }
        }
        (worst_e, worst_v, tripped)
    }

    #[test]
    fn the_paper_loop_with_mu_hat_a_quarter_off_stays_within_its_derived_bound() {
        // A 25 % `mu_hat` error at f_n = 12 N and det Q / p = 15 1/kg bounds d by
        // 0.2 x 12 x 15 = 36 m/s^2 (40 mm steady): the error stays within the
        // bound and the check never trips, however the disturbance switches.
        let pieces = [(36.0, 1.0, 700), (36.0, -1.0, 400), (20.0, 1.0, 900), (36.0, 1.0, 2000)];
        let (e, v, tripped) = healthy_loop(900.0, 900.0, 1e-3, &pieces);
        assert!(e <= 1.0 + 1e-3 && v <= 1.0 + 1e-3, "{e} {v}");
        assert!(!tripped);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The derived bound holds for any gains of the envelope (real or
        /// complex poles, `kd Ts <= 1`) and any disturbance within `D(t)`:
        /// `|e| <= z2` and `|e'| <= z1 + a z2` to `f32`'s roundings, and
        /// the check never trips on it.
        #[test]
        fn a_healthy_error_never_leaves_its_derived_bound(
            kp_ts2 in 1e-5f32..0.25,
            kd_ts in 5e-3f32..1.0,
            ts_us in 100u32..=4000,
            pieces in prop::collection::vec((0.0f32..60.0, prop::sample::select(vec![-1.0f32, 1.0]), 1u32..600), 1..8),
        ) {
            let ts = ts_us as f32 * 1e-6;
            let (kp, kd) = (kp_ts2 / (ts * ts), kd_ts / ts);
            let (e, v, tripped) = healthy_loop(kp, kd, ts, &pieces);
            prop_assert!(e <= 1.0 + 1e-4 && v <= 1.0 + 1e-4, "{} {}", e, v);
            prop_assert!(!tripped);
        }
    }

    #[test]
    fn a_miswired_arms_error_trips_within_a_few_periods_even_under_a_large_bound() {
        // The bound allowing 30 mm (D = 27 m/s^2 for a second), a fault drives the
        // error away at 0.1 m/s from 5 mm: past 5 mm plus the growth the derived
        // rate allows within 70 ms.
        let rule = TrackingRule::at_period(1e-3, PAPER.0, PAPER.1, 0.0);
        let mut m = TrackingMonitor::default();
        for _ in 0..1000 {
            assert_eq!(m.update(&rule, 0.0, false, 27.0, false), None);
        }
        let tripped = (0..200).position(|k| m.update(&rule, 0.005 + 1e-4 * k as f32, false, 27.0, false).is_some());
        assert!(tripped.is_some_and(|k| k < 70), "{tripped:?}");
    }

    #[test]
    fn outside_the_gain_envelope_every_trip_is_the_laws_instability() {
        // The paper's gains at 250 Hz (K'_D Ts = 3.6), 900 Hz (1.0: inside), a
        // missing gain.
        for (ts, kp, kd, unstable) in
            [(4e-3, 900.0, 900.0, true), (1.0 / 900.0, 900.0, 900.0, false), (1e-3, 0.0, 900.0, true), (1e-3, 900.0, 0.0, true)]
        {
            let rule = TrackingRule::at_period(ts, kp, kd, 0.0);
            assert_eq!(rule.unstable, unstable, "{ts} {kp} {kd}");
            let mut m = TrackingMonitor::default();
            let found = (0..20).find_map(|_| m.update(&rule, 0.1, false, 0.0, false));
            assert_eq!(found, Some(if unstable { Expectation::Unstable } else { Expectation::Tracking }), "{ts} {kp} {kd}");
        }
    }

    #[test]
    fn a_lift_off_of_2_ms_trips_and_a_bounce_shorter_does_not() {
        for (ts, n) in [(1e-3, 2u16), (1e-4, 20), (4e-3, 1)] {
            let rule = rule_at(ts);
            assert_eq!(rule.lift_off, n, "{ts}");
            let mut m = TrackingMonitor::default();
            for _ in 0..20 {
                for _ in 1..n {
                    assert_eq!(m.update(&rule, 0.0, true, 0.0, false), None);
                }
                assert_eq!(m.update(&rule, 0.0, false, 0.0, false), None, "touchdown clears it");
            }
            for _ in 1..n {
                assert_eq!(m.update(&rule, 0.0, true, 0.0, false), None);
            }
            assert_eq!(m.update(&rule, 0.0, true, 0.0, false), Some(Expectation::LiftOff));
        }
    }
}
