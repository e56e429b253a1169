//! The figure of `sil-host modes`: the mode map with the curves `b = 0`, `p = 0` and `z_r_dot = 0` (`modes.svg`).

use crate::{
    error::CliError,
    plot::{
        axis::NiceAxis,
        chart::{Frame, frame_chart},
    },
};
use analyses::modes::*;
use experiments::modes::branch_label;
use plotters::prelude::*;
use shared::ContactMode;
use std::path::Path;

/// The fill colour of a mode in `modes.svg`.
pub(crate) fn color(mode: PointMode) -> RGBColor {
    match mode {
        PointMode::Contact(ContactMode::Sliding) => RGBColor(161, 217, 155),
        PointMode::Contact(ContactMode::Flight) => RGBColor(158, 202, 225),
        PointMode::Contact(ContactMode::Indeterminate) => RGBColor(253, 174, 97),
        PointMode::Contact(ContactMode::Inconsistent) => RGBColor(215, 48, 39),
        PointMode::Contact(ContactMode::Sticking) => RGBColor(255, 255, 153),
        PointMode::Unreachable => RGBColor(228, 228, 228),
        PointMode::Singular => RGBColor(60, 60, 60),
    }
}

pub(crate) fn plot_err(path: &Path) -> impl Fn(String) -> CliError + '_ {
    move |message| CliError::Plot { path: path.to_path_buf(), message }
}

/// `theta1` (rad) of the straight arm on the map's root of `theta2`, if the map
/// follows one root across it (`plus`: `+acos(H/2l)`, `minus`: `-acos(H/2l)`).
pub(crate) fn straight_arm_theta1(map: &ModeMap) -> Option<f64> {
    let t = (map.params.h / (2.0 * map.params.l)).acos();
    match map.sign {
        Theta2Sign::Auto => None,
        Theta2Sign::Plus => Some(t),
        Theta2Sign::Minus => Some(-t),
    }
}

/// Draws the map as an SVG at `path` (a staged file): cells coloured by mode
/// (merged into runs along `theta1` to keep the file small), the curves `b = 0`,
/// `p = 0` and `z_r_dot = 0`, and a legend with the counts.
///
/// # Errors
/// [`CliError::Plot`] when plotters fails (including writing the file).
pub fn draw_figure(map: &ModeMap, path: &Path) -> Result<(), CliError> {
    let perr = plot_err(path);
    let (n1, n2) = (map.theta1.len(), map.theta1_dot.len());
    let deg = &map.theta1_deg;
    let half = |v: &[f64]| if v.len() > 1 { 0.5 * (v[1] - v[0]) } else { 0.5 };
    let (hx, hy) = (half(deg), half(&map.theta1_dot));
    let (x0, x1) = (deg[0] - hx, deg[n1 - 1] + hx);
    let (y0, y1) = (map.theta1_dot[0] - hy, map.theta1_dot[n2 - 1] + hy);
    let x_edge = |i: usize| {
        if i == 0 {
            x0
        } else if i == n1 {
            x1
        } else {
            0.5 * (deg[i - 1] + deg[i])
        }
    };
    let y_edge = |j: usize| {
        if j == 0 {
            y0
        } else if j == n2 {
            y1
        } else {
            0.5 * (map.theta1_dot[j - 1] + map.theta1_dot[j])
        }
    };

    let root = crate::plot::svg_canvas(path, (1100, 700)).map_err(|e| perr(e.to_string()))?;
    let title = format!(
        "Contact modes on the belt (paper Fig. 2): mu = {}, v_belt = {} m/s, u = 0, {}",
        map.params.mu,
        map.params.v_belt,
        branch_label(map)
    );
    let (top, root) = root.split_vertically(36);
    crate::plot::draw_title(&top, &title, 18.0, 8).map_err(|e| perr(e.to_string()))?;
    let (left, right) = root.split_horizontally(790);
    let frame =
        Frame { x_desc: "theta1 (deg)", y_desc: "theta1_dot (rad/s)", x_tick_labels: true, caption: None, margin_top: 8, y_area: None };
    let mut chart = frame_chart(&left, NiceAxis::new(x0..x1, 9), NiceAxis::new(y0..y1, 11), &frame).map_err(|e| perr(e.to_string()))?;

    // Cells, run-length merged along theta1 within each theta1_dot row.
    let mut rects = Vec::new();
    for j in 0..n2 {
        let mut i = 0;
        while i < n1 {
            let mode = map.points[i * n2 + j].mode;
            let mut k = i + 1;
            while k < n1 && map.points[k * n2 + j].mode == mode {
                k += 1;
            }
            rects.push(Rectangle::new([(x_edge(i), y_edge(j)), (x_edge(k), y_edge(j + 1))], color(mode).filled()));
            i = k;
        }
    }
    chart.draw_series(rects).map_err(|e| perr(e.to_string()))?;

    let zr_style = RGBColor(80, 80, 80).stroke_width(2);
    for line in &map.zr_zero {
        chart.draw_series(DashedLineSeries::new(line.iter().copied(), 6, 5, zr_style)).map_err(|e| perr(e.to_string()))?;
    }
    let b_style = BLACK.stroke_width(2);
    for line in &map.b_zero {
        if line.len() == 1 {
            chart.draw_series(std::iter::once(Circle::new(line[0], 1, BLACK.filled()))).map_err(|e| perr(e.to_string()))?;
        } else {
            chart.draw_series(LineSeries::new(line.iter().copied(), b_style)).map_err(|e| perr(e.to_string()))?;
        }
    }
    let straight_style = BLACK.mix(0.6).stroke_width(1);
    let straight = straight_arm_theta1(map).map(f64::to_degrees).filter(|d| *d > x0 && *d < x1);
    if let Some(d) = straight {
        chart.draw_series(DashedLineSeries::new([(d, y0), (d, y1)], 2, 3, straight_style)).map_err(|e| perr(e.to_string()))?;
    }
    let p_style = RGBColor(148, 0, 211).stroke_width(3);
    for z in &map.p_zero {
        if let Some([a, b]) = z.theta1_dot_range {
            chart.draw_series(LineSeries::new([(z.theta1_deg, a), (z.theta1_deg, b)], p_style)).map_err(|e| perr(e.to_string()))?;
        }
    }

    // Legend panel.
    let total = map.points.len().max(1);
    let text = |s: &str, size: u32| (s.to_string(), ("sans-serif", size).into_font().color(&BLACK));
    let mut y = 40;
    let (t, f) = text("Mode (count, share of grid)", 15);
    right.draw_text(&t, &f, (10, y)).map_err(|e| perr(e.to_string()))?;
    y += 28;
    for (mode, count) in map.counts() {
        right.draw(&Rectangle::new([(12, y - 2), (32, y + 14)], color(mode).filled())).map_err(|e| perr(e.to_string()))?;
        right.draw(&Rectangle::new([(12, y - 2), (32, y + 14)], BLACK.mix(0.5))).map_err(|e| perr(e.to_string()))?;
        let (t, f) = text(&format!("{} ({count}, {:.1}%)", mode.name(), 100.0 * count as f64 / total as f64), 14);
        right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
        y += 26;
    }
    y += 14;
    let (t, f) = text("Curves", 15);
    right.draw_text(&t, &f, (10, y)).map_err(|e| perr(e.to_string()))?;
    y += 28;
    right.draw(&PathElement::new([(12, y + 6), (32, y + 6)], b_style)).map_err(|e| perr(e.to_string()))?;
    let (t, f) = text("b = 0", 14);
    right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    y += 26;
    right.draw(&PathElement::new([(12, y + 6), (32, y + 6)], p_style)).map_err(|e| perr(e.to_string()))?;
    let (t, f) = text("p = 0 (p for the local sign(z_r_dot))", 14);
    right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    y += 26;
    right.draw(&PathElement::new([(12, y + 6), (18, y + 6)], zr_style)).map_err(|e| perr(e.to_string()))?;
    right.draw(&PathElement::new([(24, y + 6), (32, y + 6)], zr_style)).map_err(|e| perr(e.to_string()))?;
    let (t, f) = text("z_r_dot = 0 (p jumps)", 14);
    right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    if straight.is_some() {
        y += 26;
        right.draw(&PathElement::new([(12, y + 6), (14, y + 6)], straight_style)).map_err(|e| perr(e.to_string()))?;
        right.draw(&PathElement::new([(18, y + 6), (20, y + 6)], straight_style)).map_err(|e| perr(e.to_string()))?;
        right.draw(&PathElement::new([(24, y + 6), (26, y + 6)], straight_style)).map_err(|e| perr(e.to_string()))?;
        let (t, f) = text("straight arm: elbow up left, down right", 14);
        right.draw_text(&t, &f, (40, y)).map_err(|e| perr(e.to_string()))?;
    }
    y += 40;
    let notes = [
        "theta2: tip on the belt (z_n = -H)".to_string(),
        "theta2_dot: z_n_dot = 0".to_string(),
        format!("grid {n1} x {n2}"),
        "sliding: p > 0, b < 0".to_string(),
        "flight: p > 0, b >= 0".to_string(),
        "indeterminate: p <= 0, b >= 0".to_string(),
        "inconsistent: p <= 0, b < 0".to_string(),
    ];
    for n in notes {
        let (t, f) = text(&n, 13);
        right.draw_text(&t, &f, (10, y)).map_err(|e| perr(e.to_string()))?;
        y += 20;
    }
    root.present().map_err(|e| perr(e.to_string()))?;
    Ok(())
}
