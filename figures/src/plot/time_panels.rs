//! Stacked time-series panels against a shared time axis (`simulate`, `run`,
//! `pil`, `zmax`): one chart per signal, its legend in a column beside it, the
//! time axis labelled under the last panel only. A panel whose curves are all one
//! constant (an open-loop bounce has `f_n = 0` and flight between instantaneous
//! impacts) carries no picture: it is left out and said in a note under the title.

use std::{borrow::Cow, path::Path};

use plotters::prelude::*;

use super::{
    axis::{CategoryAxis, NiceAxis},
    chart::{Frame, TickLabels, frame_chart, y_label_area},
    font::{FAMILY, TEXT_PX, TITLE_PX},
    legend::{Legend, Swatch},
    plot_err,
    print::{PrintWidth, finish},
    svg_canvas,
};
use crate::error::Error;

/// One curve of a panel.
pub struct Series<'a> {
    /// Legend label.
    pub label: Cow<'a, str>,
    /// Points `(t, value)`: t in s, value in the panel's unit.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Draw as a step function (a zero-order hold, a discrete signal such as the contact mode).
    pub step: bool,
    /// Draw dashed: a reference or a limit (`z_t*`, the belt, a budget), so that a
    /// measured curve under it stays visible.
    pub dashed: bool,
    /// Draw each point as a marker, not joined: instants such as impacts.
    pub markers: bool,
}

/// One panel: a y-axis label and its curves.
pub struct Panel<'a> {
    /// Y-axis description with units, `name (unit)`.
    pub y_label: Cow<'a, str>,
    /// The curves.
    pub series: Vec<Series<'a>>,
    /// Optional fixed y-range (in the panel's unit).
    pub y_range: Option<(f64, f64)>,
    /// A categorical y axis: the value `i` is drawn as `categories[i]`.
    pub categories: Option<&'static [&'static str]>,
    /// What happened between the samples that the panel's curves cannot show
    /// (`58 touchdowns between the samples, marked on z_n`): added to the note
    /// when the panel is constant and so not drawn.
    pub between_samples: Option<String>,
}

impl<'a> Panel<'a> {
    /// A numeric panel of `series` under `y_label` (`name (unit)`), its y range from the data.
    pub fn numeric(y_label: impl Into<Cow<'a, str>>, series: Vec<Series<'a>>) -> Self {
        Self { y_label: y_label.into(), series, y_range: None, categories: None, between_samples: None }
    }
}

impl<'a> Series<'a> {
    /// A curve drawn as a line between its points.
    pub fn line(label: impl Into<Cow<'a, str>>, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self { label: label.into(), points, color, step: false, dashed: false, markers: false }
    }

    /// A reference or a limit, dashed, drawn over the measured curves.
    pub fn reference(label: impl Into<Cow<'a, str>>, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self { label: label.into(), points, color, step: false, dashed: true, markers: false }
    }

    /// Instants (impacts, events) drawn as markers over the curves.
    pub fn markers(label: impl Into<Cow<'a, str>>, points: Vec<(f64, f64)>, color: RGBColor) -> Self {
        Self { label: label.into(), points, color, step: false, dashed: false, markers: true }
    }
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

/// The finite values' range of a panel's curves, `None` when it has none.
fn value_range(panel: &Panel) -> Option<(f64, f64)> {
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
    lo.is_finite().then_some((lo, hi))
}

/// The panel's y range: its fixed range, or its values' range padded by 5 %. A
/// curve constant to within a millionth of its magnitude (an ideal force law's
/// `f_n` of 10 N give or take rounding) gets the range a constant gets, half its
/// magnitude (at least one unit) either side, so the axis shows the value and not
/// its last bits.
fn y_range(panel: &Panel) -> (f64, f64) {
    if let Some(r) = panel.y_range {
        return r;
    }
    let Some((lo, hi)) = value_range(panel) else { return (-1.0, 1.0) };
    let magnitude = lo.abs().max(hi.abs());
    let pad = if hi - lo > 1e-6 * magnitude { (hi - lo) * 0.05 } else { 0.5 * magnitude.max(1.0) };
    (lo - pad, hi + pad)
}

/// What a constant panel says in the note: `f_n = 0 N throughout`, `contact mode:
/// flight throughout`; `None` when the panel's curves vary.
fn constant_note(panel: &Panel) -> Option<String> {
    let (lo, hi) = match value_range(panel) {
        Some(r) => r,
        None => return Some(format!("{}: no finite value", panel.y_label)),
    };
    if hi > lo {
        return None;
    }
    if let Some(names) = panel.categories {
        let name = names.get(lo.round().max(0.0) as usize).copied().unwrap_or("?");
        return Some(match &panel.between_samples {
            Some(between) => format!("{}: {name} at every sample ({between})", panel.y_label),
            None => format!("{}: {name} throughout", panel.y_label),
        });
    }
    let (name, unit) = match panel.y_label.split_once(" (") {
        Some((n, u)) => (n, format!(" {}", u.trim_end_matches(')'))),
        None => (panel.y_label.as_ref(), String::new()),
    };
    let v = if lo == 0.0 { "0".to_string() } else { format!("{lo:.4}") };
    Some(format!("{name} = {v}{unit} throughout"))
}

/// The end of the time axis: `t_range`'s end, or the round tick just after it when
/// that is within 2 % of the span (a 10 s run's last sample is at 9.999 s: its axis
/// ends at 10 s, not at its last round tick, 9 s).
fn round_end(t_range: (f64, f64)) -> f64 {
    let (t0, t1) = t_range;
    let step = NiceAxis::step(&NiceAxis::new(t0..t1, 12), 12);
    let up = (t1 / step).ceil() * step;
    if up.is_finite() && up > t1 && up - t1 <= 0.02 * (t1 - t0) { up } else { t1 }
}

/// The points drawn for a series: decimated, as steps when asked, finite only.
fn drawn_points(s: &Series) -> Vec<(f64, f64)> {
    let pts = decimate(&s.points, 4000);
    let drawn = if s.step {
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
    drawn.into_iter().filter(|p| p.1.is_finite()).collect()
}

/// Draws `panels` stacked vertically against a shared time axis `t_range` (s)
/// into an SVG file at `path`, under `title`. Constant panels are left out and
/// named in a note under the title (at least one panel is drawn).
///
/// # Errors
/// [`Error::Plot`] when plotters fails (e.g. the file cannot be written).
pub fn time_panels(path: &Path, title: &str, t_range: (f64, f64), panels: &[Panel]) -> Result<(), Error> {
    let err = plot_err(path);
    let t_end = round_end(t_range);
    let notes: Vec<Option<String>> = panels.iter().map(constant_note).collect();
    let mut shown: Vec<&Panel> = panels.iter().zip(&notes).filter(|(_, n)| n.is_none()).map(|(p, _)| p).collect();
    if shown.is_empty() {
        shown = panels.iter().take(1).collect();
    }
    let note: Vec<&str> = notes.iter().flatten().map(String::as_str).collect();
    let legends: Vec<Legend> =
        shown.iter().map(|p| Legend::new(p.series.iter().map(|s| (s.label.to_string(), swatch(s))).collect())).collect();
    let legend_w = legends.iter().map(Legend::column_width).max().unwrap_or(0) + 10;
    let print = PrintWidth::TwoColumn;
    let width = print.px();
    let title_h = super::title_height(title, width, TITLE_PX, 8);
    let note_lines =
        if note.is_empty() { Vec::new() } else { super::title_lines(&format!("not drawn, constant: {}", note.join("; ")), width, TEXT_PX) };
    let head = title_h + 24 * note_lines.len() as u32;
    let panel_h = 210u32;
    let height = head + panel_h * shown.len() as u32 + 30;
    let root = svg_canvas(path, print, height).map_err(|e| err(&e))?;
    let (top, body) = root.split_vertically(head);
    super::draw_title(&top, title, TITLE_PX, 8).map_err(|e| err(&e))?;
    let grey = BLACK.mix(0.75);
    let style = TextStyle::from((FAMILY, TEXT_PX).into_font()).color(&grey);
    for (i, line) in note_lines.iter().enumerate() {
        top.draw_text(line, &style, (16, (title_h - 6) as i32 + 24 * i as i32)).map_err(|e| err(&e.to_string()))?;
    }
    let mut heights: Vec<u32> = vec![panel_h; shown.len()];
    if let Some(last) = heights.last_mut() {
        *last += 30;
    }
    let mut breaks = Vec::with_capacity(heights.len());
    let mut y = 0u32;
    for h in &heights[..heights.len() - 1] {
        y += h;
        breaks.push(y);
    }
    let areas = body.split_by_breakpoints([] as [u32; 0], breaks);
    // One y label area for all panels, so that their time axes line up.
    let y_area = shown
        .iter()
        .map(|p| {
            let labels = match y_axis(p) {
                YAxis::Categories(y) => y.tick_labels(),
                YAxis::Numeric(y) => y.tick_labels(),
            };
            y_label_area(&labels, &p.y_label)
        })
        .max()
        .unwrap_or(0);
    for (i, ((panel, legend), area)) in shown.iter().zip(&legends).zip(areas.iter()).enumerate() {
        let last = i + 1 == shown.len();
        let (chart_area, legend_area) = area.split_horizontally(width - legend_w);
        let frame = Frame {
            x_desc: if last { "t (s)" } else { "" },
            y_desc: &panel.y_label,
            x_tick_labels: last,
            caption: None,
            margin_top: 8,
            y_area: Some(y_area),
        };
        let x = NiceAxis::new(t_range.0..t_end, 10);
        let drawn = match y_axis(panel) {
            YAxis::Categories(y) => frame_chart(&chart_area, x, y, &frame).and_then(|c| draw_series(c, panel)),
            YAxis::Numeric(y) => frame_chart(&chart_area, x, y, &frame).and_then(|c| draw_series(c, panel)),
        };
        drawn.map_err(|e| err(&e))?;
        legend.draw_column(&legend_area.margin(8, 0, 0, 0)).map_err(|e| err(&e))?;
    }
    finish(root, path, print).map_err(|e| err(&e))
}

/// A panel's y axis.
enum YAxis {
    Numeric(NiceAxis),
    Categories(CategoryAxis),
}

fn y_axis(panel: &Panel) -> YAxis {
    match panel.categories {
        Some(names) => YAxis::Categories(CategoryAxis::new(names.iter().map(|s| s.to_string()).collect())),
        None => {
            let (lo, hi) = y_range(panel);
            YAxis::Numeric(NiceAxis::new(lo..hi, 6))
        }
    }
}

fn draw_series<DB: DrawingBackend, Y>(mut chart: super::chart::Chart<'_, DB, Y>, panel: &Panel) -> Result<(), String>
where
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    // Measured curves first, references and limits dashed over them, instants on top.
    for s in panel.series.iter().filter(|s| !s.dashed && !s.markers) {
        chart.draw_series(LineSeries::new(drawn_points(s), s.color.stroke_width(1))).map_err(|e| e.to_string())?;
    }
    for s in panel.series.iter().filter(|s| s.dashed) {
        chart.draw_series(DashedLineSeries::new(drawn_points(s), 6, 4, s.color.stroke_width(2))).map_err(|e| e.to_string())?;
    }
    for s in panel.series.iter().filter(|s| s.markers) {
        let points = s.points.iter().copied().filter(|p| p.1.is_finite());
        chart.draw_series(points.map(|p| Circle::new(p, 3, s.color.filled()))).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// A series' legend swatch: a line, dashed for a reference, a marker for instants.
fn swatch(s: &Series) -> Swatch {
    if s.markers {
        Swatch::Marker(s.color)
    } else if s.dashed {
        Swatch::Dashed(s.color)
    } else {
        Swatch::Line(s.color)
    }
}

#[cfg(test)]
mod tests {
    use super::round_end;

    /// A curve constant but for its last bits is drawn on a constant's range.
    #[test]
    fn rounding_noise_does_not_set_the_range() {
        use super::{Panel, Series, y_range};
        let noisy = Panel::numeric(
            "fₙ (N)",
            vec![Series::line("fₙ", vec![(0.0, 10.0), (1.0, 10.0 + 1e-12), (2.0, 10.0 - 1e-12)], plotters::style::BLACK)],
        );
        let (lo, hi) = y_range(&noisy);
        assert!((lo - 5.0).abs() < 1e-9 && (hi - 15.0).abs() < 1e-9, "{lo} {hi}");
        let varying = Panel::numeric("fₙ (N)", vec![Series::line("fₙ", vec![(0.0, 10.0), (1.0, 12.0)], plotters::style::BLACK)]);
        let (lo, hi) = y_range(&varying);
        assert!((lo - 9.9).abs() < 1e-12 && (hi - 12.1).abs() < 1e-12, "{lo} {hi}");
    }

    /// A run's axis ends at its duration, not at its last sample or last round tick;
    /// an end far from a tick stays.
    #[test]
    fn a_ten_second_run_ends_at_ten_seconds() {
        assert_eq!(round_end((0.0, 9.999)), 10.0);
        assert_eq!(round_end((0.0, 10.0)), 10.0);
        assert_eq!(round_end((0.0, 2.999)), 3.0);
        assert_eq!(round_end((0.0, 9.5)), 9.5);
        assert_eq!(round_end((0.0, 0.0)), 0.0);
    }
}
