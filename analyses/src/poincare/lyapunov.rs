//! The largest Lyapunov exponent of a return map by two nearby trajectories
//! with renormalisation (Benettin, Galgani, Giorgilli and Strelcyn, Meccanica
//! 15, 1980; the "two-trajectory" form of Wolf et al., Physica D 16, 1985).
//!
//! A reference point `x` and a perturbed point `x + d0 e` (`|e| = 1`) are each
//! mapped once; the separation `d = |F(x + d0 e) - F(x)|` gives `ln(d / d0)`;
//! the perturbed point is put back at distance `d0` along the new separation
//! (`e = (F(x + d0 e) - F(x)) / d`) and the reference goes on from `F(x)`. After
//! `skip` iterations (for `e` to align with the most expanding direction) the
//! exponent is the mean of `ln(d / d0)` per iteration, and per second when the
//! map reports its return times (a Poincaré map of a flow).
//!
//! Why this and not the variational equations: the plant is nonsmooth (impacts,
//! stick-slip, the impact without collision), so its Jacobian needs saltation
//! matrices at every event; two trajectories need none, only the map itself.
//! Limits: near a grazing or a switching boundary the map is discontinuous and
//! one renormalisation can see an `O(1)` separation (a spike of `ln(d / d0)`
//! that biases the mean upward); a collapse of the separation (sticking: a
//! finite-time contraction) gives `ln(d / d0) -> -inf` and is floored at
//! `ln(floor)` (counted in [`LyapunovEstimate::collapsed`]); the estimate has a
//! statistical error that falls as `1 / sqrt(iterations)`.

use serde::Serialize;

/// A return map `x -> F(x)` on `D` coordinates.
pub trait ReturnMap<const D: usize> {
    /// Why the map could not be applied.
    type Error;
    /// `F(x)` and the return time (s, or 1 for a discrete map); `Ok(None)` when
    /// the orbit of `x` does not return (e.g. it comes to rest off the section).
    ///
    /// # Errors
    /// When the map fails (e.g. a simulation error).
    fn apply(&mut self, x: &[f64; D]) -> Result<Option<([f64; D], f64)>, Self::Error>;
}

/// Settings of [`largest_exponent`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LyapunovConfig {
    /// Initial separation `d0` (units of the map's coordinates).
    pub d0: f64,
    /// Iterations averaged.
    pub iterations: usize,
    /// Iterations first discarded (alignment of the separation).
    pub skip: usize,
    /// A separation below `floor d0` counts as a collapse, `ln(d / d0) = ln(floor)`.
    pub floor: f64,
}

impl Default for LyapunovConfig {
    fn default() -> Self {
        Self { d0: 1e-7, iterations: 200, skip: 20, floor: 1e-6 }
    }
}

/// The estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LyapunovEstimate {
    /// Largest exponent per iteration of the map (ln 2 for the logistic map at r = 4).
    pub per_iteration: f64,
    /// Largest exponent per second (the per-iteration sum over the summed return times), 1/s.
    pub per_second: f64,
    /// Iterations averaged (fewer than asked when an orbit stopped returning).
    pub iterations: usize,
    /// Standard error of `per_iteration` (the iterates' spread over `sqrt(iterations)`;
    /// iterates are correlated, so this is indicative).
    pub std_error: f64,
    /// Renormalisations where the separation collapsed below `floor d0`.
    pub collapsed: usize,
    /// Largest single `ln(d / d0)` (a large value flags a discontinuity of the map).
    pub max_log_growth: f64,
}

/// The largest Lyapunov exponent of `map` from `x0`, with the first separation
/// along `e0` (normalised here; zero is an error).
///
/// Returns `Ok(None)` when no iteration after `skip` could be made (an orbit
/// stopped returning), when `e0` is zero or not finite, or when a setting is out
/// of range (`d0 <= 0`, `floor` not in (0, 1), no iterations).
///
/// # Errors
/// The map's error.
pub fn largest_exponent<M: ReturnMap<D>, const D: usize>(
    map: &mut M,
    x0: &[f64; D],
    e0: &[f64; D],
    cfg: &LyapunovConfig,
) -> Result<Option<LyapunovEstimate>, M::Error> {
    let norm = |v: &[f64; D]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
    let n0 = norm(e0);
    if !(n0.is_finite() && n0 > 0.0 && cfg.d0 > 0.0 && cfg.floor > 0.0 && cfg.floor < 1.0 && cfg.iterations > 0) {
        return Ok(None);
    }
    let mut e = e0.map(|v| v / n0);
    let mut x = *x0;
    let (mut sum, mut sum_sq, mut time, mut n, mut collapsed) = (0.0, 0.0, 0.0, 0usize, 0usize);
    let mut max_log: f64 = f64::NEG_INFINITY;
    for k in 0..cfg.skip + cfg.iterations {
        let xp: [f64; D] = std::array::from_fn(|i| x[i] + cfg.d0 * e[i]);
        let Some((fx, dt)) = map.apply(&x)? else { break };
        let Some((fxp, _)) = map.apply(&xp)? else { break };
        let delta: [f64; D] = std::array::from_fn(|i| fxp[i] - fx[i]);
        let d = norm(&delta);
        let log_growth = if d.is_finite() && d > cfg.floor * cfg.d0 {
            e = delta.map(|v| v / d);
            (d / cfg.d0).ln()
        } else {
            // Collapsed (or lost): keep the direction, count it.
            if k >= cfg.skip {
                collapsed += 1;
            }
            cfg.floor.ln()
        };
        x = fx;
        if k >= cfg.skip {
            sum += log_growth;
            sum_sq += log_growth * log_growth;
            time += dt;
            n += 1;
            max_log = max_log.max(log_growth);
        }
    }
    if n == 0 {
        return Ok(None);
    }
    let mean = sum / n as f64;
    let var = (sum_sq / n as f64 - mean * mean).max(0.0);
    Ok(Some(LyapunovEstimate {
        per_iteration: mean,
        per_second: if time > 0.0 { sum / time } else { f64::NAN },
        iterations: n,
        std_error: (var / n as f64).sqrt(),
        collapsed,
        max_log_growth: max_log,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    struct Logistic(f64);
    impl ReturnMap<1> for Logistic {
        type Error = Infallible;
        fn apply(&mut self, x: &[f64; 1]) -> Result<Option<([f64; 1], f64)>, Infallible> {
            Ok(Some(([self.0 * x[0] * (1.0 - x[0])], 1.0)))
        }
    }

    /// A linear map with eigenvalues 0.5 and 0.8 (rotated), return time 0.1 s.
    struct Linear;
    impl ReturnMap<2> for Linear {
        type Error = Infallible;
        fn apply(&mut self, x: &[f64; 2]) -> Result<Option<([f64; 2], f64)>, Infallible> {
            // A = R diag(0.5, 0.8) R^T with a 30-degree rotation R.
            let (s, c) = 30f64.to_radians().sin_cos();
            let u = [c * x[0] + s * x[1], -s * x[0] + c * x[1]];
            let v = [0.5 * u[0], 0.8 * u[1]];
            Ok(Some(([c * v[0] - s * v[1], s * v[0] + c * v[1]], 0.1)))
        }
    }

    #[test]
    fn logistic_at_r4_is_ln_2() {
        let cfg = LyapunovConfig { d0: 1e-9, iterations: 20_000, skip: 100, floor: 1e-6 };
        let est = largest_exponent(&mut Logistic(4.0), &[0.123], &[1.0], &cfg).unwrap().unwrap();
        assert!((est.per_iteration - std::f64::consts::LN_2).abs() < 0.03, "{est:?}");
        assert_eq!(est.iterations, 20_000);
    }

    #[test]
    fn logistic_four_cycle_is_negative() {
        // r = 3.5: the 4-cycle's multiplier gives ln|prod f'(x_i)| / 4 = -0.872.
        let cfg = LyapunovConfig { d0: 1e-9, iterations: 400, skip: 1000, floor: 1e-12 };
        let est = largest_exponent(&mut Logistic(3.5), &[0.2], &[1.0], &cfg).unwrap().unwrap();
        let cycle = {
            let mut x = 0.2;
            for _ in 0..5000 {
                x = 3.5 * x * (1.0 - x);
            }
            let mut p: f64 = 1.0;
            for _ in 0..4 {
                p *= 3.5 * (1.0 - 2.0 * x);
                x = 3.5 * x * (1.0 - x);
            }
            p.abs().ln() / 4.0
        };
        assert!((est.per_iteration - cycle).abs() < 1e-3, "{} vs {cycle}", est.per_iteration);
    }

    #[test]
    fn stable_linear_map_gives_its_largest_eigenvalue() {
        let cfg = LyapunovConfig { d0: 1e-3, iterations: 100, skip: 30, floor: 1e-12 };
        let est = largest_exponent(&mut Linear, &[0.3, -0.2], &[1.0, 0.0], &cfg).unwrap().unwrap();
        assert!((est.per_iteration - 0.8f64.ln()).abs() < 1e-9, "{est:?}");
        assert!((est.per_second - 0.8f64.ln() / 0.1).abs() < 1e-7);
    }

    #[test]
    fn zero_direction_gives_none() {
        let est = largest_exponent(&mut Logistic(4.0), &[0.1], &[0.0], &LyapunovConfig::default()).unwrap();
        assert!(est.is_none());
    }
}
