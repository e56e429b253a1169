//! Sines and cosines of the joint angles for the plant's model evaluations,
//! computed from the last angles evaluated in full when the new ones are close.
//!
//! The twelve stages of an integration step, the event function at its end, the
//! projection onto the contact and the report's contact force all evaluate the
//! model at angles within a few milliradians of each other, and two `sin_cos`
//! calls were a third of the cost of an evaluation. For angles `q = q_b + d` with
//! `|d| <= 1/16` rad from the angles `q_b` last evaluated by `sin_cos`, the
//! angle-addition identities
//! `sin q = sin q_b + (sin q_b (cos d - 1) + cos q_b sin d)`,
//! `cos q = cos q_b + (cos q_b (cos d - 1) - sin q_b sin d)`
//! with the Taylor series of `sin d` and `cos d - 1` (to `d^9` and `d^10`: the
//! remainder is below `2e-21`) give the same values to rounding (absolute error
//! about `2e-16`, as of any product of two such values); the same angles give the
//! cached values exactly. Odd and even in `d`, so mirror-symmetric motions stay
//! exactly symmetric.

use std::cell::Cell;

use nalgebra::Vector2;
use shared::kinematics::JointTrig;

/// Largest angle step (rad) taken by the series from the last full evaluation.
const D_MAX: f64 = 0.0625;

/// The joint angles last evaluated by `sin_cos` and their sines and cosines.
#[derive(Debug, Clone)]
pub struct TrigCache {
    /// The angles (rad); NaN while empty, so that no angle is near them.
    base: Cell<[f64; 2]>,
    /// Their sines and cosines.
    trig: Cell<JointTrig<f64>>,
}

impl Default for TrigCache {
    fn default() -> Self {
        Self { base: Cell::new([f64::NAN; 2]), trig: Cell::new(JointTrig { s1: f64::NAN, c1: f64::NAN, s2: f64::NAN, c2: f64::NAN }) }
    }
}

impl TrigCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The sines and cosines of `q = [theta1, theta2]` (rad): the cached ones for the
    /// same angles, by the series within `1/16` rad of them, otherwise by `sin_cos`
    /// (which then becomes the cache).
    #[inline]
    pub fn get(&self, q: &Vector2<f64>) -> JointTrig<f64> {
        // Two plain cells (no `Option` to unpack): this runs at every model evaluation.
        let qb = self.base.get();
        let (d1, d2) = (q[0] - qb[0], q[1] - qb[1]);
        // NaN (empty cache or non-finite angles) fails both tests.
        if d1.abs() <= D_MAX && d2.abs() <= D_MAX {
            let tb = self.trig.get();
            if d1 == 0.0 && d2 == 0.0 {
                return tb;
            }
            let (s1, c1) = rotate(tb.s1, tb.c1, d1);
            let (s2, c2) = rotate(tb.s2, tb.c2, d2);
            return JointTrig { s1, c1, s2, c2 };
        }
        let trig = JointTrig::new(q);
        if trig.s1.is_finite() && trig.s2.is_finite() {
            self.base.set([q[0], q[1]]);
            self.trig.set(trig);
        }
        trig
    }
}

/// `(sin(b + d), cos(b + d))` from `(sin b, cos b)` and a small `d` (rad, `|d| <= 1/16`).
#[inline(always)]
fn rotate(s: f64, c: f64, d: f64) -> (f64, f64) {
    let (sd, cm1) = sin_cosm1(d);
    (s + (s * cm1 + c * sd), c + (c * cm1 - s * sd))
}

/// `(sin d, cos d - 1)` by their Taylor series for `|d| <= 1/16` (terms to `d^9` and
/// `d^10`; the first omitted terms are below `2e-21` and `1e-23`), the polynomials
/// in `d^2` evaluated by Estrin's scheme (short dependency chains: the integration
/// stages wait on each other, so latency is what counts).
#[inline(always)]
fn sin_cosm1(d: f64) -> (f64, f64) {
    const S3: f64 = -1.0 / 6.0;
    const S5: f64 = 1.0 / 120.0;
    const S7: f64 = -1.0 / 5040.0;
    const S9: f64 = 1.0 / 362_880.0;
    const C2: f64 = -0.5;
    const C4: f64 = 1.0 / 24.0;
    const C6: f64 = -1.0 / 720.0;
    const C8: f64 = 1.0 / 40_320.0;
    const C10: f64 = -1.0 / 3_628_800.0;
    let d2 = d * d;
    let d4 = d2 * d2;
    let d3 = d * d2;
    // sin d = d + d^3 ((S3 + S5 d^2) + d^4 (S7 + S9 d^2))
    let sin = d + d3 * ((S3 + S5 * d2) + d4 * (S7 + S9 * d2));
    // cos d - 1 = d^2 ((C2 + C4 d^2) + d^4 ((C6 + C8 d^2) + d^4 C10))
    let cm1 = d2 * ((C2 + C4 * d2) + d4 * ((C6 + C8 * d2) + d4 * C10));
    (sin, cm1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within 1/16 rad of the cached angles the series agrees with `sin_cos` to rounding.
    #[test]
    fn series_agrees_with_sin_cos_to_rounding() {
        let mut worst: f64 = 0.0;
        for i in -40..=40 {
            let base = Vector2::new(0.077 * i as f64, -0.13 * i as f64 + 0.4);
            for j in -50..=50 {
                let cache = TrigCache::new();
                cache.get(&base);
                let d = 0.999 * D_MAX * j as f64 / 50.0;
                let q = Vector2::new(base[0] + d, base[1] - 0.7 * d);
                let a = cache.get(&q);
                let b = JointTrig::new(&q);
                for (x, y) in [(a.s1, b.s1), (a.c1, b.c1), (a.s2, b.s2), (a.c2, b.c2)] {
                    worst = worst.max((x - y).abs());
                }
                // The base stays: the series was used.
                assert_eq!(cache.base.get(), [base[0], base[1]]);
            }
        }
        eprintln!("worst deviation from sin_cos: {worst:e}");
        assert!(worst <= 4.5e-16, "worst deviation {worst:e}");
    }

    /// The same angles give the cached values; far ones are evaluated afresh and cached.
    #[test]
    fn exact_hits_and_refresh() {
        let cache = TrigCache::new();
        let q = Vector2::new(0.3, -1.2);
        let t = cache.get(&q);
        assert_eq!(t, JointTrig::new(&q));
        assert_eq!(cache.get(&q), t);
        let far = Vector2::new(0.3 + 0.2, -1.2);
        assert_eq!(cache.get(&far), JointTrig::new(&far));
        assert_eq!(cache.base.get(), [far[0], far[1]]);
        // Non-finite angles give NaN and are not cached.
        let nan = cache.get(&Vector2::new(f64::NAN, 0.0));
        assert!(nan.s1.is_nan());
        assert_eq!(cache.base.get(), [far[0], far[1]]);
    }

    /// Mirror symmetry: `q -> -q` gives `sin -> -sin`, `cos -> cos` exactly.
    #[test]
    fn odd_and_even_exactly() {
        let (a, b) = (TrigCache::new(), TrigCache::new());
        let q = Vector2::new(0.41, -0.93);
        a.get(&q);
        b.get(&-q);
        for d in [1e-9, 3e-4, 0.01, 0.1] {
            let x = a.get(&Vector2::new(q[0] + d, q[1] - d));
            let y = b.get(&Vector2::new(-q[0] - d, -q[1] + d));
            assert_eq!((x.s1, x.c1, x.s2, x.c2), (-y.s1, y.c1, -y.s2, y.c2));
        }
    }
}
