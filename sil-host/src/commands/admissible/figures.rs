//! The figure of `sil-host admissible`: `p(z_t)` on the belt per elbow branch (`admissible.svg`).

use super::summary::fmt_intervals;
use crate::error::CliError;
use analyses::admissible::{AdmissibleReport, p_on_belt};
use analyses::paper;
use figures::plot::{
    PrintWidth,
    axis::NiceAxis,
    chart::{Frame, frame_chart},
    colors,
    font::{FAMILY, TEXT_PX, TITLE_PX},
    symbols::{MU, Z_T, axis},
};
use plotters::prelude::*;
use shared::{Arm, ElbowBranch, SlipDirection};

/// Largest `|p|` (1/kg) shown in `admissible.svg`; larger values are clamped.
pub(crate) const P_PLOT_MAX: f64 = 1e6;

pub(crate) fn plot_err(path: &std::path::Path) -> impl Fn(String) -> CliError + '_ {
    move |message| CliError::Plot { path: path.to_path_buf(), message }
}

/// Draws `p(z_t)` for `z_r_dot > 0` as an SVG at `path` (a staged file): one
/// panel per elbow branch (up on top, down below) sharing the `z_t` axis (m),
/// each with the line `p = 0`, the ends of the reachable belt (dashed) and the
/// admissible intervals (`p > 0`) shaded; at the paper's `mu` (0.6) the ends of
/// its Table II as red triangles on `p = 0` and in each panel's caption.
///
/// # Errors
/// [`CliError::Plot`] when plotters fails (including writing the file).
pub fn draw_figure(r: &AdmissibleReport, path: &std::path::Path) -> Result<(), CliError> {
    let perr = plot_err(path);
    let arm = Arm::new(r.params);
    let dir = SlipDirection::Positive;
    let n = 2000;
    let curve = |branch| {
        (0..=n)
            .map(|i| {
                let z = -r.reach + 2.0 * r.reach * (i as f64) / (n as f64);
                (z, p_on_belt(&arm, z, branch, dir))
            })
            .filter(|(_, p)| p.is_finite())
            .collect::<Vec<_>>()
    };
    let panels = [(ElbowBranch::Up, curve(ElbowBranch::Up)), (ElbowBranch::Down, curve(ElbowBranch::Down))];
    // One p range for both panels, so that they compare at a glance; always
    // including p = 0 and capped at +-P_PLOT_MAX (absurd mu gives absurd p, and
    // plotters cannot lay out an infinite axis): values beyond are clamped.
    let (mut ymin, mut ymax) = panels.iter().flat_map(|(_, c)| c.iter()).fold((0.0f64, 0.0f64), |(a, b), &(_, p)| (a.min(p), b.max(p)));
    ymin = ymin.max(-P_PLOT_MAX);
    ymax = ymax.min(P_PLOT_MAX);
    let pad = 0.08 * (ymax - ymin).max(1e-9);
    ymin -= pad;
    ymax += pad;
    let clamp = |p: f64| p.clamp(ymin, ymax);
    let (x0, x1) = (-r.reach * 1.03, r.reach * 1.03);

    let print = PrintWidth::TwoColumn;
    let canvas = figures::plot::svg_canvas(path, print, 760).map_err(&perr)?;
    let (top, root) = canvas.split_vertically(44);
    figures::plot::draw_title(
        &top,
        &format!("Admissible configurations on the belt (paper Table II): p({Z_T}) for ż_r > 0, {MU} = {}", r.params.mu),
        TITLE_PX,
        10,
    )
    .map_err(&perr)?;
    let (panels_area, note_area) = root.split_vertically(root.dim_in_pixel().1.saturating_sub(56));
    let areas = panels_area.split_evenly((2, 1));
    let line_color = colors::BLUE;
    let shade = colors::GREEN.mix(0.22);
    // The paper's Table II, side by side, where its mu is ours.
    let paper_of = |branch| {
        (r.params.mu == paper::TABLE_II_MU).then_some(match branch {
            ElbowBranch::Up => paper::TABLE_II_ELBOW_UP_M,
            ElbowBranch::Down => paper::TABLE_II_ELBOW_DOWN_M,
        })
    };
    for ((branch, pts), area) in panels.iter().zip(areas.iter()) {
        let iv = r.intervals(*branch, dir);
        let paper = paper_of(*branch);
        let caption = match paper {
            Some([from, to]) => {
                format!("elbow {}: p > 0 (shaded) for {Z_T} in {} m; paper: [{from}, {to}) m", branch.name(), fmt_intervals(iv))
            }
            None => format!("elbow {}: p > 0 (shaded) for {Z_T} in {} m", branch.name(), fmt_intervals(iv)),
        };
        let x_desc = axis(Z_T, "m");
        let frame =
            Frame { x_desc: &x_desc, y_desc: "p (1/kg)", x_tick_labels: true, caption: Some(&caption), margin_top: 6, y_area: None };
        let mut chart = frame_chart(area, NiceAxis::new(x0..x1, 9), NiceAxis::new(ymin..ymax, 5), &frame).map_err(&perr)?;
        chart
            .draw_series(iv.iter().map(|i| Rectangle::new([(i.lo, ymin), (i.hi, ymax)], shade.filled())))
            .map_err(|e| perr(e.to_string()))?;
        chart.draw_series(LineSeries::new([(x0, 0.0), (x1, 0.0)], BLACK.stroke_width(1))).map_err(|e| perr(e.to_string()))?;
        for x in [-r.reach, r.reach] {
            chart
                .draw_series(DashedLineSeries::new([(x, ymin), (x, ymax)], 4, 4, BLACK.mix(0.5).stroke_width(1)))
                .map_err(|e| perr(e.to_string()))?;
        }
        chart
            .draw_series(LineSeries::new(pts.iter().map(|&(z, p)| (z, clamp(p))), line_color.stroke_width(2)))
            .map_err(|e| perr(e.to_string()))?;
        // The paper's ends on the line p = 0, as triangles pointing up at it.
        let paper_red = colors::RED;
        chart
            .draw_series(
                paper
                    .into_iter()
                    .flatten()
                    .map(|z| EmptyElement::at((z, 0.0)) + Polygon::new(vec![(0, 0), (-6, 11), (6, 11)], paper_red.filled())),
            )
            .map_err(|e| perr(e.to_string()))?;
    }
    let notes = [
        "solid black: p = 0; dashed: the ends of the reachable belt, ±√((2l)² − H²)",
        if r.params.mu == paper::TABLE_II_MU {
            "*: an end of the belt, not a zero of p; red triangles: the paper's ends"
        } else {
            "*: an end of the belt, not a zero of p"
        },
    ];
    let grey = BLACK.mix(0.75);
    for (i, note) in notes.iter().enumerate() {
        note_area.draw_text(note, &(FAMILY, TEXT_PX).into_font().color(&grey), (16, 4 + 26 * i as i32)).map_err(|e| perr(e.to_string()))?;
    }
    figures::plot::finish(canvas, path, print).map_err(perr)
}
