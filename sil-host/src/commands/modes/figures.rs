//! The figure of `sil-host modes`: the mode map with the curves `b = 0`, `p = 0` and `z_r_dot = 0` (`modes.svg`).

use crate::error::CliError;
use analyses::modes::*;
use experiments::modes::branch_label;
use figures::plot::{
    PrintWidth,
    axis::NiceAxis,
    chart::{Frame, frame_chart},
    font::{DESC_PX, FAMILY, TEXT_PX, TITLE_PX},
    symbols::{BELT_SPEED, MU, THETA1, THETA1_DOT, THETA2, THETA2_DOT, Z_N, Z_N_DOT, Z_R_DOT, axis},
};
use plotters::prelude::*;
use shared::ContactMode;
use std::path::Path;

/// The fill colour of a mode in `modes.svg`: pale tints of the Okabe-Ito bluish
/// green and sky blue for the consistent modes, its orange and vermillion at full
/// strength for the two the paradox is about, its yellow for sticking.
pub(crate) fn color(mode: PointMode) -> RGBColor {
    match mode {
        PointMode::Contact(ContactMode::Sliding) => RGBColor(153, 216, 199),
        PointMode::Contact(ContactMode::Flight) => RGBColor(187, 225, 246),
        PointMode::Contact(ContactMode::Indeterminate) => figures::plot::colors::ORANGE,
        PointMode::Contact(ContactMode::Inconsistent) => figures::plot::colors::RED,
        PointMode::Contact(ContactMode::Sticking) => figures::plot::colors::YELLOW,
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

    let print = PrintWidth::TwoColumn;
    let canvas = figures::plot::svg_canvas(path, print, 700).map_err(|e| perr(e.to_string()))?;
    let title =
        format!("Contact modes on the belt (paper Fig. 2): {MU} = {}, {BELT_SPEED} {} m/s, u = 0", map.params.mu, map.params.v_belt);
    let (top, root) = canvas.split_vertically(66);
    figures::plot::draw_title(&top, &title, TITLE_PX, 8).map_err(|e| perr(e.to_string()))?;
    let branch = figures::plot::symbols::prose(&branch_label(map));
    figures::plot::draw_title(&top, &branch, TEXT_PX, 38).map_err(|e| perr(e.to_string()))?;
    let (left, right) = root.split_horizontally(640);
    let (x_desc, y_desc) = (axis(THETA1, "deg"), axis(THETA1_DOT, "rad/s"));
    let frame = Frame { x_desc: &x_desc, y_desc: &y_desc, x_tick_labels: true, caption: None, margin_top: 8, y_area: None };
    let mut chart = frame_chart(&left, NiceAxis::new(x0..x1, 7), NiceAxis::new(y0..y1, 10), &frame).map_err(|e| perr(e.to_string()))?;

    // Cells, run-length merged along theta1 within each theta1_dot row, rows drawn
    // upwards; each run reaches a quarter of a cell into its right and upper
    // neighbours, which are drawn after it and cover that (runs that only touch
    // leave hairline seams in PDF viewers' anti-aliasing).
    let overlap = |e0: f64, e1: f64| 0.25 * (e1 - e0);
    let mut rects = Vec::new();
    for j in 0..n2 {
        let mut i = 0;
        while i < n1 {
            let mode = map.points[i * n2 + j].mode;
            let mut k = i + 1;
            while k < n1 && map.points[k * n2 + j].mode == mode {
                k += 1;
            }
            let right = if k < n1 { overlap(x_edge(k - 1), x_edge(k)) } else { 0.0 };
            let up = if j + 1 < n2 { overlap(y_edge(j), y_edge(j + 1)) } else { 0.0 };
            rects.push(Rectangle::new([(x_edge(i), y_edge(j)), (x_edge(k) + right, y_edge(j + 1) + up)], color(mode).filled()));
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
    let p_style = RGBColor(120, 40, 160).stroke_width(3);
    for z in &map.p_zero {
        if let Some([a, b]) = z.theta1_dot_range {
            chart.draw_series(LineSeries::new([(z.theta1_deg, a), (z.theta1_deg, b)], p_style)).map_err(|e| perr(e.to_string()))?;
        }
    }

    // Legend panel.
    let total = map.points.len().max(1);
    let text = |s: &str, size: f64| (s.to_string(), (FAMILY, size).into_font().color(&BLACK));
    let e = |e: DrawingAreaErrorKind<_>| perr(e.to_string());
    let mut y = 12;
    let (t, f) = text("Mode (count, share of grid)", DESC_PX);
    right.draw_text(&t, &f, (10, y)).map_err(e)?;
    y += 30;
    for (mode, count) in map.counts().into_iter().filter(|&(_, n)| n > 0) {
        right.draw(&Rectangle::new([(12, y - 2), (32, y + 16)], color(mode).filled())).map_err(e)?;
        right.draw(&Rectangle::new([(12, y - 2), (32, y + 16)], BLACK.mix(0.5))).map_err(e)?;
        let (t, f) = text(&format!("{} ({count}, {:.1} %)", mode.name(), 100.0 * count as f64 / total as f64), TEXT_PX);
        right.draw_text(&t, &f, (40, y)).map_err(e)?;
        y += 26;
    }
    y += 12;
    let (t, f) = text("Curves", DESC_PX);
    right.draw_text(&t, &f, (10, y)).map_err(e)?;
    y += 30;
    right.draw(&PathElement::new([(12, y + 7), (32, y + 7)], b_style)).map_err(e)?;
    let (t, f) = text("b = 0", TEXT_PX);
    right.draw_text(&t, &f, (40, y)).map_err(e)?;
    y += 26;
    right.draw(&PathElement::new([(12, y + 7), (32, y + 7)], p_style)).map_err(e)?;
    let (t, f) = text(&format!("p = 0 (p for the local sign of {Z_R_DOT})"), TEXT_PX);
    right.draw_text(&t, &f, (40, y)).map_err(e)?;
    y += 26;
    right.draw(&PathElement::new([(12, y + 7), (18, y + 7)], zr_style)).map_err(e)?;
    right.draw(&PathElement::new([(24, y + 7), (32, y + 7)], zr_style)).map_err(e)?;
    let (t, f) = text(&format!("{Z_R_DOT} = 0 (p jumps)"), TEXT_PX);
    right.draw_text(&t, &f, (40, y)).map_err(e)?;
    if straight.is_some() {
        y += 26;
        for x in [12, 18, 24] {
            right.draw(&PathElement::new([(x, y + 7), (x + 2, y + 7)], straight_style)).map_err(e)?;
        }
        let (t, f) = text("straight arm (elbow up left,", TEXT_PX);
        right.draw_text(&t, &f, (40, y)).map_err(e)?;
        y += 22;
        let (t, f) = text("down right)", TEXT_PX);
        right.draw_text(&t, &f, (40, y)).map_err(e)?;
    }
    y += 38;
    let notes = [
        format!("{THETA2}: the tip on the belt ({Z_N} = −H)"),
        format!("{THETA2_DOT}: {Z_N_DOT} = 0"),
        format!("grid {n1} × {n2}"),
        "sliding: p > 0, b < 0".to_string(),
        "flight: p > 0, b ≥ 0".to_string(),
        "indeterminate: p ≤ 0, b ≥ 0".to_string(),
        "inconsistent: p ≤ 0, b < 0".to_string(),
    ];
    for n in notes {
        let (t, f) = text(&n, TEXT_PX);
        right.draw_text(&t, &f, (10, y)).map_err(e)?;
        y += 23;
    }
    figures::plot::finish(canvas, path, print).map_err(perr)
}
