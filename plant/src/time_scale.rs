//! The arm's fastest time scale, and the step cap of a densely sampled run taken
//! from it (issue 67: "steps set by the arm's dynamics").
//!
//! Linearised about any configuration, paper eq. 1 with `u = 0` and no contact
//! reads `M(q) dq_ddot + C dq_dot + K(q) dq = 0`, with
//! - `K = d(w)/dq = [[3 m g l/2 cos theta1 + k, -k], [-k, m g l/2 cos theta2 + k]]`
//!   (gravity and the spring; N m/rad),
//! - `C = d(w)/dq_dot = [[2 sigma, -sigma], [-sigma, sigma]]` (the joint damping; N m s/rad),
//! - `M` the mass matrix (kg m^2), which depends on `cos(theta2 - theta1)` only.
//!
//! The generalised eigenvalues `lambda` of `(K, M)` are real (`M` is symmetric
//! positive definite): `sqrt|lambda|` is a natural frequency (rad/s) where
//! `lambda > 0`, a growth rate (1/s) where gravity makes it negative. Those of
//! `(C, M)` are decay rates (1/s). The largest of all of them over every
//! configuration is the arm's fastest rate, [`fastest_rate`]. The centripetal
//! terms (rates of order `|theta_dot|`) are left to the integrator's error
//! control; so are the contact's constraints, whose frequencies lie within the
//! free arm's for a frictionless contact (Rayleigh's interlacing theorem).
//!
//! The paper's arm (MODEL.md Table I): 60.1 rad/s (a period of 0.105 s). The
//! short, light arm of issue 67 (`m` 0.02 kg, `l` 0.06 m, `k` 1.5 N m/rad,
//! `sigma` 3e-4 N m s/rad): 535 rad/s (11.7 ms).

use shared::Params;

/// The step cap of a densely sampled run of the paper's arm, s: issue 53's 2 ms,
/// measured against the accuracy contract (docs/architecture.md "The accuracy
/// contract"): 0.12 rad of its fastest mode. Another arm's cap is this one scaled
/// by the ratio of the fastest rates ([`dense_max_step`]), so the paper's arm keeps
/// exactly 2 ms (its outputs bit for bit).
///
/// Measured (issue 67): on the paper's arm, at 4.16 ms (0.25 rad) the 300 s
/// bouncing leaves the contract (3e-6 rad in `theta1`, eight times a thousandth
/// of the encoder's quantum), and even 1.996 ms (the same angle rounded) moves the
/// bouncing from `x0a` past 1000 tolerances near its predictability horizon at
/// 1.6 s, where any other step sequence may; on issue 67's short arm the scaled
/// cap is 0.22 ms, where 0.5 ms (0.27 rad) still keeps the contract for 5 s and
/// 0.7 ms (0.37 rad) leaves it at 0.83 s.
pub const PAPER_ARM_MAX_STEP: f64 = 2e-3;

/// Values of `cos(theta2 - theta1)` on `[-1, 1]` at which [`fastest_rate`]
/// evaluates the mass matrix (the gravity terms take their extremes at
/// `cos theta1, cos theta2 = +-1`, where the bound is exact).
const COS_GRID: usize = 201;

/// The arm's fastest rate, 1/s (rad/s for an oscillation): the largest of the
/// natural frequencies, growth rates and decay rates of the arm linearised about
/// any configuration (module docs), for parameters that pass
/// [`Params::validate`] (`m`, `l`, `g` > 0; `k`, `sigma` >= 0). Always finite and
/// positive for such parameters (gravity alone gives at least `sqrt(g / l)`-like
/// rates); `mu`, `v_belt`, `h` and `alpha0` do not enter.
///
/// The extremes over `cos theta1` and `cos theta2` are taken at `+-1` exactly (the
/// largest eigenvalue is convex in `K`, the smallest concave, and `K` is affine in
/// both cosines); over `cos(theta2 - theta1)` on a grid of [`COS_GRID`] values
/// (within 1e-4 relative of a grid 20 times finer: `plant` test
/// `the_fastest_rate_is_the_paper_arms_and_scales_as_its_dimensions`).
pub fn fastest_rate(p: &Params<f64>) -> f64 {
    let ml2 = p.m * p.l * p.l;
    let (m11, m22) = (ml2 * 4.0 / 3.0, ml2 / 3.0);
    let mgl2 = 0.5 * p.m * p.g * p.l;
    let mut fastest: f64 = 0.0;
    for i in 0..COS_GRID {
        let c21 = -1.0 + 2.0 * i as f64 / (COS_GRID - 1) as f64;
        let m12 = 0.5 * ml2 * c21;
        let mass = [m11, m12, m22];
        for c1 in [-1.0, 1.0] {
            for c2 in [-1.0, 1.0] {
                let stiffness = [3.0 * mgl2 * c1 + p.k, -p.k, mgl2 * c2 + p.k];
                let (lo, hi) = generalised_eigenvalues(stiffness, mass);
                fastest = fastest.max(lo.abs().sqrt()).max(hi.abs().sqrt());
            }
        }
        let damping = [2.0 * p.sigma, -p.sigma, p.sigma];
        let (lo, hi) = generalised_eigenvalues(damping, mass);
        fastest = fastest.max(lo.abs()).max(hi.abs());
    }
    fastest
}

/// The largest integrator step of a densely sampled run of the arm `p`, s:
/// [`PAPER_ARM_MAX_STEP`] times the paper's arm's [`fastest_rate`] over `p`'s
/// (0.12 rad of the fastest mode; exactly 2 ms for the paper's arm, 0.22 ms for
/// issue 67's short arm), whatever the sampling period, so that the path does not
/// depend on it (issue 53).
pub fn dense_max_step(p: &Params<f64>) -> f64 {
    PAPER_ARM_MAX_STEP * (fastest_rate(&Params::paper()) / fastest_rate(p))
}

/// The two roots of `det(A - lambda B) = 0` for symmetric 2x2 `A = [a11, a12,
/// a22]` and symmetric positive definite `B` (same layout), smallest first: real,
/// since `B` is positive definite.
fn generalised_eigenvalues(a: [f64; 3], b: [f64; 3]) -> (f64, f64) {
    // det(A - lambda B) = det B lambda^2 - (a11 b22 + a22 b11 - 2 a12 b12) lambda + det A.
    let det_b = b[0] * b[2] - b[1] * b[1];
    let half_trace = 0.5 * (a[0] * b[2] + a[2] * b[0] - 2.0 * a[1] * b[1]);
    let det_a = a[0] * a[2] - a[1] * a[1];
    // Rounding can leave a tiny negative discriminant for a double root.
    let root = (half_trace * half_trace - det_b * det_a).max(0.0).sqrt();
    ((half_trace - root) / det_b, (half_trace + root) / det_b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rate against an independent evaluation: the eigenvalues of `M^-1 K`
    /// by the 2x2 matrix's trace and determinant, over a grid 20 times finer
    /// and over the cosines of both angles on a grid as well.
    fn brute_force(p: &Params<f64>) -> f64 {
        let ml2 = p.m * p.l * p.l;
        let mut fastest: f64 = 0.0;
        let n = 20 * (COS_GRID - 1);
        for i in 0..=n {
            let c21 = -1.0 + 2.0 * i as f64 / n as f64;
            let m = nalgebra::Matrix2::new(ml2 * 4.0 / 3.0, 0.5 * ml2 * c21, 0.5 * ml2 * c21, ml2 / 3.0);
            let m_inv = m.try_inverse().unwrap();
            let c = m_inv * nalgebra::Matrix2::new(2.0 * p.sigma, -p.sigma, -p.sigma, p.sigma);
            for e in c.complex_eigenvalues().iter() {
                fastest = fastest.max(e.norm());
            }
            for j in 0..=4 {
                for k in 0..=4 {
                    let (c1, c2) = (-1.0 + j as f64 / 2.0, -1.0 + k as f64 / 2.0);
                    let kmat = nalgebra::Matrix2::new(1.5 * p.m * p.g * p.l * c1 + p.k, -p.k, -p.k, 0.5 * p.m * p.g * p.l * c2 + p.k);
                    for e in (m_inv * kmat).complex_eigenvalues().iter() {
                        fastest = fastest.max(e.norm().sqrt());
                    }
                }
            }
        }
        fastest
    }

    #[test]
    fn the_fastest_rate_is_the_paper_arms_and_scales_as_its_dimensions() {
        let paper = Params::<f64>::paper();
        let w = fastest_rate(&paper);
        let reference = brute_force(&paper);
        assert!((w - reference).abs() <= 1e-4 * reference, "{w} against {reference}");
        assert!((60.0..60.3).contains(&w), "the paper's arm: {w} rad/s");
        // The paper's arm's step cap is issue 53's 2 ms exactly (its outputs bit for
        // bit), 0.12 rad of its fastest mode, whatever the friction and the belt.
        assert_eq!(dense_max_step(&Params { mu: 0.9, v_belt: -1.0, ..paper }), 2e-3);
        assert!((dense_max_step(&paper) * w - 0.12).abs() < 1e-3);
        // Issue 67's short arm.
        let short = Params { m: 0.02, l: 0.06, sigma: 3e-4, k: 1.5, h: 0.11, alpha0: 0.2f64.to_radians(), ..paper };
        let w_short = fastest_rate(&short);
        assert!((w_short - brute_force(&short)).abs() <= 1e-4 * w_short, "{w_short}");
        assert!((530.0..540.0).contains(&w_short), "the short arm: {w_short} rad/s");
        assert!((dense_max_step(&short) * w_short - dense_max_step(&paper) * w).abs() < 1e-12);
        // Dimensional analysis: with gravity and damping scaled away, every rate is
        // sqrt(k / (m l^2)) times a number, so the rate scales as 1/sqrt(m) at fixed l.
        let springy = Params { g: 1e-12, sigma: 0.0, ..paper };
        let heavy = Params { m: 4.0 * paper.m, ..springy };
        let ratio = fastest_rate(&springy) / fastest_rate(&heavy);
        assert!((ratio - 2.0).abs() < 1e-6, "{ratio}");
        // A stiffer spring is never slower; damping alone sets a rate sigma / (m l^2) times a number.
        assert!(fastest_rate(&Params { k: 2.0 * paper.k, ..paper }) > w);
        let damped = Params { g: 1e-12, k: 0.0, sigma: 1.0, ..paper };
        let d = fastest_rate(&damped);
        assert!((d - brute_force(&damped)).abs() <= 1e-4 * d && d > 1.0 / (paper.m * paper.l * paper.l), "{d}");
    }

    #[test]
    fn the_fastest_rate_is_finite_and_positive_over_random_valid_arms() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = |lo: f64, hi: f64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (hi - lo) * (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let l = uniform(0.01, 2.0);
            let p = Params {
                m: uniform(1e-3, 10.0),
                l,
                sigma: uniform(0.0, 1.0),
                k: uniform(0.0, 100.0),
                h: uniform(0.1, 1.9) * l,
                g: uniform(0.1, 30.0),
                ..Params::paper()
            };
            p.validate().unwrap();
            let w = fastest_rate(&p);
            let reference = brute_force(&p);
            assert!(w.is_finite() && w > 0.0, "{p:?}: {w}");
            assert!((w - reference).abs() <= 1e-4 * reference, "{p:?}: {w} against {reference}");
        }
    }
}
