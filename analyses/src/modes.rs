//! The map of contact modes over `(theta1, theta1_dot)` with the
//! tip on the belt (docs/model.md experiment 1, paper Fig. 2).
//!
//! At each grid point the configuration is completed so that the tip is on the
//! belt and moves along it:
//! - `theta2` solves `z_n = -H`, i.e. `cos theta2 = H/l - cos theta1`: `theta2 = ±acos(H/l - cos theta1)`,
//!   the sign chosen by `--theta2-sign` (see [`Theta2Sign`]); the point is
//!   *unreachable* when there is no solution (`|theta1| > acos(H/l - 1)`, 37.1
//!   degrees for the paper's arm) or, with `auto`, when the solution is not on `--branch`;
//! - `theta2_dot` makes `z_n_dot = l (sin theta1 theta1_dot + sin theta2 theta2_dot) = 0`:
//!   `theta2_dot = -sin theta1 theta1_dot / sin theta2`; the point is *singular* when
//!   `|sin theta2| <` [`SIN_THETA2_MIN`] (the turning point of the belt curve);
//! - `u = 0`; `z_r_dot = z_t_dot - v_belt`; `b` (paper eq. 6) and `p` (eq. 7) for the
//!   slip direction `sign(z_r_dot)` (zero counts as positive);
//! - the mode is [`shared::contact::classify_slipping`]`(b, p)`: sliding, flight,
//!   indeterminate or inconsistent. Sticking is not part of this map (it needs
//!   `z_r_dot = 0`, a curve of the plane, drawn dashed in the figure).
//!
//! Elbow branches do not map one-to-one onto the sign of `theta2`: for
//! `|theta1|` beyond the straight-arm angle `acos(H / 2l)` (25.98 degrees) both
//! roots are on the same branch (e.g. `x0a = [32, 0, 18.27, 0]` deg is elbow
//! down with `theta2 > 0`, while `x0d` is elbow down with `theta2 < 0`), hence
//! `--theta2-sign`: `auto` keeps the root on `--branch` that is continuous with
//! the branch's configuration at `theta1 = 0`; `plus`/`minus` follow one root
//! across the straight arm, where the branch changes.
//!
//! Curves: `b = 0` by marching squares on the grid, each crossing refined by
//! bisection along its cell edge (`b` does not depend on the slip direction);
//! `p = 0` by a fine scan of `theta1` plus bisection, for each slip
//! direction (`p` depends on `theta1` only), drawn over the `theta1_dot` where
//! `z_r_dot` has that direction; and the switching curve `z_r_dot = 0`, across
//! which `p` jumps.

use nalgebra::Vector2;
use serde::Serialize;
use shared::{Arm, ContactMode, ElbowBranch, Params, SlipDirection, contact::classify_slipping};

use crate::{admissible::bisect_sign_change, error::AnalysisError};

/// Below this `|sin theta2|` the point is singular: `theta2_dot = -sin theta1 theta1_dot / sin theta2`
/// is unbounded (the tip cannot move along the belt there with `theta1_dot != 0`).
pub const SIN_THETA2_MIN: f64 = 1e-6;

/// Largest accepted `--grid` (points per axis): the map is held in memory
/// (about 50 bytes a point) and written to `modes.csv` (about 150 bytes a point).
pub const GRID_MAX: usize = 1000;

/// Largest accepted magnitude of the ends of `--theta1-deg` (degrees) and
/// `--theta1-dot` (rad/s), so that grid spacings stay finite.
pub const RANGE_MAX: f64 = 1e6;

/// Steps of the scan of `theta1` for the zeros of `p` (before bisection).
pub const P_SCAN_STEPS: usize = 20_000;

/// Which root of `cos theta2 = H/l - cos theta1` to use (`--theta2-sign`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Theta2Sign {
    /// The root on the chosen elbow branch that is continuous with the branch's
    /// configuration at `theta1 = 0`: `theta2 < 0` for elbow down, `theta2 > 0`
    /// for elbow up; points where that root is on the other branch are unreachable.
    Auto,
    /// `theta2 = +acos(H/l - cos theta1)` whatever the branch (elbow up below the
    /// straight arm at `theta1 = acos(H/2l)`, elbow down above it).
    Plus,
    /// `theta2 = -acos(H/l - cos theta1)` whatever the branch (elbow up below the
    /// straight arm at `theta1 = -acos(H/2l)`, elbow down above it).
    Minus,
}

impl Theta2Sign {
    /// The sign (`+1.0` or `-1.0`) for elbow branch `branch`.
    pub fn sign(self, branch: ElbowBranch) -> f64 {
        match (self, branch) {
            (Self::Plus, _) | (Self::Auto, ElbowBranch::Up) => 1.0,
            (Self::Minus, _) | (Self::Auto, ElbowBranch::Down) => -1.0,
        }
    }
}

/// `theta2` (rad) that puts the tip on the belt (`z_n = -H`) for `theta1` (rad):
/// `theta2 = s acos(H/l - cos theta1)` with `s = sign.sign(branch)` (docs/model.md
/// geometry), if it exists and, for [`Theta2Sign::Auto`], the configuration is on
/// `branch` (`theta2 - theta1 > 0` for up, `< 0` for down; the straight arm,
/// within `1e-12` rad, counts as both). `None` otherwise (also for non-finite input).
pub fn belt_theta2(params: &Params<f64>, theta1: f64, branch: ElbowBranch, sign: Theta2Sign) -> Option<f64> {
    let c = params.h / params.l - theta1.cos();
    // Also rejects NaN.
    if c.is_nan() || c.abs() > 1.0 {
        return None;
    }
    let theta2 = sign.sign(branch) * c.acos();
    if sign != Theta2Sign::Auto {
        return Some(theta2);
    }
    let rel = theta2 - theta1;
    let on_branch = rel.abs() <= 1e-12
        || match branch {
            ElbowBranch::Up => rel > 0.0,
            ElbowBranch::Down => rel < 0.0,
        };
    on_branch.then_some(theta2)
}

/// The mode of one grid point: a contact mode, or why there is none.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointMode {
    /// The tip is on the belt and slipping: the mode from the signs of `b` and `p`.
    Contact(ContactMode),
    /// No `theta2` puts the tip on the belt on the chosen branch and sign.
    Unreachable,
    /// On the belt but `sin theta2 ~ 0`: no finite `theta2_dot` keeps `z_n_dot = 0`.
    Singular,
}

impl PointMode {
    /// Every mode the map can hold, in legend order.
    pub const ALL: [PointMode; 6] = [
        PointMode::Contact(ContactMode::Sliding),
        PointMode::Contact(ContactMode::Flight),
        PointMode::Contact(ContactMode::Indeterminate),
        PointMode::Contact(ContactMode::Inconsistent),
        PointMode::Unreachable,
        PointMode::Singular,
    ];

    /// Lower-case name, as in `modes.csv` (`sliding`, `flight`, `indeterminate`,
    /// `inconsistent`, `unreachable`, `singular`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Contact(m) => m.name(),
            Self::Unreachable => "unreachable",
            Self::Singular => "singular",
        }
    }
}

/// One point of the map. Quantities that do not exist for the point's mode are NaN
/// (`theta2` and everything after it when unreachable; `theta2_dot`, `b`, `p`,
/// `z_r_dot` when singular).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModePoint {
    /// `theta2`, rad.
    pub theta2: f64,
    /// `theta2_dot`, rad/s (so that `z_n_dot = 0`).
    pub theta2_dot: f64,
    /// Free normal acceleration `b` (paper eq. 6), m/s^2, with `u = 0`.
    pub b: f64,
    /// `p` (paper eq. 7) for the slip direction `sign(z_r_dot)`, 1/kg.
    pub p: f64,
    /// Relative tangential velocity `z_r_dot = z_t_dot - v_belt`, m/s.
    pub z_r_dot: f64,
    /// The mode.
    pub mode: PointMode,
}

/// Evaluates one point `(theta1 (rad), theta1_dot (rad/s))` of the map (see the
/// module documentation). Never panics; non-finite input gives an unreachable point.
pub fn evaluate_point(arm: &Arm<f64>, theta1: f64, theta1_dot: f64, branch: ElbowBranch, sign: Theta2Sign) -> ModePoint {
    let nan = f64::NAN;
    let Some(theta2) = belt_theta2(&arm.params, theta1, branch, sign) else {
        return ModePoint { theta2: nan, theta2_dot: nan, b: nan, p: nan, z_r_dot: nan, mode: PointMode::Unreachable };
    };
    let s2 = theta2.sin();
    if s2.abs() < SIN_THETA2_MIN || !theta1_dot.is_finite() {
        return ModePoint { theta2, theta2_dot: nan, b: nan, p: nan, z_r_dot: nan, mode: PointMode::Singular };
    }
    // `+ 0.0` turns -0.0 into 0.0 (for the CSV).
    let theta2_dot = -theta1.sin() * theta1_dot / s2 + 0.0;
    let q = Vector2::new(theta1, theta2);
    let qd = Vector2::new(theta1_dot, theta2_dot);
    let td = arm.tip_dynamics(&q, &qd, &Vector2::zeros());
    let z_r_dot = td.z_dot[0] - arm.params.v_belt;
    let b = td.b();
    let p = td.p(arm.params.mu, SlipDirection::of(z_r_dot));
    ModePoint { theta2, theta2_dot, b, p, z_r_dot, mode: PointMode::Contact(classify_slipping(b, p)) }
}

/// `p` (1/kg) on the belt at `theta1` (rad) for slip direction `dir`; NaN where
/// unreachable. Independent of `theta1_dot` (paper eq. 7: `p` depends on `q` only).
pub fn p_of_theta1(arm: &Arm<f64>, theta1: f64, branch: ElbowBranch, sign: Theta2Sign, dir: SlipDirection) -> f64 {
    match belt_theta2(&arm.params, theta1, branch, sign) {
        Some(theta2) => arm.p(&Vector2::new(theta1, theta2), dir),
        None => f64::NAN,
    }
}

/// `dz_t/dtheta1` (m/rad) along the belt at `theta1` (rad), with `theta2_dot`
/// tied to `theta1_dot` by `z_n_dot = 0`: `z_t_dot = g theta1_dot` with
/// `g = l (cos theta1 - cos theta2 sin theta1 / sin theta2)`. NaN where unreachable
/// or singular.
pub fn z_t_rate(params: &Params<f64>, theta1: f64, branch: ElbowBranch, sign: Theta2Sign) -> f64 {
    match belt_theta2(params, theta1, branch, sign) {
        Some(t2) if t2.sin().abs() >= SIN_THETA2_MIN => params.l * (theta1.cos() - t2.cos() * theta1.sin() / t2.sin()),
        _ => f64::NAN,
    }
}

/// A segment of the curve `p = 0`: the vertical line `theta1 = theta1_deg`,
/// drawn over the `theta1_dot` where `z_r_dot` has direction `dir`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PZero {
    /// Slip direction whose `p` vanishes here.
    #[serde(serialize_with = "ser_dir")]
    pub dir: SlipDirection,
    /// `theta1` of the zero, degrees.
    pub theta1_deg: f64,
    /// Part of the `theta1_dot` window (rad/s) where `sign(z_r_dot)` is `dir`;
    /// `None` if there is none (the zero is then not a boundary on this map).
    pub theta1_dot_range: Option<[f64; 2]>,
}

fn ser_dir<S: serde::Serializer>(d: &SlipDirection, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(dir_name(*d))
}

/// How `modes.csv`, the summary and the figure name a slip direction.
pub fn dir_name(d: SlipDirection) -> &'static str {
    match d {
        SlipDirection::Positive => "z_r_dot > 0",
        SlipDirection::Negative => "z_r_dot < 0",
    }
}

/// The computed map of experiment 1.
#[derive(Debug, Clone)]
pub struct ModeMap {
    /// Parameters (Table I with the requested `mu` and `v_belt`).
    pub params: Params<f64>,
    /// Elbow branch.
    pub branch: ElbowBranch,
    /// Root choice for `theta2`.
    pub sign: Theta2Sign,
    /// `theta1` grid, rad (length `n1`).
    pub theta1: Vec<f64>,
    /// The same grid in degrees, as generated from `--theta1-deg` (length `n1`).
    pub theta1_deg: Vec<f64>,
    /// `theta1_dot` grid, rad/s (length `n2`).
    pub theta1_dot: Vec<f64>,
    /// Points, `points[i * n2 + j]` at `(theta1[i], theta1_dot[j])`.
    pub points: Vec<ModePoint>,
    /// Polylines of `b = 0`, points `(theta1 deg, theta1_dot rad/s)`; every point
    /// is a zero of `b` on a grid-cell edge.
    pub b_zero: Vec<Vec<(f64, f64)>>,
    /// Zeros of `p` along `theta1`, both directions.
    pub p_zero: Vec<PZero>,
    /// Polylines of `z_r_dot = 0`, points `(theta1 deg, theta1_dot rad/s)`.
    pub zr_zero: Vec<Vec<(f64, f64)>>,
}

impl ModeMap {
    /// The point at `(theta1[i], theta1_dot[j])`, if the indices are in range.
    pub fn at(&self, i: usize, j: usize) -> Option<&ModePoint> {
        if i < self.theta1.len() && j < self.theta1_dot.len() { self.points.get(i * self.theta1_dot.len() + j) } else { None }
    }

    /// Number of points in each mode, in [`PointMode::ALL`] order.
    pub fn counts(&self) -> Vec<(PointMode, usize)> {
        PointMode::ALL.iter().map(|&m| (m, self.points.iter().filter(|p| p.mode == m).count())).collect()
    }
}

fn linspace(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n).map(|k| if k + 1 == n { hi } else { lo + (hi - lo) * k as f64 / (n - 1).max(1) as f64 }).collect()
}

/// Splits `columns` (`(x, sorted roots)` per `theta1` column; an empty list where
/// the column has no roots or is unusable) into polylines, joining the `k`-th root
/// of neighbouring columns when both have the same number of roots.
fn polylines(columns: &[(f64, Vec<f64>)]) -> Vec<Vec<(f64, f64)>> {
    let mut done: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open: Vec<Vec<(f64, f64)>> = Vec::new();
    for (x, roots) in columns {
        if roots.len() != open.len() {
            done.append(&mut open);
            open = roots.iter().map(|_| Vec::new()).collect();
        }
        for (line, &y) in open.iter_mut().zip(roots) {
            line.push((*x, y));
        }
    }
    done.append(&mut open);
    done.retain(|l| !l.is_empty());
    done
}

/// Computes the map of experiment 1 (paper Fig. 2).
///
/// `theta1_deg` is the `theta1` range in degrees, `theta1_dot` the range in rad/s,
/// `grid` the number of points along each axis (ends included).
///
/// # Errors
/// [`AnalysisError::Param`] for a negative or non-finite `mu` or a non-finite `v_belt`;
/// [`AnalysisError::BadInput`] for `grid` outside `2..=`[`GRID_MAX`] or a range that is
/// not finite and increasing or has an end beyond [`RANGE_MAX`].
pub fn compute(
    mu: f64,
    v_belt: f64,
    branch: ElbowBranch,
    sign: Theta2Sign,
    theta1_deg: (f64, f64),
    theta1_dot: (f64, f64),
    grid: usize,
) -> Result<ModeMap, AnalysisError> {
    compute_for(Params { mu, v_belt, ..Params::<f64>::paper() }, branch, sign, theta1_deg, theta1_dot, grid)
}

/// [`compute`] for an arm with `params` (paper Table I as given, with its `mu`
/// and `v_belt`).
///
/// # Errors
/// As [`compute`], for any invalid parameter.
pub fn compute_for(
    params: Params<f64>,
    branch: ElbowBranch,
    sign: Theta2Sign,
    theta1_deg: (f64, f64),
    theta1_dot: (f64, f64),
    grid: usize,
) -> Result<ModeMap, AnalysisError> {
    params.validate()?;
    let v_belt = params.v_belt;
    if !(2..=GRID_MAX).contains(&grid) {
        return Err(AnalysisError::BadInput(format!("--grid must be between 2 and {GRID_MAX}, got {grid}")));
    }
    for (flag, (a, b)) in [("theta1-deg", theta1_deg), ("theta1-dot", theta1_dot)] {
        if !(a.is_finite() && b.is_finite() && a < b && a.abs() <= RANGE_MAX && b.abs() <= RANGE_MAX) {
            return Err(AnalysisError::BadInput(format!("--{flag} expects MIN < MAX with |MIN|, |MAX| <= {RANGE_MAX:e}, got {a:?},{b:?}")));
        }
    }
    let arm = Arm::new(params);
    let th1_deg = linspace(theta1_deg.0, theta1_deg.1, grid);
    let th1: Vec<f64> = th1_deg.iter().map(|d| d.to_radians()).collect();
    let th1d = linspace(theta1_dot.0, theta1_dot.1, grid);
    let mut points = Vec::with_capacity(grid * grid);
    for &t1 in &th1 {
        for &w in &th1d {
            points.push(evaluate_point(&arm, t1, w, branch, sign));
        }
    }

    let b_zero = b_zero_curves(&arm, branch, sign, &th1, &th1d, &points);

    // z_r_dot = 0: theta1_dot = v_belt / g(theta1), inside the window.
    let zr_columns: Vec<(f64, Vec<f64>)> = th1
        .iter()
        .map(|&t1| {
            let g = z_t_rate(&params, t1, branch, sign);
            let w = v_belt / g;
            let roots = if g.is_finite() && g != 0.0 && w >= theta1_dot.0 && w <= theta1_dot.1 { vec![w] } else { vec![] };
            (t1.to_degrees(), roots)
        })
        .collect();
    let zr_zero = polylines(&zr_columns);

    // p = 0 along theta1, for each direction.
    let (a, b) = (theta1_deg.0.to_radians(), theta1_deg.1.to_radians());
    let mut p_zero = Vec::new();
    for dir in [SlipDirection::Positive, SlipDirection::Negative] {
        let mut f = |t1: f64| p_of_theta1(&arm, t1, branch, sign, dir);
        let mut x_prev = a;
        let mut f_prev = f(a);
        for k in 1..=P_SCAN_STEPS {
            let x = if k == P_SCAN_STEPS { b } else { a + (b - a) * k as f64 / P_SCAN_STEPS as f64 };
            let fx = f(x);
            if f_prev.is_finite() && fx.is_finite() && (f_prev > 0.0) != (fx > 0.0) {
                let root = bisect_sign_change(&mut f, x_prev, x, f_prev, 1e-13);
                let g = z_t_rate(&params, root, branch, sign);
                p_zero.push(PZero { dir, theta1_deg: root.to_degrees(), theta1_dot_range: dir_window(g, v_belt, dir, theta1_dot) });
            }
            x_prev = x;
            f_prev = fx;
        }
    }
    Ok(ModeMap { params, branch, sign, theta1: th1, theta1_deg: th1_deg, theta1_dot: th1d, points, b_zero, p_zero, zr_zero })
}

/// A grid-cell edge: along `theta1` from node `(i, j)` to `(i + 1, j)` (`along_theta1`),
/// or along `theta1_dot` from `(i, j)` to `(i, j + 1)`.
type EdgeId = (bool, usize, usize);

/// The curve `b = 0` by marching squares over the grid cells whose four corners
/// have the tip on the belt; each crossing is located by bisection along its edge
/// (to `1e-12` rad or rad/s), and the segments are chained into polylines of
/// `(theta1 deg, theta1_dot rad/s)`. Saddle cells are resolved by `b` at the cell
/// centre. The curve stops one cell short of unreachable or singular points.
fn b_zero_curves(
    arm: &Arm<f64>,
    branch: ElbowBranch,
    sign: Theta2Sign,
    th1: &[f64],
    th1d: &[f64],
    points: &[ModePoint],
) -> Vec<Vec<(f64, f64)>> {
    use std::collections::HashMap;
    let (n1, n2) = (th1.len(), th1d.len());
    let node = |i: usize, j: usize| &points[i * n2 + j];
    let on_belt = |i: usize, j: usize| matches!(node(i, j).mode, PointMode::Contact(_));
    let pos = |i: usize, j: usize| node(i, j).b > 0.0;
    let mut roots: HashMap<EdgeId, (f64, f64)> = HashMap::new();
    let mut edge_root = |e: EdgeId| -> (f64, f64) {
        *roots.entry(e).or_insert_with(|| {
            let (along_theta1, i, j) = e;
            let fa = node(i, j).b;
            if along_theta1 {
                let w = th1d[j];
                let mut f = |t: f64| evaluate_point(arm, t, w, branch, sign).b;
                (bisect_sign_change(&mut f, th1[i], th1[i + 1], fa, 1e-12).to_degrees(), w)
            } else {
                let t = th1[i];
                let mut f = |w: f64| evaluate_point(arm, t, w, branch, sign).b;
                (t.to_degrees(), bisect_sign_change(&mut f, th1d[j], th1d[j + 1], fa, 1e-12))
            }
        })
    };
    let mut segments: Vec<(EdgeId, EdgeId)> = Vec::new();
    for i in 0..n1.saturating_sub(1) {
        for j in 0..n2.saturating_sub(1) {
            if !(on_belt(i, j) && on_belt(i + 1, j) && on_belt(i + 1, j + 1) && on_belt(i, j + 1)) {
                continue;
            }
            // Corners c0 (i, j), c1 (i+1, j), c2 (i+1, j+1), c3 (i, j+1); edges e0 = c0c1,
            // e1 = c1c2, e2 = c3c2, e3 = c0c3.
            let c = [pos(i, j), pos(i + 1, j), pos(i + 1, j + 1), pos(i, j + 1)];
            let edges: [(EdgeId, bool); 4] = [
                ((true, i, j), c[0] != c[1]),
                ((false, i + 1, j), c[1] != c[2]),
                ((true, i, j + 1), c[3] != c[2]),
                ((false, i, j), c[0] != c[3]),
            ];
            let crossing: Vec<EdgeId> = edges.iter().filter(|(_, x)| *x).map(|(e, _)| *e).collect();
            match crossing.len() {
                2 => segments.push((crossing[0], crossing[1])),
                4 => {
                    let centre = evaluate_point(arm, 0.5 * (th1[i] + th1[i + 1]), 0.5 * (th1d[j] + th1d[j + 1]), branch, sign).b > 0.0;
                    let e = [edges[0].0, edges[1].0, edges[2].0, edges[3].0];
                    if centre == c[0] {
                        segments.push((e[0], e[1]));
                        segments.push((e[2], e[3]));
                    } else {
                        segments.push((e[3], e[0]));
                        segments.push((e[1], e[2]));
                    }
                }
                _ => {}
            }
        }
    }
    // Chain the segments through their shared edges.
    let mut by_edge: HashMap<EdgeId, Vec<usize>> = HashMap::new();
    for (k, (a, b)) in segments.iter().enumerate() {
        by_edge.entry(*a).or_default().push(k);
        by_edge.entry(*b).or_default().push(k);
    }
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    for start in 0..segments.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let (a, b) = segments[start];
        let mut chain = std::collections::VecDeque::from([a, b]);
        for forward in [true, false] {
            loop {
                let end = if forward { chain[chain.len() - 1] } else { chain[0] };
                let next = by_edge.get(&end).and_then(|v| v.iter().copied().find(|&k| !used[k]));
                let Some(k) = next else { break };
                used[k] = true;
                let (x, y) = segments[k];
                let other = if x == end { y } else { x };
                if forward {
                    chain.push_back(other);
                } else {
                    chain.push_front(other);
                }
            }
        }
        lines.push(chain.into_iter().map(&mut edge_root).collect::<Vec<_>>());
    }
    lines
}

/// The part of `[lo, hi]` (rad/s) where `z_r_dot = g theta1_dot - v_belt` has
/// direction `dir` (zero counts as positive, as [`SlipDirection::of`]).
fn dir_window(g: f64, v_belt: f64, dir: SlipDirection, (lo, hi): (f64, f64)) -> Option<[f64; 2]> {
    if !g.is_finite() {
        return None;
    }
    let (mut a, mut b) = (lo, hi);
    if g == 0.0 {
        return (SlipDirection::of(-v_belt) == dir).then_some([lo, hi]);
    }
    let w0 = v_belt / g;
    // z_r_dot >= 0  <=>  g w >= v_belt.
    let above = (g > 0.0) == (dir == SlipDirection::Positive);
    if above {
        a = a.max(w0);
    } else {
        b = b.min(w0);
    }
    (a < b).then_some([a, b])
}

#[cfg(test)]
mod tests {
    use super::*;

    const MU: f64 = 0.6;
    const V: f64 = -0.4;

    /// `b` and `p` recomputed from docs/model.md's formulas, without the shared model.
    fn independent_b_p(pr: &Params<f64>, t1: f64, t2: f64, w1: f64, w2: f64, dir_sign: f64) -> (f64, f64) {
        let (m, l, g, k, s, a0) = (pr.m, pr.l, pr.g, pr.k, pr.sigma, pr.alpha0);
        let ml2 = m * l * l;
        let (m11, m12, m22) = (4.0 / 3.0 * ml2, 0.5 * ml2 * (t2 - t1).cos(), ml2 / 3.0);
        let det = m11 * m22 - m12 * m12;
        let (i11, i12, i22) = (m22 / det, -m12 / det, m11 / det);
        let spring = k * (t2 - t1 + a0);
        let w = [1.5 * m * g * l * t1.sin() - spring - s * (w2 - 2.0 * w1), 0.5 * m * g * l * t2.sin() + spring + s * (w2 - w1)];
        let c = [0.5 * ml2 * w2 * w2 * (t1 - t2).sin(), 0.5 * ml2 * w1 * w1 * (t2 - t1).sin()];
        let r = [w[0] + c[0], w[1] + c[1]];
        let minv_r = [i11 * r[0] + i12 * r[1], i12 * r[0] + i22 * r[1]];
        let j1 = [l * t1.cos(), l * t2.cos()];
        let j2 = [l * t1.sin(), l * t2.sin()];
        let s2 = l * (w1 * w1 * t1.cos() + w2 * w2 * t2.cos());
        let b = -(j2[0] * minv_r[0] + j2[1] * minv_r[1]) + s2;
        let quad = |u: [f64; 2], v: [f64; 2]| u[0] * (i11 * v[0] + i12 * v[1]) + u[1] * (i12 * v[0] + i22 * v[1]);
        let p = quad(j2, j2) - pr.mu * dir_sign * quad(j2, j1);
        (b, p)
    }

    fn map(branch: ElbowBranch, sign: Theta2Sign, grid: usize) -> ModeMap {
        compute(MU, V, branch, sign, (-90.0, 90.0), (-10.0, 10.0), grid).unwrap()
    }

    #[test]
    fn every_point_is_on_the_belt_and_classified_by_independent_b_and_p() {
        for (branch, sign) in [
            (ElbowBranch::Down, Theta2Sign::Auto),
            (ElbowBranch::Up, Theta2Sign::Auto),
            (ElbowBranch::Down, Theta2Sign::Plus),
            (ElbowBranch::Up, Theta2Sign::Minus),
        ] {
            let m = map(branch, sign, 101);
            let pr = m.params;
            let mut contact = 0;
            for (i, &t1) in m.theta1.iter().enumerate() {
                for (j, &w1) in m.theta1_dot.iter().enumerate() {
                    let pt = m.at(i, j).unwrap();
                    let PointMode::Contact(mode) = pt.mode else { continue };
                    contact += 1;
                    let (t2, w2) = (pt.theta2, pt.theta2_dot);
                    // On the belt, moving along it, on the branch.
                    assert!((-pr.l * (t1.cos() + t2.cos()) + pr.h).abs() < 1e-12);
                    assert!((pr.l * (t1.sin() * w1 + t2.sin() * w2)).abs() < 1e-12 * (1.0 + w1.abs()));
                    if sign == Theta2Sign::Auto {
                        assert!(t2 - t1 == 0.0 || ElbowBranch::of(&Vector2::new(t1, t2)) == branch);
                    } else {
                        assert_eq!(t2.signum(), sign.sign(branch));
                    }
                    // z_r_dot.
                    let zr = pr.l * (t1.cos() * w1 + t2.cos() * w2) - V;
                    assert!((zr - pt.z_r_dot).abs() < 1e-12 * (1.0 + zr.abs()));
                    // b and p from scratch.
                    let (b, p) = independent_b_p(&pr, t1, t2, w1, w2, if zr < 0.0 { -1.0 } else { 1.0 });
                    assert!((b - pt.b).abs() < 1e-9 * (1.0 + b.abs()), "b {b} vs {}", pt.b);
                    assert!((p - pt.p).abs() < 1e-9 * (1.0 + p.abs()), "p {p} vs {}", pt.p);
                    // The mode follows docs/model.md's table of signs.
                    match mode {
                        ContactMode::Sliding => assert!(p > 0.0 && b < 0.0),
                        ContactMode::Flight => assert!(p > 0.0 && b >= 0.0),
                        ContactMode::Indeterminate => assert!(p <= 0.0 && b >= 0.0),
                        ContactMode::Inconsistent => assert!(p <= 0.0 && b < 0.0),
                        ContactMode::Sticking => panic!("sticking is not part of the slipping map"),
                    }
                }
            }
            assert!(contact > 0, "{branch:?} {sign:?}: no point on the belt");
        }
    }

    #[test]
    fn reachability_follows_the_geometry() {
        let pr = Params::<f64>::paper();
        let th_max = (pr.h / pr.l - 1.0).acos(); // 37.1 deg: theta2 = 0.
        let th_straight = (pr.h / (2.0 * pr.l)).acos(); // 25.98 deg: theta2 = theta1.
        let m = map(ElbowBranch::Down, Theta2Sign::Auto, 181);
        for (i, &t1) in m.theta1.iter().enumerate() {
            let mode = m.at(i, 7).unwrap().mode;
            if t1.abs() > th_max + 1e-9 || t1 < -th_straight - 1e-9 {
                assert_eq!(mode, PointMode::Unreachable, "theta1 = {} deg", t1.to_degrees());
            } else if t1.abs() < th_max - 1e-3 && t1 > -th_straight + 1e-9 {
                assert!(matches!(mode, PointMode::Contact(_)), "theta1 = {} deg: {mode:?}", t1.to_degrees());
            }
        }
        // The paper's initial conditions sit on the sheets the docs say. They are
        // rounded (docs/model.md: the tip is a fraction of a millimetre inside the belt), and
        // near theta2 = 0, theta2 is sensitive to theta1 (x0u: -11.63 deg here), so the
        // tolerance is 0.5 deg; the tips then agree to about a millimetre.
        let d = |x: f64| x.to_radians();
        for (name, t1, t2_paper, branch, sign) in [
            ("x0d", -11.4, -35.1, ElbowBranch::Down, Theta2Sign::Auto),
            ("x0d", -11.4, -35.1, ElbowBranch::Down, Theta2Sign::Minus),
            ("x0a", 32.0, 18.27, ElbowBranch::Down, Theta2Sign::Plus),
            ("x0u", -35.1, -11.4, ElbowBranch::Up, Theta2Sign::Minus),
        ] {
            let t2 = belt_theta2(&pr, d(t1), branch, sign).unwrap();
            assert!((t2.to_degrees() - t2_paper).abs() < 0.5, "{name}: theta2 = {} deg", t2.to_degrees());
            let ours = shared::kinematics::tip_position(pr.l, &Vector2::new(d(t1), t2));
            let paper = shared::kinematics::tip_position(pr.l, &Vector2::new(d(t1), d(t2_paper)));
            assert!((ours - paper).norm() < 1.5e-3, "{name}: tip {ours:?} vs {paper:?}");
            assert_eq!(ElbowBranch::of(&Vector2::new(d(t1), t2)), branch, "{name}");
        }
        assert!(belt_theta2(&pr, d(-35.1), ElbowBranch::Down, Theta2Sign::Auto).is_none());
        assert!(belt_theta2(&pr, f64::NAN, ElbowBranch::Down, Theta2Sign::Auto).is_none());
        // Singular: theta2 = 0 exactly at theta1 = th_max.
        let pt = evaluate_point(&Arm::new(pr), th_max, 1.0, ElbowBranch::Down, Theta2Sign::Auto);
        assert_eq!(pt.mode, PointMode::Singular);
    }

    #[test]
    fn b_zero_curve_points_have_b_zero() {
        for sign in [Theta2Sign::Auto, Theta2Sign::Plus] {
            let m = map(ElbowBranch::Down, sign, 200);
            let arm = Arm::new(m.params);
            let pts: Vec<_> = m.b_zero.iter().flatten().collect();
            assert!(pts.len() > 100, "{sign:?}: only {} points on b = 0", pts.len());
            for &&(deg, w) in &pts {
                let t = deg.to_radians();
                let b = |t: f64, w: f64| evaluate_point(&arm, t, w, m.branch, m.sign).b;
                // b is O(10) m/s^2 and its slopes O(10^3) per rad: bisection to 1e-12 leaves |b| ~ 1e-9.
                assert!(b(t, w).abs() < 1e-7, "b({deg}, {w}) = {}", b(t, w));
                // and b changes sign across it, along theta1 or along theta1_dot.
                let h = 1e-7;
                assert!(b(t - h, w) * b(t + h, w) < 0.0 || b(t, w - h) * b(t, w + h) < 0.0, "no sign change at ({deg}, {w})");
            }
            // The curve separates the grid: neighbours across it have b of opposite signs,
            // and every sign change between on-belt neighbours has a curve point between them.
            let n2 = m.theta1_dot.len();
            for i in 0..m.theta1.len() {
                for j in 0..n2 - 1 {
                    let (a, c) = (m.at(i, j).unwrap(), m.at(i, j + 1).unwrap());
                    if matches!(a.mode, PointMode::Contact(_)) && matches!(c.mode, PointMode::Contact(_)) && (a.b > 0.0) != (c.b > 0.0) {
                        let deg = m.theta1[i].to_degrees();
                        let found = pts.iter().any(|&&(d, w)| d == deg && w >= m.theta1_dot[j] && w <= m.theta1_dot[j + 1]);
                        let border = i == 0
                            || i + 1 == m.theta1.len()
                            || !matches!(m.at(i - 1, j).unwrap().mode, PointMode::Contact(_))
                            || !matches!(m.at(i + 1, j).unwrap().mode, PointMode::Contact(_));
                        assert!(found || border, "{sign:?}: missed b = 0 at theta1 = {deg}, row {j}");
                    }
                }
            }
        }
    }

    #[test]
    fn p_zero_is_a_zero_of_p_and_bounds_the_p_sign_on_the_grid() {
        let m = map(ElbowBranch::Down, Theta2Sign::Auto, 200);
        let arm = Arm::new(m.params);
        assert!(!m.p_zero.is_empty(), "mu = 0.6 should have a zero of p on the elbow-down map");
        for z in &m.p_zero {
            let t = z.theta1_deg.to_radians();
            let p = |x: f64| p_of_theta1(&arm, x, m.branch, m.sign, z.dir);
            assert!(p(t).abs() < 1e-8, "p = {}", p(t));
            assert!(p(t - 1e-7) * p(t + 1e-7) < 0.0);
            // Over its window, z_r_dot has the direction dir.
            if let Some([a, b]) = z.theta1_dot_range {
                for w in [a + 1e-9 * (b - a), 0.5 * (a + b), b - 1e-9 * (b - a)] {
                    let pt = evaluate_point(&arm, t, w, m.branch, m.sign);
                    assert_eq!(SlipDirection::of(pt.z_r_dot), z.dir);
                }
            }
        }
        // Grid points on either side of a zero carry p of opposite signs (same direction).
        for (i, &t1) in m.theta1.iter().enumerate() {
            for (j, _) in m.theta1_dot.iter().enumerate().step_by(17) {
                let pt = m.at(i, j).unwrap();
                if let PointMode::Contact(_) = pt.mode {
                    let dir = SlipDirection::of(pt.z_r_dot);
                    let expect_pos = p_of_theta1(&arm, t1, m.branch, m.sign, dir) > 0.0;
                    assert_eq!(pt.p > 0.0, expect_pos);
                }
            }
        }
    }

    #[test]
    fn z_r_dot_zero_curve_is_where_z_r_dot_vanishes() {
        let m = map(ElbowBranch::Down, Theta2Sign::Auto, 150);
        let arm = Arm::new(m.params);
        let n: usize = m.zr_zero.iter().map(Vec::len).sum();
        assert!(n > 0);
        for &(deg, w) in m.zr_zero.iter().flatten() {
            let pt = evaluate_point(&arm, deg.to_radians(), w, m.branch, m.sign);
            assert!(pt.z_r_dot.abs() < 1e-12, "{}", pt.z_r_dot);
        }
    }

    #[test]
    fn counts_add_up_and_the_map_has_the_paper_modes() {
        let m = map(ElbowBranch::Down, Theta2Sign::Auto, 120);
        let counts = m.counts();
        assert_eq!(counts.iter().map(|(_, c)| c).sum::<usize>(), 120 * 120);
        let get = |mode| counts.iter().find(|(m, _)| *m == mode).unwrap().1;
        assert!(get(PointMode::Contact(ContactMode::Sliding)) > 0);
        assert!(get(PointMode::Contact(ContactMode::Flight)) > 0);
        assert!(get(PointMode::Unreachable) > 0);
    }

    #[test]
    fn polylines_join_equal_root_counts() {
        let cols = vec![(0.0, vec![1.0]), (1.0, vec![2.0]), (2.0, vec![]), (3.0, vec![1.0, 5.0]), (4.0, vec![2.0, 4.0])];
        let l = polylines(&cols);
        assert_eq!(l, vec![vec![(0.0, 1.0), (1.0, 2.0)], vec![(3.0, 1.0), (4.0, 2.0)], vec![(3.0, 5.0), (4.0, 4.0)]]);
    }
}
