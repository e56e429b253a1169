//! Joint-angle and joint-velocity estimation from quantised absolute encoders.
//!
//! Each angle has a critically damped alpha-beta tracker (a steady-state
//! two-state observer `x' = v`, `v' = 0`; Kalata 1984, "The tracking index"),
//! with `r = exp(-w Ts)`, `alpha = 1 - r^2`, `beta = (1 - r)^2`: both observer
//! poles at `r`, i.e. bandwidth `w` (rad/s). It tracks a constant velocity with
//! no lag; for a signal of bandwidth well below `w` its velocity estimate lags by
//! about `2 / w` (8 ms at the default 40 Hz). The 14-bit quantisation
//! (0.38 mrad, `q / sqrt(12)` = 0.11 mrad rms) then gives a velocity noise of a
//! few hundredths of a rad/s instead of the 0.38 rad/s of a raw difference.
//!
//! The firmware drives the prediction with the model's joint acceleration
//! (`M^-1 (u - w - c + J^T f)` with the torque it commanded and the forces it
//! measured): the estimate then follows the motion the model explains with no
//! lag, and the observer only corrects what the model misses.

use nalgebra::Vector2;
use shared::{kinematics::JointTrig, model::ArmTerms};

use crate::decode::wrap;

/// The joint accelerations the model predicts, rad/s^2 (paper eq. 1):
/// `q_ddot = M^-1 (u - w - c + J^T f)` at the angles whose sines and cosines are
/// `trig` (rad, `q` themselves for the spring), rates `qd` (rad/s), generalised
/// torques `u = [u1 - u2, u2]` (N m) and tip forces `f = [f_t, f_n]` (N), with the
/// arm's folded factors `t`: what the observer's prediction is driven by.
///
/// The value of [`ArmTerms::tip_dynamics_trig`]`(..).qdd_with_force(f)` within a
/// few `f32` roundings (test below), with one division where that takes three:
/// `M^-1 = adj(M) / det M` with one reciprocal of `det M` (at least
/// `7/36 m^2 l^4 > 0`, so `M` is never singular), and `u - w - c + J^T f` summed
/// before the one product by `M^-1` (that function keeps the free acceleration
/// and the force's part apart, for the plant's contact modes).
///
/// Also returns the generalised torque that drives it, `M q_ddot = u - w - c +
/// J^T f` (N m): the net torque the model expects to accelerate the joints (the
/// wiring check's second reference, [`crate::wiring`]).
#[inline(always)]
pub fn predicted_acceleration(
    t: &ArmTerms<f32>,
    trig: &JointTrig<f32>,
    q: &Vector2<f32>,
    qd: &Vector2<f32>,
    u: &Vector2<f32>,
    f: &Vector2<f32>,
) -> (Vector2<f32>, [f32; 2]) {
    let l = t.l;
    let JointTrig { s1, c1, s2, c2 } = *trig;
    let s12 = trig.s12(); // sin(theta1 - theta2)
    let m12 = t.half_ml2 * trig.c21();
    let inv_det = 1.0 / (t.m11_m22 - m12 * m12);
    // w + c (paper eq. 1), as ArmTerms::tip_dynamics_trig writes them.
    let spring = t.k * (q[1] - q[0] + t.alpha0);
    let (w1, w2) = (qd[0] * qd[0], qd[1] * qd[1]);
    let wc0 = t.mgl2_3 * s1 - spring - t.sigma * (qd[1] - qd[0] - qd[0]) + t.half_ml2 * w2 * s12;
    let wc1 = t.mgl2 * s2 + spring + t.sigma * (qd[1] - qd[0]) - t.half_ml2 * w1 * s12;
    // J^T f with J = [[l c1, l c2], [l s1, l s2]].
    let v0 = (u[0] - wc0) + (l * c1 * f[0] + l * s1 * f[1]);
    let v1 = (u[1] - wc1) + (l * c2 * f[0] + l * s2 * f[1]);
    (Vector2::new((t.m22 * v0 - m12 * v1) * inv_det, (t.m11 * v1 - m12 * v0) * inv_det), [v0, v1])
}

/// An alpha-beta tracker of one angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleTracker {
    /// Estimated angle, rad (unwrapped: continuous across +-pi).
    pub angle: f32,
    /// Estimated angular velocity, rad/s.
    pub rate: f32,
    alpha: f32,
    beta_over_ts: f32,
}

impl AngleTracker {
    /// A tracker at `angle` (rad), at rest, with bandwidth `w` (rad/s) and period `ts` (s).
    pub fn new(angle: f32, w: f32, ts: f32) -> Self {
        let r = libm::expf(-w * ts);
        Self { angle, rate: 0.0, alpha: 1.0 - r * r, beta_over_ts: (1.0 - r) * (1.0 - r) / ts }
    }

    /// A tracker with this one's gains, at `angle` (rad) and at rest: the same as
    /// [`AngleTracker::new`] with this one's bandwidth and period, without its `expf`.
    pub fn restarted_at(&self, angle: f32) -> Self {
        Self { angle, rate: 0.0, ..*self }
    }

    /// Folds in measurement `measured` (rad, any turn) taken `dt` s after the
    /// previous one; returns the innovation (measured minus predicted angle, rad).
    pub fn update(&mut self, measured: f32, dt: f32) -> f32 {
        self.update_with_acceleration(measured, dt, 0.0)
    }

    /// As [`AngleTracker::update`], with the prediction driven by a known angular
    /// acceleration `accel` (rad/s^2) over the interval: a model-based observer,
    /// whose estimate does not lag the motion the model explains. Returns the
    /// innovation (measured minus predicted angle, wrapped to one turn, rad).
    // Inlined: the step calls it twice, and the call's register saves cost as much as its body.
    #[inline(always)]
    pub fn update_with_acceleration(&mut self, measured: f32, dt: f32, accel: f32) -> f32 {
        let predicted = self.angle + self.rate * dt + 0.5 * accel * dt * dt;
        self.rate += accel * dt;
        // The residual is taken modulo one turn, so the estimate stays continuous.
        let residual = wrap(measured - predicted);
        self.angle = predicted + self.alpha * residual;
        self.rate += self.beta_over_ts * residual;
        residual
    }

    /// The rate correction an innovation `residual` (rad) made, rad/s: the
    /// velocity change over the interval that the model's acceleration did not
    /// explain (divided by the interval, the unexplained acceleration;
    /// [`crate::wiring`]).
    pub fn rate_correction(&self, residual: f32) -> f32 {
        self.beta_over_ts * residual
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use shared::{Arm, Params};

    proptest! {
        /// The prediction (one reciprocal of `det M`, the force's part summed in)
        /// against the model's own (`ArmTerms::tip_dynamics_trig`: three divisions,
        /// the free acceleration and the force's part apart) and against the model in
        /// `f64` at the same inputs: within 1e-6 of the magnitude of the terms,
        /// `sum_j |M^-1_ij| |v_j|` with `v = u - w - c + J^T f` term by term (a dozen
        /// `f32` roundings of 6e-8 each, `M^-1` well conditioned: `det M >= 7/36 m^2 l^4`),
        /// over the arm's range of states, torques and forces.
        #[test]
        fn the_prediction_is_the_models_acceleration(
            q0 in -7.0f32..7.0, q1 in -7.0f32..7.0, qd0 in -30.0f32..30.0, qd1 in -30.0f32..30.0,
            u0 in -10.0f32..10.0, u1 in -5.0f32..5.0, f_t in -25.0f32..25.0, f_n in -25.0f32..25.0,
        ) {
            let params = crate::config::Config::default().params;
            let terms = ArmTerms::of(&params);
            let (q, qd, u, f) = (Vector2::new(q0, q1), Vector2::new(qd0, qd1), Vector2::new(u0, u1), Vector2::new(f_t, f_n));
            let trig = JointTrig::new(&q);
            let ours = predicted_acceleration(&terms, &trig, &q, &qd, &u, &f).0;
            let model = terms.tip_dynamics_trig(&trig, &q, &qd, &u).qdd_with_force(&f);
            // f64 at the same f32 sines and cosines (their error is the same in both f32 forms).
            let p64: Params<f64> = params.cast();
            let arm = Arm::new(p64);
            let (q64, qd64) = (Vector2::new(q0 as f64, q1 as f64), Vector2::new(qd0 as f64, qd1 as f64));
            let t64 = JointTrig { s1: trig.s1 as f64, c1: trig.c1 as f64, s2: trig.s2 as f64, c2: trig.c2 as f64 };
            let td = arm.tip_dynamics_trig(&t64, &q64, &qd64, &Vector2::new(u0 as f64, u1 as f64));
            let exact = td.qdd_with_force(&Vector2::new(f_t as f64, f_n as f64));
            let wc = arm.w(&q64, &qd64) + arm.c(&q64, &qd64);
            let jtf = td.jac.transpose() * Vector2::new(f_t as f64, f_n as f64);
            for i in 0..2 {
                let scale: f64 = (0..2).map(|j| td.m_inv[(i, j)].abs() * ([u0, u1][j].abs() as f64 + wc[j].abs() + jtf[j].abs())).sum();
                prop_assert!((ours[i] as f64 - exact[i]).abs() <= 1e-6 * scale, "qdd[{}] = {} against {} (scale {:e})", i, ours[i], exact[i], scale);
                prop_assert!((ours[i] - model[i]).abs() as f64 <= 2e-6 * scale, "qdd[{}] = {} against the model's {}", i, ours[i], model[i]);
            }
        }
    }

    #[test]
    fn tracks_a_ramp_without_lag_and_across_the_wrap() {
        let ts = 1e-3;
        let mut t = AngleTracker::new(3.0, 2.0 * core::f32::consts::PI * 40.0, ts);
        for k in 1..2000 {
            let truth = 3.0 + 0.8 * k as f32 * ts;
            // Quantise like the encoder.
            let q = core::f32::consts::TAU / 16384.0;
            let measured = wrap(libm::roundf(truth / q) * q);
            t.update(measured, ts);
        }
        assert!((t.rate - 0.8).abs() < 0.02, "rate {}", t.rate);
        assert!((t.angle - (3.0 + 0.8 * 1.999)).abs() < 1e-3, "angle {} continuous past pi", t.angle);
    }
}
