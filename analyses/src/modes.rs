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

mod curves;

use curves::{b_zero_curves, dir_window, polylines};

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

#[cfg(test)]
#[path = "modes_tests.rs"]
mod tests;
