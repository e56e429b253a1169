//! Sines and cosines of the joint angles for the plant's model evaluations, from
//! those of the nearest point of a fixed grid of angles.
//!
//! The twelve stages of an integration step, the dense output's extra stages, the
//! event function at its end, the projection onto the contact and the report's
//! contact force all evaluate the model at angles within a few milliradians of each
//! other, and two `sin_cos` calls were a third of the cost of an evaluation.
//!
//! Each angle `q` is written `q = g + d` with `g = k / 128` rad (`k` an integer: the
//! nearest grid point, ties to the upper one) and `|d| <= 1/256` rad, `d` exact
//! (the subtraction of two nearby floats). The angle-addition identities
//! `sin q = sin g + (sin g (cos d - 1) + cos g sin d)`,
//! `cos q = cos g + (cos g (cos d - 1) - sin g sin d)`
//! with the Taylor series of `sin d` to `d^5` and of `cos d - 1` to `d^6` (the first
//! omitted terms, `d^7/5040` and `d^8/40320`, are below `3e-21` and `2e-24`) give
//! `sin_cos`'s values to rounding (absolute error about `2e-16`, as of any product of
//! two such values). The cache keeps each angle's last grid point and its `sin_cos`;
//! an angle that enters a new cell (it moved by about 8 mrad) evaluates its `sin_cos`
//! once.
//!
//! So the value for an angle is a function of that angle alone, not of what was
//! evaluated before: a dense-output sample or a rolled-back attempt changes no later
//! step (`plant::tests::the_sample_inside_an_advance_is_the_state_there`). The grid
//! is symmetric and the series odd and even in `d`, so mirror-symmetric motions stay
//! exactly symmetric (away from the ties at `d = +-1/256`, which go up).

use std::cell::Cell;

use nalgebra::Vector2;
use shared::kinematics::JointTrig;

/// Grid points per radian (a power of two: `k / GRID` is exact).
const GRID: f64 = 128.0;
/// Half the grid's spacing (rad): the largest `|d|` the series takes.
const D_MAX: f64 = 0.5 / GRID;

/// Each joint angle's last grid point and its sine and cosine.
#[derive(Debug, Clone)]
pub struct TrigCache {
    /// The grid points (rad, multiples of `1/GRID`); NaN while empty, so that no
    /// angle is near them.
    base: Cell<[f64; 2]>,
    /// Their sines and cosines.
    trig: Cell<JointTrig<f64>>,
}

impl Default for TrigCache {
    fn default() -> Self {
        Self { base: Cell::new([f64::NAN; 2]), trig: Cell::new(JointTrig { s1: f64::NAN, c1: f64::NAN, s2: f64::NAN, c2: f64::NAN }) }
    }
}

/// Whether `d = q - g` puts `q` in grid point `g`'s cell `[g - 1/256, g + 1/256)`
/// (false for NaN).
#[inline(always)]
fn in_cell(d: f64) -> bool {
    (-D_MAX..D_MAX).contains(&d)
}

impl TrigCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The sines and cosines of `q = [theta1, theta2]` (rad), from the nearest grid
    /// points' (module docs); NaN for non-finite angles. The same angles give the
    /// same values whatever was evaluated before.
    #[inline(always)]
    pub fn get(&self, q: &Vector2<f64>) -> JointTrig<f64> {
        // Two plain cells (no `Option` to unpack): this runs at every model evaluation.
        let qb = self.base.get();
        let (d1, d2) = (q[0] - qb[0], q[1] - qb[1]);
        // NaN (empty cache or non-finite angles) fails the tests.
        let (tb, d1, d2) = if in_cell(d1) && in_cell(d2) {
            (self.trig.get(), d1, d2)
        } else {
            let (g, tb) = self.refresh(q);
            (tb, q[0] - g[0], q[1] - g[1])
        };
        let (s1, c1) = rotate(tb.s1, tb.c1, d1);
        let (s2, c2) = rotate(tb.s2, tb.c2, d2);
        JointTrig { s1, c1, s2, c2 }
    }

    /// Moves each angle that left its cell to its own grid point (one `sin_cos`
    /// for each: once per 8 mrad of motion) and gives the grid points' sines and
    /// cosines; a non-finite angle, or one beyond 2^45 rad (where the grid point is
    /// not exact), is given as its own grid point, not cached, so that the
    /// rotation by 0 leaves `sin_cos`'s values (NaN for NaN).
    #[inline(never)]
    fn refresh(&self, q: &Vector2<f64>) -> ([f64; 2], JointTrig<f64>) {
        let (mut base, mut trig) = (self.base.get(), self.trig.get());
        let mut cache = true;
        for (i, x) in [q[0], q[1]].into_iter().enumerate() {
            if in_cell(x - base[i]) {
                continue;
            }
            let g = grid_point(x);
            let g = if in_cell(x - g) {
                g
            } else {
                cache = false;
                x
            };
            let (s, c) = g.sin_cos();
            base[i] = g;
            if i == 0 {
                (trig.s1, trig.c1) = (s, c);
            } else {
                (trig.s2, trig.c2) = (s, c);
            }
        }
        if cache {
            self.base.set(base);
            self.trig.set(trig);
        }
        (base, trig)
    }
}

/// The grid point of `x`'s cell (rad): `floor(x GRID + 1/2) / GRID`, then moved by
/// one point where the rounding of `x GRID + 1/2` crossed a cell's edge, so that
/// `x - g` lies in `[-1/256, 1/256)` for every finite `|x| < 2^45` (`x - g` is exact
/// there: Sterbenz's lemma).
#[inline]
fn grid_point(x: f64) -> f64 {
    let g = (x * GRID + 0.5).floor() / GRID;
    let d = x - g;
    if d >= D_MAX {
        g + 1.0 / GRID
    } else if d < -D_MAX {
        g - 1.0 / GRID
    } else {
        g
    }
}

/// `(sin(b + d), cos(b + d))` from `(sin b, cos b)` and a small `d` (rad, `|d| <= 1/256`).
#[inline(always)]
fn rotate(s: f64, c: f64, d: f64) -> (f64, f64) {
    let (sd, cm1) = sin_cosm1(d);
    (s + (s * cm1 + c * sd), c + (c * cm1 - s * sd))
}

/// `(sin d, cos d - 1)` by their Taylor series for `|d| <= 1/256` (terms to `d^5`
/// and `d^6`; the first omitted terms are below `3e-21` and `2e-24`).
#[inline(always)]
fn sin_cosm1(d: f64) -> (f64, f64) {
    const S3: f64 = -1.0 / 6.0;
    const S5: f64 = 1.0 / 120.0;
    const C2: f64 = -0.5;
    const C4: f64 = 1.0 / 24.0;
    const C6: f64 = -1.0 / 720.0;
    let d2 = d * d;
    let d3 = d * d2;
    let sin = d + d3 * (S3 + S5 * d2);
    let cm1 = d2 * (C2 + d2 * (C4 + C6 * d2));
    (sin, cm1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over many turns and every offset within a cell, the series agrees with
    /// `sin_cos` to rounding.
    #[test]
    fn series_agrees_with_sin_cos_to_rounding() {
        let mut worst: f64 = 0.0;
        let cache = TrigCache::new();
        for i in -4000..=4000 {
            // Steps that are not a divisor of the grid's spacing: every offset in a cell occurs.
            let q = Vector2::new(0.001_237 * i as f64, -0.002_91 * i as f64 + 0.4);
            let (a, b) = (cache.get(&q), JointTrig::new(&q));
            for (x, y) in [(a.s1, b.s1), (a.c1, b.c1), (a.s2, b.s2), (a.c2, b.c2)] {
                worst = worst.max((x - y).abs());
            }
        }
        eprintln!("worst deviation from sin_cos: {worst:e}");
        assert!(worst <= 4.5e-16, "worst deviation {worst:e}");
    }

    /// The value for an angle does not depend on what the cache saw before: the
    /// same angles asked after any other angles (near, far, in another cell, on a
    /// cell's edge) give the same bits as a fresh cache.
    #[test]
    fn values_do_not_depend_on_history() {
        let targets = [[0.3, -1.2], [0.3 + 1e-9, -1.2], [0.5 / 128.0, -0.5 / 128.0], [1.0 / 128.0, 0.0], [-2.7, 3.1]];
        let priors = [[0.3, -1.2], [0.31, -1.19], [0.2, -1.3], [0.5 / 128.0 - 1e-17, 0.0], [1e3, -1e3], [-2.7, 3.1]];
        for t in targets {
            let t = Vector2::new(t[0], t[1]);
            let fresh = TrigCache::new().get(&t);
            for p in priors {
                let cache = TrigCache::new();
                cache.get(&Vector2::new(p[0], p[1]));
                assert_eq!(cache.get(&t), fresh, "{t:?} after {p:?}");
            }
        }
    }

    /// Grid points give `sin_cos` exactly; non-finite angles give NaN and leave the cache.
    #[test]
    fn grid_points_exactly_and_non_finite_angles() {
        let cache = TrigCache::new();
        let g = Vector2::new(38.0 / 128.0, -154.0 / 128.0);
        assert_eq!(cache.get(&g), JointTrig::new(&g));
        assert_eq!(cache.base.get(), [g[0], g[1]]);
        for bad in [f64::NAN, f64::INFINITY, -f64::INFINITY] {
            let t = cache.get(&Vector2::new(bad, 0.0));
            assert!(t.s1.is_nan() && t.c1.is_nan());
            assert_eq!(cache.base.get(), [g[0], g[1]]);
        }
        // Beyond 2^45 rad the grid point is not exact: sin_cos itself.
        let huge = Vector2::new(3e15, 0.1);
        assert_eq!(cache.get(&huge), JointTrig::new(&huge));
    }

    /// Every angle lands in the cell of the grid point `grid_point` gives it, at the
    /// cells' edges and where `x GRID + 1/2` rounds across one.
    #[test]
    fn grid_point_gives_the_cell() {
        let mut xs = vec![0.0, -0.0, 1e-300, -1e-300, 0.5 / GRID, -0.5 / GRID, 1e10, -1e10, 3e13];
        for k in [-1000_i32, -3, -1, 0, 1, 2, 77, 5000] {
            let edge = (k as f64 + 0.5) / GRID;
            let mut x = edge;
            for _ in 0..4 {
                xs.extend([x, -x]);
                x = x.next_down();
            }
            x = edge;
            for _ in 0..4 {
                x = x.next_up();
                xs.extend([x, -x]);
            }
        }
        for x in xs {
            let g = grid_point(x);
            assert!(in_cell(x - g), "{x:e}: grid point {g:e}, offset {:e}", x - g);
            assert_eq!((g * GRID).fract(), 0.0, "{g:e} is not a grid point");
        }
    }

    /// Mirror symmetry: `q -> -q` gives `sin -> -sin`, `cos -> cos` exactly (away
    /// from the cells' edges).
    #[test]
    fn odd_and_even_exactly() {
        let (a, b) = (TrigCache::new(), TrigCache::new());
        let q = Vector2::new(0.41, -0.93);
        for d in [0.0, 1e-9, 3e-4, 0.01, 0.1, 1.3] {
            let x = a.get(&Vector2::new(q[0] + d, q[1] - d));
            let y = b.get(&Vector2::new(-q[0] - d, -q[1] + d));
            assert_eq!((x.s1, x.c1, x.s2, x.c2), (-y.s1, y.c1, -y.s2, y.c2));
        }
    }
}
