//! The admissible configurations of the tip on the belt
//! (docs/model.md experiment 2, paper Table II).
//!
//! With the tip on the belt (`z_n = -H`) at tangential position `z_t`, the arm's
//! configuration `q(z_t)` on each elbow branch comes from inverse kinematics, and
//! `p(q, mu, sign z_r_dot) = Q_22 - mu sign(z_r_dot) Q_21` (paper eq. 7) decides
//! whether sliding is possible: the configuration is *admissible* when `p > 0`
//! (then some `f_n >= 0` keeps the tip on the belt whatever `b` is, or the tip
//! lifts off cleanly; with `p < 0` the tip is in the indeterminate or
//! inconsistent — Painlevé — mode).
//!
//! Method: `p` is sampled at [`SCAN_STEPS`]` + 1` equally spaced `z_t` over the
//! whole reachable segment `|z_t| <= sqrt((2 l)^2 - H^2)`; every sign change of
//! `p` between neighbouring samples is refined by bisection to [`ROOT_TOL_M`].
//! Intervals narrower than the scan step, or zeros where `p` touches 0 without
//! changing sign, would be missed; the scan step is `3.8e-6 m` for the paper's
//! arm.
//!
//! The root finders here ([`positive_intervals`], [`bisect_sign_change`]) are
//! also used by the mode map (the `modes` module) for the curve `p = 0`.

use nalgebra::Vector2;
use serde::Serialize;
use shared::{Arm, ElbowBranch, ParamError, Params, SlipDirection, kinematics::inverse_kinematics};

/// Number of steps of the scan of `z_t` over the reachable segment (before bisection).
pub const SCAN_STEPS: usize = 100_000;

/// Tolerance of the bisection on each end of an admissible interval, m.
pub const ROOT_TOL_M: f64 = 1e-9;

/// An interval `[lo, hi]` of the scanned variable on which `f > 0`.
///
/// `lo_is_root` / `hi_is_root` say whether each end is a located zero (sign
/// change) of `f`, as opposed to an end of the scanned range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PositiveInterval {
    /// Lower end (units of the scanned variable).
    pub lo: f64,
    /// Upper end (units of the scanned variable).
    pub hi: f64,
    /// `lo` is a zero of `f` (false: `lo` is the start of the scanned range).
    pub lo_is_root: bool,
    /// `hi` is a zero of `f` (false: `hi` is the end of the scanned range).
    pub hi_is_root: bool,
}

/// Whether a sample counts as positive: `f > 0`; NaN is not positive.
#[inline]
fn positive(v: f64) -> bool {
    v > 0.0
}

/// Bisection on `[a, b]` for the point where `f` switches between `f > 0` and
/// `f <= 0` (NaN counts as `<= 0`), to an absolute tolerance `tol` on the
/// argument.
///
/// `fa` is `f(a)` (already known to the caller); `f(b)` must be on the other
/// side of zero. Returns the midpoint of the final bracket (within `tol / 2` of
/// a switching point). If the precondition fails, the bisection still ends and
/// returns a point of `[a, b]`, but it then means nothing. Never panics; at most
/// 200 halvings (enough for any `f64` bracket).
pub fn bisect_sign_change<F: FnMut(f64) -> f64>(f: &mut F, mut a: f64, mut b: f64, fa: f64, tol: f64) -> f64 {
    let pa = positive(fa);
    for _ in 0..200 {
        if (b - a).abs() <= tol {
            break;
        }
        let m = 0.5 * (a + b);
        if m == a || m == b {
            break;
        }
        if positive(f(m)) == pa {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// The intervals of `[lo, hi]` on which `f > 0`, by a scan of `steps` equal steps
/// (`steps + 1` samples, ends included) and bisection of every sign change to
/// `tol` (same units as `lo`, `hi`).
///
/// NaN values count as "not positive" (so a NaN region splits intervals; its ends
/// are then not zeros of `f`). Sign changes closer together than one scan step
/// may be missed. Returns the intervals in increasing order; empty when `f <= 0`
/// at every sample, or when `steps == 0` or the range is empty or not finite.
pub fn positive_intervals<F: FnMut(f64) -> f64>(mut f: F, lo: f64, hi: f64, steps: usize, tol: f64) -> Vec<PositiveInterval> {
    let mut out = Vec::new();
    if steps == 0 || !(lo.is_finite() && hi.is_finite()) || lo >= hi {
        return out;
    }
    let x_at = |i: usize| if i == steps { hi } else { lo + (hi - lo) * (i as f64) / (steps as f64) };
    let mut x_prev = lo;
    let mut f_prev = f(lo);
    // Start of the interval being built, with whether it is a root.
    let mut open: Option<(f64, bool)> = if positive(f_prev) { Some((lo, false)) } else { None };
    for i in 1..=steps {
        let x = x_at(i);
        let fx = f(x);
        if positive(fx) != positive(f_prev) {
            let root = bisect_sign_change(&mut f, x_prev, x, f_prev, tol);
            match open.take() {
                Some((start, start_is_root)) => {
                    out.push(PositiveInterval { lo: start, hi: root, lo_is_root: start_is_root, hi_is_root: true });
                }
                None => open = Some((root, true)),
            }
        }
        x_prev = x;
        f_prev = fx;
    }
    if let Some((start, start_is_root)) = open {
        out.push(PositiveInterval { lo: start, hi, lo_is_root: start_is_root, hi_is_root: false });
    }
    out
}

/// Half-length of the reachable segment of the belt, m:
/// `sqrt((2 l)^2 - H^2)` (docs/model.md geometry). Zero if the belt is out of reach
/// (invalid parameters; see [`Params::validate`]).
pub fn belt_reach(params: &Params<f64>) -> f64 {
    let reach = 2.0 * params.l;
    (reach * reach - params.h * params.h).max(0.0).sqrt()
}

/// `p` (1/kg, paper eq. 7) with the tip on the belt at `z = [z_t, -H]` (m), on
/// elbow branch `branch` (configuration from inverse kinematics), sliding in
/// direction `dir`, with the arm's own `mu`.
///
/// Returns NaN when `z_t` is out of reach (or not finite): never panics.
pub fn p_on_belt(arm: &Arm<f64>, z_t: f64, branch: ElbowBranch, dir: SlipDirection) -> f64 {
    match inverse_kinematics(arm.params.l, &Vector2::new(z_t, -arm.params.h), branch) {
        Ok(q) => arm.p(&q, dir),
        Err(_) => f64::NAN,
    }
}

/// The admissible `z_t` intervals (m) of one elbow branch and slip direction.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchIntervals {
    /// Elbow branch of the configuration.
    pub branch: ElbowBranch,
    /// Slip direction, the sign of `z_r_dot = z_t_dot - v_belt`.
    pub dir: SlipDirection,
    /// Intervals of `z_t` (m) where `p > 0`, increasing.
    pub intervals: Vec<PositiveInterval>,
}

/// Result of experiment 2 for one friction coefficient.
#[derive(Debug, Clone, PartialEq)]
pub struct AdmissibleReport {
    /// The parameters used (paper's Table I with the requested `mu`).
    pub params: Params<f64>,
    /// Half-length of the reachable belt segment, m ([`belt_reach`]).
    pub reach: f64,
    /// One entry per (direction, branch): `z_r_dot > 0` up, down, then `z_r_dot < 0` up, down.
    pub rows: Vec<BranchIntervals>,
    /// Largest difference (m) between an interval end and the mirror image
    /// (`z_t -> -z_t`, up <-> down, direction reversed) of the matching end;
    /// `None` when the interval lists do not even match in number.
    pub mirror_max_diff: Option<f64>,
}

impl AdmissibleReport {
    /// The intervals of one branch and direction (empty if absent).
    pub fn intervals(&self, branch: ElbowBranch, dir: SlipDirection) -> &[PositiveInterval] {
        self.rows.iter().find(|r| r.branch == branch && r.dir == dir).map(|r| r.intervals.as_slice()).unwrap_or(&[])
    }
}

/// Computes experiment 2 (paper Table II) for friction coefficient `mu`, with
/// the other parameters from Table I.
///
/// # Errors
/// [`ParamError`] when `mu` is negative or not finite.
pub fn compute(mu: f64) -> Result<AdmissibleReport, ParamError> {
    compute_with_steps(mu, SCAN_STEPS)
}

/// [`compute`] with a scan of `steps` steps instead of [`SCAN_STEPS`] (coarser
/// scans are faster but may miss intervals narrower than `2 reach / steps`).
///
/// # Errors
/// As [`compute`].
pub fn compute_with_steps(mu: f64, steps: usize) -> Result<AdmissibleReport, ParamError> {
    compute_for(Params { mu, ..Params::<f64>::paper() }, steps)
}

/// [`compute_with_steps`] for an arm with `params` (paper Table I as given, with
/// its `mu`; only `l`, `H` and `mu` change where `p > 0`: `m` scales `p` and the
/// other parameters do not enter it).
///
/// # Errors
/// [`ParamError`] when `params` are invalid.
pub fn compute_for(params: Params<f64>, steps: usize) -> Result<AdmissibleReport, ParamError> {
    params.validate()?;
    let arm = Arm::new(params);
    let reach = belt_reach(&params);
    let mut rows = Vec::with_capacity(4);
    for dir in [SlipDirection::Positive, SlipDirection::Negative] {
        for branch in [ElbowBranch::Up, ElbowBranch::Down] {
            let intervals = positive_intervals(|z| p_on_belt(&arm, z, branch, dir), -reach, reach, steps, ROOT_TOL_M);
            rows.push(BranchIntervals { branch, dir, intervals });
        }
    }
    let mut report = AdmissibleReport { params, reach, rows, mirror_max_diff: None };
    report.mirror_max_diff = mirror_difference(&report);
    Ok(report)
}

/// Mirror check: the arm mirrored about the vertical (`theta -> -theta`) swaps
/// the elbow branches, maps `z_t -> -z_t` and reverses the slip direction, and
/// keeps `p` (docs/model.md, experiment 2: the slip direction `z_r_dot < 0` mirrors
/// `z_r_dot > 0`). So the
/// intervals of (branch, `z_r_dot > 0`) must be those of (other branch,
/// `z_r_dot < 0`) with `z_t -> -z_t`. Returns the largest end mismatch (m), or
/// `None` if the numbers of intervals differ.
pub fn mirror_difference(report: &AdmissibleReport) -> Option<f64> {
    let mut worst = 0.0f64;
    for (branch, other) in [(ElbowBranch::Up, ElbowBranch::Down), (ElbowBranch::Down, ElbowBranch::Up)] {
        let a = report.intervals(branch, SlipDirection::Positive);
        let b = report.intervals(other, SlipDirection::Negative);
        if a.len() != b.len() {
            return None;
        }
        for (x, y) in a.iter().zip(b.iter().rev()) {
            worst = worst.max((x.lo + y.hi).abs()).max((x.hi + y.lo).abs());
        }
    }
    Some(worst)
}

/// Tolerance (m) of the mirror check reported by the command: a few bisection tolerances.
pub const MIRROR_TOL_M: f64 = 1e-8;

#[cfg(test)]
mod tests {
    use super::*;

    fn arm(mu: f64) -> Arm<f64> {
        Arm::new(Params { mu, ..Params::paper() })
    }

    /// The command's own computation at mu = 0.6 (full scan), shared by the tests.
    fn paper_report() -> &'static AdmissibleReport {
        static R: std::sync::OnceLock<AdmissibleReport> = std::sync::OnceLock::new();
        R.get_or_init(|| compute(0.6).unwrap())
    }

    #[test]
    fn interval_ends_are_zeros_of_p_with_a_sign_change() {
        let r = paper_report();
        let a = arm(0.6);
        let mut roots = 0;
        for row in &r.rows {
            for i in &row.intervals {
                assert!(i.lo < i.hi);
                let p = |z| p_on_belt(&a, z, row.branch, row.dir);
                // Inside: p > 0 at the midpoint.
                assert!(p(0.5 * (i.lo + i.hi)) > 0.0);
                for (x, is_root, inward) in [(i.lo, i.lo_is_root, 1.0), (i.hi, i.hi_is_root, -1.0)] {
                    if is_root {
                        roots += 1;
                        // p vanishes there (p is O(10) 1/kg; slope O(100) 1/(kg m); tolerance 1e-9 m).
                        assert!(p(x).abs() < 1e-5, "p({x}) = {}", p(x));
                        // and changes sign across it.
                        assert!(p(x + inward * 1e-7) > 0.0, "{row:?} at {x}");
                        assert!(p(x - inward * 1e-7) <= 0.0, "{row:?} at {x}");
                    } else {
                        assert!((x.abs() - r.reach).abs() < 1e-15, "non-root end {x} must be +-reach");
                    }
                }
            }
        }
        assert!(roots > 0, "mu = 0.6 should give at least one zero of p on the belt");
    }

    #[test]
    fn outside_the_intervals_p_is_not_positive() {
        let r = paper_report();
        let a = arm(0.6);
        for row in &r.rows {
            for k in 0..=2000 {
                let z = -r.reach + 2.0 * r.reach * k as f64 / 2000.0;
                let inside = row.intervals.iter().any(|i| z >= i.lo - 1e-9 && z <= i.hi + 1e-9);
                let p = p_on_belt(&a, z, row.branch, row.dir);
                if !inside {
                    assert!(p <= 0.0, "{:?} {:?}: p({z}) = {p} outside the intervals", row.branch, row.dir);
                }
            }
        }
    }

    #[test]
    fn z_r_dot_negative_is_the_mirror_image() {
        for (mu, r) in
            [(0.3, compute_with_steps(0.3, 5_000).unwrap()), (0.6, paper_report().clone()), (1.0, compute_with_steps(1.0, 5_000).unwrap())]
        {
            for (b, o) in [(ElbowBranch::Up, ElbowBranch::Down), (ElbowBranch::Down, ElbowBranch::Up)] {
                let pos = r.intervals(b, SlipDirection::Positive);
                let neg = r.intervals(o, SlipDirection::Negative);
                assert_eq!(pos.len(), neg.len(), "mu = {mu}");
                for (x, y) in pos.iter().zip(neg.iter().rev()) {
                    assert!((x.lo + y.hi).abs() < 1e-8, "mu = {mu}: {x:?} vs {y:?}");
                    assert!((x.hi + y.lo).abs() < 1e-8, "mu = {mu}: {x:?} vs {y:?}");
                    assert_eq!(x.lo_is_root, y.hi_is_root);
                }
            }
            assert!(r.mirror_max_diff.unwrap() < 1e-8);
        }
    }

    #[test]
    fn without_friction_the_whole_belt_is_admissible() {
        // mu = 0: p = Q_22 = j2^T M^-1 j2 > 0 on the belt (j2 = 0 only with the arm horizontal... never on the belt).
        let r = compute_with_steps(0.0, 5_000).unwrap();
        for row in &r.rows {
            assert_eq!(row.intervals.len(), 1);
            let i = row.intervals[0];
            assert_eq!((i.lo, i.hi, i.lo_is_root, i.hi_is_root), (-r.reach, r.reach, false, false));
        }
    }

    #[test]
    fn positive_intervals_of_a_known_function() {
        // sin(x) on [0.5, 10]: positive on [0.5, pi] and [2 pi, 3 pi].
        let iv = positive_intervals(f64::sin, 0.5, 10.0, 1000, 1e-12);
        let pi = std::f64::consts::PI;
        assert_eq!(iv.len(), 2);
        assert_eq!((iv[0].lo, iv[0].lo_is_root), (0.5, false));
        assert!((iv[0].hi - pi).abs() < 1e-11 && iv[0].hi_is_root);
        assert!((iv[1].lo - 2.0 * pi).abs() < 1e-11 && (iv[1].hi - 3.0 * pi).abs() < 1e-11);
        // Degenerate input does not panic.
        assert!(positive_intervals(f64::sin, 1.0, 1.0, 10, 1e-9).is_empty());
        assert!(positive_intervals(f64::sin, 0.0, f64::NAN, 10, 1e-9).is_empty());
        assert!(positive_intervals(f64::sin, 0.0, 1.0, 0, 1e-9).is_empty());
        assert!(positive_intervals(|_| f64::NAN, 0.0, 1.0, 10, 1e-9).is_empty());
    }

    #[test]
    fn p_matches_an_independent_computation_from_model_md() {
        // Q = J M^-1 J^T written out from docs/model.md, against the shared model via IK.
        let a = arm(0.6);
        let pr = a.params;
        for &(z_t, branch) in &[(-0.15, ElbowBranch::Up), (0.05, ElbowBranch::Down), (0.17, ElbowBranch::Down)] {
            let q = inverse_kinematics(pr.l, &Vector2::new(z_t, -pr.h), branch).unwrap();
            let (t1, t2) = (q[0], q[1]);
            let ml2 = pr.m * pr.l * pr.l;
            let (m11, m12, m22) = (4.0 / 3.0 * ml2, 0.5 * ml2 * (t2 - t1).cos(), ml2 / 3.0);
            let det = m11 * m22 - m12 * m12;
            let (i11, i12, i22) = (m22 / det, -m12 / det, m11 / det);
            let j2 = [pr.l * t1.sin(), pr.l * t2.sin()];
            let j1 = [pr.l * t1.cos(), pr.l * t2.cos()];
            let quad = |u: [f64; 2], v: [f64; 2]| u[0] * (i11 * v[0] + i12 * v[1]) + u[1] * (i12 * v[0] + i22 * v[1]);
            let (q21, q22) = (quad(j2, j1), quad(j2, j2));
            for (dir, s) in [(SlipDirection::Positive, 1.0), (SlipDirection::Negative, -1.0)] {
                let expect = q22 - 0.6 * s * q21;
                let got = p_on_belt(&a, z_t, branch, dir);
                assert!((got - expect).abs() < 1e-10 * expect.abs().max(1.0), "{z_t} {branch:?} {dir:?}");
            }
        }
    }
}
