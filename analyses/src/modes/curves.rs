//! The map's curves ([`super`] documentation, "Curves"): `b = 0` by marching
//! squares over the grid, the `p = 0` columns' slip windows, and the polylines
//! that join the roots of neighbouring `theta1` columns.

use shared::{Arm, ElbowBranch, SlipDirection};

use super::{ModePoint, PointMode, Theta2Sign, evaluate_point};
use crate::admissible::bisect_sign_change;

/// Splits `columns` (`(x, sorted roots)` per `theta1` column; an empty list where
/// the column has no roots or is unusable) into polylines, joining the `k`-th root
/// of neighbouring columns when both have the same number of roots.
pub(super) fn polylines(columns: &[(f64, Vec<f64>)]) -> Vec<Vec<(f64, f64)>> {
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

/// A grid-cell edge: along `theta1` from node `(i, j)` to `(i + 1, j)` (`along_theta1`),
/// or along `theta1_dot` from `(i, j)` to `(i, j + 1)`.
type EdgeId = (bool, usize, usize);

/// The curve `b = 0` by marching squares over the grid cells whose four corners
/// have the tip on the belt; each crossing is located by bisection along its edge
/// (to `1e-12` rad or rad/s), and the segments are chained into polylines of
/// `(theta1 deg, theta1_dot rad/s)`. Saddle cells are resolved by `b` at the cell
/// centre. The curve stops one cell short of unreachable or singular points.
pub(super) fn b_zero_curves(
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
pub(super) fn dir_window(g: f64, v_belt: f64, dir: SlipDirection, (lo, hi): (f64, f64)) -> Option<[f64; 2]> {
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
