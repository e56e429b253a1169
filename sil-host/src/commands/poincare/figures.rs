//! The figures of `sil-host poincare`: the bifurcation diagram (`bifurcation.svg`) and the Lyapunov exponents (`lyapunov.svg`).

use crate::error::CliError;
use analyses::poincare::{PoincareConfig, PointResult, classify::Class};
use figures::plot::{
    self, PrintWidth, colors,
    legend::{Legend, Swatch},
    plot_err,
    symbols::{BELT_SPEED, MU, THETA1, THETA1_DOT, axis},
};
use plotters::prelude::*;
use std::path::Path;

/// Colour and legend label of a result's class.
pub(crate) fn class_style(r: &PointResult) -> (RGBColor, &'static str) {
    match (r.class, r.period) {
        (Class::Periodic, Some(1)) => (colors::BLUE, "period 1"),
        (Class::Periodic, Some(2)) => (colors::GREEN, "period 2"),
        (Class::Periodic, Some(3 | 4)) => (colors::ORANGE, "period 3-4"),
        (Class::Periodic, _) => (colors::PURPLE, "period ≥ 5"),
        (Class::Chaotic, _) => (colors::RED, "chaotic"),
        (Class::Aperiodic, _) => (colors::GREY, "aperiodic"),
        (Class::Settling, _) => (colors::LIGHT_GREY, "settling"),
        (Class::Equilibrium, _) => (colors::BLACK, "equilibrium (final θ₁)"),
        (Class::Failed, _) => (colors::SKY, "failed"),
        (Class::Invalid, _) => (colors::YELLOW, "invalid (violates the model)"),
    }
}

/// Whether a point's label is the equilibrium class's ([`class_style`]).
fn is_equilibrium(label: &str) -> bool {
    label.starts_with("equilibrium")
}

/// The y range a diagram shows: all its points, except a few at either end set
/// apart from the rest by a gap wider than a fifth of the whole span (within the
/// lowest or highest 5 % of the points: an equilibrium far below a chaotic band),
/// padded by 5 %. Points outside it are drawn at its edge as triangles.
pub(crate) fn bulk_range(values: &[f64]) -> (f64, f64) {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (-1.0, 1.0);
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let span = v[n - 1] - v[0];
    let tail = ((n as f64) * 0.05).ceil() as usize;
    let (mut lo, mut hi) = (v[0], v[n - 1]);
    for i in 0..tail.min(n - 1) {
        if v[i + 1] - v[i] > 0.2 * span {
            lo = v[i + 1];
        }
        let j = n - 1 - i;
        if v[j] - v[j - 1] > 0.2 * span {
            hi = v[j - 1];
        }
    }
    let pad = ((hi - lo) * 0.05).max(0.5);
    (lo - pad, hi + pad)
}

/// Draws the points `(x, y, colour, label)` on `chart`, one series per label, and
/// those outside `y_range` as triangles at its edge (their legend: [`legend_of`]).
fn draw_classes<DB: DrawingBackend>(
    chart: &mut plot::XyChart<'_, DB>,
    pts: &[(f64, f64, RGBColor, &'static str)],
    y_range: (f64, f64),
    radius: i32,
) -> Result<(), String> {
    let inside = |y: f64| y >= y_range.0 && y <= y_range.1;
    let dots = pts.iter().filter(|p| inside(p.1) && !is_equilibrium(p.3)).map(|p| Circle::new((p.0, p.1), radius, p.2.filled()));
    chart.draw_series(dots).map_err(|e| e.to_string())?;
    // The equilibria over the section points, larger (a branch a reader looks for).
    let equilibria = pts.iter().filter(|p| inside(p.1) && is_equilibrium(p.3)).map(|p| Circle::new((p.0, p.1), radius + 2, p.2.filled()));
    chart.draw_series(equilibria).map_err(|e| e.to_string())?;
    // A triangle 8 px wide, pointing out of the axis, its tip on the edge, in the
    // colour its legend entry gives (`outside_color`).
    let marks = pts.iter().filter(|p| !inside(p.1)).map(|p| {
        let below = p.1 < y_range.0;
        let edge = if below { y_range.0 } else { y_range.1 };
        let color = outside_color(pts, y_range, below);
        EmptyElement::at((p.0, edge))
            + Polygon::new(if below { vec![(-4, -7), (4, -7), (0, 0)] } else { vec![(-4, 7), (4, 7), (0, 0)] }, color.filled())
    });
    chart.draw_series(marks).map_err(|e| e.to_string())?;
    Ok(())
}

pub(crate) fn draw_bifurcation(path: &Path, cfg: &PoincareConfig, x0_name: &str, results: &[PointResult]) -> Result<(), CliError> {
    let err = plot_err(path);
    let v_lo = results.first().map_or(-1.0, |r| r.v_belt);
    let v_hi = results.last().map_or(0.0, |r| r.v_belt);
    let pad = ((v_hi - v_lo) * 0.02).max(1e-3);
    // (v_belt, theta1 in degrees, style) for every section point, and the final
    // theta1 of the belt speeds without crossings.
    let mut pts: Vec<(f64, f64, RGBColor, &'static str)> = Vec::new();
    for r in results {
        let (c, label) = class_style(r);
        if r.class == Class::Equilibrium {
            if r.final_theta1.is_finite() {
                pts.push((r.v_belt, r.final_theta1.to_degrees(), c, label));
            }
        } else {
            pts.extend(r.crossings.iter().map(|x| (r.v_belt, x.x[0].to_degrees(), c, label)));
        }
    }
    // The section points set the range (a few far ones at its edge); the equilibria
    // are a branch of the diagram (the paper's Fig. 4 draws it), so the range always
    // takes them in.
    let (mut lo, mut hi) = bulk_range(&pts.iter().filter(|p| !is_equilibrium(p.3)).map(|p| p.1).collect::<Vec<_>>());
    if pts.iter().all(|p| is_equilibrium(p.3)) {
        (lo, hi) = (f64::INFINITY, f64::NEG_INFINITY);
    }
    let (mut eq_lo, mut eq_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in pts.iter().filter(|p| is_equilibrium(p.3)) {
        (eq_lo, eq_hi) = (eq_lo.min(p.1), eq_hi.max(p.1));
    }
    if eq_lo <= eq_hi {
        // Padded like the section points' range (5 % of the whole, at least 0.5 deg).
        let pad = ((hi.max(eq_hi) - lo.min(eq_lo)) * 0.05).max(0.5);
        (lo, hi) = (lo.min(eq_lo - pad), hi.max(eq_hi + pad));
    }
    if !lo.is_finite() || !hi.is_finite() || lo >= hi {
        (lo, hi) = (-1.0, 1.0);
    }
    // One marker per pixel row and belt speed (the figure is about 700 px high): a
    // periodic orbit repeats its points hundreds of times.
    let resolution = (hi - lo).max(1e-9) / 1500.0;
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup_by(|b, a| a.0 == b.0 && (b.1 - a.1).abs() < resolution);
    let print = PrintWidth::TwoColumn;
    let title = format!(
        "Poincaré section {THETA1_DOT} = 0 (upward) against {BELT_SPEED} (paper Fig. 4), open loop, {MU} = {}, from {x0_name}",
        cfg.mu
    );
    let (root, chart_area) = plot::titled_canvas(path, print, &title, Some(&legend_of(&pts, (lo, hi))), 560).map_err(|e| err(&e))?;
    let (x_desc, y_desc) = (axis(BELT_SPEED, "m/s"), axis(&format!("{THETA1} at the section"), "deg"));
    let axes = plot::Axes { caption: None, x: (v_lo - pad)..(v_hi + pad), y: lo..hi, x_desc: &x_desc, y_desc: &y_desc };
    let mut chart = plot::xy_chart(&chart_area, &axes).map_err(|e| err(&e))?;
    draw_classes(&mut chart, &pts, (lo, hi), 1).map_err(|e| err(&e))?;
    plot::finish(root, path, print).map_err(|e| err(&e).into())
}

/// The colour of the triangles marking the points of `pts` below (`below`) or
/// above `y_range`: their class's when they are all of one class, else black.
fn outside_color(pts: &[(f64, f64, RGBColor, &'static str)], y_range: (f64, f64), below: bool) -> RGBColor {
    let mut outside = pts.iter().filter(|p| if below { p.1 < y_range.0 } else { p.1 > y_range.1 });
    let first = outside.next().map_or(BLACK, |p| p.2);
    if outside.all(|p| p.2 == first) { first } else { BLACK }
}

/// The legend of [`draw_classes`] for `pts` in `y_range`: each class with its
/// colour, and how many points lie outside the axis.
fn legend_of(pts: &[(f64, f64, RGBColor, &'static str)], y_range: (f64, f64)) -> Legend {
    let mut classes: Vec<(&'static str, RGBColor)> = pts.iter().map(|p| (p.3, p.2)).collect();
    classes.sort_unstable_by_key(|c| c.0);
    classes.dedup_by_key(|c| c.0);
    let mut legend = Legend::new(classes.into_iter().map(|(l, c)| (l.to_string(), Swatch::Marker(c))).collect());
    for (below, side) in [(true, "below"), (false, "above")] {
        let outside: Vec<f64> = pts.iter().map(|p| p.1).filter(|&y| if below { y < y_range.0 } else { y > y_range.1 }).collect();
        if !outside.is_empty() {
            let (lo, hi) = outside.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(*y), b.max(*y)));
            let color = outside_color(pts, y_range, below);
            let swatch = if below { Swatch::TriangleDown(color) } else { Swatch::Triangle(color) };
            legend.entries.push((format!("{} {side} the axis ({lo:.1} to {hi:.1}), at its edge", outside.len()), swatch));
        }
    }
    legend
}

pub(crate) fn draw_lyapunov(path: &Path, cfg: &PoincareConfig, results: &[PointResult]) -> Result<(), CliError> {
    let err = plot_err(path);
    let pts: Vec<(f64, f64, RGBColor, &'static str)> = results
        .iter()
        .filter_map(|r| {
            let (c, label) = class_style(r);
            r.lyapunov.filter(|l| l.per_iteration.is_finite()).map(|l| (r.v_belt, l.per_iteration, c, label))
        })
        .collect();
    let v_lo = results.first().map_or(-1.0, |r| r.v_belt);
    let v_hi = results.last().map_or(0.0, |r| r.v_belt);
    let pad = ((v_hi - v_lo) * 0.02).max(1e-3);
    let (mut lo, mut hi) = pts.iter().fold((0.0f64, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if hi - lo < 1e-3 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    let ypad = (hi - lo) * 0.05;
    let (lo, hi) = (lo - ypad, hi + ypad);
    let print = PrintWidth::TwoColumn;
    let title = format!("Largest Lyapunov exponent of the section map, {MU} = {} (chaotic above {})", cfg.mu, cfg.classify.chaos_threshold);
    let (root, chart_area) = plot::titled_canvas(path, print, &title, Some(&legend_of(&pts, (lo, hi))), 380).map_err(|e| err(&e))?;
    let x_desc = axis(BELT_SPEED, "m/s");
    let axes = plot::Axes { caption: None, x: (v_lo - pad)..(v_hi + pad), y: lo..hi, x_desc: &x_desc, y_desc: "λ per crossing (-)" };
    let mut chart = plot::xy_chart(&chart_area, &axes).map_err(|e| err(&e))?;
    chart.draw_series(LineSeries::new([(v_lo - pad, 0.0), (v_hi + pad, 0.0)], BLACK.mix(0.5).stroke_width(1))).map_err(|e| err(&e))?;
    draw_classes(&mut chart, &pts, (lo, hi), 2).map_err(|e| err(&e))?;
    plot::finish(root, path, print).map_err(|e| err(&e).into())
}

#[cfg(test)]
mod tests {
    use super::bulk_range;

    #[test]
    fn a_few_points_far_from_the_rest_fall_outside_and_a_continuous_band_stays_whole() {
        // A chaotic band from 28 to 68 deg and three equilibria at -17 deg.
        let mut v: Vec<f64> = (0..400).map(|i| 28.0 + 40.0 * i as f64 / 399.0).collect();
        v.extend([-17.4, -17.3, -17.2]);
        let (lo, hi) = bulk_range(&v);
        assert!(lo > -17.0 && lo < 28.0 && hi >= 68.0, "{lo} {hi}");
        // Without the outliers the whole band is shown.
        let (lo, hi) = bulk_range(&v[..400]);
        assert!(lo <= 28.0 && hi >= 68.0);
    }
}
