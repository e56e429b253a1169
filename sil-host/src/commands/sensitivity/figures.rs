//! The study's figures: one per headline result, a panel per open choice that
//! enters it, the result against the choice's values (the default marked).

use std::path::Path;

use analyses::sensitivity::{ChoiceResult, Dimension, Study};
use analyses::zmax::Combination;
use plotters::{coord::Shift, prelude::*};

use crate::error::CliError;
use crate::plot::{
    self, PrintWidth,
    axis::{CategoryAxis, NiceAxis},
    chart::{Frame, frame_chart},
    colors,
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
    /// Title (in the symbols of [`crate::plot::symbols`]).
    pub title: fn() -> String,
    /// The value axis's description with units.
    pub value_desc: fn() -> String,
    /// A value that is a category (`0` no, `1` yes): its names by value.
    pub value_names: Option<&'static [&'static str]>,
    /// Whether the value counts something (ticks on whole numbers).
    pub count: bool,
    /// The series: a label and the value under a choice (`None`: not computed; NaN:
    /// computed, with no value, drawn as [`Figure::none`] says).
    pub series: fn() -> Vec<SeriesOf>,
    /// What a computed result with no value means, and the panel edge its hollow
    /// marker is drawn at.
    pub none: Option<NoValue>,
    /// The series come in pairs of one case, the paper's ideal setting then the
    /// sampled firmware: one colour per case (Okabe-Ito), the ideal result a large
    /// ring and the sampled one a dot on the same row, so that equal results show
    /// as a dot in its ring instead of one marker hiding the other.
    pub paired: bool,
}

/// Colours of the cases of a paired figure (Okabe-Ito: distinct under the common
/// colour-vision deficiencies).
const CASE_COLORS: [RGBColor; 4] = [colors::BLUE, colors::RED, colors::GREEN, colors::PURPLE];

/// How series `s` of `fig` is drawn: its colour, whether as a ring (else a dot),
/// and its row slot (the dodge within a choice's row) among `slots`.
fn style(fig: &Figure, s: usize, n: usize) -> (RGBColor, bool, usize, usize) {
    if fig.paired {
        (CASE_COLORS[(s / 2) % 4], s.is_multiple_of(2), s / 2, n.div_ceil(2))
    } else {
        (colors::CYCLE[s % colors::CYCLE.len()], false, s, n)
    }
}

/// A result computed with no value (no critical `mu` on the grid, no bouncing band,
/// a `Z_t,sliding` below the bisection's bracket): a hollow marker at one edge of
/// its panel, explained in the legend.
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
/// result on the other; series side by side in each row, one legend above.
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
    let mut entries: Vec<(String, Swatch)> = series
        .iter()
        .enumerate()
        .map(|(s, (name, _, _))| {
            let (color, ring, _, _) = style(fig, s, n);
            (name.clone(), if ring { Swatch::Ring(color) } else { Swatch::Marker(color) })
        })
        .collect();
    let any_none = study.results.iter().any(|r| series.iter().any(|(_, f, i)| f(r, *i).is_some_and(f64::is_nan)));
    if let (Some(none), true) = (&fig.none, any_none) {
        let edge = if none.at_low_end { "left" } else { "right" };
        let how = if fig.paired { "the series' marker" } else { "hollow" };
        entries.push((format!("{} ({how} in a grey ring, at the {edge} edge)", none.desc), Swatch::Ring(colors::GREY)));
    }
    // A legend of one series says nothing its title does not.
    let legend = Some(Legend::new(entries)).filter(|l| l.entries.len() > 1);
    // Each row of panels as high as its longest list of choices.
    let choices_of = |d: &Dimension| study.results.iter().filter(|r| r.choice.dimension == *d).count() as u32;
    let row_heights: Vec<u32> = dims.chunks(cols).map(|row| 84 + 22 * row.iter().map(choices_of).max().unwrap_or(1)).collect();
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
            draw_panel(area, study, fig, &series, *dim).map_err(|e| err(&e))?;
        }
    }
    plot::finish(root, path, print).map_err(|e| err(&e))
}

/// One dimension's panel: its choices top down, each series' value as a marker,
/// the series dodged vertically within a choice's row; a result with no value
/// (NaN) as a hollow marker at the edge [`Figure::none`] names.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    study: &Study,
    fig: &Figure,
    series: &[SeriesOf],
    dim: Dimension,
) -> Result<(), String> {
    let of: Vec<&ChoiceResult> = study.results.iter().filter(|r| r.choice.dimension == dim).collect();
    let names: Vec<String> =
        of.iter().map(|r| prose(&format!("{}{}", r.choice.value, if r.choice.is_default { "*" } else { "" }))).collect();
    let y = CategoryAxis::top_down(names);
    let value_desc = (fig.value_desc)();
    let caption = prose(dim.label());
    let frame = Frame { x_desc: &value_desc, y_desc: "", x_tick_labels: true, caption: Some(&caption), margin_top: 6, y_area: None };
    let slots = style(fig, 0, series.len()).3 as f64;
    let dodge = |s: usize| {
        let slot = style(fig, s, series.len()).2 as f64;
        if slots > 1.0 { (slot - (slots - 1.0) / 2.0) * (0.6 / slots) } else { 0.0 }
    };
    // Rows are drawn top down: a later series sits lower, so the dodge is negated.
    let points = |s: usize, f: &fn(&ChoiceResult, usize) -> Option<f64>, i: usize| -> Vec<(f64, f64)> {
        of.iter().enumerate().filter_map(|(k, r)| f(r, i).filter(|v| v.is_finite()).map(|v| (v, k as f64 - dodge(s)))).collect()
    };
    // The rows of a series' results with no value.
    let nones = |s: usize, f: &fn(&ChoiceResult, usize) -> Option<f64>, i: usize| -> Vec<f64> {
        of.iter().enumerate().filter(|(_, r)| f(r, i).is_some_and(f64::is_nan)).map(|(k, _)| k as f64 - dodge(s)).collect()
    };
    let all: Vec<(f64, f64)> = series.iter().enumerate().flat_map(|(s, (_, f, i))| points(s, f, *i)).collect();
    // A series' marker: a filled dot, or (the ideal result of a paired figure) a
    // larger ring around where the sampled result's dot sits when the two agree.
    let marker = |chart_points: Vec<(f64, f64)>, s: usize| {
        let (color, ring, _, _) = style(fig, s, series.len());
        chart_points
            .into_iter()
            .map(move |p| if ring { Circle::new(p, 7, color.stroke_width(2)) } else { Circle::new(p, 4, color.filled()) })
    };
    let ring = |rows: Vec<f64>, x: f64, s: usize| {
        let (color, paired_ring, _, _) = style(fig, s, series.len());
        let paired = fig.paired;
        rows.into_iter().map(move |y| match (paired, paired_ring) {
            (true, false) => Circle::new((x, y), 4, color.filled()),
            (true, true) => Circle::new((x, y), 7, color.stroke_width(2)),
            _ => Circle::new((x, y), 5, color.stroke_width(2)),
        })
    };
    // The grey ring around each result with no value (its legend entry's swatch).
    let no_value = |rows: Vec<f64>, x: f64| rows.into_iter().map(move |y| Circle::new((x, y), 10, colors::GREY.stroke_width(1)));
    if let Some(value_names) = fig.value_names {
        let x = CategoryAxis::new(value_names.iter().map(|s| s.to_string()).collect());
        let mut chart = frame_chart(area, x, y, &frame)?;
        for (s, (_, f, i)) in series.iter().enumerate() {
            chart.draw_series(marker(points(s, f, *i), s)).map_err(|e| e.to_string())?;
        }
        return Ok(());
    }
    let (lo, hi) = all.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (lo, hi) = if all.is_empty() {
        (0.0, 1.0)
    } else if hi - lo < 1e-9 {
        (lo - 0.5 * lo.abs().max(0.1), hi + 0.5 * hi.abs().max(0.1))
    } else {
        (lo - 0.08 * (hi - lo), hi + 0.08 * (hi - lo))
    };
    let (lo, hi) = if fig.count { (lo.min(-0.5), hi.max(1.5)) } else { (lo, hi) };
    // Hollow markers sit a little inside the edge they are drawn at.
    let none_x = match &fig.none {
        Some(none) if none.at_low_end => lo + 0.02 * (hi - lo),
        _ => hi - 0.02 * (hi - lo),
    };
    let (w, _) = area.dim_in_pixel();
    let mut x = NiceAxis::new(lo..hi, (w / 55).clamp(3, 8) as usize);
    if fig.count {
        x = x.with_min_step(1.0);
    }
    let mut chart = frame_chart(area, x, y, &frame)?;
    for (s, (_, f, i)) in series.iter().enumerate() {
        chart.draw_series(marker(points(s, f, *i), s)).map_err(|e| e.to_string())?;
        chart.draw_series(ring(nones(s, f, *i), none_x, s)).map_err(|e| e.to_string())?;
        chart.draw_series(no_value(nones(s, f, *i), none_x)).map_err(|e| e.to_string())?;
    }
    Ok(())
}
