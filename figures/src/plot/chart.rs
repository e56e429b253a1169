//! The frame every x-y chart of the figures shares: round-valued ticks
//! ([`NiceAxis`]) or names ([`CategoryAxis`]), label areas sized from the
//! measured width of the tick labels (so no label leaves the canvas), a light
//! grid at the ticks, axis descriptions with units.

use plotters::{
    coord::{
        Shift,
        ranged1d::{Ranged, ValueFormatter},
    },
    prelude::*,
};

use super::{
    axis::{CategoryAxis, NiceAxis},
    font::FAMILY,
    legend::text_size,
};

/// A chart of `f64` against `f64` on axes `X` and `Y`.
pub type Chart<'a, DB, Y, X = NiceAxis> = ChartContext<'a, DB, Cartesian2d<X, Y>>;

pub use super::font::{CAPTION_PX, DESC_PX, TEXT_PX as TICK_PX};

/// The tick labels an axis draws.
pub trait TickLabels {
    /// The labels, in order.
    fn tick_labels(&self) -> Vec<String>;
}

impl TickLabels for NiceAxis {
    fn tick_labels(&self) -> Vec<String> {
        self.ticks(self.max_ticks()).into_iter().map(|v| self.label(v)).collect()
    }
}

impl TickLabels for CategoryAxis {
    fn tick_labels(&self) -> Vec<String> {
        (0..self.len()).map(|i| self.format_ext(&(i as f64))).collect()
    }
}

/// How a chart is framed.
pub struct Frame<'s> {
    /// X-axis description with units (empty: none).
    pub x_desc: &'s str,
    /// Y-axis description with units (empty: none).
    pub y_desc: &'s str,
    /// Whether the x ticks are labelled (stacked panels label only the last).
    pub x_tick_labels: bool,
    /// Caption above the chart.
    pub caption: Option<&'s str>,
    /// Space above the chart (or its caption), px.
    pub margin_top: u32,
    /// Width of the y label area, px, when charts stacked above each other must
    /// align ([`y_label_area`] of the widest); `None`: this chart's own.
    pub y_area: Option<u32>,
}

/// Width of a y label area holding tick labels `labels` and the description
/// `y_desc` (rotated), px.
pub fn y_label_area(labels: &[String], y_desc: &str) -> u32 {
    let widest = labels.iter().map(|l| text_size(l, TICK_PX).0).max().unwrap_or(0);
    widest + 12 + if y_desc.is_empty() { 0 } else { text_size(y_desc, DESC_PX).1 + 22 }
}

/// Builds a chart on `area` with axes `x` and `y` framed as `frame`, its mesh drawn.
///
/// # Errors
/// plotters' error, as text.
pub fn frame_chart<'a, DB, X, Y>(area: &'a DrawingArea<DB, Shift>, x: X, y: Y, frame: &Frame) -> Result<Chart<'a, DB, Y, X>, String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64> + TickLabels,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64> + TickLabels,
{
    super::font::register();
    let y_area = frame.y_area.unwrap_or_else(|| y_label_area(&y.tick_labels(), frame.y_desc));
    let x_area = if frame.x_tick_labels { text_size("0", TICK_PX).1 + 10 } else { 4 }
        + if frame.x_desc.is_empty() { 0 } else { text_size(frame.x_desc, DESC_PX).1 + 10 };
    // The last x tick label is centred on the axis's right end: leave half its width.
    let right = x.tick_labels().last().map_or(0, |l| text_size(l, TICK_PX).0 / 2) + 6;
    let mut builder = ChartBuilder::on(area);
    builder.margin_top(frame.margin_top).margin_right(right.max(12)).margin_left(6).margin_bottom(4);
    builder.x_label_area_size(x_area).y_label_area_size(y_area);
    if let Some(caption) = frame.caption {
        builder.caption(caption, (FAMILY, CAPTION_PX));
    }
    let mut chart = builder.build_cartesian_2d(x, y).map_err(|e| e.to_string())?;
    let blank = |_: &f64| String::new();
    let mut mesh = chart.configure_mesh();
    mesh.x_labels(100)
        .y_labels(100)
        .light_line_style(TRANSPARENT)
        .bold_line_style(BLACK.mix(0.1))
        .label_style((FAMILY, TICK_PX))
        .axis_desc_style((FAMILY, DESC_PX))
        .x_desc(frame.x_desc)
        .y_desc(frame.y_desc);
    if !frame.x_tick_labels {
        mesh.x_label_formatter(&blank);
    }
    mesh.draw().map_err(|e| e.to_string())?;
    Ok(chart)
}
