//! Running maxima of `theta1_dot` and of the tip height `z_n` over the continuous
//! trajectory (not only at sample times): the paper's persistent-bouncing
//! indicator `max theta1_dot` (docs/model.md experiment 3) and the largest tip height.
//!
//! Every accepted integrator step contributes its two ends. A maximum inside a
//! step shows as a sign change of the component's derivative across the step
//! (`theta1_ddot` from the stages, `z_n_dot = l (sin theta1 theta1_dot + sin
//! theta2 theta2_dot)`, paper eq. 2); it is located on the cubic Hermite
//! interpolant of the step's end values and slopes, and its value is then read
//! from the step's 7th-order dense output at that time. The value error is
//! quadratic in the location error (the slope vanishes there), far below the
//! integrator's tolerance. Two maxima inside one step (a step longer than half an
//! oscillation) would be seen as one; the step-size control keeps steps much
//! shorter than that. Impacts change `theta1_dot` by a jump: the state after the
//! jump is the first point of the next step, so it is counted.

use serde::Serialize;

use plant::{
    Observer,
    dop853::DenseStep,
    segment::{OdeState, STATE_LEN},
};
use shared::ContactMode;

/// The running maxima since tracking started.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Extrema {
    /// Largest `theta1_dot`, rad/s (`-inf` before any point).
    pub theta1_dot_max: f64,
    /// When it occurred, s.
    pub t_theta1_dot_max: f64,
    /// Largest tip normal position `z_n`, m (the belt is at `z_n = -H`).
    pub z_n_max: f64,
    /// When it occurred, s.
    pub t_z_n_max: f64,
    /// Maxima inside steps that were read from the dense output (a cost measure).
    pub interior_refinements: u64,
}

impl Default for Extrema {
    fn default() -> Self {
        Self::new()
    }
}

impl Extrema {
    /// No points seen yet: both maxima at `-inf`.
    pub fn new() -> Self {
        Self {
            theta1_dot_max: f64::NEG_INFINITY,
            t_theta1_dot_max: f64::NAN,
            z_n_max: f64::NEG_INFINITY,
            t_z_n_max: f64::NAN,
            interior_refinements: 0,
        }
    }

    /// Counts the state `y` at time `t` (s); `l` is the link length, m.
    pub fn observe_point(&mut self, t: f64, y: &OdeState, l: f64) {
        self.offer_theta1_dot(t, y[1]);
        self.offer_z_n(t, z_n(y, l));
    }

    fn offer_theta1_dot(&mut self, t: f64, v: f64) {
        if v > self.theta1_dot_max {
            self.theta1_dot_max = v;
            self.t_theta1_dot_max = t;
        }
    }

    fn offer_z_n(&mut self, t: f64, v: f64) {
        if v > self.z_n_max {
            self.z_n_max = v;
            self.t_z_n_max = t;
        }
    }

    /// Counts one accepted step of a smooth segment, up to `t_end` (s, `<=` the
    /// step's end: an event located inside the step ends the trajectory there),
    /// where the state is `y_end`. `l`: link length, m. `flight`: whether the tip
    /// is off the belt in this segment (in contact `z_n = -H`, held by the
    /// constraint, so only its end values are counted).
    pub fn observe_step(&mut self, step: &mut dyn DenseStep<STATE_LEN>, t_end: f64, y_end: &OdeState, l: f64, flight: bool) {
        let (t0, t1) = (step.t_prev(), step.t_curr());
        let (y0, y1) = (*step.y_prev(), *step.y_curr());
        let (f0, f1) = (*step.f_prev(), *step.f_curr());
        self.observe_point(t0, &y0, l);
        self.observe_point(t_end, y_end, l);
        let h = t1 - t0;
        if h <= 0.0 {
            return;
        }
        // theta1_dot: slope theta1_ddot = f[1].
        if f0[1] > 0.0
            && f1[1] < 0.0
            && let Some((s, bound)) = hermite_max(y0[1], y1[1], h * f0[1], h * f1[1])
        {
            let t = t0 + s * h;
            if t < t_end && bound > self.theta1_dot_max {
                self.interior_refinements += 1;
                let (t, v) = refine_max(step, t, (t0, t_end), |y| y[1]);
                self.offer_theta1_dot(t, v);
            }
        }
        if flight {
            let (zd0, zd1) = (z_n_dot(&y0, l), z_n_dot(&y1, l));
            if zd0 > 0.0
                && zd1 < 0.0
                && let Some((s, bound)) = hermite_max(z_n(&y0, l), z_n(&y1, l), h * zd0, h * zd1)
            {
                let t = t0 + s * h;
                if t < t_end && bound > self.z_n_max {
                    self.interior_refinements += 1;
                    let (t, v) = refine_max(step, t, (t0, t_end), |y| z_n(y, l));
                    self.offer_z_n(t, v);
                }
            }
        }
    }
}

/// The running maxima as an [`Observer`] of the plant's advances: it sees every
/// accepted step of the trajectory from its start (`start`) on, and keeps an
/// attempt's observations only when the plant keeps the attempt.
#[derive(Debug, Clone, Copy)]
pub struct ExtremaWatch {
    /// Link length `l`, m (for the tip height).
    l: f64,
    /// The maxima over the kept trajectory.
    kept: Extrema,
    /// The maxima including the current attempt.
    trying: Extrema,
}

impl ExtremaWatch {
    /// Starts tracking at time `t` (s) in plant state `x = [theta1, theta1_dot,
    /// theta2, theta2_dot]` (rad, rad/s), counting that point; `l` is the link length, m.
    pub fn start(t: f64, x: [f64; 4], l: f64) -> Self {
        let mut e = Extrema::new();
        e.observe_point(t, &[x[0], x[1], x[2], x[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], l);
        Self { l, kept: e, trying: e }
    }

    /// The maxima so far.
    pub fn extrema(&self) -> &Extrema {
        &self.kept
    }
}

impl Observer for ExtremaWatch {
    fn on_attempt(&mut self) {
        self.trying = self.kept;
    }

    fn on_step(&mut self, step: &mut dyn DenseStep<STATE_LEN>, stop: Option<(f64, OdeState)>, mode: ContactMode) {
        let (t1, y1) = stop.unwrap_or((step.t_curr(), *step.y_curr()));
        self.trying.observe_step(step, t1, &y1, self.l, mode == ContactMode::Flight);
    }

    fn on_kept(&mut self, _y_end: &OdeState, _mode: ContactMode) {
        self.kept = self.trying;
    }

    fn on_advanced(&mut self, t: f64, y: &OdeState) {
        self.kept.observe_point(t, y, self.l);
        self.trying = self.kept;
    }
}

/// Refines the maximum of `value(y(t))` near `t` (s) on the step's dense output by
/// two Newton steps on its slope, both taken from central differences over
/// `delta = 1e-3 h` (the vertex of the parabola through three points), kept inside
/// `[lo, hi]`; returns the best `(t, value)` seen.
fn refine_max(step: &mut dyn DenseStep<STATE_LEN>, t: f64, (lo, hi): (f64, f64), value: impl Fn(&OdeState) -> f64) -> (f64, f64) {
    let delta = 1e-3 * (step.t_curr() - step.t_prev());
    let mut at = |t: f64| value(&step.interpolate(t));
    let mut best = (t, at(t));
    let mut t = t;
    for _ in 0..2 {
        let (tm, tp) = ((t - delta).max(lo), (t + delta).min(hi));
        if tp - tm <= 0.0 {
            break;
        }
        let (fm, f0, fp) = (at(tm), at(t), at(tp));
        for c in [(tm, fm), (t, f0), (tp, fp)] {
            if c.1 > best.1 {
                best = c;
            }
        }
        // Vertex of the parabola through the three points.
        let (d1, d2) = (t - tm, tp - t);
        let denom = d1 * (fp - f0) + d2 * (fm - f0);
        if denom >= 0.0 {
            break; // not concave here
        }
        let shift = 0.5 * (d1 * d1 * (fp - f0) - d2 * d2 * (fm - f0)) / denom;
        t = (t - shift).clamp(lo, hi);
    }
    let v = at(t);
    if v > best.1 { (t, v) } else { best }
}

/// Tip normal position `z_n = -l (cos theta1 + cos theta2)`, m (docs/model.md).
#[inline]
fn z_n(y: &OdeState, l: f64) -> f64 {
    -l * (y[0].cos() + y[2].cos())
}

/// `z_n_dot = l (sin theta1 theta1_dot + sin theta2 theta2_dot)`, m/s.
#[inline]
fn z_n_dot(y: &OdeState, l: f64) -> f64 {
    l * (y[0].sin() * y[1] + y[2].sin() * y[3])
}

/// The maximum inside `(0, 1)` of the cubic Hermite interpolant with end values
/// `v0`, `v1` and end slopes (per unit `s`) `m0 > 0 > m1`: its location `s` and a
/// safe upper bound on the true maximum (the interpolant's value plus its rise above
/// the ends again, a generous allowance for the interpolant's error), used to skip
/// the dense output when the step cannot hold a new maximum.
fn hermite_max(v0: f64, v1: f64, m0: f64, m1: f64) -> Option<(f64, f64)> {
    // p'(s) = a s^2 + b s + c.
    let a = 6.0 * (v0 - v1) + 3.0 * (m0 + m1);
    let b = 6.0 * (v1 - v0) - 4.0 * m0 - 2.0 * m1;
    let c = m0;
    let s = if a.abs() <= 1e-12 * (b.abs() + c.abs()) {
        -c / b
    } else {
        let disc = (b * b - 4.0 * a * c).max(0.0);
        // p'(0) > 0 > p'(1): exactly one root in (0, 1); take the one there.
        let sq = disc.sqrt();
        let q = -0.5 * (b + b.signum() * sq);
        let (r1, r2) = (q / a, if q != 0.0 { c / q } else { f64::NAN });
        if (0.0..=1.0).contains(&r1) { r1 } else { r2 }
    };
    if !(s.is_finite() && (0.0..=1.0).contains(&s)) {
        return None;
    }
    let p = (2.0 * s.powi(3) - 3.0 * s * s + 1.0) * v0
        + (s.powi(3) - 2.0 * s * s + s) * m0
        + (-2.0 * s.powi(3) + 3.0 * s * s) * v1
        + (s.powi(3) - s * s) * m1;
    let rise = (p - v0.max(v1)).max(0.0);
    Some((s, p + rise + 1e-12 * p.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use plant::{
        Hold, NoObserver, Plant, SimConfig,
        initial::{X0A, deg_to_state},
    };
    use shared::Params;

    #[test]
    fn hermite_max_of_a_parabola_is_exact() {
        // v(s) = 1 - (s - 0.3)^2: v0 = 0.91, v1 = 0.51, slopes 0.6 and -1.4; the cubic
        // Hermite interpolant of a parabola is the parabola.
        let (s, bound) = hermite_max(0.91, 0.51, 0.6, -1.4).unwrap();
        assert!((s - 0.3).abs() < 1e-12, "{s}");
        assert!((1.0..1.1).contains(&bound), "{bound}");
    }

    #[test]
    fn hermite_max_of_a_sine_is_close() {
        // sin over [0.5, 2.5]: maximum 1 at pi/2.
        let (t0, t1) = (0.5f64, 2.5f64);
        let h = t1 - t0;
        let (s, _) = hermite_max(t0.sin(), t1.sin(), h * t0.cos(), h * t1.cos()).unwrap();
        let t = t0 + s * h;
        assert!((t - std::f64::consts::FRAC_PI_2).abs() < 0.05, "{t}");
        // The value at the located time is within the square of the location error.
        assert!(1.0 - t.sin() < 2e-3);
    }

    /// The maxima tracked inside the integrator's own steps agree with the maxima of a
    /// trace of the same motion sampled every 10 us (two independent paths), and are
    /// never below them. The window is short (bouncing is chaotic: over seconds the
    /// two runs' different step sequences would part).
    #[test]
    fn tracked_maxima_match_a_fine_sampling() {
        let params = Params::new(0.7, -0.5).unwrap();
        let mut fine = Plant::new(params, SimConfig::default(), deg_to_state(X0A.deg), 0.0, [0.0, 0.0]).unwrap();
        fine.advance(&Hold([0.0, 0.0]), 5.2, &mut NoObserver).unwrap();
        let mut coarse = fine.clone();
        let mut watch = ExtremaWatch::start(coarse.time(), coarse.state(), params.l);
        coarse.advance(&Hold([0.0, 0.0]), 1.0, &mut watch).unwrap();
        let (mut th1d_max, mut z_n_max) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for _ in 0..100_000 {
            fine.advance(&Hold([0.0, 0.0]), 1e-5, &mut NoObserver).unwrap();
            th1d_max = th1d_max.max(fine.state()[1]);
            z_n_max = z_n_max.max(fine.tip()[1]);
        }
        let e = *watch.extrema();
        let gap = coarse.state().iter().zip(fine.state()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(gap < 1e-5, "same motion: {gap}");
        assert!(coarse.counters().touchdowns > 0, "this case bounces");
        assert!(e.t_z_n_max > 5.2 && e.t_z_n_max < 6.2 && e.z_n_max > -params.h + 1e-3, "an apex inside the window: {e:?}");
        // Sampling misses up to |theta1_ddot| dt after an impact's jump, the curvature
        // times (dt/2)^2 at a smooth apex.
        // The two runs' states agree to ~1e-7 (their steps differ), which bounds how far
        // the sampled maxima may exceed the tracked ones.
        assert!(e.theta1_dot_max >= th1d_max - 1e-6 && e.theta1_dot_max - th1d_max < 1e-3, "{} vs {th1d_max}", e.theta1_dot_max);
        assert!(e.z_n_max >= z_n_max - 1e-8 && e.z_n_max - z_n_max < 1e-7, "{} vs {z_n_max}", e.z_n_max);
        assert!(e.interior_refinements > 0);
    }
}
