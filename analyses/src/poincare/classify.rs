//! Classification of a sequence of Poincaré-section points: no points, periodic
//! (and its period), or aperiodic (then chaotic or not by the Lyapunov exponent,
//! [`super::lyapunov`]).
//!
//! Period: the smallest `p <= max_period` such that every point is within `tol`
//! (max norm over the point's coordinates) of the point `p` places later, over
//! the whole recorded sequence, which must hold at least `min_repeats` full
//! periods. A period-`p` sequence then has exactly `p` distinct points within
//! `tol` (the period is minimal). Distinct points are also counted on their own
//! (greedy clustering at `tol`), as a check and for aperiodic sequences (for a
//! chaotic attractor they grow with the record length; for a periodic orbit they
//! do not).

use serde::Serialize;

/// Settings of the classification.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClassifyConfig {
    /// Two section points are the same when no coordinate differs by more than
    /// this (rad for the angles of the plant's section).
    pub tol: f64,
    /// Largest period looked for.
    pub max_period: usize,
    /// Full periods the record must hold for a period to be accepted.
    pub min_repeats: usize,
    /// An aperiodic sequence is chaotic when its largest Lyapunov exponent per
    /// section iteration, less twice its standard error, exceeds this (otherwise:
    /// aperiodic, e.g. quasi-periodic, a transient not yet settled, or an exponent
    /// too close to 0 to tell).
    pub chaos_threshold: f64,
}

impl Default for ClassifyConfig {
    fn default() -> Self {
        Self { tol: 1e-4, max_period: 32, min_repeats: 3, chaos_threshold: 0.01 }
    }
}

/// The class of one parameter value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    /// No section points in the record: the arm is at rest relative to the
    /// section (steady sliding or sticking, or an equilibrium in flight).
    Equilibrium,
    /// Too few section points for a period (the motion is dying out, or its
    /// period is longer than the record).
    Settling,
    /// Periodic with the given period (section points per period).
    Periodic,
    /// No period up to the maximum, and a largest Lyapunov exponent positive
    /// beyond its error ([`ClassifyConfig::chaos_threshold`]).
    Chaotic,
    /// No period up to the maximum, and no clearly positive largest Lyapunov
    /// exponent (quasi-periodic, a transient longer than the one simulated, or
    /// an exponent within its error of 0).
    Aperiodic,
    /// The simulation failed.
    Failed,
    /// The simulation finished but its trajectory violates the model (an
    /// energy-creating impact or a friction-cone violation; [`plant::Validity`]).
    Invalid,
}

impl Class {
    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Equilibrium => "equilibrium",
            Self::Settling => "settling",
            Self::Periodic => "periodic",
            Self::Chaotic => "chaotic",
            Self::Aperiodic => "aperiodic",
            Self::Failed => "failed",
            Self::Invalid => "invalid",
        }
    }
}

/// Max-norm distance between two points.
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// The smallest period `p` of `points` (see the module docs), or `None`.
///
/// `points`: the section points in order, each a slice of the same length.
pub fn period<P: AsRef<[f64]>>(points: &[P], cfg: &ClassifyConfig) -> Option<usize> {
    let n = points.len();
    (1..=cfg.max_period)
        .take_while(|&p| n >= p * cfg.min_repeats.max(2))
        .find(|&p| (0..n - p).all(|i| distance(points[i].as_ref(), points[i + p].as_ref()) <= cfg.tol))
}

/// Number of distinct points within `tol` (greedy clustering: a point joins the
/// first cluster whose first member is within `tol`), at most `cap` clusters
/// counted (the count saturates there).
pub fn distinct_points<P: AsRef<[f64]>>(points: &[P], tol: f64, cap: usize) -> usize {
    let mut centres: Vec<&[f64]> = Vec::new();
    for p in points {
        let p = p.as_ref();
        if centres.len() >= cap {
            break;
        }
        if !centres.iter().any(|c| distance(c, p) <= tol) {
            centres.push(p);
        }
    }
    centres.len()
}

/// The class and period of a record of section points, given the largest
/// Lyapunov exponent per iteration and its standard error (`None` when it could
/// not be estimated).
///
/// Fewer than `2 min_repeats` points: [`Class::Settling`] (none at all:
/// [`Class::Equilibrium`]).
pub fn classify<P: AsRef<[f64]>>(points: &[P], lyapunov: Option<(f64, f64)>, cfg: &ClassifyConfig) -> (Class, Option<usize>) {
    if points.is_empty() {
        return (Class::Equilibrium, None);
    }
    if points.len() < 2 * cfg.min_repeats.max(1) {
        return (Class::Settling, None);
    }
    if let Some(p) = period(points, cfg) {
        return (Class::Periodic, Some(p));
    }
    match lyapunov {
        Some((l, se)) if l - 2.0 * se > cfg.chaos_threshold => (Class::Chaotic, None),
        _ => (Class::Aperiodic, None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scalar(v: &[f64]) -> Vec<[f64; 1]> {
        v.iter().map(|&x| [x]).collect()
    }

    fn logistic(r: f64, x0: f64, skip: usize, n: usize) -> Vec<f64> {
        let mut x = x0;
        for _ in 0..skip {
            x = r * x * (1.0 - x);
        }
        (0..n)
            .map(|_| {
                x = r * x * (1.0 - x);
                x
            })
            .collect()
    }

    #[test]
    fn constant_is_period_one() {
        let cfg = ClassifyConfig::default();
        let pts = scalar(&[0.3 + 2e-5; 40]);
        assert_eq!(classify(&pts, Some((-1.0, 0.01)), &cfg), (Class::Periodic, Some(1)));
        assert_eq!(distinct_points(&pts, cfg.tol, 100), 1);
    }

    #[test]
    fn alternating_is_period_two_not_one() {
        let cfg = ClassifyConfig::default();
        let pts: Vec<[f64; 1]> = (0..60).map(|i| [if i % 2 == 0 { 0.1 } else { 0.25 } + 1e-6 * (i as f64).sin()]).collect();
        assert_eq!(period(&pts, &cfg), Some(2));
        assert_eq!(distinct_points(&pts, cfg.tol, 100), 2);
    }

    #[test]
    fn logistic_period_four_is_found() {
        // r = 3.5: the attracting 4-cycle of the logistic map.
        let cfg = ClassifyConfig::default();
        let pts = scalar(&logistic(3.5, 0.2, 2000, 200));
        assert_eq!(classify(&pts, Some((-0.8, 0.01)), &cfg), (Class::Periodic, Some(4)));
        assert_eq!(distinct_points(&pts, cfg.tol, 100), 4);
    }

    #[test]
    fn logistic_chaos_has_no_period_and_many_points() {
        let cfg = ClassifyConfig::default();
        let pts = scalar(&logistic(4.0, 0.2, 100, 400));
        assert_eq!(period(&pts, &cfg), None);
        assert_eq!(classify(&pts, Some((std::f64::consts::LN_2, 0.05)), &cfg), (Class::Chaotic, None));
        // Without a clearly positive exponent the same sequence is only aperiodic.
        assert_eq!(classify(&pts, Some((0.0, 0.01)), &cfg).0, Class::Aperiodic);
        assert_eq!(classify(&pts, Some((0.1, 0.05)), &cfg).0, Class::Aperiodic);
        assert_eq!(classify(&pts, None, &cfg).0, Class::Aperiodic);
        assert!(distinct_points(&pts, cfg.tol, 1000) > 300);
    }

    #[test]
    fn a_tolerance_breach_breaks_the_period() {
        let cfg = ClassifyConfig::default();
        let mut v = vec![0.5; 30];
        v[17] += 2.0 * cfg.tol;
        assert_eq!(period(&scalar(&v), &cfg), None);
    }

    #[test]
    fn few_points_and_none() {
        let cfg = ClassifyConfig::default();
        let none: Vec<[f64; 1]> = Vec::new();
        assert_eq!(classify(&none, None, &cfg).0, Class::Equilibrium);
        assert_eq!(classify(&scalar(&[0.1, 0.1, 0.1]), None, &cfg).0, Class::Settling);
    }

    #[test]
    fn period_needs_enough_repeats() {
        // Six points of a period-4 pattern are not enough for 3 repeats.
        let cfg = ClassifyConfig::default();
        let v = [0.1, 0.2, 0.3, 0.4, 0.1, 0.2];
        assert_eq!(period(&scalar(&v), &cfg), None);
    }
}
