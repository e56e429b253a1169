//! The study's figures: one per headline result, a panel per open choice that
//! enters it, the result against the choice's values (the default marked).

use std::path::Path;

use analyses::sensitivity::{ChoiceResult, Dimension, Study};
use analyses::zmax::Combination;
use plotters::{coord::Shift, prelude::*};

use super::layout::{Mark, dodge};
use crate::error::CliError;
use figures::plot::{
    self, PrintWidth,
    axis::{CategoryAxis, NiceAxis},
    chart::{Frame, TickLabels, frame_chart, y_label_area},
    colors,
    gutter::GutterAxis,
    legend::{Legend, Swatch},
    plot_err,
    symbols::{BELT_SPEED, MU, Z_T_SLIDING, axis, prose},
};

/// A series of a figure: its label, its value under a choice (given the series'
/// index), and that index.
pub type SeriesOf = (String, fn(&ChoiceResult, usize) -> Option<f64>, usize);

/// One figure: its file, title, value axis, and its series (name and value under a choice).
pub struct Figure {
    /// File name.
    pub file: &'static str,
    /// Title (in the symbols of [`figures::plot::symbols`]).
    pub title: fn() -> String,
    /// The value axis's description with units.
    pub value_desc: fn() -> String,
    /// A value that is a category (`0` no, `1` yes): its names by value.
    pub value_names: Option<&'static [&'static str]>,
    /// Whether the value counts something (ticks on whole numbers): the series'
    /// counts are drawn as one stacked bar per choice.
    pub count: bool,
    /// The series: a label and the value under a choice (`None`: not computed; NaN:
    /// computed, with no value, drawn as [`Figure::none`] says).
    pub series: fn() -> Vec<SeriesOf>,
    /// What a computed result with no value means, and the panel edge its hollow
    /// marker is drawn at.
    pub none: Option<NoValue>,
    /// The series come in pairs of one case, the paper's ideal setting then the
    /// sampled firmware: one colour per case (Okabe-Ito), the ideal result a
    /// ring and the sampled one a smaller dot on the case's line, so that equal
    /// results show as a dot in its ring instead of one marker hiding the other.
    pub paired: bool,
}

/// Colours of the cases of a paired figure (Okabe-Ito: distinct under the common
/// colour-vision deficiencies).
const CASE_COLORS: [RGBColor; 4] = [colors::BLUE, colors::RED, colors::GREEN, colors::PURPLE];

/// How series `s` of `fig` is drawn: its colour, whether as a ring (else a dot),
/// and its group (the markers that form one glyph and share a line of the row:
/// a series, or a case of a paired figure) among `groups`.
fn style(fig: &Figure, s: usize, n: usize) -> (RGBColor, bool, usize, usize) {
    if fig.paired {
        (CASE_COLORS[(s / 2) % 4], s.is_multiple_of(2), s / 2, n.div_ceil(2))
    } else {
        (colors::CYCLE[s % colors::CYCLE.len()], false, s, n)
    }
}

/// The size of a figure's markers and of the room between them, px.
struct Geometry {
    /// Radius of a dot.
    dot: i32,
    /// Radius of a ring (paired figures' ideal results) and its stroke.
    ring: (i32, u32),
    /// Half the width of the widest glyph.
    half_w: f64,
    /// Height of a choice's row.
    row_px: u32,
}

impl Geometry {
    /// `fig`'s, for `groups` groups: a paired figure's ring around a smaller dot,
    /// else dots; rows high enough that a row's dodged groups clear the next row's.
    fn of(fig: &Figure, groups: usize) -> Self {
        if fig.paired {
            Self { dot: 3, ring: (5, 2), half_w: 6.0, row_px: 28 }
        } else {
            Self { dot: 4, ring: (4, 2), half_w: 4.0, row_px: if groups >= 3 && !fig.count { 26 } else { 22 } }
        }
    }

    /// The distance between dodged groups' lines, and between the gutter's slots, px.
    fn pitch(&self) -> f64 {
        2.0 * self.half_w + 1.0
    }

    /// The gutter's slots for `groups` groups: columns and rows (two rows from
    /// four groups on, so that the band stays narrow).
    fn slots(groups: usize) -> (usize, usize) {
        let cols = if groups >= 4 { groups.div_ceil(2) } else { groups.max(1) };
        (cols, groups.div_ceil(cols).max(1))
    }

    /// Where group `group` of `groups` sits in the gutter: px from its middle and its row's line.
    fn slot(&self, group: usize, groups: usize) -> (i32, i32) {
        let (cols, rows) = Self::slots(groups);
        let at = |i: usize, n: usize| ((i as f64 - (n as f64 - 1.0) / 2.0) * self.pitch()).round() as i32;
        (at(group % cols, cols), at(group / cols, rows))
    }

    /// The gutter's width for `groups` groups, px.
    fn gutter_px(&self, groups: usize) -> u32 {
        (self.pitch() * Self::slots(groups).0 as f64).ceil() as u32 + 10
    }
}

/// The gutter's colour: a light grey band at the value axis's end holding the
/// results with no value.
const NONE_BAND: RGBColor = RGBColor(228, 228, 228);

/// A result computed with no value (no critical `mu` on the grid, no bouncing band,
/// a `Z_t,sliding` below the bisection's bracket): its series' marker in a grey
/// band beyond one end of the value axis (a slot per series), explained in the legend.
pub struct NoValue {
    /// The legend's text.
    pub desc: &'static str,
    /// Drawn at the value axis's lower end (else its upper end).
    pub at_low_end: bool,
}

/// `Some(v)`, or NaN when the result was computed and has no value.
fn or_none(computed: bool, v: Option<f64>) -> Option<f64> {
    if computed { Some(v.unwrap_or(f64::NAN)) } else { None }
}

fn open<T>(r: &ChoiceResult, f: impl Fn(&analyses::sensitivity::OpenLoop) -> T) -> Option<T> {
    r.open_loop.as_ref().map(f)
}

/// The figures, one per headline result.
pub const FIGURES: [Figure; 5] = [
    Figure {
        file: "critical_mu.svg",
        title: || format!("Critical {MU} (open loop)"),
        value_desc: || axis(&format!("critical {MU}"), "-"),
        value_names: None,
        count: false,
        series: || {
            vec![
                ("x0a".into(), |r, _| or_none(r.open_loop.is_some(), open(r, |o| o.critical_mu_x0a).flatten()), 0),
                ("x0d".into(), |r, _| or_none(r.open_loop.is_some(), open(r, |o| o.critical_mu_x0d).flatten()), 0),
            ]
        },
        none: Some(NoValue { desc: "none: no persistent bouncing at any μ of the grid", at_low_end: false }),
        paired: false,
    },
    Figure {
        file: "band_mu06_x0a.svg",
        title: || format!("Persistent bouncing at {MU} = 0.6 from x0a: the longest interval of {BELT_SPEED} (open loop)"),
        value_desc: || axis(BELT_SPEED, "m/s"),
        value_names: None,
        count: false,
        series: || {
            vec![
                ("from".into(), |r, _| or_none(r.open_loop.is_some(), open(r, |o| o.band_x0a_mu06.map(|b| b[0])).flatten()), 0),
                ("to".into(), |r, _| or_none(r.open_loop.is_some(), open(r, |o| o.band_x0a_mu06.map(|b| b[1])).flatten()), 0),
            ]
        },
        none: Some(NoValue { desc: "none: no persistent bouncing at μ = 0.6", at_low_end: false }),
        paired: false,
    },
    Figure {
        file: "x0d_bounces.svg",
        title: || "Does x0d ever bounce? (open loop)".into(),
        value_desc: || format!("x0d bounces at some ({BELT_SPEED}, {MU})"),
        value_names: Some(&["no", "yes"]),
        count: false,
        series: || vec![("x0d".into(), |r, _| open(r, |o| if o.x0d_bounces { 1.0 } else { 0.0 }), 0)],
        none: None,
        paired: false,
    },
    Figure {
        file: "zt_sliding.svg",
        title: || format!("{Z_T_SLIDING} of the four paper cases, ideal and sampled"),
        value_desc: || axis(Z_T_SLIDING, "m"),
        value_names: None,
        count: false,
        series: || {
            Combination::all()
                .into_iter()
                .enumerate()
                .map(|(i, k)| {
                    let f: fn(&ChoiceResult, usize) -> Option<f64> =
                        |r, i| r.zmax.iter().find(|z| z.combination == Combination::all()[i]).map(|z| z.z_t_sliding.unwrap_or(f64::NAN));
                    (format!("{} x0{} {}", k.controller, k.x0, k.setting), f, i)
                })
                .collect()
        },
        none: Some(NoValue { desc: "none: fails already at the bisection's lower end", at_low_end: true }),
        paired: true,
    },
    Figure {
        file: "hybrid_closed_loop.svg",
        title: || format!("Hybrid closed loop from x0d at {MU} = 0.6: how the runs at each belt speed ended"),
        value_desc: || "belt speeds (count)".into(),
        value_names: None,
        count: true,
        series: || {
            vec![
                ("lift-off".into(), |r, _| r.closed_loop.as_ref().map(|c| c.lift_off_points as f64), 0),
                ("safe state".into(), |r, _| r.closed_loop.as_ref().map(|c| c.safe_state_points as f64), 0),
                ("target not reached".into(), |r, _| r.closed_loop.as_ref().map(|c| c.target_not_reached_points as f64), 0),
            ]
        },
        none: None,
        paired: false,
    },
];

/// Draws `fig` of `study` at `path`: a panel per dimension with at least one
/// value, its choices on a categorical axis (the default starred, top down), the
/// result on the other; markers that would touch moved apart within their row
/// ([`dodge`]), results with no value in a grey band at the value axis's end,
/// one legend above.
///
/// # Errors
/// [`CliError::Plot`].
pub fn draw(path: &Path, study: &Study, fig: &Figure) -> Result<(), CliError> {
    let err = plot_err(path);
    let series = (fig.series)();
    let dims: Vec<Dimension> = Dimension::ALL
        .into_iter()
        .filter(|d| study.results.iter().filter(|r| r.choice.dimension == *d).any(|r| series.iter().any(|(_, f, i)| f(r, *i).is_some())))
        .collect();
    // Three columns for many panels, so that the figure fits a page's height.
    let cols = if dims.len() > 6 { 3usize } else { 2 };
    let print = PrintWidth::TwoColumn;
    let n = series.len();
    let geometry = Geometry::of(fig, style(fig, 0, n).3);
    let mut entries: Vec<(String, Swatch)> = series
        .iter()
        .enumerate()
        .map(|(s, (name, _, _))| {
            let (color, ring, _, _) = style(fig, s, n);
            let swatch = match (fig.count, ring) {
                (true, _) => Swatch::Box(color),
                (false, true) => Swatch::Ring(color),
                (false, false) => Swatch::Marker(color),
            };
            (name.clone(), swatch)
        })
        .collect();
    let any_none = study.results.iter().any(|r| series.iter().any(|(_, f, i)| f(r, *i).is_some_and(f64::is_nan)));
    let gutter = match (&fig.none, any_none) {
        (Some(none), true) => {
            let edge = if none.at_low_end { "left" } else { "right" };
            entries.push((format!("{} (the series' marker in the grey band at the {edge})", none.desc), Swatch::Box(NONE_BAND)));
            Some(none.at_low_end)
        }
        _ => None,
    };
    // A legend of one series says nothing its title does not.
    let legend = Some(Legend::new(entries)).filter(|l| l.entries.len() > 1);
    // Each row of panels as high as its longest list of choices.
    let choices_of = |d: &Dimension| study.results.iter().filter(|r| r.choice.dimension == *d).count() as u32;
    let row_heights: Vec<u32> = dims.chunks(cols).map(|row| 84 + geometry.row_px * row.iter().map(choices_of).max().unwrap_or(1)).collect();
    let body_h = row_heights.iter().sum::<u32>().max(100);
    let (root, body) = plot::titled_canvas(path, print, &(fig.title)(), legend.as_ref(), body_h).map_err(|e| err(&e))?;
    let mut breaks = Vec::new();
    let mut y = 0;
    for h in &row_heights {
        y += h;
        breaks.push(y);
    }
    breaks.pop();
    let rows = body.split_by_breakpoints([] as [u32; 0], breaks);
    for (row_dims, row_area) in dims.chunks(cols).zip(rows.iter()) {
        let halves = row_area.split_evenly((1, cols));
        for (dim, area) in row_dims.iter().zip(halves.iter()) {
            let panel = Panel { study, fig, series: &series, geometry: &geometry, gutter };
            draw_panel(area, &panel, *dim).map_err(|e| err(&e))?;
        }
    }
    plot::finish(root, path, print).map_err(|e| err(&e).into())
}

/// What every panel of a figure shares.
struct Panel<'a> {
    study: &'a Study,
    fig: &'a Figure,
    series: &'a [SeriesOf],
    geometry: &'a Geometry,
    /// Whether the panels have the band of results with no value, at the low end (`Some(true)`).
    gutter: Option<bool>,
}

/// One dimension's panel: its choices top down, each series' value as a marker
/// on its choice's row, markers that would touch dodged apart ([`dodge`]); a
/// result with no value (NaN) in the band at the value axis's end, in its series'
/// slot.
fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel, dim: Dimension) -> Result<(), String> {
    let (fig, series, g) = (p.fig, p.series, p.geometry);
    let of: Vec<&ChoiceResult> = p.study.results.iter().filter(|r| r.choice.dimension == dim).collect();
    let names: Vec<String> =
        of.iter().map(|r| prose(&format!("{}{}", r.choice.value, if r.choice.is_default { "*" } else { "" }))).collect();
    let y = CategoryAxis::top_down(names);
    let value_desc = (fig.value_desc)();
    let caption = prose(dim.label());
    let frame = Frame { x_desc: &value_desc, y_desc: "", x_tick_labels: true, caption: Some(&caption), margin_top: 6, y_area: None };
    let n = series.len();
    // A marker: a dot, or (the ideal result of a paired figure) a ring around where the sampled result's dot sits.
    let glyph = |s: usize, dx: i32, dy: i32| {
        let (color, ring, _, _) = style(fig, s, n);
        if ring { Circle::new((dx, dy), g.ring.0, color.stroke_width(g.ring.1)) } else { Circle::new((dx, dy), g.dot, color.filled()) }
    };
    if let Some(value_names) = fig.value_names {
        let x = CategoryAxis::new(value_names.iter().map(|s| s.to_string()).collect());
        let mut chart = frame_chart(area, x, y, &frame)?;
        let points = of.iter().enumerate().flat_map(|(k, r)| {
            series.iter().enumerate().filter_map(move |(s, (_, f, i))| f(r, *i).filter(|v| v.is_finite()).map(|v| (s, v, k)))
        });
        chart.draw_series(points.map(|(s, v, k)| EmptyElement::at((v, k as f64)) + glyph(s, 0, 0))).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let finite: Vec<f64> = of.iter().flat_map(|r| series.iter().filter_map(|(_, f, i)| f(r, *i).filter(|v| v.is_finite()))).collect();
    let (lo, hi) = finite.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    let (lo, hi) = if finite.is_empty() {
        (0.0, 1.0)
    } else if hi - lo < 1e-9 {
        (lo - 0.5 * lo.abs().max(0.1), hi + 0.5 * hi.abs().max(0.1))
    } else {
        (lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo))
    };
    // Counts are stacked bars from 0: the axis to the largest total.
    let total = |r: &ChoiceResult| series.iter().filter_map(|(_, f, i)| f(r, *i).filter(|v| v.is_finite())).sum::<f64>();
    let (lo, hi) = if fig.count { (0.0, (1.08 * of.iter().map(|r| total(r)).fold(0.0, f64::max)).max(1.5)) } else { (lo, hi) };
    let (w, _) = area.dim_in_pixel();
    let groups = style(fig, 0, n).3;
    let gutter_px = if p.gutter.is_some() { g.gutter_px(groups) } else { 0 };
    // About one tick per 55 px of the data's part of the axis (less the labels, the margins and the band).
    let data_w = w.saturating_sub(y_label_area(&y.tick_labels(), "") + 40 + gutter_px);
    let max_ticks = (data_w / 55).clamp(if fig.count { 3 } else { 2 }, 8) as usize;
    let mut x = NiceAxis::new(lo..hi, max_ticks);
    if fig.count {
        x = x.with_min_step(1.0);
    }
    // A narrow panel whose round step leaves fewer than two ticks inside: its
    // range widened out to the step's multiples, so that two labelled ticks frame the data.
    if x.ticks(max_ticks).len() < 2 {
        let step = NiceAxis::step(&x, max_ticks);
        x = NiceAxis::new((lo / step).floor() * step..(hi / step).ceil() * step, max_ticks);
        if fig.count {
            x = x.with_min_step(1.0);
        }
    }
    let x = GutterAxis::new(x, gutter_px, p.gutter.unwrap_or(false));
    let mut chart = frame_chart(area, x.clone(), y, &frame)?;
    if gutter_px > 0 {
        // The band, over the plotting area's height, 1 px clear of the axis line.
        let (top, bottom) = (chart.backend_coord(&(f64::NAN, -0.5)).1, chart.backend_coord(&(f64::NAN, of.len() as f64 - 0.5)).1);
        let base = chart.plotting_area().get_base_pixel();
        let (w_px, _) = chart.plotting_area().dim_in_pixel();
        let (g0, g1) = x.gutter((base.0, base.0 + w_px as i32));
        let (l, r) = (g0.max(base.0 + 1) - base.0, g1.min(base.0 + w_px as i32 - 1) - base.0);
        let (t, b) = (top.min(bottom) - base.1, top.max(bottom) - base.1);
        chart.plotting_area().strip_coord_spec().draw(&Rectangle::new([(l, t), (r, b)], NONE_BAND.filled())).map_err(|e| e.to_string())?;
    }
    if fig.count {
        // Each row's counts as one bar, a segment per series in the legend's order.
        for (k, r) in of.iter().enumerate() {
            let mut from = 0.0;
            for (s, (_, f, i)) in series.iter().enumerate() {
                let v = f(r, *i).filter(|v| v.is_finite() && *v > 0.0).unwrap_or(0.0);
                if v > 0.0 {
                    let (color, _, _, _) = style(fig, s, n);
                    let y = k as f64;
                    chart
                        .draw_series([Rectangle::new([(from, y - 0.3), (from + v, y + 0.3)], color.filled())])
                        .map_err(|e| e.to_string())?;
                    from += v;
                }
            }
        }
        return Ok(());
    }
    for (k, r) in of.iter().enumerate() {
        let mut marks = Vec::new();
        let mut at = Vec::new();
        let mut nones = Vec::new();
        for (s, (_, f, i)) in series.iter().enumerate() {
            let (_, _, group, _) = style(fig, s, n);
            match f(r, *i) {
                Some(v) if v.is_finite() => {
                    marks.push(Mark { group, x_px: chart.backend_coord(&(v, k as f64)).0 as f64, half_w: g.half_w });
                    at.push((s, v));
                }
                Some(v) if v.is_nan() && gutter_px > 0 => nones.push((s, group)),
                _ => {}
            }
        }
        let dy = dodge(&marks, g.pitch());
        let row = at.iter().zip(&dy).map(|(&(s, v), dy)| EmptyElement::at((v, k as f64)) + glyph(s, 0, dy.round() as i32));
        chart.draw_series(row).map_err(|e| e.to_string())?;
        // In the band, each group in its own slot across it.
        let band = nones.iter().map(|&(s, group)| {
            let (dx, dy) = g.slot(group, groups);
            EmptyElement::at((f64::NAN, k as f64)) + glyph(s, dx, dy)
        });
        chart.draw_series(band).map_err(|e| e.to_string())?;
    }
    Ok(())
}
