//! The sweep's figures (plotters, SVG), one pair per impact law and `e_n`:
//! - `map_<law>_e<e_n>.svg`: the `(v_belt, mu)` plane, one panel per initial
//!   condition, each grid cell coloured by the run's outcome (paper Figs. 3 and 9);
//!   with several seeds per cell (`--seeds N`), shaded by the fraction of its
//!   seeds that lift off, a ring on each undecided cell (a Wilson 95 %
//!   interval holds one half; [`draw_probability_map`]);
//! - `slices_<law>_e<e_n>.svg`: per `mu`, the indicator `max theta1_dot` over the
//!   record window against `v_belt`, one curve per initial condition, with the
//!   threshold.
//!
//! Each also as PDF; one column wide for one panel per row, two for more
//! ([`plot::print`]).

use std::path::Path;

use plotters::prelude::*;

use crate::error::CliError;
use analyses::sweep::{
    SweepSpec,
    cells::CellRow,
    run::{Outcome, RunRow},
};
use figures::plot::{
    self, PrintWidth, colors,
    legend::{Legend, Swatch},
    plot_err,
    symbols::{BELT_SPEED, E_N, MU, THETA1_DOT, axis},
};

/// Colour of an outcome on the map. The outcomes a reader looks for (bouncing,
/// oscillating, lift-off) are saturated colours of the Okabe-Ito palette (distinct
/// under the common colour-vision deficiencies); staying in contact, the expected
/// outcome, is a pale tint, as the paper shades only the bouncing region (Figs. 3
/// and 9).
pub fn outcome_color(o: Outcome) -> RGBColor {
    match o {
        Outcome::Bouncing => colors::RED,
        Outcome::Oscillating => colors::SKY,
        Outcome::LiftOffOnly => colors::PURPLE,
        Outcome::LiftOff => colors::BLUE,
        Outcome::TargetNotReached => colors::YELLOW,
        Outcome::Contact => RGBColor(228, 234, 242),
        Outcome::Flight => colors::ORANGE,
        Outcome::SafeState => colors::GREEN,
        Outcome::Failed => colors::LIGHT_GREY,
        Outcome::Invalid => colors::BLACK,
    }
}

/// An outcome in words for a figure's legend (`lift-off`, `safe state`), not the
/// CSV's code (`lift_off`, `safe_state`).
pub fn outcome_words(o: Outcome) -> String {
    o.name().replace("lift_off", "lift-off").replace('_', " ")
}

/// File-name suffix of a case: `newton_e0.2`.
pub fn case_suffix(law: &str, e_n: f64) -> String {
    format!("{law}_e{e_n}")
}

/// Colours of the initial conditions' curves.
const IC_COLORS: [RGBColor; 6] = [colors::BLUE, colors::ORANGE, colors::GREEN, colors::RED, colors::PURPLE, colors::GREY];

/// One cell of a map: a grid point of one initial condition, its fill, and
/// whether it is ringed.
struct MapCell<'a> {
    ic: &'a str,
    mu: f64,
    v_belt: f64,
    fill: RGBColor,
    ring: bool,
}

/// Draws a (`v_belt`, `mu`) map into `path`: one panel per initial condition of
/// `spec`, each cell of `cells` filled with its colour, a black ring on the
/// ringed ones, under `title` and `legend`.
///
/// # Errors
/// [`CliError::Plot`].
fn draw_cells(path: &Path, spec: &SweepSpec, title: &str, legend: &Legend, cells: &[MapCell]) -> Result<(), CliError> {
    let err = plot_err(path);
    let ics = spec.initial_conditions();
    let cols = ics.len().min(3);
    let grid_rows = ics.len().div_ceil(cols);
    // One column for one panel, the page's width for two or three.
    let print = if cols == 1 { PrintWidth::OneColumn } else { PrintWidth::TwoColumn };
    let panel_h = if cols == 3 { 360 } else { 420 };
    let (root, panels_area) = plot::titled_canvas(path, print, title, Some(legend), panel_h * grid_rows as u32).map_err(|e| err(&e))?;
    let (dv, dmu) = (half_step(&spec.v_belt), half_step(&spec.mu));
    let (vs, mus) = (spec.v_belt.values(), spec.mu.values());
    let x_range = (vs[0] - dv)..(vs[vs.len() - 1] + dv);
    let y_range = (mus[0] - dmu)..(mus[mus.len() - 1] + dmu);
    for (i, area) in panels_area.split_evenly((grid_rows, cols)).iter().enumerate().take(ics.len()) {
        let ic = &ics[i];
        let caption = format!("from {} (elbow {})", ic.name, ic.branch.name());
        let (x_desc, y_desc) = (axis(BELT_SPEED, "m/s"), axis(MU, "-"));
        let axes = plot::Axes { caption: Some(&caption), x: x_range.clone(), y: y_range.clone(), x_desc: &x_desc, y_desc: &y_desc };
        let mut chart = plot::xy_chart(area, &axes).map_err(|e| err(&e))?;
        // Row by row from the lowest mu, each cell reaching a quarter of a cell into
        // its right and upper neighbours, which are drawn after it and cover that:
        // cells that only touch leave hairline seams in PDF viewers' anti-aliasing.
        let mut of_ic: Vec<&MapCell> = cells.iter().filter(|c| c.ic == ic.name).collect();
        of_ic.sort_by(|a, b| a.mu.total_cmp(&b.mu).then(a.v_belt.total_cmp(&b.v_belt)));
        let (v_last, mu_last) = (vs[vs.len() - 1], mus[mus.len() - 1]);
        let rects = of_ic.iter().map(|c| {
            let right = if c.v_belt < v_last { 0.5 * dv } else { 0.0 };
            let up = if c.mu < mu_last { 0.5 * dmu } else { 0.0 };
            Rectangle::new([(c.v_belt - dv, c.mu - dmu), (c.v_belt + dv + right, c.mu + dmu + up)], c.fill.filled())
        });
        chart.draw_series(rects).map_err(|e| err(&e))?;
        if of_ic.iter().any(|c| c.ring) {
            let rings = of_ic.iter().filter(|c| c.ring).map(|c| Circle::new((c.v_belt, c.mu), 4, BLACK.stroke_width(2)));
            chart.draw_series(rings).map_err(|e| err(&e))?;
        }
    }
    plot::finish(root, path, print).map_err(|e| err(&e).into())
}

/// Draws the outcome map of the case `(law, e_n)` from its `rows` into `path`.
///
/// # Errors
/// [`CliError::Plot`].
pub fn draw_map(path: &Path, spec: &SweepSpec, law: &str, e_n: f64, rows: &[&RunRow]) -> Result<(), CliError> {
    // The legend: one coloured box, name and count per outcome that occurs in this
    // case (in the order of the outcomes the sweep can give), packed in rows across
    // the width (measured with the figures' font).
    let outcomes: &[Outcome] = if spec.scenario.is_some() { &Outcome::CLOSED_LOOP } else { &Outcome::OPEN_LOOP };
    let legend = Legend::new(
        outcomes
            .iter()
            .map(|&o| (o, rows.iter().filter(|r| r.outcome == o).count()))
            .filter(|&(_, n)| n > 0)
            .map(|(o, n)| (format!("{} ({n} run{})", outcome_words(o), if n == 1 { "" } else { "s" }), Swatch::Box(outcome_color(o))))
            .collect(),
    );
    let title = format!("Outcome over ({BELT_SPEED}, {MU}){}, {} ({law}, {E_N} = {e_n})", paper_figure(spec), controller_label(spec));
    let cells: Vec<MapCell> =
        rows.iter().map(|r| MapCell { ic: &r.ic, mu: r.mu, v_belt: r.v_belt, fill: outcome_color(r.outcome), ring: false }).collect();
    draw_cells(path, spec, &title, &legend, &cells)
}

/// The shade of a lift-off fraction `p` in [0, 1]: the contact tint at 0, the
/// bouncing red at 1, linear in between (NaN: the failed grey).
pub fn fraction_color(p: f64) -> RGBColor {
    if !p.is_finite() {
        return colors::LIGHT_GREY;
    }
    let (a, b) = (outcome_color(Outcome::Contact), colors::RED);
    let mix = |x: u8, y: u8| (f64::from(x) + (f64::from(y) - f64::from(x)) * p.clamp(0.0, 1.0)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Draws the lift-off probability map of the case `(law, e_n)` from its `cells`
/// (each grid point and initial condition over its seeds) into `path`: each cell
/// shaded by the fraction of its seeds that lift off ([`fraction_color`]; "lift
/// off" is the open loop's persistent bouncing or the closed loop's lift-off), a
/// black ring on each undecided cell (the Wilson 95 % interval of its lift-off
/// or its contact fraction holds one half: its seeds do not decide it).
///
/// # Errors
/// [`CliError::Plot`].
pub fn draw_probability_map(path: &Path, spec: &SweepSpec, law: &str, e_n: f64, cells: &[&CellRow]) -> Result<(), CliError> {
    let undecided = cells.iter().filter(|c| c.undecided).count();
    // The legend's shades are fractions that occur (a legend entry must be in the
    // figure): all of them up to five, else five spread by rank, ends included.
    let mut present: Vec<f64> = cells.iter().map(|c| c.lift_off_fraction).filter(|p| p.is_finite()).collect();
    present.sort_by(f64::total_cmp);
    present.dedup();
    let shown: Vec<f64> = if present.len() <= 5 {
        present
    } else {
        let n = present.len() - 1;
        let mut v: Vec<f64> = (0..5).map(|i| present[(i * n).div_ceil(4)]).collect();
        v.dedup();
        v
    };
    let mut entries: Vec<(String, Swatch)> =
        shown.iter().map(|&p| (format!("{:.0} % lift off", p * 100.0), Swatch::Box(fraction_color(p)))).collect();
    entries.push((
        format!("undecided: a 95 % interval holds 1/2 ({undecided} cell{})", if undecided == 1 { "" } else { "s" }),
        Swatch::Ring(BLACK),
    ));
    let legend = Legend::new(entries);
    let title = format!(
        "Lift-off fraction over {} seeds per cell, ({BELT_SPEED}, {MU}){}, {} ({law}, {E_N} = {e_n})",
        spec.seeds,
        paper_figure(spec),
        controller_label(spec)
    );
    let map_cells: Vec<MapCell> = cells
        .iter()
        .map(|c| MapCell { ic: &c.ic, mu: c.mu, v_belt: c.v_belt, fill: fraction_color(c.lift_off_fraction), ring: c.undecided })
        .collect();
    draw_cells(path, spec, &title, &legend, &map_cells)
}

fn half_step(a: &analyses::sweep::Axis) -> f64 {
    if a.len() > 1 { 0.5 * a.step } else { 0.05_f64.max(a.start.abs() * 0.05) }
}

/// The paper's counterpart of a sweep's figures: Fig. 3 in open loop, Fig. 9 with
/// the hybrid controller (docs/model.md experiments 3 and 7); the PID's sweep has none.
fn paper_figure(spec: &SweepSpec) -> &'static str {
    match spec.controller {
        analyses::sweep::SweepController::None => " (paper Fig. 3)",
        analyses::sweep::SweepController::Hybrid => " (paper Fig. 9)",
        analyses::sweep::SweepController::Pid => "",
    }
}

fn controller_label(spec: &SweepSpec) -> String {
    match (spec.controller, spec.ideal) {
        (analyses::sweep::SweepController::None, _) => "open loop".into(),
        (c, true) => format!("{} (ideal, continuous time)", c.name()),
        (c, false) => format!("{} (firmware, sampled)", c.name()),
    }
}

/// Draws the per-`mu` indicator slices of the case `(law, e_n)` into `path`.
///
/// # Errors
/// [`CliError::Plot`].
pub fn draw_slices(path: &Path, spec: &SweepSpec, law: &str, e_n: f64, rows: &[&RunRow]) -> Result<(), CliError> {
    let err = plot_err(path);
    let ics = spec.initial_conditions();
    let mus = spec.mu.values();
    let cols = if mus.len() > 4 { 2 } else { 1 };
    let grid_rows = mus.len().div_ceil(cols);
    let print = if cols == 1 { PrintWidth::OneColumn } else { PrintWidth::TwoColumn };
    // The indicator spans from 0 (a tip at rest) to tens of rad/s (bouncing), and the
    // threshold is 1e-6 rad/s: a log axis, values at or below a thousandth of the
    // threshold drawn on its floor. One marker shape per initial condition (a hollow
    // ring under a filled dot, then a triangle), so that equal values of two
    // conditions both stay visible.
    let floor = spec.threshold * 1e-3;
    let mut legend = Legend::new(vec![(format!("threshold ({:e} rad/s)", spec.threshold), Swatch::Dashed(BLACK))]);
    for (i, ic) in ics.iter().enumerate() {
        let color = IC_COLORS[i % IC_COLORS.len()];
        let swatch = match i % 3 {
            0 => Swatch::Ring(color),
            1 => Swatch::Marker(color),
            _ => Swatch::Triangle(color),
        };
        legend.entries.push((format!("from {}", ic.name), swatch));
    }
    legend.entries.push((format!("floor: at or below {floor:e} rad/s"), Swatch::Dashed(colors::GREY)));
    let title = format!(
        "Largest {THETA1_DOT} over the record window against {BELT_SPEED}{}, {} ({law}, {E_N} = {e_n})",
        paper_figure(spec),
        controller_label(spec)
    );
    let (root, panels) = plot::titled_canvas(path, print, &title, Some(&legend), 240 * grid_rows as u32).map_err(|e| err(&e))?;
    let vs = spec.v_belt.values();
    let dv = half_step(&spec.v_belt);
    let (x_lo, x_hi) = (vs[0] - dv, vs[vs.len() - 1] + dv);
    for (m, area) in panels.split_evenly((grid_rows, cols)).iter().enumerate().take(mus.len()) {
        let mu = mus[m];
        let at_mu: Vec<&&RunRow> = rows.iter().filter(|r| r.mu == mu).collect();
        let log = |v: f64| v.max(floor).log10();
        let hi = at_mu.iter().map(|r| r.theta1_dot_max).filter(|v| v.is_finite()).fold(spec.threshold * 10.0, f64::max);
        let (y_lo, y_hi) = (log(floor) - 0.3, log(hi) + 0.3);
        let caption = format!("{MU} = {mu}");
        let (x_desc, y_desc) = (axis(BELT_SPEED, "m/s"), format!("log₁₀ max {}", axis(THETA1_DOT, "rad/s")));
        let axes = plot::Axes { caption: Some(&caption), x: x_lo..x_hi, y: y_lo..y_hi, x_desc: &x_desc, y_desc: &y_desc };
        let mut chart = plot::xy_chart(area, &axes).map_err(|e| err(&e))?;
        chart
            .draw_series(DashedLineSeries::new([(x_lo, log(floor)), (x_hi, log(floor))], 2, 4, colors::GREY.stroke_width(1)))
            .map_err(|e| err(&e))?;
        chart
            .draw_series(DashedLineSeries::new([(x_lo, log(spec.threshold)), (x_hi, log(spec.threshold))], 5, 4, BLACK.stroke_width(1)))
            .map_err(|e| err(&e))?;
        for (i, ic) in ics.iter().enumerate() {
            let color = IC_COLORS[i % IC_COLORS.len()];
            let mut pts: Vec<(f64, f64)> = at_mu
                .iter()
                .filter(|r| r.ic == ic.name && r.theta1_dot_max.is_finite())
                .map(|r| (r.v_belt, log(r.theta1_dot_max)))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            // The curve through the nominal runs (seed 0); a marker for every seed.
            let mut nominal: Vec<(f64, f64)> = at_mu
                .iter()
                .filter(|r| r.ic == ic.name && r.seed == 0 && r.theta1_dot_max.is_finite())
                .map(|r| (r.v_belt, log(r.theta1_dot_max)))
                .collect();
            nominal.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart.draw_series(LineSeries::new(nominal.iter().copied(), color.stroke_width(1))).map_err(|e| err(&e))?;
            match i % 3 {
                0 => chart.draw_series(pts.iter().map(|&p| Circle::new(p, 5, color.stroke_width(2)))),
                1 => chart.draw_series(pts.iter().map(|&p| Circle::new(p, 2, color.filled()))),
                _ => chart.draw_series(pts.iter().map(|&p| TriangleMarker::new(p, 4, color.filled()))),
            }
            .map_err(|e| err(&e))?;
        }
    }
    plot::finish(root, path, print).map_err(|e| err(&e).into())
}
