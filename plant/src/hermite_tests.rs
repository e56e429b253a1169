use proptest::prelude::*;

use super::sample;
use crate::{
    dop853::{Control, DenseStep, Dop853, OdeSystem, State},
    segment::{OdeState, STATE_LEN},
};

/// A step with given ends, no dense output of its own.
struct Ends {
    t: (f64, f64),
    y: (OdeState, OdeState),
    f: (OdeState, OdeState),
}

impl DenseStep<STATE_LEN> for Ends {
    fn t_prev(&self) -> f64 {
        self.t.0
    }
    fn t_curr(&self) -> f64 {
        self.t.1
    }
    fn y_prev(&self) -> &OdeState {
        &self.y.0
    }
    fn y_curr(&self) -> &OdeState {
        &self.y.1
    }
    fn f_prev(&self) -> &OdeState {
        &self.f.0
    }
    fn f_curr(&self) -> &OdeState {
        &self.f.1
    }
    fn interpolate(&mut self, _t: f64) -> OdeState {
        unreachable!("the Hermite sample needs no dense output")
    }
}

/// `p(t) = sum c_j t^j`, its first and second derivatives.
fn poly(c: &[f64], t: f64) -> (f64, f64, f64) {
    let mut v = (0.0, 0.0, 0.0);
    for (j, cj) in c.iter().enumerate() {
        let j = j as i32;
        v.0 += cj * t.powi(j);
        if j >= 1 {
            v.1 += cj * f64::from(j) * t.powi(j - 1);
        }
        if j >= 2 {
            v.2 += cj * f64::from(j * (j - 1)) * t.powi(j - 2);
        }
    }
    v
}

/// The state of angles following quintics `q1`, `q2` and other components cubics `r`.
fn state_of(q1: &[f64], q2: &[f64], r: &[f64], t: f64) -> (OdeState, OdeState) {
    let (mut y, mut f) = ([0.0; STATE_LEN], [0.0; STATE_LEN]);
    for (p, q) in [(0, q1), (2, q2)] {
        let (x, v, a) = poly(q, t);
        (y[p], y[p + 1], f[p], f[p + 1]) = (x, v, v, a);
    }
    for i in 4..STATE_LEN {
        let c = [r[0] * i as f64, r[1], r[2], r[3] / i as f64];
        let (x, v, _) = poly(&c, t);
        (y[i], f[i]) = (x, v);
    }
    (y, f)
}

proptest! {
    /// The interpolant reproduces quintic angles (with their rates) and cubic other
    /// components to rounding, anywhere in the step.
    #[test]
    fn exact_on_quintic_angles_and_cubic_components(
        q1 in prop::collection::vec(-2.0..2.0f64, 6),
        q2 in prop::collection::vec(-2.0..2.0f64, 6),
        r in prop::collection::vec(-2.0..2.0f64, 4),
        t0 in -1.0..1.0f64,
        h in 1e-3..1.0f64,
        s in 0.0..=1.0f64,
    ) {
        let t1 = t0 + h;
        let ((y0, f0), (y1, f1)) = (state_of(&q1, &q2, &r, t0), state_of(&q1, &q2, &r, t1));
        let step = Ends { t: (t0, t1), y: (y0, y1), f: (f0, f1) };
        let t = t0 + s * h;
        let (want, _) = state_of(&q1, &q2, &r, t);
        let got = sample(&step, t);
        for i in 0..STATE_LEN {
            // Rounding of a sum of terms of size up to about 100 (t^5 at |t| = 2, scaled).
            prop_assert!((got[i] - want[i]).abs() <= 1e-11 * (1.0 + want[i].abs()), "{i}: {} against {}", got[i], want[i]);
        }
    }
}

/// Damped oscillators `theta'' = -w^2 theta - 2 z w theta'` (underdamped, `z < 1`),
/// exactly: `theta = a e^(-z w t) cos(w_d t + phi)`, `w_d = w sqrt(1 - z^2)`; the
/// other components carry `i theta_1` with derivative `i theta_1'`.
struct Oscillators {
    w: [f64; 2],
    z: f64,
    a: [f64; 2],
    phi: [f64; 2],
}

impl Oscillators {
    /// `(theta, theta', theta'')` of oscillator `j` at `t`.
    fn exact(&self, j: usize, t: f64) -> (f64, f64, f64) {
        let (w, z) = (self.w[j], self.z);
        let (sigma, wd) = (z * w, w * (1.0 - z * z).sqrt());
        let e = self.a[j] * (-sigma * t).exp();
        let (s, c) = (wd * t + self.phi[j]).sin_cos();
        let x = e * c;
        let v = e * (-sigma * c - wd * s);
        (x, v, -w * w * x - 2.0 * z * w * v)
    }

    fn state(&self, t: f64) -> (OdeState, OdeState) {
        let (mut y, mut f) = ([0.0; STATE_LEN], [0.0; STATE_LEN]);
        for (j, p) in [0, 2].into_iter().enumerate() {
            let (x, v, a) = self.exact(j, t);
            (y[p], y[p + 1], f[p], f[p + 1]) = (x, v, v, a);
        }
        for i in 4..STATE_LEN {
            (y[i], f[i]) = (i as f64 * y[0], i as f64 * y[1]);
        }
        (y, f)
    }

    /// The Hermite sample's largest error per component over `[t0, t0 + span]` in
    /// steps of `h`, at nine fractions of each step.
    fn error(&self, t0: f64, span: f64, h: f64) -> [f64; STATE_LEN] {
        let mut worst = [0.0f64; STATE_LEN];
        let steps = (span / h).round() as usize;
        for k in 0..steps {
            let ta = t0 + k as f64 * h;
            let ((y0, f0), (y1, f1)) = (self.state(ta), self.state(ta + h));
            let step = Ends { t: (ta, ta + h), y: (y0, y1), f: (f0, f1) };
            for j in 1..10 {
                let t = ta + 0.1 * j as f64 * h;
                let (want, _) = self.state(t);
                let got = sample(&step, t);
                for i in 0..STATE_LEN {
                    worst[i] = worst[i].max((got[i] - want[i]).abs());
                }
            }
        }
        worst
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Convergence under refinement against the exact solution, in the largest
    /// error over one period of the slower oscillator: halving the step divides the
    /// angles' error by 2^6, the rates' by 2^5 and the other components' by 2^4 (the
    /// interpolants' orders); required at least half of each, from steps of 0.1 / w,
    /// wherever the coarse error is well above rounding. The exact solution's own
    /// rounding is about `eps a (1 + w t)` in an angle (the phase `w t` rounded), and
    /// the rate's interpolant divides the angles' difference by the step, so its floor
    /// is that times `4 / h` at the fine step: an error is checked only when it is at
    /// least 64 times its floor (then the floor can halve the ratio at most), and
    /// above 1e-10.
    #[test]
    fn converges_at_its_orders(
        w1 in 1.0..100.0f64,
        w2 in 1.0..100.0f64,
        z in 0.0..0.9f64,
        a in prop::collection::vec(0.1..1.5f64, 2),
        phi in prop::collection::vec(0.0..6.3f64, 2),
        t0 in 0.0..1.0f64,
    ) {
        let osc = Oscillators { w: [w1, w2], z, a: [a[0], a[1]], phi: [phi[0], phi[1]] };
        let h = 0.1 / w1.max(w2);
        let span = h * (std::f64::consts::TAU / w1.min(w2) / h).ceil();
        let (coarse, fine) = (osc.error(t0, span, h), osc.error(t0, span, h / 2.0));
        let t_end = t0 + span + h;
        let angle_floor = |j: usize| 4.0 * f64::EPSILON * osc.a[j] * (1.0 + osc.w[j] * t_end);
        for (i, order) in [(0, 5), (2, 5), (1, 4), (3, 4), (4, 3), (9, 3)] {
            let floor = match i {
                0 | 2 => angle_floor(i / 2),
                1 | 3 => angle_floor(i / 2) * 4.0 / (h / 2.0),
                _ => i as f64 * angle_floor(0),
            };
            if coarse[i] > 1e-10 && coarse[i] > 64.0 * floor {
                let ratio = coarse[i] / fine[i];
                prop_assert!(ratio >= f64::from(1 << order), "component {i}: error {:e} then {:e}, ratio {ratio}", coarse[i], fine[i]);
            }
        }
    }
}

/// Two pendulums in the plant's layout (`theta_i'' = -w_i^2 sin theta_i - c
/// theta_i'`), the other components integrating `theta_1'^2`.
struct Pendulums {
    w: [f64; 2],
    c: f64,
}

impl OdeSystem<STATE_LEN> for Pendulums {
    fn rhs(&self, _t: f64, y: &State<STATE_LEN>, dy: &mut State<STATE_LEN>) {
        for (j, p) in [0, 2].into_iter().enumerate() {
            dy[p] = y[p + 1];
            dy[p + 1] = -self.w[j] * self.w[j] * y[p].sin() - self.c * y[p + 1];
        }
        for (i, d) in dy.iter_mut().enumerate().skip(4) {
            *d = y[1] * y[1] / i as f64;
        }
    }
    const NORM_LEN: usize = 4;
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// On the 1 ms steps of a real solve (the SIL loop's period) with the sample at
    /// 0.8 of the step (`t_k` between the zero-order hold's switches at 0.2 ms), the
    /// sample agrees with DOP853's 7th-order dense output, an independent
    /// interpolant of the same step: angles within 1e-11 rad and rates within 1e-7
    /// rad/s on pendulums up to 60 rad/s swinging up to 1.5 rad (the errors scale as
    /// `(h w)^6` and `w (h w)^5`; measured up to 1.3e-12 rad and 1.5e-8 rad/s).
    #[test]
    fn agrees_with_the_dense_output_at_1_ms(
        w1 in 5.0..60.0f64,
        w2 in 5.0..60.0f64,
        c in 0.0..5.0f64,
        q in prop::collection::vec(-1.5..1.5f64, 4),
    ) {
        let sys = Pendulums { w: [w1, w2], c };
        let mut y0 = [0.0; STATE_LEN];
        y0[..4].copy_from_slice(&q);
        let h = 1e-3;
        let solver = Dop853 { h_max: h, ..Dop853::new(1e-9, 1e-11) };
        let mut worst = [0.0f64; STATE_LEN];
        solver
            .solve(&sys, 0.0, &y0, None, 0.1, h, |step| {
                let t = step.t_prev() + 0.8 * (step.t_curr() - step.t_prev());
                let (hermite, dense) = (sample(&*step, t), step.interpolate(t));
                for i in 0..STATE_LEN {
                    worst[i] = worst[i].max((hermite[i] - dense[i]).abs());
                }
                Control::Continue
            })
            .unwrap();
        prop_assert!(worst[0] < 1e-11 && worst[2] < 1e-11, "angles {worst:?}");
        prop_assert!(worst[1] < 1e-7 && worst[3] < 1e-7, "rates {worst:?}");
    }
}
