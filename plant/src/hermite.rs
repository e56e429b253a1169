//! The plant's state inside an accepted step from the step's ends alone: a
//! Hermite interpolant of the second-order system `theta'' = a(theta, theta_dot)`,
//! with no model evaluation (issue 56).
//!
//! DOP853's own dense output ([`DenseStep::interpolate`]) is of order 7 but needs
//! three extra stages, a sixth of the model evaluations of the SIL loop's period.
//! The ends of a step already hold, for each joint angle `theta` (state components
//! 0 and 2), `theta`, `theta' = theta_dot` (components 1 and 3) and
//! `theta'' = f[1], f[3]` (the FSAL stage at the end, the first stage at the start):
//! the six conditions of the quintic Hermite interpolant `P` of `theta` on
//! `[t0, t1]`. The angle is `P(t)`, its rate `P'(t)`; their errors are
//! `theta^(6) (t - t0)^3 (t - t1)^3 / 720` and its derivative, `O(h^6)` and `O(h^5)`
//! (Hairer, Nørsett, Wanner I, II.6, on Hermite interpolation). The other
//! components (the controller's states and the ledger's works) take the cubic
//! Hermite interpolant of their values and derivatives, `O(h^4)`.
//!
//! The accuracy contract (docs/architecture.md) holds the samples read this way:
//! `tests/e2e/accuracy.rs`, and the test of this module against the
//! 7th-order dense output over random steps.

use crate::{
    dop853::DenseStep,
    segment::{OdeState, STATE_LEN},
};

/// The state at `t` (s, within `[t_prev, t_curr]` of `step`) from the step's ends:
/// angles (components 0 and 2) and rates (1 and 3) from the quintic Hermite
/// interpolant of each angle, every other component from the cubic Hermite
/// interpolant of its values and derivatives (module docs). Units as the state's
/// (rad, rad/s, the controller's states, J). A step of zero length gives its start.
#[inline]
pub fn sample<S: DenseStep<STATE_LEN> + ?Sized>(step: &S, t: f64) -> OdeState {
    let (t0, t1) = (step.t_prev(), step.t_curr());
    let (y0, y1, f0, f1) = (step.y_prev(), step.y_curr(), step.f_prev(), step.f_curr());
    let h = t1 - t0;
    if h <= 0.0 {
        return *y0;
    }
    let s = (t - t0) / h;
    let (s2, s3) = (s * s, s * s * s);
    let (s4, s5) = (s3 * s, s3 * s2);
    // Quintic basis (for `P` = p0 + (p1 - p0) e + h v0 a + h^2 a0 b + h v1 c + h^2 a1 d).
    let e = 10.0 * s3 - 15.0 * s4 + 6.0 * s5;
    let a = s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5;
    let b = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5;
    let c = -4.0 * s3 + 7.0 * s4 - 3.0 * s5;
    let d = 0.5 * s3 - s4 + 0.5 * s5;
    // Their derivatives in s.
    let de = 30.0 * s2 * (1.0 - s) * (1.0 - s);
    let da = 1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4;
    let db = s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4;
    let dc = -12.0 * s2 + 28.0 * s3 - 15.0 * s4;
    let dd = 1.5 * s2 - 4.0 * s3 + 2.5 * s4;
    let mut y = [0.0; STATE_LEN];
    for (p, v) in [(0, 1), (2, 3)] {
        let dp = y1[p] - y0[p];
        let (v0, v1, a0, a1) = (y0[v], y1[v], f0[v], f1[v]);
        y[p] = y0[p] + (dp * e + h * (v0 * a + v1 * c) + h * h * (a0 * b + a1 * d));
        y[v] = dp / h * de + v0 * da + v1 * dc + h * (a0 * db + a1 * dd);
    }
    // Cubic Hermite for the rest.
    let hc = 3.0 * s2 - 2.0 * s3;
    let h1 = s - 2.0 * s2 + s3;
    let h2 = s3 - s2;
    for i in 4..STATE_LEN {
        y[i] = y0[i] + ((y1[i] - y0[i]) * hc + h * (f0[i] * h1 + f1[i] * h2));
    }
    y
}

#[cfg(test)]
#[path = "hermite_tests.rs"]
mod tests;
