//! Figures: stacked time-series panels drawn with plotters (SVG), and the
//! scaffolding every x-y chart of the commands shares (axes, legend, errors).

use std::{ops::Range, path::Path};

use plotters::{coord::Shift, prelude::*};
use rig::envelope::Envelope;

use crate::error::CliError;

/// The error of drawing the figure at `path`, as a [`CliError::Plot`].
pub fn plot_err(path: &Path) -> impl Fn(&dyn std::fmt::Display) -> CliError + '_ {
    move |e| CliError::Plot { path: path.to_path_buf(), message: e.to_string() }
}

/// An x-y chart of `f64` against `f64`.
pub type XyChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>;

/// The axes of an [`xy_chart`].
pub struct Axes<'s> {
    /// Caption above the chart and its font size, if any.
    pub caption: Option<(String, u32)>,
    /// X range.
    pub x: Range<f64>,
    /// Y range.
    pub y: Range<f64>,
    /// X-axis description with units.
    pub x_desc: &'s str,
    /// Y-axis description with units.
    pub y_desc: &'s str,
    /// Height of the x label area, px.
    pub x_label_area: u32,
    /// Width of the y label area, px.
    pub y_label_area: u32,
    /// Margin around the chart, px.
    pub margin: u32,
}

/// A chart on `area` with `axes`, its mesh drawn (axis descriptions, no light
/// grid lines).
///
/// # Errors
/// plotters' error, as text.
pub fn xy_chart<'a, DB: DrawingBackend>(area: &'a DrawingArea<DB, Shift>, axes: &Axes) -> Result<XyChart<'a, DB>, String> {
    let mut builder = ChartBuilder::on(area);
    builder.margin(axes.margin).x_label_area_size(axes.x_label_area).y_label_area_size(axes.y_label_area);
    if let Some((text, size)) = &axes.caption {
        builder.caption(text, ("sans-serif", *size));
    }
    let mut chart = builder.build_cartesian_2d(axes.x.clone(), axes.y.clone()).map_err(|e| e.to_string())?;
    chart.configure_mesh().x_desc(axes.x_desc).y_desc(axes.y_desc).light_line_style(WHITE.mix(0.0)).draw().map_err(|e| e.to_string())?;
    Ok(chart)
}

/// Draws the chart's series labels in its upper right corner, on a light box.
///
/// # Errors
/// plotters' error, as text.
pub fn legend_upper_right<'a, DB: DrawingBackend + 'a>(chart: &mut XyChart<'a, DB>) -> Result<(), String> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())
}

/// One curve of a panel.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Points `(t, value)`.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Draw as a step function (for discrete signals like the contact mode).
    pub step: bool,
}

/// One panel: a y-axis label and its curves.
pub struct Panel<'a> {
    /// Y-axis description with units.
    pub y_label: &'a str,
    /// The curves.
    pub series: Vec<Series<'a>>,
    /// Optional fixed y-range.
    pub y_range: Option<(f64, f64)>,
}

/// One sample of a closed-loop time history, for [`history_panels`].
#[derive(Debug, Clone, Copy)]
pub struct HistorySample {
    /// Time, s.
    pub t: f64,
    /// Tip position `z_t`, m.
    pub z_t: f64,
    /// Its reference `z_t*`, m.
    pub z_t_ref: f64,
    /// Normal force `f_n`, N.
    pub f_n: f64,
    /// Motor torques `[u1, u2]`, N m.
    pub u: [f64; 2],
    /// Contact mode name (`sliding`, `flight`, `sticking`).
    pub mode: &'static str,
}

/// The four panels of a closed-loop figure (`run`, `pil`, `zmax`): tip position
/// against its reference, normal force, torques (drawn as steps when `step_torques`,
/// a zero-order hold) and contact mode, against time.
pub fn history_panels(samples: &[HistorySample], step_torques: bool) -> [Panel<'static>; 4] {
    let col = |f: fn(&HistorySample) -> f64| samples.iter().map(|r| (r.t, f(r))).collect::<Vec<_>>();
    let columns = [col(|r| r.z_t), col(|r| r.z_t_ref), col(|r| r.f_n), col(|r| r.u[0]), col(|r| r.u[1]), col(|r| mode_code(r.mode))];
    panels_of_columns(columns, step_torques)
}

/// [`history_panels`] from the columns `z_t`, `z_t*`, `f_n`, `u1`, `u2` and the
/// mode code ([`mode_code`]), each as `(t, value)` points.
fn panels_of_columns(columns: [Vec<(f64, f64)>; 6], step_torques: bool) -> [Panel<'static>; 4] {
    let [z_t, z_t_ref, f_n, u1, u2, mode] = columns;
    [
        Panel {
            y_label: "z_t (m)",
            series: vec![
                Series { label: "z_t", points: z_t, color: colors::BLUE, step: false },
                Series { label: "z_t*", points: z_t_ref, color: colors::GREY, step: false },
            ],
            y_range: None,
        },
        Panel { y_label: "f_n (N)", series: vec![Series { label: "f_n", points: f_n, color: colors::GREEN, step: false }], y_range: None },
        Panel {
            y_label: "torque (N m)",
            series: vec![
                Series { label: "u1", points: u1, color: colors::ORANGE, step: step_torques },
                Series { label: "u2", points: u2, color: colors::RED, step: step_torques },
            ],
            y_range: None,
        },
        mode_panel_of_points(mode),
    ]
}

/// A closed-loop time history kept for its figure in fixed memory while a run
/// of any length goes: one [`Envelope`] per curve (every sample up to
/// [`Envelope::DEFAULT_CAPACITY`], then the minimum and maximum of even
/// buckets of samples, so impacts and hops stay visible).
#[derive(Debug, Clone, Default)]
pub struct HistoryEnvelope {
    /// `z_t`, `z_t*`, `f_n`, `u1`, `u2` and the mode code, against time.
    curves: [Envelope; 6],
}

impl HistoryEnvelope {
    /// Adds the next sample (in time order).
    #[inline]
    pub fn push(&mut self, s: &HistorySample) {
        let values = [s.z_t, s.z_t_ref, s.f_n, s.u[0], s.u[1], mode_code(s.mode)];
        for (curve, y) in self.curves.iter_mut().zip(values) {
            curve.push(s.t, y);
        }
    }

    /// The four panels of [`history_panels`], from the kept points.
    pub fn panels(&self, step_torques: bool) -> [Panel<'static>; 4] {
        panels_of_columns(self.curves.each_ref().map(Envelope::points), step_torques)
    }
}

/// The contact mode's code in figures: 0 flight, 1 sliding, 2 sticking.
pub fn mode_code(mode: &str) -> f64 {
    match mode {
        "sliding" => 1.0,
        "sticking" => 2.0,
        _ => 0.0,
    }
}

/// The contact-mode panel: a step curve of 0 flight, 1 sliding, 2 sticking
/// against time, from `(t, mode name)` samples.
pub fn mode_panel<'s>(samples: impl Iterator<Item = (f64, &'s str)>) -> Panel<'static> {
    mode_panel_of_points(samples.map(|(t, mode)| (t, mode_code(mode))).collect())
}

/// The contact-mode panel from `(t, mode code)` points ([`mode_code`]).
pub fn mode_panel_of_points(points: Vec<(f64, f64)>) -> Panel<'static> {
    Panel {
        y_label: "mode (0 flight, 1 sliding, 2 sticking)",
        series: vec![Series { label: "mode", points, color: colors::PURPLE, step: true }],
        y_range: Some((-0.2, 2.2)),
    }
}

/// Colours used across figures.
pub mod colors {
    use plotters::style::RGBColor;
    /// Blue.
    pub const BLUE: RGBColor = RGBColor(31, 119, 180);
    /// Orange.
    pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
    /// Green.
    pub const GREEN: RGBColor = RGBColor(44, 160, 44);
    /// Red.
    pub const RED: RGBColor = RGBColor(214, 39, 40);
    /// Purple.
    pub const PURPLE: RGBColor = RGBColor(148, 103, 189);
    /// Grey.
    pub const GREY: RGBColor = RGBColor(110, 110, 110);
}

/// Keeps at most about `max_points` points of a series, preserving each bucket's
/// minimum and maximum (so spikes such as impacts stay visible).
pub fn decimate(points: &[(f64, f64)], max_points: usize) -> Vec<(f64, f64)> {
    if points.len() <= max_points || max_points < 4 {
        return points.to_vec();
    }
    let buckets = max_points / 2;
    let per = points.len().div_ceil(buckets);
    let mut out = Vec::with_capacity(max_points + 2);
    for chunk in points.chunks(per) {
        let (mut lo, mut hi) = (chunk[0], chunk[0]);
        for &p in chunk {
            if p.1 < lo.1 {
                lo = p;
            }
            if p.1 > hi.1 {
                hi = p;
            }
        }
        if lo.0 <= hi.0 {
            out.push(lo);
            out.push(hi);
        } else {
            out.push(hi);
            out.push(lo);
        }
    }
    out
}

fn finite_range(panel: &Panel) -> (f64, f64) {
    if let Some(r) = panel.y_range {
        return r;
    }
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in &panel.series {
        for &(_, y) in &s.points {
            if y.is_finite() {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = if hi > lo { (hi - lo) * 0.05 } else { 0.5 * hi.abs().max(1.0) };
    (lo - pad, hi + pad)
}

/// Draws `panels` stacked vertically against a shared time axis `t_range` (s)
/// into an SVG file at `path`, with a title.
///
/// # Errors
/// [`CliError::Plot`] when plotters fails (e.g. the file cannot be written).
pub fn time_panels(path: &Path, title: &str, t_range: (f64, f64), panels: &[Panel]) -> Result<(), CliError> {
    let err = plot_err(path);
    let height = 60 + 230 * panels.len() as u32;
    let root = SVGBackend::new(path, (1100, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(|e| err(&e))?;
    let areas = root.split_evenly((panels.len(), 1));
    for (i, (panel, area)) in panels.iter().zip(areas.iter()).enumerate() {
        let (lo, hi) = finite_range(panel);
        let last = i + 1 == panels.len();
        let axes = Axes {
            caption: None,
            x: t_range.0..t_range.1,
            y: lo..hi,
            x_desc: if last { "t (s)" } else { "" },
            y_desc: panel.y_label,
            x_label_area: if last { 40 } else { 25 },
            y_label_area: 80,
            margin: 8,
        };
        let mut chart = xy_chart(area, &axes).map_err(|e| err(&e))?;
        for s in &panel.series {
            let pts = decimate(&s.points, 4000);
            let color = s.color;
            let drawn: Vec<(f64, f64)> = if s.step {
                let mut v = Vec::with_capacity(pts.len() * 2);
                for w in pts.windows(2) {
                    v.push(w[0]);
                    v.push((w[1].0, w[0].1));
                }
                if let Some(&last) = pts.last() {
                    v.push(last);
                }
                v
            } else {
                pts
            };
            chart
                .draw_series(LineSeries::new(drawn.into_iter().filter(|p| p.1.is_finite()), color.stroke_width(1)))
                .map_err(|e| err(&e))?
                .label(s.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        }
        legend_upper_right(&mut chart).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
